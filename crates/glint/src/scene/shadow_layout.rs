//! Beginner layer: the shadow-map budget of a scene's lights, plain data that the
//! `.scn` loader checks and the renderer allocates by: where each shadow-casting
//! light's views go and how much memory the maps take.

use super::{Light, LightKind, CASCADES};

/// 2D shadow views (cascades and spot lights) the Shadow block holds.
pub(crate) const MAX_2D_VIEWS: usize = 16;
/// Shadow-casting point lights at once.
pub const MAX_CUBES: usize = 4;
/// Most memory the shadow maps of one frame may take: one directional light's
/// four 8192² cascades, or four point lights' cubes at 2048². A frame that asks
/// for more is refused (see [`ShadowLayout::bytes`]) before anything is allocated.
pub const MAX_SHADOW_MAP_BYTES: u64 = 1 << 30;

/// Where each shadow-casting light's views go in the shadow maps, and how big
/// the maps are: the one plan that both the renderer and scene checks use.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ShadowLayout {
    /// Side of every 2D map (the largest any directional or spot light asks for).
    pub size_2d: u32,
    /// Side of every cube face (the largest any point light asks for).
    pub size_cube: u32,
    /// 2D layers and cubes in use.
    pub layers: u32,
    /// Cubes in use.
    pub cubes: u32,
    /// Per light, its first 2D layer (directional, spot) or cube (point); `None`
    /// for lights without shadows or past the maps' room.
    pub first: Vec<Option<u32>>,
}

impl ShadowLayout {
    /// Place `lights` in order: four layers per directional light, one per spot
    /// light (16 layers in all), a cube per point light ([`MAX_CUBES`] in all).
    pub fn plan(lights: &[Light]) -> Self {
        let size_of = |l: &Light| l.shadows.map_or(0, |s| s.map_size.clamp(16, 8192));
        let point = |l: &&Light| matches!(l.kind, LightKind::Point { .. });
        let size_2d = lights.iter().filter(|l| !point(l)).map(size_of).max().unwrap_or(0).max(1);
        let size_cube = lights.iter().filter(point).map(size_of).max().unwrap_or(0).max(1);
        let (mut layers, mut cubes) = (0u32, 0u32);
        let first = lights
            .iter()
            .map(|light| {
                light.shadows?;
                let (slot, count) = match light.kind {
                    LightKind::Directional { .. } if layers as usize + CASCADES <= MAX_2D_VIEWS => {
                        (&mut layers, CASCADES as u32)
                    }
                    LightKind::Spot { .. } if (layers as usize) < MAX_2D_VIEWS => (&mut layers, 1),
                    LightKind::Point { .. } if (cubes as usize) < MAX_CUBES => (&mut cubes, 1),
                    _ => return None,
                };
                *slot += count;
                Some(*slot - count)
            })
            .collect();
        Self { size_2d, size_cube, layers, cubes, first }
    }

    /// Bytes of depth the maps take (4 per texel); the 1-texel placeholders kept
    /// for a kind no light uses count nothing.
    pub fn bytes(&self) -> u64 {
        let texels = |size: u32| if size > 1 { u64::from(size) * u64::from(size) } else { 0 };
        4 * (texels(self.size_2d) * u64::from(self.layers) + texels(self.size_cube) * 6 * u64::from(self.cubes))
    }
}
