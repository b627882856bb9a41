//! Reynolds' steering rules for one fish, as accelerations before their
//! weights; the GPU's `shader/school.wgsl` computes the same sums. Each rule is a
//! field of [`Forces`] so tests can check it alone.

use super::{Obstacle, SchoolParams};
use glam::Vec3;

/// The steering one fish feels, rule by rule, before weighting.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Forces {
    /// Away from neighbours, each weighted by 1 / distance.
    pub separation: Vec3,
    /// Towards the neighbours' mean velocity, from its own.
    pub alignment: Vec3,
    /// Towards the neighbours' mean position.
    pub cohesion: Vec3,
    /// Back inside the bounds, growing from 0 one margin in to 1 at the wall.
    pub bounds: Vec3,
    /// Away from obstacles and the floor, likewise within one margin.
    pub avoid: Vec3,
    /// Away from the predator, from 0 at the fear radius to 1 on it.
    pub flee: Vec3,
    /// How many neighbours it saw.
    pub neighbours: u32,
}

impl Forces {
    /// The weighted sum, no longer than `max_accel`.
    pub fn acceleration(&self, p: &SchoolParams) -> Vec3 {
        let w = &p.weights;
        let a = w.separation * self.separation
            + w.alignment * self.alignment
            + w.cohesion * self.cohesion
            + w.bounds * self.bounds
            + w.avoid * self.avoid
            + w.flee * self.flee;
        a.clamp_length_max(p.max_accel)
    }
}

/// Sums over the neighbours a fish sees, built one neighbour at a time.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Seen {
    separation: Vec3,
    velocity: Vec3,
    position: Vec3,
    count: u32,
}

impl Seen {
    /// Count fish at `q` moving at `w` if fish (`p`, heading `ahead`) sees it:
    /// closer than the radius (`r2` squared) and within the view cone
    /// (`cos_half`, the cosine of half the view angle).
    #[inline]
    pub(crate) fn add(&mut self, p: Vec3, ahead: Vec3, r2: f32, cos_half: f32, q: Vec3, w: Vec3) {
        let d = q - p;
        let d2 = d.length_squared();
        if d2 >= r2 || d2 == 0.0 {
            return;
        }
        if cos_half > -1.0 && d.dot(ahead) < cos_half * d2.sqrt() {
            return;
        }
        self.separation -= d / d2.max(1e-4);
        self.velocity += w;
        self.position += q;
        self.count += 1;
    }

    /// Scale the separation by `stride`: the neighbours seen were every
    /// `stride`-th of those there, and separation is a sum over them all
    /// (alignment and cohesion are means).
    pub(crate) fn scale_separation(&mut self, stride: f32) {
        if stride != 1.0 {
            self.separation *= stride;
        }
    }

    /// The rules for a fish at `p` moving at `v`, given what it saw and the
    /// predator's position.
    pub(crate) fn forces(self, params: &SchoolParams, p: Vec3, v: Vec3, predator: Option<Vec3>) -> Forces {
        let mut f = Forces { neighbours: self.count, separation: self.separation, ..Forces::default() };
        if self.count > 0 {
            let n = self.count as f32;
            f.alignment = self.velocity / n - v;
            f.cohesion = self.position / n - p;
        }
        let m = params.margin();
        let (lo, hi) = (params.bounds.min, params.bounds.max);
        f.bounds = ((lo + m - p).max(Vec3::ZERO) - (p - (hi - m)).max(Vec3::ZERO)) / m;
        for o in &params.obstacles {
            f.avoid += push(p, o, m);
        }
        if let Some(floor) = params.floor {
            f.avoid.y += ((floor + m - p.y) / m).max(0.0);
        }
        if let (Some(q), Some(hunter)) = (predator, &params.predator) {
            let e = p - q;
            let d = e.length();
            if d < hunter.fear && d > 0.0 {
                f.flee = e / d * (1.0 - d / hunter.fear);
            }
        }
        f
    }
}

/// Away from obstacle `o` for a fish at `p`: 0 a margin `m` off its surface,
/// 1 on it.
fn push(p: Vec3, o: &Obstacle, m: f32) -> Vec3 {
    let e = p - o.center;
    let d = e.length();
    let gap = d - o.radius;
    if gap >= m || d == 0.0 {
        return Vec3::ZERO;
    }
    e / d * ((m - gap) / m).min(2.0)
}

/// Speed into the limits (a still fish keeps heading along `fallback`).
pub(crate) fn limit_speed(v: Vec3, fallback: Vec3, params: &SchoolParams) -> Vec3 {
    let s = v.length();
    let dir = if s > 1e-6 { v / s } else { fallback.try_normalize().unwrap_or(Vec3::Z) };
    dir * s.clamp(params.min_speed, params.max_speed)
}

/// Where a fish moved to `p` at velocity `v` may be: inside the bounds, out
/// of every obstacle and above the floor, the velocity's offending part
/// turned back. Obstacles go first, so the bounds always hold.
pub(crate) fn confine(mut p: Vec3, mut v: Vec3, params: &SchoolParams) -> (Vec3, Vec3) {
    for o in &params.obstacles {
        let e = p - o.center;
        let d = e.length();
        if d < o.radius {
            let n = if d > 1e-6 { e / d } else { Vec3::Y };
            p = o.center + n * o.radius;
            v -= n * v.dot(n).min(0.0);
        }
    }
    let (lo, hi) = (params.bounds.min, params.bounds.max);
    for k in 0..3 {
        if p[k] < lo[k] {
            p[k] = lo[k];
            v[k] = v[k].abs();
        } else if p[k] > hi[k] {
            p[k] = hi[k];
            v[k] = -v[k].abs();
        }
    }
    if let Some(floor) = params.floor {
        if p.y < floor {
            p.y = floor;
            v.y = v.y.abs();
        }
    }
    (p, v)
}
