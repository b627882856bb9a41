//! `glint bench --live`: the whole frame of a running scene, its simulations
//! stepping (fish schools, particles, cloth) as the viewer runs it: each frame
//! poses the world one frame later ([`World::pose`]) and draws it
//! ([`World::draw`]), and the GPU is let finish before the next.

use crate::bench::BenchConfig;
use glint::asset::SceneDesc;
use glint::{Error, Gpu, OffscreenTarget, Renderer, World};
use std::time::Instant;

/// What `--live` measures.
#[derive(serde::Serialize)]
pub struct LiveReport {
    /// Measured frames.
    pub frames: usize,
    /// Scene time of the first measured frame, seconds, and seconds a frame.
    pub start: f32,
    /// Seconds of scene time a frame.
    pub step: f32,
    /// Median wall time of a whole frame (pose, draw, GPU done), ms.
    pub frame_ms_median: f64,
    /// 95th percentile of it, ms.
    pub frame_ms_p95: f64,
    /// Median CPU time of posing (CPU simulations' steps, moved entities), ms.
    pub pose_ms_median: f64,
    /// Median CPU time of drawing (particle records, GPU simulations'
    /// recording, the renderer's frame), ms.
    pub draw_cpu_ms_median: f64,
    /// Median GPU time of the forward pass (particles included), from
    /// timestamp queries, every view's summed; null where unsupported.
    pub forward_gpu_ms_median: Option<f64>,
    /// Median GPU time of the shadow passes, every view's summed; null where
    /// unsupported or the scene draws no shadows.
    pub shadow_gpu_ms_median: Option<f64>,
    /// Shadow views the last frame drew (a cascade, a spot light, a cube
    /// face each), every view's summed.
    pub shadow_views: u32,
    /// Whether the particles stepped with compute shaders.
    pub particles_on_gpu: bool,
    /// Where the last frame's simulations stepped.
    pub simulations: glint::scene::SimulationPaths,
    /// Particles alive in the last frame.
    pub particles_alive: u64,
    /// Instances the last frame submitted.
    pub instances: u64,
    /// Whether levels of detail were on.
    pub levels_of_detail: bool,
    /// Triangles the last frame's forward passes drew, every view's summed.
    pub triangles: u64,
    /// Triangles the last frame's shadow passes drew, every view's summed.
    pub shadow_triangles: u64,
    /// The last frame's picture, to compare.
    #[serde(skip)]
    pub image: Option<image::RgbaImage>,
}

/// Levels of detail against full detail, in one run.
#[derive(serde::Serialize)]
pub struct LodComparison {
    /// How many times faster the whole frame is with levels (median over median).
    pub frame_speedup: f64,
    /// How many times fewer triangles (forward and shadow passes) it draws.
    pub triangle_ratio: f64,
    /// Mean difference of the two last frames' pictures, per channel, in 255ths.
    pub mean_difference: f64,
    /// The largest mean difference of a 4×4 block of pixels, in 255ths: where
    /// a level's change is most visible.
    pub block_difference: f64,
}

/// The comparison of `sides` (with levels, then at full detail), when both ran.
pub fn compare(sides: &[LiveReport]) -> Option<LodComparison> {
    let [with, full] = sides else { return None };
    let (a, b) = (with.image.as_ref()?, full.image.as_ref()?);
    let (mean, block) = glint::compare::mean_difference(a, b, 4)?;
    Some(LodComparison {
        frame_speedup: full.frame_ms_median / with.frame_ms_median.max(1e-9),
        triangle_ratio: (full.triangles + full.shadow_triangles) as f64
            / (with.triangles + with.shadow_triangles).max(1) as f64,
        mean_difference: mean,
        block_difference: block,
    })
}

/// The simulations as asked against every school on the CPU, in one run.
#[derive(serde::Serialize)]
pub struct SimComparison {
    /// How many times faster the whole frame is as asked (median over median).
    pub frame_speedup: f64,
    /// Median pose time as asked, ms (GPU steps are recorded in the frame instead).
    pub pose_ms: f64,
    /// Median pose time with the schools on the CPU, ms.
    pub cpu_pose_ms: f64,
}

/// `asked` (simulations where the scene or --sim says) against `cpu`.
pub fn compare_sim(asked: &LiveReport, cpu: &LiveReport) -> SimComparison {
    SimComparison {
        frame_speedup: cpu.frame_ms_median / asked.frame_ms_median.max(1e-9),
        pose_ms: asked.pose_ms_median,
        cpu_pose_ms: cpu.pose_ms_median,
    }
}

fn median(values: &mut [f64]) -> f64 {
    crate::bench::median(values).unwrap_or(0.0)
}

/// Run `desc` live from `start` seconds, `step` seconds a frame.
pub fn run(gpu: &Gpu, desc: SceneDesc, config: &BenchConfig, (start, step): (f32, f32)) -> Result<LiveReport, Error> {
    let (width, height) = config.size;
    let mut target = OffscreenTarget::new(gpu, width, height, config.msaa)?;
    let mut renderer = Renderer::new(gpu);
    renderer.set_density(config.density);
    config.lod.apply(&mut renderer);
    let timed = renderer.enable_gpu_timing();
    let mut world = World::place(desc, &mut renderer)?;
    let views = config.lod.views(world.views(None));
    let (mut frame_ms, mut pose_ms, mut draw_ms) = (Vec::new(), Vec::new(), Vec::new());
    let (mut gpu_ms, mut shadow_ms) = (Vec::new(), Vec::new());
    let (mut last, mut shadow_views) = (None, 0);
    for i in 0..config.warmup + config.frames {
        let time = start + step * (i as f32 - config.warmup as f32).max(0.0);
        let frame_start = Instant::now();
        world.pose(time, &mut renderer)?;
        let posed = frame_start.elapsed().as_secs_f64() * 1e3;
        let stats = world.draw(&mut renderer, &views, &mut target)?;
        let drawn = frame_start.elapsed().as_secs_f64() * 1e3 - posed;
        gpu.wait()?;
        let whole = frame_start.elapsed().as_secs_f64() * 1e3;
        if i >= config.warmup {
            frame_ms.push(whole);
            pose_ms.push(posed);
            draw_ms.push(drawn);
            if let Some(times) = renderer.read_gpu_times() {
                gpu_ms.push(times.forward_ms);
                shadow_ms.extend(times.shadow_ms);
            }
            shadow_views = stats.iter().map(|s| s.shadow_views).sum();
            last = stats.into_iter().last();
        }
    }
    let last = last.unwrap_or_default();
    let frame_ms_median = median(&mut frame_ms);
    // Triangles counted on the GPU come back a frame or two late: one more
    // frame of the last pose, its counts waited for.
    let mut counted = world.draw(&mut renderer, &views, &mut target)?;
    renderer.wait_for_counts(&mut counted);
    let triangles = counted.iter().fold((0, 0), |t, s| (t.0 + s.triangles_drawn, t.1 + s.passes.shadow.triangles));
    let image = target.read_rgba8(gpu).ok();
    Ok(LiveReport {
        frames: config.frames,
        start,
        step,
        frame_ms_median,
        frame_ms_p95: crate::bench::percentile(&frame_ms, 0.95),
        pose_ms_median: median(&mut pose_ms),
        draw_cpu_ms_median: median(&mut draw_ms),
        forward_gpu_ms_median: (timed && !gpu_ms.is_empty()).then(|| median(&mut gpu_ms)),
        shadow_gpu_ms_median: (timed && !shadow_ms.is_empty()).then(|| median(&mut shadow_ms)),
        shadow_views,
        particles_on_gpu: world.particles_on_gpu(),
        simulations: last.simulations,
        particles_alive: last.particles_alive,
        instances: last.instances_submitted,
        levels_of_detail: config.lod.lod == crate::lod::LodSwitch::On,
        triangles: triangles.0,
        shadow_triangles: triangles.1,
        image,
    })
}
