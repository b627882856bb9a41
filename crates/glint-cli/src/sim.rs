//! `glint sim cloth`: run a Discrete Elastic Plates simulation without a window
//! (on the CPU, or with `--gpu` on compute shaders), writing the trajectory as
//! CSV and, with `--bench`, its speed (and with `--vs-cpu` the CPU solves'
//! beside it, and how far the GPU's nodes end from the converged solve's).

use clap::{Args, ValueEnum};
use glam::DVec3;
use glint::sim::cloth::{
    Cloth, ClothMesh, ClothParams, Collider, GpuCloth, GpuSolve, Integrator, PinSelector, Solve, MAX_GPU_ITERATIONS,
};
use glint::{Diagnostic, Error};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Most nodes a side of `--sheet`: a 1025 × 1025 sheet's solver would need
/// about 22 GB; larger meshes from files are refused by the solver's memory
/// estimate before it is allocated.
const MAX_SIDE: u32 = 257;

/// `glint sim cloth` options.
#[derive(Args)]
#[command(group(clap::ArgGroup::new("shape").required(true).args(["mesh", "sheet"])))]
pub struct ClothArgs {
    /// The mesh: OBJ, or the `*Nodes` / `*Triangles` text format.
    #[arg(long, value_name = "FILE")]
    mesh: Option<PathBuf>,
    /// A rectangular sheet in the XY plane, W,H metres.
    #[arg(long, value_name = "W,H", value_parser = parse_pair::<f64>, requires = "resolution")]
    sheet: Option<(f64, f64)>,
    /// Nodes along the sheet's width and height, N,M (2..=257 each; one step
    /// at 257 × 257 takes about two minutes and 1 GB).
    #[arg(long, value_name = "N,M", value_parser = parse_pair::<u32>)]
    resolution: Option<(u32, u32)>,
    /// Thickness h, metres.
    #[arg(long, default_value_t = 1e-3, value_parser = positive)]
    thickness: f64,
    /// Young's modulus E, pascals.
    #[arg(long, default_value_t = 1e7, value_parser = positive)]
    young: f64,
    /// Poisson's ratio (recorded; the DEP constants do not use it).
    #[arg(long, default_value_t = 0.3, value_parser = poisson)]
    poisson: f64,
    /// Density ρ, kg/m³.
    #[arg(long, default_value_t = 200.0, value_parser = positive)]
    density: f64,
    /// Gravity, "GX GY GZ" in m/s².
    #[arg(long, default_value = "0 0 -9.81", value_parser = parse_vector, allow_hyphen_values = true)]
    gravity: DVec3,
    /// Pinned nodes: a predicate on rest positions such as `x<=0.01`
    /// (`&&`, `||`), `nodes 1 2 3` (1-based), or `none`.
    #[arg(long, value_name = "PREDICATE", default_value = "none", value_parser = PinSelector::parse)]
    fix: PinSelector,
    /// A rigid obstacle: `plane PX PY PZ NX NY NZ`, `sphere CX CY CZ R` or
    /// `box MINX MINY MINZ MAXX MAXY MAXZ`. Repeatable.
    #[arg(long, value_name = "SHAPE", value_parser = Collider::parse)]
    collider: Vec<Collider>,
    /// Mass-proportional damping c, 1/s: a drag −c·m·v on every free node.
    #[arg(long, default_value_t = 0.0, value_parser = non_negative)]
    damping: f64,
    /// Time step, seconds (ignored by `static`).
    #[arg(long, default_value_t = 0.01, value_parser = positive)]
    dt: f64,
    /// Steps to take (`static` takes one).
    #[arg(long, default_value_t = 100, value_parser = clap::value_parser!(u32).range(1..=10_000_000))]
    steps: u32,
    /// How to advance.
    #[arg(long, value_enum, default_value_t = IntegratorArg::ImplicitEuler)]
    integrator: IntegratorArg,
    /// Write `step,t,x1,y1,z1,…` (1-based node numbers), one row per step.
    #[arg(long, value_name = "traj.csv")]
    out: Option<PathBuf>,
    /// How each time step is solved: Newton's method to convergence (the
    /// reference) or on a fixed budget for interactive use (the GPU's is
    /// `--gpu`).
    #[arg(long, value_enum, default_value_t = SolveArg::Converged)]
    solve: SolveArg,
    /// Step on the GPU's compute shaders (Vertex Block Descent on the same
    /// energies, a fixed number of iterations a step) instead of the CPU.
    #[arg(long, conflicts_with = "solve")]
    gpu: bool,
    /// With `--gpu`: sweeps over the node colours a step.
    #[arg(long, requires = "gpu", default_value_t = GpuSolve::default().iterations,
          value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_GPU_ITERATIONS)))]
    iterations: u32,
    /// With `--gpu`: Chebyshev's ρ accelerating the sweeps, 0 ≤ ρ < 1 (0: none,
    /// and the step's potential falls at every sweep).
    #[arg(long, requires = "gpu", default_value_t = GpuSolve::default().acceleration, value_parser = spectral_radius)]
    acceleration: f64,
    /// With `--gpu --bench`: take the same steps with the CPU's realtime and
    /// converged solves too, in the same run, and say how far the GPU's nodes
    /// end from the converged solve's.
    #[arg(long, requires = "gpu", requires = "bench")]
    vs_cpu: bool,
    /// Print steps per second and Newton iterations per step.
    #[arg(long)]
    bench: bool,
    /// With `--bench`: print one JSON object instead of text.
    #[arg(long, requires = "bench")]
    json: bool,
}

/// `--solve` (here, and on `render` and `view`; here the GPU's is `--gpu`,
/// with its settings).
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SolveArg {
    Converged,
    Realtime,
    Gpu,
}

impl SolveArg {
    /// The name `--solve` and `.scn` give it.
    fn name(self) -> &'static str {
        match self {
            SolveArg::Converged => "converged",
            SolveArg::Realtime => "realtime",
            SolveArg::Gpu => "gpu",
        }
    }
}

impl From<SolveArg> for Solve {
    fn from(arg: SolveArg) -> Self {
        match arg {
            SolveArg::Converged => Solve::Converged,
            SolveArg::Realtime => Solve::Realtime,
            SolveArg::Gpu => Solve::Gpu,
        }
    }
}

/// One solve's figures, as `--bench --json` prints them.
#[derive(serde::Serialize)]
struct BenchReport {
    nodes: usize,
    pinned: usize,
    edges: usize,
    hinges: usize,
    /// The CPU's threads (none on the GPU).
    #[serde(skip_serializing_if = "Option::is_none")]
    threads: Option<usize>,
    solve: &'static str,
    dt: f64,
    steps: u32,
    seconds: f64,
    steps_per_second: f64,
    /// Newton iterations, or on the GPU its sweeps over the colours.
    newton_iterations_per_step: f64,
    factorizations_per_step: f64,
    substeps_per_step: f64,
    /// On the GPU: the node colours (passes a sweep).
    #[serde(skip_serializing_if = "Option::is_none")]
    colours: Option<usize>,
}

/// What `--gpu --bench --vs-cpu --json` prints.
#[derive(serde::Serialize)]
struct VersusReport {
    gpu: BenchReport,
    realtime: BenchReport,
    converged: BenchReport,
    gpu_speedup_over_realtime: f64,
    gpu_speedup_over_converged: f64,
    /// Mean and largest distance of the GPU's nodes from the converged
    /// solve's after the last step, metres.
    gpu_from_converged_mean_m: f64,
    gpu_from_converged_worst_m: f64,
}

/// `--integrator`.
#[derive(Clone, Copy, ValueEnum)]
enum IntegratorArg {
    ImplicitEuler,
    Newmark,
    Static,
}

/// A finished run: the cloth at the end and its figures.
struct Run {
    cloth: Cloth,
    report: BenchReport,
}

/// Run `glint sim cloth`.
pub fn cloth(args: &ClothArgs) -> Result<(), Error> {
    let (integrator, steps) = match args.integrator {
        IntegratorArg::ImplicitEuler => (Integrator::ImplicitEuler, args.steps),
        IntegratorArg::Newmark => (Integrator::Newmark, args.steps),
        IntegratorArg::Static => (Integrator::Static, 1),
    };
    if args.solve == SolveArg::Gpu {
        return Err(usage("the GPU solve is --gpu here (with --iterations and --acceleration)"));
    }
    if args.gpu && integrator == Integrator::Static {
        return Err(usage("--gpu steps in time: a static solve (--integrator static) runs on the CPU"));
    }
    let mut out = args.out.as_deref().map(Trajectory::new);
    let first = match args.gpu {
        true => gpu_run(args, integrator, steps, out.as_mut())?,
        false => cpu_run(args, args.solve, integrator, steps, out.as_mut())?,
    };
    if let Some(out) = out {
        out.finish()?;
    }
    if !args.bench {
        return Ok(());
    }
    if !args.vs_cpu {
        let text = match args.json {
            true => format!("{}\n", serde_json::to_string(&first.report).expect("plain numbers serialise")),
            false => describe(&first.report, true),
        };
        return Ok(crate::output::print(&text)?);
    }
    let realtime = cpu_run(args, SolveArg::Realtime, integrator, steps, None)?;
    let converged = cpu_run(args, SolveArg::Converged, integrator, steps, None)?;
    let gaps: Vec<f64> =
        first.cloth.positions.iter().zip(&converged.cloth.positions).map(|(a, b)| a.distance(*b)).collect();
    let versus = VersusReport {
        gpu_speedup_over_realtime: first.report.steps_per_second / realtime.report.steps_per_second,
        gpu_speedup_over_converged: first.report.steps_per_second / converged.report.steps_per_second,
        gpu_from_converged_mean_m: gaps.iter().sum::<f64>() / gaps.len().max(1) as f64,
        gpu_from_converged_worst_m: gaps.iter().copied().fold(0.0, f64::max),
        gpu: first.report,
        realtime: realtime.report,
        converged: converged.report,
    };
    let text = match args.json {
        true => format!("{}\n", serde_json::to_string(&versus).expect("plain numbers serialise")),
        false => format!(
            "{}{}{}the gpu's steps: {:.2}x the realtime solve's speed, {:.2}x the converged one's; \
             its nodes end {:.4} m from the converged solve's on average, {:.4} m at most\n",
            describe(&versus.gpu, true),
            describe(&versus.realtime, false),
            describe(&versus.converged, false),
            versus.gpu_speedup_over_realtime,
            versus.gpu_speedup_over_converged,
            versus.gpu_from_converged_mean_m,
            versus.gpu_from_converged_worst_m
        ),
    };
    Ok(crate::output::print(&text)?)
}

/// The cloth the options describe, solved as `solve` on the CPU.
fn build(args: &ClothArgs, solve: SolveArg) -> Result<Cloth, Error> {
    let mesh = match (&args.mesh, args.sheet, args.resolution) {
        (Some(path), _, _) => glint::asset::load_cloth_mesh(path)?,
        (None, Some((w, h)), Some((n, m))) => {
            let sizes = w.is_finite() && h.is_finite() && w > 0.0 && h > 0.0;
            if !(sizes && (2..=MAX_SIDE).contains(&n) && (2..=MAX_SIDE).contains(&m)) {
                return Err(usage(&format!(
                    "--sheet needs sizes above 0 and --resolution 2..={MAX_SIDE} nodes a side"
                )));
            }
            ClothMesh::sheet(w, h, n, m)
        }
        _ => return Err(usage("give --mesh FILE, or --sheet W,H with --resolution N,M")),
    };
    let source = args.mesh.clone().unwrap_or_else(|| PathBuf::from("--sheet"));
    let pinned = args.fix.select(&mesh.nodes).map_err(|m| Diagnostic::file(&source, format!("--fix: {m}")))?;
    let params = ClothParams {
        thickness: args.thickness,
        young: args.young,
        poisson: args.poisson,
        density: args.density,
        gravity: args.gravity,
    };
    let mut cloth = Cloth::new(mesh, params, &pinned).map_err(|e| Diagnostic::file(&source, e.to_string()))?;
    cloth.set_colliders(args.collider.clone(), args.thickness.max(1e-3));
    cloth.set_damping(args.damping);
    cloth.set_solve(solve.into());
    Ok(cloth)
}

/// `steps` steps on the CPU, solved as `solve`, each row written to `out`.
fn cpu_run(
    args: &ClothArgs,
    solve: SolveArg,
    integrator: Integrator,
    steps: u32,
    mut out: Option<&mut Trajectory<'_>>,
) -> Result<Run, Error> {
    let mut cloth = build(args, solve)?;
    let (mut stepping, mut iterations, mut factorizations, mut substeps) = (0.0, 0u64, 0u64, 0u64);
    for step in 1..=steps {
        let start = Instant::now();
        let stats = cloth.step(args.dt, integrator)?;
        stepping += start.elapsed().as_secs_f64();
        iterations += u64::from(stats.newton_iterations);
        factorizations += u64::from(stats.factorizations);
        substeps += u64::from(stats.substeps);
        if let Some(out) = out.as_deref_mut() {
            out.row(step, cloth.time, &cloth.positions)?;
        }
    }
    let per_step = |n: u64| n as f64 / f64::from(steps);
    let counts = [per_step(iterations), per_step(factorizations), per_step(substeps)];
    let report = report(args, &cloth, solve.name(), (steps, stepping), counts, None);
    Ok(Run { cloth, report })
}

/// `steps` steps on the GPU, each row written to `out` (read back each step).
fn gpu_run(
    args: &ClothArgs,
    integrator: Integrator,
    steps: u32,
    mut out: Option<&mut Trajectory<'_>>,
) -> Result<Run, Error> {
    let mut cloth = build(args, SolveArg::Converged)?;
    let gpu = glint::Gpu::headless()?;
    let settings = GpuSolve { iterations: args.iterations, acceleration: args.acceleration };
    let mut on_gpu = GpuCloth::new(&gpu, &cloth, args.dt, integrator, settings)?;
    gpu.wait()?;
    // Without rows to write, every step is submitted before one wait; with
    // them, each step is timed to its wait, and its reading back is not.
    let mut stepping = 0.0;
    let mut start = Instant::now();
    for step in 1..=steps {
        on_gpu.step(&gpu);
        if let Some(out) = out.as_deref_mut() {
            gpu.wait()?;
            stepping += start.elapsed().as_secs_f64();
            on_gpu.read_into(&gpu, &mut cloth)?;
            out.row(step, cloth.time, &cloth.positions)?;
            start = Instant::now();
        }
    }
    gpu.wait()?;
    stepping += start.elapsed().as_secs_f64();
    on_gpu.read_into(&gpu, &mut cloth)?;
    let counts = [f64::from(args.iterations), 0.0, 1.0];
    let report = report(args, &cloth, "gpu", (steps, stepping), counts, Some(on_gpu.colours()));
    Ok(Run { cloth, report })
}

/// The figures of a run of `steps` steps in `seconds`, with its Newton
/// iterations, factorisations and sub-steps a step.
fn report(
    args: &ClothArgs,
    cloth: &Cloth,
    solve: &'static str,
    (steps, seconds): (u32, f64),
    [iterations, factorizations, substeps]: [f64; 3],
    colours: Option<usize>,
) -> BenchReport {
    let nodes = cloth.positions.len();
    BenchReport {
        nodes,
        pinned: (0..nodes).filter(|&i| cloth.is_pinned(i)).count(),
        edges: cloth.topology().edges.len(),
        hinges: cloth.topology().hinges.len(),
        threads: colours.is_none().then(rayon::current_num_threads),
        solve,
        dt: args.dt,
        steps,
        seconds,
        steps_per_second: f64::from(steps) / seconds,
        newton_iterations_per_step: iterations,
        factorizations_per_step: factorizations,
        substeps_per_step: substeps,
        colours,
    }
}

/// A report as text; the cloth's line first when `header`.
fn describe(r: &BenchReport, header: bool) -> String {
    let mut text = String::new();
    if header {
        text.push_str(&format!(
            "cloth: {} nodes ({} pinned), {} edges, {} hinges\n",
            r.nodes, r.pinned, r.edges, r.hinges
        ));
    }
    let speed = format!("{} steps of {} s in {:.3} s: {:.1} steps/s", r.steps, r.dt, r.seconds, r.steps_per_second);
    text.push_str(&match r.colours {
        Some(colours) => format!(
            "gpu solve: {speed}, {} iterations/step over {colours} node colours\n",
            r.newton_iterations_per_step
        ),
        None => format!(
            "{} solve ({} threads): {speed}, {:.2} Newton iterations/step ({:.2} factorisations), {:.2} sub-steps/step\n",
            r.solve,
            r.threads.unwrap_or(0),
            r.newton_iterations_per_step, r.factorizations_per_step, r.substeps_per_step
        ),
    });
    text
}

/// The CSV trajectory being written. The file is made with the first row
/// (which also says how many nodes the header names), so a run refused
/// before its first step leaves an existing file alone.
struct Trajectory<'p> {
    path: &'p Path,
    file: Option<std::io::BufWriter<std::fs::File>>,
}

impl<'p> Trajectory<'p> {
    fn new(path: &'p Path) -> Self {
        Self { path, file: None }
    }

    fn row(&mut self, step: u32, time: f64, positions: &[DVec3]) -> Result<(), Error> {
        if self.file.is_none() {
            let file = std::fs::File::create(self.path)
                .map_err(|e| Diagnostic::file(self.path, format!("cannot create: {e}")))?;
            self.file = Some(std::io::BufWriter::new(file));
            let mut header = String::from("step,t");
            for n in 1..=positions.len() {
                header.push_str(&format!(",x{n},y{n},z{n}"));
            }
            self.line(&header)?;
        }
        let mut line = format!("{step},{time}");
        for p in positions {
            line.push_str(&format!(",{},{},{}", p.x, p.y, p.z));
        }
        self.line(&line)
    }

    fn line(&mut self, text: &str) -> Result<(), Error> {
        let file = self.file.as_mut().expect("made with the first row");
        writeln!(file, "{text}").map_err(|e| Diagnostic::file(self.path, format!("cannot write: {e}")).into())
    }

    fn finish(self) -> Result<(), Error> {
        match self.file {
            Some(mut file) => {
                file.flush().map_err(|e| Diagnostic::file(self.path, format!("cannot write: {e}")).into())
            }
            None => Ok(()),
        }
    }
}

pub(crate) fn usage(message: &str) -> Error {
    Diagnostic::file(Path::new("glint sim"), message).into()
}

fn parse_pair<T: std::str::FromStr>(s: &str) -> Result<(T, T), String> {
    let (a, b) = s.split_once(',').ok_or_else(|| "expected two numbers, A,B".to_string())?;
    match (a.trim().parse(), b.trim().parse()) {
        (Ok(a), Ok(b)) => Ok((a, b)),
        _ => Err("expected two numbers, A,B".into()),
    }
}

fn positive(s: &str) -> Result<f64, String> {
    s.trim().parse::<f64>().ok().filter(|v| v.is_finite() && *v > 0.0).ok_or_else(|| "expected a number above 0".into())
}

/// A number above 0, for `f32` options: one that stays finite and above 0
/// as an `f32` (1e300 would be infinite, 1e-300 zero).
pub(crate) fn positive_f32(s: &str) -> Result<f32, String> {
    let v = positive(s)? as f32;
    match v.is_finite() && v >= f32::MIN_POSITIVE {
        true => Ok(v),
        false => Err(format!("expected a number from {:e} to {:e} (a 32-bit float)", f32::MIN_POSITIVE, f32::MAX)),
    }
}

fn non_negative(s: &str) -> Result<f64, String> {
    s.trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite() && *v >= 0.0)
        .ok_or_else(|| "expected a number 0 or above".into())
}

fn spectral_radius(s: &str) -> Result<f64, String> {
    s.trim().parse::<f64>().ok().filter(|v| (0.0..1.0).contains(v)).ok_or_else(|| "expected 0 <= ρ < 1".into())
}

fn poisson(s: &str) -> Result<f64, String> {
    s.trim().parse::<f64>().ok().filter(|v| (0.0..=0.5).contains(v)).ok_or_else(|| "expected 0 <= ν <= 0.5".into())
}

fn parse_vector(s: &str) -> Result<DVec3, String> {
    let v: Vec<f64> = s.split_whitespace().filter_map(|w| w.parse().ok().filter(|v: &f64| v.is_finite())).collect();
    match v[..] {
        [x, y, z] if s.split_whitespace().count() == 3 => Ok(DVec3::new(x, y, z)),
        _ => Err("expected three numbers, \"X Y Z\"".into()),
    }
}
