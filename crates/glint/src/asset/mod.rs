//! Core layer: reading assets from files. Nothing read from a file is trusted:
//! sizes, counts, indices and paths are checked, and every problem comes back as a
//! [`Diagnostic`] naming the file, the line where there is one, and what was expected.

pub mod animation;
mod cloth_mesh;
mod environment;
mod files;
mod gltf;
mod gltf_check;
mod gltf_data;
mod gltf_lod;
#[cfg(test)]
mod gltf_tests;
mod model;
mod obj;
mod placement;
/// Procedural shapes (now plain data in [`scene`](crate::scene)), under their old path.
pub use crate::scene::procedural;
mod scene_desc;
mod scn;
mod scn_cloth;
mod scn_emitter;
mod scn_fields;
mod scn_lights;
mod scn_material;
mod scn_post;
mod scn_school;
mod scn_syntax;
mod scn_targets;
mod texture;

pub use crate::scene::cloth::ClothSetup;
pub use crate::scene::ShapeKind;
pub use cloth_mesh::{load_cloth_mesh, parse_nodes_triangles, read_cloth_mesh};
pub(crate) use environment::{decoded_bytes, read_environment};
pub use environment::{
    equirect_direction, equirect_uv, EnvironmentImage, MAX_ENVIRONMENT_PIXELS, MAX_HDR_HEADER_BYTES, MAX_RADIANCE,
};
pub(crate) use files::AssetFolder;
pub use files::{read_file, FileSet, Files};
pub use files::{
    MAX_BUFFER_BYTES, MAX_IMAGE_FILE_BYTES, MAX_MATERIAL_LIBRARY_BYTES, MAX_MODEL_BYTES, MAX_SCENE_BYTES,
    MAX_SCENE_TOTAL_BYTES,
};
pub use model::{Model, ModelPart, Morph, Skin};
pub use scene_desc::{
    CameraView, DrawOptions, EntityDesc, LightCircle, LightSway, MaterialDesc, MeshRef, SceneDesc, TextureRef,
};
pub use scn::{load_scene, load_scene_with, parse_scene, parse_scene_with, MAX_CAMERAS, MAX_INSTANCES};
pub use scn_cloth::{ClothDesc, MAX_POSE_STEPS};
pub use scn_emitter::{EmitterDesc, MAX_EMITTERS, MAX_POSE_PARTICLE_STEPS, MAX_SCENE_PARTICLES, STEP_OVERHEAD};
pub use scn_school::{SchoolDesc, MAX_POSE_SCHOOL_TESTS};
pub use scn_targets::{RenderTargetDesc, MAX_RENDER_TARGETS, MAX_RENDER_TARGET_BYTES, MAX_RENDER_TARGET_SIDE};
pub(crate) use texture::image_error;
pub use texture::{load_image, load_texture, Texture, MAX_TEXTURE_MEMORY, MAX_TEXTURE_SIDE};

use std::fmt;
use std::path::{Path, PathBuf};

/// How model and scene files are read: which folders the paths inside them may
/// name (see `docs/limits.md`).
#[derive(Clone, Debug, PartialEq)]
pub struct LoadOptions {
    /// Let files name assets outside their asset roots (absolute paths, `..` that
    /// leaves them, symlinks out, `file:` URIs). Off by default: a scene or model
    /// from elsewhere cannot make glint read arbitrary files.
    pub allow_outside_assets: bool,
    /// Folders besides a file's own that its paths may name (`--asset-root`). A
    /// scene's own folder counts, widened to the current directory when the scene
    /// lies inside it; a model's own folder counts.
    pub asset_roots: Vec<PathBuf>,
    /// Most bytes of decoded texture pixels the load may hold (default
    /// [`MAX_TEXTURE_MEMORY`]); a scene passes what it has left to its models.
    pub texture_memory: u64,
    /// How every cloth is solved, whatever its scene block says (`None`: as it says).
    pub cloth_solve: Option<crate::scene::cloth::Solve>,
    /// Where every school steps, whatever its block's `"sim"` says (`None`: as it says).
    pub sim: Option<crate::scene::SimPath>,
    /// A scene file's time of day, whatever its world block says (`None`: as
    /// it says; see [`SceneDesc::set_time_of_day`]).
    pub time_of_day: Option<f32>,
    /// How every camera of a scene file draws its transparency, whatever its
    /// world block's `"transparency"` says (`None`: as it says).
    pub transparency: Option<crate::scene::Transparency>,
    /// Where the files are read (default: the file system).
    pub files: Files,
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self {
            allow_outside_assets: false,
            asset_roots: Vec::new(),
            texture_memory: MAX_TEXTURE_MEMORY,
            cloth_solve: None,
            sim: None,
            time_of_day: None,
            transparency: None,
            files: Files::Disk,
        }
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

/// Shown within the message policy of [`crate::text`]: the path and the message
/// cut to their most characters, however long the input that made them.
impl fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use crate::text::{shorten, MAX_MESSAGE_CHARS, MAX_PATH_CHARS};
        let path = shorten(&self.path.display().to_string(), MAX_PATH_CHARS);
        let message = shorten(&self.message, MAX_MESSAGE_CHARS);
        match self.line {
            Some(line) => write!(f, "{path}:{line}: {message}"),
            None => write!(f, "{path}: {message}"),
        }
    }
}

impl std::error::Error for Diagnostic {}
