//! Two-phase occlusion culling: a crowd behind a wall is not drawn once the
//! view has seen the wall, everything in front of it is, and the picture is the
//! frustum-only picture (nothing pops), at a size that is not a power of two.

mod common;

use glam::{Mat4, Vec3};
use glint::asset::ShapeKind;
use glint::{Camera, Culling, Entity, FrameStats, Gpu, Light, Material, OffscreenTarget, Renderer, View};
use rand::{Rng, SeedableRng};

/// Store instances of the wall, the crowd and the people in front, in that
/// order (each entity's range follows the last).
const CROWD: u32 = 2000;
const FRONT: u32 = 60;

struct Street {
    renderer: Renderer,
    entities: Vec<Entity>,
    target: OffscreenTarget,
}

/// A wall across the view, a crowd of cubes behind it (wholly hidden) and a
/// row of cubes in front, seen from the origin down −z, into a 97 × 61 target.
fn street(gpu: &Gpu) -> Street {
    let mut rng = rand_pcg::Pcg32::seed_from_u64(4);
    let mut renderer = Renderer::new(gpu);
    let cube = renderer.add_shape(ShapeKind::Cube.mesh());
    let grey = renderer.add_material(Material::default());
    let red = renderer.add_material(Material::color("red", 0.8, 0.1, 0.1));
    let wall = Entity::new(
        cube,
        grey,
        Mat4::from_scale_rotation_translation(
            Vec3::new(60.0, 40.0, 0.5),
            glam::Quat::IDENTITY,
            Vec3::new(0.0, 0.0, -8.0),
        ),
    );
    let crowd = (0..CROWD)
        .map(|_| {
            let p = Vec3::new(rng.random_range(-6.0..6.0), rng.random_range(-3.0..3.0), rng.random_range(-30.0..-12.0));
            Mat4::from_scale_rotation_translation(Vec3::splat(0.4), glam::Quat::IDENTITY, p)
        })
        .collect();
    let front = (0..FRONT)
        .map(|i| {
            Mat4::from_scale_rotation_translation(
                Vec3::splat(0.1),
                glam::Quat::IDENTITY,
                Vec3::new(i as f32 * 0.05 - 1.5, -0.5, -3.0),
            )
        })
        .collect();
    let entities = vec![wall, Entity::instanced(cube, red, crowd), Entity::instanced(cube, red, front)];
    let target = OffscreenTarget::new(gpu, 97, 61, 4).expect("target");
    Street { renderer, entities, target }
}

fn view(culling: Culling) -> View {
    View::new(Camera::perspective(60.0, 0.1, 100.0).looking_at(Vec3::ZERO, Vec3::NEG_Z)).with_culling(culling)
}

fn frame(street: &mut Street, culling: Culling) -> FrameStats {
    let sun = [Light::directional(Vec3::new(-0.3, -1.0, -0.5), Vec3::ONE, 1.0)];
    let Street { renderer, entities, target } = street;
    renderer.render(entities.iter(), view(culling), &sun[..], target).expect("frame")
}

#[test]
fn a_crowd_behind_a_wall_is_not_drawn_and_the_picture_is_the_frustum_only_one() {
    let Some(gpu) = common::gpu() else { return };
    if !gpu.occlusion_culls() {
        eprintln!("skipping: {} cannot occlusion-cull", gpu.info().name);
        return;
    }
    let mut frustum_only = street(gpu);
    let expected = frame(&mut frustum_only, Culling::Cpu);
    let all = frustum_only.renderer.drawn_instances().expect("read back").swap_remove(0);
    assert_eq!(all.len() as u32, 1 + CROWD + FRONT, "the frustum alone keeps everything");
    let picture = frustum_only.target.read_rgba8(gpu).expect("readback");

    let mut occluded = street(gpu);
    // The first frame draws everything (nothing was seen before); later ones
    // draw what the last one saw, and test the rest against its depth.
    let stats: Vec<FrameStats> = (0..6).map(|_| frame(&mut occluded, Culling::Gpu)).collect();
    assert!(stats.iter().all(|s| s.occlusion && s.culling == Culling::Gpu));
    let kept = occluded.renderer.drawn_instances().expect("read back").swap_remove(0);
    let front: Vec<u32> = (1 + CROWD..1 + CROWD + FRONT).collect();
    assert!(kept.contains(&0), "the wall is drawn");
    assert!(front.iter().all(|i| kept.contains(i)), "everything in front of the wall is drawn");
    let crowd = kept.iter().filter(|&&i| (1..1 + CROWD).contains(&i)).count();
    assert_eq!(crowd, 0, "none of the crowd behind the wall is drawn");
    let counted = stats.last().expect("frames").instances_drawn;
    assert!(counted > 0, "the counts came back");
    assert!(
        (counted as f64) < 0.2 * expected.instances_drawn as f64,
        "{counted} drawn, frustum culling alone draws {}",
        expected.instances_drawn
    );
    let image = occluded.target.read_rgba8(gpu).expect("readback");
    let differing = image.pixels().zip(picture.pixels()).filter(|(a, b)| a != b).count();
    assert_eq!(differing, 0, "pixels that differ from the frustum-only picture");
}

#[test]
fn what_comes_out_from_behind_the_wall_is_drawn_in_the_same_frame() {
    let Some(gpu) = common::gpu() else { return };
    if !gpu.occlusion_culls() {
        return;
    }
    let mut street = street(gpu);
    for _ in 0..4 {
        frame(&mut street, Culling::Gpu);
    }
    // The wall goes: the crowd, hidden last frame, must be drawn now (late phase).
    street.entities[0].set_transform(0, Mat4::from_translation(Vec3::new(0.0, 0.0, 50.0)));
    frame(&mut street, Culling::Gpu);
    let kept = street.renderer.drawn_instances().expect("read back").swap_remove(0);
    let crowd = kept.iter().filter(|&&i| (1..1 + CROWD).contains(&i)).count();
    assert_eq!(crowd as u32, CROWD, "every one of the crowd is in view now");
    let image = street.target.read_rgba8(gpu).expect("readback");
    let mut frustum_only = self::street(gpu);
    frustum_only.entities[0].set_transform(0, Mat4::from_translation(Vec3::new(0.0, 0.0, 50.0)));
    frame(&mut frustum_only, Culling::Cpu);
    let picture = frustum_only.target.read_rgba8(gpu).expect("readback");
    let differing = image.pixels().zip(picture.pixels()).filter(|(a, b)| a != b).count();
    assert_eq!(differing, 0, "pixels that differ from the frustum-only picture");
}

#[test]
fn where_nothing_is_hidden_occlusion_culling_pauses_and_tries_again() {
    let Some(gpu) = common::gpu() else { return };
    if !gpu.occlusion_culls() {
        return;
    }
    // Only the row in front of where the wall was: occlusion culling hides nothing.
    let mut street = street(gpu);
    street.entities.drain(..2);
    let occluded: Vec<bool> = (0..45).map(|_| frame(&mut street, Culling::Gpu).occlusion).collect();
    let paused = occluded.iter().position(|o| !o).expect("it pauses once a count says it hid nothing");
    assert!(occluded[..paused].iter().all(|&o| o) && paused <= 4, "{occluded:?}");
    let resumed = paused + occluded[paused..].iter().position(|&o| o).expect("and tries again");
    // The probe frames' counts still coming back restart the pause: a few frames more.
    let skip = glint::render::SKIP_UNPAID_OCCLUSION as usize;
    assert!((skip..=skip + 4).contains(&(resumed - paused)), "{occluded:?}");
}
