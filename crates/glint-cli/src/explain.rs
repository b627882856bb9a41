//! `glint explain`: a frame as the GPU receives it, for people. Each pass
//! (compute and render) in encoding order, then each of its draw calls with
//! the batches it draws (sort keys decoded: queue, pipeline variant and its
//! shader features, material and mesh by name), the state set before it and
//! the state it kept, its instances and triangles; then the stage costs. With
//! `--naive`, the naive frame of the same view beside it.

use crate::{check_camera, culled, load, output, CullArg};
use glint::asset::LoadOptions;
use glint::render::clusters::MAX_CLUSTER_LIGHTS;
use glint::render::{FrameCalls, FrameMode, PassCalls};
use glint::scene::Transparency;
use glint::{Diagnostic, Error, FrameStats, Gpu, OffscreenTarget, Renderer, World};
use serde::Serialize;
use std::fmt::Write;
use std::path::Path;

/// Frames drawn before the explained one: pipelines are built by the first,
/// and counts culled on the GPU come back a frame or two late.
const WARMUP_FRAMES: usize = 3;

/// Frames whose CPU costs are taken (median), the explained one last.
const COSTED_FRAMES: usize = 5;

/// What `glint explain` was asked for.
pub struct ExplainArgs<'a> {
    pub scene: &'a Path,
    pub naive: bool,
    pub json: bool,
    /// The view of the frame to explain.
    pub view: usize,
    pub camera: Option<usize>,
    pub cull: Option<CullArg>,
    pub size: (u32, u32),
    pub time: f32,
    /// Sub-frames of each frame's accumulated still (1: a frame of its own).
    pub spp: u32,
    /// Levels of detail (`--lod`, `--lod-error`).
    pub lod: crate::lod::LodArgs,
    pub options: LoadOptions,
}

/// One way of building the frame, explained.
#[derive(Serialize)]
struct Explained {
    /// "optimized" or "naive".
    mode: &'static str,
    /// The view's statistics for the explained frame.
    stats: FrameStats,
    /// Median CPU time of the whole flush over the costed frames, ms.
    cpu_ms_median: f64,
    /// The view's passes, in encoding order.
    passes: Vec<PassCalls>,
    /// The view's post effects, in order (the GPU times' `post_ms` are theirs).
    post: Vec<&'static str>,
}

/// Explain the frame as `args` says and print it.
pub fn explain(args: ExplainArgs) -> Result<(), Error> {
    let desc = load(args.scene, args.options.clone())?;
    check_camera(&desc, args.scene, args.camera)?;
    desc.check_pose(args.time)?;
    if args.naive {
        crate::bench::check_naive(&desc, args.scene)?;
    }
    let gpu = Gpu::headless()?;
    let mut modes = vec![explain_mode(&gpu, &desc, &args, FrameMode::Optimized)?];
    if args.naive {
        modes.push(explain_mode(&gpu, &desc, &args, FrameMode::Naive)?);
    }
    // Weighted transparency's error against the exact reference, where both run.
    let weighted = modes[0].stats.transparency == Transparency::Weighted && gpu.fragment_lists();
    let error = if weighted { Some(weighted_error(&gpu, &desc, &args)?) } else { None };
    let adapter = format!("{} ({:?})", gpu.info().name, gpu.info().backend);
    let (width, height) = args.size;
    let text = if args.json {
        let mut json = serde_json::to_value(&modes[0]).expect("explanations serialise");
        json["scene"] = args.scene.display().to_string().into();
        json["adapter"] = adapter.into();
        json["size"] = format!("{width}x{height}").into();
        json["view"] = args.view.into();
        json["spp"] = args.spp.into();
        if let Some(error) = &error {
            json["weighted_error"] = serde_json::to_value(error).expect("errors serialise");
        }
        if let Some(naive) = modes.get(1) {
            json["naive"] = serde_json::to_value(naive).expect("explanations serialise");
            json["ratios"] = serde_json::to_value(Ratios::of(&modes[0], naive)).expect("ratios serialise");
        }
        format!("{json}\n")
    } else {
        let mut text = format!("{}, view {}, {width}x{height} on {adapter}\n", args.scene.display(), args.view);
        if args.spp > 1 {
            let n = args.spp;
            let _ = writeln!(
                text,
                "an accumulated still of {n} sub-frames: below is its last; each draws the frame with its camera jittered, so the still costs about {n} frames, and the last folds it into the mean and runs the post chain on the mean"
            );
        }
        for mode in &modes {
            text.push_str(&describe(mode));
        }
        if let Some(e) = &error {
            let _ = writeln!(
                text,
                "weighted transparency against exact (the same frame with per-pixel lists): mean difference {:.4} of full scale over the picture, {:.4} over the {} pixels that differ; largest {} of 255",
                e.mean, e.mean_differing, e.differing, e.largest
            );
        }
        if let Some(naive) = modes.get(1) {
            let r = Ratios::of(&modes[0], naive);
            let _ = writeln!(
                text,
                "\nnaive / optimized: {:.1}x the draw calls, {:.1}x the pipelines bound, {:.1}x the bind groups set\nCPU time of the flush, naive / optimized: {:.1}x",
                r.draw_calls, r.pipelines_bound, r.bind_groups_set, r.cpu
            );
        }
        text
    };
    Ok(output::print(&text)?)
}

/// How far weighted transparency's picture is from the exact one's.
#[derive(Serialize)]
struct WeightedError {
    /// Mean absolute difference of the colour channels, 0..1, over the picture.
    mean: f64,
    /// The same over the pixels that differ.
    mean_differing: f64,
    /// Pixels that differ.
    differing: usize,
    /// The largest difference of a channel, 0..255.
    largest: u8,
}

/// The explained frame (the optimized one, all its views) drawn with every
/// camera's transparency weighted and exact, compared.
fn weighted_error(gpu: &Gpu, desc: &glint::asset::SceneDesc, args: &ExplainArgs) -> Result<WeightedError, Error> {
    let picture = |transparency| -> Result<image::RgbaImage, Error> {
        let mut target = OffscreenTarget::new(gpu, args.size.0, args.size.1, 1)?;
        let mut renderer = Renderer::new(gpu);
        args.lod.apply(&mut renderer);
        let desc = glint::asset::SceneDesc { transparency, ..desc.clone() };
        let mut world = World::place(desc, &mut renderer)?;
        let views = args.lod.views(culled(world.views(args.camera), args.cull));
        world.pose(args.time, &mut renderer)?;
        world.draw_still(&mut renderer, (&views, &mut target), args.spp)?;
        Ok(target.read_rgba8(gpu)?)
    };
    let (weighted, exact) = (picture(Transparency::Weighted)?, picture(Transparency::Exact)?);
    let pixels: Vec<[u8; 3]> =
        weighted.pixels().zip(exact.pixels()).map(|(w, e)| std::array::from_fn(|c| w.0[c].abs_diff(e.0[c]))).collect();
    let sum = |p: &[u8; 3]| p.iter().map(|&d| f64::from(d)).sum::<f64>();
    let total: f64 = pixels.iter().map(sum).sum();
    let differing = pixels.iter().filter(|p| p.iter().any(|&d| d > 0)).count();
    let channels = |n: usize| (3 * n.max(1)) as f64 * 255.0;
    Ok(WeightedError {
        mean: total / channels(pixels.len()),
        mean_differing: total / channels(differing),
        differing,
        largest: pixels.iter().flatten().copied().max().unwrap_or(0),
    })
}

/// The naive frame's costs over the optimized one's.
#[derive(Serialize)]
struct Ratios {
    draw_calls: f64,
    pipelines_bound: f64,
    bind_groups_set: f64,
    /// Median CPU time of the flush.
    cpu: f64,
}

impl Ratios {
    fn of(optimized: &Explained, naive: &Explained) -> Self {
        let over = |n: u32, o: u32| f64::from(n) / f64::from(o.max(1));
        let (o, n) = (&optimized.stats, &naive.stats);
        Self {
            draw_calls: over(n.draw_calls, o.draw_calls),
            pipelines_bound: over(n.pipelines_bound, o.pipelines_bound),
            bind_groups_set: over(n.bind_groups_set, o.bind_groups_set),
            cpu: naive.cpu_ms_median / optimized.cpu_ms_median.max(1e-9),
        }
    }
}

/// Draw the scene's frame built as `mode` a few times while explaining, and
/// keep the last one's passes for the asked view.
fn explain_mode(
    gpu: &Gpu,
    desc: &glint::asset::SceneDesc,
    args: &ExplainArgs,
    mode: FrameMode,
) -> Result<Explained, Error> {
    let mut target = OffscreenTarget::new(gpu, args.size.0, args.size.1, 1)?;
    let mut renderer = Renderer::new(gpu);
    renderer.set_mode(mode);
    renderer.set_explaining(true);
    // Each pass's GPU time too, where the device has timestamp queries.
    renderer.enable_gpu_timing();
    args.lod.apply(&mut renderer);
    let mut world = World::place(desc.clone(), &mut renderer)?;
    let views = args.lod.views(culled(world.views(args.camera), args.cull));
    if args.view >= views.len() {
        let message = format!("--view {} requested, but the frame has {} views", args.view, views.len());
        return Err(Diagnostic::file(args.scene, message).into());
    }
    world.pose(args.time, &mut renderer)?;
    let mut totals = Vec::new();
    let mut last = Vec::new();
    for _ in 0..WARMUP_FRAMES + COSTED_FRAMES {
        last = world.draw_still(&mut renderer, (&views, &mut target), args.spp)?;
        gpu.check()?;
        // Each frame starts with the GPU idle, so no submission waits on an
        // earlier frame's work (a CPU rasterizer's queue is short).
        gpu.wait()?;
        totals.push(last[args.view].cpu_ms.total);
    }
    renderer.wait_for_counts(&mut last);
    let mut costed = totals.split_off(WARMUP_FRAMES);
    costed.sort_by(f64::total_cmp);
    let calls: &FrameCalls = renderer.explained().expect("explaining");
    let passes = calls.of_view(args.view).into_iter().cloned().collect();
    let mode = match mode {
        FrameMode::Naive => "naive",
        _ => "optimized",
    };
    let post = views[args.view].post.iter().map(|e| e.name()).collect();
    let stats = last.swap_remove(args.view);
    Ok(Explained { mode, stats, cpu_ms_median: costed[costed.len() / 2], passes, post })
}

/// A draw call's lines, after its number.
fn call_text(call: &glint::render::DrawCall) -> String {
    let mut t = String::new();
    let late = if call.late { " (late phase)" } else { "" };
    let _ = writeln!(
        t,
        "{} of {}{late}: {} draws, {} instances, {} triangles",
        call.command, call.what, call.draws, call.instances, call.triangles
    );
    let list = |l: &[String]| if l.is_empty() { "nothing".to_owned() } else { l.join(", ") };
    let _ = writeln!(t, "    set: {}; kept: {}", list(&call.changed), list(&call.kept));
    for b in &call.batches {
        let textures = b.texture_set.map_or(String::new(), |s| format!(" texture set {s},"));
        let _ = writeln!(
            t,
            "    key {}: {} (stage {}){}, pipeline {} [{}],{textures} material {} '{}', mesh {} '{}' level {} ({} triangles), depth {:.3}: {} instances, {} triangles",
            b.key,
            b.queue,
            b.stage,
            if b.blended { " far to near" } else { "" },
            b.pipeline,
            b.features.join(" "),
            b.material,
            b.material_name,
            b.mesh,
            b.mesh_name,
            b.level,
            b.level_triangles,
            b.depth,
            b.instances,
            b.triangles
        );
    }
    t
}

/// The text of one explained frame.
fn describe(e: &Explained) -> String {
    let s = &e.stats;
    let mut t = String::new();
    let _ = writeln!(t, "\n== {} frame ({})", e.mode, s.culled());
    let _ = writeln!(
        t,
        "{} draw calls ({} draws, {} late), {} pipelines bound, {} bind groups set; instances {} submitted, {} drawn, {} culled; {} shadow views",
        s.draw_calls,
        s.draws,
        s.late_draw_calls,
        s.pipelines_bound,
        s.bind_groups_set,
        s.instances_submitted,
        s.instances_drawn,
        s.instances_culled,
        s.shadow_views
    );
    if s.simulations != Default::default() {
        let _ = writeln!(t, "simulations: {}", s.simulations);
    }
    match &s.light_clusters {
        Some(c) => {
            let [x, y, z] = c.grid;
            let binned = match (c.on_gpu, s.gpu.as_ref().and_then(|g| g.lights_ms)) {
                (true, Some(ms)) => {
                    format!("on the GPU by the pass 'bin lights' in {ms:.3} ms (CPU {:.3} ms)", s.cpu_ms.lights)
                }
                (true, None) => format!("on the GPU by the pass 'bin lights' (CPU {:.3} ms)", s.cpu_ms.lights),
                (false, _) => format!("on the CPU in {:.3} ms", s.cpu_ms.lights),
            };
            let _ = writeln!(
                t,
                "light clusters: {x} × {y} tiles of {} px × {z} depth slices ({} clusters, {} empty), binned {binned}; \
                 {} point and spot lights reach them, {:.2} a cluster on average, {} at most; {} entries over the {MAX_CLUSTER_LIGHTS} a cluster holds",
                c.tile_pixels,
                x * y * z,
                c.empty,
                c.lights_visible,
                c.mean_per_cluster,
                c.max_per_cluster,
                c.overflow
            );
        }
        None => {
            let _ = writeln!(t, "light clusters: none (every fragment loops over every light)");
        }
    }
    let _ = writeln!(
        t,
        "transparency: {}",
        match s.transparency {
            Transparency::Sorted => "sorted (blended instances far to near, alpha-blended particle layers in their records' order)",
            Transparency::Weighted => "weighted (blended materials and alpha-blended particles drawn in any order into two half-float sums, 'transparency: weighted sums', composited by the pass that ends the view)",
            Transparency::Exact => "exact (blended materials and alpha-blended particles kept in per-pixel lists, 'transparency: fragment lists', sorted and blended by the pass that ends the view)",
        }
    );
    if let Some(f) = &s.transparent_fragments {
        let dropped = f.appended.saturating_sub(f.held);
        let _ = writeln!(
            t,
            "  {} transparent fragments appended, the lists hold {}: {dropped} dropped",
            f.appended, f.held
        );
    }
    for (k, pass) in e.passes.iter().enumerate() {
        let kind = match pass.kind {
            glint::render::PassType::Compute => "compute",
            glint::render::PassType::Render => "render",
        };
        let _ = writeln!(t, "pass {k}: {kind} '{}' in {}", pass.name, pass.group);
        if !pass.bound.is_empty() {
            let _ = writeln!(t, "  bound at its start: {}", pass.bound.join(", "));
        }
        // Runs of calls that read the same (the naive frame's instances of
        // one entity) are printed once, with their count.
        let mut c = 0;
        while c < pass.draw_calls.len() {
            let text = call_text(&pass.draw_calls[c]);
            let same = pass.draw_calls[c + 1..].iter().take_while(|d| call_text(d) == text).count();
            match same {
                0 => t.push_str(&format!("  call {c}: {text}")),
                n => t.push_str(&format!("  calls {c}–{}, each: {text}", c + n)),
            }
            c += 1 + same;
        }
    }
    let c = &s.cpu_ms;
    let _ = writeln!(
        t,
        "CPU ms (this frame): prepare {:.3}, lights {:.3}, cull {:.3}, queue {:.3}, sort {:.3}, batch {:.3}, upload {:.3}, encode {:.3}, submit {:.3}; whole flush {:.3} (median of {COSTED_FRAMES} frames {:.3})",
        c.prepare, c.lights, c.cull, c.queue, c.sort, c.batch, c.upload, c.encode, c.submit, c.total, e.cpu_ms_median
    );
    if let Some(g) = &s.gpu {
        let post: Vec<String> = (g.post_ms.iter().zip(&e.post)).map(|(ms, name)| format!("{name} {ms:.3}")).collect();
        let shadow = g.shadow_ms.map_or(String::new(), |ms| format!("shadow pass {ms:.3}, "));
        let depth = g.depth_prepass_ms.map_or(String::new(), |ms| format!("depth pre-pass {ms:.3}, "));
        let occlusion = g.ambient_occlusion_ms.map_or(String::new(), |ms| format!("ambient occlusion {ms:.3}, "));
        let lights = g.lights_ms.map_or(String::new(), |ms| format!("light binning {ms:.3}, "));
        let transparency = g.transparency_ms.map_or(String::new(), |ms| format!(" (transparency pass {ms:.3})"));
        let _ = writeln!(
            t,
            "GPU ms (frame {}): {shadow}{lights}{depth}{occlusion}forward pass {:.3}{transparency}, post [{}]",
            g.frame,
            g.forward_ms,
            post.join(", ")
        );
    }
    t
}
