//! Tiny Graphics' program structure in glint: create everything once, then each
//! frame update, submit, draw the shadow maps and flush. Writes `hello.png`.
//!
//! Run: `cargo run --example hello`
use glam::{Mat4, Quat, Vec3};
use glint::{asset::ShapeKind, Camera, Entity, Gpu, Light, Material, OffscreenTarget, Renderer, ShadowSettings};
use std::f32::consts::TAU;

fn main() -> Result<(), glint::Error> {
    // Init: GPU, renderer, camera, lights, materials, shapes, entities.
    let gpu = Gpu::headless()?;
    let mut renderer = Renderer::new(&gpu);
    let camera = Camera::perspective(45.0, 0.1, 100.0).looking_at(Vec3::new(0.0, 4.0, 9.0), Vec3::new(0.0, 0.5, 0.0));
    let lights = [
        Light::directional(Vec3::new(-1.0, -2.0, -1.5), Vec3::ONE, 1.2).with_shadows(ShadowSettings::default()),
        Light::point(Vec3::new(0.0, 2.5, 0.0), Vec3::new(1.0, 0.6, 0.3), 6.0, 6.0),
    ];
    let red = renderer.add_material(Material::color("red", 0.8, 0.12, 0.08));
    let blue = renderer.add_material(Material::color("blue", 0.1, 0.3, 0.85));
    let grey = renderer.add_material(Material::color("grey", 0.45, 0.45, 0.45));
    let cube = renderer.add_shape(ShapeKind::Cube.mesh());
    let ball = renderer.add_shape(ShapeKind::Sphere.mesh());
    let floor = renderer.add_shape(ShapeKind::Plane.mesh());
    let ground = Entity::new(floor, grey, Mat4::from_scale(Vec3::new(12.0, 1.0, 12.0)));
    let mut ring = Entity::instanced(cube, red, Vec::new());
    let mut bouncer = Entity::new(ball, blue, Mat4::IDENTITY);
    let mut target = OffscreenTarget::new(&gpu, 640, 360, 4)?;

    // Per frame: update entities, submit them, draw the shadow maps, flush with
    // camera and lights (`renderer.render(..)` does the last three in one call).
    for frame in 0..3 {
        let t = frame as f32 * 0.4;
        *ring.transforms_mut() = (0..12)
            .map(|i| Quat::from_rotation_y(i as f32 / 12.0 * TAU + t))
            .map(|r| Mat4::from_rotation_translation(r, r * Vec3::new(3.0, 0.5, 0.0)))
            .collect();
        bouncer.set_transform(0, Mat4::from_translation(Vec3::new(0.0, 0.8 + t.sin(), 0.0)));
        renderer.submit(&ground);
        renderer.submit(&ring);
        renderer.submit(&bouncer);
        let shadows = renderer.shadow_pass(camera, &lights, &target)?;
        let mut stats = renderer.flush(camera, &lights, &shadows, &mut target)?;
        // Culled on the GPU, the instance counts come back a frame or two
        // late; waiting for them here keeps the printout simple.
        renderer.wait_for_counts(std::slice::from_mut(&mut stats));
        println!(
            "frame {frame}: {} draws, {} instances, {} shadow views ({} draws), {} bytes uploaded",
            stats.draw_calls,
            stats.instances_drawn,
            stats.shadow_views,
            stats.passes.shadow.draws,
            stats.bytes_uploaded.total
        );
    }
    target.save_png(&gpu, "hello.png")?;
    Ok(())
}
