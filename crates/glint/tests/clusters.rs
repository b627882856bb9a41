//! Clustered forward shading (`render/clusters.rs`): a fragment shading with
//! its cluster's point and spot lights gives the picture of the loop over
//! every light, on each path (storage buffers natively, data textures on the
//! GL and WebGL2 paths), and the frame says how the lights fell.

mod common;

use glam::Vec3;
use glint::render::clusters::{bin_lights, ClusterGrid, MAX_CLUSTER_LIGHTS};
use glint::render::Clusters;
use glint::{Gpu, Light, OffscreenTarget, Renderer};
use rand::{Rng, SeedableRng};

/// 63 small lights (the sun makes 64, a frame's most) in an 8 × 8 grid over the floor, every colour its own,
/// every fourth a spot pointing down; ranges from 0.6 to 1.5 m.
fn lights() -> Vec<Light> {
    (0..63)
        .map(|i| {
            let (x, z) = ((i % 8) as f32, (i / 8) as f32);
            let position = Vec3::new(-4.2 + 1.2 * x, 0.25 + 0.1 * ((i * 7) % 5) as f32, -4.2 + 1.2 * z);
            let hue = i as f32 / 64.0 * std::f32::consts::TAU;
            let color = Vec3::new(hue.cos(), (hue + 2.1).cos(), (hue + 4.2).cos()) * 0.5 + 0.5;
            let range = 0.6 + 0.9 * ((i * 13) % 8) as f32 / 7.0;
            match i % 4 {
                3 => Light::spot(position + Vec3::Y, Vec3::NEG_Y, color, 3.0, range + 1.0, (0.3, 0.6)),
                _ => Light::point(position, color, 1.5, range),
            }
        })
        .collect()
}

/// One 256 × 256 frame of `tests/scenes/clusters.scn` with [`lights`], clustered as `clusters` says.
fn render(gpu: &Gpu, clusters: Clusters) -> (image::RgbaImage, glint::FrameStats) {
    let mut desc = common::load_scene(&common::repo_root().join("tests/scenes/clusters.scn"));
    desc.lights.extend(lights());
    let mut renderer = Renderer::new(gpu);
    renderer.set_clusters(clusters);
    let entities = renderer.place_scene(&desc).entities;
    let mut target = OffscreenTarget::new(gpu, 256, 256, 4).expect("target");
    let view = glint::View::new(desc.cameras[0]);
    let stats = renderer.render(&entities, view, desc.lighting(), &mut target).expect("frame");
    let mut stats = [stats];
    renderer.wait_for_counts(&mut stats); // binned on the GPU, its counts
    let [stats] = stats;
    (target.read_rgba8(gpu).expect("readback"), stats)
}

/// Clustered and not on `gpu`: the same picture (the reference), and the counts.
fn clustered_equals_every_light(gpu: &Gpu) {
    let (every, unclustered) = render(gpu, Clusters::Off);
    let (clustered, stats) = render(gpu, Clusters::Auto);
    assert_eq!(unclustered.light_clusters, None, "--clusters off loops over every light");
    let clusters = stats.light_clusters.expect("64 lights are clustered by default");
    eprintln!("{}: {clusters:?}", gpu.info().name);
    assert_eq!((clusters.grid, clusters.tile_pixels), ([16, 16, 24], 16));
    assert_eq!(clusters.overflow, 0);
    assert!(clusters.lights_visible > 32 && clusters.lights_visible <= 63, "{clusters:?}");
    assert!(clusters.max_per_cluster < 24 && clusters.mean_per_cluster < 4.0, "{clusters:?}");
    assert!(stats.bytes_uploaded.lights >= 64 * clusters.lights_visible as u64, "{:?}", stats.bytes_uploaded);
    let difference = common::max_difference(&every, &clustered);
    assert!(difference <= 2, "clustered shading differs from every light's by {difference}");
    common::assert_matches_reference("clusters", &clustered);
}

#[test]
fn clustered_shading_draws_what_the_loop_over_every_light_draws() {
    let Some(gpu) = common::gpu() else { return };
    clustered_equals_every_light(gpu);
}

#[test]
fn clustered_shading_matches_on_gl_and_the_webgl2_path() {
    for gpu in [common::gl_gpu(), common::webgl2_gpu()].into_iter().flatten() {
        clustered_equals_every_light(gpu);
    }
}

/// `n` × `n` tiny lights 0.15 m apart just over the floor, seen from straight
/// above, each one of six colours (red, green, blue, yellow, cyan, magenta)
/// by a hash of its number: each light's colour must appear under it, and
/// only its own (their ranges do not meet on the floor).
fn every_light_shows_its_colour_under_it(gpu: &Gpu, n: usize) {
    const COLOURS: [[f32; 3]; 6] = [[1., 0., 0.], [0., 1., 0.], [0., 0., 1.], [1., 1., 0.], [0., 1., 1.], [1., 0., 1.]];
    let mut desc = common::load_scene(&common::repo_root().join("tests/scenes/clusters.scn"));
    desc.lights.clear();
    desc.entities.truncate(1); // the floor, not the spheres over it
    let spacing = 0.15;
    let place = |k: usize| (k as f32 - (n as f32 - 1.0) / 2.0) * spacing;
    let colour_of = |i: usize| COLOURS[(i * 7 + i / 5) % 6];
    for i in 0..n * n {
        let position = Vec3::new(place(i % n), 0.05, place(i / n));
        desc.lights.push(Light::point(position, Vec3::from(colour_of(i)), 0.003, 0.07));
    }
    let side = spacing * n as f32;
    let camera = glint::Camera::orthographic(side, 0.5, 20.0).looking_at(Vec3::new(0.0, 10.0, 0.0), Vec3::ZERO);
    let size = (n * 4) as u32;
    let mut renderer = Renderer::new(gpu);
    let entities = renderer.place_scene(&desc).entities;
    let mut target = OffscreenTarget::new(gpu, size, size, 1).expect("target");
    let stats = renderer.render(&entities, glint::View::new(camera), desc.lighting(), &mut target).expect("frame");
    let mut stats = [stats];
    renderer.wait_for_counts(&mut stats);
    let [stats] = stats;
    let image = target.read_rgba8(gpu).expect("readback");
    let clusters = stats.light_clusters.expect("clustered");
    eprintln!("{} lights on {}: {clusters:?}, {:.2} ms binning", n * n, gpu.info().name, stats.cpu_ms.lights);
    assert_eq!(clusters.overflow, 0);
    let view_proj = camera.projection(1.0) * camera.view();
    for (i, light) in desc.lights.iter().enumerate() {
        let glint::scene::LightKind::Point { position, .. } = light.kind else { unreachable!() };
        let ndc = view_proj.project_point3(position.with_y(0.0));
        let (x, y) = (((ndc.x + 1.0) * 0.5 * size as f32) as u32, ((1.0 - ndc.y) * 0.5 * size as f32) as u32);
        let pixel = image.get_pixel(x.min(size - 1), y.min(size - 1)).0;
        for (channel, &wanted) in colour_of(i).iter().enumerate() {
            let lit = pixel[channel] > 60;
            assert_eq!(
                lit,
                wanted > 0.5,
                "light {i} at {position} ({x}, {y}): pixel {pixel:?}, colour {:?}",
                colour_of(i)
            );
        }
    }
}

#[test]
fn four_thousand_lights_each_light_their_own_spot() {
    let Some(gpu) = common::gpu() else { return };
    every_light_shows_its_colour_under_it(gpu, 64);
}

#[test]
fn a_thousand_lights_each_light_their_own_spot_on_the_webgl2_path() {
    let Some(gpu) = common::webgl2_gpu() else { return };
    every_light_shows_its_colour_under_it(gpu, 32);
}

/// `n` random point and spot lights around and behind a camera at (1, 2, 8)
/// looking at (0, 0.5, 0), ranges from 1 cm to 50 m (so straddling cluster
/// planes, and some reaching through the eye), and 300 small ones on one
/// spot 10 m ahead (more than a cluster holds).
fn random_lights(rng: &mut impl Rng, n: usize) -> Vec<Light> {
    let mut lights: Vec<Light> = (0..n)
        .map(|_| {
            let position =
                Vec3::new(rng.random_range(-30.0..30.0), rng.random_range(-20.0..20.0), rng.random_range(-60.0..20.0));
            let range = 10f32.powf(rng.random_range(-2.0..1.7));
            let direction =
                Vec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
            let outer = rng.random_range(0.05..std::f32::consts::FRAC_PI_2);
            match rng.random_bool(0.5) {
                true => Light::point(position, Vec3::ONE, 1.0, range),
                false => Light::spot(position, direction, Vec3::ONE, 1.0, range, (outer * 0.5, outer)),
            }
        })
        .collect();
    let ahead = Vec3::new(1.0, 2.0, 8.0) + (Vec3::new(0.0, 0.5, 0.0) - Vec3::new(1.0, 2.0, 8.0)).normalize() * 10.0;
    lights.extend((0..300).map(|_| Light::point(ahead, Vec3::ONE, 1.0, 0.1)));
    lights
}

/// Both binnings decide with the same single-precision products, term by
/// term; a driver that fused a product into a sum (a fused multiply-add)
/// could move a light exactly on a cluster's padded box across it, which
/// lavapipe does not.
#[test]
fn the_gpu_bins_the_same_lights_into_each_cluster_as_the_cpu() {
    let Some(gpu) = common::gpu() else { return };
    if !Renderer::new(gpu).computes() {
        eprintln!("skipped: {} culls on the CPU, and bins there too", gpu.info().name);
        return;
    }
    let mut rng = rand_pcg::Pcg64::seed_from_u64(4049);
    let place = |c: glint::Camera| c.looking_at(Vec3::new(1.0, 2.0, 8.0), Vec3::new(0.0, 0.5, 0.0));
    let cameras =
        [place(glint::Camera::perspective(60.0, 0.1, 60.0)), place(glint::Camera::orthographic(12.0, 0.1, 60.0))];
    for (camera, (width, height)) in cameras.into_iter().zip([(250, 190), (320, 200)]) {
        let mut desc = common::load_scene(&common::repo_root().join("tests/scenes/clusters.scn"));
        desc.lights = random_lights(&mut rng, 1200);
        // A light of endless range reaches every cluster, on both sides alike.
        desc.lights.push(Light::point(Vec3::new(3.0, 1.0, -4.0), Vec3::ONE, 1.0, f32::INFINITY));
        let mut renderer = Renderer::new(gpu);
        let entities = renderer.place_scene(&desc).entities;
        let mut target = OffscreenTarget::new(gpu, width, height, 1).expect("target");
        let mut frame = |culling| {
            let view = glint::View::new(camera).with_culling(culling);
            let mut stats = [renderer.render(&entities, view, desc.lighting(), &mut target).expect("frame")];
            renderer.wait_for_counts(&mut stats);
            let [stats] = stats;
            (stats.light_clusters.expect("clustered"), renderer.gpu_light_clusters().expect("read back"))
        };
        let (on_cpu, none) = frame(glint::Culling::Cpu);
        let (on_gpu, binned) = frame(glint::Culling::Gpu);
        assert!(!on_cpu.on_gpu && none.is_none(), "a view culled on the CPU bins there");
        assert!(on_gpu.on_gpu, "a view culled on the GPU bins there");
        let gpu_clusters = binned.expect("the GPU's clusters");
        let grid = ClusterGrid::new(&camera, [width, height]);
        let cpu_clusters = bin_lights(&grid, camera.view(), &desc.lights);
        assert_eq!(gpu_clusters.grid, grid);
        for c in 0..grid.clusters() {
            assert_eq!(gpu_clusters.lights(c), cpu_clusters.lights(c), "cluster {c}");
        }
        // The GPU's counts are the CPU's, overflow included.
        assert_eq!(on_gpu, glint::render::ClusterStats { on_gpu: true, ..on_cpu });
        assert!(on_cpu.overflow > 0 && on_cpu.max_per_cluster == MAX_CLUSTER_LIGHTS, "{on_cpu:?}");
        assert!(cpu_clusters.indices.len() > 20_000, "{}", cpu_clusters.indices.len());
        eprintln!("{}: {on_gpu:?}", gpu.info().name);
    }
}

/// The heat map's colour (`forward.wgsl`'s `cluster_heat`) for a cluster of
/// `count` lights, before shading: the jet scale at log2(1 + count) / 8.
fn jet(count: u32) -> [f32; 3] {
    let t = ((1.0 + count as f32).log2() / 8.0).min(1.0);
    [3.0, 2.0, 1.0].map(|c: f32| (1.5 - (4.0 * t - c).abs()).clamp(0.0, 1.0))
}

/// A pixel's colour from sRGB bytes to linear, scaled to its largest channel.
fn hue(pixel: [u8; 4]) -> [f32; 3] {
    let linear = [0, 1, 2].map(|c| {
        let v = pixel[c] as f32 / 255.0;
        if v <= 0.04045 {
            v / 12.92
        } else {
            ((v + 0.055) / 1.055).powf(2.4)
        }
    });
    let top = linear.iter().copied().fold(1e-6, f32::max);
    linear.map(|v| v / top)
}

/// With the heat map on, each tile of a floor seen from straight above shows
/// the colour of the number of lights its cluster at the floor's depth lists
/// (as the CPU bins them), on each path.
fn heat_map_shows_each_clusters_lights(gpu: &Gpu) {
    let mut desc = common::load_scene(&common::repo_root().join("tests/scenes/clusters.scn"));
    desc.entities.truncate(1); // the floor
    desc.lights = lights();
    let camera = glint::Camera::orthographic(10.0, 0.5, 20.0).looking_at(Vec3::new(0.0, 10.0, 0.0), Vec3::ZERO);
    let size = 256;
    let mut renderer = Renderer::new(gpu);
    renderer.set_cluster_heat_map(true);
    let entities = renderer.place_scene(&desc).entities;
    let mut target = OffscreenTarget::new(gpu, size, size, 1).expect("target");
    renderer.render(&entities, glint::View::new(camera), desc.lighting(), &mut target).expect("frame");
    let image = target.read_rgba8(gpu).expect("readback");
    let grid = ClusterGrid::new(&camera, [size, size]);
    let clusters = bin_lights(&grid, camera.view(), &desc.lights);
    let slice = grid.slice_of(10.0);
    let mut seen = std::collections::BTreeSet::new();
    for y in 0..grid.tiles[1] {
        for x in 0..grid.tiles[0] {
            let count = clusters.lights(grid.index(x, y, slice)).len() as u32;
            let wanted = jet(count);
            let top = wanted.iter().copied().fold(0.0, f32::max);
            let centre = (x * grid.tile_pixels + grid.tile_pixels / 2, y * grid.tile_pixels + grid.tile_pixels / 2);
            let got = hue(image.get_pixel(centre.0, centre.1).0);
            for c in 0..3 {
                assert!(
                    (got[c] - wanted[c] / top).abs() < 0.08,
                    "tile {x} {y}: {count} lights, {got:?} for {wanted:?}"
                );
            }
            seen.insert(count.min(8));
        }
    }
    assert!(seen.len() >= 4, "the floor shows several counts: {seen:?}");
    // Off again, the floor is shaded as ever.
    renderer.set_cluster_heat_map(false);
    renderer.render(&entities, glint::View::new(camera), desc.lighting(), &mut target).expect("frame");
    assert!(common::max_difference(&image, &target.read_rgba8(gpu).expect("readback")) > 100);
}

#[test]
fn the_heat_map_shows_each_clusters_light_count() {
    let Some(gpu) = common::gpu() else { return };
    heat_map_shows_each_clusters_lights(gpu);
}

#[test]
fn the_heat_map_shows_each_clusters_light_count_on_gl_and_the_webgl2_path() {
    for gpu in [common::gl_gpu(), common::webgl2_gpu()].into_iter().flatten() {
        heat_map_shows_each_clusters_lights(gpu);
    }
}

/// A light's pixel on the picture, and its colour.
type LightPixel = ([u32; 2], [f32; 3]);

/// A wall of lit white particles (10 × 10, 0.5 apart, alpha-blended) facing
/// the camera, and 5 × 5 small point lights 0.3 in front of it, 1 apart,
/// each one of six colours, drawn `clusters` as said (or the particles
/// unlit): the picture, and the lights' pixels with their colours.
fn lit_particles(gpu: &Gpu, clusters: Clusters, lit: bool) -> (image::RgbaImage, Vec<LightPixel>) {
    use glint::render::{ParticleBlend, ParticleLook};
    const COLOURS: [[f32; 3]; 6] = [[1., 0., 0.], [0., 1., 0.], [0., 0., 1.], [1., 1., 0.], [0., 1., 1.], [1., 0., 1.]];
    let mut renderer = Renderer::new(gpu);
    renderer.set_clusters(clusters);
    let look = ParticleLook { blend: ParticleBlend::Alpha, texture: None, soft: 0.0, lit };
    let layer = renderer.add_particles(100, look).expect("a layer");
    let records: Vec<glint::render::ParticleGpu> = (0..100)
        .map(|i| glint::render::ParticleGpu {
            center_size: [(i % 10) as f32 * 0.5 - 2.25, (i / 10) as f32 * 0.5 - 2.25, 0.0, 0.9],
            color: [1.0, 1.0, 1.0, 1.0],
        })
        .collect();
    renderer.write_particles(layer, &records);
    let lights: Vec<Light> = (0..25)
        .map(|i| {
            let position = Vec3::new((i % 5) as f32 - 2.0, (i / 5) as f32 - 2.0, 0.3);
            Light::point(position, Vec3::from(COLOURS[(i * 7 + i / 5) % 6]), 0.2, 0.6)
        })
        .collect();
    let camera = glint::Camera::perspective(60.0, 0.5, 20.0).looking_at(Vec3::new(0.0, 0.0, 6.0), Vec3::ZERO);
    let environment = glint::Environment { ambient: Vec3::ZERO, ..Default::default() };
    let size = 128;
    let mut target = OffscreenTarget::new(gpu, size, size, 1).expect("target");
    let view = glint::View::new(camera);
    let input = glint::FrameInput::new(&[], glint::Lighting::new(&lights, environment)).view(glint::ViewKey(0), &view);
    let stats = renderer.render_frame(input, &mut target).expect("frame").views;
    assert_eq!(stats[0].light_clusters.is_some(), clusters != Clusters::Off, "{:?}", stats[0].light_clusters);
    let view_proj = camera.projection(1.0) * camera.view();
    let under = (lights.iter().enumerate())
        .map(|(i, light)| {
            let glint::scene::LightKind::Point { position, .. } = light.kind else { unreachable!() };
            let ndc = view_proj.project_point3(position.with_z(0.0));
            let pixel = [((ndc.x + 1.0) * 0.5 * size as f32) as u32, ((1.0 - ndc.y) * 0.5 * size as f32) as u32];
            (pixel, COLOURS[(i * 7 + i / 5) % 6])
        })
        .collect();
    (target.read_rgba8(gpu).expect("readback"), under)
}

/// Lit particles take their point lights from the clusters as the loop over
/// every light gives them, each light's colour on the particles behind it.
fn particles_are_lit_from_the_clusters(gpu: &Gpu) {
    let (clustered, under) = lit_particles(gpu, Clusters::On, true);
    let (every, _) = lit_particles(gpu, Clusters::Off, true);
    let (unlit, _) = lit_particles(gpu, Clusters::On, false);
    let difference = common::max_difference(&every, &clustered);
    assert!(difference <= 2, "{}: lit from the clusters differs from every light's by {difference}", gpu.info().name);
    for ([x, y], colour) in under {
        let pixel = clustered.get_pixel(x, y).0;
        for (channel, &wanted) in colour.iter().enumerate() {
            assert_eq!(pixel[channel] > 60, wanted > 0.5, "{}: ({x}, {y}) {pixel:?} for {colour:?}", gpu.info().name);
        }
        let [r, g, b, _] = unlit.get_pixel(x, y).0;
        let grey = r.max(g).max(b) - r.min(g).min(b) <= 4;
        assert!(r > 100 && grey, "unlit particles show their own white (over the sky), however lit: {r} {g} {b}");
    }
}

#[test]
fn lit_particles_take_their_lights_from_the_clusters() {
    let Some(gpu) = common::gpu() else { return };
    particles_are_lit_from_the_clusters(gpu);
}

#[test]
fn lit_particles_take_their_lights_from_the_clusters_on_gl_and_the_webgl2_path() {
    for gpu in [common::gl_gpu(), common::webgl2_gpu()].into_iter().flatten() {
        particles_are_lit_from_the_clusters(gpu);
    }
}
