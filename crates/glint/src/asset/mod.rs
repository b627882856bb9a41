//! Core layer: reading assets from files. Nothing read from a file is trusted:
//! sizes, counts, indices and paths are checked, and every problem comes back as a
//! [`Diagnostic`] naming the file, the line where there is one, and what was expected.

pub mod animation;
mod gltf;
mod model;
mod obj;
mod placement;
pub mod procedural;
mod scn;
mod scn_cloth;
mod scn_fields;
mod scn_lights;
mod scn_syntax;
mod texture;

pub use model::{AddedModel, Model, ModelPart, Morph, Skin};
pub use procedural::ShapeKind;
pub use scn::{
    load_scene, load_scene_with, parse_scene, parse_scene_with, DrawOptions, EntityDesc, MaterialDesc, MeshRef,
    SceneDesc, TextureRef, MAX_INSTANCES,
};
pub use scn_cloth::{ClothDesc, ClothSetup, MAX_POSE_STEPS};
pub use texture::{load_texture, Texture, MAX_TEXTURE_SIDE};

use std::fmt;
use std::path::{Component, Path, PathBuf};

/// Largest model file (OBJ, MTL, glTF, GLB) read, in bytes.
pub const MAX_MODEL_BYTES: u64 = 1 << 31;

/// Read a whole model file, refusing ones larger than [`MAX_MODEL_BYTES`].
pub(crate) fn read_capped(path: &Path) -> Result<Vec<u8>, Diagnostic> {
    let size = std::fs::metadata(path).map_err(|e| Diagnostic::file(path, format!("cannot read: {e}")))?.len();
    if size > MAX_MODEL_BYTES {
        return Err(Diagnostic::file(path, format!("{size} bytes is larger than the {MAX_MODEL_BYTES}-byte limit")));
    }
    std::fs::read(path).map_err(|e| Diagnostic::file(path, format!("cannot read: {e}")))
}

/// How model files are read.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// Let a model name files outside its own folder (absolute paths, `..` that
    /// leaves it, `file:` URIs). Off by default: a model from elsewhere cannot
    /// make glint read arbitrary files.
    pub allow_outside_assets: bool,
}

/// The folder a model's relative paths resolve in, and whether they may leave it.
pub(crate) struct AssetFolder {
    folder: PathBuf,
    allow_outside: bool,
}

impl AssetFolder {
    /// The folder of the model file `path`.
    pub(crate) fn of(path: &Path, options: LoadOptions) -> Self {
        Self {
            folder: path.parent().unwrap_or(Path::new("")).to_path_buf(),
            allow_outside: options.allow_outside_assets,
        }
    }

    /// Resolve `relative` (as written in `file`): inside the folder only, unless
    /// outside assets are allowed. URIs with a scheme (`file:`, `http:`) are
    /// outside by definition.
    pub(crate) fn resolve(&self, relative: &str, file: &Path) -> Result<PathBuf, Diagnostic> {
        if self.allow_outside {
            return Ok(self.folder.join(relative));
        }
        let outside = || {
            let message = format!(
                "'{relative}' points outside the model's folder; only relative paths inside it are read (--allow-outside-assets reads it)"
            );
            Diagnostic::file(file, message)
        };
        let scheme = relative.split_once(':').is_some_and(|(s, _)| s.len() > 1 && !s.contains(['/', '\\']));
        if scheme {
            return Err(outside());
        }
        let mut depth = 0usize;
        for c in Path::new(relative).components() {
            match c {
                Component::Normal(_) => depth += 1,
                Component::CurDir => {}
                Component::ParentDir if depth > 0 => depth -= 1,
                _ => return Err(outside()),
            }
        }
        Ok(self.folder.join(relative))
    }
}

/// A problem in an input file: `path:line: message`, or `path: message` when no
/// line applies. Used for errors and for warnings.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Diagnostic {
    /// The file.
    pub path: PathBuf,
    /// 1-based line, when the problem has one.
    pub line: Option<usize>,
    /// What was wrong or expected.
    pub message: String,
}

impl Diagnostic {
    /// A diagnostic at `path:line`.
    pub fn at(path: &Path, line: usize, message: impl Into<String>) -> Self {
        Self { path: path.to_path_buf(), line: Some(line), message: message.into() }
    }

    /// A diagnostic for the whole file `path`.
    pub fn file(path: &Path, message: impl Into<String>) -> Self {
        Self { path: path.to_path_buf(), line: None, message: message.into() }
    }
}

impl fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(line) => write!(f, "{}:{}: {}", self.path.display(), line, self.message),
            None => write!(f, "{}: {}", self.path.display(), self.message),
        }
    }
}

impl std::error::Error for Diagnostic {}
