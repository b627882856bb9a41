//! Core layer: the bytes a glTF file names, read without the gltf crate's
//! importers (which open any path with `std::fs`, block on FIFOs, read a buffer
//! of any size whole and decode every image, used or not).
//!
//! Buffers come from the GLB binary chunk, from `data:` URIs (their decoded size
//! checked before decoding) or from files read through [`Files::read`](super::Files::read) with
//! [`MAX_BUFFER_BYTES`]; together one model's buffers may declare at most
//! [`MAX_BUFFER_BYTES`]. Images are read only when a material uses them, files
//! through [`Files::read`](super::Files::read) with [`MAX_IMAGE_FILE_BYTES`].

use super::{AssetFolder, Diagnostic, MAX_BUFFER_BYTES, MAX_IMAGE_FILE_BYTES};
use gltf::json;
use std::borrow::Cow;
use std::path::{Path, PathBuf};

/// Where a glTF file's URIs resolve: the model file and its asset folder.
pub(super) struct UriBase<'a> {
    /// The glTF or GLB file (named in messages).
    pub(super) path: &'a Path,
    pub(super) assets: &'a AssetFolder,
}

impl UriBase<'_> {
    /// The file a URI that is not `data:` names, checked to lie inside the asset
    /// folder. A relative URI is percent-decoded first (as the gltf crate did).
    pub(super) fn file(&self, uri: &str) -> Result<PathBuf, Diagnostic> {
        let decode = |s: &str| {
            urlencoding::decode(s).map(|d| d.into_owned()).map_err(|_| {
                Diagnostic::file(
                    self.path,
                    format!("uri {}: percent-encoding does not decode to UTF-8", crate::text::quote(uri)),
                )
            })
        };
        if !uri.contains(':') {
            return self.assets.resolve(&decode(uri)?, self.path);
        }
        // A scheme is refused unless outside assets are allowed; a `file:` URI
        // then names its path.
        let resolved = self.assets.resolve(uri, self.path)?;
        match uri.strip_prefix("file://") {
            Some(rest) => self.assets.resolve(&decode(rest)?, self.path),
            None => Ok(resolved),
        }
    }

    /// Check every buffer and image URI before anything is read, so a file that
    /// names something outside its folder is refused whole.
    pub(super) fn check_uris(&self, root: &json::Root) -> Result<(), Diagnostic> {
        let uris = root.buffers.iter().filter_map(|b| b.uri.as_deref());
        for uri in uris.chain(root.images.iter().filter_map(|i| i.uri.as_deref())) {
            if !uri.starts_with("data:") {
                self.file(uri)?;
            }
        }
        Ok(())
    }
}

/// Decode a base64 `data:` URI's payload, refusing (before decoding) one that
/// would be more than `limit` bytes.
fn decode_data_uri(uri: &str, limit: u64) -> Result<Vec<u8>, String> {
    let rest = uri.strip_prefix("data:").ok_or("not a data: URI")?;
    let (header, data) = rest.split_once(',').ok_or("a data: URI needs a ',' before its data")?;
    if !header.ends_with(";base64") {
        return Err("only base64 data: URIs are read".into());
    }
    let decoded = data.len() as u64 / 4 * 3;
    if decoded > limit {
        return Err(format!("data: URI of about {decoded} bytes is larger than the {limit}-byte limit"));
    }
    base64::decode(data).map_err(|e| format!("data: URI is not valid base64: {e}"))
}

/// Every buffer's bytes, in order, cut to its `byteLength` (a buffer shorter
/// than that is left short for [`super::gltf_check::check_buffers`] to report).
/// `blob` is a GLB file's binary chunk, which only buffer 0 may name (by having
/// no URI).
pub(super) fn read_buffers(
    root: &json::Root,
    blob: Option<Vec<u8>>,
    base: &UriBase,
) -> Result<Vec<Vec<u8>>, Diagnostic> {
    let fail = |m: String| Diagnostic::file(base.path, m);
    let declared: u128 = root.buffers.iter().map(|b| u128::from(b.byte_length.0)).sum();
    if declared > u128::from(MAX_BUFFER_BYTES) {
        return Err(fail(format!(
            "the buffers declare {declared} bytes in all, more than the {MAX_BUFFER_BYTES}-byte limit for one model"
        )));
    }
    let mut blob = blob;
    let mut buffers = Vec::with_capacity(root.buffers.len());
    for (i, buffer) in root.buffers.iter().enumerate() {
        let mut bytes = match buffer.uri.as_deref() {
            None if i == 0 => blob.take().ok_or_else(|| fail("buffer 0: no uri and no GLB binary chunk".into()))?,
            None => return Err(fail(format!("buffer {i}: no uri (only buffer 0 may be the GLB binary chunk)"))),
            Some(uri) if uri.starts_with("data:") => {
                decode_data_uri(uri, MAX_BUFFER_BYTES).map_err(|e| fail(format!("buffer {i}: {e}")))?
            }
            Some(uri) => base.assets.files.read(&base.file(uri)?, MAX_BUFFER_BYTES)?,
        };
        let length = usize::try_from(buffer.byte_length.0).unwrap_or(usize::MAX);
        bytes.truncate(length);
        buffers.push(bytes);
    }
    Ok(buffers)
}

/// The encoded bytes of image `index` (a file, a `data:` URI or a buffer view
/// of the already read `buffers`), or why they cannot be had.
pub(super) fn read_image<'b>(
    root: &json::Root,
    index: usize,
    buffers: &'b [Vec<u8>],
    base: &UriBase,
) -> Result<Cow<'b, [u8]>, String> {
    let image = root.images.get(index).ok_or("no such image")?;
    if let Some(uri) = image.uri.as_deref() {
        if uri.starts_with("data:") {
            return decode_data_uri(uri, MAX_IMAGE_FILE_BYTES).map(Cow::Owned);
        }
        let file = base.file(uri).map_err(|e| e.message)?;
        return base.assets.files.read(&file, MAX_IMAGE_FILE_BYTES).map(Cow::Owned).map_err(|e| e.to_string());
    }
    let outside = || "its bufferView lies outside the buffers".to_string();
    let view = image.buffer_view.and_then(|v| root.buffer_views.get(v.value())).ok_or_else(outside)?;
    let start = usize::try_from(view.byte_offset.map_or(0, |o| o.0)).map_err(|_| outside())?;
    let length = usize::try_from(view.byte_length.0).map_err(|_| outside())?;
    let end = start.checked_add(length).ok_or_else(outside)?;
    let bytes = buffers.get(view.buffer.value()).and_then(|b| b.get(start..end)).ok_or_else(outside)?;
    Ok(Cow::Borrowed(bytes))
}
