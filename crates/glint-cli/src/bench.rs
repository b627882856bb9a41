//! `glint bench`: steady-state frame cost of a scene: the naive baseline, and
//! the optimized frame culled on the CPU and on the GPU.

use glint::asset::SceneDesc;
use glint::{Error, FrameMode, FrameStats, Gpu, OffscreenTarget, Renderer};
use serde::Serialize;

/// One way of building frames that a bench measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BenchRun {
    /// The naive baseline ([`FrameMode::Naive`]).
    Naive,
    /// The optimized frame, culled this way (`--mode optimized` and `both`).
    Optimized(glint::Culling),
    /// The optimized frame culled this way, beside the others (`--mode all`).
    Culled(glint::Culling),
    /// The optimized frame culled this way at full detail, beside the frames
    /// with levels of detail (`--mode all`, `--lod both`).
    FullDetail(glint::Culling),
}

impl BenchRun {
    /// Its name in reports: `naive`, `optimized`, or (`--mode all`)
    /// `unculled`, `cpu-culled` or `gpu-culled`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Naive => "naive",
            Self::Optimized(_) => "optimized",
            Self::Culled(glint::Culling::Off) => "unculled",
            Self::Culled(glint::Culling::Cpu) => "cpu-culled",
            Self::Culled(glint::Culling::Gpu) => "gpu-culled",
            Self::FullDetail(_) => "full-detail",
        }
    }
}

/// One mode's measurements.
#[derive(Serialize)]
pub struct ModeReport {
    /// [`BenchRun::name`] (the way asked for: `stats.culling` says which way
    /// the device culled), with the post chain in brackets where a bench
    /// compares chains (`--post` given more than once).
    pub mode: String,
    /// Frames measured (after the warm-up).
    pub frames: usize,
    /// Median of the whole frame, ms: from the frame's first call (`submit`)
    /// until the GPU has finished it, as a frame rate sees it.
    pub frame_ms_median: f64,
    /// 95th percentile of the whole frame, ms.
    pub frame_ms_p95: f64,
    /// Frames per second at the median whole frame.
    pub fps: f64,
    /// Median CPU time of `flush`, ms (the shadow pass is apart: `shadow_cpu_ms_median`).
    pub cpu_ms_median: f64,
    /// Median of glint's own CPU work in `flush`, ms: all of it but the encode
    /// and submit stages, whose time is mostly wgpu's recording and submission
    /// (`examples/bare_cubes.rs` measures that floor alone).
    pub own_cpu_ms_median: f64,
    /// 95th percentile CPU time of `flush`, ms.
    pub cpu_ms_p95: f64,
    /// Median GPU time of the forward pass from timestamp queries; null where unsupported.
    pub gpu_ms_median: Option<f64>,
    /// Median CPU time of the shadow pass (planning, culling, batching and
    /// encoding every shadow view), ms.
    pub shadow_cpu_ms_median: f64,
    /// Median GPU time of the shadow pass; null where unsupported or without shadow views.
    pub shadow_gpu_ms_median: Option<f64>,
    /// GPU time binning the view's lights into its clusters, median; `None`
    /// where the CPU binned them (its time is `stage_ms_median.lights`) or untimed.
    pub lights_gpu_ms_median: Option<f64>,
    /// The view's post effects, in order (empty without a chain).
    pub post: Vec<&'static str>,
    /// Median GPU time of each post effect (the chain's order); empty where unsupported.
    pub post_gpu_ms_median: Vec<f64>,
    /// Median CPU time per submitted instance, ns.
    pub ns_per_instance: f64,
    /// Bytes of instance records on the GPU per submitted instance
    /// (`FrameStats::instance_bytes`): 64, or 16 for compact instances.
    pub instance_bytes_per_instance: f64,
    /// Median of cull + queue + sort + batch + upload per submitted instance, ns.
    pub ns_per_instance_cull_sort_batch_upload: f64,
    /// Median CPU time of each stage, ms.
    pub stage_ms_median: glint::render::StageTimes,
    /// Resident memory of the process after the 100th measured frame (or the last,
    /// when fewer), MiB; null where the system does not say (Linux only).
    pub resident_mib_frame_100: Option<f64>,
    /// Resident memory after the last measured frame, MiB; null where unknown.
    pub resident_mib_end: Option<f64>,
    /// The last frame's statistics (steady state).
    pub stats: FrameStats,
}

/// Frame after which `resident_mib_frame_100` is taken: past the warm-up's
/// allocations, so what follows is growth.
const RESIDENT_FRAME: usize = 100;

/// This process's resident memory, MiB (Linux: `/proc/self/statm`'s second field,
/// in pages of 4 KiB).
fn resident_mib() -> Option<f64> {
    let statm = std::fs::read_to_string("/proc/self/statm").ok()?;
    let pages: f64 = statm.split_whitespace().nth(1)?.parse().ok()?;
    Some(pages * 4096.0 / (1024.0 * 1024.0))
}

/// Settings of one bench run.
#[derive(Clone, Copy)]
pub struct BenchConfig {
    /// Measured frames per mode.
    pub frames: usize,
    /// Unmeasured frames first (caches, allocations).
    pub warmup: usize,
    /// Target size.
    pub size: (u32, u32),
    /// MSAA samples.
    pub msaa: u32,
    /// Degrees the camera turns about its target (around the up axis) each frame.
    pub orbit: f32,
    /// Milliseconds to sleep before each frame's flush, outside its times.
    pub settle_ms: u64,
    /// Share of every tile drawn ([`Renderer::set_density`]).
    pub density: f32,
    /// Levels of detail (`--lod`, `--lod-error`).
    pub lod: crate::lod::LodArgs,
}

/// Whether the naive frame may draw `desc`: at most
/// [`MAX_NAIVE_DRAWS`](glint::render::MAX_NAIVE_DRAWS) instances (each one
/// draw, about 5 KB of memory while the frame is built), else an error naming
/// `scene`, before any GPU work.
pub fn check_naive(desc: &SceneDesc, scene: &std::path::Path) -> Result<(), glint::Diagnostic> {
    let (n, most) = (desc.instance_count(), glint::render::MAX_NAIVE_DRAWS);
    if n > most {
        return Err(glint::Diagnostic::file(
            scene,
            format!(
                "the naive frame draws each instance alone, and this scene has {n}, more than the {most} it draws \
                 (about 5 KB of memory each); measure the optimized frame alone (--mode optimized)"
            ),
        ));
    }
    Ok(())
}

/// The view a bench draws: the scene's first camera with its post chain, or
/// with `post` instead when given.
pub fn bench_view(desc: &SceneDesc, post: Option<Vec<glint::scene::PostEffect>>) -> glint::View {
    let view = desc.camera_view(0);
    match post {
        Some(post) => view.with_post(post),
        None => view,
    }
}

/// The `p` quantile (0..=1) of `sorted`, 0 when empty.
pub(crate) fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    let rank = (p * (sorted.len() - 1) as f64).round() as usize;
    sorted[rank.min(sorted.len() - 1)]
}

/// The median of `values` (sorted in place), `None` when empty.
pub(crate) fn median(values: &mut [f64]) -> Option<f64> {
    values.sort_by(f64::total_cmp);
    (!values.is_empty()).then(|| percentile(values, 0.5))
}

fn median_of(frames: &[FrameStats], f: impl Fn(&FrameStats) -> f64) -> f64 {
    let mut v: Vec<f64> = frames.iter().map(f).collect();
    v.sort_by(f64::total_cmp);
    percentile(&v, 0.5)
}

/// Run `config.frames` frames of `desc` built as `run` says and summarise them.
pub fn run_mode(
    gpu: &Gpu,
    desc: &SceneDesc,
    view: &glint::View,
    run: BenchRun,
    config: &BenchConfig,
) -> Result<ModeReport, Error> {
    let (width, height) = config.size;
    let mut target = OffscreenTarget::new(gpu, width, height, config.msaa)?;
    let mut renderer = Renderer::new(gpu);
    renderer.set_density(config.density);
    let lod = match run {
        BenchRun::FullDetail(_) => config.lod.with(false),
        _ => config.lod,
    };
    lod.apply(&mut renderer);
    let view = &match run {
        BenchRun::Naive => {
            renderer.set_mode(FrameMode::Naive);
            view.clone()
        }
        BenchRun::Optimized(culling) | BenchRun::Culled(culling) | BenchRun::FullDetail(culling) => {
            view.clone().with_culling(culling)
        }
    };
    let view = &lod.views(vec![view.clone()]).remove(0);
    let timed = renderer.enable_gpu_timing();
    let mut gpu_ms = Vec::new();
    let mut shadow_gpu_ms = Vec::new();
    let mut lights_gpu_ms = Vec::new();
    let entities = renderer.place_scene(desc).entities;
    let refs: Vec<_> = entities.iter().collect();
    renderer.precompile(&refs, desc.lighting(), config.msaa)?;
    let mut post_gpu_ms: Vec<Vec<f64>> = vec![Vec::new(); view.post.len()];
    let mut frames = Vec::with_capacity(config.frames);
    let mut frame_ms = Vec::with_capacity(config.frames);
    let mut resident_frame_100 = None;
    for i in 0..config.warmup + config.frames {
        let view = &crate::render::turned(view, config.orbit * i as f32);
        let frame_start = std::time::Instant::now();
        // The frame's three calls, with the GPU let finish after the shadow pass and
        // after flush, outside the measured CPU times: a CPU rasterizer's threads
        // would otherwise share the cores with the next call's CPU work. The whole
        // frame runs from the first submit until the GPU has finished the flush
        // (the wait after the shadow pass included).
        for e in &entities {
            renderer.submit(e);
        }
        let shadows = renderer.shadow_pass(view, desc.lighting(), &target)?;
        let _ = gpu.device.poll(wgpu::PollType::wait_indefinitely());
        // `--settle`: the flush's CPU stages start from the same state whatever
        // the GPU's last work took (the thread asleep that long).
        let settle = std::time::Duration::from_millis(config.settle_ms);
        std::thread::sleep(settle);
        let stats = renderer.flush(view, desc.lighting(), &shadows, &mut target)?;
        let _ = gpu.device.poll(wgpu::PollType::wait_indefinitely());
        let whole = (frame_start.elapsed() - settle).as_secs_f64() * 1e3;
        let frame_gpu = renderer.read_gpu_times();
        if i >= config.warmup {
            frames.push(stats);
            frame_ms.push(whole);
            if let Some(times) = frame_gpu {
                gpu_ms.push(times.forward_ms);
                shadow_gpu_ms.extend(times.shadow_ms);
                lights_gpu_ms.extend(times.lights_ms);
                for (all, ms) in post_gpu_ms.iter_mut().zip(&times.post_ms) {
                    all.push(*ms);
                }
            }
            if frames.len() == RESIDENT_FRAME.min(config.frames) {
                resident_frame_100 = resident_mib();
            }
        }
    }
    let resident_end = resident_mib();
    frame_ms.sort_by(f64::total_cmp);
    let frame_ms_median = percentile(&frame_ms, 0.5);
    let mut totals: Vec<f64> = frames.iter().map(|f| f.cpu_ms.total).collect();
    totals.sort_by(f64::total_cmp);
    let last = frames.last().expect("at least one frame").clone();
    let instances = last.instances_submitted.max(1) as f64;
    let per_instance_stages =
        |f: &FrameStats| f.cpu_ms.cull + f.cpu_ms.queue + f.cpu_ms.sort + f.cpu_ms.batch + f.cpu_ms.upload;
    let stage_ms_median = glint::render::StageTimes {
        prepare: median_of(&frames, |f| f.cpu_ms.prepare),
        cull: median_of(&frames, |f| f.cpu_ms.cull),
        queue: median_of(&frames, |f| f.cpu_ms.queue),
        sort: median_of(&frames, |f| f.cpu_ms.sort),
        lights: median_of(&frames, |f| f.cpu_ms.lights),
        batch: median_of(&frames, |f| f.cpu_ms.batch),
        upload: median_of(&frames, |f| f.cpu_ms.upload),
        encode: median_of(&frames, |f| f.cpu_ms.encode),
        submit: median_of(&frames, |f| f.cpu_ms.submit),
        total: percentile(&totals, 0.5),
    };
    Ok(ModeReport {
        mode: run.name().to_owned(),
        frames: config.frames,
        frame_ms_median,
        frame_ms_p95: percentile(&frame_ms, 0.95),
        fps: 1e3 / frame_ms_median.max(1e-9),
        cpu_ms_median: percentile(&totals, 0.5),
        cpu_ms_p95: percentile(&totals, 0.95),
        own_cpu_ms_median: median_of(&frames, |f| f.cpu_ms.total - f.cpu_ms.encode - f.cpu_ms.submit),
        gpu_ms_median: timed.then(|| median(&mut gpu_ms)).flatten(),
        shadow_cpu_ms_median: median_of(&frames, |f| f.passes.shadow.cpu_ms),
        shadow_gpu_ms_median: timed.then(|| median(&mut shadow_gpu_ms)).flatten(),
        lights_gpu_ms_median: timed.then(|| median(&mut lights_gpu_ms)).flatten(),
        post: view.post.iter().map(|e| e.name()).collect(),
        post_gpu_ms_median: post_gpu_ms.iter_mut().filter_map(|all| median(all)).collect(),
        ns_per_instance: percentile(&totals, 0.5) * 1e6 / instances,
        instance_bytes_per_instance: last.instance_bytes as f64 / instances,
        ns_per_instance_cull_sort_batch_upload: median_of(&frames, per_instance_stages) * 1e6 / instances,
        stage_ms_median,
        resident_mib_frame_100: resident_frame_100,
        resident_mib_end: resident_end,
        stats: last,
    })
}

/// One mode's report for people, as lines of text.
pub fn format_mode(r: &ModeReport) -> String {
    let mut text = String::new();
    let s = &r.stage_ms_median;
    let gpu = r.gpu_ms_median.map_or_else(|| "n/a".to_string(), |ms| format!("{ms:.3} ms"));
    text.push_str(&format!(
        "{:>10}: frame {:.3} ms median ({:.1} fps), {:.3} ms p95 (first call until the GPU is done), culled: {}\n",
        r.mode,
        r.frame_ms_median,
        r.fps,
        r.frame_ms_p95,
        r.stats.culling.name()
    ));
    text.push_str(&format!(
        "{:>9}  cpu {:.4} ms median ({:.4} ms glint's own), {:.4} ms p95 | gpu {gpu} median | {:.2} ns/instance ({:.2} ns cull+sort+batch+upload)\n",
        "", r.cpu_ms_median, r.own_cpu_ms_median, r.cpu_ms_p95, r.ns_per_instance, r.ns_per_instance_cull_sort_batch_upload
    ));
    text.push_str(&format!(
        "           stages (median ms): prepare {:.4}  cull {:.4}  queue {:.4}  sort {:.4}  batch {:.4}  upload {:.4}  encode {:.4}  submit {:.4}\n",
        s.prepare, s.cull, s.queue, s.sort, s.batch, s.upload, s.encode, s.submit
    ));
    let st = &r.stats;
    text.push_str(&format!(
        "           frame: {} draws in {} draw calls, {} pipelines bound, {} bind groups, {} instances submitted, {} culled, {} drawn ({} per level of detail), {} triangles, {} bytes uploaded\n",
        st.draws,
        st.draw_calls,
        st.pipelines_bound,
        st.bind_groups_set,
        st.instances_submitted,
        st.instances_culled,
        st.instances_drawn,
        st.instances_per_level.map(|n| n.to_string()).join("/"),
        st.triangles_drawn,
        st.bytes_uploaded.total
    ));
    if let (Some(at_100), Some(end)) = (r.resident_mib_frame_100, r.resident_mib_end) {
        text.push_str(&format!(
            "           resident memory: {at_100:.1} MiB after measured frame {}, {end:.1} MiB at the end ({:+.1} MiB)\n",
            RESIDENT_FRAME.min(r.frames),
            end - at_100
        ));
    }
    if let Some(c) = &st.light_clusters {
        let [x, y, z] = c.grid;
        let gpu = r.lights_gpu_ms_median.map_or_else(|| "n/a".to_string(), |ms| format!("{ms:.3} ms"));
        text.push_str(&format!(
            "           light clusters: {x}x{y}x{z}, binned on the {} | cpu {:.4} ms median | gpu {gpu} median | {} lights visible, {:.2} a cluster, {} at most, {} left out\n",
            if c.on_gpu { "GPU" } else { "CPU" },
            s.lights,
            c.lights_visible,
            c.mean_per_cluster,
            c.max_per_cluster,
            c.overflow
        ));
    }
    if st.shadow_views > 0 {
        let shadow = &st.passes.shadow;
        let gpu = r.shadow_gpu_ms_median.map_or_else(|| "n/a".to_string(), |ms| format!("{ms:.3} ms"));
        text.push_str(&format!(
            "           shadow pass: {} views, {} draws in {} draw calls, {} instances | cpu {:.4} ms median | gpu {gpu} median\n",
            st.shadow_views, shadow.draws, shadow.draw_calls, shadow.instances, r.shadow_cpu_ms_median
        ));
    }
    if !r.post.is_empty() {
        let times: Vec<String> = (r.post.iter().enumerate())
            .map(|(k, name)| match r.post_gpu_ms_median.get(k) {
                Some(ms) => format!("{name} {ms:.3} ms"),
                None => format!("{name} n/a"),
            })
            .collect();
        let total: f64 = r.post_gpu_ms_median.iter().sum();
        text.push_str(&format!(
            "           post chain: {} draws | gpu (median): {} | {total:.3} ms in all\n",
            st.passes.post.draws,
            times.join(", ")
        ));
    }
    text
}

/// Ratios of every pair of runs (the earlier over the later: how many times
/// faster the later is), whole frame and `flush` CPU, as (name, frame, cpu).
pub fn ratios(reports: &[ModeReport]) -> Vec<(String, f64, f64)> {
    let mut out = Vec::new();
    for (k, a) in reports.iter().enumerate() {
        for b in &reports[k + 1..] {
            let name = format!("{} / {}", a.mode, b.mode);
            out.push((name, a.frame_ms_median / b.frame_ms_median, a.cpu_ms_median / b.cpu_ms_median));
        }
    }
    out
}
