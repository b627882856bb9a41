//! An emitter as a scene describes it ([`EmitterParams`]): where particles
//! start, how many, how long they live, the forces on them and how they look.
//! `sim::particles` steps them; the `.scn` `emitter` block reads them.

use glam::{Vec3, Vec4};

/// Most particles one emitter may have alive at once: their records, 32 bytes
/// each, fill 128 MiB, the storage binding every adapter has (one emitter is
/// one GPU layer).
pub const MAX_PARTICLES: u32 = 1 << 22;

/// Where particles start.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SpawnShape {
    /// At the origin.
    Point,
    /// Anywhere inside a ball of this radius.
    Sphere(f32),
    /// Anywhere inside a box of these half extents.
    Box(Vec3),
    /// On a disc of this radius across the direction, each particle's
    /// direction tilted outwards by up to the spread the further out it starts.
    Cone(f32),
}

/// A one-off or repeating burst.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Burst {
    /// Particles in each burst.
    pub count: u32,
    /// Seconds between bursts (0: one burst, at time 0).
    pub every: f32,
}

/// Everything an emitter is made from.
#[derive(Clone, Debug, PartialEq)]
pub struct EmitterParams {
    /// Where it emits from.
    pub origin: Vec3,
    /// The way particles leave (normalised when used).
    pub direction: Vec3,
    /// Particles a second, steadily.
    pub rate: f32,
    /// Particles at once, at time 0 and every so often.
    pub burst: Burst,
    /// Shortest and longest life, seconds (each particle's drawn between).
    pub lifetime: (f32, f32),
    /// Where they start.
    pub shape: SpawnShape,
    /// Slowest and fastest start speed.
    pub speed: (f32, f32),
    /// Degrees the start direction strays from `direction` at most (180: any way).
    pub spread: f32,
    /// Acceleration, world units a second².
    pub gravity: Vec3,
    /// Drag: velocity falls by e^(−drag·t).
    pub drag: f32,
    /// Strength of the swirling noise force.
    pub noise: f32,
    /// Size of the noise's swirls, world units.
    pub noise_scale: f32,
    /// Colour (linear RGB, alpha) at birth.
    pub color: Vec4,
    /// Colour at death.
    pub color_end: Vec4,
    /// Billboard size at birth, world units.
    pub size: f32,
    /// Size at death.
    pub size_end: f32,
    /// A ground plane at this height, and how much of their speed they keep
    /// bouncing off it.
    pub ground: Option<(f32, f32)>,
    /// The hash's seed: the same seed spawns the same particles.
    pub seed: u32,
}

impl Default for EmitterParams {
    fn default() -> Self {
        Self {
            origin: Vec3::ZERO,
            direction: Vec3::Y,
            rate: 100.0,
            burst: Burst { count: 0, every: 0.0 },
            lifetime: (2.0, 2.0),
            shape: SpawnShape::Point,
            speed: (1.0, 1.0),
            spread: 15.0,
            gravity: Vec3::ZERO,
            drag: 0.0,
            noise: 0.0,
            noise_scale: 1.0,
            color: Vec4::ONE,
            color_end: Vec4::new(1.0, 1.0, 1.0, 0.0),
            size: 0.1,
            size_end: 0.1,
            ground: None,
            seed: 1,
        }
    }
}

impl EmitterParams {
    /// Why these parameters cannot make an emitter, if they cannot.
    pub fn check(&self) -> Result<(), String> {
        let positive = |x: f32| x.is_finite() && x > 0.0;
        let (lo, hi) = self.lifetime;
        if !(positive(lo) && positive(hi) && lo <= hi) {
            return Err(format!("lifetime must be min max with 0 < min <= max, got {lo} {hi}"));
        }
        if !(self.rate.is_finite() && self.rate >= 0.0 && self.burst.every.is_finite() && self.burst.every >= 0.0) {
            return Err("rate and burst period must be 0 or more".into());
        }
        if self.rate == 0.0 && self.burst.count == 0 {
            return Err("an emitter needs a rate or a burst".into());
        }
        let slots = self.slots();
        if slots > u64::from(MAX_PARTICLES) {
            return Err(format!(
                "rate × lifetime and bursts make {slots} particles alive at once, more than {MAX_PARTICLES}"
            ));
        }
        let vectors = [self.origin, self.direction, self.gravity];
        let numbers = [
            self.speed.0,
            self.speed.1,
            self.spread,
            self.drag,
            self.noise,
            self.noise_scale,
            self.size,
            self.size_end,
        ];
        if vectors.iter().any(|v| !v.is_finite()) || numbers.iter().any(|x| !x.is_finite() || *x < 0.0) {
            return Err(
                "origin, direction and gravity must be finite; speeds, spread, drag, noise and sizes 0 or more".into(),
            );
        }
        Ok(())
    }

    /// The pool's slots of the steady stream (as many particles as can be
    /// alive at once, plus one) and the bursts that can be alive at once:
    /// particle k of the stream takes slot k mod the first, burst particles
    /// the slots after those.
    pub fn slot_counts(&self) -> (u32, u32) {
        let life_max = self.lifetime.1.max(self.lifetime.0);
        let rate = f64::from(self.rate.max(0.0));
        let stream =
            if rate > 0.0 { (rate * f64::from(life_max)).ceil().min(f64::from(u32::MAX - 1)) as u32 + 1 } else { 0 };
        let every = f64::from(self.burst.every.max(0.0));
        let bursts_alive = match (self.burst.count, every > 0.0) {
            (0, _) => 0,
            (_, false) => 1,
            (_, true) => (f64::from(life_max) / every).ceil().min(1e6) as u32 + 1,
        };
        (stream, bursts_alive)
    }

    /// Slots in all: the most particles alive at once (and a few more), not
    /// checked against any limit.
    pub fn slots(&self) -> u64 {
        let (stream, bursts_alive) = self.slot_counts();
        u64::from(stream) + u64::from(self.burst.count) * u64::from(bursts_alive)
    }
}
