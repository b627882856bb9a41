//! `glint sim school`: step a fish school on the CPU (or, with `--gpu`, with
//! compute shaders) and print its statistics or, with `--bench`, its speed.

use clap::Args;
use glam::Vec3;
use glint::scene::Aabb;
use glint::sim::school::{School, SchoolParams, SchoolStats};
use glint::Error;
use std::time::Instant;

/// Fish per cubic world unit the bounds are sized for: about seven within a
/// fish's view radius at the start.
const DENSITY: f32 = 0.5;

/// `glint sim school` options.
#[derive(Args)]
pub struct SchoolArgs {
    /// How many fish (1 to 4,194,304).
    #[arg(long, default_value_t = 10_000, value_parser = clap::value_parser!(u32).range(1..=(1 << 22)))]
    fish: u32,
    /// Steps to take.
    #[arg(long, default_value_t = 100, value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    steps: u32,
    /// Seconds a step.
    #[arg(long, default_value_t = 1.0 / 60.0, value_parser = crate::sim::positive_f32)]
    dt: f32,
    /// The random start's seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// With a predator hunting the school.
    #[arg(long)]
    predator: bool,
    /// Step with compute shaders instead of the CPU.
    #[arg(long)]
    gpu: bool,
    /// Time every step and print the median.
    #[arg(long)]
    bench: bool,
    /// With `--gpu --bench`: step the same start on the CPU too, in the same
    /// run, and print both and the ratio.
    #[arg(long, requires = "gpu", requires = "bench")]
    vs_cpu: bool,
    /// With `--bench`: print one JSON object instead of text.
    #[arg(long, requires = "bench")]
    json: bool,
}

/// What `--bench --json` prints: one object.
#[derive(serde::Serialize)]
struct BenchReport {
    fish: u32,
    steps: u32,
    path: &'static str,
    threads: usize,
    ms_per_step: f64,
    ms_per_step_min: f64,
    ms_per_step_max: f64,
    steps_per_second: f64,
    mean_speed: f32,
    polarisation: f32,
    nearest: f32,
}

/// The benchmark's school: `fish` fish in a cube sized for [`DENSITY`],
/// optionally hunted.
fn params(args: &SchoolArgs) -> SchoolParams {
    let half = 0.5 * (args.fish as f32 / DENSITY).cbrt().max(4.0);
    let bounds = Aabb { min: Vec3::splat(-half), max: Vec3::splat(half) };
    let predator =
        args.predator.then_some(glint::sim::school::Hunter { start: Vec3::ZERO, speed: 3.5, accel: 6.0, fear: 4.0 });
    SchoolParams { count: args.fish as usize, bounds, predator, seed: args.seed, ..SchoolParams::default() }
}

/// What `--bench --vs-cpu --json` prints: both paths from one start, and how
/// many times faster the GPU's steps are.
#[derive(serde::Serialize)]
struct VersusReport {
    gpu: BenchReport,
    cpu: BenchReport,
    gpu_speedup: f64,
}

/// Run `glint sim school`.
pub fn school(args: &SchoolArgs) -> Result<(), Error> {
    let params = params(args);
    let school = School::new(params.clone()).map_err(|why| crate::sim::usage(&why))?;
    // The same seeded start, for the CPU's side.
    let start = args.vs_cpu.then(|| School::new(params)).transpose().map_err(|why| crate::sim::usage(&why))?;
    let (times, stats) = if args.gpu { gpu_steps(args, school)? } else { cpu_steps(args, school) };
    if !args.bench {
        crate::output::print(&format!(
            "{} fish after {} steps: mean speed {:.3}, polarisation {:.3}, nearest neighbour {:.3}\n",
            args.fish, args.steps, stats.mean_speed, stats.polarisation, stats.nearest
        ))?;
        return Ok(());
    }
    let first = report(args, if args.gpu { "gpu" } else { "cpu" }, times, stats);
    let Some(start) = start else {
        return match args.json {
            true => print_json(&first),
            false => Ok(crate::output::print(&line(&first))?),
        };
    };
    let (times, stats) = cpu_steps(args, start);
    let cpu = report(args, "cpu", times, stats);
    let versus = VersusReport { gpu_speedup: cpu.ms_per_step / first.ms_per_step, gpu: first, cpu };
    match args.json {
        true => print_json(&versus),
        false => Ok(crate::output::print(&format!(
            "{}{}the gpu's steps: {:.2}x the cpu's speed\n",
            line(&versus.gpu),
            line(&versus.cpu),
            versus.gpu_speedup
        ))?),
    }
}

/// The benchmark's figures from each step's milliseconds on `path`.
fn report(args: &SchoolArgs, path: &'static str, mut times: Vec<f64>, stats: SchoolStats) -> BenchReport {
    let median = crate::bench::median(&mut times).unwrap_or(0.0);
    BenchReport {
        fish: args.fish,
        steps: args.steps,
        path,
        threads: rayon::current_num_threads(),
        ms_per_step: median,
        ms_per_step_min: crate::bench::percentile(&times, 0.0),
        ms_per_step_max: crate::bench::percentile(&times, 1.0),
        steps_per_second: 1000.0 / median,
        mean_speed: stats.mean_speed,
        polarisation: stats.polarisation,
        nearest: stats.nearest,
    }
}

fn print_json(report: &impl serde::Serialize) -> Result<(), Error> {
    Ok(crate::output::print(&format!("{}\n", serde_json::to_string(report).expect("plain numbers serialise")))?)
}

/// One path's figures as a line of text.
fn line(report: &BenchReport) -> String {
    format!(
        "{} fish on the {}: {:.3} ms a step (median of {}; min {:.3}, max {:.3}), {:.1} steps/s\n",
        report.fish,
        report.path,
        report.ms_per_step,
        report.steps,
        report.ms_per_step_min,
        report.ms_per_step_max,
        report.steps_per_second
    )
}

/// Each step's milliseconds on the CPU, and the statistics at the end.
fn cpu_steps(args: &SchoolArgs, mut school: School) -> (Vec<f64>, SchoolStats) {
    let times = (0..args.steps)
        .map(|_| {
            let start = Instant::now();
            school.step(args.dt);
            start.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    (times, school.stats())
}

/// Each step's milliseconds with compute shaders (submitted and waited
/// for), and the statistics at the end.
fn gpu_steps(args: &SchoolArgs, school: School) -> Result<(Vec<f64>, SchoolStats), Error> {
    let gpu = glint::Gpu::headless()?;
    let mut on_gpu = glint::sim::school::GpuSchool::new(&gpu, &school)?;
    let mut times = Vec::with_capacity(args.steps as usize);
    for _ in 0..args.steps {
        let start = Instant::now();
        on_gpu.step(&gpu, args.dt);
        gpu.wait()?;
        times.push(start.elapsed().as_secs_f64() * 1e3);
    }
    let stats = on_gpu.read(&gpu)?.stats();
    Ok((times, stats))
}
