//! Beginner layer: [`Texture`], decoded RGBA8 pixels waiting to be uploaded
//! (`asset` decodes files into it; a program may make one from its own pixels).

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

    /// Bytes of decoded pixels.
    pub fn bytes(&self) -> u64 {
        4 * u64::from(self.image.width()) * u64::from(self.image.height())
    }

    /// Number of mip levels down to 1×1.
    pub fn mip_levels(&self) -> u32 {
        32 - self.image.width().max(self.image.height()).max(1).leading_zeros()
    }
}
