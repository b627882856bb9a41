//! Hot reload: notice when the scene file changes on disk and load it again.

use glint::asset::{load_scene_with, LoadOptions, SceneDesc};
use glint::Diagnostic;
use std::path::{Path, PathBuf};
use std::time::SystemTime;

/// The scene file and the version of it last looked at (modification time and length).
pub struct SceneWatch {
    path: PathBuf,
    options: LoadOptions,
    seen: Option<(SystemTime, u64)>,
}

impl SceneWatch {
    /// Watch `path`, taking its current contents as already loaded.
    pub fn new(path: &Path, options: LoadOptions) -> Self {
        let mut watch = Self { path: path.to_path_buf(), options, seen: None };
        watch.seen = watch.version();
        watch
    }

    fn version(&self) -> Option<(SystemTime, u64)> {
        let meta = std::fs::metadata(&self.path).ok()?;
        Some((meta.modified().ok()?, meta.len()))
    }

    /// The scene loaded again if the file changed since the last call, or `None`.
    /// A file that cannot be read right now (mid-save) counts as unchanged.
    pub fn poll(&mut self) -> Option<Result<SceneDesc, Diagnostic>> {
        let version = self.version()?;
        if Some(version) == self.seen {
            return None;
        }
        self.seen = Some(version);
        Some(load_scene_with(&self.path, self.options.clone()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    /// Write `text` to `path`, dated `seconds` after the epoch, so changes are
    /// seen however coarse the file system's clock is.
    fn write(path: &Path, text: &str, seconds: u64) {
        std::fs::write(path, text).unwrap();
        let file = std::fs::File::options().write(true).open(path).unwrap();
        file.set_modified(SystemTime::UNIX_EPOCH + Duration::from_secs(seconds)).unwrap();
    }

    #[test]
    fn reloads_on_change_and_reports_errors_with_their_line() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.scn");
        write(&path, "{ \"classname\" \"entity\"\n\"mesh\" \"cube\" }\n", 1_000);
        let mut watch = SceneWatch::new(&path, LoadOptions::default());
        assert!(watch.poll().is_none(), "unchanged since it was loaded");

        write(&path, "{ \"classname\" \"entity\"\n\"mesh\" \"cube\"\n\"origin\" \"1 x 3\" }\n", 2_000);
        let err = watch.poll().expect("changed").unwrap_err().to_string();
        assert!(err.ends_with("s.scn:3: \"origin\": bad number 'x', expected 3 numbers (x y z)"), "{err}");
        assert!(watch.poll().is_none(), "a bad version is reported once");

        write(
            &path,
            "{ \"classname\" \"entity\"\n\"mesh\" \"sphere\" }\n{ \"classname\" \"entity\"\n\"mesh\" \"cube\" }\n",
            3_000,
        );
        let scene = watch.poll().expect("changed").expect("fixed");
        assert_eq!(scene.entities.len(), 2);

        std::fs::remove_file(&path).unwrap();
        assert!(watch.poll().is_none(), "a missing file (mid-save) is not a change");
    }
}
