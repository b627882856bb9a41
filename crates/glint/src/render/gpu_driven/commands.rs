//! Core layer: the shape of a draw list's indirect commands, which the
//! GPU-driven passes share: a run of batches drawn by one call ([`Run`]),
//! a command's size, and where each entity's instances come from
//! ([`Placed`]).

/// Bytes of one indexed indirect command.
pub(crate) const COMMAND_BYTES: u64 = std::mem::size_of::<wgpu::util::DrawIndexedIndirectArgs>() as u64;

/// Batches `first .. first + len` of a list, drawn by one call, seen by `frustum`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct Run {
    pub first: u32,
    pub len: u32,
    pub frustum: u32,
    pad: u32,
}

impl Run {
    pub(crate) fn new(first: usize, len: usize, frustum: u32) -> Self {
        Self { first: first as u32, len: len as u32, frustum, pad: 0 }
    }

    /// Its batches.
    pub(crate) fn batches(&self) -> std::ops::Range<usize> {
        self.first as usize..(self.first + self.len) as usize
    }
}

/// How a submitted entity's instances reach a draw list: which of
/// [`Visible`](crate::render::frame::visible::Visible)'s lists holds them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) enum Placed {
    /// Its visible instances, listed one by one in `instances` (culled on the
    /// CPU; blended ones always, to be sorted).
    #[default]
    Listed,
    /// Runs of store instances in `ranges`, which the GPU culls.
    OnGpu,
    /// Runs of store instances in `ranges` drawn whole: a tiled entity's
    /// visible tiles, culled on the CPU.
    Whole,
    /// Runs of compact instances in `ranges` (numbered by quarter records,
    /// [`Slot::instance_base`](crate::render::resources::instances::Slot::instance_base)), drawn whole: a compact entity's visible tiles,
    /// culled on the CPU whatever the culling path.
    Compact,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shader::layout::assert_mirrors;

    #[test]
    fn a_run_mirrors_its_wgsl_struct() {
        assert_mirrors!(Run, crate::shader::CULL, "Run", [first, len, frustum, pad]);
    }
}
