//! Writes glint's own HDR environment, `assets/environments/courtyard.hdr`: an
//! equirectangular courtyard (a sky with a sun, buildings with lit windows
//! around the horizon, a tiled floor), made here rather than downloaded so its
//! licence is glint's. Run: `cargo run -p glint --example make_environment -- OUT.hdr`.

use glam::Vec3;
use glint::asset::EnvironmentImage;

/// A number in 0..1 fixed by `k`.
fn hash(k: u32) -> f32 {
    let mut x = k.wrapping_mul(0x9E37_79B9) ^ 0x85EB_CA6B;
    x ^= x >> 15;
    x = x.wrapping_mul(0x2C1B_3C6D);
    x ^= x >> 12;
    (x & 0xFFFF) as f32 / 65535.0
}

fn radiance(d: Vec3) -> Vec3 {
    let sun = Vec3::new(0.45, 0.38, -0.8).normalize();
    let azimuth = d.x.atan2(-d.z) / std::f32::consts::TAU + 0.5;
    let elevation = d.y.clamp(-1.0, 1.0).asin();
    if d.y < 0.0 {
        // Floor tiles a metre square seen from 1.5 m up, fading to their mean far away.
        let t = 1.5 / -d.y;
        let (x, z) = ((d.x * t).floor() as i32, (d.z * t).floor() as i32);
        let tile = if (x + z) % 2 == 0 { Vec3::new(0.3, 0.26, 0.21) } else { Vec3::new(0.17, 0.15, 0.13) };
        let far = (t / 40.0).min(1.0);
        return tile.lerp(Vec3::new(0.235, 0.205, 0.17), far) * (0.6 + 0.6 * sun.y);
    }
    // Sixteen buildings around the horizon, each its own height and windows.
    let block = (azimuth * 16.0) as u32;
    let height = (0.08 + 0.22 * hash(block)) * std::f32::consts::FRAC_PI_2;
    if elevation < height {
        let (column, row) = ((azimuth * 16.0 * 6.0).fract(), (elevation / 0.035).fract());
        let window = column > 0.3 && column < 0.7 && row > 0.3 && row < 0.75;
        let cell = (azimuth * 96.0) as u32 * 31 + (elevation / 0.035) as u32;
        return match window && hash(cell) > 0.55 {
            true => Vec3::new(2.2, 1.6, 0.8),
            false => Vec3::new(0.09, 0.08, 0.075) * (1.0 + hash(block + 100)),
        };
    }
    let zenith = Vec3::new(0.18, 0.36, 0.85);
    let horizon = Vec3::new(0.95, 0.9, 0.85);
    let sky = horizon.lerp(zenith, d.y.max(0.0).powf(0.45));
    let c = d.dot(sun);
    let disk = if c > 1.5f32.to_radians().cos() { Vec3::new(800.0, 700.0, 560.0) } else { Vec3::ZERO };
    sky + Vec3::new(1.0, 0.85, 0.6) * (0.8 * c.max(0.0).powi(64) + 0.25 * c.max(0.0).powi(6)) + disk
}

fn main() {
    let out = std::env::args().nth(1).unwrap_or_else(|| "assets/environments/courtyard.hdr".into());
    let env = EnvironmentImage::from_fn("courtyard", 512, 256, radiance);
    let pixels: Vec<image::Rgb<f32>> = env.pixels().pixels().copied().collect();
    let file = std::io::BufWriter::new(std::fs::File::create(&out).expect("create the file"));
    image::codecs::hdr::HdrEncoder::new(file).encode(&pixels, 512, 256).expect("write the image");
    println!("wrote {out}");
}
