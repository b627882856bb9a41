//! Core layer: the frame as the GPU receives it, for people
//! ([`Renderer::set_explaining`](crate::Renderer::set_explaining), `glint explain`). While explaining, every
//! pass the frame records (compute and render, in encoding order) and every
//! draw call in it is written down: the command, what it draws (each batch's
//! sort key decoded into its queue, pipeline variant and the shader features
//! in it, texture set, material and mesh, by name), the state set before it
//! and the state it kept, and its draws, instances and triangles. The list is
//! built where the calls are recorded, so it is the frame, not a model of it:
//! its draw calls and draws add up to [`FrameStats`](crate::render::FrameStats)'.

use crate::render::gpu_driven::commands::Run;
use crate::render::gpu_driven::draw_list::DrawList;
use crate::render::queue::{decode_key, Queue};
use crate::render::resources::registry::Registry;
use crate::shader::ShaderFeatures;
use serde::Serialize;
use std::sync::Mutex;

/// Every pass of one frame, in the order encoded.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct FrameCalls {
    /// The passes, compute and render, in encoding order.
    pub passes: Vec<PassCalls>,
}

impl FrameCalls {
    /// The passes of view `view` (its place in the frame's list) and the
    /// frame's own passes.
    pub fn of_view(&self, view: usize) -> Vec<&PassCalls> {
        self.passes.iter().filter(|p| p.view().is_none_or(|v| v == view)).collect()
    }

    /// Draw calls in render passes of `kind` whose group is in view `view`'s
    /// forward pass or post chain (what [`FrameStats::draw_calls`](crate::render::FrameStats::draw_calls) counts).
    pub fn draw_calls(&self, view: usize, shadow: bool) -> impl Iterator<Item = &DrawCall> {
        self.of_view(view).into_iter().filter(move |p| p.is_shadow() == shadow).flat_map(|p| &p.draw_calls)
    }
}

/// Whether a pass runs compute shaders or draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum PassType {
    /// Compute dispatches (culling, a depth pyramid, simulations).
    Compute,
    /// A render pass.
    Render,
}

/// One pass and its draw calls.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PassCalls {
    /// The pass's label ("forward pass", "light 0 cascade 1", "cull instances").
    pub name: String,
    /// Compute or render.
    pub kind: PassType,
    /// The debug group it was recorded in ("frame 3 › view 1 › forward").
    pub group: String,
    /// State bound when the pass begins, before its first call.
    pub bound: Vec<String>,
    /// Its draw calls, in encoding order (none in a compute pass).
    pub draw_calls: Vec<DrawCall>,
}

impl PassCalls {
    /// The view whose pass this is, from its group ("… › view 2 › …"); `None`
    /// for the frame's own passes and frames of one view.
    pub fn view(&self) -> Option<usize> {
        self.group.split(" › ").find_map(|g| g.strip_prefix("view ")).and_then(|k| k.parse().ok())
    }

    /// Whether it draws a shadow map.
    pub fn is_shadow(&self) -> bool {
        self.group.split(" › ").any(|g| g == "shadows")
    }
}

/// One draw call.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DrawCall {
    /// The wgpu command: `multi_draw_indexed_indirect`, `multi_draw_indexed_indirect_count`,
    /// `draw_indexed` or `draw`.
    pub command: &'static str,
    /// What it draws: "batches", "sky", "glare", "particles", "post: bloom", ….
    pub what: String,
    /// Whether occlusion culling's late phase drew it (what became visible).
    pub late: bool,
    /// Instanced draws the GPU runs for it.
    pub draws: u32,
    /// Instances it was given (culled on the GPU: the candidates, of which
    /// the GPU draws the visible).
    pub instances: u64,
    /// Triangles of those instances.
    pub triangles: u64,
    /// State set right before it.
    pub changed: Vec<String>,
    /// State it draws with that an earlier call set.
    pub kept: Vec<String>,
    /// The batches it draws, each with its sort key decoded.
    pub batches: Vec<BatchCall>,
}

/// One batch of a draw call, its sort key decoded.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BatchCall {
    /// The sort key of its first item, as hex.
    pub key: String,
    /// The key's stage: its queue's, or the entity's `render_order`.
    pub stage: u8,
    /// "opaque", "alpha-test", "transparent", or "render_order N".
    pub queue: String,
    /// Whether the key is the blended (far to near) layout.
    pub blended: bool,
    /// The pipeline id (binned keys hold it; else the batch's).
    pub pipeline: u16,
    /// The pipeline variant's shader features (its macro set).
    pub features: Vec<String>,
    /// The texture set (binned keys only).
    pub texture_set: Option<u16>,
    /// The material id in the key (masked to its field) and its name.
    pub material: u32,
    /// The material's name.
    pub material_name: String,
    /// The shape id in the key (masked to its field).
    pub mesh: u32,
    /// The mesh's name.
    pub mesh_name: String,
    /// View depth over the far plane, as the key holds it.
    pub depth: f32,
    /// Its level of detail (0: full detail) and that level's triangles.
    pub level: u8,
    /// Triangles of one instance at that level.
    pub level_triangles: u32,
    /// Instances (culled on the GPU: the candidates, of which the GPU draws
    /// the visible ones at the level each picks).
    pub instances: u32,
    /// Triangles of those instances.
    pub triangles: u64,
}

/// What a draw call set before it: one bit per piece of state.
pub(crate) mod state {
    pub const STENCIL: u8 = 1;
    pub const PIPELINE: u8 = 2;
    pub const TEXTURES: u8 = 4;
    pub const VERTICES: u8 = 8;
    /// Each bit's name, in the order set.
    pub const NAMES: [(u8, &str); 4] = [
        (STENCIL, "stencil reference"),
        (PIPELINE, "pipeline"),
        (TEXTURES, "bind group 2 (texture set)"),
        (VERTICES, "vertex and index buffers (mesh page)"),
    ];
}

/// The frame being written down, while explaining.
#[derive(Default)]
pub(crate) struct Tape(Mutex<Vec<PassCalls>>);

impl Tape {
    fn passes(&self) -> std::sync::MutexGuard<'_, Vec<PassCalls>> {
        self.0.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// Begin a pass named `name` in debug group `group`, with `bound` bound.
    pub(crate) fn pass(&self, name: &str, kind: PassType, group: &str, bound: &[&str]) {
        let (name, group) = (name.to_owned(), group.to_owned());
        let bound = bound.iter().map(|&b| b.to_owned()).collect();
        self.passes().push(PassCalls { name, kind, group, bound, draw_calls: Vec::new() });
    }

    /// Add a draw call to the pass begun last.
    pub(crate) fn call(&self, call: DrawCall) {
        if let Some(pass) = self.passes().last_mut() {
            pass.draw_calls.push(call);
        }
    }

    /// The frame written so far, leaving the tape empty.
    pub(crate) fn take(&self) -> FrameCalls {
        FrameCalls { passes: std::mem::take(&mut *self.passes()) }
    }
}

/// Split the four state bits into the names set (`changed`) and kept.
fn changed_and_kept(changed: u8, uses: u8) -> (Vec<String>, Vec<String>) {
    let names = |want: bool| {
        state::NAMES
            .iter()
            .filter(|(bit, _)| uses & bit != 0 && (changed & bit != 0) == want)
            .map(|(_, n)| (*n).to_owned())
            .collect()
    };
    (names(true), names(false))
}

/// The calls that draw `run` of `list` with `command` (in occlusion
/// culling's late phase when `late`), after setting the state bits in
/// `changed`: one multi-draw, or one `draw_indexed` per batch (each but
/// the first binding only its vertices, where the device has no base vertex).
pub(crate) fn run_calls(
    (registry, base_vertex): (&Registry, bool),
    list: &DrawList,
    run: &Run,
    (command, late): (&'static str, bool),
    changed: u8,
) -> Vec<DrawCall> {
    let batches = batch_calls(registry, list, run);
    let uses = state::STENCIL | state::PIPELINE | state::TEXTURES | state::VERTICES;
    let call = |batches: Vec<BatchCall>, changed| {
        let (changed, kept) = changed_and_kept(changed, uses);
        DrawCall {
            command,
            what: "batches".into(),
            late,
            draws: batches.len() as u32,
            instances: batches.iter().map(|b| u64::from(b.instances)).sum(),
            triangles: batches.iter().map(|b| b.triangles).sum(),
            changed,
            kept,
            batches,
        }
    };
    if command != "draw_indexed" {
        return vec![call(batches, changed)];
    }
    let later = if base_vertex { 0 } else { state::VERTICES };
    batches.into_iter().enumerate().map(|(k, b)| call(vec![b], if k == 0 { changed } else { later })).collect()
}

/// The batches of `run`, their keys decoded.
fn batch_calls(registry: &Registry, list: &DrawList, run: &Run) -> Vec<BatchCall> {
    (list.batches[run.batches()].iter().zip(&list.draws[run.batches()]))
        .map(|(b, draw)| {
            let key = registry.pipelines.key_of(b.pipeline);
            let blended = key.features.contains(ShaderFeatures::ALPHA_BLEND);
            let fields = decode_key(b.key, blended);
            let shape = &registry.shapes[b.shape.0 as usize];
            let level_triangles = draw.mesh.index_count / 3;
            let triangles = u64::from(level_triangles) * u64::from(b.instance_count);
            BatchCall {
                key: format!("{:#018x}", b.key),
                stage: fields.stage,
                queue: queue_name(fields.stage),
                blended,
                pipeline: fields.pipeline.unwrap_or(b.pipeline),
                features: key.features.iter_names().map(|(n, _)| n.to_owned()).collect(),
                texture_set: fields.texture_set.or((!blended).then_some(draw.texture_set)),
                material: fields.material,
                material_name: registry.materials[b.material.0 as usize].material.name.clone(),
                mesh: fields.shape,
                mesh_name: shape.name.clone(),
                depth: fields.depth,
                level: b.level,
                level_triangles,
                instances: b.instance_count,
                triangles,
            }
        })
        .collect()
}

impl DrawCall {
    /// A call that draws no batch ("sky", "particles", "post: bloom"): one
    /// draw of `instances` making `triangles`, after setting `changed`.
    pub(crate) fn single(
        what: &str,
        command: &'static str,
        (instances, triangles): (u64, u64),
        changed: &[&str],
    ) -> Self {
        DrawCall {
            command,
            what: what.to_owned(),
            late: false,
            draws: 1,
            instances,
            triangles,
            changed: changed.iter().map(|&c| c.to_owned()).collect(),
            kept: Vec::new(),
            batches: Vec::new(),
        }
    }
}

/// A stage's name: its queue's, or the render order that put it there.
pub(crate) fn queue_name(stage: u8) -> String {
    match stage {
        s if s == Queue::Opaque.stage() => "opaque".into(),
        s if s == Queue::AlphaTest.stage() => "alpha-test".into(),
        s if s == Queue::Transparent.stage() => "transparent".into(),
        s => format!("render_order {s}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn changed_and_kept_split_the_state_a_call_uses() {
        let uses = state::PIPELINE | state::TEXTURES | state::VERTICES;
        let (changed, kept) = changed_and_kept(state::TEXTURES | state::STENCIL, uses);
        assert_eq!(changed, ["bind group 2 (texture set)"]);
        assert_eq!(kept, ["pipeline", "vertex and index buffers (mesh page)"]);
    }

    #[test]
    fn passes_know_their_view_and_whether_they_draw_shadows() {
        let pass = |group: &str| PassCalls {
            name: "p".into(),
            kind: PassType::Render,
            group: group.into(),
            bound: Vec::new(),
            draw_calls: Vec::new(),
        };
        assert_eq!(pass("frame 3 › view 12 › shadows").view(), Some(12));
        assert!(pass("frame 3 › view 12 › shadows").is_shadow());
        assert_eq!(pass("frame 3 › forward").view(), None);
        assert!(!pass("frame 3 › forward").is_shadow());
    }
}
