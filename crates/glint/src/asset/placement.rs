//! Core layer: where the copies of an `instances` block go.

use glam::{Mat4, Quat, Vec3};
use rand::{Rng, SeedableRng};

/// Place `count` instances in the box `origin ± extent/2`: on an evenly spaced grid
/// over the axes whose extent is not zero (cells as square as the box allows, filled
/// x first, then z, then y), or uniformly at random. The same seed gives the same
/// placement everywhere (PCG32).
pub(crate) fn place_instances(
    count: usize,
    random: bool,
    origin: Vec3,
    extent: Vec3,
    seed: u64,
    scale: (f32, f32),
    random_yaw: bool,
) -> Vec<Mat4> {
    let mut rng = rand_pcg::Pcg32::seed_from_u64(seed);
    let axes: Vec<usize> = [0, 2, 1].into_iter().filter(|&a| extent[a] > 0.0).collect();
    // Cell side s with (product of extents) / s^k = count; rounding each axis' cell
    // count up keeps at least `count` cells.
    let volume: f64 = axes.iter().map(|&a| f64::from(extent[a])).product();
    let side = (volume / count.max(1) as f64).powf(1.0 / axes.len().max(1) as f64);
    let cells: Vec<usize> =
        axes.iter().map(|&a| ((f64::from(extent[a]) / side - 1e-9).ceil() as usize).max(1)).collect();
    let corner = origin - extent * 0.5;
    (0..count)
        .map(|i| {
            let mut p = origin;
            if random {
                p = corner + extent * Vec3::new(rng.random(), rng.random(), rng.random());
            } else {
                let mut rest = i;
                for (&a, &n) in axes.iter().zip(&cells) {
                    p[a] = corner[a] + extent[a] * ((rest % n) as f32 + 0.5) / n as f32;
                    rest /= n;
                }
            }
            let s = scale.0 + (scale.1 - scale.0) * rng.random::<f32>();
            let yaw = if random_yaw { rng.random::<f32>() * std::f32::consts::TAU } else { 0.0 };
            Mat4::from_scale_rotation_translation(Vec3::splat(s), Quat::from_rotation_y(yaw), p)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_seed_same_placement_and_grid_is_even() {
        let scatter = |seed| place_instances(50, true, Vec3::ZERO, Vec3::new(10.0, 0.0, 10.0), seed, (0.5, 1.0), true);
        let (a, b, c) = (scatter(3), scatter(3), scatter(4));
        assert_eq!(a, b);
        assert_ne!(a, c);
        for m in &a {
            let p = m.w_axis.truncate();
            assert!(p.x.abs() <= 5.0 && p.z.abs() <= 5.0 && p.y == 0.0);
        }
        let grid = place_instances(4, false, Vec3::ZERO, Vec3::new(2.0, 0.0, 2.0), 1, (1.0, 1.0), false);
        let points: Vec<Vec3> = grid.iter().map(|m| m.w_axis.truncate()).collect();
        assert_eq!(
            points,
            vec![
                Vec3::new(-0.5, 0.0, -0.5),
                Vec3::new(0.5, 0.0, -0.5),
                Vec3::new(-0.5, 0.0, 0.5),
                Vec3::new(0.5, 0.0, 0.5)
            ]
        );
        // A long box gets more cells along its long side: 16 in 8×2 is 8×2 cells of 1.
        let long = place_instances(16, false, Vec3::ZERO, Vec3::new(8.0, 0.0, 2.0), 1, (1.0, 1.0), false);
        let xs: std::collections::BTreeSet<i32> = long.iter().map(|m| (m.w_axis.x * 2.0) as i32).collect();
        let zs: std::collections::BTreeSet<i32> = long.iter().map(|m| (m.w_axis.z * 2.0) as i32).collect();
        assert_eq!((xs.len(), zs.len()), (8, 2));
    }
}
