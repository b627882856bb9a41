//! Core layer: opening files glint did not write. Every file is read through
//! [`Files::read`] (from disk: regular files only, size checked from metadata
//! before a byte is read; or from a [`FileSet`] in memory, as the web viewer
//! fetches them) and every path a file names goes through [`AssetFolder::resolve`]
//! (inside the asset roots after resolving symlinks). The numbers are the policy
//! in `docs/limits.md`.

use super::{Diagnostic, LoadOptions};
use std::collections::{BTreeSet, HashMap, HashSet};
use std::io::Read;
use std::path::{Component, Path, PathBuf};
use std::sync::{Arc, Mutex};

/// Largest `.scn` file read, in bytes.
pub const MAX_SCENE_BYTES: u64 = 64 << 20;
/// Largest model file (OBJ, MTL, glTF JSON, GLB) read, in bytes.
pub const MAX_MODEL_BYTES: u64 = 1 << 30;
/// Largest MTL material library read, in bytes: a library defines materials,
/// not geometry (the largest in the sample models is under 20 KB).
pub const MAX_MATERIAL_LIBRARY_BYTES: u64 = 64 << 20;
/// Largest external glTF buffer (`.bin`) read, in bytes.
pub const MAX_BUFFER_BYTES: u64 = 1 << 30;
/// Largest image file (PNG, JPEG) read, in bytes.
pub const MAX_IMAGE_FILE_BYTES: u64 = 256 << 20;
/// Largest total of bytes one scene load reads, over the scene, its models,
/// their buffers and every texture.
pub const MAX_SCENE_TOTAL_BYTES: u64 = 4 << 30;

/// Where a load reads its files: the file system, or files held in memory.
#[derive(Clone, Debug, Default)]
pub enum Files {
    /// The file system (the default).
    #[default]
    Disk,
    /// Only the files of this set, by path relative to its root (a web page's
    /// site): paths are checked as written, never against a real folder.
    Memory(Arc<FileSet>),
}

/// Two sources are equal when they are the disk, or the same set.
impl PartialEq for Files {
    fn eq(&self, other: &Self) -> bool {
        match (self, other) {
            (Files::Disk, Files::Disk) => true,
            (Files::Memory(a), Files::Memory(b)) => Arc::ptr_eq(a, b),
            _ => false,
        }
    }
}

impl Eq for Files {}

impl Files {
    /// The whole file at `path`, at most `limit` bytes (see [`read_file`]);
    /// from memory, a file the set lacks is noted as missing ([`FileSet::take_missing`]).
    pub(crate) fn read(&self, path: &Path, limit: u64) -> Result<Vec<u8>, Diagnostic> {
        match self {
            Files::Disk => read_file(path, limit),
            Files::Memory(set) => set.read(path, limit),
        }
    }

    /// How many reads have found the memory set lacking their file (always 0
    /// from disk). A load that sees this grow across a step knows the step
    /// failed for want of a file the page has yet to fetch, and may go on to
    /// find the others in the same pass (`.scn` blocks and textures do).
    pub(crate) fn misses(&self) -> usize {
        match self {
            Files::Disk => 0,
            Files::Memory(set) => set.misses.load(std::sync::atomic::Ordering::Relaxed),
        }
    }

    /// The pixels of the PNG or JPEG `bytes` as the host decoded them, or why it
    /// could not; `None` when glint decodes them itself (from disk, or a set
    /// without [`FileSet::host_decoding`]). An image the host has yet to decode
    /// is noted ([`FileSet::take_undecoded`]) and counted as a miss, like a file
    /// the set lacks, so a load goes past it to find the others.
    pub(crate) fn host_decoded(&self, bytes: &[u8]) -> Option<Result<image::RgbaImage, String>> {
        match self {
            Files::Memory(set) if set.host_decodes => Some(set.decoded(bytes)),
            _ => None,
        }
    }

    /// The size of the file at `path`, 0 when it cannot be had.
    pub(crate) fn size(&self, path: &Path) -> u64 {
        match self {
            Files::Disk => std::fs::metadata(path).map_or(0, |m| m.len()),
            Files::Memory(set) => set.lock().get(&normal(path)).map_or(0, |b| b.len() as u64),
        }
    }
}

/// Files held in memory by path (relative, `/`-separated, `.` and `..` applied),
/// for loading without a file system: the web viewer fetches a scene, loads it
/// from the set, fetches what the load found missing, and loads again.
///
/// A set made by [`FileSet::host_decoding`] also leaves PNG and JPEG decoding
/// to its host (a browser decodes them natively, so the page need not ship a
/// decoder): a load names the images it needs decoded as it names missing
/// files, and the host hands back their pixels between loads. So that a load
/// need not pass over its files once more only to name their images, a PNG or
/// JPEG file is named for decoding as soon as it is inserted.
#[derive(Debug, Default)]
pub struct FileSet {
    files: Mutex<HashMap<PathBuf, Arc<[u8]>>>,
    missing: Mutex<BTreeSet<PathBuf>>,
    misses: std::sync::atomic::AtomicUsize,
    host_decodes: bool,
    images: Mutex<HostImages>,
}

/// The images of a [`FileSet`] that its host decodes, by their encoded bytes.
#[derive(Debug, Default)]
struct HostImages {
    /// Pixels the host decoded, or why it could not.
    decoded: HashMap<Arc<[u8]>, Result<image::RgbaImage, String>>,
    /// Images a load asked for, or files inserted, since the last [`FileSet::take_undecoded`].
    undecoded: HashSet<Arc<[u8]>>,
    /// RGBA bytes, by their headers, of the files named for decoding as they
    /// were inserted: at most [`super::MAX_TEXTURE_MEMORY`], the most one load
    /// could decode (past it, only what a load asks for is decoded).
    inserted_bytes: u64,
}

impl FileSet {
    /// An empty set whose host decodes its PNG and JPEG images: loads ask for
    /// them through [`FileSet::take_undecoded`] and get them from
    /// [`FileSet::insert_decoded`]. glint still checks each image's format and
    /// size from its header, against the same limits, before asking.
    pub fn host_decoding() -> Self {
        Self { host_decodes: true, ..Self::default() }
    }

    /// The encoded images named for the host to decode since the last call: by
    /// loads, and by [`FileSet::insert`] as their files came in.
    pub fn take_undecoded(&self) -> Vec<Arc<[u8]>> {
        self.lock_images().undecoded.drain().collect()
    }

    /// Hand back what the host made of `encoded` (one of [`FileSet::take_undecoded`]'s):
    /// its width, height and RGBA8 pixels, top row first, not premultiplied and
    /// with no colour conversion, turned as its EXIF orientation says (as
    /// browsers do, and glint's own decoder); or why it could not decode them.
    pub fn insert_decoded(&self, encoded: Arc<[u8]>, decoded: Result<(u32, u32, Vec<u8>), String>) {
        let image = decoded.and_then(|(w, h, pixels)| {
            let len = pixels.len();
            image::RgbaImage::from_raw(w, h, pixels).ok_or_else(|| format!("{w} x {h} pixels in {len} bytes"))
        });
        self.lock_images().decoded.insert(encoded, image);
    }

    fn decoded(&self, bytes: &[u8]) -> Result<image::RgbaImage, String> {
        let mut images = self.lock_images();
        if let Some(decoded) = images.decoded.get(bytes) {
            return decoded.clone();
        }
        images.undecoded.insert(bytes.into());
        self.misses.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        Err("not decoded yet".into())
    }

    fn lock_images(&self) -> std::sync::MutexGuard<'_, HostImages> {
        self.images.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Add (or replace) the file at `path`. In a [`FileSet::host_decoding`]
    /// set, a PNG or JPEG whose header passes the texture checks is named for
    /// decoding at once ([`FileSet::take_undecoded`]), while the pixels of all
    /// so named stay within [`super::MAX_TEXTURE_MEMORY`].
    pub fn insert(&self, path: &Path, bytes: Vec<u8>) {
        let bytes: Arc<[u8]> = bytes.into();
        if self.host_decodes {
            self.name_for_decoding(&bytes);
        }
        self.lock().insert(normal(path), bytes);
    }

    fn name_for_decoding(&self, bytes: &Arc<[u8]>) {
        let Ok((w, h)) = super::texture::texture_size(bytes) else { return };
        let mut images = self.lock_images();
        let needs = images.inserted_bytes + 4 * u64::from(w) * u64::from(h);
        if needs <= super::MAX_TEXTURE_MEMORY
            && !images.decoded.contains_key(bytes)
            && images.undecoded.insert(bytes.clone())
        {
            images.inserted_bytes = needs;
        }
    }

    /// The paths reads asked for that the set lacked, since the last call.
    pub fn take_missing(&self) -> Vec<PathBuf> {
        std::mem::take(&mut *self.missing.lock().unwrap_or_else(|e| e.into_inner())).into_iter().collect()
    }

    /// Total bytes held.
    pub fn bytes(&self) -> u64 {
        self.lock().values().map(|b| b.len() as u64).sum()
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, HashMap<PathBuf, Arc<[u8]>>> {
        self.files.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn read(&self, path: &Path, limit: u64) -> Result<Vec<u8>, Diagnostic> {
        let key = normal(path);
        let Some(bytes) = self.lock().get(&key).cloned() else {
            self.missing.lock().unwrap_or_else(|e| e.into_inner()).insert(key);
            self.misses.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            return Err(Diagnostic::file(path, "cannot read: not found"));
        };
        if bytes.len() as u64 > limit {
            return Err(over_limit(path, bytes.len() as u64, limit));
        }
        Ok(bytes.to_vec())
    }
}

/// `path` relative to a set's root with `.` and `..` applied (a `..` above
/// the root is dropped: [`AssetFolder::resolve`] refuses such paths first).
fn normal(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::ParentDir => {
                out.pop();
            }
            Component::Normal(part) => out.push(part),
            Component::CurDir | Component::RootDir | Component::Prefix(_) => {}
        }
    }
    out
}

/// Whether `path` (relative) stays inside its root when `..` is applied as written.
fn stays_inside(path: &Path) -> bool {
    let mut depth = 0usize;
    for c in path.components() {
        match c {
            Component::ParentDir if depth == 0 => return false,
            Component::ParentDir => depth -= 1,
            Component::Normal(_) => depth += 1,
            Component::CurDir => {}
            Component::RootDir | Component::Prefix(_) => return false,
        }
    }
    true
}

/// Read the whole file at `path`, refusing anything but a regular file (FIFOs,
/// devices and directories would block or never end) and files over `limit`
/// bytes.
///
/// The size comes from the file's metadata before anything is read, and the read
/// itself stops one byte past `limit`, so a file that grows meanwhile is refused
/// too. Errors name `path`.
pub fn read_file(path: &Path, limit: u64) -> Result<Vec<u8>, Diagnostic> {
    let fail = |e: std::io::Error| Diagnostic::file(path, format!("cannot read: {e}"));
    // Checked before opening: opening a FIFO for reading blocks until a writer comes.
    let size = regular_size(path, std::fs::metadata(path).map_err(fail)?, limit)?;
    let file = std::fs::File::open(path).map_err(fail)?;
    // The path may have been swapped between the check and the open.
    regular_size(path, file.metadata().map_err(fail)?, limit)?;
    let mut bytes = Vec::with_capacity(usize::try_from(size).unwrap_or(0));
    file.take(limit.saturating_add(1)).read_to_end(&mut bytes).map_err(fail)?;
    if bytes.len() as u64 > limit {
        return Err(over_limit(path, bytes.len() as u64, limit));
    }
    Ok(bytes)
}

/// The size of a regular file, or why it is not read.
fn regular_size(path: &Path, meta: std::fs::Metadata, limit: u64) -> Result<u64, Diagnostic> {
    if !meta.is_file() {
        return Err(Diagnostic::file(path, "not a regular file"));
    }
    if meta.len() > limit {
        return Err(over_limit(path, meta.len(), limit));
    }
    Ok(meta.len())
}

fn over_limit(path: &Path, size: u64, limit: u64) -> Diagnostic {
    Diagnostic::file(path, format!("{size} bytes is larger than the {limit}-byte limit for this kind of file"))
}

/// The folder a file's relative paths resolve in, and the roots they must stay
/// inside (after symlinks are resolved) unless outside assets are allowed.
pub(crate) struct AssetFolder {
    folder: PathBuf,
    /// Canonical folders a resolved path must lie in.
    roots: Vec<PathBuf>,
    allow_outside: bool,
    /// What `roots` are called in messages ("the model's folder").
    roots_name: &'static str,
    /// Where its files are read.
    pub(crate) files: Files,
}

impl AssetFolder {
    /// For a model file `path`: its own folder, plus `options.asset_roots`.
    pub(crate) fn of(path: &Path, options: &LoadOptions) -> Self {
        let folder = parent(path);
        let mut roots = vec![canonical(&folder)];
        roots.extend(options.asset_roots.iter().map(|r| canonical(r)));
        let roots_name = if options.asset_roots.is_empty() { "the model's folder" } else { "the asset roots" };
        let (allow_outside, files) = (options.allow_outside_assets, options.files.clone());
        Self { folder, roots, allow_outside, roots_name, files }
    }

    /// For a scene file `path`: its own folder, widened to the current directory
    /// when the scene lies inside it (so `glint render scenes/x.scn` may use
    /// `../assets`), plus `options.asset_roots`.
    pub(crate) fn for_scene(path: &Path, options: &LoadOptions) -> Self {
        let folder = parent(path);
        let own = canonical(&folder);
        let mut roots = vec![own.clone()];
        if let Ok(cwd) = std::env::current_dir().and_then(std::fs::canonicalize) {
            if own.starts_with(&cwd) {
                roots.push(cwd);
            }
        }
        roots.extend(options.asset_roots.iter().map(|r| canonical(r)));
        let (allow_outside, files) = (options.allow_outside_assets, options.files.clone());
        Self { folder, roots, allow_outside, roots_name: "the scene's asset roots", files }
    }

    /// Resolve `relative` (as written in `file`): the path to read, which after
    /// resolving symlinks lies inside the roots, unless outside assets are
    /// allowed. URIs with a scheme (`file:`, `http:`) are outside by definition.
    /// A path that does not exist is checked as written (reading it then fails).
    pub(crate) fn resolve(&self, relative: &str, file: &Path) -> Result<PathBuf, Diagnostic> {
        let path = self.folder.join(relative);
        if self.allow_outside {
            return Ok(path);
        }
        let outside = || {
            let message = format!(
                "{} points outside {}; only paths inside it are read (--asset-root DIR widens it, --allow-outside-assets lifts it)",
                crate::text::quote(relative),
                self.roots_name
            );
            Diagnostic::file(file, message)
        };
        let scheme = relative.split_once(':').is_some_and(|(s, _)| s.len() > 1 && !s.contains(['/', '\\']));
        if scheme {
            return Err(outside());
        }
        if let Files::Memory(_) = self.files {
            // In memory the root is the set's: the path as written must stay under it.
            return if stays_inside(&path) { Ok(path) } else { Err(outside()) };
        }
        let real = std::fs::canonicalize(&path).unwrap_or_else(|_| lexical(&canonical(&self.folder).join(relative)));
        if self.roots.iter().any(|root| real.starts_with(root)) {
            Ok(path)
        } else {
            Err(outside())
        }
    }
}

/// The folder of `path` ("" for a bare file name).
fn parent(path: &Path) -> PathBuf {
    path.parent().unwrap_or(Path::new("")).to_path_buf()
}

/// `path` with symlinks resolved, or made absolute and normalised as written
/// when it does not exist.
fn canonical(path: &Path) -> PathBuf {
    let path = if path.as_os_str().is_empty() { Path::new(".") } else { path };
    std::fs::canonicalize(path).unwrap_or_else(|_| lexical(path))
}

/// `path` made absolute against the current directory, with `.` and `..`
/// applied as written.
fn lexical(path: &Path) -> PathBuf {
    let absolute = std::env::current_dir().map(|cwd| cwd.join(path)).unwrap_or_else(|_| path.to_path_buf());
    let mut out = PathBuf::new();
    for c in absolute.components() {
        match c {
            Component::ParentDir => {
                out.pop();
            }
            Component::CurDir => {}
            other => out.push(other),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    #[cfg(unix)]
    use std::os::unix::fs::symlink;

    #[test]
    fn paths_stay_inside_the_model_folder() {
        let obj = Path::new("m/model.obj");
        let inside = AssetFolder::of(obj, &LoadOptions::default());
        assert_eq!(inside.resolve("tex/a.png", obj).expect("inside"), Path::new("m/tex/a.png"));
        assert!(inside.resolve("tex/../a.png", obj).is_ok());
        for outside in ["../secret.png", "tex/../../secret.png", "/etc/passwd", "file:///etc/passwd", "http://x/y.png"]
        {
            assert!(inside.resolve(outside, obj).is_err(), "{outside}");
        }
        let anywhere = AssetFolder::of(obj, &LoadOptions { allow_outside_assets: true, ..LoadOptions::default() });
        assert_eq!(anywhere.resolve("../shared/a.png", obj).expect("allowed"), Path::new("m/../shared/a.png"));
    }

    #[cfg(unix)]
    /// A fresh folder under the system's temporary directory.
    fn temp_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("glint-files-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("temp dir");
        dir
    }

    #[cfg(unix)]
    #[test]
    fn only_regular_files_are_read() {
        let dir = temp_dir("regular");
        let fifo = dir.join("pipe.obj");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status().expect("mkfifo runs");
        assert!(made.success());
        // Without the check this blocks for ever: nobody writes to the FIFO.
        let error = read_file(&fifo, MAX_MODEL_BYTES).expect_err("a FIFO is refused");
        assert!(error.to_string().ends_with("pipe.obj: not a regular file"), "{error}");
        symlink("/dev/zero", dir.join("zero.png")).expect("symlink");
        let error = read_file(&dir.join("zero.png"), MAX_IMAGE_FILE_BYTES).expect_err("a device is refused");
        assert!(error.message.contains("not a regular file"), "{error}");
        assert!(read_file(&dir, MAX_MODEL_BYTES).expect_err("a folder").message.contains("not a regular file"));
        std::fs::write(dir.join("big.mtl"), [b'#'; 100]).expect("write");
        let error = read_file(&dir.join("big.mtl"), 99).expect_err("over the limit");
        assert!(error.message.contains("100 bytes is larger than the 99-byte limit"), "{error}");
        assert_eq!(read_file(&dir.join("big.mtl"), 100).expect("at the limit").len(), 100);
    }

    #[cfg(unix)]
    #[test]
    fn symlinks_are_resolved_before_the_folder_check() {
        let dir = temp_dir("links");
        let model = dir.join("model");
        let elsewhere = dir.join("elsewhere");
        std::fs::create_dir_all(&model).expect("dir");
        std::fs::create_dir_all(&elsewhere).expect("dir");
        std::fs::write(elsewhere.join("x.mtl"), "newmtl a\n").expect("write");
        std::fs::write(model.join("own.mtl"), "newmtl a\n").expect("write");
        symlink(&elsewhere, model.join("linkdir")).expect("symlink");
        symlink("/etc/passwd", model.join("passwd.mtl")).expect("symlink");
        symlink(model.join("own.mtl"), model.join("alias.mtl")).expect("symlink");
        let obj = model.join("m.obj");
        let folder = AssetFolder::of(&obj, &LoadOptions::default());
        for escape in ["linkdir/x.mtl", "passwd.mtl", "../elsewhere/x.mtl", "/etc/passwd", "file:///etc/passwd"] {
            let error = folder.resolve(escape, &obj).expect_err(escape);
            assert!(error.message.contains("points outside the model's folder"), "{escape}: {error}");
        }
        assert_eq!(folder.resolve("alias.mtl", &obj).expect("a link inside stays inside"), model.join("alias.mtl"));
        assert_eq!(folder.resolve("missing.mtl", &obj).expect("checked as written"), model.join("missing.mtl"));
        // An asset root widens the folder; allowing outside assets lifts it.
        let widened = LoadOptions { asset_roots: vec![elsewhere.clone()], ..LoadOptions::default() };
        assert!(AssetFolder::of(&obj, &widened).resolve("linkdir/x.mtl", &obj).is_ok());
        assert!(AssetFolder::of(&obj, &widened).resolve("passwd.mtl", &obj).is_err());
        let anywhere = LoadOptions { allow_outside_assets: true, ..LoadOptions::default() };
        assert!(AssetFolder::of(&obj, &anywhere).resolve("passwd.mtl", &obj).is_ok());
    }
}
