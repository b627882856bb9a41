//! Levels of detail kept on disk between runs, for meshes large enough that
//! making them takes longer than reading them: a million triangles take about
//! 1.6 s to simplify and 3 ms to read back
//! (`cargo bench -p glint --bench levels`).
//!
//! A file is named by a 128-bit hash (xxh3) of what the levels are made from:
//! the mesh's vertices, skin and indices, glint's version and this format's.
//! Layout (little-endian): the 8 bytes `GLINTLOD`, the level count (u32), then
//! per level its error (f32) and index count (u32), then every level's indices
//! (u32). Nothing read is trusted: a file whose size, counts, errors or indices
//! do not fit the mesh is made again and written over. Writing goes through a
//! temporary file and a rename, so a reader never sees half a file; a folder
//! past [`CACHE_BYTES`] loses the files least recently used (a read touches
//! its file). Failures to read or write are
//! logged and the levels are made as without a cache (also on the web page,
//! which has no files).

use crate::scene::levels::{detail_levels, DetailLevel, MAX_LEVELS};
use crate::scene::Mesh;
use std::path::{Path, PathBuf};

/// Meshes with fewer triangles make their levels each time (under about 0.2 s).
pub const CACHE_FROM: usize = 100_000;

/// The most bytes the cache folder keeps; the oldest files go first.
pub const CACHE_BYTES: u64 = 1 << 30;

const MAGIC: &[u8; 8] = b"GLINTLOD";
/// Changed whenever the levels made from the same mesh change.
const FORMAT: u32 = 1;

/// Where a mesh's levels came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LevelSource {
    /// Made now (too small to cache, not in the cache, or a bad file there).
    Made,
    /// Read from the cache.
    Read,
}

/// A folder of cached levels of detail.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LevelCache {
    dir: PathBuf,
}

impl LevelCache {
    /// A cache in `dir` (made when first written).
    pub fn new(dir: impl Into<PathBuf>) -> Self {
        Self { dir: dir.into() }
    }

    /// The user's cache: `$GLINT_CACHE_DIR/levels`, else
    /// `$XDG_CACHE_HOME/glint/levels`, else `$HOME/.cache/glint/levels`; none
    /// where none is set, or `GLINT_CACHE_DIR` is set empty (no cache).
    pub fn user() -> Option<Self> {
        let var = |name: &str| std::env::var_os(name);
        let root = match var("GLINT_CACHE_DIR") {
            Some(dir) if dir.is_empty() => return None,
            Some(dir) => PathBuf::from(dir),
            None => (var("XDG_CACHE_HOME").filter(|d| !d.is_empty()).map(PathBuf::from))
                .or_else(|| var("HOME").filter(|d| !d.is_empty()).map(|h| PathBuf::from(h).join(".cache")))?
                .join("glint"),
        };
        Some(Self::new(root.join("levels")))
    }

    /// The folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The levels of `mesh` ([`detail_levels`]): read from the folder where a
    /// run made them for the same mesh before, else made (and written there
    /// for a mesh of [`CACHE_FROM`] triangles or more).
    pub fn levels(&self, mesh: &Mesh) -> (Vec<DetailLevel>, LevelSource) {
        self.levels_from(mesh, CACHE_FROM)
    }

    fn levels_from(&self, mesh: &Mesh, from: usize) -> (Vec<DetailLevel>, LevelSource) {
        // The web page has no files (and leaves the hashing and file code out).
        if cfg!(target_arch = "wasm32") || mesh.indices().len() / 3 < from || !mesh.given_levels().is_empty() {
            return (detail_levels(mesh), LevelSource::Made);
        }
        let path = self.dir.join(format!("{:032x}.lod", key(mesh)));
        match read_bounded(&path, mesh).and_then(|bytes| decode(&bytes, mesh)) {
            Ok(levels) => {
                // Kept in use: the folder is trimmed oldest first.
                let touched = std::fs::File::options()
                    .append(true)
                    .open(&path)
                    .and_then(|f| f.set_modified(std::time::SystemTime::now()));
                if let Err(e) = touched {
                    log::debug!("{}: {e}", path.display());
                }
                return (levels, LevelSource::Read);
            }
            Err(e) if path.exists() => log::warn!("{}: {e}; levels made again", path.display()),
            Err(_) => {}
        }
        let levels = detail_levels(mesh);
        if let Err(e) = self.write(&path, &encode(&levels)) {
            log::warn!("{}: levels of detail not cached: {e}", path.display());
        }
        (levels, LevelSource::Made)
    }

    /// Write `bytes` to `path` through a temporary file of this process and
    /// thread, then trim the folder.
    fn write(&self, path: &Path, bytes: &[u8]) -> std::io::Result<()> {
        std::fs::create_dir_all(&self.dir)?;
        let thread = format!("{:?}", std::thread::current().id()).replace(|c: char| !c.is_ascii_digit(), "");
        let temporary = path.with_extension(format!("tmp{}-{thread}", std::process::id()));
        let written = std::fs::write(&temporary, bytes).and_then(|()| std::fs::rename(&temporary, path));
        if written.is_err() {
            let _ = std::fs::remove_file(&temporary);
        }
        written?;
        self.trim(CACHE_BYTES)
    }

    /// Remove the oldest `.lod` files until the folder holds at most `most` bytes.
    fn trim(&self, most: u64) -> std::io::Result<()> {
        let mut files = Vec::new();
        for entry in std::fs::read_dir(&self.dir)? {
            let entry = entry?;
            let meta = entry.metadata()?;
            if meta.is_file() && entry.path().extension().is_some_and(|e| e == "lod") {
                files.push((meta.modified()?, meta.len(), entry.path()));
            }
        }
        files.sort();
        let mut total: u64 = files.iter().map(|f| f.1).sum();
        for (_, len, path) in files {
            if total <= most {
                break;
            }
            std::fs::remove_file(path)?;
            total -= len;
        }
        Ok(())
    }
}

/// The bytes of `path` if it is a regular file no longer than levels of
/// `mesh` can be (so a link to a device or a huge file is not read).
fn read_bounded(path: &Path, mesh: &Mesh) -> Result<Vec<u8>, String> {
    let meta = std::fs::metadata(path).map_err(|e| e.to_string())?;
    // Each level has at most three quarters of the indices of the one before.
    let most = 12 + 8 * (MAX_LEVELS as u64 - 1) + 4 * 3 * mesh.indices().len() as u64;
    if !meta.is_file() || meta.len() > most {
        return Err(format!("not a regular file of at most {most} bytes"));
    }
    std::fs::read(path).map_err(|e| e.to_string())
}

/// What the levels are made from, hashed.
fn key(mesh: &Mesh) -> u128 {
    let mut hasher = xxhash_rust::xxh3::Xxh3::new();
    hasher.update(MAGIC);
    hasher.update(&FORMAT.to_le_bytes());
    hasher.update(env!("CARGO_PKG_VERSION").as_bytes());
    hasher.update(&(mesh.vertices().len() as u64).to_le_bytes());
    hasher.update(bytemuck::cast_slice(mesh.vertices()));
    hasher.update(bytemuck::cast_slice(mesh.skin().unwrap_or(&[])));
    hasher.update(bytemuck::cast_slice(mesh.indices()));
    hasher.digest128()
}

fn encode(levels: &[DetailLevel]) -> Vec<u8> {
    let mut bytes = MAGIC.to_vec();
    bytes.extend((levels.len() as u32).to_le_bytes());
    for level in levels {
        bytes.extend(level.error.to_le_bytes());
        bytes.extend((level.indices.len() as u32).to_le_bytes());
    }
    for level in levels {
        bytes.extend(level.indices.iter().flat_map(|i| i.to_le_bytes()));
    }
    bytes
}

/// The levels in `bytes`, if they are levels `detail_levels` could have made
/// for `mesh`: at most `MAX_LEVELS - 1`, each of whole triangles and at most
/// three quarters of the one before, errors finite and non-decreasing, every
/// index a vertex of the mesh, and nothing after them.
fn decode(bytes: &[u8], mesh: &Mesh) -> Result<Vec<DetailLevel>, String> {
    let mut at = 0usize;
    let mut take = |n: usize| -> Result<&[u8], String> {
        let piece = bytes.get(at..at + n).ok_or("the file ends early")?;
        at += n;
        Ok(piece)
    };
    let word = |b: &[u8]| u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
    if take(8)? != MAGIC {
        return Err("not a levels file".into());
    }
    let count = word(take(4)?) as usize;
    if count >= MAX_LEVELS {
        return Err(format!("{count} levels, past {}", MAX_LEVELS - 1));
    }
    let (mut heads, mut before, mut last_error) = (Vec::with_capacity(count), mesh.indices().len(), 0.0f32);
    for _ in 0..count {
        let (error, indices) = (f32::from_bits(word(take(4)?)), word(take(4)?) as usize);
        if !error.is_finite() || error < last_error || indices % 3 != 0 || indices == 0 || indices * 4 > before * 3 {
            return Err("a level's error or index count does not fit the mesh".into());
        }
        heads.push((error, indices));
        (before, last_error) = (indices, error);
    }
    let vertices = mesh.vertices().len();
    let mut levels = Vec::with_capacity(count);
    for (error, n) in heads {
        let indices: Vec<u32> = take(n * 4)?.chunks_exact(4).map(word).collect();
        if indices.iter().any(|&i| i as usize >= vertices) {
            return Err("an index past the mesh's vertices".into());
        }
        levels.push(DetailLevel { indices, error });
    }
    if at != bytes.len() {
        return Err("bytes after the levels".into());
    }
    Ok(levels)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::procedural;

    fn folder(name: &str) -> LevelCache {
        let dir = std::env::temp_dir().join(format!("glint-level-cache-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        LevelCache::new(dir)
    }

    fn files(cache: &LevelCache) -> Vec<PathBuf> {
        let mut paths: Vec<PathBuf> = std::fs::read_dir(cache.dir()).unwrap().map(|e| e.unwrap().path()).collect();
        paths.sort();
        paths
    }

    #[test]
    fn levels_are_made_once_then_read_and_equal() {
        let cache = folder("once");
        let sphere = procedural::sphere(48, 32);
        let (made, source) = cache.levels_from(&sphere, 0);
        assert_eq!(source, LevelSource::Made);
        assert_eq!(files(&cache).len(), 1, "one file, no temporary left");
        let (read, source) = cache.levels_from(&sphere, 0);
        assert_eq!((source, &read), (LevelSource::Read, &made));
        assert_eq!(made, detail_levels(&sphere));
        // Another mesh is another file.
        assert_eq!(cache.levels_from(&procedural::sphere(40, 32), 0).1, LevelSource::Made);
        assert_eq!(files(&cache).len(), 2);
        // Small meshes are not cached.
        assert_eq!(cache.levels(&procedural::sphere(30, 20)).1, LevelSource::Made);
        assert_eq!(files(&cache).len(), 2);
        std::fs::remove_dir_all(cache.dir()).unwrap();
    }

    #[test]
    fn a_bad_file_is_made_again_and_written_over() {
        let cache = folder("bad");
        let sphere = procedural::sphere(48, 32);
        let (made, _) = cache.levels_from(&sphere, 0);
        let path = files(&cache).remove(0);
        let good = std::fs::read(&path).unwrap();
        let index_at = 12 + 8 * made.len();
        let mut past = good.clone();
        past[index_at..index_at + 4].copy_from_slice(&(sphere.vertices().len() as u32).to_le_bytes());
        let mut huge = good.clone();
        huge[12 + 4..12 + 8].copy_from_slice(&u32::MAX.to_le_bytes());
        let mut longer = good.clone();
        longer.push(0);
        let mut nan = good.clone();
        nan[12..16].copy_from_slice(&f32::NAN.to_le_bytes());
        for bad in [good[..good.len() - 4].to_vec(), past, huge, longer, nan, b"GLINTLOX".to_vec(), Vec::new()] {
            assert!(decode(&bad, &sphere).is_err());
            std::fs::write(&path, &bad).unwrap();
            let (levels, source) = cache.levels_from(&sphere, 0);
            assert_eq!((source, &levels), (LevelSource::Made, &made));
            assert_eq!(std::fs::read(&path).unwrap(), good, "written over with good levels");
        }
        // Too long for any levels of the mesh, or not a file: not read at all.
        std::fs::write(&path, vec![0u8; 16 * sphere.indices().len()]).unwrap();
        assert!(read_bounded(&path, &sphere).unwrap_err().contains("not a regular file of at most"));
        assert!(read_bounded(cache.dir(), &sphere).is_err());
        assert_eq!(cache.levels_from(&sphere, 0), (made, LevelSource::Made));
        std::fs::remove_dir_all(cache.dir()).unwrap();
    }

    #[test]
    fn the_folder_keeps_the_newest_files_within_its_bytes() {
        let cache = folder("trim");
        for segments in [40, 44, 48] {
            cache.levels_from(&procedural::sphere(segments, 32), 0);
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        let sizes: Vec<u64> = files(&cache).iter().map(|p| std::fs::metadata(p).unwrap().len()).collect();
        let newest = std::fs::read(cache.dir().join(format!("{:032x}.lod", key(&procedural::sphere(48, 32))))).unwrap();
        cache.trim(newest.len() as u64).unwrap();
        assert_eq!(sizes.len(), 3);
        let kept = files(&cache);
        assert_eq!(kept.len(), 1, "{kept:?}");
        assert_eq!(std::fs::read(&kept[0]).unwrap(), newest);
        std::fs::remove_dir_all(cache.dir()).unwrap();
    }
}
