//! [`Schedule`]: when each particle of an emitter spawns and which slot it
//! takes. The steady stream's particle k spawns at k / rate and takes slot
//! k mod (its slots); burst b's particle i spawns at b · every and takes a
//! slot after those. Ids: k for the stream, [`BURST`] + b · count + i for
//! bursts.

use super::EmitterParams;

/// The id bit that marks a burst particle.
pub const BURST: u32 = 1 << 31;

/// An emitter's spawn times and slots.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Schedule {
    rate: f64,
    every: f64,
    burst: u32,
    /// Slots of the steady stream: as many as can be alive at once, plus one.
    stream: u32,
    /// Bursts that can be alive at once.
    bursts_alive: u32,
    life_max: f32,
}

impl Schedule {
    /// The schedule of `params` (its slots are not checked against any limit).
    pub fn new(params: &EmitterParams) -> Self {
        let life_max = params.lifetime.1.max(params.lifetime.0);
        let (rate, every) = (f64::from(params.rate.max(0.0)), f64::from(params.burst.every.max(0.0)));
        let (stream, bursts_alive) = params.slot_counts();
        Self { rate, every, burst: params.burst.count, stream, bursts_alive, life_max }
    }

    /// Slots in all: the most particles alive at once (and a few more:
    /// [`EmitterParams::slots`]).
    pub fn slots(&self) -> u64 {
        u64::from(self.stream) + u64::from(self.burst) * u64::from(self.bursts_alive)
    }

    /// Slots of the steady stream (the burst slots follow).
    pub fn stream_slots(&self) -> u32 {
        self.stream
    }

    /// Steady particles spawned by `time` (one at time 0), and bursts fired.
    pub fn counts_at(&self, time: f32) -> (u64, u64) {
        if time < 0.0 {
            return (0, 0);
        }
        let t = f64::from(time);
        let stream = if self.rate > 0.0 { (self.rate * t + 1e-9).floor() as u64 + 1 } else { 0 };
        let bursts = match (self.burst, self.every > 0.0) {
            (0, _) => 0,
            (_, false) => 1,
            (_, true) => (t / self.every + 1e-9).floor() as u64 + 1,
        };
        (stream.min(u64::from(BURST)), bursts)
    }

    /// Particles spawned by `time`.
    pub fn spawned_at(&self, time: f32) -> u64 {
        let (stream, bursts) = self.counts_at(time);
        stream + bursts * u64::from(self.burst)
    }

    /// The particle in `slot` at `time`: the latest spawned there, alive or not.
    pub fn occupant(&self, slot: u32, time: f32) -> Option<u32> {
        let (stream, bursts) = self.counts_at(time);
        occupant(slot, (stream, bursts), (self.stream, self.burst, self.bursts_alive))
    }

    /// When particle `id` spawns, seconds.
    pub fn spawn_time(&self, id: u32) -> f32 {
        if id & BURST != 0 {
            let b = (id & !BURST) / self.burst.max(1);
            (f64::from(b) * self.every) as f32
        } else {
            (f64::from(id) / self.rate) as f32
        }
    }

    /// How many particles are alive at `time` (spawned, and younger than
    /// their life), from the schedule and each particle's drawn life alone:
    /// the same on every path.
    pub fn alive_at(&self, params: &EmitterParams, time: f32) -> u64 {
        let (stream, bursts) = self.counts_at(time);
        let lives = |id: u32| time - self.spawn_time(id) < params.life(id);
        let first = stream.saturating_sub(u64::from(self.stream));
        // Particles younger than the shortest life are alive for sure.
        let young = if self.rate > 0.0 {
            let oldest_young = ((f64::from(time) - f64::from(params.lifetime.0)) * self.rate).floor() + 1.0;
            (oldest_young.max(0.0) as u64).clamp(first, stream)
        } else {
            stream
        };
        let steady = (stream - young) + (first..young).filter(|&k| lives(k as u32)).count() as u64;
        let first_burst = bursts.saturating_sub(u64::from(self.bursts_alive));
        let burst = (first_burst..bursts)
            .flat_map(|b| (0..self.burst).map(move |i| BURST | (b as u32 * self.burst + i)))
            .filter(|&id| lives(id))
            .count() as u64;
        steady + burst
    }

    /// The longest life, seconds.
    pub fn life_max(&self) -> f32 {
        self.life_max
    }
}

/// The particle in `slot` after `stream` steady particles and `bursts`
/// bursts, with `(stream slots, burst size, bursts alive)` (the same integer
/// steps in `shader/particles_step.wgsl`).
pub fn occupant(
    slot: u32,
    (stream, bursts): (u64, u64),
    (stream_slots, burst, bursts_alive): (u32, u32, u32),
) -> Option<u32> {
    if slot < stream_slots {
        let last = stream.checked_sub(1)?;
        let slot = u64::from(slot);
        (last >= slot).then(|| (last - (last - slot) % u64::from(stream_slots)) as u32)
    } else {
        let within = slot - stream_slots;
        let (group, i) = (within / burst.max(1), within % burst.max(1));
        let last = bursts.checked_sub(1)?;
        let group = u64::from(group);
        (last >= group).then(|| {
            let b = last - (last - group) % u64::from(bursts_alive.max(1));
            BURST | (b as u32 * burst + i)
        })
    }
}
