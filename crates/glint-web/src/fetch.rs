//! Loading a scene over HTTP: the scene is loaded from a [`FileSet`] in memory,
//! and whatever the load asked for and the set lacked is fetched (all of it at
//! once, relative to the page) before loading again, round by round, as the
//! loader's own checks allow: paths stay under the page's folder, each file within its kind's size
//! limit, the whole within one scene's total. A file the server does not have
//! stays missing and is reported by the loader with its `file:line`. The
//! browser decodes the PNG and JPEG images of each round's files, and those
//! a load asks for, before the next load ([`super::decode`]).

use glint::asset::{load_scene_with, FileSet, Files, LoadOptions, Model, SceneDesc, MAX_SCENE_TOTAL_BYTES};
use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use wasm_bindgen::JsCast;
use wasm_bindgen_futures::JsFuture;

/// Rounds of fetching. A load goes past a file the set lacks (or an image not
/// yet decoded) to the next texture or block, so a round fetches every file the
/// files of the last round name, and decodes the images among them: the
/// showcase takes two (the scene, then its environment and textures together).
/// Every round fetches a file not asked for before or decodes an image not
/// decoded before, so the rounds end; this bounds how deep one scene's files may name others.
const MAX_ROUNDS: usize = 64;

/// Largest file fetched at all (the loader's largest limit, a model or buffer).
const MAX_FETCH_BYTES: f64 = (1u64 << 30) as f64;

/// Milliseconds a load spent waiting for the network and for the browser's decoders.
#[derive(Default)]
pub struct Waits {
    /// Fetching files (every request of a round sent before the first answer is read).
    pub fetch: f64,
    /// Decoding images.
    pub decode: f64,
}

/// Load the scene (or model, shown alone) at `path`, relative to the page,
/// adding the time spent waiting to `waits`.
pub async fn load(path: &str, waits: &mut Waits) -> Result<SceneDesc, String> {
    let set = Arc::new(FileSet::host_decoding());
    let options = LoadOptions { files: Files::Memory(set.clone()), ..Default::default() };
    let path = Path::new(path);
    let mut asked = HashSet::new();
    for _ in 0..MAX_ROUNDS {
        let result = match Model::is_model_path(path) {
            true => Model::load_with(path, options.clone()).map(Model::into_shown_scene),
            false => load_scene_with(path, options.clone()),
        };
        let missing: Vec<PathBuf> = set.take_missing().into_iter().filter(|p| asked.insert(p.clone())).collect();
        let undecoded = set.take_undecoded();
        if missing.is_empty() && undecoded.is_empty() {
            return result.map_err(|e| e.to_string());
        }
        let started = super::startup::now();
        // Every request is sent before the first answer is read.
        let requests =
            missing.into_iter().map(|file| request(&file).map(|r| (file, r))).collect::<Result<Vec<_>, _>>()?;
        for (file, request) in requests {
            if let Some(bytes) = request.receive().await? {
                set.insert(&file, bytes);
            }
        }
        let decoding = super::startup::now();
        waits.fetch += decoding - started;
        // The images the load asked for, and those just fetched (the next load would ask for them).
        let undecoded = undecoded.into_iter().chain(set.take_undecoded()).collect();
        for (encoded, decoded) in super::decode::decode_all(undecoded).await? {
            set.insert_decoded(encoded, decoded);
        }
        waits.decode += super::startup::now() - decoding;
        if set.bytes() > MAX_SCENE_TOTAL_BYTES {
            let limit = MAX_SCENE_TOTAL_BYTES;
            return Err(format!("{}: its files are over the {limit}-byte limit for one scene", path.display()));
        }
    }
    Err(format!("{}: still naming new files after {MAX_ROUNDS} rounds of fetching", path.display()))
}

/// A request sent for one file under the page.
struct Request {
    url: String,
    response: JsFuture,
}

/// Send the request for the file at `path` under the page.
fn request(path: &Path) -> Result<Request, String> {
    let url: Vec<String> = path.components().map(|c| c.as_os_str().to_string_lossy().into_owned()).collect();
    let url = url.join("/");
    let window = web_sys::window().ok_or("no window")?;
    let response = JsFuture::from(window.fetch_with_str(&url));
    Ok(Request { url, response })
}

impl Request {
    /// The file's bytes, or `None` when the server has none.
    async fn receive(self) -> Result<Option<Vec<u8>>, String> {
        let url = self.url;
        let failed = |e: wasm_bindgen::JsValue| format!("{url}: cannot fetch: {e:?}");
        let response: web_sys::Response = self.response.await.map_err(failed)?.dyn_into().map_err(failed)?;
        if !response.ok() {
            return Ok(None);
        }
        let length = response.headers().get("content-length").ok().flatten().and_then(|l| l.parse::<f64>().ok());
        if length.is_some_and(|l| l > MAX_FETCH_BYTES) {
            return Err(format!("{url}: larger than the {MAX_FETCH_BYTES}-byte limit for any file"));
        }
        let body = JsFuture::from(response.array_buffer().map_err(failed)?).await.map_err(failed)?;
        Ok(Some(js_sys::Uint8Array::new(&body).to_vec()))
    }
}
