//! The far field (`scene/far_field.rs`): a field of thin blades whose material
//! has one draws fewer, wider blades far from the camera that cover the
//! ground as all of them do; nearer than its start every blade is drawn as it is; the culler
//! leaves out of each tile only blades the vertex shader narrows away.

mod common;

use glam::{Mat4, Vec3};
use glint::asset::ShapeKind;
use glint::scene::far_field::rank_order;
use glint::scene::FarField;
use glint::scene::ShadowSettings;
use glint::{Camera, Culling, Entity, FrameStats, Light, Material, OffscreenTarget, Renderer, Tiles, View};

/// Tiles along x and z, and blades along each side of a tile.
const TILES: usize = 6;
const SIDE: usize = 24;
/// A tile's side in world units.
const TILE: f32 = 5.0;

/// Thin upright blades (unit cubes 2 cm wide, 2 mm deep, 40 cm tall) over a square field
/// of [`TILES`]² tiles, tile by tile, each tile's in rank order.
fn blades() -> (Vec<Mat4>, Tiles) {
    let mut transforms = Vec::new();
    for (tx, tz) in (0..TILES * TILES).map(|t| (t % TILES, t / TILES)) {
        for (i, j) in (0..SIDE * SIDE).map(|k| (k % SIDE, k / SIDE)) {
            // A jittered grid: even cover, no two blades in a line.
            let jitter = |a: usize, b: usize| ((a * 7919 + b * 104_729) % 997) as f32 / 997.0;
            let x = (tx as f32 + (i as f32 + jitter(i, j)) / SIDE as f32) * TILE - 0.5 * TILES as f32 * TILE;
            let z = -(tz as f32 + (j as f32 + jitter(j, i)) / SIDE as f32) * TILE;
            let yaw = glam::Quat::from_rotation_y(jitter(i + 3, j + 5) * std::f32::consts::TAU);
            transforms.push(Mat4::from_scale_rotation_translation(
                Vec3::new(0.02, 0.4, 0.002),
                yaw,
                Vec3::new(x, 0.2, z),
            ));
        }
    }
    let tiles = Tiles::from_sizes(vec![(SIDE * SIDE) as u32; TILES * TILES], 0.0);
    rank_order(&mut transforms, &tiles);
    (transforms, tiles)
}

/// One frame of the field at 128 × 128 (its material's far field `field`,
/// tiled or not, levels of detail as `levels` says, culled as `culling`
/// says), seen from 1.2 units up looking along it, lit by a sun casting
/// shadows; and its picture.
fn frame(
    gpu: &glint::Gpu,
    (field, tiled): (Option<FarField>, bool),
    (levels, culling): (bool, Culling),
) -> (FrameStats, image::RgbaImage) {
    let mut renderer = Renderer::new(gpu);
    renderer.set_levels_of_detail(levels);
    let cube = renderer.add_shape(ShapeKind::Cube.mesh());
    let green = Material { base_color: glam::Vec4::new(0.2, 0.6, 0.15, 1.0), far_field: field, ..Material::default() };
    let material = renderer.add_material(green);
    let ground = renderer.add_material(Material::color("ground", 0.35, 0.3, 0.2));
    let (transforms, tiles) = blades();
    let mut field = Entity::instanced(cube, material, transforms);
    if tiled {
        field = field.with_tiles(tiles);
    }
    let plane = renderer.add_shape(ShapeKind::Plane.mesh());
    let floor = Entity::new(plane, ground, Mat4::from_scale(Vec3::splat(200.0)));
    let sun = Light::directional(Vec3::new(-0.4, -1.0, -0.3), Vec3::ONE, 2.0)
        .with_shadows(ShadowSettings { distance: Some(20.0), ..ShadowSettings::default() });
    let camera =
        Camera::perspective(50.0, 0.05, 200.0).looking_at(Vec3::new(0.0, 1.2, 1.0), Vec3::new(0.0, 0.3, -20.0));
    let mut target = OffscreenTarget::new(gpu, 128, 128, 1).expect("target");
    let view = View::new(camera).with_culling(culling);
    let mut stats = renderer.render(&[floor, field], view, &[sun], &mut target).expect("frame");
    renderer.wait_for_counts(std::slice::from_mut(&mut stats));
    (stats, target.read_rgba8(gpu).expect("readback"))
}

fn near_field() -> Option<FarField> {
    FarField::new(3.0, 60.0)
}

/// The mean colour of each band of 16 rows of `image` below row `from`, per channel.
fn band_means(image: &image::RgbaImage, from: u32) -> Vec<[f64; 3]> {
    (from / 16..image.height() / 16)
        .map(|band| {
            let pixels = (band * 16..band * 16 + 16).flat_map(|y| (0..image.width()).map(move |x| (x, y)));
            let mut sum = [0.0; 3];
            let mut n = 0.0;
            for (x, y) in pixels {
                let p = image.get_pixel(x, y).0;
                (0..3).for_each(|c| sum[c] += f64::from(p[c]));
                n += 1.0;
            }
            sum.map(|s| s / n)
        })
        .collect()
}

#[test]
fn a_far_field_draws_fewer_wider_blades_and_covers_the_same() {
    let Some(gpu) = common::gpu() else { return };
    for culling in [Culling::Cpu, Culling::Gpu] {
        let (thinned, image) = frame(gpu, (near_field(), true), (true, culling));
        let (all, full) = frame(gpu, (near_field(), true), (false, culling));
        let (drawn, of) = (thinned.instances_drawn, all.instances_drawn);
        assert!(drawn * 3 < of, "{culling:?}: {drawn} of {of} blades drawn");
        assert!(thinned.triangles_drawn * 3 < all.triangles_drawn, "{culling:?}");
        assert!(image != full, "{culling:?}: the far blades are drawn differently");
        // Blade for blade the pictures differ; band by band (the horizon is
        // row 64) the wider blades cover what all of them did.
        for (k, (a, b)) in band_means(&image, 64).iter().zip(band_means(&full, 64)).enumerate() {
            let apart = (0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0, f64::max);
            assert!(apart < 10.0, "{culling:?}: rows {} on: {a:?} against {b:?}", 64 + 16 * k);
        }
    }
}

#[test]
fn nearer_than_its_start_every_blade_is_drawn_as_it_is() {
    let Some(gpu) = common::gpu() else { return };
    // The whole field (under 40 units away) is nearer than the start.
    let far_away = FarField::new(100.0, 200.0);
    let (with, image) = frame(gpu, (far_away, true), (true, Culling::Cpu));
    let (without, full) = frame(gpu, (None, true), (true, Culling::Cpu));
    // Every blade the far field's wider boxes keep too.
    assert!(with.instances_drawn >= without.instances_drawn, "{} {}", with.instances_drawn, without.instances_drawn);
    assert!(image == full, "every blade at its own width: the same picture as no far field");
}

#[test]
fn tiles_leave_out_only_blades_the_shader_narrows_away() {
    let Some(gpu) = common::gpu() else { return };
    // Untiled, every blade is drawn and the vertex shader alone thins them.
    let (tiled, image) = frame(gpu, (near_field(), true), (true, Culling::Cpu));
    let (untiled, shader_only) = frame(gpu, (near_field(), false), (true, Culling::Cpu));
    assert!(
        tiled.instances_drawn * 3 < untiled.instances_drawn,
        "{} of {}",
        tiled.instances_drawn,
        untiled.instances_drawn
    );
    assert!(image == shader_only, "the tiles cut no blade the shader draws");
}
