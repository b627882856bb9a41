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
mod scn_fields;
mod scn_syntax;
mod texture;

pub use gltf::MAX_GLTF_BYTES;
pub use model::{AddedModel, Model, ModelPart};
pub use obj::MAX_OBJ_BYTES;
pub use procedural::ShapeKind;
pub use scn::{load_scene, parse_scene, EntityDesc, MaterialDesc, MeshRef, SceneDesc, TextureRef, MAX_INSTANCES};
pub use texture::{load_texture, Texture, MAX_TEXTURE_SIDE};

use std::fmt;
use std::path::{Path, PathBuf};

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
