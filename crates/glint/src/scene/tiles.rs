//! Core layer: an entity's instances grouped into tiles (the vegetation demo's
//! tiled instancing). Tile k holds the instances `ends[k-1] .. ends[k]`; each
//! tile is culled as a whole by one box (the union of its instances' boxes,
//! grown by the padding) and drawn as one range, and [`Entity::density`]
//! draws the first ⌈len × density⌉ instances of every tile, so a tile's
//! instances should be in random order: the `.scn` loader puts them in order
//! of their far-field rank ([`rank_order`]), which a material's far field
//! needs (it draws a tile's first share).
//!
//! [`rank_order`]: super::far_field::rank_order
//!
//! [`Entity::density`]: super::Entity::density

/// The tiles of an entity's instances, in order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Tiles {
    ends: Vec<u32>,
    padding: f32,
}

impl Tiles {
    /// Tiles of the given sizes, in instance order, their boxes grown by
    /// `padding` on every side (negative or NaN counts as 0). Instances past
    /// the last tile form one more tile; tiles past the instance count are cut
    /// short.
    pub fn from_sizes(sizes: impl IntoIterator<Item = u32>, padding: f32) -> Self {
        let mut end = 0u32;
        let ends = sizes.into_iter().map(|n| {
            end = end.saturating_add(n);
            end
        });
        Self { ends: ends.collect(), padding: if padding > 0.0 && padding.is_finite() { padding } else { 0.0 } }
    }

    /// How far each tile's box reaches past its instances' boxes.
    pub fn padding(&self) -> f32 {
        self.padding
    }

    /// Each tile's instances among `count`, in order; empty tiles included.
    pub fn ranges(&self, count: u32) -> impl Iterator<Item = std::ops::Range<u32>> + '_ {
        let last = self.ends.last().copied().unwrap_or(0);
        let rest = (last < count).then_some(count);
        let mut start = 0;
        self.ends.iter().copied().chain(rest).map(move |end| {
            let range = start.min(count)..end.min(count);
            start = end;
            range
        })
    }

    /// The number of instances drawn of a tile of `len` at `density` (clamped
    /// to 0..=1): ⌈len × density⌉.
    pub fn drawn(len: u32, density: f32) -> u32 {
        let density = if density.is_nan() { 1.0 } else { density.clamp(0.0, 1.0) };
        ((f64::from(len) * f64::from(density)).ceil() as u32).min(len)
    }
}

#[cfg(test)]
mod tests {
    use super::Tiles;

    #[test]
    fn ranges_cover_every_instance_once_in_order() {
        let tiles = Tiles::from_sizes([3, 0, 2], 0.5);
        let ranges: Vec<_> = tiles.ranges(7).collect();
        assert_eq!(ranges, [0..3, 3..3, 3..5, 5..7], "the two past the tiles form one more");
        let short: Vec<_> = tiles.ranges(4).collect();
        assert_eq!(short, [0..3, 3..3, 3..4], "cut at the count");
        assert_eq!(Tiles::from_sizes([1], f32::NAN).padding(), 0.0);
    }

    #[test]
    fn density_draws_the_rounded_up_fraction() {
        assert_eq!([0.0, 0.25, 0.5, 1.0, 2.0, f32::NAN].map(|d| Tiles::drawn(10, d)), [0, 3, 5, 10, 10, 10]);
        assert_eq!(Tiles::drawn(0, 0.5), 0);
    }
}
