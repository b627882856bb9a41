//! `glint explain` as a user meets it: the text is stable (a snapshot of a
//! small scene), the JSON's passes hold the draw calls that add up to the
//! frame's statistics, and `--naive` puts the naive frame beside it.

mod common;

use common::*;

/// Run glint on Vulkan (the snapshot's backend), or `None` without an adapter.
fn glint_vulkan(args: &[&str]) -> Option<std::process::Output> {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_glint"))
        .args(args)
        .current_dir(repo(""))
        .env("NODEVICE_SELECT", "1")
        .env("WGPU_BACKEND", "vulkan")
        .output()
        .expect("run glint");
    if no_adapter(&out) {
        return None;
    }
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    Some(out)
}

/// The text without what changes from run to run and machine to machine: the
/// first line (it names the adapter) and the CPU and GPU times.
fn stable(text: &str) -> String {
    text.lines()
        .skip(1)
        .filter(|l| !l.starts_with("CPU ") && !l.starts_with("GPU "))
        .map(|l| format!("{l}\n"))
        .collect()
}

#[test]
fn the_text_of_a_small_scene_is_stable() {
    let args = ["explain", "tests/scenes/states.scn", "--cull", "cpu", "--size", "64x64", "--naive"];
    let Some(out) = glint_vulkan(&args) else { return };
    let text = String::from_utf8(out.stdout).expect("UTF-8");
    let snapshot = repo("tests/snapshots/explain_states.txt");
    // The calls a device records depend on what it can do (multi-draw-indirect
    // and its count): the snapshot is lavapipe's, the CI machine's.
    if !text.lines().next().is_some_and(|l| l.contains("llvmpipe") && l.contains("Vulkan")) {
        eprintln!("skipping the snapshot: it is lavapipe's, and this is {}", text.lines().next().unwrap_or(""));
        return;
    }
    if std::env::var("GLINT_BLESS").as_deref() == Ok("1") {
        std::fs::write(&snapshot, stable(&text)).expect("snapshot written");
    }
    let expected =
        std::fs::read_to_string(&snapshot).expect("tests/snapshots/explain_states.txt (GLINT_BLESS=1 writes it)");
    assert_eq!(stable(&text), expected, "glint explain's text changed; GLINT_BLESS=1 writes the new one");
    for want in [
        "key 0x",
        "opaque (stage 64)",
        "transparent (stage 192) far to near",
        "'glow'",
        "mesh 3 'sphere'",
        "[ALPHA_BLEND FOG]",
        "set: ",
        "kept: ",
        "naive / optimized: ",
    ] {
        assert!(text.contains(want), "'{want}' in:\n{text}");
    }
}

#[test]
fn json_passes_hold_the_draw_calls_that_make_the_frame_s_counts() {
    let args = ["explain", "scenes/showcase.scn", "--size", "96x64", "--json", "--naive"];
    let Some(out) = glint_vulkan(&args) else { return };
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    for frame in [&json, &json["naive"]] {
        let passes = frame["passes"].as_array().expect("passes");
        let stats = &frame["stats"];
        let forward_calls = passes
            .iter()
            .filter(|p| !p["group"].as_str().expect("group").contains("shadows"))
            .flat_map(|p| p["draw_calls"].as_array().expect("draw_calls"))
            .filter(|c| c["late"] == false)
            .count();
        assert_eq!(forward_calls as u64, stats["draw_calls"].as_u64().expect("count"), "{}", frame["mode"]);
        for pass in passes {
            assert!(pass["kind"] == "compute" || pass["kind"] == "render", "{pass}");
        }
    }
    assert_eq!(json["mode"], "optimized");
    assert_eq!(json["naive"]["mode"], "naive");
    let ratios = &json["ratios"];
    assert!(
        ratios["draw_calls"].as_f64().expect("ratio") > 100.0,
        "the naive showcase makes hundreds of times the calls: {ratios}"
    );
    assert!(ratios["cpu"].as_f64().expect("ratio") > 1.0, "{ratios}");
}

#[test]
fn a_view_the_frame_lacks_is_an_error() {
    let out = glint(&["explain", "tests/scenes/states.scn", "--view", "3", "--size", "16x16"]);
    if no_adapter(&out) {
        return;
    }
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(stderr(&out).contains("--view 3 requested, but the frame has 1 views"), "{}", stderr(&out));
}

#[test]
fn explain_shows_the_light_clusters_and_clusters_off_refuses_more_than_64_lights() {
    let Some(out) = glint_vulkan(&["explain", "scenes/lights.scn", "--size", "320x180"]) else { return };
    let text = String::from_utf8(out.stdout).expect("UTF-8");
    let line = text.lines().find(|l| l.starts_with("light clusters:")).expect("a light clusters line");
    // 320 × 180 in tiles of 16 pixels (the smallest; a 40th of the width
    // elsewhere), 24 slices; every one of the 1,264 lights is in view, and no
    // cluster holds more than its 256 (one that did would say how many it left out).
    assert!(line.starts_with("light clusters: 20 × 12 tiles of 16 px × 24 depth slices (5760 clusters"), "{line}");
    assert!(line.contains("1264 point and spot lights reach them"), "{line}");
    // Culled on the GPU, the lights are binned there, by a pass of the view's "lights" group.
    assert!(line.contains("binned on the GPU by the pass 'bin lights'"), "{line}");
    let passes: Vec<&str> = text.lines().filter(|l| l.starts_with("pass ")).collect();
    let bin = passes.iter().position(|l| l.contains("compute 'bin lights'")).expect("the binning pass");
    let cull = passes.iter().position(|l| l.contains("'cull instances'")).expect("the cull pass");
    assert!(passes[bin].ends_with(" › lights") && bin < cull, "{passes:?}");
    assert!(line.ends_with("; 0 entries over the 256 a cluster holds"), "{line}");
    assert!(text.lines().any(|l| l.starts_with("CPU ms (this frame): prepare") && l.contains(", lights ")), "{text}");
    let off = glint(&["explain", "scenes/lights.scn", "--size", "64x36", "--clusters", "off"]);
    assert_ne!(off.status.code(), Some(0));
    assert!(
        stderr(&off).contains("1265 lights with light clusters off given, but a frame can use at most 64"),
        "{}",
        stderr(&off)
    );
    let few = glint(&["explain", "tests/scenes/lights.scn", "--size", "64x36"]);
    let text = String::from_utf8(few.stdout).expect("UTF-8");
    assert!(text.contains("light clusters: none (every fragment loops over every light)"), "{text}");
}

#[test]
fn explain_shows_an_accumulated_still_and_soft_shadows() {
    let args = ["explain", "tests/scenes/soft_shadows.scn", "--size", "64x64", "--spp", "4", "--json"];
    let Some(out) = glint_vulkan(&args) else { return };
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    assert_eq!(json["spp"], 4);
    let passes = json["passes"].as_array().expect("passes");
    let labels: Vec<&str> = passes.iter().filter_map(|p| p["name"].as_str()).collect();
    let at = |label: &str| labels.iter().position(|l| *l == label).unwrap_or_else(|| panic!("{label} in {labels:?}"));
    // The forward pass, its fold into the mean, the mean copied out, and the clamp the view's empty chain becomes.
    assert!(at("forward pass") < at("accumulate: fold"), "{labels:?}");
    assert!(at("accumulate: fold") < at("accumulate: copy"), "{labels:?}");
    assert!(at("accumulate: copy") < at("post: tonemap (fs_tonemap)"), "{labels:?}");
    let soft = passes
        .iter()
        .flat_map(|p| p["draw_calls"].as_array().expect("draw_calls"))
        .flat_map(|c| c["batches"].as_array().expect("batches"))
        .filter(|b| b["features"].as_array().expect("features").iter().any(|f| f == "SOFT_SHADOWS"))
        .count();
    assert!(soft >= 3, "the forward batches take the soft-shadow variant: {soft}");
    let one = ["explain", "tests/scenes/soft_shadows.scn", "--size", "64x64"];
    let text = String::from_utf8(glint_vulkan(&one).expect("adapter").stdout).expect("UTF-8");
    assert!(!text.contains("accumulate") && !text.contains("post:"), "a frame of its own accumulates nothing:\n{text}");
    let text = String::from_utf8(glint_vulkan(&args[..6]).expect("adapter").stdout).expect("UTF-8");
    assert!(text.contains("an accumulated still of 4 sub-frames"), "{text}");
}

#[test]
fn explain_shows_smaa_s_three_passes_and_their_cost() {
    let args = ["explain", "tests/scenes/smaa.scn", "--size", "64x64", "--json"];
    let Some(out) = glint_vulkan(&args) else { return };
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    let passes = json["passes"].as_array().expect("passes");
    let labels: Vec<&str> = passes.iter().filter_map(|p| p["name"].as_str()).collect();
    let smaa: Vec<&str> = labels.iter().copied().filter(|l| l.starts_with("post: smaa")).collect();
    assert_eq!(
        smaa,
        ["post: smaa (fs_smaa_edges)", "post: smaa (fs_smaa_weights)", "post: smaa (fs_smaa_blend)"],
        "{labels:?}"
    );
    assert_eq!(json["post"], serde_json::json!(["tonemap", "smaa"]));
    let text = String::from_utf8(glint_vulkan(&args[..4]).expect("adapter").stdout).expect("UTF-8");
    let gpu = text.lines().find(|l| l.starts_with("GPU ms")).unwrap_or_default();
    assert!(
        gpu.is_empty() || (gpu.contains("tonemap ") && gpu.contains("smaa ")),
        "each effect's time is named: {gpu}"
    );
}

#[test]
fn explain_shows_the_transparency_passes_and_weighted_error_against_exact() {
    let args = ["explain", "tests/scenes/transparency.scn", "--size", "64x64", "--json", "--transparency", "weighted"];
    let Some(out) = glint_vulkan(&args) else { return };
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    assert_eq!(json["stats"]["transparency"], "weighted");
    let labels: Vec<&str> =
        json["passes"].as_array().expect("passes").iter().filter_map(|p| p["name"].as_str()).collect();
    assert!(labels.contains(&"transparency: weighted sums"), "{labels:?}");
    let error = &json["weighted_error"];
    let (mean, largest) = (error["mean"].as_f64().expect("mean"), error["largest"].as_u64().expect("largest"));
    assert!(mean > 0.0 && mean < 0.05 && largest > 0, "weighted against exact: {error}");
    // The scene's own exact: the lists' fragments counted, none dropped.
    let Some(out) = glint_vulkan(&args[..5]) else { return };
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    let fragments = &json["stats"]["transparent_fragments"];
    let appended = fragments["appended"].as_u64().expect("appended");
    assert!(appended > 64 * 64 / 4 && appended <= fragments["held"].as_u64().expect("held"), "{fragments}");
    assert!(json.get("weighted_error").is_none(), "exact is the reference itself");
}
