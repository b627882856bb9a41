use super::{Diagnostic, TextureRef};
use std::collections::HashMap;
use std::hash::Hash;
use std::path::Path;

/// Largest accepted side of a texture, in pixels.
pub const MAX_TEXTURE_SIDE: u32 = 8192;

/// A decoded texture waiting to be uploaded: RGBA8 pixels and how to read them.
///
/// Colour maps are sRGB (decoded to linear by the sampler); normal and specular
/// maps are linear. Mipmaps are generated on the GPU when it is uploaded.
#[derive(Clone, Debug)]
pub struct Texture {
    /// Name for labels and diagnostics (usually the file name).
    pub name: String,
    /// The pixels, top row first.
    pub image: image::RgbaImage,
    /// Whether the pixel values are sRGB-encoded colour.
    pub srgb: bool,
}

impl Texture {
    /// Wrap decoded pixels.
    pub fn new(name: impl Into<String>, image: image::RgbaImage, srgb: bool) -> Self {
        Self { name: name.into(), image, srgb }
    }

    /// Number of mip levels down to 1×1.
    pub fn mip_levels(&self) -> u32 {
        32 - self.image.width().max(self.image.height()).max(1).leading_zeros()
    }
}

/// Textures decoded while loading one file, each source once per colour space;
/// a texture's index is its [`TextureRef`].
pub(crate) struct TextureCache<K> {
    textures: Vec<Texture>,
    index: HashMap<(K, bool), TextureRef>,
}

impl<K: Hash + Eq> Default for TextureCache<K> {
    fn default() -> Self {
        Self { textures: Vec::new(), index: HashMap::new() }
    }
}

impl<K: Hash + Eq> TextureCache<K> {
    /// The texture from `source` read as sRGB or not, decoding it with `decode`
    /// the first time it is asked for.
    pub(crate) fn get_or_decode<E>(
        &mut self,
        source: K,
        srgb: bool,
        decode: impl FnOnce() -> Result<Texture, E>,
    ) -> Result<TextureRef, E> {
        let key = (source, srgb);
        if let Some(&i) = self.index.get(&key) {
            return Ok(i);
        }
        self.textures.push(decode()?);
        self.index.insert(key, self.textures.len() - 1);
        Ok(self.textures.len() - 1)
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
/// Rejects images wider or taller than [`MAX_TEXTURE_SIDE`] before decoding their
/// pixels, and any file that is missing, unreadable or not a supported image.
pub fn load_texture(path: &Path, srgb: bool) -> Result<Texture, Diagnostic> {
    let fail = |m: String| Diagnostic::file(path, m);
    let mut reader = image::ImageReader::open(path)
        .map_err(|e| fail(format!("cannot open texture: {e}")))?
        .with_guessed_format()
        .map_err(|e| fail(format!("cannot read texture: {e}")))?;
    match reader.format() {
        Some(image::ImageFormat::Png | image::ImageFormat::Jpeg) => {}
        other => return Err(fail(format!("expected a PNG or JPEG image, found {other:?}"))),
    }
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_TEXTURE_SIDE);
    limits.max_image_height = Some(MAX_TEXTURE_SIDE);
    limits.max_alloc = Some(4 * u64::from(MAX_TEXTURE_SIDE) * u64::from(MAX_TEXTURE_SIDE));
    reader.limits(limits);
    let image = reader.decode().map_err(|e| fail(format!("cannot decode texture: {e}")))?.into_rgba8();
    let name = path.file_name().map_or_else(|| "texture".into(), |n| n.to_string_lossy().into_owned());
    Ok(Texture::new(name, image, srgb))
}
