//! Core layer: a material's far field, the vegetation demo's distant meadow
//! drawn with fewer, wider instances. Past [`FarField::start`] world units
//! from the camera an instance is drawn only when its [`rank`] (a number in
//! 0..1 fixed by its placed position) is below the share
//! [`FarField::share`] gives its distance, and drawn wider in x and z by
//! [`FarField::widening`], so the instances drawn cover what all of them
//! did. The share falls as (start / distance)² to [`MIN_SHARE`], then to
//! nothing over the last [`RING`] of [`FarField::end`]: past `end` the ground
//! alone is drawn. Instances whose rank is just under the share ([`BAND`])
//! narrow to nothing rather than vanish, so moving the camera pops none.
//!
//! The vertex shader (`FAR_FIELD`, forward.wgsl `far_field_width`) applies
//! the rule to each instance; the culler draws of each tile of a tiled
//! entity only the first share its nearest point allows, so a tile's
//! instances are in order of rank ([`rank_order`]; the `.scn` loader sorts
//! them so). With levels of detail off the far field is off too.
//!
//! [`rank`]: FarField::rank

/// The smallest share of instances drawn before the ring: at most about
/// 1 / `MIN_SHARE` = 16× widening.
pub const MIN_SHARE: f32 = 0.0625;
/// The band of ranks under the share in which an instance narrows from its
/// full width to nothing, times f · (1 − f) of the falloff f (none where
/// every instance is drawn; at most a sixteenth of the ranks).
pub const BAND: f32 = 0.25;
/// The fraction of [`FarField::end`] over which the share falls to nothing.
pub const RING: f32 = 0.2;

/// Where a material's far field starts and ends, in world units from the camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FarField {
    /// Every instance nearer than this is drawn, at its own width.
    pub start: f32,
    /// No instance further than this is drawn.
    pub end: f32,
}

impl FarField {
    /// A far field from `start` to `end`, if `0 < start < end` (both finite).
    pub fn new(start: f32, end: f32) -> Option<Self> {
        (start > 0.0 && end > start && end.is_finite()).then_some(Self { start, end })
    }

    /// The share of instances thinned by distance alone: (start / distance)²
    /// in `MIN_SHARE..=1`, as the instances a pixel holds grow. Widened by its
    /// inverse, an instance grows on screen as its distance over the start:
    /// a blade one pixel wide at the start is four at the [`MIN_SHARE`]
    /// floor. (start / distance keeps it one pixel, but on the meadow needs a
    /// start of 4 to draw as few triangles, 1.10 M against 1.01 M at a start
    /// of 6, and then differs more from the full picture: 1.79/255 against 1.10.)
    fn falloff(self, distance: f32) -> f32 {
        let r = self.start / distance.max(1e-6);
        (r * r).clamp(MIN_SHARE, 1.0)
    }

    /// The share of instances drawn at `distance`: the falloff, going to 0
    /// over the last [`RING`] of `end`.
    pub fn share(self, distance: f32) -> f32 {
        let ring = ((self.end - distance) / (RING * self.end)).clamp(0.0, 1.0);
        self.falloff(distance) * ring
    }

    /// The band of ranks under the share in which an instance narrows:
    /// [`BAND`] · f · (1 − f) of the falloff f, so none narrows where every
    /// instance is drawn.
    fn band(self, distance: f32) -> f32 {
        let f = self.falloff(distance);
        BAND * f * (1.0 - f)
    }

    /// How much wider in x and z an instance at `distance` whose rank is
    /// well under the share is drawn: one over what the instances drawn
    /// cover, the falloff less half the band.
    pub fn widening(self, distance: f32) -> f32 {
        1.0 / (self.falloff(distance) - 0.5 * self.band(distance))
    }

    /// The width (times its own) an instance of `rank` at `distance` is
    /// drawn with: the widening, narrowed to 0 as the rank nears the share.
    pub fn width(self, distance: f32, rank: f32) -> f32 {
        let (share, band) = (self.share(distance), self.band(distance));
        let narrowing = match band > 0.0 {
            true => ((share - rank) / band).clamp(0.0, 1.0),
            false => f32::from(u8::from(rank < share)),
        };
        self.widening(distance) * narrowing
    }

    /// How many of a tile's `len` instances, in rank order, to draw when its
    /// nearest point is `nearest` from the camera: every one whose rank is
    /// under the share there, and a few past to cover the ranks' scatter
    /// (three standard deviations and one).
    pub fn drawn(self, len: u32, nearest: f32) -> u32 {
        let expected = f64::from(len) * f64::from(self.share(nearest));
        if expected <= 0.0 {
            return 0;
        }
        ((expected + 3.0 * expected.sqrt() + 1.0).ceil() as u32).min(len)
    }

    /// The box `local` (an instance's, in its own units) grown to cover its
    /// far-field drawings: x and z scaled about its origin by anything from 0
    /// (narrowed away) to the widest widening (the falloff's least).
    pub fn reach(self, local: super::Aabb) -> super::Aabb {
        let widest = self.widening(f32::INFINITY);
        let w = glam::Vec3::new(widest, 1.0, widest);
        let (low, high) = (local.min.with_x(0.0).with_z(0.0), local.max.with_x(0.0).with_z(0.0));
        super::Aabb { min: local.min.min(local.min * w).min(low), max: local.max.max(local.max * w).max(high) }
    }

    /// The rank of an instance placed at (`x`, `z`): a hash of the two
    /// numbers' bits, uniform in 0..1 (the shader computes the same).
    pub fn rank(x: f32, z: f32) -> f32 {
        let mut h = x.to_bits().wrapping_mul(0x9e37_79b1) ^ z.to_bits();
        h ^= h >> 16;
        h = h.wrapping_mul(0x7feb_352d);
        h ^= h >> 15;
        h = h.wrapping_mul(0x846c_a68b);
        h ^= h >> 16;
        (h >> 8) as f32 / 16_777_216.0
    }
}

/// Sort each of `tiles`' runs of `transforms` by the [`rank`](FarField::rank)
/// of its instances' positions, so the first share of a tile is the share a
/// far field draws (and, ranks being random, spread over the tile).
pub fn rank_order(transforms: &mut [glam::Mat4], tiles: &super::Tiles) {
    let count = transforms.len() as u32;
    for range in tiles.ranges(count) {
        let run = &mut transforms[range.start as usize..range.end as usize];
        run.sort_by(|a, b| FarField::rank(a.w_axis.x, a.w_axis.z).total_cmp(&FarField::rank(b.w_axis.x, b.w_axis.z)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const FIELD: FarField = FarField { start: 8.0, end: 100.0 };

    #[test]
    fn the_share_is_whole_near_falls_with_distance_and_ends_at_end() {
        assert_eq!([0.0, 4.0, 8.0].map(|d| FIELD.share(d)), [1.0; 3]);
        assert_eq!([16.0, 32.0].map(|d| FIELD.share(d)), [0.25, MIN_SHARE]);
        assert_eq!(FIELD.share(50.0), MIN_SHARE);
        assert_eq!([100.0, 150.0].map(|d| FIELD.share(d)), [0.0; 2]);
        let shares: Vec<f32> = (0..200).map(|d| FIELD.share(d as f32)).collect();
        assert!(shares.windows(2).all(|w| w[1] <= w[0]), "never rises with distance");
        assert_eq!(FarField::new(8.0, 8.0), None);
        assert_eq!(FarField::new(0.0, 8.0), None);
    }

    #[test]
    fn ranks_are_uniform_and_the_widths_keep_the_coverage() {
        let ranks: Vec<f32> = (0..100_000).map(|i| FarField::rank(0.37 * i as f32, -0.11 * (i % 977) as f32)).collect();
        let mut counts = [0u32; 10];
        ranks.iter().for_each(|&r| counts[(r * 10.0) as usize] += 1);
        assert!(counts.iter().all(|&c| (9_500..10_500).contains(&c)), "{counts:?}");
        assert!(ranks.iter().all(|&r| FIELD.width(7.9, r) == 1.0), "near, every instance as it is");
        // The widths of every instance at a distance sum to what they all
        // covered before (up to the sampling), near and far alike.
        for d in [4.0, 12.0, 30.0, 70.0] {
            let covered = ranks.iter().map(|&r| FIELD.width(d, r)).sum::<f32>() / ranks.len() as f32;
            assert!((covered - 1.0).abs() < 0.02, "at {d}: {covered}");
        }
        // In the ring the share, and so the cover, falls to nothing.
        let at = |d: f32| ranks.iter().map(|&r| FIELD.width(d, r)).sum::<f32>() / ranks.len() as f32;
        assert!(at(90.0) < 0.6 && at(99.0) < 0.1, "{} {}", at(90.0), at(99.0));
    }

    #[test]
    fn the_shader_follows_these_constants() {
        let wgsl = include_str!("../shader/forward.wgsl");
        for (name, value) in [("FAR_MIN_SHARE", MIN_SHARE), ("FAR_BAND", BAND), ("FAR_RING", RING)] {
            assert!(wgsl.contains(&format!("const {name}: f32 = {value:?};")), "forward.wgsl's {name} is {value}");
        }
    }

    #[test]
    fn a_tile_draws_every_instance_its_share_keeps() {
        let ranks: Vec<f32> = (0..4000).map(|i| FarField::rank(i as f32 * 0.013, i as f32 * -0.029)).collect();
        let mut sorted = ranks.clone();
        sorted.sort_by(f32::total_cmp);
        for nearest in [5.0, 10.0, 20.0, 40.0, 85.0, 99.0, 120.0] {
            let drawn = FIELD.drawn(4000, nearest) as usize;
            let kept = sorted.iter().filter(|&&r| r < FIELD.share(nearest)).count();
            assert!(
                drawn >= kept && drawn <= kept + 3 * (kept as f64).sqrt() as usize + 200,
                "{nearest}: {drawn} {kept}"
            );
        }
        assert_eq!(FIELD.drawn(4000, 120.0), 0);
    }
}
