//! Order-independent transparency ([`Transparency`]): two transparent quads
//! crossing in an X. Exact shows each quad in front on its own side of the
//! crossing, where sorting shows one in front on both; weighted draws the
//! same picture in either submission order, and its error against exact is
//! reported; where nothing crosses, exact draws what sorting does. Exact is
//! an error on the WebGL2 path. On Vulkan, GL and the WebGL2 path, with and
//! without MSAA.

mod common;

use glam::{Mat4, Quat, Vec3, Vec4};
use glint::asset::ShapeKind;
use glint::render::RenderError;
use glint::scene::{AlphaMode, Background, ShadingModel, Transparency};
use glint::{Camera, Entity, Environment, FrameStats, Gpu, Lighting, Material, OffscreenTarget, Renderer, View};

/// Side of the test images, in pixels.
const SIZE: u32 = 64;

/// The GPUs the tests draw on: the default one, GL, and GL within WebGL2's limits.
fn gpus() -> Vec<(&'static str, &'static Gpu)> {
    let all = [("default", common::gpu()), ("GL", common::gl_gpu()), ("GL, WebGL2 limits", common::gl_webgl2_gpu())];
    all.into_iter().filter_map(|(name, gpu)| Some((name, gpu?))).collect()
}

/// A red and a blue quad, unlit, 60% opaque, 1.6 units square, facing the
/// camera turned ±35° about Y: red is nearer on the left (x < 0), blue on
/// the right. `depths` moves them apart along Z (0: they cross at x = 0).
fn quads(renderer: &mut Renderer, depths: f32) -> Vec<Entity> {
    let plane = renderer.add_shape(ShapeKind::Plane.mesh());
    [(Vec4::new(1.0, 0.0, 0.0, 0.6), 35f32, depths), (Vec4::new(0.0, 0.0, 1.0, 0.6), -35.0, -depths)]
        .into_iter()
        .map(|(base_color, degrees, z)| {
            let material = renderer.add_material(Material {
                shading: ShadingModel::Unlit,
                base_color,
                alpha_mode: AlphaMode::Blend,
                ..Material::default()
            });
            let turn = Quat::from_rotation_y(degrees.to_radians()) * Quat::from_rotation_x(90f32.to_radians());
            Entity::new(plane, material, Mat4::from_scale_rotation_translation(Vec3::splat(1.6), turn, Vec3::Z * z))
        })
        .collect()
}

/// The quads (`depths` apart, submitted in reverse when `reversed`) drawn
/// with `transparency` into a target of `samples`, on black.
fn draw(
    gpu: &Gpu,
    (transparency, samples): (Transparency, u32),
    (depths, reversed): (f32, bool),
) -> Result<(image::RgbaImage, FrameStats), RenderError> {
    draw_ordered(gpu, (transparency, samples), (depths, reversed), None)
}

/// [`draw`], the quads drawn at `render_order` (`None`: in the transparent stage).
fn draw_ordered(
    gpu: &Gpu,
    (transparency, samples): (Transparency, u32),
    (depths, reversed): (f32, bool),
    render_order: Option<u8>,
) -> Result<(image::RgbaImage, FrameStats), RenderError> {
    let mut renderer = Renderer::new(gpu);
    let mut entities: Vec<Entity> =
        quads(&mut renderer, depths).into_iter().map(|e| e.with_render_order(render_order)).collect();
    if reversed {
        entities.reverse();
    }
    let camera = Camera::orthographic(2.0, 0.1, 20.0).looking_at(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO);
    let view = View::new(camera).with_transparency(transparency);
    let environment = Environment { background: Background::Color(Vec3::ZERO), ..Default::default() };
    let mut target = OffscreenTarget::new(gpu, SIZE, SIZE, samples).expect("target");
    let stats = renderer.render(&entities, view, Lighting::new(&[], environment), &mut target)?;
    Ok((target.read_rgba8(gpu).expect("readback"), stats))
}

/// The red and blue of the pixel at `x` across, halfway down, 0..255 (sRGB).
fn red_blue(image: &image::RgbaImage, x: u32) -> (u8, u8) {
    let p = image.get_pixel(x, SIZE / 2).0;
    (p[0], p[2])
}

/// The mean absolute difference of two images' channels, 0..1.
fn mean_difference(a: &image::RgbaImage, b: &image::RgbaImage) -> f64 {
    let sum: u64 =
        a.pixels().zip(b.pixels()).flat_map(|(p, q)| (0..3).map(move |c| u64::from(p.0[c].abs_diff(q.0[c])))).sum();
    sum as f64 / (a.pixels().len() * 3) as f64 / 255.0
}

#[test]
fn exact_shows_each_quad_in_front_on_its_side_where_sorting_cannot() {
    for (name, gpu) in gpus().into_iter().filter(|(_, gpu)| gpu.fragment_lists()) {
        for samples in [1, 4] {
            let (exact, stats) = draw(gpu, (Transparency::Exact, samples), (0.0, false)).expect("exact");
            assert_eq!(stats.transparency, Transparency::Exact, "{name}");
            let (left, right) = (red_blue(&exact, SIZE / 4), red_blue(&exact, 3 * SIZE / 4));
            assert!(left.0 > left.1 + 40, "{name} {samples}x: red in front on the left, {left:?}");
            assert!(right.1 > right.0 + 40, "{name} {samples}x: blue in front on the right, {right:?}");
            let (sorted, stats) = draw(gpu, (Transparency::Sorted, samples), (0.0, false)).expect("sorted");
            assert_eq!(stats.transparency, Transparency::Sorted, "{name}");
            let (left, right) = (red_blue(&sorted, SIZE / 4), red_blue(&sorted, 3 * SIZE / 4));
            assert!(
                (left.0 > left.1) == (right.0 > right.1),
                "{name} {samples}x: sorting puts one quad in front on both sides, {left:?} {right:?}"
            );
        }
    }
}

#[test]
fn weighted_is_the_same_in_either_order_and_close_to_exact() {
    for (name, gpu) in gpus() {
        for samples in [1, 4] {
            let (forward, stats) = draw(gpu, (Transparency::Weighted, samples), (0.0, false)).expect("weighted");
            assert_eq!(stats.transparency, Transparency::Weighted, "{name}");
            let (backward, _) = draw(gpu, (Transparency::Weighted, samples), (0.0, true)).expect("weighted");
            let most = common::max_difference(&forward, &backward);
            assert!(most <= 1, "{name} {samples}x: weighted differs by {most} between the orders");
            // Sorting's picture changes with the order where the quads tie.
            let (left, right) = (red_blue(&forward, SIZE / 4), red_blue(&forward, 3 * SIZE / 4));
            assert!(
                left.0 > 0 && left.1 > 0 && right.0 > 0 && right.1 > 0,
                "{name}: both quads show {left:?} {right:?}"
            );
            if !gpu.fragment_lists() {
                continue;
            }
            let (exact, _) = draw(gpu, (Transparency::Exact, samples), (0.0, false)).expect("exact");
            let error = mean_difference(&forward, &exact);
            eprintln!("{name} {samples}x: weighted's mean error against exact {error:.4}");
            assert!(error > 0.0 && error < 0.1, "{name} {samples}x: weighted against exact {error:.4}");
        }
    }
}

#[test]
fn where_nothing_crosses_exact_draws_what_sorting_does() {
    for (name, gpu) in gpus().into_iter().filter(|(_, gpu)| gpu.fragment_lists()) {
        // 0.9 apart along Z: red wholly in front. At one sample: under MSAA
        // exact keeps a fragment whole at the edges (`Transparency::Exact`).
        let (exact, _) = draw(gpu, (Transparency::Exact, 1), (0.9, false)).expect("exact");
        let (sorted, _) = draw(gpu, (Transparency::Sorted, 1), (0.9, false)).expect("sorted");
        let most = common::max_difference(&exact, &sorted);
        assert!(most <= 2, "{name}: exact and sorted differ by {most} where nothing crosses");
        let (left, right) = (red_blue(&exact, SIZE / 4), red_blue(&exact, 3 * SIZE / 4));
        assert!(left.0 > left.1 && right.0 > right.1, "{name}: red in front on both sides {left:?} {right:?}");
    }
}

#[test]
fn exact_is_an_error_on_the_webgl2_path_and_weighted_draws_there() {
    let Some(gpu) = common::gl_webgl2_gpu() else { return };
    assert!(!gpu.fragment_lists());
    match draw(gpu, (Transparency::Exact, 4), (0.0, false)) {
        Err(RenderError::Unavailable { what, .. }) => assert_eq!(what, "exact transparency"),
        other => panic!("exact on the WebGL2 path: {:?}", other.map(|(_, s)| s.transparency)),
    }
}

#[test]
fn a_frame_without_blended_materials_draws_the_same_whatever_the_way() {
    for (name, gpu) in gpus() {
        let opaque = |transparency| {
            let mut renderer = Renderer::new(gpu);
            let cube = renderer.add_shape(ShapeKind::Cube.mesh());
            let material = renderer.add_material(Material::default());
            let entities = [Entity::new(cube, material, Mat4::from_rotation_y(0.5))];
            let camera = Camera::perspective(50.0, 0.1, 20.0).looking_at(Vec3::new(1.0, 1.5, 3.0), Vec3::ZERO);
            let mut target = OffscreenTarget::new(gpu, SIZE, SIZE, 4).expect("target");
            let view = View::new(camera).with_transparency(transparency);
            let sun = [glint::Light::directional(Vec3::new(-0.4, -1.0, -0.6), Vec3::ONE, 1.0)];
            let lighting = Lighting::new(&sun, Environment::default());
            let stats = renderer.render(&entities, view, lighting, &mut target).expect("frame");
            (target.read_rgba8(gpu).expect("readback"), stats)
        };
        let (sorted, _) = opaque(Transparency::Sorted);
        for way in [Transparency::Weighted, Transparency::Exact]
            .into_iter()
            .filter(|w| *w != Transparency::Exact || gpu.fragment_lists())
        {
            let (image, stats) = opaque(way);
            assert!(image == sorted, "{name}: {way:?} changed an opaque frame");
            assert_eq!(stats.transparency, Transparency::Sorted, "{name}: nothing to draw {way:?}");
        }
    }
}

/// A red particle 0.4 behind a blue one (`near_first`: the blue one's record
/// first), and with `pane` a green 60% pane between them, drawn with
/// `transparency` at 4× MSAA: the pixel at the particles' centre (on the
/// diagonal inside each billboard, which both its triangles cover part of:
/// exact must keep one fragment of it).
fn particles(gpu: &Gpu, transparency: Transparency, near_first: bool, pane: bool) -> [u8; 3] {
    use glint::render::{ParticleBlend, ParticleGpu, ParticleLook};
    let mut renderer = Renderer::new(gpu);
    let look = ParticleLook { blend: ParticleBlend::Alpha, texture: None, soft: 0.0, lit: false };
    let layer = renderer.add_particles(2, look).expect("layer");
    let particle = |z: f32, color: [f32; 4]| ParticleGpu { center_size: [0.0, 0.0, z, 1.2], color };
    let mut records = [particle(-0.4, [1.0, 0.0, 0.0, 0.7]), particle(0.4, [0.0, 0.0, 1.0, 0.5])];
    if near_first {
        records.reverse();
    }
    renderer.write_particles(layer, &records);
    let mut entities = Vec::new();
    if pane {
        let plane = renderer.add_shape(ShapeKind::Plane.mesh());
        let material = renderer.add_material(Material {
            shading: ShadingModel::Unlit,
            base_color: Vec4::new(0.0, 1.0, 0.0, 0.6),
            alpha_mode: AlphaMode::Blend,
            ..Material::default()
        });
        let place = Mat4::from_rotation_x(90f32.to_radians()) * Mat4::from_scale(Vec3::splat(1.6));
        entities.push(Entity::new(plane, material, place));
    }
    let camera = Camera::orthographic(2.0, 0.1, 20.0).looking_at(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO);
    let view = View::new(camera).with_transparency(transparency);
    let environment = Environment { background: Background::Color(Vec3::ZERO), ..Default::default() };
    let mut target = OffscreenTarget::new(gpu, SIZE, SIZE, 4).expect("target");
    renderer.render(&entities, view, Lighting::new(&[], environment), &mut target).expect("frame");
    let p = target.read_rgba8(gpu).expect("readback").get_pixel(SIZE / 2, SIZE / 2).0;
    [p[0], p[1], p[2]]
}

#[test]
fn alpha_particles_blend_in_any_order_and_exact_puts_a_pane_between_them() {
    for (name, gpu) in gpus() {
        // Sorted needs the records back to front; weighted and exact do not.
        let sorted = particles(gpu, Transparency::Sorted, false, false);
        assert!(sorted[2] > sorted[0], "{name}: the nearer blue particle over the red {sorted:?}");
        let weighted = [false, true].map(|near_first| particles(gpu, Transparency::Weighted, near_first, false));
        assert_eq!(weighted[0], weighted[1], "{name}: weighted particles in either order");
        if !gpu.fragment_lists() {
            continue;
        }
        for near_first in [false, true] {
            let exact = particles(gpu, Transparency::Exact, near_first, false);
            let most = (0..3).map(|c| exact[c].abs_diff(sorted[c])).max().unwrap_or(0);
            assert!(most <= 2, "{name}: exact {exact:?} against sorted back to front {sorted:?}");
        }
        // Sorting draws particles after blended materials, over the pane
        // though the red one is behind it; exact blends all three in depth order.
        let over = particles(gpu, Transparency::Sorted, false, true);
        let exact = particles(gpu, Transparency::Exact, false, true);
        assert!(exact[0] < over[0], "{name}: the pane hides more of the red particle {exact:?} {over:?}");
        assert!(exact[1] > 0 && exact[2] > exact[1], "{name}: blue over green over red {exact:?}");
    }
}

#[test]
fn blended_materials_queued_before_the_sky_go_to_the_transparency_pass_too() {
    for (name, gpu) in gpus() {
        let ways = [Transparency::Weighted, Transparency::Exact];
        for way in ways.into_iter().filter(|w| *w != Transparency::Exact || gpu.fragment_lists()) {
            let (own, _) = draw(gpu, (way, 4), (0.0, false)).expect("frame");
            // A render order in the opaque stages' range, before the sky.
            let (early, _) = draw_ordered(gpu, (way, 4), (0.0, false), Some(10)).expect("frame");
            let most = common::max_difference(&own, &early);
            assert!(most <= 1, "{name} {way:?}: queued before the sky, the quads differ by {most}");
        }
    }
}
