//! Writes the textures glint ships under `assets/textures/`, so they can be
//! regenerated rather than trusted: `cargo run --example gen_textures`.
//!
//! - `tiles.png` (sRGB colour): 4×4 glazed tiles with grout.
//! - `tiles_normal.png` (linear, +Y up): the tiles' bevels as a normal map.
//! - `leaf.png` (sRGB colour + alpha): a leaf on transparent ground, for alpha masking.
//! - `turned.jpg` (sRGB colour): a 64×32 sign (red left, blue right, a yellow top
//!   band) stored sideways, 32×64, with the EXIF orientation 6 ("turn a quarter
//!   clockwise") that shows it upright, as cameras store photos taken on end.

use image::{Rgba, RgbaImage};

const SIZE: u32 = 256;
const TILE: f32 = 64.0;
const GROUT: f32 = 3.0;
const BEVEL: f32 = 6.0;

/// Height of the tile surface at (x, y): 0 in the grout, rising to 1 across the bevel.
fn height(x: f32, y: f32) -> f32 {
    let edge = |v: f32| {
        let d = v.rem_euclid(TILE).min(TILE - v.rem_euclid(TILE));
        ((d - GROUT) / BEVEL).clamp(0.0, 1.0)
    };
    edge(x).min(edge(y))
}

fn main() -> Result<(), image::ImageError> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/textures");
    std::fs::create_dir_all(&dir).map_err(image::ImageError::IoError)?;

    let tiles = RgbaImage::from_fn(SIZE, SIZE, |x, y| {
        let (tx, ty) = (x / TILE as u32, y / TILE as u32);
        let h = height(x as f32 + 0.5, y as f32 + 0.5);
        // Two glazes in a checker, each tile a little lighter or darker.
        let shade = 0.9 + 0.1 * (((tx * 7 + ty * 13) % 5) as f32 / 4.0);
        let glaze = if (tx + ty) % 2 == 0 { [196.0, 98.0, 60.0] } else { [232.0, 220.0, 196.0] };
        let grout = [90.0, 86.0, 80.0];
        let c = |i: usize| (grout[i] + (glaze[i] * shade - grout[i]) * h) as u8;
        Rgba([c(0), c(1), c(2), 255])
    });
    tiles.save(dir.join("tiles.png"))?;

    let normal = RgbaImage::from_fn(SIZE, SIZE, |x, y| {
        let (fx, fy) = (x as f32 + 0.5, y as f32 + 0.5);
        let dx = height(fx + 1.0, fy) - height(fx - 1.0, fy);
        // Image y runs down; the normal map's +Y is up the image.
        let dy = height(fx, fy - 1.0) - height(fx, fy + 1.0);
        let n = glam::Vec3::new(-dx * 2.0, -dy * 2.0, 1.0).normalize();
        let e = |v: f32| ((v * 0.5 + 0.5) * 255.0).round() as u8;
        Rgba([e(n.x), e(n.y), e(n.z), 255])
    });
    normal.save(dir.join("tiles_normal.png"))?;

    let leaf = RgbaImage::from_fn(128, 128, |x, y| {
        // A leaf along the diagonal: inside a lens of two circles, with a vein.
        let (u, v) = (x as f32 / 127.0 - 0.5, y as f32 / 127.0 - 0.5);
        let (a, b) = ((u + v) * std::f32::consts::FRAC_1_SQRT_2, (u - v) * std::f32::consts::FRAC_1_SQRT_2);
        let inside = (b.abs() + 0.62).powi(2) + a * a < 0.9f32.powi(2) && a.abs() < 0.62;
        let vein = b.abs() < 0.012;
        let g = (140.0 + 60.0 * (0.5 - a)) as u8;
        match (inside, vein) {
            (false, _) => Rgba([0, 0, 0, 0]),
            (true, true) => Rgba([190, 220, 120, 255]),
            (true, false) => Rgba([50, g, 40, 255]),
        }
    });
    leaf.save(dir.join("leaf.png"))?;

    // The underwater scene's fish skin: u runs nose (0) to tail (1), v top (0)
    // to belly (1): a dark back, bright flanks with vertical bands, a pale belly.
    let fish = RgbaImage::from_fn(128, 64, |x, y| {
        let (u, v) = (x as f32 / 127.0, y as f32 / 63.0);
        let band = ((u * 5.0 * std::f32::consts::PI).sin() > 0.55 && u > 0.15 && u < 0.8) as u8 as f32;
        let back = [20.0, 50.0, 90.0];
        let flank = [235.0, 170.0, 40.0];
        let belly = [245.0, 240.0, 220.0];
        let mix = |a: [f32; 3], b: [f32; 3], t: f32| [0, 1, 2].map(|i| a[i] + (b[i] - a[i]) * t.clamp(0.0, 1.0));
        let mut c = if v < 0.5 { mix(back, flank, v * 3.0) } else { mix(flank, belly, (v - 0.6) * 3.0) };
        c = mix(c, [250.0, 250.0, 250.0], band * 0.8 * (1.0 - (v - 0.5).abs() * 1.6));
        let eye = ((u - 0.08).powi(2) * 4.0 + (v - 0.42).powi(2)).sqrt() < 0.05;
        let c = if eye { [10.0, 10.0, 10.0] } else { c };
        Rgba([c[0] as u8, c[1] as u8, c[2] as u8, 255])
    });
    // Beside the fish model, which may only read textures in its own folder.
    let underwater = dir.join("../underwater");
    std::fs::create_dir_all(&underwater).map_err(image::ImageError::IoError)?;
    fish.save(underwater.join("fish.png"))?;

    // A bubble: clear inside, a bright rim and a highlight up and to the left.
    let bubble = RgbaImage::from_fn(64, 64, |x, y| {
        let (u, v) = (x as f32 / 31.5 - 1.0, y as f32 / 31.5 - 1.0);
        let r = (u * u + v * v).sqrt();
        let rim = (1.0 - ((r - 0.85).abs() / 0.12)).clamp(0.0, 1.0);
        let glint = (1.0 - (((u + 0.35).powi(2) + (v + 0.35).powi(2)).sqrt() / 0.22)).clamp(0.0, 1.0);
        let a = if r > 1.0 { 0.0 } else { (0.12 + 0.8 * rim + glint).min(1.0) };
        Rgba([255, 255, 255, (a * 255.0) as u8])
    });
    bubble.save(underwater.join("bubble.png"))?;

    // Sand: pale grains and gentle ripples.
    let sand = RgbaImage::from_fn(SIZE, SIZE, |x, y| {
        let (fx, fy) = (x as f32, y as f32);
        let ripple = 0.5 + 0.5 * (fx * 0.19 + (fy * 0.05).sin() * 3.0).sin();
        let grain = ((x.wrapping_mul(73_856_093) ^ y.wrapping_mul(19_349_663)) % 97) as f32 / 97.0;
        let l = 0.78 + 0.1 * ripple + 0.12 * (grain - 0.5);
        Rgba([(225.0 * l) as u8, (200.0 * l) as u8, (150.0 * l) as u8, 255])
    });
    sand.save(dir.join("sand.png"))?;

    // The sign as it should look, stored turned a quarter back.
    let sign = image::RgbImage::from_fn(64, 32, |x, y| match (x, y) {
        (_, 0..8) => image::Rgb([240, 200, 40]),
        (0..32, _) => image::Rgb([200, 40, 40]),
        _ => image::Rgb([40, 60, 200]),
    });
    let mut jpeg = Vec::new();
    let mut encoder = image::codecs::jpeg::JpegEncoder::new_with_quality(&mut jpeg, 95);
    // TIFF, big-endian: one IFD entry, Orientation (0x0112), SHORT, 1 value: 6.
    let exif =
        [b"MM\0*".as_slice(), &[0, 0, 0, 8, 0, 1, 0x01, 0x12, 0, 3, 0, 0, 0, 1, 0, 6, 0, 0, 0, 0, 0, 0]].concat();
    image::ImageEncoder::set_exif_metadata(&mut encoder, exif).map_err(image::ImageError::Unsupported)?;
    encoder.encode_image(&image::imageops::rotate270(&sign))?;
    std::fs::write(dir.join("turned.jpg"), jpeg).map_err(image::ImageError::IoError)?;
    println!(
        "wrote tiles.png, tiles_normal.png, leaf.png, sand.png, turned.jpg to {} and fish.png, bubble.png beside the underwater models",
        dir.display()
    );
    Ok(())
}
