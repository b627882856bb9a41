//! SMAA's area texture, computed when first needed rather than shipped: the
//! share of a pixel on each side of the line that SMAA reconstructs from an
//! edge pattern and the distances to the pattern's two ends. It follows
//! `Scripts/AreaTex.py` of Jimenez, Echevarria, Sousa and Gutierrez's SMAA
//! (<https://github.com/iryoku/smaa>, MIT licence, © 2013 Jorge Jimenez, Jose
//! I. Echevarria, Belen Masia, Fernando Navarro and Diego Gutierrez: its text
//! in `crates/glint/licenses/SMAA-LICENSE.txt`), reduced
//! to SMAA 1x: its one sub-pixel offset, 0, so the texture is the published
//! 160×560 texture's first 160×80 rows. A test checks the bytes against
//! the published ones.
//!
//! Layout (RG8, row-major): the left 80×80 holds the orthogonal patterns, 16
//! squares of 16×16 texels at [`ORTHO_SLOTS`]; within one, texel (l, r) is the
//! area for distances l² and r² to the left and right ends (the distances are
//! compressed quadratically, and the shader takes the square root, filtering
//! between texels). The right 80×80 holds the diagonal patterns: 16 squares of
//! 20×20 at [`DIAG_SLOTS`], texel (l, r) for distances l and r. Red is the
//! area on the pixel's side of the line, green the area across it.

use glam::DVec2;
use std::sync::OnceLock;

/// Texels across.
pub(crate) const WIDTH: u32 = 160;
/// Texel rows.
pub(crate) const HEIGHT: u32 = 80;

/// Texels per side of one orthogonal pattern's square.
const SIZE_ORTHO: usize = 16;
/// Texels per side of one diagonal pattern's square.
const SIZE_DIAG: usize = 20;
/// Samples per side of the grid that measures a diagonal pattern's area.
const SAMPLES_DIAG: usize = 30;
/// Lines shorter than this many pixels take a gentler (square-root) area in
/// their U-shaped patterns.
const SMOOTH_MAX_DISTANCE: f64 = 32.0;

/// Where each orthogonal pattern's square lies, in squares: a pattern's bits
/// are the crossing edges at its ends, and the shader reads each end's pair
/// as a number 0..=4 (bilinear fetches of two edges).
const ORTHO_SLOTS: [(usize, usize); 16] = [
    (0, 0),
    (3, 0),
    (0, 3),
    (3, 3),
    (1, 0),
    (4, 0),
    (1, 3),
    (4, 3),
    (0, 1),
    (3, 1),
    (0, 4),
    (3, 4),
    (1, 1),
    (4, 1),
    (1, 4),
    (4, 4),
];

/// Where each diagonal pattern's square lies, in squares.
const DIAG_SLOTS: [(usize, usize); 16] = [
    (0, 0),
    (1, 0),
    (0, 2),
    (1, 2),
    (2, 0),
    (3, 0),
    (2, 2),
    (3, 2),
    (0, 1),
    (1, 1),
    (0, 3),
    (1, 3),
    (2, 1),
    (3, 1),
    (2, 3),
    (3, 3),
];

/// The lines each diagonal pattern may be, as (start, end less (d, d)): a
/// pattern's area is the mean of its possible lines' (its ends are not known).
const DIAG_LINES: [&[([f64; 2], [f64; 2])]; 16] = [
    &[([1.0, 1.0], [1.0, 1.0]), ([1.0, 0.0], [1.0, 0.0])],
    &[([1.0, 0.0], [0.0, 0.0]), ([1.0, 0.0], [1.0, 0.0])],
    &[([0.0, 0.0], [1.0, 0.0]), ([1.0, 0.0], [1.0, 0.0])],
    &[([1.0, 0.0], [1.0, 0.0])],
    &[([1.0, 1.0], [0.0, 0.0]), ([1.0, 1.0], [1.0, 0.0])],
    &[([1.0, 1.0], [0.0, 0.0]), ([1.0, 0.0], [1.0, 0.0])],
    &[([1.0, 1.0], [1.0, 0.0])],
    &[([1.0, 1.0], [1.0, 0.0]), ([1.0, 0.0], [1.0, 0.0])],
    &[([0.0, 0.0], [1.0, 1.0]), ([1.0, 0.0], [1.0, 1.0])],
    &[([1.0, 0.0], [1.0, 1.0])],
    &[([0.0, 0.0], [1.0, 1.0]), ([1.0, 0.0], [1.0, 0.0])],
    &[([1.0, 0.0], [1.0, 1.0]), ([1.0, 0.0], [1.0, 0.0])],
    &[([1.0, 1.0], [1.0, 1.0])],
    &[([1.0, 1.0], [1.0, 1.0]), ([1.0, 0.0], [1.0, 1.0])],
    &[([1.0, 1.0], [1.0, 1.0]), ([1.0, 1.0], [1.0, 0.0])],
    &[([1.0, 1.0], [1.0, 1.0]), ([1.0, 0.0], [1.0, 0.0])],
];

/// The texture's bytes: RG8, [`WIDTH`] × [`HEIGHT`], computed once per process.
pub(crate) fn bytes() -> &'static [u8] {
    static AREA: OnceLock<Vec<u8>> = OnceLock::new();
    AREA.get_or_init(compute)
}

fn compute() -> Vec<u8> {
    let mut out = vec![0u8; (WIDTH * HEIGHT * 2) as usize];
    let mut put = |x: usize, y: usize, area: DVec2| {
        let at = (y * WIDTH as usize + x) * 2;
        // Truncated, as the published texture's bytes were.
        out[at] = (255.0 * area.x) as u8;
        out[at + 1] = (255.0 * area.y) as u8;
    };
    for (pattern, &(sx, sy)) in ORTHO_SLOTS.iter().enumerate() {
        for (left, right) in (0..SIZE_ORTHO).flat_map(|l| (0..SIZE_ORTHO).map(move |r| (l, r))) {
            let area = ortho(pattern, (left * left) as f64, (right * right) as f64);
            put(sx * SIZE_ORTHO + left, sy * SIZE_ORTHO + right, area);
        }
    }
    for (pattern, &(sx, sy)) in DIAG_SLOTS.iter().enumerate() {
        for (left, right) in (0..SIZE_DIAG).flat_map(|l| (0..SIZE_DIAG).map(move |r| (l, r))) {
            let area = diag(pattern, left as f64, right as f64);
            put(WIDTH as usize / 2 + sx * SIZE_DIAG + left, sy * SIZE_DIAG + right, area);
        }
    }
    out
}

/// The area of pixel `x..x + 1` under the line `p1`→`p2`: (below the axis,
/// above it); zero where the line does not span the pixel.
fn under(p1: DVec2, p2: DVec2, x: f64) -> DVec2 {
    let d = p2 - p1;
    let (x1, x2) = (x, x + 1.0);
    let y1 = p1.y + d.y * (x1 - p1.x) / d.x;
    let y2 = p1.y + d.y * (x2 - p1.x) / d.x;
    let inside = (x1 >= p1.x && x1 < p2.x) || (x2 > p1.x && x2 <= p2.x);
    if !inside {
        return DVec2::ZERO;
    }
    let trapezoid = 1f64.copysign(y1) == 1f64.copysign(y2) || y1.abs() < 1e-4 || y2.abs() < 1e-4;
    if trapezoid {
        let a = (y1 + y2) / 2.0;
        return if a < 0.0 { DVec2::new(-a, 0.0) } else { DVec2::new(0.0, a) };
    }
    // The line crosses the axis inside the pixel: two triangles.
    let cross = -p1.y * d.x / d.y + p1.x;
    let a1 = if cross > p1.x { y1 * cross.fract() / 2.0 } else { 0.0 };
    let a2 = if cross < p2.x { y2 * (1.0 - cross.fract()) / 2.0 } else { 0.0 };
    let a = if a1.abs() > a2.abs() { a1 } else { -a2 };
    if a < 0.0 {
        DVec2::new(a1.abs(), a2.abs())
    } else {
        DVec2::new(a2.abs(), a1.abs())
    }
}

/// A short U-shaped pattern's two halves, made gentler the shorter it is.
fn smooth(d: f64, a1: DVec2, a2: DVec2) -> DVec2 {
    let p = (d / SMOOTH_MAX_DISTANCE).clamp(0.0, 1.0);
    let gentle = |a: DVec2| DVec2::new((a.x * 2.0).sqrt(), (a.y * 2.0).sqrt()) * 0.5;
    let lerp = |b: DVec2, a: DVec2| b + (a - b) * p;
    lerp(gentle(a1), a1) + lerp(gentle(a2), a2)
}

/// The area of orthogonal `pattern` (its crossing edges: bit 0 below the
/// left end, 1 below the right, 2 above the left, 3 above the right) for a
/// pixel `left` pixels from the line's left end and `right` from its right.
fn ortho(pattern: usize, left: f64, right: f64) -> DVec2 {
    let d = left + right + 1.0;
    let (above, below) = (0.5, -0.5);
    let p = DVec2::new;
    let (start_below, start_above, middle) = (p(0.0, below), p(0.0, above), p(d / 2.0, 0.0));
    let (end_below, end_above) = (p(d, below), p(d, above));
    // An L pattern is revectorized on its crossing edge's side only, so it
    // meets the unfiltered straight line (pattern 0) at the other end.
    let on_left = |a: DVec2| if left <= right { a } else { DVec2::ZERO };
    let on_right = |a: DVec2| if left >= right { a } else { DVec2::ZERO };
    match pattern {
        1 => on_left(under(start_below, middle, left)),
        2 => on_right(under(middle, end_below, left)),
        3 => smooth(d, under(start_below, middle, left), under(middle, end_below, left)),
        4 => on_left(under(start_above, middle, left)),
        6 | 7 | 14 => under(start_above, end_below, left),
        8 => on_right(under(middle, end_above, left)),
        9 | 11 | 13 => under(start_below, end_above, left),
        12 => smooth(d, under(start_above, middle, left), under(middle, end_above, left)),
        // Straight lines and crossings (0, 5, 10, 15) are left as they are.
        _ => DVec2::ZERO,
    }
}

/// The share of pixel `p`'s samples on the left of the line `p1`→`p2` (all
/// of them where the line has no length).
fn share_left(p1: DVec2, p2: DVec2, p: DVec2) -> f64 {
    if p1 == p2 {
        return 1.0;
    }
    let middle = (p1 + p2) / 2.0;
    let normal = DVec2::new(p2.y - p1.y, p1.x - p2.x);
    let last = (SAMPLES_DIAG - 1) as f64;
    let grid = (0..SAMPLES_DIAG).flat_map(|x| (0..SAMPLES_DIAG).map(move |y| DVec2::new(x as f64, y as f64) / last));
    let inside = grid.filter(|o| normal.dot(p + *o - middle) > 0.0).count();
    inside as f64 / (SAMPLES_DIAG * SAMPLES_DIAG) as f64
}

/// The area of diagonal `pattern` for a pixel `left` pixels from the line's
/// start and `right` from its end: the mean over the lines it may be.
fn diag(pattern: usize, left: f64, right: f64) -> DVec2 {
    let d = left + right + 1.0;
    let lines = DIAG_LINES[pattern];
    let area = |(start, end): &([f64; 2], [f64; 2])| {
        let (p1, p2) = (DVec2::from(*start), DVec2::from(*end) + DVec2::splat(d));
        let pixel = DVec2::splat(left);
        let a1 = share_left(p1, p2, DVec2::new(1.0, 0.0) + pixel);
        let a2 = share_left(p1, p2, DVec2::new(1.0, 1.0) + pixel);
        DVec2::new(1.0 - a1, a2)
    };
    lines.iter().map(area).sum::<DVec2>() / lines.len() as f64
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_area_texture_is_the_published_one() {
        // SMAA's own texture's first 160x80 texels: red as grey, green as alpha.
        let png = include_bytes!("../../../../../tests/smaa/area_published.png");
        let published = image::load_from_memory(png).expect("the published texture").into_luma_alpha8();
        assert_eq!(published.dimensions(), (super::WIDTH, super::HEIGHT));
        let ours = super::bytes();
        let differing = ours.iter().zip(published.as_raw()).filter(|(a, b)| a != b).count();
        assert_eq!(differing, 0, "bytes differing from the published texture");
        let covered = ours.iter().filter(|&&b| b > 0).count();
        assert!(covered > ours.len() / 2 && ours.iter().any(|&b| b > 120), "{covered} bytes cover anything");
    }
}
