//! `glint bench`'s command: which ways of building frames it measures (for
//! each `--post` chain), or the scene as it plays (`--live`), and the report.
//! The measurements themselves are `bench.rs` and `bench_live.rs`.

use crate::{bench, bench_live, load, lod, output, plot, render, CullArg, PostArg};
use clap::ValueEnum;
use glint::asset::LoadOptions;
use glint::{Error, Gpu};
use std::path::Path;

/// `glint bench --mode`.
#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum BenchMode {
    /// The naive baseline, then the optimized frame culled on the CPU and on the GPU.
    All,
    /// The optimized frame, culled as the camera (or --cull) says.
    Optimized,
    /// The naive baseline.
    Naive,
    /// The optimized frame (as with `optimized`), then the naive baseline.
    Both,
}

/// Where `glint bench` reports: JSON or text, and a chart.
pub(crate) struct BenchOutput<'a> {
    pub json: bool,
    pub plot: Option<&'a Path>,
}

/// `glint bench --live`: the whole frame of the scene as it plays.
pub(crate) fn run_live(
    scene: &Path,
    config: &bench::BenchConfig,
    timing: (f32, f32),
    (json, lod, vs_cpu): (bool, lod::BenchLod, bool),
    options: LoadOptions,
) -> Result<(), Error> {
    let desc = load(scene, options)?;
    // Posed a frame at a time: each frame's step is checked, from the one before.
    render::check_sequence(&desc, (timing.0, 1.0 / timing.1), config.frames as u32)?;
    let gpu = Gpu::headless()?;
    let adapter = format!("{} ({:?})", gpu.info().name, gpu.info().backend);
    let mut sides = Vec::new();
    for &on in lod.sides() {
        let config = bench::BenchConfig { lod: config.lod.with(on), ..*config };
        sides.push(bench_live::run(&gpu, desc.clone(), &config, timing)?);
    }
    let compared = bench_live::compare(&sides);
    // The same frames with every school on the CPU, levels as the first side.
    let on_cpu = match vs_cpu {
        true => {
            let mut desc = desc.clone();
            desc.schools.iter_mut().for_each(|s| s.sim = glint::scene::SimPath::Cpu);
            let config = bench::BenchConfig { lod: config.lod.with(lod.sides()[0]), ..*config };
            Some(bench_live::run(&gpu, desc, &config, timing)?)
        }
        false => None,
    };
    let sim = on_cpu.as_ref().map(|cpu| bench_live::compare_sim(&sides[0], cpu));
    let text = match json {
        true => {
            let mut out = serde_json::json!({"scene": scene.display().to_string(), "adapter": adapter, "size": format!("{}x{}", config.size.0, config.size.1), "live": sides[0]});
            if let (Some(full), Some(compared)) = (sides.get(1), &compared) {
                out["full_detail"] = serde_json::to_value(full).expect("report serialises");
                out["lod"] = serde_json::to_value(compared).expect("comparison serialises");
            }
            if let (Some(cpu), Some(sim)) = (&on_cpu, &sim) {
                out["cpu_sim"] = serde_json::to_value(cpu).expect("report serialises");
                out["sim"] = serde_json::to_value(sim).expect("comparison serialises");
            }
            format!("{out}\n")
        }
        false => {
            let mut text: String = sides.iter().chain(&on_cpu).map(|r| live_text(scene, &adapter, config, r)).collect();
            if let Some(c) = &compared {
                text.push_str(&format!(
                    "levels of detail: whole frame {:.2}x faster, {:.2}x fewer triangles, images {:.3}/255 apart (mean), {:.3}/255 at most over a 4x4 block\n",
                    c.frame_speedup, c.triangle_ratio, c.mean_difference, c.block_difference
                ));
            }
            if let Some(c) = &sim {
                text.push_str(&format!(
                    "simulations as asked against every school on the CPU: whole frame {:.2}x faster, pose {:.2} ms against {:.2} ms{}\n",
                    c.frame_speedup,
                    c.pose_ms,
                    c.cpu_pose_ms,
                    if sides[0].simulations.schools.gpu == 0 { " (no school stepped on the GPU: both on the CPU)" } else { "" }
                ));
            }
            text
        }
    };
    Ok(output::print(&text)?)
}

/// One `--live` report for people.
fn live_text(scene: &Path, adapter: &str, config: &bench::BenchConfig, r: &bench_live::LiveReport) -> String {
    format!(
            "{} on {adapter}, {}x{}, {} frames from {} s, {:.4} s a frame, levels of detail {}\n  frame {:.2} ms median ({:.2} p95): pose {:.2} ms, draw (CPU) {:.2} ms, forward pass (GPU) {}, shadows (GPU, {} views) {}\n  simulations: {}; {} particles alive; {} instances; {} triangles drawn ({} in shadows)\n",
            scene.display(),
            config.size.0,
            config.size.1,
            r.frames,
            r.start,
            r.step,
            if r.levels_of_detail { "on" } else { "off" },
            r.frame_ms_median,
            r.frame_ms_p95,
            r.pose_ms_median,
            r.draw_cpu_ms_median,
            r.forward_gpu_ms_median.map_or("n/a".into(), |ms| format!("{ms:.2} ms")),
            r.shadow_views,
            r.shadow_gpu_ms_median.map_or("n/a".into(), |ms| format!("{ms:.2} ms")),
            r.simulations,
            r.particles_alive,
            r.instances,
            r.triangles,
            r.shadow_triangles
        )
}

/// The ways `glint bench` builds frames of `view`: as `--mode` says, with the
/// naive baseline where `with_naive`, and the optimized frame at full detail
/// beside the frames with levels (with `--mode all`, and wherever `--lod both` asks).
fn bench_runs(
    view: &glint::View,
    (mode, cull, lod): (BenchMode, Option<CullArg>, lod::BenchLod),
    with_naive: bool,
) -> Vec<bench::BenchRun> {
    let optimized = bench::BenchRun::Optimized(cull.map_or(view.culling, CullArg::culling));
    let mut runs = match mode {
        BenchMode::All => {
            let culled = [glint::Culling::Cpu, glint::Culling::Gpu].map(bench::BenchRun::Culled);
            with_naive.then_some(bench::BenchRun::Naive).into_iter().chain(culled).collect()
        }
        BenchMode::Optimized => vec![optimized],
        BenchMode::Naive => vec![bench::BenchRun::Naive],
        BenchMode::Both => vec![optimized, bench::BenchRun::Naive],
    };
    if lod == lod::BenchLod::Both || (matches!(mode, BenchMode::All) && lod == lod::BenchLod::On) {
        runs.push(bench::BenchRun::FullDetail(cull.map_or(glint::Culling::Gpu, CullArg::culling)));
    }
    runs
}

pub(crate) fn run_bench(
    scene: &Path,
    config: &bench::BenchConfig,
    (mode, cull, lod): (BenchMode, Option<CullArg>, lod::BenchLod),
    BenchOutput { json, plot }: BenchOutput,
    posts: &[PostArg],
    options: LoadOptions,
) -> Result<(), Error> {
    let bench::BenchConfig { frames, warmup, size, msaa, orbit, settle_ms, density, .. } = *config;
    if frames == 0 {
        return Err(glint::Diagnostic::file(scene, "--frames must be at least 1").into());
    }
    let desc = load(scene, options)?;
    // The naive baseline of a scene past its limit: refused when asked for
    // alone, left out (and said so) beside the others.
    let naive = bench::check_naive(&desc, scene);
    let with_naive = match (mode, naive) {
        (BenchMode::All, Err(e)) => {
            eprintln!("note: no naive baseline: {}", e.message);
            false
        }
        (BenchMode::Naive | BenchMode::Both, Err(e)) => return Err(e.into()),
        (BenchMode::Optimized, _) => false,
        (_, Ok(())) => true,
    };
    if posts.len() > 1 {
        let compared = |what: &str| glint::Diagnostic::file(scene, format!("--post given more than once {what}"));
        if !matches!(mode, BenchMode::Optimized) || lod == lod::BenchLod::Both {
            return Err(compared(
                "compares chains on the optimized frame alone: add --mode optimized (without --lod both)",
            )
            .into());
        }
        if let Some((k, _)) = posts.iter().enumerate().find(|(k, p)| posts[..*k].iter().any(|q| q.0 == p.0)) {
            return Err(
                compared(&format!("names one chain twice (its number {} repeats an earlier one)", k + 1)).into()
            );
        }
    }
    let gpu = Gpu::headless()?;
    // Each chain asked for in turn (the scene's own where none was).
    let chains: Vec<Option<&PostArg>> = if posts.is_empty() { vec![None] } else { posts.iter().map(Some).collect() };
    let optimized_culling = cull.map_or(glint::Culling::Gpu, CullArg::culling);
    let mut reports = Vec::new();
    for chain in &chains {
        let view = bench::bench_view(&desc, chain.map(|c| c.0.clone()));
        for run in bench_runs(&view, (mode, cull, lod), with_naive) {
            let mut report = bench::run_mode(&gpu, &desc, &view, run, config)?;
            if chains.len() > 1 {
                report.mode = format!("{} [{}]", report.mode, report.post.join(" "));
            }
            reports.push(report);
        }
    }
    let speedup = match mode {
        BenchMode::Both => Some(reports[1].cpu_ms_median / reports[0].cpu_ms_median),
        BenchMode::All if with_naive => Some(reports[0].cpu_ms_median / reports[2].cpu_ms_median),
        _ => None,
    };
    let detail = |run: &&bench::ModeReport| run.mode == bench::BenchRun::FullDetail(optimized_culling).name();
    let lod_speedup = reports.iter().find(detail).map(|full| {
        let with_levels = reports.iter().rev().find(|r| !detail(r) && r.mode != "naive").unwrap_or(full);
        serde_json::json!({
            "frame": full.frame_ms_median / with_levels.frame_ms_median,
            "triangles": full.stats.triangles_drawn as f64 / with_levels.stats.triangles_drawn.max(1) as f64,
            "with_levels": with_levels.mode,
        })
    });
    let ratios = bench::ratios(&reports);
    if json {
        let modes: serde_json::Map<String, serde_json::Value> =
            reports.iter().map(|r| (r.mode.to_string(), serde_json::to_value(r).expect("report serialises"))).collect();
        let out = serde_json::json!({
            "scene": scene.display().to_string(),
            "frames": frames,
            "size": format!("{}x{}", size.0, size.1),
            "msaa": msaa,
            "adapter": format!("{} ({:?})", gpu.info().name, gpu.info().backend),
            "orbit_degrees_per_frame": orbit,
            "settle_ms": settle_ms,
            "density": density,
            "modes": modes,
            "speedup": speedup,
            "lod_speedup": lod_speedup,
            "ratios": ratios.iter().map(|(name, frame, cpu)| serde_json::json!({"runs": name, "frame": frame, "cpu": cpu})).collect::<Vec<_>>(),
        });
        output::print(&format!("{out}\n"))?;
    } else {
        let mut text = format!(
            "{} on {} ({:?}), {}x{} {}x MSAA, {frames} frames after {warmup} warm-up\n",
            scene.display(),
            gpu.info().name,
            gpu.info().backend,
            size.0,
            size.1,
            msaa
        );
        for r in &reports {
            text.push_str(&bench::format_mode(r));
        }
        for (name, frame, cpu) in &ratios {
            text.push_str(&format!("{name}: whole frame {frame:.2}x, flush CPU {cpu:.2}x\n"));
        }
        if let Some(lod) = &lod_speedup {
            text.push_str(&format!(
                "levels of detail ({}): whole frame {:.2}x faster, {:.2}x fewer triangles than full detail\n",
                lod["with_levels"], lod["frame"], lod["triangles"]
            ));
        }
        output::print(&text)?;
    }
    if let Some(path) = plot {
        let name = scene.file_name().map_or_else(|| scene.display().to_string(), |n| n.to_string_lossy().into());
        let title = format!("{name}: CPU per stage, {}x{} on {}", size.0, size.1, gpu.info().name);
        plot::stage_chart(path, &title, &reports)?;
    }
    Ok(())
}
