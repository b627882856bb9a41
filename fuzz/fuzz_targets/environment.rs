//! Environment images from bytes: the first byte picks Radiance `.hdr` or
//! OpenEXR, the rest is the file, loaded as a scene's world `environment` from
//! memory with 64 MiB of texture memory. Headers are checked before the
//! decoders read them: an environment or an error, never a panic, an abort
//! or a runaway allocation.
#![no_main]

use glint::asset::{load_scene_with, FileSet, Files, LoadOptions};
use libfuzzer_sys::fuzz_target;
use std::path::Path;
use std::sync::Arc;

fuzz_target!(|data: &[u8]| {
    let Some((&kind, bytes)) = data.split_first() else { return };
    let name = if kind % 2 == 0 { "sky.hdr" } else { "sky.exr" };
    let set = Arc::new(FileSet::default());
    let scene = format!("{{\n\"classname\" \"world\"\n\"environment\" \"{name}\"\n}}\n");
    set.insert(Path::new("fuzz.scn"), scene.into_bytes());
    set.insert(Path::new(name), bytes.to_vec());
    let options = LoadOptions { files: Files::Memory(set), texture_memory: 64 << 20, ..LoadOptions::default() };
    let _ = load_scene_with(Path::new("fuzz.scn"), options);
});
