//! The post chain on fixed HDR inputs: unlit cubes of known linear colours seen
//! face on through an orthographic camera, so each pixel's input is known.
//! Tonemapping is pinned to its operator's formula; bloom spreads light only
//! around what is above its threshold; edges, FXAA and SMAA change only pixels at
//! geometric edges; the vignette darkens the corners; a chain costs nothing
//! when empty and says what it drew.

mod common;

use glam::{Mat4, Quat, Vec3, Vec4};
use glint::asset::ShapeKind;
use glint::scene::{Background, PostEffect, ShadingModel, Tonemap};
use glint::{Camera, Entity, Environment, Gpu, Lighting, Material, OffscreenTarget, Renderer, View};

/// `boxes` (centre x, y; size; rotation about z; linear colour), unlit, on a
/// `background`, seen face on by an orthographic camera 2 units high, through
/// `post`, into a `width` × `height` image without MSAA.
fn draw(
    gpu: &Gpu,
    boxes: &[(f32, f32, f32, f32, f32)],
    background: f32,
    post: Vec<PostEffect>,
    (width, height): (u32, u32),
) -> (image::RgbaImage, glint::FrameStats) {
    let mut renderer = Renderer::new(gpu);
    let cube = renderer.add_shape(ShapeKind::Cube.mesh());
    let entities: Vec<Entity> = boxes
        .iter()
        .map(|&(x, y, size, angle, value)| {
            let material = renderer.add_material(Material {
                shading: ShadingModel::Unlit,
                base_color: Vec4::new(value, value, value, 1.0),
                ..Material::default()
            });
            let place = Mat4::from_scale_rotation_translation(
                Vec3::splat(size),
                Quat::from_rotation_z(angle),
                Vec3::new(x, y, 0.0),
            );
            Entity::new(cube, material, place)
        })
        .collect();
    let camera = Camera::orthographic(2.0, 0.1, 20.0).looking_at(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO);
    let mut target = OffscreenTarget::new(gpu, width, height, 1).expect("target");
    let view = View::new(camera).with_post(post);
    let environment = Environment { background: Background::Color(Vec3::splat(background)), ..Default::default() };
    let stats = renderer.render(&entities, view, Lighting::new(&[], environment), &mut target).expect("frame");
    (target.read_rgba8(gpu).expect("readback"), stats)
}

/// sRGB encoding of a linear value in 0..1, as a byte.
fn srgb(linear: f64) -> u8 {
    let c = linear.clamp(0.0, 1.0);
    let encoded = if c <= 0.0031308 { 12.92 * c } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 };
    (encoded * 255.0).round() as u8
}

/// AgX of a grey `x`, as `post.wgsl` computes it.
fn agx(x: f64) -> f64 {
    let inset = [
        [0.842479062253094, 0.0423282422610123, 0.0423756549057051],
        [0.0784335999999992, 0.878468636469772, 0.0784336],
        [0.0792237451477643, 0.0791661274605434, 0.879142973793104],
    ];
    let outset = [
        [1.19687900512017, -0.0528968517574562, -0.0529716355144438],
        [-0.0980208811401368, 1.15190312990417, -0.0980434501171241],
        [-0.0990297440797205, -0.0989611768448433, 1.15107367264116],
    ];
    // Column-major, as WGSL's mat3x3 constructor: m · v = Σ column_j · v_j.
    let apply = |m: [[f64; 3]; 3], v: [f64; 3]| -> [f64; 3] {
        std::array::from_fn(|row| (0..3).map(|col| m[col][row] * v[col]).sum())
    };
    let (lo, hi) = (-12.47393, 4.026069);
    let v = apply(inset, [x.max(1e-10); 3]).map(|c| ((c.log2() - lo) / (hi - lo)).clamp(0.0, 1.0));
    let v = v.map(|v| {
        let (v2, v4) = (v * v, v * v * v * v);
        15.5 * v4 * v2 - 40.14 * v4 * v + 31.96 * v4 - 6.868 * v2 * v + 0.4298 * v2 + 0.1191 * v - 0.00232
    });
    apply(outset, v)[0].clamp(0.0, 1.0).powf(2.2)
}

#[test]
fn tonemapping_maps_a_known_ramp_as_each_operator_says() {
    let Some(gpu) = common::gpu() else { return };
    tonemapped_ramp(gpu);
}

#[test]
fn the_post_chain_works_on_gl_too() {
    let Some(gpu) = common::gl_gpu() else { return };
    tonemapped_ramp(gpu);
    let chain = vec![
        PostEffect::BLOOM,
        PostEffect::TONEMAP,
        PostEffect::Fxaa,
        PostEffect::SMAA,
        PostEffect::EDGES,
        PostEffect::VIGNETTE,
    ];
    let (image, stats) = draw(gpu, &[(0.0, 0.0, 0.5, 0.3, 4.0)], 0.1, chain, (48, 48));
    assert_eq!(stats.passes.post.draws, 11, "bloom's four passes, SMAA's three and one for each other effect");
    // The corner: the background, tonemapped by ACES, then 40 % darker.
    let aces = |x: f64| (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14);
    let corner = image.get_pixel(0, 0).0[0];
    assert!(corner.abs_diff(srgb(aces(0.1) * 0.6)) <= 3, "corner {corner}, want {}", srgb(aces(0.1) * 0.6));
    assert!(image.get_pixel(24, 24).0[0] > 200, "the bright square: {:?}", image.get_pixel(24, 24));
}

/// A tonemapping operator's formula on one linear value.
type Curve = fn(f64) -> f64;

/// [`tonemapping_maps_a_known_ramp_as_each_operator_says`] on `gpu`.
fn tonemapped_ramp(gpu: &Gpu) {
    // Eight cubes of 0.125 .. 16, 8 pixels square each, in a 64 × 16 image.
    let values: Vec<f32> = (0..8).map(|i| 2f32.powi(i - 3)).collect();
    let boxes: Vec<_> = (values.iter().enumerate()).map(|(i, &v)| (-3.5 + i as f32, 0.0, 1.0, 0.0, v)).collect();
    let operators: [(Tonemap, Curve); 4] = [
        (Tonemap::None, |x| x.min(1.0)),
        (Tonemap::Reinhard, |x| x / (1.0 + x)),
        (Tonemap::Aces, |x| (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)),
        (Tonemap::Agx, agx),
    ];
    for exposure in [0.0f32, -1.0] {
        for (operator, formula) in operators {
            let (image, stats) = draw(gpu, &boxes, 0.0, vec![PostEffect::Tonemap { operator, exposure }], (64, 16));
            assert_eq!(stats.passes.post.draws, 1, "one full-screen pass");
            for (i, &v) in values.iter().enumerate() {
                let got = image.get_pixel(4 + 8 * i as u32, 8).0;
                let want = srgb(formula(f64::from(v) * 2f64.powf(f64::from(exposure))));
                assert!(
                    got[..3].iter().all(|c| c.abs_diff(want) <= 2),
                    "{operator:?} at exposure {exposure} maps {v} to {got:?}, the formula to {want}"
                );
            }
        }
    }
}

#[test]
fn bloom_spreads_light_around_what_is_above_its_threshold_only() {
    let Some(gpu) = common::gpu() else { return };
    let bloom = vec![PostEffect::Bloom { threshold: 1.0, intensity: 1.0 }];
    let bright = [(0.0, 0.0, 0.25, 0.0, 8.0)];
    let (plain, _) = draw(gpu, &bright, 0.0, Vec::new(), (64, 64));
    let (glow, stats) = draw(gpu, &bright, 0.0, bloom.clone(), (64, 64));
    assert_eq!(stats.passes.post.draws, 4, "bright pass, two blurs, the add");
    // The square covers pixels 28..36; 3 pixels beside it glows, the corners stay dark.
    assert_eq!(plain.get_pixel(25, 32).0[0], 0, "nothing there without bloom");
    assert!(glow.get_pixel(25, 32).0[0] > 20, "light spreads beside the square: {:?}", glow.get_pixel(25, 32));
    assert!(glow.get_pixel(32, 25).0[0] > 20, "above it too");
    assert_eq!(glow.get_pixel(2, 2).0[..3], [0, 0, 0], "far away stays dark");
    // Below the threshold: no halo at all.
    let dim = [(0.0, 0.0, 0.25, 0.0, 0.5)];
    let (dim_plain, _) = draw(gpu, &dim, 0.0, Vec::new(), (64, 64));
    let (dim_bloom, _) = draw(gpu, &dim, 0.0, bloom, (64, 64));
    let most = dim_plain.pixels().zip(dim_bloom.pixels()).map(|(a, b)| a.0[0].abs_diff(b.0[0])).max();
    assert!(most <= Some(1), "a dim square gains no halo: {most:?}");
}

/// Whether pixel (x, y) of `plain` lies within `radius` pixels of a place where
/// neighbouring pixels differ (a geometric edge of the picture).
fn near_edge(plain: &image::RgbaImage, x: u32, y: u32, radius: i32) -> bool {
    let (w, h) = (plain.width() as i32, plain.height() as i32);
    let at = |x: i32, y: i32| plain.get_pixel(x.clamp(0, w - 1) as u32, y.clamp(0, h - 1) as u32).0;
    (-radius..=radius).any(|dy| {
        (-radius..=radius).any(|dx| {
            let (px, py) = (x as i32 + dx, y as i32 + dy);
            at(px, py) != at(px + 1, py) || at(px, py) != at(px, py + 1)
        })
    })
}

#[test]
fn edges_are_drawn_exactly_along_geometric_edges() {
    let Some(gpu) = common::gpu() else { return };
    let square = [(0.0, 0.0, 1.0, 0.3, 0.8)];
    let (plain, _) = draw(gpu, &square, 0.05, Vec::new(), (64, 64));
    let red = Vec3::new(1.0, 0.0, 0.0);
    let (edged, _) = draw(gpu, &square, 0.05, vec![PostEffect::Edges { color: red, threshold: 0.4 }], (64, 64));
    let mut marked = 0;
    for (x, y, p) in edged.enumerate_pixels() {
        if p.0[..3] == [255, 0, 0] {
            marked += 1;
            assert!(near_edge(&plain, x, y, 1), "an edge drawn at ({x}, {y}) away from any edge");
        } else if !near_edge(&plain, x, y, 2) {
            assert_eq!(p.0, plain.get_pixel(x, y).0, "({x}, {y}) is untouched away from the edges");
        }
    }
    // The square's outline is about 4 × 32 pixels long.
    assert!(marked > 100, "the outline is drawn: {marked} pixels");
}

#[test]
fn fxaa_and_smaa_change_only_pixels_at_edges() {
    let Some(gpu) = common::gpu() else { return };
    let square = [(0.0, 0.0, 1.2, 0.5, 0.9)];
    let (plain, _) = draw(gpu, &square, 0.1, Vec::new(), (64, 64));
    // FXAA is one pass, SMAA three (edges, blending weights, blending).
    for (effect, passes) in [(PostEffect::Fxaa, 1), (PostEffect::SMAA, 3)] {
        let (smooth, stats) = draw(gpu, &square, 0.1, vec![effect], (64, 64));
        assert_eq!(stats.passes.post.draws, passes, "{effect:?}");
        let mut changed = 0;
        for (x, y, p) in smooth.enumerate_pixels() {
            let before = plain.get_pixel(x, y).0;
            if p.0.iter().zip(before).any(|(a, b)| a.abs_diff(b) > 2) {
                changed += 1;
                assert!(near_edge(&plain, x, y, 1), "{effect:?} changed ({x}, {y}) away from an edge");
            }
        }
        assert!(changed > 20, "{effect:?}: the rotated square's stair steps are smoothed: {changed} pixels");
    }
}

#[test]
fn a_vignette_darkens_the_corners_and_an_empty_chain_draws_nothing() {
    let Some(gpu) = common::gpu() else { return };
    let (plain, stats) = draw(gpu, &[], 0.5, Vec::new(), (32, 32));
    assert_eq!(stats.passes.post, glint::render::PassStats::default(), "no chain, no post passes");
    let (dark, _) = draw(gpu, &[], 0.5, vec![PostEffect::Vignette { strength: 0.5 }], (32, 32));
    let (centre, corner) = (dark.get_pixel(16, 16).0[0], dark.get_pixel(0, 0).0[0]);
    assert!(centre.abs_diff(plain.get_pixel(16, 16).0[0]) <= 1, "the centre keeps its brightness");
    assert!(corner + 40 < centre, "the corner is darker: {corner} against {centre}");
}
