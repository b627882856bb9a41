//! Core layer: [`Texture`], decoded pixels of a PNG or JPEG image, read
//! within [`MAX_TEXTURE_SIDE`] and [`MAX_TEXTURE_MEMORY`] (the header checked
//! before any pixel is decoded).

use super::{Diagnostic, TextureRef, MAX_IMAGE_FILE_BYTES};
pub use crate::scene::Texture;
use std::collections::HashMap;
use std::hash::Hash;
use std::path::Path;

/// Largest accepted side of a texture, in pixels.
pub const MAX_TEXTURE_SIDE: u32 = 8192;

/// Most decoded texture memory (RGBA8 pixels, before mipmaps) that one scene,
/// with every model it places, or one model loaded alone may hold: four
/// 8192 × 8192 textures, or sixty-four of 2048 × 2048.
pub const MAX_TEXTURE_MEMORY: u64 = 1 << 30;

/// Textures decoded while loading one file, each source once per colour space;
/// a texture's index is its [`TextureRef`].
///
/// The cache holds at most `limit` bytes of decoded pixels: each decode is told
/// how many are left, and refuses an image that needs more before decoding it.
pub(crate) struct TextureCache<K> {
    textures: Vec<Texture>,
    index: HashMap<(K, bool), TextureRef>,
    /// Decoded bytes held, and the most allowed.
    used: u64,
    limit: u64,
}

impl<K: Hash + Eq> TextureCache<K> {
    /// An empty cache that may hold `limit` bytes of decoded pixels.
    pub(crate) fn new(limit: u64) -> Self {
        Self { textures: Vec::new(), index: HashMap::new(), used: 0, limit }
    }

    /// The texture from `source` read as sRGB or not, decoding it with `decode`
    /// (given the bytes still free) the first time it is asked for.
    pub(crate) fn get_or_decode<E>(
        &mut self,
        source: K,
        srgb: bool,
        decode: impl FnOnce(u64) -> Result<Texture, E>,
    ) -> Result<TextureRef, E> {
        let key = (source, srgb);
        if let Some(&i) = self.index.get(&key) {
            return Ok(i);
        }
        let texture = decode(self.free())?;
        self.used += texture.bytes();
        self.textures.push(texture);
        self.index.insert(key, self.textures.len() - 1);
        Ok(self.textures.len() - 1)
    }

    /// Bytes of decoded pixels that may still be added.
    pub(crate) fn free(&self) -> u64 {
        self.limit.saturating_sub(self.used)
    }

    /// Count `bytes` held elsewhere (a model's textures) against the limit.
    pub(crate) fn charge(&mut self, bytes: u64) {
        self.used += bytes;
    }

    /// The decoded textures, in [`TextureRef`] order.
    /// A texture already decoded.
    pub(crate) fn get(&self, texture: TextureRef) -> &Texture {
        &self.textures[texture]
    }

    pub(crate) fn into_textures(self) -> Vec<Texture> {
        self.textures
    }
}
/// `color` (or white, for `None`) with its alpha multiplied by `dissolve`'s red
/// channel, resampled to the colour map's size: a colour map with an alpha mask
/// (OBJ `map_d`).
pub(crate) fn with_dissolve(color: Option<&Texture>, dissolve: &Texture) -> Texture {
    let (w, h) = color.map_or(dissolve.image.dimensions(), |c| c.image.dimensions());
    let mask = image::imageops::resize(&dissolve.image, w, h, image::imageops::FilterType::Triangle);
    let mut image =
        color.map_or_else(|| image::RgbaImage::from_pixel(w, h, image::Rgba([255; 4])), |c| c.image.clone());
    for (p, m) in image.pixels_mut().zip(mask.pixels()) {
        p[3] = ((u16::from(p[3]) * u16::from(m[0]) + 127) / 255) as u8;
    }
    let name = color.map_or_else(|| dissolve.name.clone(), |c| format!("{} + {}", c.name, dissolve.name));
    Texture::new(name, image, true)
}

/// Decode a PNG or JPEG file into a [`Texture`].
///
/// Rejects anything but a regular file of at most [`MAX_IMAGE_FILE_BYTES`],
/// images wider or taller than [`MAX_TEXTURE_SIDE`] or needing more than
/// [`MAX_TEXTURE_MEMORY`] (both before decoding their pixels), and any file that
/// is missing, unreadable or not a supported image.
pub fn load_texture(path: &Path, srgb: bool) -> Result<Texture, Diagnostic> {
    read_texture(path, srgb, MAX_TEXTURE_MEMORY, &super::Files::Disk)
}

/// Decode a PNG or JPEG file as [`load_texture`] does, with at most `free`
/// bytes of decoded RGBA pixels to spend (for images that are not a scene's
/// textures: `glint compare` reads its two through here).
pub fn load_image(path: &Path, free: u64) -> Result<image::RgbaImage, Diagnostic> {
    read_texture(path, true, free, &super::Files::Disk).map(|t| t.image)
}

/// [`load_texture`] from `files`, with at most `free` bytes of decoded pixels to spend.
pub(crate) fn read_texture(path: &Path, srgb: bool, free: u64, files: &super::Files) -> Result<Texture, Diagnostic> {
    let bytes = files.read(path, MAX_IMAGE_FILE_BYTES)?;
    let name = path.file_name().map_or_else(|| "texture".into(), |n| n.to_string_lossy().into_owned());
    decode_texture(&bytes, name, srgb, free, files).map_err(|m| Diagnostic::file(path, m))
}

/// The width and height of a PNG or JPEG image, from its header: an error for
/// any other format, and for a side over [`MAX_TEXTURE_SIDE`].
pub(crate) fn texture_size(bytes: &[u8]) -> Result<(u32, u32), String> {
    // imagesize knows only these two formats here (its features).
    if !matches!(imagesize::image_type(bytes), Ok(imagesize::ImageType::Png | imagesize::ImageType::Jpeg)) {
        return Err("expected a PNG or JPEG image".into());
    }
    let size = imagesize::blob_size(bytes).map_err(|e| format!("cannot read texture: {e}"))?;
    let side = |side: usize| u32::try_from(side).ok().filter(|&s| s <= MAX_TEXTURE_SIDE);
    match (side(size.width), side(size.height)) {
        (Some(w), Some(h)) => Ok((w, h)),
        _ => {
            let (w, h) = (size.width, size.height);
            Err(format!("{w} x {h} pixels: textures may be at most {MAX_TEXTURE_SIDE} pixels a side"))
        }
    }
}

/// Decode PNG or JPEG bytes into a [`Texture`] called `name`, refusing (from the
/// header, before anyone decodes the pixels) an image larger than
/// [`MAX_TEXTURE_SIDE`] or needing more than `free` bytes. `files` decides who
/// decodes: glint, or the host of a [`super::FileSet::host_decoding`] set. The
/// error says what was wrong, never quoting the bytes.
pub(crate) fn decode_texture(
    bytes: &[u8],
    name: String,
    srgb: bool,
    free: u64,
    files: &super::Files,
) -> Result<Texture, String> {
    let (w, h) = texture_size(bytes)?;
    let needs = 4 * u64::from(w) * u64::from(h);
    if needs > free {
        let mib = |bytes: u64| bytes as f64 / f64::from(1 << 20);
        return Err(format!(
            "{w} x {h} pixels need {:.1} MiB decoded, but only {:.1} MiB of the {} MiB texture memory limit are left",
            mib(needs),
            mib(free),
            MAX_TEXTURE_MEMORY >> 20
        ));
    }
    let image = files
        .host_decoded(bytes)
        .unwrap_or_else(|| decode_here(bytes, needs))
        .map_err(|e| format!("cannot decode texture: {e}"))?;
    // An EXIF orientation that turns the image a quarter swaps its sides.
    if image.dimensions() != (w, h) && image.dimensions() != (h, w) {
        let (dw, dh) = image.dimensions();
        return Err(format!("cannot decode texture: its header says {w} x {h} pixels, its data {dw} x {dh}"));
    }
    Ok(Texture::new(name, image, srgb))
}

/// What went wrong in one of `image`'s decoders, by kind alone: their own
/// messages may quote the file (a Radiance header's `FORMAT` value), and
/// nothing read from a file is quoted (`docs/limits.md`).
pub(crate) fn image_error(e: &image::ImageError) -> String {
    use image::ImageError as E;
    match e {
        E::Decoding(d) => format!("its {} data is malformed", format_name(d.format_hint())),
        E::Limits(_) => "decoding it needs more memory than its size allows".into(),
        E::Unsupported(u) => {
            format!("it uses a {} feature glint's decoder does not support", format_name(u.format_hint()))
        }
        E::IoError(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => "it ends early (cut short)".into(),
        E::IoError(_) => "it cannot be read".into(),
        E::Encoding(_) | E::Parameter(_) => "it cannot be decoded".into(),
    }
}

/// The name of the format `hint` names, or "image" when it names none.
fn format_name(hint: image::error::ImageFormatHint) -> String {
    match hint {
        image::error::ImageFormatHint::Exact(format) => format!("{format:?}"),
        _ => "image".into(),
    }
}

/// Decode PNG or JPEG bytes with the `image` crate, allocating at most about
/// twice the `needs` bytes of the RGBA result, and turn the pixels as the
/// image's EXIF orientation says, as browsers do (the page's images, which its
/// browser decodes, look the same).
#[cfg(feature = "png-jpeg")]
fn decode_here(bytes: &[u8], needs: u64) -> Result<image::RgbaImage, String> {
    use image::ImageDecoder;
    let mut reader = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| image_error(&e.into()))?;
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_TEXTURE_SIDE);
    limits.max_image_height = Some(MAX_TEXTURE_SIDE);
    limits.max_alloc = Some(needs.max(1 << 20) * 2);
    reader.limits(limits);
    let mut decoder = reader.into_decoder().map_err(|e| image_error(&e))?;
    // An unreadable orientation leaves the image as stored, as browsers do.
    let orientation = decoder.orientation().unwrap_or(image::metadata::Orientation::NoTransforms);
    let mut image = image::DynamicImage::from_decoder(decoder).map_err(|e| image_error(&e))?;
    image.apply_orientation(orientation);
    Ok(image.into_rgba8())
}

/// Without the `png-jpeg` feature only a host decodes PNG and JPEG.
#[cfg(not(feature = "png-jpeg"))]
fn decode_here(_: &[u8], _: u64) -> Result<image::RgbaImage, String> {
    Err("glint was built without PNG and JPEG decoding (its feature `png-jpeg`)".into())
}
