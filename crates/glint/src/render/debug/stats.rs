//! Core layer: [`FrameStats`], the cost of one frame in numbers.

use crate::render::debug::timer::GpuTimes;
use crate::scene::levels::MAX_LEVELS;
use crate::scene::Culling;
use serde::Serialize;
use web_time::Instant;

/// Bytes written to the GPU during a frame, per shader data block and kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct UploadStats {
    /// Scene block (`@group(0)`): environment and lights.
    pub scene: u64,
    /// Camera block (`@group(1)`).
    pub camera: u64,
    /// Material block (`@group(2)`): entries of the material table.
    pub material: u64,
    /// Renderer block (`@group(3)`): instances (transform and material) that changed.
    pub instances: u64,
    /// The world boxes of the instances that changed, where views cull on the GPU.
    pub bounds: u64,
    /// Renderer block (`@group(3)`): the visible instance indices in draw order,
    /// when they differ from the last frame's.
    pub draw_indices: u64,
    /// Indirect draw commands, when they differ from the last frame's.
    pub indirect: u64,
    /// Texture pixels (mip levels are made on the GPU, so only level 0 counts).
    pub textures: u64,
    /// Vertex and index buffers of shapes used for the first time.
    pub meshes: u64,
    /// The view's light clusters (`@group(0)`): its point and spot lights'
    /// records and its cluster words, when they changed.
    pub lights: u64,
    /// Scene + camera + material blocks.
    pub uniforms: u64,
    /// Everything.
    pub total: u64,
}

impl UploadStats {
    /// Fill in the sums from the per-block counts.
    pub(crate) fn finish(&mut self) {
        self.uniforms = self.scene + self.camera + self.material;
        self.total = self.uniforms
            + self.instances
            + self.bounds
            + self.draw_indices
            + self.indirect
            + self.textures
            + self.meshes
            + self.lights;
    }
}

/// CPU time of each frame stage, in milliseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct StageTimes {
    /// GPU twins of new shapes, textures, materials and pipelines; edited materials.
    pub prepare: f64,
    /// Frustum culling of entities and instances.
    pub cull: f64,
    /// Building draw items with sort keys.
    pub queue: f64,
    /// Radix-sorting the draw items.
    pub sort: f64,
    /// Binning point and spot lights into the view's clusters.
    pub lights: f64,
    /// Merging runs into instanced draws, packing draw indices, making indirect commands.
    pub batch: f64,
    /// Writing changed blocks, changed instances, draw indices and indirect commands.
    pub upload: f64,
    /// Recording the render pass.
    pub encode: f64,
    /// Handing the command buffer to the queue.
    pub submit: f64,
    /// The whole of `flush`.
    pub total: f64,
}

/// What a pass drew: instances, triangles, and instances at each level of
/// detail ([`crate::scene::levels`]; 0 is full detail).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct DrawnCounts {
    /// Instances drawn.
    pub instances: u64,
    /// Triangles drawn: each instance's level's.
    pub triangles: u64,
    /// Instances drawn at each level.
    pub per_level: [u64; MAX_LEVELS],
}

/// Draws and CPU time of one named pass.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct PassStats {
    /// Draw commands recorded (a multi-draw-indirect call counts one).
    pub draw_calls: u32,
    /// Instanced draws the GPU runs.
    pub draws: u32,
    /// Instances drawn.
    pub instances: u64,
    /// Triangles the shadow pass drew (from the GPU's counts where it culls,
    /// as [`FrameStats::triangles_drawn`] is); 0 for the forward passes,
    /// whose total is [`FrameStats::triangles_drawn`].
    pub triangles: u64,
    /// CPU time: for the shadow pass all of [`Renderer::shadow_pass`](crate::Renderer::shadow_pass);
    /// for the forward passes, recording their draws.
    pub cpu_ms: f64,
}

/// Exact transparency's per-pixel lists of one view's frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct ListCounts {
    /// Transparent fragments appended.
    pub appended: u64,
    /// Fragments the lists hold: beyond, fragments were dropped.
    pub held: u64,
}

/// The frame's passes, in the order they run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Passes {
    /// Every shadow view (cascades, spot lights, cube faces), culled and batched one by one.
    pub shadow: PassStats,
    /// Screen-space ambient occlusion: its depth pre-pass (the opaque and
    /// alpha-tested draws again, once a phase of occlusion culling), then its
    /// occlusion and blur passes (one draw each as fragment passes). Not in
    /// the frame's totals, as the shadow pass is not.
    pub ambient_occlusion: PassStats,
    /// Opaque materials, near to far.
    pub opaque: PassStats,
    /// Alpha-tested materials.
    pub alpha_test: PassStats,
    /// The gradient sky.
    pub sky: PassStats,
    /// Blended materials, far to near.
    pub transparent: PassStats,
    /// The view's post chain: one draw per full-screen pass (bloom takes four).
    pub post: PassStats,
}

/// A view's light clusters (`render/clusters.rs`): its grid and how its
/// point and spot lights fell into it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct ClusterStats {
    /// Tiles across and down, and depth slices.
    pub grid: [u32; 3],
    /// A tile's side, pixels.
    pub tile_pixels: u32,
    /// Point and spot lights that reach at least one cluster.
    pub lights_visible: u32,
    /// The most lights one cluster lists.
    pub max_per_cluster: u32,
    /// Lights a cluster lists, on average.
    pub mean_per_cluster: f64,
    /// Clusters with no light.
    pub empty: u32,
    /// Cluster entries left out: lights past
    /// [`MAX_CLUSTER_LIGHTS`](crate::render::clusters::MAX_CLUSTER_LIGHTS) in a
    /// cluster (not drawn there).
    pub overflow: u32,
    /// Whether the GPU binned them (the counts are then a frame or two old,
    /// and 0 until the first come back; `Renderer::wait_for_counts` waits for them).
    pub on_gpu: bool,
}

impl ClusterStats {
    /// A grid's stats before its counts: its size, tiles and where it was binned.
    pub(crate) fn of_grid(grid: &crate::render::clusters::ClusterGrid, on_gpu: bool) -> Self {
        Self {
            grid: [grid.tiles[0], grid.tiles[1], grid.slices],
            tile_pixels: grid.tile_pixels,
            on_gpu,
            ..Self::default()
        }
    }

    /// The stats of clusters binned on the CPU.
    pub(crate) fn of(clusters: &crate::render::clusters::LightClusters) -> Self {
        let counts = clusters.ranges.iter().map(|r| r[1]);
        Self {
            lights_visible: clusters.visible,
            max_per_cluster: counts.clone().max().unwrap_or(0),
            mean_per_cluster: clusters.indices.len() as f64 / clusters.grid.clusters() as f64,
            empty: counts.filter(|&c| c == 0).count() as u32,
            overflow: clusters.overflow,
            ..Self::of_grid(&clusters.grid, false)
        }
    }
}

/// What one view of a frame cost: one per view of
/// [`Renderer::render_frame`](crate::Renderer::render_frame), or the one of
/// [`Renderer::flush`](crate::Renderer::flush).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct FrameStats {
    /// The frame's number: the renderer's frames counted from 0 (every view of
    /// a frame has the same).
    pub frame: u64,
    /// Draw commands recorded into the pass: a multi-draw-indirect call counts
    /// one however many draws it holds; the sky counts one.
    pub draw_calls: u32,
    /// Instanced draws the GPU runs: one per batch (each command of a
    /// multi-draw-indirect call), plus the sky.
    pub draws: u32,
    /// With occlusion culling, the late phase's draw calls (one per run of
    /// batches, drawing what became visible), besides `draw_calls`.
    pub late_draw_calls: u32,
    /// `set_pipeline` calls.
    pub pipelines_bound: u32,
    /// Pipelines compiled during this frame (0 in steady state).
    pub pipelines_compiled: u32,
    /// Queue submissions since the previous frame: the frame's own (its shadow
    /// pass, forward pass and post chain go in one) plus any made to upload a
    /// new texture's mip levels or grow a mesh page.
    pub submits: u32,
    /// `set_bind_group` calls.
    pub bind_groups_set: u32,
    /// Bytes written to the GPU, per block and kind.
    pub bytes_uploaded: UploadStats,
    /// Entities submitted since the last flush.
    pub entities_submitted: u32,
    /// Instances submitted since the last flush.
    pub instances_submitted: u64,
    /// Instances outside the view frustum (culled on the GPU: counted there,
    /// as [`instances_drawn`](Self::instances_drawn) is).
    pub instances_culled: u64,
    /// Instances skipped because their transform has NaN or infinity.
    pub instances_invalid: u64,
    /// Bytes the submitted entities' instance records take on the GPU: 64 an
    /// instance or joint, 16 a compact instance
    /// ([`Entity::with_compact_instances`](crate::Entity::with_compact_instances)).
    pub instance_bytes: u64,
    /// Tiles of tiled entities ([`Tiles`](crate::Tiles)) whose box this view
    /// tested against its frustum (an entity wholly inside or outside tests none).
    pub tiles_tested: u64,
    /// Tiles of which this view draws any instance (culled on the GPU: sent to
    /// the GPU's test, which keeps or culls a tile whole).
    pub tiles_drawn: u64,
    /// Instances drawn. Culled on the GPU, the count of the newest earlier
    /// frame of this view whose count came back (a frame or two before; read
    /// without waiting), plus the blended instances culled on the CPU; 0 until
    /// the first comes back.
    pub instances_drawn: u64,
    /// Triangles drawn: each instance's level of detail's (counted where
    /// [`instances_drawn`](Self::instances_drawn) is).
    pub triangles_drawn: u64,
    /// Instances drawn at each level of detail, full detail first (counted
    /// where [`instances_drawn`](Self::instances_drawn) is).
    pub instances_per_level: [u64; MAX_LEVELS],
    /// Particle billboards this view drew (every record of every particle
    /// layer written from the CPU; a layer written on the GPU counts its whole
    /// pool, dead slots drawing nothing).
    pub particles_drawn: u32,
    /// Particles alive in the scene's emitters at this frame's time, from
    /// their schedules (filled in by [`World::draw`](crate::World::draw)).
    pub particles_alive: u64,
    /// Particles the scene's emitters spawned since the previous frame's time.
    pub particles_spawned: u64,
    /// Where the scene's simulations stepped this frame (filled in by
    /// [`World::draw`](crate::World::draw)).
    pub simulations: crate::scene::SimulationPaths,
    /// How the view was culled: [`Culling::Gpu`] only where the device can
    /// (else [`Culling::Cpu`], whatever the view asked for).
    pub culling: Culling,
    /// Whether it was occlusion-culled too (two phases with a depth pyramid:
    /// culled on the GPU where the device has storage textures).
    pub occlusion: bool,
    /// How its blended materials were drawn: [`Transparency::Sorted`]
    /// where the view asked so, where nothing it drew had a twin for the
    /// way it asked for, or where the device cannot draw weighted
    /// (`render/passes/transparency.rs`).
    pub transparency: crate::scene::Transparency,
    /// Exact transparency's fragments this frame, where the view drew them
    /// ([`Renderer::wait_for_counts`](crate::Renderer::wait_for_counts) reads them back).
    pub transparent_fragments: Option<ListCounts>,
    /// CPU time per stage.
    pub cpu_ms: StageTimes,
    /// Shadow views drawn by this frame's shadow pass.
    pub shadow_views: u32,
    /// The view's light clusters, where its point and spot lights were
    /// clustered ([`Clusters`](crate::render::Clusters)).
    pub light_clusters: Option<ClusterStats>,
    /// Whether this frame prefiltered its environment (image-based lighting):
    /// the first frame with it, and after the environment or the sky it bakes changed.
    pub environment_prefiltered: bool,
    /// Draws and time per pass (the totals above are the forward passes').
    pub passes: Passes,
    /// GPU time per pass of the newest earlier frame the GPU has finished
    /// (its [`GpuTimes::frame`] says which; usually one or two before this
    /// one), read without waiting. `None` until timing is on
    /// ([`Renderer::enable_gpu_timing`](crate::Renderer::enable_gpu_timing))
    /// and a timed frame has come back, or where the device has no timestamp queries.
    pub gpu: Option<GpuTimes>,
}

impl FrameStats {
    /// Take the instances, triangles and levels the view drew from `drawn`.
    pub(crate) fn set_drawn(&mut self, drawn: DrawnCounts) {
        (self.instances_drawn, self.triangles_drawn, self.instances_per_level) =
            (drawn.instances, drawn.triangles, drawn.per_level);
    }

    /// How the view was culled, for a status line: "culled on the GPU, with
    /// occlusion", or as [`Culling::describe`] says.
    pub fn culled(&self) -> &'static str {
        match self.occlusion {
            true => "culled on the GPU, with occlusion",
            false => self.culling.describe(),
        }
    }
}

/// Milliseconds since `t`.
pub(crate) fn ms_since(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// The CPU time of consecutive stages: each [`Laps::next`] is the time since
/// the last (or since [`Laps::start`]), in milliseconds.
pub(crate) struct Laps(Instant);

impl Laps {
    pub(crate) fn start() -> Self {
        Self(Instant::now())
    }

    pub(crate) fn next(&mut self) -> f64 {
        ms_since(std::mem::replace(&mut self.0, Instant::now()))
    }
}
