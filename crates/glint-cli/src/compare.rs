//! `glint compare`: whether two images match within the reference-image tolerance.

use crate::output;
use glint::compare::MAX_COMPARE_BYTES;
use glint::{Diagnostic, Error};
use std::path::Path;

/// Compare `actual` with `expected`, print one line saying how they compare, and
/// write the difference map to `diff` when given. Returns whether they match.
///
/// Both images are read as textures are (regular files only, within the image
/// file limit, sizes checked from the header before decoding) and may hold
/// [`MAX_COMPARE_BYTES`] of pixels together; the difference map and the line go
/// through the checked output, so a failed write is an error naming its path.
pub fn run(expected: &Path, actual: &Path, diff: Option<&Path>) -> Result<bool, Error> {
    let a = glint::asset::load_image(expected, MAX_COMPARE_BYTES)?;
    let b = glint::asset::load_image(actual, MAX_COMPARE_BYTES - a.as_raw().len() as u64)?;
    let (a, b) = (image::DynamicImage::from(a).into_rgb8(), image::DynamicImage::from(b).into_rgb8());
    let comparison = glint::compare::compare(&a, &b).ok_or_else(|| {
        let (w, h) = b.dimensions();
        let expected = glint::text::shorten(&expected.display().to_string(), glint::text::MAX_PATH_CHARS);
        Diagnostic::file(actual, format!("{w}x{h}, but {expected} is {}x{}", a.width(), a.height()))
    })?;
    if let Some(path) = diff {
        let bytes = output::png_bytes(&comparison.diff.to_rgb8())
            .map_err(|e| Diagnostic::file(path, format!("cannot encode the difference: {e}")))?;
        output::write_file(path, &bytes)?;
    }
    let verdict = if comparison.matches() { "match" } else { "differ" };
    output::print(&format!(
        "{verdict}: similarity {:.4} (at least {}), {:.3}% of pixels off by more than {} (at most {}%)\n",
        comparison.similarity,
        glint::compare::MIN_SIMILARITY,
        comparison.bad_pixels * 100.0,
        glint::compare::BAD_PIXEL_DELTA,
        glint::compare::MAX_BAD_PIXELS * 100.0
    ))?;
    Ok(comparison.matches())
}
