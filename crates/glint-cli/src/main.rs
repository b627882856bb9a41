//! The `glint` command-line tool.

// Everything printed goes through `output` (checked writes): `println!`
// panics when standard output cannot be written.
#![deny(clippy::print_stdout)]

mod bench;
mod bench_command;
mod bench_live;
mod compare;
mod explain;
mod frames;
mod lod;
mod output;
mod particles;
mod plot;
mod render;
mod school;
mod sim;
mod sim_cache;
mod view;

use bench_command::{run_bench, run_live, BenchMode, BenchOutput};
use clap::{Parser, Subcommand};
use glint::asset::{load_scene_with, LoadOptions, Model, SceneDesc};
use glint::Error;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

const EXIT_CODES: &str =
    "Exit codes: 0 ok, 1 bad input or an output that cannot be written (file:line: message on stderr), 2 no GPU adapter, 3 other GPU or render failure.";

/// Most frames `glint bench` measures (and warms up) per mode: each keeps its
/// statistics until the report.
const MAX_BENCH_FRAMES: u64 = 100_000;

/// Lowest and highest `--fps` of `glint render`.
const FPS_RANGE: std::ops::RangeInclusive<f32> = 0.001..=1000.0;

/// glint: a real-time 3D renderer on wgpu.
#[derive(Parser)]
#[command(name = "glint", version, about, after_help = EXIT_CODES)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Let scenes and models name assets outside their asset roots (absolute
    /// paths, `..`, symlinks out, file: URIs). Off by default, so a scene or model
    /// from elsewhere cannot make glint read any file.
    #[arg(long, global = true)]
    allow_outside_assets: bool,
    /// A folder scenes and models may read assets from, besides their own folder
    /// (a scene's folder is widened to the current directory when the scene lies
    /// inside it). Repeatable.
    #[arg(long = "asset-root", value_name = "DIR", global = true)]
    asset_roots: Vec<PathBuf>,
}

#[derive(Subcommand)]
enum Command {
    /// Render one frame of a .scn scene to a PNG file.
    #[command(after_help = EXIT_CODES)]
    Render {
        /// The scene file.
        scene: PathBuf,
        /// Output PNG path.
        #[arg(short, long, default_value = "out.png")]
        output: PathBuf,
        #[command(flatten)]
        picture: Picture,
        /// Print the frame's statistics as one JSON object on stdout.
        #[arg(long)]
        stats: bool,
        /// Pose animated models at this time, in seconds (their first animation).
        #[arg(long, default_value_t = 0.0, value_parser = parse_time)]
        time: f32,
        /// A sequence of this many frames from --time on: -o names them with
        /// %04d, or is one animation (-o clip.gif, or -o clip.png --apng).
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100_000))]
        frames: u32,
        /// Frames per second of the sequence (0.001..=1000).
        #[arg(long, default_value_t = 30.0, value_parser = parse_fps)]
        fps: f32,
        /// Render only these frames of the --frames sequence, numbered and
        /// posed as in the whole run, so machines of a render farm can each
        /// take a part: FIRST..END (END not included), or as Slurm and Open Job
        /// Description list them, inclusive: N, A-B, A-B:STEP, or a
        /// comma-separated list of those (1,3,5-7).
        #[arg(long, value_name = "FRAMES", value_parser = frames::parse_frame_range)]
        frame_range: Option<frames::FrameRange>,
        /// Leave alone the numbered frames already on disk (so a failed chunk
        /// can be run again): each is neither posed nor drawn.
        #[arg(long)]
        skip_existing: bool,
        /// Start each simulation (cloth, school, emitter) from this cache's
        /// state at or before the first frame (glint bake makes caches): frames
        /// equal the whole run's. A cache made for another scene, other
        /// settings, another glint or another adapter is refused.
        #[arg(long, value_name = "CACHE")]
        sim_cache: Option<PathBuf>,
        /// Write the frames as one animated PNG (-o clip.png) rather than numbered PNGs.
        #[arg(long)]
        apng: bool,
        /// Orbit the camera once around its target over the --frames sequence
        /// (for models without animation).
        #[arg(long)]
        turntable: bool,
        /// Samples per pixel: average this many sub-frames of each frame, at
        /// its time, with the camera jittered within the pixel (Halton 2, 3)
        /// and ambient occlusion's noise turned, in HDR before tonemapping
        /// (1..=4096; 1 draws each frame once, as without it).
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=glint::render::MAX_SUB_FRAMES as i64))]
        spp: u32,
        /// Post-process every camera that draws into the picture with these
        /// effects, e.g. "tonemap smaa", instead of its own "post" (each with
        /// the settings the camera's own chain gave it, else its defaults);
        /// "" for none.
        #[arg(long)]
        post: Option<String>,
    },
    /// Step a scene's simulations once through a sequence and store their
    /// state every few frames in a cache (a folder), so `glint render
    /// --sim-cache` chunks of the sequence start where they begin.
    #[command(after_help = EXIT_CODES)]
    Bake {
        /// The scene file.
        scene: PathBuf,
        /// The cache's folder (made where missing).
        #[arg(short, long)]
        output: PathBuf,
        /// Frames in the sequence, as `glint render --frames` renders it.
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..=100_000))]
        frames: u32,
        /// Frames per second of the sequence (0.001..=1000).
        #[arg(long, default_value_t = 30.0, value_parser = parse_fps)]
        fps: f32,
        /// Scene time of frame 0, in seconds.
        #[arg(long, default_value_t = 0.0, value_parser = parse_time)]
        time: f32,
        /// Store the state every this many frames (1..=100000).
        #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u32).range(1..=100_000))]
        every: u32,
        /// Solve every cloth this way, as `glint render --solve` would.
        #[arg(long, value_enum)]
        solve: Option<sim::SolveArg>,
        #[command(flatten)]
        sim: SimArgs,
    },
    /// Measure a scene's steady-state frame cost: the naive baseline, and the
    /// optimized frame culled on the CPU and on the GPU, side by side.
    #[command(after_help = EXIT_CODES)]
    Bench {
        /// The scene file.
        scene: PathBuf,
        /// Measured frames per mode (1..=100000).
        #[arg(long, default_value_t = 100, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..=MAX_BENCH_FRAMES))]
        frames: usize,
        /// Unmeasured frames before them (0..=100000).
        #[arg(long, default_value_t = 5, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(0..=MAX_BENCH_FRAMES))]
        warmup: usize,
        /// Which ways to build frames.
        #[arg(long, value_enum, default_value_t = BenchMode::All)]
        mode: BenchMode,
        /// How the optimized frame culls (modes optimized and both), whatever
        /// the camera's "cull" says.
        #[arg(long, value_enum)]
        cull: Option<CullArg>,
        /// Draw this share (0..=1) of every tile of tiled instances (times each
        /// block's own "density").
        #[arg(long, default_value_t = 1.0, value_parser = parse_density)]
        density: f32,
        /// Turn the camera this many degrees about its target each frame (0..=360).
        #[arg(long, default_value_t = 0.0, value_parser = parse_orbit)]
        orbit: f32,
        /// Sleep this many milliseconds (0..=2000) before each frame's flush,
        /// outside its times, so scenes of every size start their CPU stages
        /// from the same state: on a CPU rasterizer the thread otherwise sleeps
        /// as long as the last GPU work took, and wakes slower the longer it slept.
        #[arg(long, default_value_t = 0, value_parser = clap::value_parser!(u64).range(0..=2000))]
        settle: u64,
        /// Image size, WIDTHxHEIGHT.
        #[arg(long, default_value = "1280x720", value_parser = parse_size)]
        size: (u32, u32),
        /// Samples per pixel: 1 or 4.
        #[arg(long, default_value_t = 1, value_parser = parse_msaa)]
        msaa: u32,
        /// Print one JSON object instead of text.
        #[arg(long)]
        json: bool,
        /// Also draw the per-stage CPU breakdown into this PNG.
        #[arg(long, value_name = "CHART.png")]
        plot: Option<PathBuf>,
        /// Post-process the first camera with these effects (with their
        /// defaults), e.g. "bloom tonemap fxaa", instead of its own "post"; ""
        /// for none. Given more than once (with --mode optimized), each chain
        /// is measured in turn in the same run (e.g. --post "tonemap fxaa"
        /// --post "tonemap smaa"), each report naming its chain.
        #[arg(long, value_parser = parse_post)]
        post: Vec<PostArg>,
        /// Run the scene as it plays instead (its fish, particles and cloth
        /// stepping, as in the viewer), FPS frames a second of scene time
        /// from --time: the whole frame, posing included.
        #[arg(long, value_name = "FPS", value_parser = parse_fps)]
        live: Option<f32>,
        /// With --live: run it again with every school stepped on the CPU,
        /// and put that whole frame beside the one from --sim (GPU by default).
        #[arg(long, requires = "live")]
        vs_cpu: bool,
        /// With --live: the scene time of the first frame, seconds.
        #[arg(long, default_value_t = 0.0, requires = "live", value_parser = parse_time)]
        time: f32,
        /// Levels of detail: on (each instance at the coarsest level whose
        /// error its view allows), off (every mesh at full detail), or both
        /// (each measurement with levels, then at full detail, and their ratios).
        #[arg(long, value_enum, default_value_t = lod::BenchLod::On)]
        lod: lod::BenchLod,
        /// The error, in pixels (0..=1000), a level of detail may make,
        /// whatever the camera's "lod_error" says (default 1).
        #[arg(long, value_name = "PX", value_parser = lod::parse_lod_error)]
        lod_error: Option<f32>,
        /// Light clusters: auto (when a frame has more than 8 point and spot
        /// lights), on, or off (every fragment loops over every light, at most 64).
        #[arg(long, value_enum, default_value_t = lod::ClustersArg::Auto)]
        clusters: lod::ClustersArg,
        #[command(flatten)]
        sim: SimArgs,
    },
    /// Open a window onto a .scn scene (or a model file) and fly through it.
    #[command(after_help = view::KEYS)]
    View {
        /// The scene file.
        scene: PathBuf,
        #[command(flatten)]
        picture: Picture,
        /// Quit after this many frames.
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
        frames: Option<u32>,
        /// On quitting, write the last frame to this PNG.
        #[arg(long, value_name = "PATH")]
        screenshot: Option<PathBuf>,
        /// Before frame FRAME (from 1): resize=WxH, minimize, restore or
        /// screenshot=PATH. Repeatable; for scripted runs such as CI.
        #[arg(long, value_name = "FRAME:ACTION", value_parser = view::parse_at)]
        at: Vec<view::Scripted>,
    },
    /// Explain a frame as the GPU receives it: each pass, each draw call in
    /// order with its decoded sort key, the state it changed and kept, its
    /// instances and triangles, and the stage costs (no window needed).
    #[command(after_help = EXIT_CODES)]
    Explain {
        /// The scene file.
        scene: PathBuf,
        /// Explain the naive frame too, beside the optimized one, with the ratios of their costs.
        #[arg(long)]
        naive: bool,
        /// Print one JSON object: the frame's `stats` and its `passes`, each
        /// holding its `draw_calls` in encoding order (and `naive` likewise).
        #[arg(long)]
        json: bool,
        /// Which view of the frame (0 = the first).
        #[arg(long, default_value_t = 0)]
        view: usize,
        /// Use only this camera of the scene (0 = the first).
        #[arg(long)]
        camera: Option<usize>,
        /// Cull every view this way, whatever its camera's "cull" says.
        #[arg(long, value_enum)]
        cull: Option<CullArg>,
        /// Image size, WIDTHxHEIGHT.
        #[arg(long, default_value = "640x360", value_parser = parse_size)]
        size: (u32, u32),
        /// Pose the scene at this time, in seconds.
        #[arg(long, default_value_t = 0.0, value_parser = parse_time)]
        time: f32,
        /// Draw each frame as an accumulated still of this many sub-frames,
        /// as `glint render --spp` does, and explain its last sub-frame: its
        /// passes (the fold into the mean, the post chain run on it) and its
        /// costs (a sub-frame's; the still's are about this many times them).
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=glint::render::MAX_SUB_FRAMES as i64))]
        spp: u32,
        #[command(flatten)]
        lod: lod::LodArgs,
        #[command(flatten)]
        sim: SimArgs,
    },
    /// Run a simulation (see `glint sim cloth --help`, `glint sim school --help`).
    #[command(subcommand, after_help = EXIT_CODES)]
    Sim(SimCommand),
    /// Parse and validate a .scn scene without a GPU, and summarise it.
    #[command(after_help = EXIT_CODES)]
    Check {
        /// The scene file.
        scene: PathBuf,
    },
    /// Say whether two images match within the reference-image tolerance.
    #[command(after_help = "Exit codes: 0 they match, 4 they differ, 1 an image that cannot be read or written.")]
    Compare {
        /// The reference image.
        expected: PathBuf,
        /// The image to check.
        actual: PathBuf,
        /// Write the difference map here (PNG).
        #[arg(long)]
        diff: Option<PathBuf>,
    },
}

/// `glint sim` subcommands.
#[derive(Subcommand)]
enum SimCommand {
    /// Discrete Elastic Plates cloth: write its trajectory as CSV, or benchmark it.
    #[command(after_help = EXIT_CODES)]
    Cloth(Box<sim::ClothArgs>),
    /// Fish schooling: step a school and print its statistics, or benchmark it.
    #[command(after_help = EXIT_CODES)]
    School(school::SchoolArgs),
    /// Particles: step an emitter of about N living particles and time it.
    #[command(after_help = EXIT_CODES)]
    Particles(particles::ParticleArgs),
}

/// Size, samples and camera of `render` and `view`.
#[derive(clap::Args)]
struct Picture {
    /// Size in pixels (the window's, to begin with), WIDTHxHEIGHT.
    #[arg(long, default_value = "1280x720", value_parser = parse_size)]
    size: (u32, u32),
    /// Samples per pixel: 1 (no MSAA) or 4.
    #[arg(long, default_value_t = 4, value_parser = parse_msaa)]
    msaa: u32,
    /// Draw only this camera of the scene (0 = the first), over the whole image.
    /// Without it, every camera with a "viewport" draws into its rectangle, or
    /// the first camera alone when none has one.
    #[arg(long)]
    camera: Option<usize>,
    /// Solve every cloth this way, whatever its scene block says: Newton's
    /// method to convergence (the reference), on a fixed budget for
    /// interactive use, or on the GPU (compute shaders, drawn from their
    /// buffers; converged on the CPU where the adapter cannot, as on GL).
    #[arg(long, value_enum)]
    solve: Option<sim::SolveArg>,
    /// Cull every view this way, whatever its camera's "cull" says: off (draw
    /// everything), cpu (frustum culling on the CPU) or gpu (on the GPU, the
    /// default; the CPU's way where the adapter cannot, as on GL).
    #[arg(long, value_enum)]
    cull: Option<CullArg>,
    /// Draw this share (0..=1) of every tile of tiled instances (times each
    /// block's own "density").
    #[arg(long, default_value_t = 1.0, value_parser = parse_density)]
    density: f32,
    /// Move the sun, sky and glare to this hour (0..=24), whatever the scene's
    /// "time_of_day" says (scene files).
    #[arg(long, value_parser = parse_hours)]
    time_of_day: Option<f32>,
    #[command(flatten)]
    lod: lod::LodArgs,
    #[command(flatten)]
    sim: SimArgs,
}

/// `--sim` and `--transparency`, on `render`, `view`, `bench`, `explain`
/// and `bake`: what the scene's own blocks say, overridden.
#[derive(clap::Args, Clone, Copy)]
pub(crate) struct SimArgs {
    /// Step every fish school here, whatever its block's "sim" says: gpu
    /// (compute shaders, drawn in place from the simulation's buffers; the
    /// CPU where the adapter cannot, as on GL) or cpu (the reference).
    #[arg(long, value_enum)]
    sim: Option<SimArg>,
    /// Draw every camera's blended materials and alpha-blended particles
    /// this way, whatever the world's "transparency" says: sorted (far to
    /// near), weighted (weighted blended order-independent transparency) or
    /// exact (per-pixel lists, the reference; Vulkan and GL only).
    #[arg(long, value_enum)]
    transparency: Option<TransparencyArg>,
}

impl SimArgs {
    /// `options` with these choices.
    pub(crate) fn apply(self, options: LoadOptions) -> LoadOptions {
        let sim = self.sim.map(|s| match s {
            SimArg::Cpu => glint::scene::SimPath::Cpu,
            SimArg::Gpu => glint::scene::SimPath::Gpu,
        });
        let transparency = self.transparency.map(|t| glint::scene::Transparency::ALL[t as usize]);
        LoadOptions { sim: sim.or(options.sim), transparency: transparency.or(options.transparency), ..options }
    }
}

/// `--transparency`, in the order of [`glint::scene::Transparency::ALL`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum TransparencyArg {
    Sorted,
    Weighted,
    Exact,
}

/// `--sim`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum SimArg {
    Cpu,
    Gpu,
}

/// `--time-of-day`: hours, 0..=24.
fn parse_hours(s: &str) -> Result<f32, String> {
    number_in(s, 0.0..=24.0, "an hour of the day")
}

/// `s` as a number in `range`, else "expected `what` from LO to HI, found "s"".
fn number_in(s: &str, range: std::ops::RangeInclusive<f32>, what: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(v) if range.contains(&v) => Ok(v),
        _ => Err(format!("expected {what} from {} to {}", range.start(), range.end())),
    }
}

/// `--cull`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum CullArg {
    Off,
    Cpu,
    Gpu,
}

impl CullArg {
    pub(crate) fn culling(self) -> glint::Culling {
        match self {
            Self::Off => glint::Culling::Off,
            Self::Cpu => glint::Culling::Cpu,
            Self::Gpu => glint::Culling::Gpu,
        }
    }
}

/// `views` culled as `cull` says, where given.
pub(crate) fn culled(views: Vec<glint::View>, cull: Option<CullArg>) -> Vec<glint::View> {
    match cull {
        None => views,
        Some(c) => views.into_iter().map(|v| v.with_culling(c.culling())).collect(),
    }
}

/// An error naming the scene when it has no camera `camera`.
pub(crate) fn check_camera(desc: &SceneDesc, scene: &Path, camera: Option<usize>) -> Result<(), Error> {
    match camera {
        Some(k) if k >= desc.cameras.len() => Err(glint::Diagnostic::file(
            scene,
            format!("camera {k} requested, but the scene has {}", desc.cameras.len()),
        )
        .into()),
        _ => Ok(()),
    }
}

impl Picture {
    /// `options` with this picture's cloth solve, school path and time of day.
    fn load_options(&self, options: LoadOptions) -> LoadOptions {
        let options = self.sim.apply(options);
        LoadOptions { cloth_solve: self.solve.map(Into::into), time_of_day: self.time_of_day, ..options }
    }
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| "expected WIDTHxHEIGHT".to_string())?;
    let side = |v: &str| v.trim().parse::<u32>().ok().filter(|&n| (1..=16384).contains(&n));
    match (side(w), side(h)) {
        (Some(w), Some(h)) => Ok((w, h)),
        _ => Err("each side must be a whole number in 1..=16384".into()),
    }
}

/// `--density`: a share, 0..=1.
fn parse_density(s: &str) -> Result<f32, String> {
    number_in(s, 0.0..=1.0, "a share of every tile")
}

/// `--orbit`: degrees per frame, 0..=360.
fn parse_orbit(s: &str) -> Result<f32, String> {
    number_in(s, 0.0..=360.0, "degrees per frame")
}

fn parse_time(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(t) if t.is_finite() && t >= 0.0 => Ok(t),
        _ => Err("not a time: expected seconds, 0 or more".into()),
    }
}

fn parse_fps(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(f) if FPS_RANGE.contains(&f) => Ok(f),
        _ => Err(format!("not a frame rate: expected a number in {}..={}", FPS_RANGE.start(), FPS_RANGE.end())),
    }
}

/// `--post`: the effects, in order.
#[derive(Clone)]
struct PostArg(Vec<glint::scene::PostEffect>);

fn parse_post(s: &str) -> Result<PostArg, String> {
    let all = glint::scene::PostEffect::ALL;
    glint::scene::PostEffect::chain(s, &all).map(PostArg)
}

fn parse_msaa(s: &str) -> Result<u32, String> {
    match s {
        "1" => Ok(1),
        "4" => Ok(4),
        _ => Err("MSAA must be 1 or 4".into()),
    }
}

/// A scene file, or a model file shown alone with a framing camera and lights.
/// More lights than a frame can use (a glTF's `KHR_lights_punctual` may hold
/// any number) is an error naming the file, for `check` as for `render`.
pub(crate) fn load(scene: &Path, options: LoadOptions) -> Result<SceneDesc, Error> {
    let desc = if Model::is_model_path(scene) {
        let transparency = options.transparency;
        let mut desc = Model::load_with(scene, options)?.into_shown_scene();
        desc.transparency = transparency.unwrap_or(desc.transparency);
        desc
    } else {
        load_scene_with(scene, options)?
    };
    for warning in &desc.warnings {
        eprintln!("warning: {warning}");
    }
    if desc.lights.len() > glint::scene::MAX_CLUSTERED_LIGHTS {
        let most = glint::scene::MAX_CLUSTERED_LIGHTS;
        let message = format!("{} lights, but a frame can use at most {most}", desc.lights.len());
        return Err(glint::Diagnostic::file(scene, message).into());
    }
    Ok(desc)
}

fn check(scene: &Path, options: LoadOptions) -> Result<(), Error> {
    let desc = load(scene, options)?;
    let mut text = String::new();
    let mut line = |l: String| {
        text.push_str(&l);
        text.push('\n');
    };
    line(format!("{}: ok", scene.display()));
    line(format!("  cameras:    {}", desc.cameras.len()));
    line(format!("  lights:     {}", desc.lights.len()));
    line(format!("  materials:  {}", desc.materials.len()));
    line(format!("  textures:   {}", desc.textures.len()));
    line(format!("  render tasks (mesh x material): {}", desc.entities.len()));
    for model in &desc.models {
        let triangles: usize = model.parts.iter().map(|p| p.mesh.indices().len() / 3).sum();
        line(format!(
            "  model {}: {} parts, {} materials, {} textures, {triangles} triangles",
            model.path.display(),
            model.parts.len(),
            model.materials.len(),
            model.textures.len()
        ));
        for a in &model.animations {
            line(format!("    animation '{}': {} channels, {:.2} s", a.name, a.channels.len(), a.duration()));
        }
        for skin in &model.skins {
            line(format!("    skin '{}': {} joints", skin.name, skin.joints.len()));
        }
        for part in model.parts.iter().filter(|p| p.morph.is_some()) {
            let targets = part.morph.as_ref().map_or(0, |m| m.targets.len());
            line(format!("    part '{}': {targets} morph targets", part.name));
        }
    }
    line(format!("  instances:  {}", desc.instance_count()));
    line(format!("  warnings:   {}", desc.warnings.len()));
    output::print(&text)?;
    Ok(())
}

/// `e` with every value it quotes from the command line (an invalid value,
/// an unknown argument) cut to the message policy's
/// [`MAX_QUOTED_CHARS`](glint::text::MAX_QUOTED_CHARS) characters, then its
/// length, as `glint::text::quote` cuts values from files.
fn quoted_within_policy(mut e: clap::Error) -> clap::Error {
    use clap::error::ContextValue;
    let most = glint::text::MAX_QUOTED_CHARS;
    let cut = |s: &String| match s.chars().count() {
        n if n > most => Some(format!("{}…({n} characters)", s.chars().take(most).collect::<String>())),
        _ => None,
    };
    // A tip built from the value (how to pass it after `--`) is cut whole.
    let styled = |s: &clap::builder::StyledStr| {
        let text = s.to_string();
        (text.chars().count() > 3 * most).then(|| glint::text::shorten(&text, 3 * most).into())
    };
    let long: Vec<_> = e
        .context()
        .filter_map(|(kind, value)| match value {
            ContextValue::String(s) => cut(s).map(|s| (kind, ContextValue::String(s))),
            ContextValue::Strings(list) if list.iter().any(|s| cut(s).is_some()) => {
                let list = list.iter().map(|s| cut(s).unwrap_or_else(|| s.clone())).collect();
                Some((kind, ContextValue::Strings(list)))
            }
            ContextValue::StyledStr(s) => styled(s).map(|s| (kind, ContextValue::StyledStr(s))),
            ContextValue::StyledStrs(list) if list.iter().any(|s| styled(s).is_some()) => {
                let list = list.iter().map(|s| styled(s).unwrap_or_else(|| s.clone())).collect();
                Some((kind, ContextValue::StyledStrs(list)))
            }
            _ => None,
        })
        .collect();
    for (kind, value) in long {
        e.insert(kind, value);
    }
    e
}

fn main() -> ExitCode {
    // Mesa's device-select Vulkan layer complains about XDG_RUNTIME_DIR on headless
    // machines; it has nothing to select here. Set before any thread starts.
    if std::env::var_os("NODEVICE_SELECT").is_none() {
        std::env::set_var("NODEVICE_SELECT", "1");
    }
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    // clap exits 2 on usage errors, which here means "no GPU adapter": a bad
    // argument is bad input, exit 1.
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            let e = quoted_within_policy(e);
            // Help and version go to stdout: a failed write there is a failure too.
            let printed = e.print().and_then(|()| std::io::Write::flush(&mut std::io::stdout()));
            return ExitCode::from(if e.use_stderr() || printed.is_err() { 1 } else { 0 });
        }
    };
    let options = LoadOptions {
        allow_outside_assets: cli.allow_outside_assets,
        asset_roots: cli.asset_roots.clone(),
        ..LoadOptions::default()
    };
    let result = match &cli.command {
        Command::Render {
            scene,
            output,
            picture,
            stats,
            time,
            frames,
            fps,
            frame_range,
            skip_existing,
            sim_cache,
            apng,
            turntable,
            spp,
            post,
        } => render::render(render::RenderArgs {
            scene,
            output,
            size: picture.size,
            msaa: picture.msaa,
            camera: picture.camera,
            stats: *stats,
            cull: picture.cull,
            density: picture.density,
            time: *time,
            frames: *frames,
            range: frame_range.clone(),
            skip_existing: *skip_existing,
            sim_cache: sim_cache.as_deref(),
            fps: *fps,
            turntable: *turntable,
            spp: *spp,
            post: post.as_deref(),
            apng: *apng,
            lod: picture.lod,
            options: picture.load_options(options),
        }),
        Command::Bake { scene, output, frames, fps, time, every, solve, sim } => sim_cache::bake(sim_cache::BakeArgs {
            scene,
            output,
            frames: *frames,
            fps: *fps,
            time: *time,
            every: *every,
            options: LoadOptions { cloth_solve: solve.map(Into::into), ..sim.apply(options) },
        }),
        Command::Check { scene } => check(scene, options),
        Command::Explain { scene, naive, json, view, camera, cull, size, time, spp, lod, sim } => {
            explain::explain(explain::ExplainArgs {
                scene,
                naive: *naive,
                json: *json,
                view: *view,
                camera: *camera,
                cull: *cull,
                size: *size,
                time: *time,
                spp: *spp,
                lod: *lod,
                options: sim.apply(options),
            })
        }
        Command::Compare { expected, actual, diff } => match compare::run(expected, actual, diff.as_deref()) {
            Ok(true) => Ok(()),
            Ok(false) => return ExitCode::from(4),
            Err(e) => Err(e),
        },
        Command::Sim(SimCommand::Cloth(args)) => sim::cloth(args),
        Command::Sim(SimCommand::School(args)) => school::school(args),
        Command::Sim(SimCommand::Particles(args)) => particles::particles(args),
        Command::View { scene, picture, frames, screenshot, at } => {
            let options = picture.load_options(options);
            load(scene, options.clone()).and_then(|desc| {
                let args = view::ViewArgs {
                    scene: scene.clone(),
                    size: picture.size,
                    msaa: picture.msaa,
                    camera: picture.camera,
                    cull: picture.cull,
                    density: picture.density,
                    lod: picture.lod,
                    frames: *frames,
                    screenshot: screenshot.clone(),
                    script: at.clone(),
                    options,
                };
                view::run(args, desc)
            })
        }
        Command::Bench {
            scene,
            frames,
            warmup,
            size,
            msaa,
            json,
            density,
            live: Some(fps),
            time,
            lod,
            lod_error,
            sim,
            vs_cpu,
            clusters,
            ..
        } => {
            let config = bench::BenchConfig {
                frames: *frames,
                warmup: *warmup,
                size: *size,
                msaa: *msaa,
                orbit: 0.0,
                settle_ms: 0,
                density: *density,
                lod: lod::LodArgs { lod_error: *lod_error, clusters: *clusters, ..lod::LodArgs::default() },
            };
            run_live(scene, &config, (*time, 1.0 / *fps), (*json, *lod, *vs_cpu), sim.apply(options))
        }
        Command::Bench {
            scene,
            frames,
            warmup,
            mode,
            cull,
            density,
            orbit,
            settle,
            size,
            msaa,
            json,
            plot,
            post,
            lod,
            lod_error,
            clusters,
            sim,
            ..
        } => {
            let config = bench::BenchConfig {
                frames: *frames,
                warmup: *warmup,
                size: *size,
                msaa: *msaa,
                orbit: *orbit,
                settle_ms: *settle,
                density: *density,
                lod: lod::LodArgs { lod_error: *lod_error, clusters: *clusters, ..lod::LodArgs::default() }
                    .with(*lod != lod::BenchLod::Off),
            };
            let output = BenchOutput { json: *json, plot: plot.as_deref() };
            match sim.sim {
                // Without --live the scene stands still at its start: nothing steps.
                Some(_) => Err(glint::Diagnostic::file(scene, "--sim needs --live (without it nothing steps)").into()),
                None => run_bench(scene, &config, (*mode, *cull, *lod), output, post, options),
            }
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // Every error within the message policy, whatever a file named (a
            // texture's name in a render error is not a Diagnostic).
            eprintln!("error: {}", glint::text::shorten(&e.to_string(), 2 * glint::text::MAX_MESSAGE_CHARS));
            ExitCode::from(e.exit_code())
        }
    }
}
