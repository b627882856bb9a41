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
    /// timestamp queries; null where unsupported.
    pub forward_gpu_ms_median: Option<f64>,
    /// Whether the particles stepped with compute shaders.
    pub particles_on_gpu: bool,
    /// Particles alive in the last frame.
    pub particles_alive: u64,
    /// Instances the last frame submitted.
    pub instances: u64,
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
    let timed = renderer.enable_gpu_timing();
    let mut world = World::place(desc, &mut renderer)?;
    let views = world.views(None);
    let (mut frame_ms, mut pose_ms, mut draw_ms, mut gpu_ms) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut last = None;
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
            gpu_ms.extend(renderer.read_gpu_times().map(|t| t.forward_ms));
            last = stats.into_iter().last();
        }
    }
    let last = last.unwrap_or_default();
    let frame_ms_median = median(&mut frame_ms);
    Ok(LiveReport {
        frames: config.frames,
        start,
        step,
        frame_ms_median,
        frame_ms_p95: crate::bench::percentile(&frame_ms, 0.95),
        pose_ms_median: median(&mut pose_ms),
        draw_cpu_ms_median: median(&mut draw_ms),
        forward_gpu_ms_median: (timed && !gpu_ms.is_empty()).then(|| median(&mut gpu_ms)),
        particles_on_gpu: world.particles_on_gpu(),
        particles_alive: last.particles_alive,
        instances: last.instances_submitted,
    })
}
