//! Core layer: comparing a rendered image with a reference, within the
//! tolerance every reference-image test uses (and `glint compare`, which the
//! web page's browser test calls). Both must hold:
//! - image-compare's hybrid similarity (MSSIM on luma, RMS on chroma) is at
//!   least [`MIN_SIMILARITY`];
//! - at most [`MAX_BAD_PIXELS`] of the pixels differ by more than
//!   [`BAD_PIXEL_DELTA`] (of 255) in a channel, so a small missing detail
//!   cannot hide in the mean.

/// Least hybrid similarity of a match.
pub const MIN_SIMILARITY: f64 = 0.97;
/// Fraction of pixels allowed past [`BAD_PIXEL_DELTA`].
pub const MAX_BAD_PIXELS: f64 = 0.005;
/// Per-channel difference that makes a pixel "bad".
pub const BAD_PIXEL_DELTA: u8 = 40;
/// Most decoded bytes (RGBA8) of the two images `glint compare` reads
/// together: the comparison itself takes about five times as much again
/// (two 8192² images took 2.6 GB).
pub const MAX_COMPARE_BYTES: u64 = 256 << 20;

/// How two images of one size compare.
pub struct Comparison {
    /// Hybrid similarity, 0..=1.
    pub similarity: f64,
    /// Fraction of pixels past [`BAD_PIXEL_DELTA`].
    pub bad_pixels: f64,
    /// Where they differ, as a colour map.
    pub diff: image::DynamicImage,
}

impl Comparison {
    /// Whether the images match within the tolerance.
    pub fn matches(&self) -> bool {
        self.similarity >= MIN_SIMILARITY && self.bad_pixels <= MAX_BAD_PIXELS
    }
}

/// Compare `actual` with `expected` (alpha ignored); `None` when their sizes differ.
pub fn compare(expected: &image::RgbImage, actual: &image::RgbImage) -> Option<Comparison> {
    let similarity = image_compare::rgb_hybrid_compare(expected, actual).ok()?;
    let bad = (expected.pixels().zip(actual.pixels()))
        .filter(|(a, b)| a.0.iter().zip(b.0.iter()).any(|(x, y)| x.abs_diff(*y) > BAD_PIXEL_DELTA))
        .count() as f64
        / f64::from(expected.width() * expected.height()).max(1.0);
    Some(Comparison { similarity: similarity.score, bad_pixels: bad, diff: similarity.image.to_color_map() })
}
