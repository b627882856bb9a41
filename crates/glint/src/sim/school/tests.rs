//! The grid against brute force, each rule in hand-built cases, the bounds,
//! obstacles and the predator over many steps.

use super::grid::{brute_neighbours, Grid, GridShape};
use super::*;
use crate::scene::Aabb;
use rand::{Rng, SeedableRng};

fn swimmer(position: Vec3, velocity: Vec3) -> Swimmer {
    Swimmer { position, velocity, phase: 0.0 }
}

/// A school of hand-placed fish that sees all round.
fn case(fish: &[(Vec3, Vec3)], tweak: impl FnOnce(&mut SchoolParams)) -> School {
    let mut params = SchoolParams { count: fish.len(), view_angle: 360.0, ..SchoolParams::default() };
    tweak(&mut params);
    School::from_state(params, fish.iter().map(|&(p, v)| swimmer(p, v)).collect(), None)
}

#[test]
fn the_grid_finds_exactly_the_neighbours_brute_force_finds() {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
    let bounds = Aabb { min: Vec3::splat(-4.0), max: Vec3::new(4.0, 3.0, 5.0) };
    for (radius, max_cells) in [(1.0, grid::MAX_CELLS), (0.7, grid::MAX_CELLS), (0.5, 64)] {
        let shape = GridShape::new(bounds, radius, max_cells);
        assert!(shape.cell >= radius && shape.cells() <= max_cells.max(27));
        // Fish on cell borders (exactly on the lines, and a radius apart
        // across them), scattered, and some outside the bounds.
        let mut points: Vec<Vec3> = (0..400)
            .map(|_| {
                let cell = Vec3::new(
                    rng.random_range(0..8) as f32,
                    rng.random_range(0..8) as f32,
                    rng.random_range(0..8) as f32,
                );
                shape.origin + cell * shape.cell
            })
            .collect();
        let across: Vec<Vec3> = (0..100).map(|k| points[k] + Vec3::X * radius).collect();
        let just_within: Vec<Vec3> = (0..100).map(|k| points[k] + Vec3::new(0.0, radius * 0.999, 0.0)).collect();
        points.extend(across.into_iter().chain(just_within));
        points.extend(
            (0..600).map(|_| {
                Vec3::new(rng.random_range(-6.0..6.0), rng.random_range(-6.0..6.0), rng.random_range(-6.0..7.0))
            }),
        );
        let mut grid = Grid::new(shape);
        grid.rebuild(&points);
        let mut total = 0;
        for i in 0..points.len() {
            let want = brute_neighbours(&points, i, radius);
            total += want.len();
            assert_eq!(grid.neighbours(&points, i, radius), want, "fish {i} at {} (radius {radius})", points[i]);
        }
        assert!(total > 500, "the case has neighbours to find: {total}");
    }
}

#[test]
fn the_counting_sort_is_stable_and_complete() {
    let shape = GridShape::new(Aabb { min: Vec3::ZERO, max: Vec3::splat(3.0) }, 1.0, grid::MAX_CELLS);
    let points = [Vec3::splat(0.5), Vec3::splat(2.5), Vec3::splat(0.6), Vec3::splat(0.4)];
    let mut grid = Grid::new(shape);
    grid.rebuild(&points);
    assert_eq!(grid.order, [0, 2, 3, 1], "one cell's fish keep their order");
    assert_eq!(*grid.start.last().unwrap(), 4);
}

#[test]
fn separation_pushes_apart_and_cohesion_pulls_together() {
    let ahead = Vec3::Z;
    let mut school = case(&[(Vec3::ZERO, ahead), (Vec3::new(0.5, 0.0, 0.0), ahead)], |_| {});
    let f = school.forces(0);
    assert_eq!(f.neighbours, 1);
    assert!(
        f.separation.x < 0.0 && f.separation.y.abs() + f.separation.z.abs() < 1e-6,
        "away from the fish at +x: {f:?}"
    );
    assert!(f.cohesion.x > 0.0 && (f.cohesion.x - 0.5).abs() < 1e-6, "towards the middle: {f:?}");
    assert_eq!(f.alignment, Vec3::ZERO, "already aligned");
    // Closer neighbours push harder.
    let near = case(&[(Vec3::ZERO, ahead), (Vec3::new(0.25, 0.0, 0.0), ahead)], |_| {}).forces(0).separation;
    assert!(near.length() > f.separation.length() * 1.9);
}

#[test]
fn alignment_turns_a_fish_towards_its_neighbours_heading() {
    let mut school = case(
        &[(Vec3::ZERO, Vec3::Z), (Vec3::new(0.6, 0.0, 0.0), Vec3::X), (Vec3::new(-0.6, 0.0, 0.0), Vec3::X)],
        |_| {},
    );
    let f = school.forces(0);
    assert_eq!(f.neighbours, 2);
    assert!((f.alignment - (Vec3::X - Vec3::Z)).length() < 1e-6, "{f:?}");
    assert!(f.separation.length() < 1e-5, "symmetric pushes cancel: {f:?}");
    // After steps with alignment alone, it swims more along +x.
    let mut school = case(
        &[(Vec3::ZERO, Vec3::Z), (Vec3::new(0.6, 0.0, 0.0), Vec3::X), (Vec3::new(-0.6, 0.0, 0.0), Vec3::X)],
        |p| p.weights = Weights { alignment: 1.0, separation: 0.0, cohesion: 0.0, ..Weights::default() },
    );
    school.step(0.05);
    let v = school.fish()[0].velocity;
    assert!(v.x > 0.0 && v.z < 1.0, "{v}");
}

#[test]
fn fish_see_only_within_their_radius_and_view_cone() {
    let fish = [
        (Vec3::ZERO, Vec3::Z),
        (Vec3::new(0.0, 0.0, -1.0), Vec3::Z),
        (Vec3::new(0.0, 0.0, 1.0), Vec3::Z),
        (Vec3::new(0.0, 0.0, 2.0), Vec3::Z),
    ];
    let all_round = case(&fish, |_| {}).forces(0);
    assert_eq!(all_round.neighbours, 2, "the fish 2 away is out of reach");
    let ahead_only = case(&fish, |p| p.view_angle = 180.0).forces(0);
    assert_eq!(ahead_only.neighbours, 1, "the fish behind is not seen");
    assert!(ahead_only.cohesion.z > 0.0);
}

#[test]
fn bounds_obstacles_and_the_floor_push_back() {
    let near_wall = Vec3::new(9.5, 0.0, 0.0);
    let f = case(&[(near_wall, Vec3::X)], |_| {}).forces(0);
    assert!(f.bounds.x < 0.0 && f.bounds.y == 0.0 && f.bounds.z == 0.0, "{f:?}");
    assert_eq!(case(&[(Vec3::ZERO, Vec3::X)], |_| {}).forces(0).bounds, Vec3::ZERO, "no push mid-box");
    let rock = Obstacle { center: Vec3::new(2.0, 0.0, 0.0), radius: 1.0 };
    let f = case(&[(Vec3::new(0.8, 0.0, 0.0), Vec3::X)], |p| p.obstacles = vec![rock]).forces(0);
    assert!(f.avoid.x < 0.0, "away from the rock: {f:?}");
    let f = case(&[(Vec3::new(0.0, -4.5, 0.0), Vec3::X)], |p| p.floor = Some(-5.0)).forces(0);
    assert!(f.avoid.y > 0.0, "up off the floor: {f:?}");
}

#[test]
fn fish_stay_inside_the_bounds_and_out_of_obstacles() {
    let rock = Obstacle { center: Vec3::new(0.0, -2.0, 0.0), radius: 2.5 };
    let params = SchoolParams {
        count: 3000,
        bounds: Aabb { min: Vec3::new(-8.0, -4.0, -8.0), max: Vec3::new(8.0, 4.0, 8.0) },
        obstacles: vec![rock],
        floor: Some(-3.5),
        seed: 3,
        ..SchoolParams::default()
    };
    let mut school = School::new(params.clone()).unwrap();
    let mut deepest = f32::MAX;
    for _ in 0..200 {
        school.step(1.0 / 30.0);
        for f in school.fish() {
            let p = f.position;
            assert!(p.cmpge(params.bounds.min).all() && p.cmple(params.bounds.max).all(), "{p} left the bounds");
            assert!(p.y >= -3.5, "{p} went under the floor");
            deepest = deepest.min(p.distance(rock.center) - rock.radius);
            let s = f.velocity.length();
            assert!(s >= params.min_speed - 1e-4 && s <= params.max_speed + 1e-4, "speed {s}");
        }
    }
    assert!(deepest >= -1e-4, "a fish went into the rock by {}", -deepest);
    // The steering keeps most fish a margin off the walls, not pinned there.
    let inside = school.fish().iter().filter(|f| (f.position.x.abs() < 7.9) && (f.position.z.abs() < 7.9)).count();
    assert!(inside as f32 > 0.95 * 3000.0, "{inside} of 3000 clear of the walls");
}

#[test]
fn schooling_aligns_a_random_school() {
    let bounds = Aabb { min: Vec3::splat(-4.0), max: Vec3::splat(4.0) };
    let mut school = School::new(SchoolParams { count: 400, bounds, seed: 5, ..SchoolParams::default() }).unwrap();
    let before = school.stats();
    for _ in 0..300 {
        school.step(1.0 / 30.0);
    }
    let after = school.stats();
    assert!(before.polarisation < 0.1, "{before:?}");
    assert!(after.polarisation > before.polarisation + 0.2, "neighbours line up: {before:?} → {after:?}");
}

#[test]
fn the_predator_hunts_the_nearest_fish_and_scatters_the_school() {
    let hunter = Hunter { start: Vec3::ZERO, speed: 3.5, accel: 6.0, fear: 4.0 };
    let run = |flee: f32| {
        let weights = Weights { flee, ..Weights::default() };
        let params = SchoolParams { count: 1500, predator: Some(hunter), weights, seed: 9, ..SchoolParams::default() };
        let mut school = School::new(params).unwrap();
        let start = school.stats().predator_distance;
        let mut near = 0.0;
        for _ in 0..90 {
            school.step(1.0 / 30.0);
            // Fish within the fear radius, summed over the run.
            let q = school.predator().unwrap().position;
            near += school.fish().iter().filter(|f| f.position.distance(q) < hunter.fear).count() as f32;
        }
        (start, school.stats().predator_distance, near)
    };
    let (start, fleeing, near_fleeing) = run(20.0);
    let (_, unafraid, near_unafraid) = run(0.0);
    assert!(near_fleeing < 0.85 * near_unafraid, "fewer fish stay near it: {near_fleeing} vs {near_unafraid}");
    assert!(fleeing > unafraid && fleeing > start * 0.9, "mean distance {start} → {fleeing} (unafraid {unafraid})");

    // It turns towards the nearest fish.
    let params = SchoolParams { count: 2, predator: Some(hunter), ..SchoolParams::default() };
    let fish = vec![swimmer(Vec3::new(5.0, 0.0, 0.0), Vec3::X), swimmer(Vec3::new(-8.0, 0.0, 0.0), Vec3::X)];
    let prey = Swimmer { position: Vec3::ZERO, velocity: Vec3::Z * 3.5, phase: 0.0 };
    let mut school = School::from_state(params, fish, Some(prey));
    school.step(0.1);
    assert!(school.predator().unwrap().velocity.x > 0.0, "towards the fish at +x");
}

#[test]
fn a_step_is_deterministic_and_beats_faster_at_speed() {
    let params = SchoolParams { count: 500, seed: 11, ..SchoolParams::default() };
    let mut a = School::new(params.clone()).unwrap();
    let mut b = School::new(params).unwrap();
    for _ in 0..20 {
        a.step(0.02);
        b.step(0.02);
    }
    assert_eq!(a.fish(), b.fish());
    let mut slow = Swimmer { velocity: Vec3::Z, ..Swimmer::default() };
    let mut fast = Swimmer { velocity: Vec3::Z * 3.0, ..Swimmer::default() };
    slow.beat(0.1, 3.0, 3.0);
    fast.beat(0.1, 3.0, 3.0);
    assert!(fast.phase > slow.phase * 1.5, "{} vs {}", fast.phase, slow.phase);
}

#[test]
fn bad_parameters_are_refused_with_a_reason() {
    let bad = [
        SchoolParams { count: 0, ..SchoolParams::default() },
        SchoolParams { radius: -1.0, ..SchoolParams::default() },
        SchoolParams { view_angle: 400.0, ..SchoolParams::default() },
        SchoolParams { min_speed: 4.0, max_speed: 2.0, ..SchoolParams::default() },
        SchoolParams { bounds: Aabb { min: Vec3::ONE, max: Vec3::ZERO }, ..SchoolParams::default() },
    ];
    for p in bad {
        assert!(School::new(p).is_err());
    }
}

#[test]
fn a_crowded_fish_tests_an_even_sample_that_keeps_its_rules() {
    // 4,000 fish in a unit box all lie in each other's 27 cells: every fish
    // tested every other (13 s a step at 40,000). Now each tests an even
    // sample of at most MAX_NEIGHBOUR_TESTS; the means it steers by stay
    // those of the whole crowd, and the separation sum keeps its size.
    let mut rng = rand_pcg::Pcg64::seed_from_u64(5);
    let fish: Vec<(Vec3, Vec3)> = (0..4000)
        .map(|_| {
            let p = Vec3::new(rng.random_range(-0.5..0.5), rng.random_range(-0.5..0.5), rng.random_range(-0.5..0.5));
            let v = Vec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), 1.0);
            (p, v)
        })
        .collect();
    let mut school = case(&fish, |p| p.bounds = Aabb { min: Vec3::splat(-0.5), max: Vec3::splat(0.5) });
    for i in [0, 1234, 3999] {
        let sampled = school.forces(i);
        assert!(sampled.neighbours <= MAX_NEIGHBOUR_TESTS && sampled.neighbours > 400, "{}", sampled.neighbours);
        let (p, v) = fish[i];
        let others = || fish.iter().enumerate().filter(|&(j, _)| j != i).map(|(_, f)| f);
        let n = (fish.len() - 1) as f32;
        let cohesion = others().map(|f| f.0).sum::<Vec3>() / n - p;
        let alignment = others().map(|f| f.1).sum::<Vec3>() / n - v;
        let separation: Vec3 = others().map(|f| -(f.0 - p) / (f.0 - p).length_squared().max(1e-4)).sum();
        assert!((sampled.cohesion - cohesion).length() < 0.05, "{} against {cohesion}", sampled.cohesion);
        assert!((sampled.alignment - alignment).length() < 0.1, "{} against {alignment}", sampled.alignment);
        let ratio = sampled.separation.length() / separation.length();
        assert!((0.5..2.0).contains(&ratio), "separation {} against {separation}", sampled.separation);
    }
}
