//! A fish school as a scene describes it ([`SchoolParams`]): how many fish,
//! the box they keep to, how they steer, what they avoid and what hunts them;
//! with what one step of it costs, and the grid it is sorted into each step
//! ([`GridShape`]). `sim::school` steps it; the `.scn` `school` block reads it.

use super::Aabb;
use glam::{IVec3, UVec3, Vec3};

/// Most obstacles a school may have: the GPU school keeps them in a table of
/// this size.
pub const MAX_OBSTACLES: usize = 64;

/// Most fish a school holds.
pub const MAX_FISH: usize = 1 << 22;

/// How strongly each rule steers: accelerations per unit of each rule's
/// force (`sim::school::Forces`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Weights {
    /// Keep apart.
    pub separation: f32,
    /// Swim the way the neighbours swim.
    pub alignment: f32,
    /// Swim to the neighbours' middle.
    pub cohesion: f32,
    /// Stay inside the bounds.
    pub bounds: f32,
    /// Keep off obstacles and the floor.
    pub avoid: f32,
    /// Flee the predator.
    pub flee: f32,
}

impl Default for Weights {
    fn default() -> Self {
        Self { separation: 1.5, alignment: 1.0, cohesion: 0.6, bounds: 8.0, avoid: 12.0, flee: 20.0 }
    }
}

/// A sphere fish swim around.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Obstacle {
    /// Its centre.
    pub center: Vec3,
    /// Its radius.
    pub radius: f32,
}

/// The predator: it swims at `speed` towards the nearest fish, and fish
/// closer than `fear` flee it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hunter {
    /// Where it starts.
    pub start: Vec3,
    /// Its cruising speed, world units a second.
    pub speed: f32,
    /// How fast it turns: the most its velocity changes a second.
    pub accel: f32,
    /// Fish closer than this flee.
    pub fear: f32,
}

/// Everything a school is made from.
#[derive(Clone, Debug, PartialEq)]
pub struct SchoolParams {
    /// How many fish.
    pub count: usize,
    /// The box the fish stay in.
    pub bounds: Aabb,
    /// How far a fish sees its neighbours (also the margin the bounds,
    /// obstacles and floor push within).
    pub radius: f32,
    /// The view cone's whole angle, degrees (360: all round).
    pub view_angle: f32,
    /// The rules' weights.
    pub weights: Weights,
    /// Slowest a fish swims.
    pub min_speed: f32,
    /// Fastest a fish swims.
    pub max_speed: f32,
    /// The most a fish's velocity changes a second.
    pub max_accel: f32,
    /// Spheres to swim around.
    pub obstacles: Vec<Obstacle>,
    /// A floor height to keep above, if any.
    pub floor: Option<f32>,
    /// The predator, if any.
    pub predator: Option<Hunter>,
    /// Tail beats a second at top speed (fewer when slower).
    pub beat_rate: f32,
    /// Start the fish in this many balls of this radius at random places
    /// (schools already), instead of spread through the bounds.
    pub clusters: Option<(u32, f32)>,
    /// The random start's seed.
    pub seed: u64,
}

impl Default for SchoolParams {
    fn default() -> Self {
        Self {
            count: 1000,
            bounds: Aabb { min: Vec3::splat(-10.0), max: Vec3::splat(10.0) },
            radius: 1.5,
            view_angle: 270.0,
            weights: Weights::default(),
            min_speed: 1.0,
            max_speed: 3.0,
            max_accel: 12.0,
            obstacles: Vec::new(),
            floor: None,
            predator: None,
            beat_rate: 3.0,
            clusters: None,
            seed: 1,
        }
    }
}

impl SchoolParams {
    /// The distance within which the bounds, obstacles and floor push.
    pub fn margin(&self) -> f32 {
        self.radius
    }

    /// The cosine of half the view angle (−1: sees all round).
    pub(crate) fn cos_half_view(&self) -> f32 {
        if self.view_angle >= 360.0 {
            -1.0
        } else {
            (self.view_angle.to_radians() * 0.5).cos()
        }
    }

    /// The grid a school of `fish` fish sorts them into each step.
    pub fn grid_shape(&self, fish: usize) -> GridShape {
        let most = MAX_GRID_CELLS.min((2 * fish).min(u32::MAX as usize / 2) as u32 + 4096);
        GridShape::new(self.bounds, self.radius, most)
    }

    /// What one step of this school counts as in a pose's budget, in
    /// neighbour tests: each fish's tests at the density it starts with (its
    /// fish over the bounds, or over their balls with `clusters`; at most
    /// [`MAX_NEIGHBOUR_TESTS`]) and [`FISH_STEP_TESTS`] for its own rules,
    /// plus one for each cell of the grid it sorts the fish into. A school
    /// that gathers tighter than it starts costs more, up to
    /// [`MAX_NEIGHBOUR_TESTS`] a fish.
    pub fn step_cost(&self) -> u64 {
        let shape = self.grid_shape(self.count);
        let extent = (self.bounds.max - self.bounds.min).max(Vec3::splat(1e-6));
        let mut volume = f64::from(extent.x) * f64::from(extent.y) * f64::from(extent.z);
        if let Some((n, r)) = self.clusters {
            let balls = f64::from(n) * 4.0 / 3.0 * std::f64::consts::PI * f64::from(r).powi(3);
            volume = volume.min(balls.max(1e-9));
        }
        let around = 27.0 * f64::from(shape.cell).powi(3) * self.count as f64 / volume;
        let tests = around.ceil().min(f64::from(MAX_NEIGHBOUR_TESTS)).min(self.count as f64) as u64;
        (self.count as u64).saturating_mul(tests + FISH_STEP_TESTS).saturating_add(u64::from(shape.cells()))
    }

    /// Why these parameters cannot make a school, if they cannot.
    pub fn check(&self) -> Result<(), String> {
        let finite = |v: Vec3| v.is_finite();
        if self.count == 0 || self.count > MAX_FISH {
            return Err(format!("count must be 1 to {MAX_FISH}, got {}", self.count));
        }
        let b = self.bounds;
        if !finite(b.min) || !finite(b.max) || b.min.cmpge(b.max).any() {
            return Err("bounds must be finite with min below max on every axis".into());
        }
        if !(self.radius.is_finite() && self.radius > 0.0) {
            return Err(format!("radius must be positive, got {}", self.radius));
        }
        if !(self.view_angle > 0.0 && self.view_angle <= 360.0) {
            return Err(format!("view angle must be in (0, 360] degrees, got {}", self.view_angle));
        }
        let speeds = self.min_speed >= 0.0 && self.min_speed <= self.max_speed && self.max_speed.is_finite();
        if !speeds || self.max_speed <= 0.0 {
            return Err(format!(
                "speeds must satisfy 0 <= min <= max, max > 0, got {} {}",
                self.min_speed, self.max_speed
            ));
        }
        let w = self.weights;
        let weights = [w.separation, w.alignment, w.cohesion, w.bounds, w.avoid, w.flee];
        if weights.iter().any(|w| !w.is_finite() || *w < 0.0) || !(self.max_accel.is_finite() && self.max_accel > 0.0) {
            return Err("weights must be finite and non-negative, and the acceleration positive".into());
        }
        if self.obstacles.iter().any(|o| !(finite(o.center) && o.radius.is_finite() && o.radius > 0.0)) {
            return Err("obstacles need a finite centre and a positive radius".into());
        }
        if self.floor.is_some_and(|f| !f.is_finite()) || !(self.beat_rate.is_finite() && self.beat_rate >= 0.0) {
            return Err("the floor and beat rate must be finite".into());
        }
        if self.clusters.is_some_and(|(n, r)| n == 0 || !(r.is_finite() && r > 0.0)) {
            return Err("clusters need a count of 1 or more and a positive radius".into());
        }
        if let Some(h) = self.predator {
            let ok = finite(h.start) && [h.speed, h.accel, h.fear].iter().all(|x| x.is_finite() && *x > 0.0);
            if !ok {
                return Err("the predator needs a finite start and positive speed, turn and fear radius".into());
            }
        }
        Ok(())
    }
}

/// Most other fish one fish tests as neighbours in a step: where more lie in
/// the 27 cells around it, it tests an even sample of them (on the CPU and
/// the GPU alike). Schools of the documented density see about 50; forty
/// thousand fish in a 2-unit box took 13 s a step testing every pair.
pub const MAX_NEIGHBOUR_TESTS: u32 = 512;

/// A fish's own work in a step (its rules, speed limits, confinement and its
/// place in the grid), counted as this many neighbour tests
/// ([`SchoolParams::step_cost`]). Measured in release on 2 cores, a test
/// costs about 3 ns so counted: 40,000 fish at the documented density step in
/// 13.7 ms (4.4·10⁶ tests), 40,000 in a 2-unit box in 76 ms (2.3·10⁷).
pub const FISH_STEP_TESTS: u64 = 64;

/// Most cells a school's grid has: wider cells beyond that (the counting
/// sort's running sum is over cells, and the GPU's scan covers 2²⁰ entries,
/// one past the last cell: `sim::scan` checks that it does).
pub const MAX_GRID_CELLS: u32 = (1 << 20) - 1;

/// The grid's shape: where it starts, its cell width and its cells per axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridShape {
    /// The corner of cell (0, 0, 0): the bounds' smallest corner less one cell.
    pub origin: Vec3,
    /// Cell width, at least the view radius.
    pub cell: f32,
    /// Cells along x, y and z.
    pub dims: UVec3,
}

impl GridShape {
    /// The grid over `bounds` (plus one cell each side) whose cells are
    /// `radius` wide, or wider where that would take more than `max_cells`.
    pub fn new(bounds: Aabb, radius: f32, max_cells: u32) -> Self {
        let extent = (bounds.max - bounds.min).max(Vec3::ZERO);
        let mut cell = radius.max(1e-3);
        loop {
            let dims = (extent / cell).ceil().as_uvec3().max(UVec3::ONE) + 2;
            let cells = dims.x as u64 * dims.y as u64 * dims.z as u64;
            if cells <= max_cells.max(27) as u64 {
                return Self { origin: bounds.min - cell, cell, dims };
            }
            cell *= 1.25;
        }
    }

    /// How many cells.
    pub fn cells(&self) -> u32 {
        self.dims.x * self.dims.y * self.dims.z
    }

    /// The cell (x, y, z) holding `p`, border cells for points outside.
    pub fn coords(&self, p: Vec3) -> IVec3 {
        let c = ((p - self.origin) / self.cell).floor();
        // NaN clamps to the first cell too.
        let c = c.max(Vec3::ZERO).min((self.dims - 1).as_vec3());
        c.as_ivec3()
    }

    /// The index of cell `c`, x fastest.
    pub fn index(&self, c: IVec3) -> u32 {
        (c.x as u32) + self.dims.x * ((c.y as u32) + self.dims.y * (c.z as u32))
    }
}
