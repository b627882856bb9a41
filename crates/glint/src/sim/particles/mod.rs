//! Particles: emitters with a rate and bursts, each particle's start drawn
//! from a hash of its number (so the CPU and GPU spawn the same particles
//! without sharing a random stream), moved by gravity, drag and a noise
//! force, bouncing off a ground plane, and drawn as camera-facing billboards
//! whose colour and size change over their life.
//!
//! A particle's number says when it spawns ([`Schedule`]) and which slot of
//! the pool it takes: number k of the steady stream takes slot
//! k mod [`Schedule::stream_slots`], and burst particles the slots after
//! those. The pool is as large as can be alive at once, so a slot's last
//! particle is dead before the next takes it: no free list, and every slot
//! updates on its own ([`ParticleSystem`] on the CPU with rayon,
//! [`GpuParticles`] with a compute shader).

mod gpu;
mod schedule;
#[cfg(test)]
mod tests;

pub use crate::scene::emitter::{Burst, EmitterParams, SpawnShape, MAX_PARTICLES};
pub use gpu::{GpuParticles, ParticleKernels};
pub use schedule::Schedule;

use crate::gpu::ParticleGpu;
use glam::Vec3;
use p3_maybe_rayon::prelude::*;

/// One particle's state in its slot (32 bytes, as the GPU keeps it too).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Particle {
    /// Where it is.
    pub position: [f32; 3],
    /// Seconds since it spawned.
    pub age: f32,
    /// How it moves.
    pub velocity: [f32; 3],
    /// The number of the particle in this slot plus one (0: none yet).
    pub id: u32,
}

/// The hash every random draw comes from: PCG's output permutation over a
/// counter (the same integer steps in `shader/particles_step.wgsl`).
pub fn hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// Draw `field` (0..8) of particle `id` under `seed`, uniform in [0, 1).
pub fn random(seed: u32, id: u32, field: u32) -> f32 {
    (hash(seed ^ hash(id.wrapping_mul(8).wrapping_add(field))) >> 8) as f32 / (1u32 << 24) as f32
}

impl EmitterParams {
    /// Particle `id` as it spawns.
    pub fn spawn(&self, id: u32) -> Particle {
        let r = |field| random(self.seed, id, field);
        let axis = self.direction.try_normalize().unwrap_or(Vec3::Y);
        let (across, other) = axis.any_orthonormal_pair();
        let disc = |radius: f32| {
            let (a, d) = (r(0) * std::f32::consts::TAU, r(1).sqrt());
            (across * a.cos() + other * a.sin()) * d * radius
        };
        let offset = match self.shape {
            SpawnShape::Point => Vec3::ZERO,
            SpawnShape::Sphere(radius) => {
                let z = r(0) * 2.0 - 1.0;
                let a = r(1) * std::f32::consts::TAU;
                let s = (1.0 - z * z).max(0.0).sqrt();
                Vec3::new(s * a.cos(), s * a.sin(), z) * r(2).cbrt() * radius
            }
            SpawnShape::Box(half) => (Vec3::new(r(0), r(1), r(2)) * 2.0 - 1.0) * half,
            SpawnShape::Cone(radius) => disc(radius),
        };
        // The direction: within `spread` of the axis (uniform over the cap);
        // from a cone, tilted outwards with the distance from its middle.
        let spread = self.spread.min(180.0).to_radians();
        let dir = match self.shape {
            SpawnShape::Cone(radius) if radius > 0.0 => {
                let out = offset / radius;
                (axis * spread.cos() + out * spread.sin()).normalize_or(axis)
            }
            _ => {
                let cos = 1.0 - r(3) * (1.0 - spread.cos());
                let sin = (1.0 - cos * cos).max(0.0).sqrt();
                let a = r(4) * std::f32::consts::TAU;
                axis * cos + (across * a.cos() + other * a.sin()) * sin
            }
        };
        let speed = self.speed.0 + (self.speed.1 - self.speed.0) * r(5);
        Particle { position: (self.origin + offset).into(), age: 0.0, velocity: (dir * speed).into(), id: id + 1 }
    }

    /// Particle `id`'s life, seconds.
    pub fn life(&self, id: u32) -> f32 {
        self.lifetime.0 + (self.lifetime.1 - self.lifetime.0) * random(self.seed, id, 6)
    }

    /// `p` moved on by `dt` seconds at scene time `time`: gravity, the noise
    /// force and drag, then the ground.
    pub fn advance(&self, p: &mut Particle, dt: f32, time: f32) {
        let (mut x, mut v) = (Vec3::from(p.position), Vec3::from(p.velocity));
        let a = self.gravity + self.noise * noise(x / self.noise_scale.max(1e-3), time);
        v = (v + a * dt) * (-self.drag * dt).exp();
        x += v * dt;
        if let Some((ground, bounce)) = self.ground {
            if x.y < ground {
                x.y = ground;
                v = Vec3::new(v.x * 0.8, -v.y * bounce, v.z * 0.8);
            }
        }
        p.position = x.into();
        p.velocity = v.into();
        p.age += dt;
    }

    /// What `p` looks like: its billboard (size 0 when dead) and colour.
    pub fn record(&self, p: &Particle) -> ParticleGpu {
        let life = self.life(p.id.wrapping_sub(1));
        if p.id == 0 || p.age >= life {
            return ParticleGpu::default();
        }
        let t = (p.age / life).clamp(0.0, 1.0);
        let size = self.size + (self.size_end - self.size) * t;
        ParticleGpu {
            center_size: Vec3::from(p.position).extend(size).into(),
            color: self.color.lerp(self.color_end, t).into(),
        }
    }
}

/// A swirling force, a sum of sines of position and time (the same in
/// `shader/particles_step.wgsl`): divergence-free enough to curl smoke and bubbles.
pub fn noise(p: Vec3, t: f32) -> Vec3 {
    Vec3::new(
        (p.y * 1.7 + t * 1.3).sin() + (p.z * 2.3 - t * 0.7).sin(),
        (p.z * 1.9 + t * 1.1).sin() + (p.x * 2.1 + t * 0.9).sin(),
        (p.x * 1.5 - t * 1.2).sin() + (p.y * 2.7 + t * 0.5).sin(),
    ) * 0.5
}

/// An emitter's particles on the CPU: one [`Particle`] a slot, updated in
/// parallel.
pub struct ParticleSystem {
    params: EmitterParams,
    schedule: Schedule,
    slots: Vec<Particle>,
    steps: u64,
    dt: f32,
}

impl ParticleSystem {
    /// An emitter at time 0 that steps `dt` seconds at a time, nothing spawned
    /// yet. Errors with [`EmitterParams::check`]'s reason.
    pub fn new(params: EmitterParams, dt: f32) -> Result<Self, String> {
        params.check()?;
        if !(dt.is_finite() && dt > 0.0) {
            return Err(format!("dt must be above 0, got {dt}"));
        }
        let schedule = Schedule::new(&params);
        let slots = vec![Particle::default(); schedule.slots() as usize];
        Ok(Self { params, schedule, slots, steps: 0, dt })
    }

    /// Its parameters.
    pub fn params(&self) -> &EmitterParams {
        &self.params
    }

    /// When and where its particles spawn.
    pub fn schedule(&self) -> &Schedule {
        &self.schedule
    }

    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Seconds since time 0.
    pub fn time(&self) -> f32 {
        (self.steps as f64 * f64::from(self.dt)) as f32
    }

    /// Every slot.
    pub fn slots(&self) -> &[Particle] {
        &self.slots
    }

    /// Go on from `slots` after `steps` steps (a simulation cache's), when
    /// they are as many as its own.
    pub fn resume(&mut self, slots: Vec<Particle>, steps: u64) -> Result<(), String> {
        if slots.len() != self.slots.len() {
            return Err(format!("{} particle slots, where the emitter has {}", slots.len(), self.slots.len()));
        }
        (self.slots, self.steps) = (slots, steps);
        Ok(())
    }

    /// One step: every slot whose particle number moved on takes its new
    /// particle (moved from its spawn time to the step's end); the others move
    /// on by `dt`.
    pub fn step(&mut self) {
        let (t0, t1) = (self.time(), ((self.steps + 1) as f64 * f64::from(self.dt)) as f32);
        let (params, schedule, dt) = (&self.params, &self.schedule, self.dt);
        self.slots.par_iter_mut().enumerate().for_each(|(slot, p)| {
            // Ages come from the schedule, so a slot is alive exactly when
            // the schedule says (no sum of steps drifting across a death).
            match schedule.occupant(slot as u32, t1) {
                Some(id) if id + 1 != p.id => {
                    *p = params.spawn(id);
                    let born = schedule.spawn_time(id);
                    params.advance(p, t1 - born, born);
                    p.age = t1 - born;
                }
                Some(id) if p.age < params.life(id) => {
                    params.advance(p, dt, t0);
                    p.age = t1 - schedule.spawn_time(id);
                }
                _ => {}
            }
        });
        self.steps += 1;
    }

    /// The billboards to draw: the living particles, back to front from
    /// `eye` when given (alpha blending), else in slot order.
    pub fn records(&self, eye: Option<Vec3>) -> Vec<ParticleGpu> {
        let mut alive: Vec<ParticleGpu> =
            self.slots.par_iter().map(|p| self.params.record(p)).filter(|r| r.center_size[3] > 0.0).collect();
        if let Some(eye) = eye {
            // Farthest first: the key is the negated squared distance.
            radsort::sort_by_key(&mut alive, |r| -Vec3::from_slice(&r.center_size[..3]).distance_squared(eye));
        }
        alive
    }
}
