//! Fish schooling after Reynolds: every fish steers by separation, alignment
//! and cohesion with the neighbours it sees (within a view radius and angle),
//! stays inside bounds, keeps off obstacles and the floor, and flees a
//! predator that hunts the nearest fish. Neighbours come from a uniform grid
//! rebuilt every step by counting sort ([`grid`]): nothing is O(n²).
//!
//! [`School`] steps on the CPU with rayon; [`GpuSchool`] steps the same rules
//! with compute shaders. Both start from [`School::new`]'s state for a seed.

mod gpu;
pub mod grid;
mod place;
mod rules;
#[cfg(test)]
mod tests;

pub use crate::scene::school::{
    Hunter, Obstacle, SchoolParams, Weights, FISH_STEP_TESTS, MAX_FISH, MAX_NEIGHBOUR_TESTS,
};
pub use gpu::{GpuSchool, MAX_GPU_OBSTACLES};
pub use place::{SchoolDrawing, Swimmers, MAX_PART_TRANSFORMS};
pub use rules::Forces;

use glam::{Mat3, Mat4, Vec3};
use grid::Grid;
pub use grid::GridShape;
use p3_maybe_rayon::prelude::*;
use rand::{Rng, SeedableRng};
use rules::{confine, limit_speed, Seen};

/// One swimmer's state.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Swimmer {
    /// Where it is.
    pub position: Vec3,
    /// How it moves, world units a second.
    pub velocity: Vec3,
    /// Its tail beat, a fraction of a cycle.
    pub phase: f32,
}

impl Swimmer {
    /// Its model matrix: placed at its position, its front (+Z) along its
    /// velocity with +Y as near up as it can be, scaled by `scale`.
    pub fn transform(&self, scale: f32) -> Mat4 {
        let z = self.velocity.try_normalize().unwrap_or(Vec3::Z);
        let x = Vec3::Y.cross(z).try_normalize().unwrap_or(Vec3::X);
        let y = z.cross(x);
        Mat4::from_scale_rotation_translation(
            Vec3::splat(scale),
            glam::Quat::from_mat3(&Mat3::from_cols(x, y, z)),
            self.position,
        )
    }

    /// Advance the tail beat by `dt` at `rate` beats a second at `top` speed
    /// (0.4 of it when still).
    fn beat(&mut self, dt: f32, rate: f32, top: f32) {
        let pace = 0.4 + 0.6 * (self.velocity.length() / top.max(1e-6)).min(1.5);
        self.phase = (self.phase + dt * rate * pace).fract();
    }
}

/// What a school looks like as a whole, to compare runs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SchoolStats {
    /// Mean speed.
    pub mean_speed: f32,
    /// Length of the mean heading: 1 when all swim one way, near 0 when random.
    pub polarisation: f32,
    /// Mean distance to the nearest other fish, capped at the view radius.
    pub nearest: f32,
    /// Mean distance to the predator (0 without one).
    pub predator_distance: f32,
}

/// A school on the CPU.
pub struct School {
    params: SchoolParams,
    fish: Vec<Swimmer>,
    predator: Option<Swimmer>,
    grid: Grid,
    /// Positions and velocities in the grid's order, rebuilt each step.
    sorted: Vec<(Vec3, Vec3)>,
    steps: u64,
}

impl School {
    /// `params.count` fish spread at random through the bounds (off the
    /// obstacles where they can be), swimming random ways at random speeds
    /// between the limits; the predator, if any, at its start. Errors with
    /// [`SchoolParams::check`]'s reason.
    pub fn new(params: SchoolParams) -> Result<Self, String> {
        params.check()?;
        let mut rng = rand_pcg::Pcg64::seed_from_u64(params.seed);
        let (lo, hi) = (params.bounds.min, params.bounds.max);
        let inset = ((hi - lo) * 0.25).min(Vec3::splat(params.margin()));
        let anywhere = |rng: &mut rand_pcg::Pcg64| {
            Vec3::new(
                rng.random_range(lo.x + inset.x..=hi.x - inset.x),
                rng.random_range(lo.y + inset.y..=hi.y - inset.y),
                rng.random_range(lo.z + inset.z..=hi.z - inset.z),
            )
        };
        let centers: Vec<Vec3> = match params.clusters {
            Some((n, _)) => (0..n).map(|_| anywhere(&mut rng)).collect(),
            None => Vec::new(),
        };
        let fish = (0..params.count)
            .map(|i| {
                let mut p = lo;
                for _ in 0..8 {
                    p = match params.clusters {
                        Some((n, radius)) => {
                            let ball = loop {
                                let v = Vec3::new(
                                    rng.random_range(-1.0..1.0),
                                    rng.random_range(-1.0..1.0),
                                    rng.random_range(-1.0..1.0),
                                );
                                if v.length_squared() <= 1.0 {
                                    break v;
                                }
                            };
                            centers[i % n as usize] + ball * radius
                        }
                        None => anywhere(&mut rng),
                    };
                    if params.obstacles.iter().all(|o| p.distance(o.center) > o.radius) {
                        break;
                    }
                }
                let dir = loop {
                    let d = Vec3::new(
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-0.3..0.3),
                        rng.random_range(-1.0..1.0),
                    );
                    if let Some(d) = d.try_normalize() {
                        break d;
                    }
                };
                let speed = rng.random_range(params.min_speed..=params.max_speed);
                let (position, velocity) = confine(p, dir * speed, &params);
                Swimmer { position, velocity, phase: rng.random_range(0.0..1.0) }
            })
            .collect();
        let predator = params.predator.map(|h| Swimmer { position: h.start, velocity: Vec3::Z * h.speed, phase: 0.0 });
        Ok(Self::from_state(params, fish, predator))
    }

    /// A school in the given state (tests build small cases by hand).
    pub fn from_state(params: SchoolParams, fish: Vec<Swimmer>, predator: Option<Swimmer>) -> Self {
        let shape = params.grid_shape(fish.len());
        Self { params, fish, predator, grid: Grid::new(shape), sorted: Vec::new(), steps: 0 }
    }

    /// Go on from `fish` and `predator` after `steps` steps (a simulation
    /// cache's), when they are as many as its own.
    pub fn resume(&mut self, fish: Vec<Swimmer>, predator: Option<Swimmer>, steps: u64) -> Result<(), String> {
        if fish.len() != self.fish.len() || predator.is_some() != self.predator.is_some() {
            return Err(format!(
                "{} fish{}, where the school has {}{}",
                fish.len(),
                if predator.is_some() { " and a predator" } else { "" },
                self.fish.len(),
                if self.predator.is_some() { " and a predator" } else { "" }
            ));
        }
        (self.fish, self.predator, self.steps) = (fish, predator, steps);
        Ok(())
    }

    /// Its parameters.
    pub fn params(&self) -> &SchoolParams {
        &self.params
    }

    /// Every fish.
    pub fn fish(&self) -> &[Swimmer] {
        &self.fish
    }

    /// The predator, if it has one.
    pub fn predator(&self) -> Option<&Swimmer> {
        self.predator.as_ref()
    }

    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// The grid's shape.
    pub fn grid_shape(&self) -> GridShape {
        self.grid.shape
    }

    fn rebuild_grid(&mut self) {
        let positions: Vec<Vec3> = self.fish.par_iter().map(|f| f.position).collect();
        self.grid.rebuild(&positions);
        let fish = &self.fish;
        self.sorted = self
            .grid
            .order
            .par_iter()
            .map(|&i| {
                let f = &fish[i as usize];
                (f.position, f.velocity)
            })
            .collect();
    }

    /// What fish `i` feels now: each rule's pull, from the neighbours the
    /// grid finds.
    pub fn forces(&mut self, i: usize) -> Forces {
        self.rebuild_grid();
        self.forces_of(&self.fish[i])
    }

    /// The rules for fish `f`, from the fish in the 27 cells around it: all
    /// of them, or where more than [`MAX_NEIGHBOUR_TESTS`] crowd there, an
    /// even sample of that many (every s-th in cell order, the separation
    /// scaled by s), so a dense ball costs a bounded number of tests a fish.
    fn forces_of(&self, f: &Swimmer) -> Forces {
        let p = &self.params;
        let (r2, cos_half) = (p.radius * p.radius, p.cos_half_view());
        let ahead = f.velocity.normalize_or_zero();
        let mut seen = Seen::default();
        let candidates: usize = self.grid.around(f.position).map(|slots| slots.len()).sum();
        let stride = candidates.div_ceil(MAX_NEIGHBOUR_TESTS as usize).max(1);
        // Candidates before this row, counted over the 27 cells in order.
        let mut before = 0;
        for slots in self.grid.around(f.position) {
            let skip = (stride - before % stride) % stride;
            before += slots.len();
            for &(q, w) in self.sorted[slots].iter().skip(skip).step_by(stride) {
                seen.add(f.position, ahead, r2, cos_half, q, w);
            }
        }
        seen.scale_separation(stride as f32);
        seen.forces(p, f.position, f.velocity, self.predator.map(|h| h.position))
    }

    /// Advance every fish and the predator by `dt` seconds, all from the
    /// state at the step's start.
    pub fn step(&mut self, dt: f32) {
        self.rebuild_grid();
        let this = &*self;
        let p = &this.params;
        let next: Vec<Swimmer> = this
            .fish
            .par_iter()
            .map(|f| {
                let a = this.forces_of(f).acceleration(p);
                let v = limit_speed(f.velocity + a * dt, f.velocity, p);
                let (position, velocity) = confine(f.position + v * dt, v, p);
                let velocity = limit_speed(velocity, v, p);
                let mut moved = Swimmer { position, velocity, phase: f.phase };
                moved.beat(dt, p.beat_rate, p.max_speed);
                moved
            })
            .collect();
        if let (Some(h), Some(hunter)) = (self.predator, self.params.predator) {
            self.predator = Some(hunt(h, hunter, &self.fish, &self.params, dt));
        }
        self.fish = next;
        self.steps += 1;
    }

    /// The school's statistics now.
    pub fn stats(&mut self) -> SchoolStats {
        self.rebuild_grid();
        let positions: Vec<Vec3> = self.fish.iter().map(|f| f.position).collect();
        let r = self.params.radius;
        let this = &*self;
        let nearest: f32 = (0..positions.len())
            .into_par_iter()
            .map(|i| {
                let p = positions[i];
                this.grid
                    .around(p)
                    .flat_map(|s| this.grid.order[s].iter())
                    .filter(|&&j| j as usize != i)
                    .map(|&j| positions[j as usize].distance(p))
                    .fold(r, f32::min)
            })
            .sum();
        stats_of(&self.fish, self.predator.map(|h| h.position), nearest)
    }
}

/// Mean speed, polarisation and predator distance of `fish`, with the sum
/// of their nearest distances.
pub(crate) fn stats_of(fish: &[Swimmer], predator: Option<Vec3>, nearest_sum: f32) -> SchoolStats {
    let n = fish.len().max(1) as f32;
    let speed: f32 = fish.iter().map(|f| f.velocity.length()).sum();
    let heading: Vec3 = fish.iter().map(|f| f.velocity.normalize_or_zero()).sum();
    let predator_distance = predator.map_or(0.0, |q| fish.iter().map(|f| f.position.distance(q)).sum::<f32>() / n);
    SchoolStats {
        mean_speed: speed / n,
        polarisation: heading.length() / n,
        nearest: nearest_sum / n,
        predator_distance,
    }
}

/// The predator after `dt`: turned towards the nearest fish (lowest number
/// on ties) at most `accel` a second, at its cruising speed, inside the bounds.
fn hunt(mut h: Swimmer, hunter: Hunter, fish: &[Swimmer], params: &SchoolParams, dt: f32) -> Swimmer {
    let nearest = fish
        .par_iter()
        .enumerate()
        .map(|(i, f)| (f.position.distance_squared(h.position), i))
        .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    if let Some((_, i)) = nearest {
        let want = (fish[i].position - h.position).normalize_or_zero() * hunter.speed;
        h.velocity += (want - h.velocity).clamp_length_max(hunter.accel * dt);
    }
    let s = h.velocity.length();
    let dir = if s > 1e-6 { h.velocity / s } else { Vec3::Z };
    let v = dir * s.clamp(hunter.speed * 0.5, hunter.speed * 1.2);
    let (position, velocity) = confine(h.position + v * dt, v, params);
    h.position = position;
    h.velocity = velocity;
    h.beat(dt, params.beat_rate * 0.5, hunter.speed);
    h
}
