//! Core layer: where each shadow map looks from — the math of shadow views, no GPU.
//!
//! - **Directional:** [`CASCADES`] cascades split the camera's view distance
//!   (a blend of logarithmic and uniform splits). Each cascade is an orthographic
//!   view around the bounding sphere of its slice of the camera frustum, so its
//!   size does not change as the camera turns, and its centre moves in whole
//!   texels, so the map does not shimmer as the camera moves. Its near plane is
//!   pulled back to the farthest caster towards the light, so casters outside the
//!   camera's view still cast.
//! - **Spot:** one perspective view down the cone, as wide as the outer angle.
//! - **Point:** six 90° views, one per cube face, laid out as the GPU samples a
//!   cube map (Vulkan/WebGPU face order and orientation); they store the distance
//!   to the light over its range.

use crate::scene::{Aabb, Camera, Light, LightKind, Projection, ShadowSettings, CASCADES};
use glam::{Mat4, Vec3, Vec4};

/// The most shadow views one camera view draws from (its Camera block
/// holds a record for each, after the camera's).
pub(crate) const MAX_SHADOW_VIEWS: usize = 64;

/// Where a shadow view's depth goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ViewTarget {
    /// A layer of the 2D shadow-map array (cascades and spot lights).
    Layer(u32),
    /// A face of a cube in the cube-map array (point lights): layer `6 · cube + face`.
    CubeFace { cube: u32, face: u32 },
}

/// One view a shadow map is drawn from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ShadowView {
    pub view: Mat4,
    pub proj: Mat4,
    /// The light's position (point and spot), for distance views.
    pub eye: Vec3,
    /// Point lights: 1 / range (depth stores distance × this); 0 for depth views.
    pub distance_scale: f32,
    pub target: ViewTarget,
    /// World size of one texel: absolute for cascades, per unit of distance from
    /// the light for perspective views.
    pub texel: f32,
    /// Cascades: the camera view distance where this cascade ends; 0 otherwise.
    pub split: f32,
    /// Soft shadows: the penumbra's width in uv per unit of NDC depth between
    /// blocker and receiver ([`penumbra_scale`]); 0 keeps the 3×3 filter.
    pub penumbra: f32,
}

/// The width of a penumbra, in the shadow map's uv, per unit of NDC depth
/// between blocker and receiver, for a light of `settings.light_size` seen
/// through `proj`; 0 for a light without a size. By similar triangles: a
/// directional light of angular diameter θ casts a penumbra (d_r − d_b)·2·tan(θ/2)
/// wide, linear in an orthographic view's depth (range 1/|P₂₂|, uv per unit
/// P₀₀/2); a spot light of radius R casts one (d_r − d_b)·2R/d_b wide at the
/// receiver, which in its view's uv is R·P₀₀·(1/d_b − 1/d_r), and 1/d is
/// linear in a perspective view's NDC depth with slope 1/P₃₂ (negative: the
/// scale takes its size).
pub(crate) fn penumbra_scale(proj: Mat4, settings: &ShadowSettings, directional: bool) -> f32 {
    let size = settings.light_size;
    if !(size > 0.0 && size.is_finite()) {
        return 0.0;
    }
    match directional {
        true => (0.5 * size.to_radians()).tan() * proj.x_axis.x / proj.z_axis.z.abs().max(1e-12),
        false => size * proj.x_axis.x / (-proj.w_axis.z).max(1e-12),
    }
}

impl ShadowView {
    pub(crate) fn view_proj(&self) -> Mat4 {
        self.proj * self.view
    }
}

/// Weight of the logarithmic split scheme against the uniform one.
const SPLIT_LAMBDA: f32 = 0.75;

/// The view distances where cascades end, for a camera from `near` out to `distance`.
pub(crate) fn cascade_splits(near: f32, distance: f32) -> [f32; CASCADES] {
    let mut splits = [0.0; CASCADES];
    for (i, split) in splits.iter_mut().enumerate() {
        let f = (i + 1) as f32 / CASCADES as f32;
        let log = near * (distance / near).powf(f);
        let uniform = near + (distance - near) * f;
        *split = SPLIT_LAMBDA * log + (1.0 - SPLIT_LAMBDA) * uniform;
    }
    splits
}

/// The bounding sphere of the camera frustum between view distances `d0` and
/// `d1`, as (distance of its centre along the view axis, radius). It depends only
/// on the slice and the projection, never on where the camera points.
fn slice_sphere(camera: &Camera, aspect: f32, d0: f32, d1: f32) -> (f32, f32) {
    match camera.projection {
        Projection::Perspective { fov_y, .. } => {
            // Half-diagonal of a slice at distance d is d·k.
            let k2 = (fov_y * 0.5).tan().powi(2) * (1.0 + aspect * aspect);
            let center = ((d0 + d1) * 0.5 * (1.0 + k2)).min(d1);
            let r1 = (d1 - center).hypot(d1 * k2.sqrt());
            let r0 = (center - d0).hypot(d0 * k2.sqrt());
            (center, r0.max(r1))
        }
        Projection::Orthographic { height, .. } => {
            let half_diagonal = (height * 0.5) * (1.0 + aspect * aspect).sqrt();
            ((d0 + d1) * 0.5, ((d1 - d0) * 0.5).hypot(half_diagonal))
        }
    }
}

/// Rotation into a light's space: looking along `direction`.
fn light_rotation(direction: Vec3) -> Mat4 {
    let dir = direction.normalize_or(Vec3::NEG_Y);
    let up = if dir.cross(Vec3::Y).length_squared() < 1e-6 { Vec3::Z } else { Vec3::Y };
    glam::camera::rh::view::look_at_mat4(Vec3::ZERO, dir, up)
}

/// The cascades of a directional light travelling along `direction`, for
/// `camera` on a target of `aspect`; `casters` bounds everything that casts,
/// and `first_layer` is the 2D layer of the first cascade.
pub(crate) fn cascades(
    camera: &Camera,
    aspect: f32,
    direction: Vec3,
    settings: &ShadowSettings,
    casters: Option<Aabb>,
    first_layer: u32,
) -> [ShadowView; CASCADES] {
    let (near, far) = match camera.projection {
        Projection::Perspective { near, far, .. } | Projection::Orthographic { near, far, .. } => (near, far),
    };
    let distance = settings.distance.unwrap_or(far).clamp(near * 1.01, far);
    let splits = cascade_splits(near.max(1e-3), distance);
    let rotation = light_rotation(direction);
    let forward = (camera.target - camera.eye).normalize_or(Vec3::NEG_Z);
    let size = settings.map_size as f32;
    std::array::from_fn(|i| {
        let d0 = if i == 0 { near } else { splits[i - 1] };
        let (along, radius) = slice_sphere(camera, aspect, d0, splits[i]);
        // Round the radius up to a fixed step so float noise never resizes the view.
        let radius = (radius * 64.0).ceil() / 64.0;
        let texel = 2.0 * radius / size;
        let center = rotation.transform_point3(camera.eye + forward * along);
        // Move in whole texels only.
        let (x, y) = ((center.x / texel).floor() * texel, (center.y / texel).floor() * texel);
        // Light space looks down -Z: larger z is nearer the light.
        let caster_top = casters.map_or(f32::MIN, |b| light_space_max_z(&rotation, b));
        let top = (center.z + radius).max(caster_top) + texel;
        let bottom = center.z - radius;
        let proj = glam::camera::rh::proj::directx::orthographic(
            x - radius,
            x + radius,
            y - radius,
            y + radius,
            -top,
            -bottom,
        );
        ShadowView {
            view: rotation,
            proj,
            eye: Vec3::ZERO,
            distance_scale: 0.0,
            target: ViewTarget::Layer(first_layer + i as u32),
            texel,
            split: splits[i],
            penumbra: penumbra_scale(proj, settings, true),
        }
    })
}

/// The largest light-space z of a world box's corners.
fn light_space_max_z(rotation: &Mat4, b: Aabb) -> f32 {
    (0..8)
        .map(|k| {
            let corner = Vec3::new(
                if k & 1 == 0 { b.min.x } else { b.max.x },
                if k & 2 == 0 { b.min.y } else { b.max.y },
                if k & 4 == 0 { b.min.z } else { b.max.z },
            );
            rotation.transform_point3(corner).z
        })
        .fold(f32::MIN, f32::max)
}

/// Near plane of a light's perspective views, as a fraction of its range.
const NEAR_FRACTION: f32 = 0.005;

/// The view of a spot light, drawn into 2D layer `layer`.
pub(crate) fn spot(light: &Light, settings: &ShadowSettings, layer: u32) -> Option<ShadowView> {
    let LightKind::Spot { position, direction, range, outer_angle, .. } = light.kind else { return None };
    let half = outer_angle.clamp(1e-3, std::f32::consts::FRAC_PI_2 * 0.99);
    let range = range.max(1e-3);
    let proj = glam::camera::rh::proj::directx::perspective(2.0 * half, 1.0, range * NEAR_FRACTION, range);
    Some(ShadowView {
        view: light_rotation(direction) * Mat4::from_translation(-position),
        proj,
        eye: position,
        distance_scale: 0.0,
        target: ViewTarget::Layer(layer),
        texel: 2.0 * half.tan() / settings.map_size as f32,
        split: 0.0,
        penumbra: penumbra_scale(proj, settings, false),
    })
}

/// Cube faces in layer order (+X, −X, +Y, −Y, +Z, −Z): the directions a face's
/// image runs right and up, and the direction it looks. A direction `d` whose
/// major axis picks the face lands at NDC (right·d, up·d) / |major|, as the GPU's
/// cube lookup reads it (these bases are mirror images, so faces wind backwards:
/// shadow pipelines draw both sides).
pub(crate) const CUBE_FACES: [(Vec3, Vec3, Vec3); 6] = [
    (Vec3::NEG_Z, Vec3::Y, Vec3::X),
    (Vec3::Z, Vec3::Y, Vec3::NEG_X),
    (Vec3::X, Vec3::NEG_Z, Vec3::Y),
    (Vec3::X, Vec3::Z, Vec3::NEG_Y),
    (Vec3::X, Vec3::Y, Vec3::Z),
    (Vec3::NEG_X, Vec3::Y, Vec3::NEG_Z),
];

/// The six face views of a point light, drawn into cube `cube`.
pub(crate) fn cube(light: &Light, settings: &ShadowSettings, cube: u32) -> Option<[ShadowView; 6]> {
    let LightKind::Point { position, range } = light.kind else { return None };
    let range = range.max(1e-3);
    let proj =
        glam::camera::rh::proj::directx::perspective(std::f32::consts::FRAC_PI_2, 1.0, range * NEAR_FRACTION, range);
    Some(std::array::from_fn(|face| {
        let (right, up, forward) = CUBE_FACES[face];
        let back = -forward;
        let rows = Mat4::from_cols(right.extend(0.0), up.extend(0.0), back.extend(0.0), Vec4::W).transpose();
        let view = rows * Mat4::from_translation(-position);
        ShadowView {
            view,
            proj,
            eye: position,
            distance_scale: 1.0 / range,
            target: ViewTarget::CubeFace { cube, face: face as u32 },
            texel: 2.0 / settings.map_size as f32,
            split: 0.0,
            penumbra: 0.0,
        }
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Camera {
        Camera::perspective(60.0, 0.1, 100.0).looking_at(Vec3::new(0.0, 3.0, 8.0), Vec3::ZERO)
    }

    fn ndc(view: &ShadowView, p: Vec3) -> Vec3 {
        view.view_proj().project_point3(p)
    }

    #[test]
    fn splits_grow_to_the_distance() {
        let s = cascade_splits(0.1, 100.0);
        assert!(s.windows(2).all(|w| w[0] < w[1]), "{s:?}");
        assert!((s[CASCADES - 1] - 100.0).abs() < 1e-3);
        assert!(s[0] < 100.0 / CASCADES as f32, "log-weighted: the first cascade is short ({s:?})");
    }

    #[test]
    fn each_cascade_holds_its_slice_of_the_camera_frustum() {
        let cam = camera();
        let aspect = 16.0 / 9.0;
        let settings = ShadowSettings::default();
        let views = cascades(&cam, aspect, Vec3::new(-0.3, -1.0, -0.4), &settings, None, 0);
        let inverse = (cam.projection(aspect) * cam.view()).inverse();
        let depth_of = |d: f32| cam.projection(aspect).project_point3(Vec3::new(0.0, 0.0, -d)).z;
        for (i, v) in views.iter().enumerate() {
            let d0 = if i == 0 { 0.1 } else { views[i - 1].split };
            for (x, y, d) in [(-1.0, -1.0, d0), (1.0, 1.0, d0), (-1.0, 1.0, v.split), (1.0, -1.0, v.split)] {
                let corner = inverse.project_point3(Vec3::new(x, y, depth_of(d)));
                let p = ndc(v, corner);
                assert!(p.x.abs() <= 1.0 && p.y.abs() <= 1.0 && (0.0..=1.0).contains(&p.z), "cascade {i}: {p}");
            }
        }
    }

    #[test]
    fn cascades_keep_their_size_when_the_camera_turns_and_move_in_whole_texels() {
        let settings = ShadowSettings { map_size: 512, ..Default::default() };
        let dir = Vec3::new(-0.3, -1.0, -0.4);
        let a = cascades(&camera(), 1.5, dir, &settings, None, 0);
        let turned = Camera { target: Vec3::new(3.0, -1.0, 0.0), ..camera() };
        let b = cascades(&turned, 1.5, dir, &settings, None, 0);
        for (a, b) in a.iter().zip(&b) {
            assert_eq!(a.texel, b.texel, "same size whatever the direction");
        }
        // A small move shifts the light-space window by a whole number of texels.
        let moved = Camera { eye: camera().eye + Vec3::new(0.013, 0.0, 0.007), ..camera() };
        let c = cascades(&moved, 1.5, dir, &settings, None, 0);
        for (a, c) in a.iter().zip(&c) {
            let shift = (ndc(c, Vec3::ZERO) - ndc(a, Vec3::ZERO)).truncate() * 0.5 * settings.map_size as f32;
            assert!((shift - shift.round()).abs().max_element() < 1e-2, "shift {shift} texels");
        }
    }

    #[test]
    fn casters_towards_the_light_stay_inside_the_depth_range() {
        let settings = ShadowSettings::default();
        // A caster 40 units up, far outside the camera's view, with the sun overhead.
        let tall = Aabb { min: Vec3::new(-1.0, 40.0, -1.0), max: Vec3::new(1.0, 41.0, 1.0) };
        let views = cascades(&camera(), 1.0, Vec3::NEG_Y, &settings, Some(tall), 0);
        let z = ndc(&views[0], Vec3::new(0.0, 40.5, 0.0)).z;
        assert!((0.0..=1.0).contains(&z), "depth {z}");
    }

    #[test]
    fn cube_faces_match_the_gpu_cube_lookup() {
        // The GPU picks the face of the major axis and reads (s, t) = ((sc/|ma| + 1)/2, (tc/|ma| + 1)/2),
        // with sc, tc from the Vulkan table; a view's NDC (x, y) lands at (s, t) = ((x + 1)/2, (1 − y)/2).
        let light = Light::point(Vec3::new(1.0, 2.0, 3.0), Vec3::ONE, 1.0, 10.0);
        let faces = cube(&light, &ShadowSettings::default(), 0).expect("a point light");
        let table = |r: Vec3| -> (usize, f32, f32, f32) {
            let a = r.abs();
            if a.x >= a.y && a.x >= a.z {
                if r.x > 0.0 {
                    (0, -r.z, -r.y, a.x)
                } else {
                    (1, r.z, -r.y, a.x)
                }
            } else if a.y >= a.z {
                if r.y > 0.0 {
                    (2, r.x, r.z, a.y)
                } else {
                    (3, r.x, -r.z, a.y)
                }
            } else if r.z > 0.0 {
                (4, r.x, -r.y, a.z)
            } else {
                (5, -r.x, -r.y, a.z)
            }
        };
        for r in [
            Vec3::new(2.0, 0.3, -0.5),
            Vec3::new(-2.0, 0.7, 0.2),
            Vec3::new(0.4, 3.0, -1.0),
            Vec3::new(0.4, -3.0, 1.2),
            Vec3::new(0.1, -0.6, 2.0),
            Vec3::new(-0.8, 0.5, -2.0),
        ] {
            let (face, sc, tc, ma) = table(r);
            let p = ndc(&faces[face], Vec3::new(1.0, 2.0, 3.0) + r);
            let (s, t) = ((p.x + 1.0) * 0.5, (1.0 - p.y) * 0.5);
            assert!(
                (s - (sc / ma + 1.0) * 0.5).abs() < 1e-5 && (t - (tc / ma + 1.0) * 0.5).abs() < 1e-5,
                "face {face}: {r}"
            );
            assert!((0.0..=1.0).contains(&p.z), "inside the depth range");
        }
    }

    #[test]
    fn the_penumbra_scale_is_the_similar_triangles_ratio_in_uv_per_ndc_depth() {
        let soft = |light_size| ShadowSettings { light_size, ..Default::default() };
        // An orthographic view 4 wide and 10 deep: a 2° light's penumbra grows
        // 2·tan(1°) per unit of distance, 10 units per unit of NDC depth, over 4 units of uv.
        let ortho = glam::camera::rh::proj::directx::orthographic(-2.0, 2.0, -2.0, 2.0, 1.0, 11.0);
        let expected = 10.0 * 2.0 * 1f32.to_radians().tan() / 4.0;
        assert!((penumbra_scale(ortho, &soft(2.0), true) / expected - 1.0).abs() < 1e-5);
        // A 90° perspective view from 0.1 to 10: a blocker at 2 and a receiver at 4
        // under a light of radius 0.2 give a penumbra 2·0.2·(4−2)/2 = 0.4 wide at
        // the receiver, where the view is 8 wide.
        let proj = glam::camera::rh::proj::directx::perspective(std::f32::consts::FRAC_PI_2, 1.0, 0.1, 10.0);
        let ndc = |d: f32| proj.project_point3(Vec3::new(0.0, 0.0, -d)).z;
        let width = penumbra_scale(proj, &soft(0.2), false) * (ndc(4.0) - ndc(2.0));
        assert!((width / (0.4 / 8.0) - 1.0).abs() < 1e-3, "{width}");
        assert_eq!(penumbra_scale(ortho, &soft(0.0), true), 0.0, "no size: the 3x3 filter");
        assert_eq!(penumbra_scale(proj, &soft(f32::NAN), false), 0.0);
    }

    #[test]
    fn a_spot_view_covers_its_cone() {
        let light = Light::spot(Vec3::new(0.0, 4.0, 0.0), Vec3::NEG_Y, Vec3::ONE, 1.0, 10.0, (0.3, 0.5));
        let view = spot(&light, &ShadowSettings::default(), 3).expect("a spot light");
        assert_eq!(view.target, ViewTarget::Layer(3));
        let edge = Vec3::new(0.5f32.tan() * 3.9, 0.1, 0.0);
        let p = ndc(&view, edge);
        assert!((p.x.abs().max(p.y.abs()) - 1.0).abs() < 1e-3, "the outer angle reaches the edge: {p}");
    }
}
