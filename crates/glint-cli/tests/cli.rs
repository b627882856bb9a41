//! The `glint` binary as a user meets it: exit codes, one-line errors with
//! file:line for every class of malformed scene, `check` without a GPU, and
//! `render --stats`.

mod common;

use common::*;
use std::path::Path;
use std::process::Command;

#[test]
fn help_lists_every_subcommand_and_the_exit_codes() {
    for args in [
        &["--help"][..],
        &["render", "--help"],
        &["check", "--help"],
        &["view", "--help"],
        &["sim", "cloth", "--help"],
        &["sim", "school", "--help"],
        &["sim", "particles", "--help"],
    ] {
        let out = glint(args);
        assert_eq!(out.status.code(), Some(0), "{args:?}");
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(text.contains("Exit codes: 0 ok, 1 bad input"), "{args:?}: {text}");
    }
    let top = String::from_utf8_lossy(&glint(&["--help"]).stdout).into_owned();
    assert!(top.contains("render") && top.contains("check") && top.contains("view"));
    let view = String::from_utf8_lossy(&glint(&["view", "--help"]).stdout).into_owned();
    for key in ["W A S D", "Q E", "right mouse", "mouse wheel", "Shift", "F12", "Esc"] {
        assert!(view.contains(key), "view --help lists {key}: {view}");
    }
}

#[test]
fn bad_arguments_are_bad_input() {
    let scene = repo("scenes/showcase.scn");
    let scene = scene.to_str().expect("utf-8 path");
    for args in [
        &["render", scene, "--msaa", "3"][..],
        &["render", scene, "--size", "0x10"],
        &["render", scene, "--size", "big"],
        &["explode"],
    ] {
        assert_eq!(glint(args).status.code(), Some(1), "{args:?}");
    }
}

#[test]
fn check_summarises_the_showcase_without_a_gpu() {
    let out = glint(&["check", repo("scenes/showcase.scn").to_str().expect("path")]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("instances:  12040"), "{text}");
    assert!(text.contains("lights:     3"), "{text}");
    assert!(text.contains("warnings:   0"), "{text}");
}

/// Every class of malformed scene: (file text, line the error must name, words it must say).
const MALFORMED: &[(&str, &str, usize, &str)] = &[
    ("unknown_classname", "{\n\"classname\" \"spaceship\"\n}\n", 2, "unknown classname 'spaceship'"),
    (
        "bad_number",
        "{\n\"classname\" \"entity\"\n\"mesh\" \"cube\"\n\"origin\" \"1 two 3\"\n}\n",
        4,
        "bad number 'two'",
    ),
    (
        "missing_key",
        "{\n\"classname\" \"light_point\"\n\"intensity\" \"2\"\n}\n",
        1,
        "missing the required key \"origin\"",
    ),
    ("unterminated_quote", "{\n\"classname\" \"entity\n}\n", 2, "unterminated quote"),
    ("unterminated_brace", "{\n\"classname\" \"world\"\n", 1, "unterminated block"),
    ("stray_brace", "}\n", 1, "no block open"),
    (
        "unknown_material",
        "{\n\"classname\" \"entity\"\n\"mesh\" \"cube\"\n\"material\" \"unobtainium\"\n}\n",
        4,
        "unknown material 'unobtainium'",
    ),
    (
        "missing_texture",
        "{\n\"classname\" \"material\"\n\"name\" \"m\"\n\"diffuse_map\" \"no/such.png\"\n}\n",
        4,
        "no/such.png: cannot read: ",
    ),
    (
        "negative_count",
        "{\n\"classname\" \"instances\"\n\"mesh\" \"cube\"\n\"count\" \"-1\"\n}\n",
        4,
        "expected 0 or more",
    ),
    (
        "absurd_count",
        "{\n\"classname\" \"instances\"\n\"mesh\" \"cube\"\n\"count\" \"1000000000000\"\n}\n",
        4,
        "more than glint allows",
    ),
    (
        "not_an_image",
        "{\n\"classname\" \"material\"\n\"name\" \"m\"\n\"diffuse_map\" \"self.scn\"\n}\n",
        4,
        "expected a PNG or JPEG",
    ),
    (
        "cloth_collider",
        "{\n\"classname\" \"cloth\"\n\"colliders\" \"plane 0 0 0 0 1 0; cone 1\"\n}\n",
        3,
        "'cone 1' is not a collider",
    ),
];

#[test]
fn every_malformed_scene_is_one_error_line_with_file_and_line() {
    let dir = tempfile::tempdir().expect("tempdir");
    for (name, text, line, words) in MALFORMED {
        let path = dir.path().join(format!("{name}.scn"));
        std::fs::write(&path, text).expect("write");
        std::fs::write(dir.path().join("self.scn"), "not an image").expect("write");
        for command in ["check", "render"] {
            let out = glint(
                &[command, path.to_str().expect("path"), "-o", dir.path().join("x.png").to_str().expect("path")]
                    [..if command == "check" { 2 } else { 4 }],
            );
            assert_eq!(out.status.code(), Some(1), "{name} {command}: {}", stderr(&out));
            let errors = error_lines(&out);
            assert_eq!(errors.len(), 1, "{name} {command}: {}", stderr(&out));
            let want = format!("error: {}:{line}: ", path.display());
            assert!(errors[0].starts_with(&want), "{name}: '{}' should start with '{want}'", errors[0]);
            assert!(errors[0].contains(words), "{name}: '{}' should say '{words}'", errors[0]);
            assert!(!stderr(&out).contains("panicked"), "{name}");
        }
    }
}

#[test]
fn a_missing_scene_file_names_the_file() {
    let out = glint(&["check", "/no/such/scene.scn"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(error_lines(&out)[0].starts_with("error: /no/such/scene.scn: cannot read: "), "{}", stderr(&out));
}

#[test]
fn unknown_keys_warn_with_file_and_line_but_succeed() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("warn.scn");
    std::fs::write(&path, "{\n\"classname\" \"entity\"\n\"mesh\" \"cube\"\n\"colour\" \"red\"\n}\n").expect("write");
    let out = glint(&["check", path.to_str().expect("path")]);
    assert_eq!(out.status.code(), Some(0));
    assert!(stderr(&out).contains(&format!("warning: {}:4: unknown key 'colour'", path.display())), "{}", stderr(&out));
}

#[test]
fn no_adapter_is_exit_code_2_with_the_fix() {
    // DX12 is never compiled in on Linux, so asking for it finds no adapter.
    let out = Command::new(env!("CARGO_BIN_EXE_glint"))
        .args(["render", repo("tests/scenes/ortho.scn").to_str().expect("path"), "-o", "/tmp/glint-never-written.png"])
        .env("WGPU_BACKEND", if cfg!(windows) { "metal" } else { "dx12" })
        .output()
        .expect("run glint");
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let errors = error_lines(&out);
    assert_eq!(errors.len(), 1, "{}", stderr(&out));
    assert!(errors[0].contains("no GPU adapter found"), "{}", errors[0]);
    if cfg!(target_os = "linux") {
        assert!(errors[0].contains("apt-get install mesa-vulkan-drivers"), "{}", errors[0]);
    }
}

#[test]
fn render_writes_the_png_and_prints_stats_json() {
    let dir = tempfile::tempdir().expect("tempdir");
    let png = dir.path().join("showcase.png");
    let out = glint(&[
        "render",
        repo("scenes/showcase.scn").to_str().expect("path"),
        "-o",
        png.to_str().expect("path"),
        "--size",
        "320x180",
        "--stats",
        // The draws counted below are at full detail (a level the GPU picks is a draw of its own).
        "--lod",
        "off",
    ]);
    if out.status.code() == Some(2) && std::env::var("GLINT_REQUIRE_ADAPTER").as_deref() != Ok("1") {
        eprintln!("skipping: no GPU adapter ({})", stderr(&out));
        return;
    }
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let stats: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object on stdout");
    for key in [
        "draw_calls",
        "draws",
        "pipelines_bound",
        "bind_groups_set",
        "bytes_uploaded",
        "instances_submitted",
        "instances_drawn",
        "cpu_ms",
    ] {
        assert!(stats.get(key).is_some(), "missing {key}: {stats}");
    }
    assert_eq!(stats["instances_submitted"], 12040);
    let (drawn, culled) =
        (stats["instances_drawn"].as_u64().expect("n"), stats["instances_culled"].as_u64().expect("n"));
    assert!(culled > 1000, "the camera sees part of the gravel field: {culled} culled");
    assert_eq!(drawn + culled, 12040);
    // At full detail, every instance drawn is at level 0, and each draws its mesh's triangles.
    assert_eq!(stats["instances_per_level"], serde_json::json!([drawn, 0, 0, 0, 0]));
    assert!(stats["triangles_drawn"].as_u64().expect("n") >= 2 * drawn, "{stats}");
    // 11 render tasks (mesh × material pairs) plus the sky, in fewer calls: batches
    // sharing pipeline and texture set go in one multi-draw-indirect call.
    assert_eq!(stats["draws"], 12);
    assert!(stats["draw_calls"].as_u64().expect("n") < 12, "{stats}");
    assert!(stats["cpu_ms"]["total"].as_f64().expect("number") > 0.0);
    assert!(stats["bytes_uploaded"]["textures"].as_u64().expect("number") > 0);
    // The sun's 4 cascades and the two point lights' cube faces.
    assert_eq!(stats["shadow_views"], 4 + 2 * 6);
    assert!(stats["passes"]["shadow"]["draws"].as_u64().expect("n") > 16, "{stats}");
    let image = std::fs::read(&png).expect("png written");
    assert_eq!(&image[1..4], b"PNG");

    let scene = repo("scenes/showcase.scn");
    let args = ["render", scene.to_str().expect("path"), "-o", png.to_str().expect("path"), "--size", "64x36"];
    let out = glint(&[&args[..], &["--stats", "--cull", "off"]].concat());
    let all: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!((all["instances_drawn"].as_u64(), all["instances_culled"].as_u64()), (Some(12040), Some(0)));
    // The one frame's counts, counted on the GPU (waited for) and on the CPU, agree.
    let counts = |cull: &str| {
        let out = glint(&[&args[..], &["--stats", "--cull", cull]].concat());
        let s: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
        (s["culling"].clone(), s["instances_drawn"].as_u64(), s["instances_culled"].as_u64())
    };
    let (on_gpu, on_cpu) = (counts("gpu"), counts("cpu"));
    assert_eq!((on_gpu.1, on_gpu.2), (on_cpu.1, on_cpu.2), "{on_gpu:?} {on_cpu:?}");
    assert!(on_cpu.1.is_some_and(|drawn| drawn > 0 && drawn < 12040));
}

#[test]
fn density_scales_every_tile_on_both_culling_paths() {
    // tiles.scn: 6,000 cones in 8 × 8 tiles, its block drawing half of each.
    let dir = tempfile::tempdir().expect("tempdir");
    let png = dir.path().join("tiles.png");
    let (scene, png) = (repo("tests/scenes/tiles.scn"), png.to_str().expect("path").to_owned());
    let stats = |density: &str, cull: &str| {
        let args = ["render", scene.to_str().expect("path"), "-o", &png, "--size", "64x64", "--stats"];
        let out = glint(&[&args[..], &["--density", density, "--cull", cull]].concat());
        assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
        let s: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
        let n = |key: &str| s[key].as_u64().expect(key);
        // The ground plane is one instance more, untiled.
        (n("instances_drawn") - 1, n("tiles_tested"), n("tiles_drawn"))
    };
    if glint(&["render", scene.to_str().expect("path"), "-o", &png, "--size", "8x8"]).status.code() == Some(2)
        && std::env::var("GLINT_REQUIRE_ADAPTER").as_deref() != Ok("1")
    {
        eprintln!("skipping: no GPU adapter");
        return;
    }
    let (half, tested, drawn) = stats("1", "off");
    assert!((2_968..=3_032).contains(&half), "half of each tile, within one a tile: {half}");
    assert_eq!((tested, drawn), (0, 64), "culling off tests no tile");
    let (quarter, _, _) = stats("0.5", "off");
    assert!((1_436..=1_564).contains(&quarter), "a quarter: {quarter}");
    assert_eq!(stats("0", "off").0, 0);
    let on_cpu = stats("0.5", "cpu");
    assert!(on_cpu.0 < quarter && on_cpu.1 == 64 && on_cpu.2 < 64, "{on_cpu:?}");
    assert_eq!(stats("0.5", "gpu"), on_cpu, "counted on the GPU, the same");
    let out = glint(&["render", scene.to_str().expect("path"), "-o", &png, "--density", "1.5"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains("from 0 to 1"), "{}", stderr(&out));
}

#[test]
fn time_of_day_overrides_the_scene_s_hour() {
    // glare.scn is set at 17.2; at noon it draws the library's noon reference.
    let dir = tempfile::tempdir().expect("tempdir");
    let png = dir.path().join("noon.png");
    let (scene, png) = (repo("tests/scenes/glare.scn"), png.to_str().expect("path").to_owned());
    let args = ["render", scene.to_str().expect("path"), "-o", &png, "--size", "256x256", "--time", "0.5"];
    let out = glint(&[&args[..], &["--time-of-day", "12"]].concat());
    if out.status.code() == Some(2) && std::env::var("GLINT_REQUIRE_ADAPTER").as_deref() != Ok("1") {
        eprintln!("skipping: no GPU adapter");
        return;
    }
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let reference = repo("tests/reference/glare_noon.png");
    let compared = glint(&["compare", reference.to_str().expect("path"), &png]);
    assert_eq!(compared.status.code(), Some(0), "{}", stderr(&compared));
    let out = glint(&[&args[..], &["--time-of-day", "25"]].concat());
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains("from 0 to 24"), "{}", stderr(&out));
}

#[test]
fn render_draws_every_camera_with_a_viewport_unless_one_is_picked() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (png, picked) = (dir.path().join("split.png"), dir.path().join("picked.png"));
    let scene = repo("scenes/split.scn");
    let args = ["render", scene.to_str().expect("path"), "--size", "64x32", "--msaa", "1", "--stats", "-o"];
    let out = glint(&[&args[..], &[png.to_str().expect("path")]].concat());
    if out.status.code() == Some(2) && std::env::var("GLINT_REQUIRE_ADAPTER").as_deref() != Ok("1") {
        eprintln!("skipping: no GPU adapter ({})", stderr(&out));
        return;
    }
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let stats: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    let views = stats["views"].as_array().expect("one statistics object per view");
    assert_eq!(views.len(), 2, "{stats}");
    assert!(views.iter().all(|v| v["draws"].as_u64().is_some_and(|d| d > 1)), "{stats}");
    // `--camera 1`: that camera alone over the whole image, the stats one object.
    let out = glint(&[&args[..], &[picked.to_str().expect("path"), "--camera", "1"]].concat());
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let one: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert!(one.get("views").is_none() && one["draws"] == views[1]["draws"], "{one}");
    let (split, alone) = (image::open(&png).expect("png").into_rgb8(), image::open(&picked).expect("png").into_rgb8());
    assert_ne!(split, alone, "two views, not the second camera alone");
    // A viewport outside the image is the camera block's key, at its line.
    let bad = dir.path().join("bad.scn");
    std::fs::write(&bad, "{\n\"classname\" \"camera\"\n\"viewport\" \"0.5 0 1 1\"\n}\n").expect("write");
    let out = glint(&["render", bad.to_str().expect("path"), "-o", png.to_str().expect("path")]);
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains("bad.scn:3: \"viewport\""), "{}", stderr(&out));
}

#[test]
fn bench_reports_naive_cpu_culled_and_gpu_culled_side_by_side_as_json() {
    let scene = repo("tests/scenes/ortho.scn");
    let scene = scene.to_str().expect("path");
    let args = ["bench", scene, "--frames", "3", "--warmup", "1", "--size", "64x64", "--settle", "1", "--json"];
    let out = glint(&args);
    if out.status.code() == Some(2) && std::env::var("GLINT_REQUIRE_ADAPTER").as_deref() != Ok("1") {
        eprintln!("skipping: no GPU adapter");
        return;
    }
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    assert_eq!((&report["frames"], &report["settle_ms"]), (&3.into(), &1.into()));
    assert!(report["scene"].as_str().expect("scene").ends_with("ortho.scn"));
    for mode in ["naive", "cpu-culled", "gpu-culled"] {
        let m = &report["modes"][mode];
        let own = m["own_cpu_ms_median"].as_f64().expect("own_cpu_ms_median");
        assert!(own > 0.0 && own <= m["cpu_ms_median"].as_f64().expect("cpu"), "{mode}: {m}");
        assert_eq!(m["instance_bytes_per_instance"], 64.0, "full instances: {m}");
        for key in ["cpu_ms_median", "cpu_ms_p95", "ns_per_instance"] {
            assert!(m[key].as_f64().expect(key) > 0.0, "{mode}.{key}: {m}");
        }
        let gpu_ms = m.get("gpu_ms_median").expect("present, null where unsupported");
        assert!(gpu_ms.is_null() || gpu_ms.as_f64().expect("number") > 0.0, "{gpu_ms}");
        // Each frame holds its GPU passes and its CPU work, so its median is never
        // shorter than theirs.
        let frame = m["frame_ms_median"].as_f64().expect("frame_ms_median");
        for part in ["gpu_ms_median", "shadow_gpu_ms_median", "cpu_ms_median", "shadow_cpu_ms_median"] {
            assert!(frame >= m[part].as_f64().unwrap_or(0.0), "{part}: {m}");
        }
        assert!(m["frame_ms_p95"].as_f64().expect("p95") >= frame, "{m}");
        let fps = m["fps"].as_f64().expect("fps");
        assert!((fps * frame - 1000.0).abs() < 1e-6 * 1000.0, "fps is 1000 / frame_ms_median: {m}");
        assert!(m["stats"].get("instances_culled").is_some() && m["stats"].get("pipelines_compiled").is_some());
        // Resident memory after frame 100 (here the third and last) and at the end:
        // a process holding a GPU device has far more than a megabyte resident.
        assert_eq!(m["frames"], 3, "{m}");
        if cfg!(target_os = "linux") {
            for key in ["resident_mib_frame_100", "resident_mib_end"] {
                assert!(m[key].as_f64().is_some_and(|mib| mib > 1.0), "{key}: {m}");
            }
        }
    }
    // Ortho scene: plane + 9 cubes. Optimized: 2 draws; naive: one per instance.
    for mode in ["cpu-culled", "gpu-culled"] {
        assert_eq!(report["modes"][mode]["stats"]["draws"], 2);
        assert_eq!(report["modes"][mode]["stats"]["pipelines_compiled"], 0, "precompiled before the first frame");
    }
    assert_eq!(report["modes"]["cpu-culled"]["stats"]["culling"], "cpu");
    assert_eq!(report["modes"]["naive"]["stats"]["draws"], 10);
    assert_eq!(report["modes"]["naive"]["stats"]["draw_calls"], 10);
    assert!(report["speedup"].as_f64().expect("speedup") > 0.0);
    // Each pair of runs, the earlier over the later.
    let ratios = report["ratios"].as_array().expect("ratios");
    let names: Vec<&str> = ratios.iter().map(|r| r["runs"].as_str().expect("runs")).collect();
    let expected = [
        "naive / cpu-culled",
        "naive / gpu-culled",
        "naive / full-detail",
        "cpu-culled / gpu-culled",
        "cpu-culled / full-detail",
        "gpu-culled / full-detail",
    ];
    assert_eq!(names, expected);
    // Levels of detail beside full detail: cubes and a plane have no coarser
    // levels, so the same draws and triangles.
    assert_eq!(report["modes"]["full-detail"]["stats"]["draws"], 2);
    assert_eq!(report["lod_speedup"]["triangles"], 1.0);
    assert!(ratios.iter().all(|r| r["frame"].as_f64().is_some_and(|x| x > 0.0)));
    // One way alone keeps the name "optimized", culled as asked.
    let out = glint(&[&args[..], &["--mode", "optimized", "--cull", "cpu"]].concat());
    let one: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    assert_eq!(one["modes"].as_object().map(|m| m.len()), Some(1));
    assert_eq!(one["modes"]["optimized"]["stats"]["culling"], "cpu");
    assert_eq!(glint(&["bench", scene, "--frames", "0"]).status.code(), Some(1));
    // Post chains compared in one run, each report naming its chain and
    // timing each of its effects where the device has timestamps.
    let chains = ["--mode", "optimized", "--post", "tonemap fxaa", "--post", "tonemap smaa"];
    let out = glint(&[&args[..], &chains].concat());
    let both: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    let smaa = &both["modes"]["optimized [tonemap smaa]"];
    assert_eq!(both["modes"]["optimized [tonemap fxaa]"]["post"], serde_json::json!(["tonemap", "fxaa"]));
    assert_eq!(smaa["stats"]["passes"]["post"]["draws"], 4, "tonemap, and SMAA's three passes");
    let timed = smaa["post_gpu_ms_median"].as_array().expect("times");
    assert!(timed.is_empty() || timed.len() == 2, "one time per effect: {timed:?}");
    for (extra, says) in [
        (&["--post", "tonemap", "--post", "tonemap smaa"][..], "add --mode optimized"),
        (&["--mode", "optimized", "--post", "fxaa", "--post", "fxaa"], "names one chain twice"),
    ] {
        let out = glint(&[&args[..], extra].concat());
        assert_eq!(out.status.code(), Some(1), "{extra:?}: {}", stderr(&out));
        assert!(stderr(&out).contains(says), "{extra:?}: {}", stderr(&out));
    }
}

#[test]
fn bench_plots_the_stage_breakdown() {
    let dir = tempfile::tempdir().expect("temp dir");
    let chart = dir.path().join("chart.png");
    let scene = repo("tests/scenes/ortho.scn");
    let scene = scene.to_str().expect("path");
    let plot = |path: &str, mode: &str| {
        glint(&["bench", scene, "--frames", "2", "--size", "32x32", "--mode", mode, "--plot", path])
    };
    let out = plot(chart.to_str().expect("path"), "both");
    if out.status.code() == Some(2) && std::env::var("GLINT_REQUIRE_ADAPTER").as_deref() != Ok("1") {
        eprintln!("skipping: no GPU adapter");
        return;
    }
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let image = image::open(&chart).expect("a PNG").to_rgb8();
    assert_eq!(image.dimensions(), (2 * 560, 380), "one panel per mode");
    let dark = image.pixels().filter(|p| p.0.iter().all(|&c| c < 100)).count();
    assert!(dark > 500, "axes and labels are drawn: {dark} dark pixels");
    let one = plot(chart.to_str().expect("path"), "optimized");
    assert_eq!(one.status.code(), Some(0));
    assert_eq!(image::image_dimensions(&chart).expect("png"), (560, 380));
    let nowhere = dir.path().join("missing/chart.png");
    let out = plot(nowhere.to_str().expect("path"), "optimized");
    assert_eq!(out.status.code(), Some(1), "an unwritable chart path is bad input");
    assert!(stderr(&out).contains("chart"), "{}", stderr(&out));
}

#[test]
fn models_render_and_check_directly() {
    let model = repo("tests/models/two_materials.obj");
    let model = model.to_str().expect("path");
    let out = glint(&["check", model]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let summary = String::from_utf8_lossy(&out.stdout);
    assert!(summary.contains("3 parts, 3 materials, 1 textures, 6 triangles"), "{summary}");
    assert_eq!(stderr(&out).lines().filter(|l| l.starts_with("warning:")).count(), 2, "{}", stderr(&out));
    let out = glint(&["check", repo("tests/models/skinned.glb").to_str().expect("path")]);
    let summary = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(summary.contains("animation 'bend': 1 channels, 1.00 s"), "{summary}");
    assert!(summary.contains("skin 'arm': 2 joints"), "{summary}");

    let dir = tempfile::tempdir().expect("temp dir");
    let png = dir.path().join("model.png");
    let out = glint(&["render", model, "-o", png.to_str().expect("path"), "--size", "48x48", "--stats"]);
    if out.status.code() == Some(2) && std::env::var("GLINT_REQUIRE_ADAPTER").as_deref() != Ok("1") {
        eprintln!("skipping: no GPU adapter");
        return;
    }
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let stats: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(stats["draws"], 4, "three parts and the sky");
    assert_eq!(image::image_dimensions(&png).expect("png"), (48, 48));

    let at = |time: &str| {
        let time = format!("--time={time}");
        glint(&["render", model, "-o", png.to_str().expect("path"), "--size", "16x16", &time])
    };
    assert_eq!(at("0.5").status.code(), Some(0), "a still model renders at any time");
    let negative = at("-1");
    assert_eq!(negative.status.code(), Some(1));
    assert!(stderr(&negative).contains("not a time"), "{}", stderr(&negative));

    let bad = dir.path().join("bad.obj");
    std::fs::write(&bad, "v 0 0 0\nv 1 0\n").expect("write");
    let out = glint(&["check", bad.to_str().expect("path")]);
    assert_eq!(out.status.code(), Some(1));
    assert!(error_lines(&out).iter().any(|l| l.contains("bad.obj:2:")), "{}", stderr(&out));
}

#[test]
fn render_writes_numbered_frame_sequences_of_animations() {
    let model = repo("tests/models/animated.gltf");
    let model = model.to_str().expect("path");
    let dir = tempfile::tempdir().expect("temp dir");
    let pattern = dir.path().join("frames/%03d.png");
    let pattern = pattern.to_str().expect("path");
    let args = ["render", model, "-o", pattern, "--size", "32x32", "--frames", "3", "--fps", "2"];
    let out = glint(&args);
    if out.status.code() == Some(2) && std::env::var("GLINT_REQUIRE_ADAPTER").as_deref() != Ok("1") {
        eprintln!("skipping: no GPU adapter");
        return;
    }
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let frame = |k: u32| image::open(dir.path().join(format!("frames/{k:03}.png"))).expect("frame written").to_rgb8();
    let (first, last) = (frame(0), frame(2));
    assert_ne!(first, last, "t = 0 and t = 1 differ: the quad slid");
    assert!(!dir.path().join("frames/003.png").exists(), "exactly three frames");
    let single = glint(&["render", model, "-o", dir.path().join("one.png").to_str().expect("path"), "--frames", "2"]);
    assert_eq!(single.status.code(), Some(1), "several frames need a numbered name");
    assert!(stderr(&single).contains("%04d"), "{}", stderr(&single));
}

#[test]
fn render_steps_a_cloth_to_the_time_and_refuses_an_endless_one() {
    let scene = repo("tests/scenes/cloth_debug.scn");
    let scene = scene.to_str().expect("path");
    let dir = tempfile::tempdir().expect("temp dir");
    let png = |name: &str| dir.path().join(name).to_str().expect("path").to_string();
    let render = |time: &str, out: &str| glint(&["render", scene, "-o", out, "--size", "48x48", "--time", time]);
    let (rest, swung) = (render("0", &png("rest.png")), render("0.6", &png("swung.png")));
    if rest.status.code() == Some(2) && std::env::var("GLINT_REQUIRE_ADAPTER").as_deref() != Ok("1") {
        eprintln!("skipping: no GPU adapter");
        return;
    }
    assert_eq!((rest.status.code(), swung.status.code()), (Some(0), Some(0)), "{}{}", stderr(&rest), stderr(&swung));
    let read = |name: &str| image::open(dir.path().join(name)).expect("written").to_rgb8();
    assert_ne!(read("rest.png"), read("swung.png"), "the cloth moved between 0 and 0.6 s");
    let endless = render("1e9", &png("never.png"));
    assert_eq!(endless.status.code(), Some(1), "{}", stderr(&endless));
    let want = format!("error: {scene}:23: cloth: time 1000000000 s is");
    assert!(stderr(&endless).contains(&want), "'{}' should contain '{want}'", stderr(&endless));
}

#[test]
fn render_solves_cloth_on_the_gpu_where_asked_and_says_where_gl_cannot() {
    // The scene's two cloths ask for the GPU; `--solve converged` overrides
    // it, and GL, which has no compute path, solves them on the CPU and says so.
    let scene = repo("tests/scenes/cloth_gpu.scn");
    let scene = scene.to_str().expect("path");
    let dir = tempfile::tempdir().expect("temp dir");
    let png = |name: &str| dir.path().join(name).to_str().expect("path").to_string();
    let render = |backend: &str, extra: &[&str], out: &str| {
        let args = [&["render", scene, "-o", out, "--size", "64x64", "--time", "0.3", "--stats"][..], extra].concat();
        Command::new(env!("CARGO_BIN_EXE_glint")).args(args).env("WGPU_BACKEND", backend).output().expect("run glint")
    };
    let gpu = render("vulkan", &[], &png("gpu.png"));
    if no_adapter(&gpu) {
        return;
    }
    assert_eq!(gpu.status.code(), Some(0), "{}", stderr(&gpu));
    let stats: serde_json::Value = serde_json::from_slice(&gpu.stdout).expect("stats JSON");
    let cloths = &stats["simulations"]["cloths"];
    assert_eq!(cloths["cpu"].as_u64().zip(cloths["gpu"].as_u64()), Some((0, 2)), "{stats}");
    let cpu = render("vulkan", &["--solve", "converged"], &png("cpu.png"));
    let stats: serde_json::Value = serde_json::from_slice(&cpu.stdout).expect("stats JSON");
    assert_eq!(stats["simulations"]["cloths"]["cpu"].as_u64(), Some(2), "{stats}");
    let gl = render("gl", &["--solve", "gpu"], &png("gl.png"));
    assert_eq!(gl.status.code(), Some(0), "{}", stderr(&gl));
    let says = "cloth (line 26): solved on the CPU (converged): the renderer has no compute path";
    assert!(stderr(&gl).contains(says), "{}", stderr(&gl));
    let compare = glint(&["compare", &png("cpu.png"), &png("gpu.png")]);
    assert_eq!(compare.status.code(), Some(0), "the GPU's drape is the converged one's: {}", stderr(&compare));
}

#[test]
fn outside_assets_are_read_only_when_allowed() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::create_dir(dir.path().join("model")).expect("mkdir");
    std::fs::write(dir.path().join("shared.mtl"), "newmtl red\nKd 1 0 0\n").expect("write mtl");
    let obj = dir.path().join("model/tri.obj");
    std::fs::write(&obj, "mtllib ../shared.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n").expect("write obj");
    let obj = obj.to_str().expect("path");
    let refused = glint(&["check", obj]);
    assert_eq!(refused.status.code(), Some(0), "a warning, not a failure");
    assert!(String::from_utf8_lossy(&refused.stdout).contains("0 materials"));
    assert!(stderr(&refused).contains("outside the model's folder"), "{}", stderr(&refused));
    let allowed = glint(&["check", obj, "--allow-outside-assets"]);
    assert_eq!(allowed.status.code(), Some(0), "{}", stderr(&allowed));
    assert!(String::from_utf8_lossy(&allowed.stdout).contains("1 materials"), "{}", stderr(&allowed));
}

#[test]
fn scenes_read_only_inside_their_asset_roots() {
    // The scene's folder is its root (the tests run glint from the project root,
    // which does not hold the temporary folder); --asset-root widens it.
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::create_dir(dir.path().join("scenes")).expect("mkdir");
    std::fs::create_dir(dir.path().join("textures")).expect("mkdir");
    let texture = dir.path().join("textures/t.png");
    image::RgbaImage::from_pixel(2, 2, image::Rgba([9, 9, 9, 255])).save(&texture).expect("png");
    let scene = dir.path().join("scenes/s.scn");
    std::fs::write(&scene, "{\n\"classname\" \"material\"\n\"name\" \"m\"\n\"diffuse_map\" \"../textures/t.png\"\n}\n")
        .expect("write");
    let scene = scene.to_str().expect("path");
    let refused = glint(&["check", scene]);
    assert_eq!(refused.status.code(), Some(1), "{}", stderr(&refused));
    let lines = error_lines(&refused);
    assert_eq!(lines.len(), 1, "{lines:?}");
    assert!(
        lines[0].starts_with(&format!("error: {scene}:4: \"diffuse_map\": '../textures/t.png' points outside")),
        "{lines:?}"
    );
    let root = dir.path().join("textures");
    let widened = glint(&["check", scene, "--asset-root", root.to_str().expect("path")]);
    assert_eq!(widened.status.code(), Some(0), "{}", stderr(&widened));
    assert_eq!(glint(&["check", scene, "--allow-outside-assets"]).status.code(), Some(0));
}

#[test]
fn check_refuses_shadow_maps_that_render_would_refuse() {
    // Three suns at 8192² need 3 GiB of shadow maps: render panicked in wgpu while
    // check said ok. Now both stop at the light that crosses the 1 GiB limit.
    let dir = tempfile::tempdir().expect("temp dir");
    let sun = "{\n\"classname\" \"light_directional\"\n\"direction\" \"0 -1 0\"\n\"shadows\" \"1\"\n\"shadow_map_size\" \"8192\"\n}\n";
    let scene = dir.path().join("suns.scn");
    std::fs::write(&scene, sun.repeat(3)).expect("write");
    let scene = scene.to_str().expect("path");
    for command in ["check", "render"] {
        let out = glint(&[command, scene, "-o", "/dev/null"][..if command == "check" { 2 } else { 4 }]);
        assert_eq!(out.status.code(), Some(1), "{command}: {}", stderr(&out));
        let lines = error_lines(&out);
        assert!(
            lines.len() == 1
                && lines[0].starts_with(&format!("error: {scene}:7: with this light the shadow maps need 2048 MiB")),
            "{command}: {lines:?}"
        );
    }
}

#[test]
fn results_on_a_full_stdout_are_an_error_not_a_panic_or_success() {
    let scene = repo("tests/scenes/ortho.scn");
    let scene = scene.to_str().expect("path");
    let Some(out) = glint_to_full_stdout(&["check", scene]) else { return };
    assert_write_failed(&out, "standard output");
    let sheet = ["sim", "cloth", "--sheet", "0.2,0.1", "--resolution", "5,3", "--fix", "x<=0.05", "--steps", "2"];
    let out = glint_to_full_stdout(&[&sheet[..], &["--bench"]].concat()).expect("opened before");
    assert_write_failed(&out, "standard output");
    // The trajectory written to standard output, and to a full device by name.
    let out = glint_to_full_stdout(&[&sheet[..], &["--out", "/dev/stdout"]].concat()).expect("opened before");
    assert_write_failed(&out, "/dev/stdout");
    let out = glint(&[&sheet[..], &["--out", "/dev/full"]].concat());
    assert_write_failed(&out, "/dev/full");
    let out = glint_to_full_stdout(&["--help"]).expect("opened before");
    assert_eq!(out.status.code(), Some(1), "help that cannot be printed is not a success");
    let dir = tempfile::tempdir().expect("temp dir");
    let png = dir.path().join("a.png");
    let png = png.to_str().expect("path");
    let out = glint_to_full_stdout(&["render", scene, "-o", png, "--size", "16x16", "--stats"]).expect("opened before");
    if no_adapter(&out) {
        return;
    }
    assert_write_failed(&out, "standard output");
    let out = glint_to_full_stdout(&["bench", scene, "--frames", "2", "--warmup", "0", "--size", "16x16"])
        .expect("opened before");
    assert_write_failed(&out, "standard output");
    let out = glint_to_full_stdout(&["bench", scene, "--frames", "2", "--size", "16x16", "--json"]).expect("opened");
    assert_write_failed(&out, "standard output");
}

#[test]
fn images_that_cannot_be_written_are_an_error_with_the_path() {
    let scene = repo("tests/scenes/ortho.scn");
    let scene = scene.to_str().expect("path");
    let out = glint(&["render", scene, "-o", "/dev/full", "--size", "16x16"]);
    if no_adapter(&out) {
        return;
    }
    assert_write_failed(&out, "/dev/full");
    // procfs takes the open but refuses the write (EIO).
    if Path::new("/proc/version").exists() {
        let out = glint(&["render", scene, "-o", "/proc/version", "--size", "16x16"]);
        assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
        assert!(stderr(&out).contains("error: /proc/version: cannot "), "{}", stderr(&out));
    }
    let out = glint(&["bench", scene, "--frames", "2", "--size", "16x16", "--plot", "/dev/full"]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(stderr(&out).contains("error: /dev/full: cannot write: "), "{}", stderr(&out));
}

#[test]
fn count_arguments_are_bounded_with_a_one_line_error() {
    let scene = repo("tests/scenes/ortho.scn");
    let scene = scene.to_str().expect("path");
    for (args, says) in [
        (&["bench", scene, "--frames", "9223372036854775807"][..], "1..=100000"),
        (&["bench", scene, "--frames", "0"], "1..=100000"),
        (&["bench", scene, "--warmup", "18446744073709551615"], "0..=100000"),
        (&["bench", scene, "--settle", "2001"], "0..=2000"),
        (&["render", scene, "-o", "/nonexistent/x.png", "--frames", "100001"], "1..=100000"),
        (&["render", scene, "-o", "/nonexistent/x.png", "--fps", "1e-30"], "0.001..=1000"),
        (&["render", scene, "-o", "/nonexistent/x.png", "--fps", "inf"], "0.001..=1000"),
        (&["sim", "cloth", "--sheet", "1,1", "--resolution", "3,3", "--steps", "4294967296"], "--steps"),
        (&["sim", "cloth", "--sheet", "1,1", "--resolution", "1025,1025"], "--resolution 2..=257"),
    ] {
        let out = glint(args);
        let text = stderr(&out);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {text}");
        assert!(!text.contains("panicked"), "{args:?}: {text}");
        assert_eq!(error_lines(&out).len(), 1, "{args:?}: {text}");
        assert!(text.contains(says), "{args:?}: {text}");
    }
}

#[test]
fn cloth_limits_are_file_line_errors_before_any_work() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = dir.path().join("cloth.scn");
    // 65 × 65 nodes at dt = 1e-5 to 1 s: 100,000 steps (the most one pose may
    // take), but far over the node²-step budget: refused before a GPU starts
    // or a step is taken.
    let text = "// a fine cloth\n{\n\"classname\" \"cloth\"\n\"resolution\" \"65 65\"\n\"dt\" \"1e-5\"\n}\n";
    std::fs::write(&scene, text).expect("write scene");
    let scene = scene.to_str().expect("path");
    let out = glint(&["render", scene, "-o", dir.path().join("x.png").to_str().expect("path"), "--time", "1"]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let errors = error_lines(&out);
    assert_eq!(errors.len(), 1, "{}", stderr(&out));
    assert!(errors[0].starts_with(&format!("error: {scene}:2: cloth: ")), "{errors:?}");
    assert!(errors[0].contains("node²-steps"), "{errors:?}");
    // A resolution over the maximum.
    let big = dir.path().join("big.scn");
    std::fs::write(&big, "{\n\"classname\" \"cloth\"\n\"resolution\" \"257 257\"\n}\n").expect("write scene");
    let out = glint(&["check", big.to_str().expect("path")]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(stderr(&out).contains("big.scn:3: \"resolution\" is '257 257'"), "{}", stderr(&out));
    // Five 129 × 129 sheets: more cloth nodes than a scene may have, refused at the fifth.
    let sheet = "{\n\"classname\" \"cloth\"\n\"resolution\" \"129 129\"\n}\n";
    std::fs::write(&big, sheet.repeat(5)).expect("write scene");
    let out = glint(&["check", big.to_str().expect("path")]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(stderr(&out).contains("big.scn:17: cloth: the scene's cloths would have"), "{}", stderr(&out));
}

#[test]
fn a_scene_in_utf16_or_invalid_utf8_is_an_error_with_its_line() {
    let dir = tempfile::tempdir().expect("temp dir");
    let text = "// a scene\n{\n\"classname\" \"world\"\n}\n";
    let utf16: Vec<u8> = std::iter::once(0xFEFF).chain(text.encode_utf16()).flat_map(u16::to_le_bytes).collect();
    let wide = dir.path().join("wide.scn");
    std::fs::write(&wide, utf16).expect("write");
    let out = glint(&["check", wide.to_str().expect("path")]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let want = format!("error: {}:1: expected UTF-8 text, found UTF-16", wide.display());
    assert!(stderr(&out).contains(&want), "{}", stderr(&out));
    let latin1 = dir.path().join("latin1.scn");
    std::fs::write(&latin1, b"{\n\"classname\" \"material\"\n\"name\" \"caf\xE9\"\n}\n").expect("write");
    let out = glint(&["check", latin1.to_str().expect("path")]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let want = format!("error: {}:3: invalid UTF-8 at column 12", latin1.display());
    assert!(stderr(&out).contains(&want), "{}", stderr(&out));
}

#[test]
fn compare_says_whether_two_images_match_within_the_reference_tolerance() {
    let same = glint(&["compare", "tests/reference/split.png", "tests/reference/split.png"]);
    assert_eq!(same.status.code(), Some(0), "{}", stderr(&same));
    assert!(String::from_utf8_lossy(&same.stdout).starts_with("match: similarity 1.0000"));
    let diff = std::env::temp_dir().join(format!("glint-compare-{}.png", std::process::id()));
    let other = glint(&[
        "compare",
        "tests/reference/lights.png",
        "tests/reference/shapes.png",
        "--diff",
        diff.to_str().unwrap(),
    ]);
    assert_eq!(other.status.code(), Some(4), "{}", stderr(&other));
    assert!(String::from_utf8_lossy(&other.stdout).starts_with("differ: "));
    assert_eq!(image::image_dimensions(&diff).expect("the difference map"), (256, 256));
    let _ = std::fs::remove_file(&diff);
    let sizes = glint(&["compare", "tests/reference/split.png", "tests/reference/monitor.png"]);
    assert_eq!(sizes.status.code(), Some(1));
    assert_eq!(
        error_lines(&sizes),
        ["error: tests/reference/monitor.png: 160x90, but tests/reference/split.png is 192x96"]
    );
}

#[test]
fn every_shipped_scene_checks_without_a_gpu() {
    let mut checked = 0;
    for dir in ["scenes", "scenes/bench"] {
        let mut names: Vec<_> = std::fs::read_dir(repo(dir)).expect("scenes").flatten().map(|e| e.path()).collect();
        names.sort();
        for path in names.iter().filter(|p| p.extension().is_some_and(|e| e == "scn")) {
            let name = path.to_str().expect("utf-8 path");
            let out = glint(&["check", name]);
            assert_eq!(out.status.code(), Some(0), "{name}: {}", stderr(&out));
            checked += 1;
        }
    }
    assert!(checked >= 15, "{checked} scenes");
}

/// The JSON report of `glint bench --live` run with `args`; `None` (skipped)
/// where the machine has no GPU adapter.
fn bench_live(args: &[&str]) -> Option<serde_json::Value> {
    let out = glint(args);
    if out.status.code() == Some(2) {
        eprintln!("skipped: no GPU adapter");
        return None;
    }
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    Some(serde_json::from_slice(&out.stdout).expect("one JSON object"))
}

#[test]
fn bench_live_runs_a_scene_as_it_plays() {
    let scene = repo("tests/scenes/emitter.scn");
    let args = [
        "bench",
        scene.to_str().unwrap(),
        "--live",
        "30",
        "--time",
        "1",
        "--frames",
        "3",
        "--warmup",
        "1",
        "--size",
        "64x64",
        "--json",
    ];
    let Some(r) = bench_live(&args) else { return };
    let live = &r["live"];
    assert_eq!((live["frames"].as_u64(), live["start"].as_f64()), (Some(3), Some(1.0)));
    assert!(live["particles_alive"].as_u64().unwrap() > 300, "{r}");
    assert!(live["frame_ms_median"].as_f64().unwrap() > 0.0);
    let far = ["bench", scene.to_str().unwrap(), "--live", "60", "--time", "1e9", "--frames", "1"];
    assert_eq!(glint(&far).status.code(), Some(1), "a pose past the budget is bad input");
}

#[test]
fn bench_live_times_every_views_shadows_of_a_split_screen() {
    // Two views and two shadowed point lights: each light's six faces drawn once a frame.
    let scene = repo("scenes/bench/split_points.scn");
    let args = [
        "bench",
        scene.to_str().unwrap(),
        "--live",
        "30",
        "--frames",
        "2",
        "--warmup",
        "1",
        "--size",
        "96x48",
        "--json",
    ];
    let Some(r) = bench_live(&args) else { return };
    let live = &r["live"];
    assert_eq!(live["shadow_views"].as_u64(), Some(12), "{r}");
    if live["forward_gpu_ms_median"].is_f64() {
        assert!(live["shadow_gpu_ms_median"].as_f64().is_some_and(|ms| ms > 0.0), "{r}");
    }
}

#[test]
fn bench_live_puts_levels_of_detail_beside_full_detail() {
    // The small school: 400 fish of the underwater scene's model.
    let scene = repo("tests/scenes/school.scn");
    let args = [
        "bench",
        scene.to_str().unwrap(),
        "--live",
        "30",
        "--time",
        "3",
        "--frames",
        "2",
        "--warmup",
        "1",
        "--size",
        "128x72",
        "--lod",
        "both",
        "--json",
    ];
    let Some(r) = bench_live(&args) else { return };
    let (with, full, lod) = (&r["live"], &r["full_detail"], &r["lod"]);
    assert_eq!((with["levels_of_detail"].as_bool(), full["levels_of_detail"].as_bool()), (Some(true), Some(false)));
    let triangles = |side: &serde_json::Value| {
        side["triangles"].as_u64().expect("n") + side["shadow_triangles"].as_u64().expect("n")
    };
    assert!(triangles(with) > 0 && triangles(with) * 2 < triangles(full), "{r}");
    let ratio = lod["triangle_ratio"].as_f64().expect("ratio");
    assert!((ratio - triangles(full) as f64 / triangles(with) as f64).abs() < 1e-9, "{r}");
    assert!(lod["frame_speedup"].as_f64().is_some_and(|x| x > 0.0), "{r}");
    let mean = lod["mean_difference"].as_f64().expect("mean");
    assert!(mean > 0.0 && mean < 2.0, "the pictures differ a little: {r}");
    assert!(lod["block_difference"].as_f64().expect("block") >= mean);
    // No error allowed is full detail: the same triangles.
    let exact = [&args[..14], &["--lod-error", "0", "--json"]].concat();
    let Some(r) = bench_live(&exact) else { return };
    assert_eq!(r["lod"]["triangle_ratio"].as_f64(), Some(1.0), "{r}");
    assert_eq!(r["lod"]["mean_difference"].as_f64(), Some(0.0), "{r}");
    // A negative error is a usage error, said of the flag.
    let bad = glint(&[&args[..14], &["--lod-error=-1"]].concat());
    assert_eq!(bad.status.code(), Some(1));
    assert!(stderr(&bad).contains("--lod-error"), "{}", stderr(&bad));
}
