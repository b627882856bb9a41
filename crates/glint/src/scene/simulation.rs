//! Beginner layer: where a scene's simulations run ([`SimPath`]) and which
//! path each took in a frame ([`SimulationPaths`], part of
//! [`FrameStats`](crate::FrameStats)).

use serde::Serialize;

/// Where a simulation steps: on the CPU (the reference, and the only path
/// on GL and WebGL2), or on the GPU in the frame's simulate stage, drawn from
/// its own buffers.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SimPath {
    /// On the CPU.
    Cpu,
    /// On the GPU where the renderer computes
    /// ([`Renderer::computes`](crate::Renderer::computes)), else on the CPU.
    #[default]
    Gpu,
}

/// How many simulations of a kind ran on each path in a frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct PathCounts {
    /// Stepped on the CPU, drawn from uploaded data.
    pub cpu: u32,
    /// Stepped on the GPU, drawn from the simulation's own buffers.
    pub gpu: u32,
}

impl PathCounts {
    /// One more that took `path`.
    pub fn add(&mut self, path: SimPath) {
        match path {
            SimPath::Cpu => self.cpu += 1,
            SimPath::Gpu => self.gpu += 1,
        }
    }
}

/// Which path each of a scene's simulations took in a frame (filled in by
/// [`World::draw`](crate::World::draw); zero for frames drawn without one).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct SimulationPaths {
    /// Fish schools.
    pub schools: PathCounts,
    /// Particle emitters.
    pub emitters: PathCounts,
    /// Cloths.
    pub cloths: PathCounts,
}

impl std::fmt::Display for SimulationPaths {
    /// "school on the GPU, 2 emitters on the GPU, cloth on the CPU": each
    /// kind with any, each path with any; "none" for none.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let kinds = [
            ("school", "schools", self.schools),
            ("emitter", "emitters", self.emitters),
            ("cloth", "cloths", self.cloths),
        ];
        let mut parts = Vec::new();
        for (one, many, counts) in kinds {
            for (n, path) in [(counts.gpu, "GPU"), (counts.cpu, "CPU")] {
                match n {
                    0 => {}
                    1 => parts.push(format!("{one} on the {path}")),
                    n => parts.push(format!("{n} {many} on the {path}")),
                }
            }
        }
        match parts.is_empty() {
            true => f.write_str("none"),
            false => f.write_str(&parts.join(", ")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_paths_read_as_a_list() {
        let mut paths = SimulationPaths::default();
        assert_eq!(paths.to_string(), "none");
        paths.schools.add(SimPath::Gpu);
        paths.emitters.add(SimPath::Gpu);
        paths.emitters.add(SimPath::Gpu);
        paths.cloths.add(SimPath::Cpu);
        assert_eq!(paths.to_string(), "school on the GPU, 2 emitters on the GPU, cloth on the CPU");
    }
}
