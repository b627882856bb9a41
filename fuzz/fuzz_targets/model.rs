//! Model loading from bytes: the first byte picks OBJ or glTF/GLB, the rest is
//! the file. Files it names resolve in a folder that does not exist, so only the
//! parsers, validation and mesh building run: a model or an error, never a panic.
#![no_main]

use glint::asset::{LoadOptions, Model};
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Some((&kind, bytes)) = data.split_first() else { return };
    let name = match kind % 3 {
        0 => "/nonexistent/fuzz.obj",
        1 => "/nonexistent/fuzz.gltf",
        _ => "/nonexistent/fuzz.glb",
    };
    let _ = Model::parse(Path::new(name), bytes, LoadOptions::default());
});
