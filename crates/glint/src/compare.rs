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

/// How far apart two pictures of one size are, per colour channel in 255ths
/// (alpha ignored): the mean over every pixel, and the largest mean over a
/// `block` × `block` square (where a change is most visible); `None` when
/// their sizes differ or `block` is 0.
pub fn mean_difference(a: &image::RgbaImage, b: &image::RgbaImage, block: u32) -> Option<(f64, f64)> {
    if a.dimensions() != b.dimensions() || block == 0 {
        return None;
    }
    let (width, height) = a.dimensions();
    let diff = |x: u32, y: u32| -> f64 {
        let (p, q) = (a.get_pixel(x, y).0, b.get_pixel(x, y).0);
        (0..3).map(|c| f64::from(p[c].abs_diff(q[c]))).sum::<f64>() / 3.0
    };
    let mut total = 0.0;
    let mut worst: f64 = 0.0;
    for by in (0..height).step_by(block as usize) {
        for bx in (0..width).step_by(block as usize) {
            let (mut sum, mut n) = (0.0, 0.0);
            for y in by..(by + block).min(height) {
                for x in bx..(bx + block).min(width) {
                    sum += diff(x, y);
                    n += 1.0;
                }
            }
            total += sum;
            worst = worst.max(sum / n);
        }
    }
    Some((total / f64::from(width * height).max(1.0), worst))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_mean_difference_counts_every_pixel_and_the_worst_block_alone() {
        let a = image::RgbaImage::from_pixel(8, 8, image::Rgba([10, 10, 10, 255]));
        let mut b = a.clone();
        // One 4×4 block 40 brighter in red: a quarter of the picture.
        for y in 0..4 {
            for x in 0..4 {
                b.put_pixel(x, y, image::Rgba([50, 10, 10, 0]));
            }
        }
        let (mean, block) = mean_difference(&a, &b, 4).expect("same size");
        assert!((mean - 40.0 / 3.0 / 4.0).abs() < 1e-9, "{mean}");
        assert!((block - 40.0 / 3.0).abs() < 1e-9, "{block}");
        assert!(mean_difference(&a, &image::RgbaImage::new(4, 4), 4).is_none());
    }
}
