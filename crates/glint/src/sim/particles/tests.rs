//! The schedule against counting, spawning, motion and the records drawn.

use super::*;
use glam::Vec3;
use glam::Vec4;

fn counted_alive(system: &ParticleSystem) -> u64 {
    system.slots().iter().filter(|p| p.id > 0 && p.age < system.params().life(p.id - 1)).count() as u64
}

#[test]
fn alive_particles_follow_rate_times_lifetime() {
    let params = EmitterParams { rate: 200.0, lifetime: (1.5, 1.5), ..EmitterParams::default() };
    let mut system = ParticleSystem::new(params.clone(), 1.0 / 60.0).unwrap();
    for step in 1..=240 {
        system.step();
        let t = system.time();
        let alive = counted_alive(&system);
        assert_eq!(alive, system.schedule().alive_at(&params, t), "step {step}");
        let expected = (200.0 * t.min(1.5)) as i64;
        assert!((alive as i64 - expected).abs() <= 2, "t {t}: {alive} alive, rate × lifetime says {expected}");
    }
    // Steady state: rate × lifetime.
    assert!((counted_alive(&system) as i64 - 300).abs() <= 1);
    assert_eq!(system.schedule().spawned_at(4.0), 801);
}

#[test]
fn varied_lives_and_bursts_are_counted_alike_by_the_schedule_and_the_slots() {
    let params = EmitterParams {
        rate: 90.0,
        lifetime: (0.5, 2.0),
        burst: Burst { count: 40, every: 0.7 },
        ..EmitterParams::default()
    };
    let mut system = ParticleSystem::new(params.clone(), 0.02).unwrap();
    let mut most = 0;
    for _ in 0..300 {
        system.step();
        let alive = counted_alive(&system);
        assert_eq!(alive, system.schedule().alive_at(&params, system.time()), "t {}", system.time());
        most = most.max(alive);
    }
    // Mean life 1.25 s: 112 from the stream and about 40 × 1.25 / 0.7 from bursts.
    assert!((150..=260).contains(&most), "{most}");
    assert!(most <= system.schedule().slots(), "the pool holds every living particle");
}

#[test]
fn a_slot_is_free_before_its_next_particle_takes_it() {
    // With lives at their longest, each slot's particle dies before the next arrives.
    let params = EmitterParams { rate: 1000.0, lifetime: (0.3, 0.3), ..EmitterParams::default() };
    let schedule = Schedule::new(&params);
    for slot in 0..schedule.stream_slots() {
        let id = schedule.occupant(slot, 5.0).unwrap();
        let next = id + schedule.stream_slots();
        assert!(schedule.spawn_time(next) - schedule.spawn_time(id) > params.life(id));
    }
}

#[test]
fn particles_spawn_within_their_shape_and_spread() {
    let base =
        EmitterParams { origin: Vec3::new(1.0, 2.0, 3.0), speed: (2.0, 3.0), spread: 20.0, ..EmitterParams::default() };
    for (shape, within) in [
        (SpawnShape::Point, 1e-6),
        (SpawnShape::Sphere(0.5), 0.5 + 1e-5),
        (SpawnShape::Box(Vec3::new(0.2, 0.3, 0.4)), 0.54),
        (SpawnShape::Cone(0.25), 0.25 + 1e-5),
    ] {
        let params = EmitterParams { shape, ..base.clone() };
        for id in 0..500 {
            let p = params.spawn(id);
            let (x, v) = (Vec3::from(p.position), Vec3::from(p.velocity));
            assert!(x.distance(params.origin) <= within, "{shape:?}: {x}");
            assert!((2.0 - 1e-4..=3.0 + 1e-4).contains(&v.length()), "speed {}", v.length());
            assert!(v.normalize().angle_between(Vec3::Y).to_degrees() <= 20.01, "{shape:?}: {v}");
        }
    }
    // The same id and seed spawn the same particle; another seed another one.
    assert_eq!(base.spawn(7), base.spawn(7));
    assert_ne!(base.spawn(7), EmitterParams { seed: 2, ..base.clone() }.spawn(7));
}

#[test]
fn gravity_drag_and_the_ground_move_particles_as_they_should() {
    let params = EmitterParams {
        speed: (0.0, 0.0),
        gravity: Vec3::new(0.0, -9.81, 0.0),
        ground: Some((-1.0, 0.5)),
        ..EmitterParams::default()
    };
    let mut p = params.spawn(0);
    for _ in 0..30 {
        params.advance(&mut p, 0.01, 0.0);
    }
    // Semi-implicit Euler: y = -g·dt²·n(n+1)/2.
    let fallen = -9.81 * 0.01 * 0.01 * 30.0 * 31.0 / 2.0;
    assert!((p.position[1] - fallen).abs() < 1e-4, "{}", p.position[1]);
    for _ in 0..100 {
        params.advance(&mut p, 0.01, 0.0);
        assert!(p.position[1] >= -1.0, "never under the ground");
    }
    let dragged = EmitterParams { drag: 2.0, speed: (1.0, 1.0), spread: 0.0, ..EmitterParams::default() };
    let mut q = dragged.spawn(0);
    dragged.advance(&mut q, 0.5, 0.0);
    assert!((Vec3::from(q.velocity).length() - (-1.0f32).exp()).abs() < 1e-5);
}

#[test]
fn records_grow_and_fade_over_life_and_sort_back_to_front() {
    let params = EmitterParams {
        rate: 50.0,
        lifetime: (1.0, 1.0),
        speed: (1.0, 1.0),
        spread: 180.0,
        size: 0.1,
        size_end: 0.5,
        color: Vec4::new(1.0, 0.0, 0.0, 1.0),
        color_end: Vec4::new(0.0, 0.0, 1.0, 0.0),
        ..EmitterParams::default()
    };
    let mut system = ParticleSystem::new(params, 0.01).unwrap();
    for _ in 0..150 {
        system.step();
    }
    let eye = Vec3::new(0.0, 0.0, 5.0);
    let records = system.records(Some(eye));
    assert_eq!(records.len() as u64, counted_alive(&system));
    let distance = |r: &ParticleGpu| Vec3::from_slice(&r.center_size[..3]).distance(eye);
    assert!(records.windows(2).all(|w| distance(&w[0]) >= distance(&w[1])), "farthest first");
    for r in &records {
        // Size and colour move together from birth to death.
        let t = (r.center_size[3] - 0.1) / 0.4;
        assert!((0.0..=1.0).contains(&t));
        assert!((r.color[0] - (1.0 - t)).abs() < 1e-4 && (r.color[3] - (1.0 - t)).abs() < 1e-4);
    }
}

#[test]
fn emitters_that_cannot_be_are_refused() {
    for bad in [
        EmitterParams { lifetime: (2.0, 1.0), ..EmitterParams::default() },
        EmitterParams { rate: 0.0, ..EmitterParams::default() },
        EmitterParams { rate: 1e7, lifetime: (10.0, 10.0), ..EmitterParams::default() },
        EmitterParams { gravity: Vec3::NAN, ..EmitterParams::default() },
    ] {
        assert!(ParticleSystem::new(bad, 0.01).is_err());
    }
}
