//! Core layer: environment images read from Radiance `.hdr` or OpenEXR
//! files into [`EnvironmentImage`]s (their convention is written where the
//! type lives, `scene/environment_image.rs`), their headers checked before a
//! decoder reads them.

use super::Diagnostic;
pub use crate::scene::{equirect_direction, equirect_uv, EnvironmentImage, MAX_RADIANCE};
use std::io::Cursor;
use std::path::Path;

/// Bytes of decoded RGB f32 pixels one environment texel needs.
const TEXEL_BYTES: u64 = 12;

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
        let mut sizes =
            vec![("data window", header.layer_size), ("display window", header.shared_attributes.display_window.size)];
        if let BlockDescription::Tiles(t) = &header.blocks {
            sizes.push(("tiles", t.tile_size));
        }
        for (what, size) in sizes {
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
    let (w, h) = environment.pixels().dimensions();
    TEXEL_BYTES * u64::from(w) * u64::from(h)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

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
