//! `glint sim particles`: step an emitter holding about N living particles
//! on the CPU (or, with `--gpu`, with compute shaders) and print how long a
//! step takes, with the alpha-blended layer's back-to-front order included.

use clap::Args;
use glam::{Vec3, Vec4};
use glint::render::{GpuSimulation, ParticleBlend, ParticleGpu};
use glint::sim::particles::{EmitterParams, GpuParticles, ParticleSystem, SpawnShape};
use glint::{Error, Gpu};
use std::time::Instant;

/// Seconds each particle lives: the emitter's rate is the count over this.
const LIFE: f32 = 4.0;

/// `glint sim particles` options.
#[derive(Args)]
pub struct ParticleArgs {
    /// Particles alive once the emitter is full (1 to 4,000,000).
    #[arg(long, default_value_t = 1_000_000, value_parser = clap::value_parser!(u32).range(1..=4_000_000))]
    alive: u32,
    /// Measured steps, after the emitter has filled.
    #[arg(long, default_value_t = 30, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    steps: u32,
    /// Alpha-blended (sorted back to front every step) rather than additive.
    #[arg(long)]
    alpha: bool,
    /// Step with compute shaders instead of the CPU.
    #[arg(long)]
    gpu: bool,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

/// What it prints.
#[derive(serde::Serialize)]
struct Report {
    path: &'static str,
    blend: &'static str,
    alive: u64,
    slots: u64,
    steps: u32,
    /// Median milliseconds of a step: update and, on the CPU, the records
    /// gathered (and sorted, alpha); on the GPU, the step's passes submitted
    /// and waited for.
    ms_per_step: f64,
    ms_per_step_min: f64,
    ms_per_step_max: f64,
    threads: usize,
}

fn params(alive: u32) -> EmitterParams {
    EmitterParams {
        rate: alive as f32 / LIFE,
        lifetime: (LIFE, LIFE),
        shape: SpawnShape::Sphere(1.0),
        speed: (0.5, 2.0),
        spread: 60.0,
        gravity: Vec3::new(0.0, -1.0, 0.0),
        drag: 0.2,
        noise: 0.5,
        color_end: Vec4::new(1.0, 1.0, 1.0, 0.0),
        ground: Some((-3.0, 0.4)),
        ..EmitterParams::default()
    }
}

/// Run `glint sim particles`.
pub fn particles(args: &ParticleArgs) -> Result<(), Error> {
    let dt = 1.0 / 60.0;
    let params = params(args.alive);
    let blend = if args.alpha { ParticleBlend::Alpha } else { ParticleBlend::Additive };
    let eye = Vec3::new(0.0, 2.0, 12.0);
    let full = (LIFE / dt).ceil() as u32 + 1;
    let (mut times, alive, slots) = if args.gpu {
        let gpu = Gpu::headless()?;
        let slots = glint::sim::particles::Schedule::new(&params).slots() as u32;
        let records = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("glint sim particles: records"),
            size: u64::from(slots) * std::mem::size_of::<ParticleGpu>() as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::VERTEX,
            mapped_at_creation: false,
        });
        let kernels = std::sync::Arc::new(glint::sim::particles::ParticleKernels::new(&gpu.device));
        let device_queue = (&gpu.device, &gpu.queue);
        let mut on_gpu = GpuParticles::new(device_queue, &kernels, params.clone(), dt, (&records, slots), blend)
            .map_err(|m| crate::sim::usage(&m))?;
        let mut run = |steps: u32| -> Result<f64, Error> {
            let start = Instant::now();
            let time = dt * steps as f32;
            on_gpu.advance_to(&gpu.queue, time, Some(eye));
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            on_gpu.encode(&gpu.device, &gpu.queue, &mut encoder);
            gpu.queue.submit([encoder.finish()]);
            gpu.wait()?;
            Ok(start.elapsed().as_secs_f64() * 1e3)
        };
        run(full)?;
        let times = (1..=args.steps).map(|k| run(full + k)).collect::<Result<Vec<_>, _>>()?;
        let end = dt * (full + args.steps) as f32;
        (times, on_gpu.schedule().alive_at(&params, end), u64::from(slots))
    } else {
        let mut system = ParticleSystem::new(params.clone(), dt).map_err(|m| crate::sim::usage(&m))?;
        for _ in 0..full {
            system.step();
        }
        let times: Vec<f64> = (0..args.steps)
            .map(|_| {
                let start = Instant::now();
                system.step();
                let records = system.records(args.alpha.then_some(eye));
                std::hint::black_box(records);
                start.elapsed().as_secs_f64() * 1e3
            })
            .collect();
        (times, system.schedule().alive_at(&params, system.time()), system.schedule().slots())
    };
    let median = crate::bench::median(&mut times).unwrap_or(0.0);
    let report = Report {
        path: if args.gpu { "gpu" } else { "cpu" },
        blend: if args.alpha { "alpha" } else { "additive" },
        alive,
        slots,
        steps: args.steps,
        ms_per_step: median,
        ms_per_step_min: crate::bench::percentile(&times, 0.0),
        ms_per_step_max: crate::bench::percentile(&times, 1.0),
        threads: rayon::current_num_threads(),
    };
    if args.json {
        crate::output::print(&format!("{}\n", serde_json::to_string(&report).expect("plain numbers serialise")))?;
    } else {
        crate::output::print(&format!(
            "{} alive particles ({} slots, {}) on the {}: {:.3} ms a step (median of {}; min {:.3}, max {:.3})\n",
            report.alive,
            report.slots,
            report.blend,
            report.path,
            report.ms_per_step,
            report.steps,
            report.ms_per_step_min,
            report.ms_per_step_max
        ))?;
    }
    Ok(())
}
