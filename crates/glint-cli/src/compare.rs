//! `glint compare`: whether two images match within the reference-image tolerance.

use glint::{Diagnostic, Error};
use std::path::Path;

/// Compare `actual` with `expected`, print one line saying how they compare, and
/// write the difference map to `diff` when given. Returns whether they match.
pub fn run(expected: &Path, actual: &Path, diff: Option<&Path>) -> Result<bool, Error> {
    let open = |path: &Path| {
        image::open(path)
            .map(|i| i.into_rgb8())
            .map_err(|e| Diagnostic::file(path, format!("cannot read the image: {e}")))
    };
    let (a, b) = (open(expected)?, open(actual)?);
    let comparison = glint::compare::compare(&a, &b).ok_or_else(|| {
        let (w, h) = b.dimensions();
        Diagnostic::file(actual, format!("{w}x{h}, but {} is {}x{}", expected.display(), a.width(), a.height()))
    })?;
    if let Some(path) = diff {
        comparison.diff.save(path).map_err(|e| Diagnostic::file(path, format!("cannot write the difference: {e}")))?;
    }
    let verdict = if comparison.matches() { "match" } else { "differ" };
    println!(
        "{verdict}: similarity {:.4} (at least {}), {:.3}% of pixels off by more than {} (at most {}%)",
        comparison.similarity,
        glint::compare::MIN_SIMILARITY,
        comparison.bad_pixels * 100.0,
        glint::compare::BAD_PIXEL_DELTA,
        glint::compare::MAX_BAD_PIXELS * 100.0
    );
    Ok(comparison.matches())
}
