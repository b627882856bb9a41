//! Core layer: what a frame adds to its forward shader variants (shadow lookups,
//! light counts, ambient occlusion), chosen before its pipelines are prepared.

use super::shadow_pass::ShadowsDrawn;
use crate::scene::{Light, LightKind};
use crate::shader::LightCounts;

/// What a frame adds to every forward variant: which shadow lookups it compiles in
/// and the light loops' counts. Set by `shadow_pass`, `flush` and `precompile` from
/// their lights.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct FrameVariant {
    /// The frame samples shadow maps (`SHADOWS`).
    pub shadows: bool,
    /// The frame samples point lights' shadow cubes (`SHADOW_CUBES`).
    pub shadow_cubes: bool,
    /// The lights by kind.
    pub lights: LightCounts,
    /// The view has screen-space ambient occlusion (`AMBIENT_OCCLUSION`).
    pub ambient_occlusion: bool,
}

impl FrameVariant {
    /// The variant of a frame lit by `lights` whose shadow pass draws every map
    /// they ask for (what the shadow pass prepares before planning its views).
    /// `ambient_occlusion`: the view's.
    pub(super) fn expected(lights: &[Light], ambient_occlusion: bool) -> Self {
        let point = |l: &Light| matches!(l.kind, LightKind::Point { .. });
        Self {
            shadows: lights.iter().any(|l| l.shadows.is_some()),
            shadow_cubes: lights.iter().any(|l| l.shadows.is_some() && point(l)),
            lights: LightCounts::of(lights),
            ambient_occlusion,
        }
    }

    /// The variant of a frame lit by `lights` after `drawn`, the shadow pass
    /// that drew its maps for these lights (none: no shadows).
    pub(super) fn after(drawn: Option<&ShadowsDrawn>, lights: &[Light], ambient_occlusion: bool) -> Self {
        let point_cubes = |f: &ShadowsDrawn| {
            lights.iter().zip(&f.first_view).any(|(l, v)| v.is_some() && matches!(l.kind, LightKind::Point { .. }))
        };
        Self {
            shadows: drawn.is_some_and(|f| f.views > 0),
            shadow_cubes: drawn.is_some_and(point_cubes),
            lights: LightCounts::of(lights),
            ambient_occlusion,
        }
    }
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
        // The pass found no room for the lamp's cube: the frame looks up 2D maps only.
        let camera = crate::scene::Camera::perspective(60.0, 0.1, 10.0);
        let drawn = ShadowsDrawn {
            frame_index: 0,
            view: camera.into(),
            lights: both.to_vec(),
            first_view: vec![Some(0), None],
            views: 4,
            cost: Default::default(),
            prepared: Default::default(),
        };
        let after = FrameVariant::after(Some(&drawn), &both, false);
        assert!(after.shadows && !after.shadow_cubes);
        let cubed = ShadowsDrawn { first_view: vec![Some(0), Some(0)], views: 10, ..drawn };
        assert!(FrameVariant::after(Some(&cubed), &both, false).shadow_cubes);
        // No maps: no lookups.
        assert_eq!(
            FrameVariant::after(None, &both, false),
            FrameVariant { lights: expected.lights, ..Default::default() }
        );
    }
}
