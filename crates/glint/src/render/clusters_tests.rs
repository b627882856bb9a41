use super::*;
use rand::{Rng, SeedableRng};

/// A perspective and an orthographic camera, looking down −Z from (1, 2, 8)
/// with a tilt, and a viewport with cut-short last tiles.
fn cameras() -> [Camera; 2] {
    let place = |c: Camera| c.looking_at(Vec3::new(1.0, 2.0, 8.0), Vec3::new(0.0, 0.5, 0.0));
    [place(Camera::perspective(60.0, 0.1, 60.0)), place(Camera::orthographic(12.0, 0.1, 60.0))]
}
const SIZE: [u32; 2] = [250, 190];

/// Random point and spot lights around the view, behind the eye too, with
/// ranges from 1 cm to 50 m.
fn random_lights(rng: &mut impl Rng, n: usize) -> Vec<Light> {
    (0..n)
        .map(|_| {
            let position =
                Vec3::new(rng.random_range(-30.0..30.0), rng.random_range(-20.0..20.0), rng.random_range(-60.0..20.0));
            let range = 10f32.powf(rng.random_range(-2.0..1.7));
            if rng.random_bool(0.5) {
                Light::point(position, Vec3::ONE, 1.0, range)
            } else {
                let direction =
                    Vec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
                let outer = rng.random_range(0.05..FRAC_PI_2);
                Light::spot(position, direction, Vec3::ONE, 1.0, range, (outer * 0.5, outer))
            }
        })
        .collect()
}

/// Whether `light` sends anything to `p` (forward.wgsl's window and cone are
/// above zero there).
fn reaches(light: &Light, p: Vec3) -> bool {
    match light.kind {
        LightKind::Directional { .. } => true,
        LightKind::Point { position, range } => p.distance(position) < range,
        LightKind::Spot { position, direction, range, outer_angle, .. } => {
            let to_p = p - position;
            let outer = outer_angle.clamp(1e-3, FRAC_PI_2).cos();
            to_p.length() < range && direction.normalize().dot(to_p.normalize_or_zero()) > outer
        }
    }
}

/// The tile column (`axis` 0) or row (1) of a pixel coordinate, clamped (the shader's rule).
fn tile_of(grid: &ClusterGrid, axis: usize, pixel: f32) -> u32 {
    (pixel / grid.tile_pixels as f32).floor().clamp(0.0, (grid.tiles[axis] - 1) as f32) as u32
}

#[test]
fn every_light_that_reaches_a_point_is_listed_in_its_cluster() {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(49);
    for camera in cameras() {
        let grid = ClusterGrid::new(&camera, SIZE);
        assert_eq!((grid.tiles, grid.tile_pixels, grid.slices), ([16, 12], 16, DEPTH_SLICES));
        let view = camera.view();
        let to_world = view.inverse();
        let lights = random_lights(&mut rng, 400);
        let clusters = bin_lights(&grid, view, &lights);
        assert_eq!(clusters.overflow, 0);
        let (mut checked, mut lit) = (0, 0);
        for _ in 0..20_000 {
            // A fragment: a pixel of the viewport and a depth in the frustum,
            // placed as the shader finds its cluster.
            let (px, py) = (rng.random_range(0.0..SIZE[0] as f32), rng.random_range(0.0..SIZE[1] as f32));
            let depth = grid.near * (grid.far / grid.near).powf(rng.random_range(0.0..1.0));
            let ndc = [2.0 * px / SIZE[0] as f32 - 1.0, 1.0 - 2.0 * py / SIZE[1] as f32];
            let s = if grid.perspective { depth } else { 1.0 };
            let v = Vec3::new(ndc[0] * grid.half_extent[0] * s, ndc[1] * grid.half_extent[1] * s, -depth);
            let p = to_world.transform_point3(v);
            let index = grid.index(tile_of(&grid, 0, px), tile_of(&grid, 1, py), grid.slice_of(depth));
            let listed = clusters.lights(index);
            for (i, light) in lights.iter().enumerate().filter(|(_, l)| reaches(l, p)) {
                assert!(listed.contains(&(i as u32)), "light {i} {light:?} reaches {p} (pixel {px} {py}, depth {depth}) but cluster {index} lists {listed:?}");
                lit += 1;
            }
            checked += 1;
        }
        assert!(lit > checked, "the test's lights reach its points: {lit} over {checked} points");
        // And the lists are far shorter than every light.
        let mean = clusters.indices.len() as f64 / grid.clusters() as f64;
        assert!(mean < lights.len() as f64 / 4.0, "{mean} lights a cluster of {}", lights.len());
    }
}

#[test]
fn a_small_light_reaches_only_the_clusters_around_it_and_hidden_ones_none() {
    let [camera, _] = cameras();
    let grid = ClusterGrid::new(&camera, SIZE);
    let view = camera.view();
    let forward = (camera.target - camera.eye).normalize();
    let at = |depth: f32| camera.eye + forward * depth;
    let lights = [
        Light::point(at(10.0), Vec3::ONE, 1.0, 0.2),
        Light::point(camera.eye - forward * 5.0, Vec3::ONE, 1.0, 2.0),
        Light::point(at(100.0), Vec3::ONE, 1.0, 5.0),
        Light::point(at(10.0) + Vec3::X * 40.0, Vec3::ONE, 1.0, 1.0),
        Light::directional(Vec3::NEG_Y, Vec3::ONE, 1.0),
    ];
    let clusters = bin_lights(&grid, view, &lights);
    assert_eq!(clusters.visible, 1, "behind the eye, beyond the far plane, off to the side and directional: none");
    let touched: Vec<usize> = (0..grid.clusters()).filter(|&c| !clusters.lights(c).is_empty()).collect();
    // 0.2 m at 10 m spans less than a tile and about a slice and a half.
    assert!(!touched.is_empty() && touched.len() <= 8, "{touched:?}");
    let slice = grid.slice_of(10.0);
    let tile = [tile_of(&grid, 0, SIZE[0] as f32 * 0.5), tile_of(&grid, 1, SIZE[1] as f32 * 0.5)];
    assert!(touched.contains(&grid.index(tile[0], tile[1], slice)));
    assert!(clusters.indices.iter().all(|&i| i == 0));
}

#[test]
fn each_cluster_lists_its_lights_in_order_and_overflow_is_counted() {
    let [camera, _] = cameras();
    let grid = ClusterGrid::new(&camera, SIZE);
    let forward = (camera.target - camera.eye).normalize();
    // 300 lights on one spot, then one elsewhere: the spot's clusters keep
    // the first MAX_CLUSTER_LIGHTS and count the rest.
    let mut lights: Vec<Light> =
        (0..300).map(|_| Light::point(camera.eye + forward * 10.0, Vec3::ONE, 1.0, 0.1)).collect();
    lights.push(Light::point(camera.eye + forward * 30.0, Vec3::ONE, 1.0, 0.5));
    let clusters = bin_lights(&grid, camera.view(), &lights);
    assert_eq!(clusters.visible, 301);
    let crowded: Vec<usize> = (0..grid.clusters()).filter(|&c| clusters.lights(c).contains(&0)).collect();
    assert!(!crowded.is_empty());
    for &c in &crowded {
        let listed = clusters.lights(c);
        assert_eq!(listed.len(), MAX_CLUSTER_LIGHTS as usize);
        assert!(listed.iter().enumerate().all(|(k, &i)| i == k as u32), "the lowest-numbered, ascending");
    }
    assert_eq!(clusters.overflow, crowded.len() as u32 * (300 - MAX_CLUSTER_LIGHTS));
    let ranges_cover = clusters.ranges.iter().map(|r| r[1]).sum::<u32>() as usize;
    assert_eq!(ranges_cover, clusters.indices.len());
}

#[test]
fn slices_grow_exponentially_from_near_to_far() {
    let [camera, _] = cameras();
    let grid = ClusterGrid::new(&camera, SIZE);
    assert_eq!(grid.slice_of(0.1), 0);
    assert_eq!(grid.slice_of(0.01), 0, "nearer than the near plane: the first");
    assert_eq!(grid.slice_of(1e4), DEPTH_SLICES - 1, "beyond the far plane: the last");
    for k in 0..DEPTH_SLICES {
        let (start, end) = (grid.slice_start(k), grid.slice_start(k + 1));
        assert_eq!(grid.slice_of(start * 1.001), k);
        assert_eq!(grid.slice_of(end * 0.999), k);
        let ratio = end / start;
        assert!((ratio - (600f32).powf(1.0 / DEPTH_SLICES as f32)).abs() < 1e-3, "slice {k}: {ratio}");
    }
}

#[test]
fn a_frame_takes_thousands_of_lights_with_clusters_and_64_without() {
    let point = Light::point(Vec3::ZERO, Vec3::ONE, 1.0, 1.0);
    let sun = Light::directional(Vec3::NEG_Y, Vec3::ONE, 1.0);
    let many = vec![point; MAX_CLUSTERED_LIGHTS];
    assert!(Clusters::Auto.check(&many).is_ok() && Clusters::On.check(&many).is_ok());
    let refused = |clusters: Clusters, lights: &[Light]| match clusters.check(lights) {
        Err(RenderError::TooManyLights { given, what, most }) => (given, what, most),
        other => panic!("{clusters:?} took {} lights: {other:?}", lights.len()),
    };
    assert_eq!(refused(Clusters::Off, &many), (4096, "lights with light clusters off", 64));
    assert!(Clusters::Off.check(&many[..MAX_LIGHTS]).is_ok());
    let too_many = vec![point; MAX_CLUSTERED_LIGHTS + 1];
    assert_eq!(refused(Clusters::Auto, &too_many), (4097, "lights", 4096));
    let suns = vec![sun; MAX_LIGHTS + 1];
    assert_eq!(refused(Clusters::On, &suns), (65, "directional lights", 64));
    // Auto clusters past 8 point and spot lights, whatever the directional ones.
    let mut few = vec![sun; 3];
    few.extend([point; AUTO_CLUSTER_LIGHTS]);
    assert!(!Clusters::Auto.applies(&few) && Clusters::On.applies(&few) && !Clusters::Off.applies(&few));
    few.push(point);
    assert!(Clusters::Auto.applies(&few));
    // And past the Scene block's 64, however few point and spot lights.
    let mut suns = vec![sun; 60];
    suns.extend([point; 5]);
    assert!(Clusters::Auto.applies(&suns) && Clusters::Auto.check(&suns).is_ok());
    assert_eq!(refused(Clusters::Off, &suns), (65, "lights with light clusters off", 64));
    let thousands = vec![point; MAX_CLUSTERED_LIGHTS + 904];
    assert_eq!(refused(Clusters::Off, &thousands), (5000, "lights with light clusters off", 64));
}

#[test]
fn an_orthographic_view_from_behind_its_eye_and_an_endless_light_are_binned_too() {
    // An orthographic camera whose near plane is behind its eye sees a light
    // there; every cluster lists a light of endless range.
    let camera = Camera::orthographic(10.0, -5.0, 20.0).looking_at(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO);
    let grid = ClusterGrid::new(&camera, SIZE);
    let behind = Light::point(Vec3::new(0.0, 0.0, 7.0), Vec3::ONE, 1.0, 0.5);
    let endless = Light::point(Vec3::new(3.0, 0.0, 0.0), Vec3::ONE, 1.0, f32::INFINITY);
    let clusters = bin_lights(&grid, camera.view(), &[behind, endless]);
    assert_eq!(clusters.visible, 2);
    let centre = grid.index(tile_of(&grid, 0, SIZE[0] as f32 * 0.5), tile_of(&grid, 1, SIZE[1] as f32 * 0.5), 0);
    assert_eq!(clusters.lights(centre), &[0, 1], "the light 2 m behind the eye, in the first slice");
    assert!((0..grid.clusters()).all(|c| clusters.lights(c).contains(&1)), "the endless light everywhere");
    assert!(grid.slice_rule().0.is_finite() && grid.slice_rule().1.is_finite());
}

#[test]
fn binning_lists_exactly_the_clusters_whose_boxes_a_light_meets() {
    // The bisection only saves tests: every cluster whose padded box a light's
    // sphere meets is listed, and no other (the rule the GPU's binning follows).
    let mut rng = rand_pcg::Pcg64::seed_from_u64(50);
    for camera in cameras() {
        let grid = ClusterGrid::new(&camera, SIZE);
        let boxes = grid.boxes();
        let view = camera.view();
        let lights = random_lights(&mut rng, 150);
        let clusters = bin_lights(&grid, view, &lights);
        let mut met = 0;
        for (n, light) in lights.iter().enumerate() {
            let (centre, radius) = light_bounds(light).unwrap();
            let c = view.transform_point3(centre);
            for k in 0..grid.slices as usize {
                for j in 0..grid.tiles[1] as usize {
                    for i in 0..grid.tiles[0] as usize {
                        let index = grid.index(i as u32, j as u32, k as u32);
                        let meets = boxes.meets((i, j, k), c, radius);
                        assert_eq!(
                            clusters.lights(index).contains(&(n as u32)),
                            meets,
                            "light {n} cluster {i} {j} {k}"
                        );
                        met += usize::from(meets);
                    }
                }
            }
        }
        assert_eq!(met, clusters.indices.len());
        assert!(met > 1000, "{met}");
    }
}

#[test]
fn a_cone_of_no_angle_is_bounded_as_the_widest_and_an_endless_light_stays_finite() {
    let spot = |outer| Light::spot(Vec3::ONE, Vec3::X, Vec3::ONE, 1.0, 4.0, (0.1, outer));
    assert_eq!(light_bounds(&spot(f32::NAN)), light_bounds(&spot(FRAC_PI_2)));
    let (_, radius) = light_bounds(&Light::point(Vec3::ZERO, Vec3::ONE, 1.0, f32::INFINITY)).unwrap();
    assert_eq!(radius, MAX_LIGHT_REACH);
    assert!((radius * radius).is_finite(), "the GPU squares it");
}
