//! Core layer: what a frame adds to its forward shader variants (shadow lookups,
//! light counts, ambient occlusion, levels of detail's cross-fade), chosen
//! before its pipelines are prepared.

use crate::scene::{Light, LightKind};
use crate::shader::LightCounts;

/// What a frame adds to every forward variant: which shadow lookups it compiles in
/// and the light loops' counts: each view's, from the frame's shadow plan and
/// lights, and `precompile`'s from its lights.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct FrameVariant {
    /// The frame samples shadow maps (`SHADOWS`).
    pub shadows: bool,
    /// The frame samples point lights' shadow cubes (`SHADOW_CUBES`).
    pub shadow_cubes: bool,
    /// A light with 2D shadow maps has a size: soft shadows (`SOFT_SHADOWS`).
    pub soft_shadows: bool,
    /// The lights by kind.
    pub lights: LightCounts,
    /// The view has screen-space ambient occlusion (`AMBIENT_OCCLUSION`).
    pub ambient_occlusion: bool,
    /// The view cross-fades levels of detail (`LOD_FADE`: render/lod.rs).
    pub lod_fade: bool,
    /// Point and spot lights come from the view's light clusters
    /// (`CLUSTERED`: render/clusters.rs); the loops' positional count is then 0.
    pub clustered: bool,
}

impl FrameVariant {
    /// The variant of a frame lit by `lights` whose shadow pass draws every map
    /// they ask for (what `precompile` builds). `ambient_occlusion`: the view's.
    pub(crate) fn expected(lights: &[Light], ambient_occlusion: bool) -> Self {
        let point = |l: &Light| matches!(l.kind, LightKind::Point { .. });
        Self {
            shadows: lights.iter().any(|l| l.shadows.is_some()),
            shadow_cubes: lights.iter().any(|l| l.shadows.is_some() && point(l)),
            soft_shadows: lights.iter().any(soft),
            lights: LightCounts::of(lights),
            ambient_occlusion,
            lod_fade: false,
            clustered: false,
        }
    }

    /// The variant with point and spot lights clustered, or not.
    pub(crate) fn with_clusters(self, clustered: bool) -> Self {
        let lights = LightCounts { positional: if clustered { 0 } else { self.lights.positional }, ..self.lights };
        Self { clustered, lights, ..self }
    }

    /// The variant with levels of detail cross-faded, or not.
    pub(crate) fn with_lod_fade(self, lod_fade: bool) -> Self {
        Self { lod_fade, ..self }
    }

    /// The variant of a view lit by `lights` whose `views` shadow views were
    /// planned with `first_view`, each light's first (empty: no shadows).
    pub(crate) fn after(first_view: &[Option<u32>], views: usize, lights: &[Light], ambient_occlusion: bool) -> Self {
        let point = |l: &Light| matches!(l.kind, LightKind::Point { .. });
        Self {
            shadows: views > 0,
            shadow_cubes: lights.iter().zip(first_view).any(|(l, v)| v.is_some() && point(l)),
            soft_shadows: lights.iter().zip(first_view).any(|(l, v)| v.is_some() && soft(l)),
            lights: LightCounts::of(lights),
            ambient_occlusion,
            lod_fade: false,
            clustered: false,
        }
    }
}

/// Whether `light` casts soft shadows ([`ShadowSettings::soft`](crate::scene::ShadowSettings::soft)).
fn soft(light: &Light) -> bool {
    light.shadows.is_some_and(|s| s.soft(&light.kind))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::ShadowSettings;
    use glam::Vec3;

    #[test]
    fn only_frames_that_drew_point_light_cubes_look_them_up() {
        let sun = Light::directional(Vec3::NEG_Y, Vec3::ONE, 1.0).with_shadows(ShadowSettings::default());
        let lamp = Light::point(Vec3::Y, Vec3::ONE, 5.0, 10.0).with_shadows(ShadowSettings::default());
        let both = [sun, lamp];
        let expected = FrameVariant::expected(&both, false);
        assert!(expected.shadows && expected.shadow_cubes);
        assert_eq!(expected.lights, LightCounts { directional: 1, positional: 1 });
        assert!(!FrameVariant::expected(&[sun], false).shadow_cubes, "cascades only: no cube lookup");
        let unshadowed = Light { shadows: None, ..lamp };
        assert!(!FrameVariant::expected(&[sun, unshadowed], false).shadow_cubes);
        // The plan found no room for the lamp's cube: the frame looks up 2D maps only.
        let after = FrameVariant::after(&[Some(0), None], 4, &both, false);
        assert!(after.shadows && !after.shadow_cubes);
        assert!(FrameVariant::after(&[Some(0), Some(0)], 10, &both, false).shadow_cubes);
        // A sun with a size: soft shadows; a point light's size changes nothing.
        let soft = ShadowSettings { light_size: 0.5, ..ShadowSettings::default() };
        assert!(!after.soft_shadows && !expected.soft_shadows);
        assert!(FrameVariant::expected(&[sun.with_shadows(soft), lamp], false).soft_shadows);
        assert!(FrameVariant::after(&[Some(0), Some(0)], 10, &[sun.with_shadows(soft), lamp], false).soft_shadows);
        assert!(!FrameVariant::expected(&[sun, lamp.with_shadows(soft)], false).soft_shadows);
        assert!(!FrameVariant::after(&[None, Some(0)], 6, &[sun.with_shadows(soft), lamp], false).soft_shadows);
        // No maps: no lookups.
        assert_eq!(
            FrameVariant::after(&[], 0, &both, false),
            FrameVariant { lights: expected.lights, ..Default::default() }
        );
    }
}
