//! Core layer: where the copies of an `instances` block go, and the block itself.

use super::scn::{Loader, Placement, MAX_INSTANCES, MAX_TILES};
use super::scn_fields::Fields;
use super::Diagnostic;
use crate::scene::MAX_COMPACT_HALF;
use crate::text::quote;
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

/// Sort `transforms` into `n` × `n` tiles over the box `origin ± extent/2`
/// (by x and z; a tile holds the instances whose position falls in its cell,
/// the box's edges clamped), tile by tile with x fastest, each tile's
/// instances in order of their far-field rank ([`rank_order`]), so any
/// first share of a tile is spread over it, and is the share a far field
/// draws. Returns the tiles, their boxes grown by `padding`.
///
/// [`rank_order`]: crate::scene::far_field::rank_order
pub(crate) fn sort_into_tiles(
    transforms: &mut Vec<Mat4>,
    n: u32,
    (origin, extent): (Vec3, Vec3),
    padding: f32,
) -> crate::scene::Tiles {
    let corner = origin - extent * 0.5;
    let cell = |v: f32, lo: f32, size: f32| match size > 0.0 {
        true => (((v - lo) / size * n as f32).floor().max(0.0) as u32).min(n - 1),
        false => 0,
    };
    let tile = |m: &Mat4| {
        let p = m.w_axis;
        cell(p.x, corner.x, extent.x) + n * cell(p.z, corner.z, extent.z)
    };
    let mut sizes = vec![0u32; (n * n) as usize];
    let mut keyed: Vec<(u32, Mat4)> = transforms.drain(..).map(|m| (tile(&m), m)).collect();
    keyed.iter().for_each(|&(t, _)| sizes[t as usize] += 1);
    radsort::sort_by_key(&mut keyed, |&(t, _)| t);
    transforms.extend(keyed.into_iter().map(|(_, m)| m));
    let tiles = crate::scene::Tiles::from_sizes(sizes, padding);
    crate::scene::far_field::rank_order(transforms, &tiles);
    tiles
}

/// Whether every instance's y and scale fit a compact instance's half floats
/// (at most [`MAX_COMPACT_HALF`] in size), else what is out of range.
fn check_compact(transforms: &[Mat4]) -> Result<(), String> {
    let (y, scale) = transforms
        .iter()
        .fold((0.0f32, 0.0f32), |(y, s), m| (y.max(m.w_axis.y.abs()), s.max(m.y_axis.truncate().length())));
    if y > MAX_COMPACT_HALF || scale > MAX_COMPACT_HALF {
        return Err(format!(
            "\"compact\" stores each instance's y and scale as half floats, at most {MAX_COMPACT_HALF}: \
             these instances reach y {y} and scale {scale}; move \"origin\" nearer, or leave out \"compact\""
        ));
    }
    Ok(())
}

impl Loader<'_> {
    /// An `instances` block: `count` copies of a mesh placed on a grid or at
    /// random in a box, optionally sorted into tiles.
    pub(super) fn instances(&mut self, f: &mut Fields) -> Result<(), Diagnostic> {
        let mesh = self.mesh(f, "mesh")?;
        let material = Self::material_ref(f);
        let count_pair = f.require("count")?;
        let count: i64 = count_pair.value.trim().parse().map_err(|_| {
            Diagnostic::at(
                self.path,
                count_pair.line,
                format!("\"count\" is {}, expected a whole number", quote(&count_pair.value)),
            )
        })?;
        if count < 0 {
            return Err(Diagnostic::at(
                self.path,
                count_pair.line,
                format!("\"count\" is {count}, expected 0 or more"),
            ));
        }
        let count = count as u64;
        if count > MAX_INSTANCES {
            return Err(Diagnostic::at(
                self.path,
                count_pair.line,
                format!("\"count\" is {count}, more than glint allows in one file ({MAX_INSTANCES})"),
            ));
        }
        self.count_instances(count, &mesh, count_pair.line)?;
        let random = matches!(f.choice("layout", &["grid", "random"])?, Some((1, _)));
        let origin = f.vec3("origin")?.unwrap_or(Vec3::ZERO);
        let extent = f.vec3("extent")?.unwrap_or(Vec3::new(10.0, 0.0, 10.0));
        if extent.min_element() < 0.0 {
            return Err(Diagnostic::at(self.path, f.block.line, "\"extent\" must not be negative"));
        }
        let seed = match f.get("seed") {
            None => 1,
            Some(p) => p.value.trim().parse::<u64>().map_err(|_| {
                Diagnostic::at(
                    self.path,
                    p.line,
                    format!("\"seed\" is {}, expected a whole number 0 or more", quote(&p.value)),
                )
            })?,
        };
        let [lo, hi] = f.numbers::<2>("scale", "2 numbers (min max)")?.unwrap_or([1.0, 1.0]);
        if lo <= 0.0 || hi < lo {
            return Err(Diagnostic::at(self.path, f.block.line, "\"scale\" must be min max with 0 < min <= max"));
        }
        let random_yaw = f.flag("random_yaw")?.unwrap_or(false);
        let mut transforms = place_instances(count as usize, random, origin, extent, seed, (lo, hi), random_yaw);
        let tiles = f.integer("tiles", 1..=MAX_TILES)?;
        let padding = f.number("tile_padding", 0.0..=1e6)?;
        let density = f.number("density", 0.0..=1.0)?;
        let compact = f.flag("compact")?;
        let tiles = match tiles {
            Some(n) => {
                if compact == Some(true) {
                    check_compact(&transforms).map_err(|m| Diagnostic::at(self.path, f.block.line, m))?;
                }
                let tiles = sort_into_tiles(&mut transforms, n as u32, (origin, extent), padding.unwrap_or(0.0));
                Some((tiles, density.unwrap_or(1.0), compact.unwrap_or(false)))
            }
            None if density.is_some() || padding.is_some() || compact.is_some() => {
                let message = "\"density\", \"tile_padding\" and \"compact\" need \"tiles\": without tiles every instance is drawn and stored in full";
                return Err(Diagnostic::at(self.path, f.block.line, message));
            }
            None => None,
        };
        let draw = Self::draw_options(f)?;
        self.placements.push(Placement { mesh, material, draw, transforms, tiles, alone: false });
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_hold_their_cells_instances_in_rank_order() {
        let (origin, extent) = (Vec3::new(5.0, 0.0, 0.0), Vec3::new(40.0, 0.0, 20.0));
        let placed = place_instances(4000, true, origin, extent, 9, (1.0, 1.0), false);
        let mut tiled = placed.clone();
        let tiles = sort_into_tiles(&mut tiled, 4, (origin, extent), 0.0);
        let sizes: Vec<u32> = tiles.ranges(4000).map(|r| r.end - r.start).collect();
        assert_eq!(sizes.len(), 16);
        assert_eq!(sizes.iter().sum::<u32>(), 4000);
        assert!(sizes.iter().all(|&s| s > 150), "about 250 each: {sizes:?}");
        let mut start = 0;
        for (t, &size) in sizes.iter().enumerate() {
            let (col, row) = ((t % 4) as f32, (t / 4) as f32);
            let run = &tiled[start..start + size as usize];
            for m in run {
                let p = m.w_axis;
                assert!(p.x >= -15.0 + 10.0 * col && p.x <= -15.0 + 10.0 * (col + 1.0), "tile {t}: x {}", p.x);
                assert!(p.z >= -10.0 + 5.0 * row && p.z <= -10.0 + 5.0 * (row + 1.0), "tile {t}: z {}", p.z);
            }
            let rank = |m: &Mat4| crate::scene::FarField::rank(m.w_axis.x, m.w_axis.z);
            assert!(run.windows(2).all(|w| rank(&w[0]) <= rank(&w[1])), "tile {t} in rank order");
            // Ranks are random: the first half of a tile is spread over it, not its own corner.
            let mean_x = |r: &[Mat4]| r.iter().map(|m| m.w_axis.x).sum::<f32>() / r.len() as f32;
            assert!((mean_x(&run[..run.len() / 2]) - mean_x(run)).abs() < 1.5, "tile {t}");
            start += size as usize;
        }
        let key = |m: &Mat4| m.w_axis.to_array().map(f32::to_bits);
        let (mut a, mut b): (Vec<_>, Vec<_>) = (placed.iter().map(key).collect(), tiled.iter().map(key).collect());
        a.sort_unstable();
        b.sort_unstable();
        assert_eq!(a, b, "the same instances");
        let mut again = placed.clone();
        sort_into_tiles(&mut again, 4, (origin, extent), 0.0);
        assert_eq!(again, tiled, "the same instances, the same order");
    }

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
