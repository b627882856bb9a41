//! Core layer: environment images for image-based lighting, read from Radiance
//! `.hdr` or OpenEXR files or made by glint (its sky, a studio, a uniform colour).
//!
//! ## The equirectangular convention (written once, here)
//! Texel coordinates (u, v) in 0..1, v down the image. The azimuth is
//! φ = 2π (u − ½), the angle from straight up is θ = π v, and the direction is
//! (sin θ sin φ, cos θ, −sin θ cos φ): the image's middle column looks along −Z
//! (a default camera's forward), its right quarter along +X, its top row up.
//! `shader/equirect.wgsl` holds the same mapping for the shaders.

use super::Diagnostic;
use crate::scene::EnvironmentId;
use glam::Vec3;
use image::Rgb32FImage;
use std::io::Cursor;
use std::path::Path;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;

/// The largest value an environment texel keeps: the largest half float (the
/// GPU copy's format), so a hot sun cannot overflow to infinity.
pub const MAX_RADIANCE: f32 = 65504.0;

/// Bytes of decoded RGB f32 pixels one environment texel needs.
const TEXEL_BYTES: u64 = 12;

/// An equirectangular environment in linear RGB (module doc: the convention),
/// every texel finite and in 0..=[`MAX_RADIANCE`]. Cloning shares the pixels.
#[derive(Clone, Debug)]
pub struct EnvironmentImage {
    id: EnvironmentId,
    /// What it is called in messages (the file name).
    pub name: String,
    pixels: Arc<Rgb32FImage>,
}

impl EnvironmentImage {
    /// An environment of `pixels` (non-finite and negative values become 0,
    /// values past [`MAX_RADIANCE`] are clamped), with a new id.
    pub fn new(name: impl Into<String>, mut pixels: Rgb32FImage) -> Self {
        for v in pixels.iter_mut() {
            *v = if v.is_finite() { v.clamp(0.0, MAX_RADIANCE) } else { 0.0 };
        }
        static NEXT: AtomicU32 = AtomicU32::new(0);
        let id = EnvironmentId(NEXT.fetch_add(1, Ordering::Relaxed));
        Self { id, name: name.into(), pixels: Arc::new(pixels) }
    }

    /// A `width` × `height` environment whose radiance in each texel's
    /// direction is `radiance(direction)`.
    pub fn from_fn(name: &str, width: u32, height: u32, radiance: impl Fn(Vec3) -> Vec3) -> Self {
        let pixels = Rgb32FImage::from_fn(width.max(1), height.max(1), |x, y| {
            let uv = [(x as f32 + 0.5) / width as f32, (y as f32 + 0.5) / height as f32];
            image::Rgb(radiance(equirect_direction(uv)).to_array())
        });
        Self::new(name, pixels)
    }

    /// The same radiance from every direction (the white furnace).
    pub fn uniform(radiance: Vec3) -> Self {
        Self::from_fn("uniform", 8, 4, |_| radiance)
    }

    /// A sky: the gradient glint's sky draws (`top` straight up, `bottom` at
    /// the horizon and below), with a soft glow of `sun` (direction the light
    /// travels, and its colour × intensity) around the sun. The sun itself
    /// stays a light, so it is not lit twice.
    pub fn sky(top: Vec3, bottom: Vec3, sun: Option<(Vec3, Vec3)>) -> Self {
        Self::from_fn("sky", 128, 64, |d| {
            let t = smoothstep(0.0, 0.6, d.y);
            let glow = sun.map_or(Vec3::ZERO, |(dir, color)| {
                let c = d.dot(-dir.normalize_or_zero()).max(0.0);
                color * (0.25 * c.powi(12)) * smoothstep(-0.1, 0.05, d.y)
            });
            bottom.lerp(top, t) + glow
        })
    }

    /// A neutral studio like glTF viewers light models with: a soft grey dome
    /// over a darker floor, a large key light and a dimmer fill.
    pub fn studio() -> Self {
        let key = Vec3::new(-0.5, 0.6, 0.62).normalize();
        let fill = Vec3::new(0.7, 0.3, -0.65).normalize();
        Self::from_fn("studio", 256, 128, |d| {
            let dome = Vec3::splat(0.35).lerp(Vec3::splat(0.8), smoothstep(-0.2, 0.8, d.y));
            let floor = Vec3::splat(0.18) * (1.0 - smoothstep(-0.05, 0.0, d.y));
            let dome = dome * smoothstep(-0.05, 0.0, d.y) + floor;
            let lamp =
                |axis: Vec3, size: f32, power: f32| power * smoothstep(1.0 - size, 1.0 - 0.6 * size, d.dot(axis));
            dome + Vec3::splat(lamp(key, 0.08, 6.0) + lamp(fill, 0.12, 1.5))
        })
    }

    /// Its handle.
    pub fn id(&self) -> EnvironmentId {
        self.id
    }

    /// The pixels.
    pub fn pixels(&self) -> &Rgb32FImage {
        &self.pixels
    }

    /// Radiance toward `direction` (nearest texel).
    pub fn radiance(&self, direction: Vec3) -> Vec3 {
        let [u, v] = equirect_uv(direction);
        let (w, h) = self.pixels.dimensions();
        let x = ((u * w as f32) as u32).min(w - 1);
        let y = ((v * h as f32) as u32).min(h - 1);
        Vec3::from_array(self.pixels.get_pixel(x, y).0)
    }
}

/// The unit direction at equirectangular texel coordinates `uv` (module doc).
pub fn equirect_direction([u, v]: [f32; 2]) -> Vec3 {
    let phi = std::f32::consts::TAU * (u - 0.5);
    let theta = std::f32::consts::PI * v;
    Vec3::new(theta.sin() * phi.sin(), theta.cos(), -theta.sin() * phi.cos())
}

/// The equirectangular texel coordinates of `direction` (module doc).
pub fn equirect_uv(direction: Vec3) -> [f32; 2] {
    let d = direction.normalize_or(Vec3::Y);
    let u = d.x.atan2(-d.z) / std::f32::consts::TAU + 0.5;
    let v = d.y.clamp(-1.0, 1.0).acos() / std::f32::consts::PI;
    [u, v]
}

fn smoothstep(a: f32, b: f32, x: f32) -> f32 {
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Read a Radiance `.hdr` or OpenEXR file as an environment, with at most
/// `free` bytes of decoded pixels to spend (the scene's texture memory).
/// Rejects, before decoding its pixels, an image wider or taller than
/// [`MAX_TEXTURE_SIDE`](super::MAX_TEXTURE_SIDE) or needing more than `free`.
pub(crate) fn read_environment(path: &Path, free: u64, files: &super::Files) -> Result<EnvironmentImage, Diagnostic> {
    let bytes = files.read(path, super::MAX_IMAGE_FILE_BYTES)?;
    let name = path.file_name().map_or_else(|| "environment".into(), |n| n.to_string_lossy().into_owned());
    decode_environment(&bytes, name, free).map_err(|m| Diagnostic::file(path, m))
}

/// Most pixels of an environment: an equirectangular image 8192 × 4096
/// (decoding one from OpenEXR peaks near 1.3 GB).
pub const MAX_ENVIRONMENT_PIXELS: u64 = 8192 * 4096;

/// Most bytes of a Radiance header, its lines up to the empty one (glint's
/// own encoder writes 50): the decoder keeps every line, at about 40 bytes of
/// memory per byte.
pub const MAX_HDR_HEADER_BYTES: usize = 64 * 1024;

/// Decode `.hdr` or OpenEXR bytes (as [`read_environment`] does).
pub(crate) fn decode_environment(bytes: &[u8], name: String, free: u64) -> Result<EnvironmentImage, String> {
    use super::MAX_TEXTURE_SIDE;
    let reader = || image::ImageReader::new(Cursor::new(bytes)).with_guessed_format();
    let decoder = reader().map_err(|e| format!("cannot read environment: {}", super::image_error(&e.into())))?;
    let format = decoder.format();
    // Bytes the decoder needs beside the result (an OpenEXR's data window).
    let decoding = match format {
        Some(image::ImageFormat::Hdr) => check_hdr_header(bytes).map(|()| 0)?,
        #[cfg(feature = "exr")]
        Some(image::ImageFormat::OpenExr) => check_exr_header(bytes)?,
        #[cfg(not(feature = "exr"))]
        Some(image::ImageFormat::OpenExr) => {
            return Err("OpenEXR environments are read where glint is built with its feature `exr` (the web page \
                        is not): convert it to a Radiance .hdr"
                .into())
        }
        Some(other) => return Err(format!("expected a Radiance .hdr or OpenEXR image, found {other:?}")),
        None => return Err("expected a Radiance .hdr or OpenEXR image".into()),
    };
    let fail = |what: &str, e: image::ImageError| format!("cannot {what} environment: {}", super::image_error(&e));
    let decoder_now = reader().map_err(|e| fail("read", e.into()))?;
    let (w, h) = decoder_now.into_dimensions().map_err(|e| fail("read", e))?;
    if w.max(h) > MAX_TEXTURE_SIDE {
        return Err(format!("{w} x {h} pixels: environments may be at most {MAX_TEXTURE_SIDE} pixels a side"));
    }
    if u64::from(w) * u64::from(h) > MAX_ENVIRONMENT_PIXELS {
        return Err(format!(
            "{w} x {h} pixels: environments may have at most {MAX_ENVIRONMENT_PIXELS} pixels (8192 x 4096)"
        ));
    }
    if w < 2 || h < 1 {
        return Err(format!("{w} x {h} pixels: an environment needs at least 2 x 1"));
    }
    let needs = TEXEL_BYTES * u64::from(w) * u64::from(h);
    if needs.max(decoding) > free {
        let mib = |bytes: u64| bytes as f64 / f64::from(1 << 20);
        return Err(format!(
            "{w} x {h} pixels need {:.1} MiB decoded, but only {:.1} MiB of texture memory are left",
            mib(needs.max(decoding)),
            mib(free)
        ));
    }
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_TEXTURE_SIDE);
    limits.max_image_height = Some(MAX_TEXTURE_SIDE);
    // The decoders hold a row buffer or an RGBA f32 copy beside the result.
    limits.max_alloc = Some(needs.max(decoding).max(1 << 20) * 3);
    let mut decoder = decoder;
    decoder.limits(limits);
    let image = decoder.decode().map_err(|e| fail("decode", e))?;
    Ok(EnvironmentImage::new(name, image.into_rgb32f()))
}

/// Check a Radiance header before the decoder reads it: it ends (an empty
/// line) within [`MAX_HDR_HEADER_BYTES`], and its `FORMAT`, when given, is
/// the one the decoder reads. Says what was expected, never quoting the file.
fn check_hdr_header(bytes: &[u8]) -> Result<(), String> {
    let head = &bytes[..bytes.len().min(MAX_HDR_HEADER_BYTES)];
    let Some(end) = head.windows(2).position(|w| w == b"\n\n") else {
        return Err(format!(
            "the Radiance header does not end (an empty line) within its first {MAX_HDR_HEADER_BYTES} bytes"
        ));
    };
    let format = head[..end].split(|&b| b == b'\n').find_map(|line| line.strip_prefix(b"FORMAT="));
    match format.map(<[u8]>::trim_ascii) {
        None | Some(b"32-bit_rle_rgbe") => Ok(()),
        Some(_) => Err("the Radiance header's FORMAT is not 32-bit_rle_rgbe, the only one glint reads".into()),
    }
}

/// Check an OpenEXR header before the decoder reads it, as its decoder does
/// not: every layer's data window, display window and tiles at most
/// [`MAX_TEXTURE_SIDE`](super::MAX_TEXTURE_SIDE) a side, and offset tables the
/// file can hold (8 bytes a chunk). Returns the bytes decoding the data
/// windows takes (RGBA f32), which must fit the texture memory too.
#[cfg(feature = "exr")]
fn check_exr_header(bytes: &[u8]) -> Result<u64, String> {
    use exr::meta::BlockDescription;
    let side = super::MAX_TEXTURE_SIDE as usize;
    let meta = exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), false)
        .map_err(|_| "cannot read the OpenEXR header: expected an OpenEXR 2 image".to_string())?;
    if meta.headers.len() > MAX_EXR_LAYERS {
        return Err(format!("{} layers: an environment may have at most {MAX_EXR_LAYERS}", meta.headers.len()));
    }
    let mut decoding = 0u64;
    let mut chunks = 0u64;
    for (k, header) in meta.headers.iter().enumerate() {
        let display = header.shared_attributes.display_window.size;
        let tiles = match &header.blocks {
            BlockDescription::Tiles(t) => Some(t.tile_size),
            BlockDescription::ScanLines => None,
        };
        let sizes = [("data window", Some(header.layer_size)), ("display window", Some(display)), ("tiles", tiles)];
        for (what, size) in sizes.iter().filter_map(|(w, s)| s.map(|s| (w, s))) {
            if size.width() > side || size.height() > side {
                return Err(format!(
                    "layer {k}: its {what} is {} x {} pixels; environments may be at most {side} a side",
                    size.width(),
                    size.height()
                ));
            }
        }
        decoding += 16 * header.layer_size.area() as u64;
        chunks += header.chunk_count as u64;
    }
    if chunks.saturating_mul(8) > bytes.len() as u64 {
        return Err(format!("its layers have {chunks} chunks, more than the file's offset tables can hold"));
    }
    Ok(decoding)
}

/// Most layers of an OpenEXR environment (each is checked and decoded).
#[cfg(feature = "exr")]
const MAX_EXR_LAYERS: usize = 16;

/// The bytes of decoded pixels `environment` holds (counted in a scene's texture memory).
pub(crate) fn decoded_bytes(environment: &EnvironmentImage) -> u64 {
    let (w, h) = environment.pixels.dimensions();
    TEXEL_BYTES * u64::from(w) * u64::from(h)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_convention_maps_directions_and_texels_both_ways() {
        // The middle looks along -Z, the right quarter along +X, the top up.
        assert!(equirect_direction([0.5, 0.5]).abs_diff_eq(Vec3::NEG_Z, 1e-6));
        assert!(equirect_direction([0.75, 0.5]).abs_diff_eq(Vec3::X, 1e-6));
        assert!(equirect_direction([0.25, 0.5]).abs_diff_eq(Vec3::NEG_X, 1e-6));
        assert!(equirect_direction([0.3, 0.0]).abs_diff_eq(Vec3::Y, 1e-6));
        for uv in [[0.1, 0.2], [0.6, 0.7], [0.9, 0.45]] {
            let back = equirect_uv(equirect_direction(uv));
            assert!((back[0] - uv[0]).abs() < 1e-5 && (back[1] - uv[1]).abs() < 1e-5, "{uv:?} -> {back:?}");
        }
    }

    #[test]
    fn hostile_values_are_made_finite_and_in_range() {
        let pixels = Rgb32FImage::from_raw(2, 1, vec![f32::NAN, -1.0, f32::INFINITY, 1e9, 0.5, 2.0]).unwrap();
        let env = EnvironmentImage::new("hostile", pixels);
        assert_eq!(env.pixels().as_raw(), &[0.0, 0.0, 0.0, MAX_RADIANCE, 0.5, 2.0]);
        assert_ne!(env.id(), EnvironmentImage::uniform(Vec3::ONE).id(), "each image its own id");
    }

    #[test]
    fn decoding_round_trips_hdr_and_refuses_other_or_oversized_images() {
        let env = EnvironmentImage::from_fn("test", 16, 8, |d| Vec3::new(d.x.max(0.0), 1.0, 4.0));
        let mut bytes = Vec::new();
        let encoder = image::codecs::hdr::HdrEncoder::new(&mut bytes);
        let rgb: Vec<image::Rgb<f32>> = env.pixels().pixels().copied().collect();
        encoder.encode(&rgb, 16, 8).unwrap();
        let back = decode_environment(&bytes, "test.hdr".into(), 1 << 20).unwrap();
        assert_eq!(back.pixels().dimensions(), (16, 8));
        // RGBE keeps about 1 % of each texel's largest channel.
        for d in [Vec3::X, Vec3::NEG_Z, Vec3::Y] {
            let (got, want) = (back.radiance(d), env.radiance(d));
            assert!((got - want).abs().max_element() < 0.04, "toward {d}: {got} vs {want}");
        }
        let err = decode_environment(&bytes, "test.hdr".into(), 100).unwrap_err();
        assert!(err.contains("MiB of texture memory"), "{err}");
        let png = {
            let mut out = Cursor::new(Vec::new());
            image::RgbImage::new(2, 2).write_to(&mut out, image::ImageFormat::Png).unwrap();
            out.into_inner()
        };
        let err = decode_environment(&png, "x.png".into(), 1 << 20).unwrap_err();
        assert!(err.contains("expected a Radiance .hdr or OpenEXR image"), "{err}");
        let err =
            decode_environment(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 9 +X 99999\n", "big.hdr".into(), u64::MAX)
                .unwrap_err();
        assert!(err.contains("at most 8192 pixels a side"), "{err}");
        assert!(decode_environment(&bytes[..bytes.len() / 2], "cut.hdr".into(), 1 << 20).is_err());
    }
}
