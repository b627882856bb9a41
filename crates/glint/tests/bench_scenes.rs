//! The benchmark scenes that stand beside the peers (`../shared/peers/README.md`)
//! place exactly the peers' scene: the same cubes in the same order, the same
//! camera, light and material.

mod common;

use glam::Vec3;
use glint::asset::load_scene;

/// The peers' grid: `rows = ceil(sqrt(n·9/32))`, `cols = ceil(n/rows)`.
fn grid(n: usize) -> (usize, usize) {
    let rows = ((n as f64 * 9.0 / 32.0).sqrt()).ceil() as usize;
    (rows, n.div_ceil(rows))
}

#[test]
fn the_peer_cube_scenes_place_the_peers_grid_camera_light_and_material() {
    for (name, n) in [("peer_cubes_1", 1), ("peer_cubes_10k", 10_000), ("peer_cubes_100k", 100_000)] {
        let desc = load_scene(&common::repo_root().join(format!("scenes/bench/{name}.scn"))).expect(name);
        assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
        let (rows, cols) = grid(n);
        let transforms = &desc.entities[0].transforms;
        assert_eq!((desc.entities.len(), transforms.len()), (1, n), "{name}");
        // Row-major from the -x/-z corner, 2 units apart, centred on the origin.
        for (i, t) in transforms.iter().enumerate() {
            let (row, col) = (i / cols, i % cols);
            let want = Vec3::new(2.0 * col as f32 - (cols - 1) as f32, 0.0, 2.0 * row as f32 - (rows - 1) as f32);
            assert!(t.w_axis.truncate().distance(want) < 1e-3, "{name} cube {i}: {} not {want}", t.w_axis);
            assert_eq!(t.x_axis.x, 1.0, "unit cubes");
        }
        // Straight down over the centre of the left half, up -Z, 45° vertical fov.
        let camera = desc.cameras[0];
        let height = rows as f32 / 22.5f32.to_radians().tan();
        assert!(camera.eye.distance(Vec3::new(-(cols as f32) / 2.0, height, 0.0)) < 1e-3, "{:?}", camera.eye);
        let forward = (camera.target - camera.eye).normalize();
        assert!(forward.distance(Vec3::NEG_Y) < 1e-5 && camera.up.distance(Vec3::NEG_Z) < 1e-5, "{camera:?}");
        match camera.projection {
            glint::scene::Projection::Perspective { fov_y, near, far } => {
                assert!((fov_y.to_degrees() - 45.0).abs() < 1e-4 && near == 0.1, "{camera:?}");
                assert!((far - 2.0 * height).abs() < 1e-2, "{camera:?}");
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(desc.lights.len(), 1);
        let light = desc.lights[0];
        assert!(matches!(light.kind, glint::scene::LightKind::Directional { direction }
            if direction.normalize().distance(Vec3::new(-1.0, -1.0, -0.5).normalize()) < 1e-5));
        assert_eq!((light.intensity, light.shadows), (2.0, None));
        let material = &desc.materials[0].material;
        assert_eq!(material.shading, glint::scene::ShadingModel::MetallicRoughness);
        assert_eq!((material.metallic, material.roughness), (0.0, 0.5));
        assert!(material.base_color.truncate().distance(Vec3::new(0.604, 0.445, 0.319)) < 1e-6);
        assert_eq!(desc.environment.ambient, Vec3::ZERO);
    }
}

#[test]
fn the_peer_cube_scenes_render_their_reference_pictures() {
    // 640 × 360 without MSAA, as the peers draw them; about half the cubes in view.
    let Some(gpu) = common::gpu() else { return };
    for (name, drawn) in [("peer_cubes_1", 1), ("peer_cubes_10k", 5_130), ("peer_cubes_100k", 50_232)] {
        let desc = load_scene(&common::repo_root().join(format!("scenes/bench/{name}.scn"))).expect(name);
        let (image, stats) = common::render_sized(gpu, &desc, (640, 360), 1, glint::Culling::Cpu);
        assert_eq!((stats.instances_drawn, stats.draw_calls), (drawn, 1), "{name}");
        common::assert_matches_reference(name, &image);
        // Culled on the GPU (its counts come back later), the same picture.
        let (image, _) = common::render_sized(gpu, &desc, (640, 360), 1, glint::Culling::Gpu);
        common::assert_matches_reference(name, &image);
    }
}
