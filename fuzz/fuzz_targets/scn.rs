//! The `.scn` parser on arbitrary text: a scene or a `file:line` error, never a
//! panic or a hang. Texture and model paths resolve in a folder that does not
//! exist, so only the parser and validation run.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = glint::asset::parse_scene(std::path::Path::new("/nonexistent/fuzz.scn"), text);
    }
});
