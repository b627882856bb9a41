//! Simulation caches: `glint bake` stores a sequence's simulation state every
//! few frames, and `glint render --sim-cache` starts a chunk from it with the
//! same frames as the whole run; caches for other scenes, settings or
//! paths, and damaged ones, are refused.

mod common;

use common::*;
use std::path::Path;

/// The backend a test runs on: wgpu's default (Vulkan here), or GL.
#[derive(Clone, Copy)]
enum Backend {
    Default,
    Gl,
}

/// `glint` with `args` on `backend`, `None` where no adapter lets it run.
fn run_on(backend: Backend, args: &[&str]) -> Option<std::process::Output> {
    let vars: &[(&str, &str)] = match backend {
        Backend::Default => &[],
        Backend::Gl => &[("WGPU_BACKEND", "gl")],
    };
    let out = glint_with(args, vars);
    (!no_adapter(&out)).then_some(out)
}

/// `glint` with `args`, `None` where no adapter lets it run.
fn run(args: &[&str]) -> Option<std::process::Output> {
    run_on(Backend::Default, args)
}

/// `glint` with `args` on `backend`, which must succeed (`None` without an adapter).
fn ok_on(backend: Backend, args: &[&str]) -> Option<std::process::Output> {
    let out = run_on(backend, args)?;
    assert_eq!(out.status.code(), Some(0), "glint {}: {}", args.join(" "), stderr(&out));
    Some(out)
}

/// `glint` with `args`, which must succeed (`None` without an adapter).
fn ok(args: &[&str]) -> Option<std::process::Output> {
    ok_on(Backend::Default, args)
}

fn text(path: &Path) -> &str {
    path.to_str().expect("a UTF-8 path")
}

/// Bake `scene`'s 12 frames every 4 into `cache` with `extra` arguments.
fn bake(scene: &str, cache: &Path, extra: &[&str]) -> Option<std::process::Output> {
    bake_on(Backend::Default, scene, cache, extra)
}

fn bake_on(backend: Backend, scene: &str, cache: &Path, extra: &[&str]) -> Option<std::process::Output> {
    ok_on(backend, &[&["bake", scene, "-o", text(cache), "--frames", "12", "--every", "4"], extra].concat())
}

/// Frames 9..=11 of `scene`'s 12, drawn whole and as a chunk from a cache
/// baked with `extra` (school and cloth paths), are the same bytes; the chunk
/// says it resumed from frame 8.
fn a_chunk_from_the_cache_equals_the_whole_run(scene: &str, extra: &[&str]) {
    a_chunk_on(Backend::Default, scene, extra);
}

fn a_chunk_on(backend: Backend, scene: &str, extra: &[&str]) {
    let dir = tempfile::tempdir().expect("temp dir");
    let (cache, whole, chunk) = (dir.path().join("cache"), dir.path().join("whole"), dir.path().join("chunk"));
    let Some(_) = bake_on(backend, &repo(scene).to_string_lossy(), &cache, extra) else { return };
    let scene = repo(scene);
    let picture = ["--size", "48x32", "--msaa", "1", "--frames", "12"];
    let render = |out: &Path, more: &[&str]| {
        let pattern = out.join("%02d.png");
        let args = [&["render", text(&scene), "-o", text(&pattern)], &picture[..], extra, more].concat();
        ok_on(backend, &args).expect("adapter")
    };
    render(&whole, &[]);
    let out = render(&chunk, &["--frame-range", "9-11", "--sim-cache", text(&cache)]);
    assert!(stderr(&out).contains("simulations resumed from frame 8"), "{}", stderr(&out));
    for k in 9..=11 {
        let name = format!("{k:02}.png");
        let (a, b) =
            (std::fs::read(whole.join(&name)).expect("drawn"), std::fs::read(chunk.join(&name)).expect("drawn"));
        assert!(a == b, "{scene:?} frame {k}: the chunk from the cache differs from the whole run");
    }
    assert!(!chunk.join("08.png").exists(), "the chunk draws only its frames");
}

#[test]
fn the_tablecloth_from_a_cache_equals_the_whole_run() {
    a_chunk_from_the_cache_equals_the_whole_run("scenes/tablecloth.scn", &[]);
}

#[test]
fn a_cloth_on_the_gpu_from_a_cache_equals_the_whole_run() {
    a_chunk_from_the_cache_equals_the_whole_run("tests/scenes/cloth_gpu.scn", &[]);
}

#[test]
fn the_aquariums_school_and_emitter_from_a_cache_equal_the_whole_run() {
    // On the GPU, and the CPU's reference.
    a_chunk_from_the_cache_equals_the_whole_run("scenes/aquarium.scn", &[]);
    a_chunk_from_the_cache_equals_the_whole_run("scenes/aquarium.scn", &["--sim", "cpu"]);
}

#[test]
fn emitters_from_a_cache_equal_the_whole_run() {
    a_chunk_from_the_cache_equals_the_whole_run("tests/scenes/emitter.scn", &[]);
}

#[test]
fn gl_resumes_its_cpu_simulations_from_a_cache() {
    // GL has no compute path: the school and emitters step on the CPU.
    a_chunk_on(Backend::Gl, "tests/scenes/school.scn", &[]);
    a_chunk_on(Backend::Gl, "tests/scenes/emitter.scn", &[]);
}

/// `glint render` of `scene` from `cache` fails with exit code 1 and a
/// message holding `expected`, drawing nothing.
fn refused(scene: &str, cache: &Path, extra: &[&str], expected: &str) {
    let dir = tempfile::tempdir().expect("temp dir");
    let pattern = dir.path().join("%02d.png");
    let args = ["render", scene, "-o", text(&pattern), "--size", "16x16", "--frames", "12", "--frame-range", "9-11"];
    let Some(out) = run(&[&args[..], &["--sim-cache", text(cache)], extra].concat()) else { return };
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(stderr(&out).contains(expected), "expected {expected:?} in: {}", stderr(&out));
    assert_eq!(std::fs::read_dir(dir.path()).expect("the folder").count(), 0, "no frame is drawn");
}

#[test]
fn caches_of_other_scenes_settings_and_paths_are_refused() {
    let dir = tempfile::tempdir().expect("temp dir");
    let cloth = repo("tests/scenes/cloth_gpu.scn");
    let cache = dir.path().join("cloth");
    let Some(_) = bake(text(&cloth), &cache, &["--solve", "converged"]) else { return };

    // Another scene.
    refused(text(&repo("tests/scenes/emitter.scn")), &cache, &[], "made for another scene");
    // The same scene with its first cloth's time step changed.
    let source = std::fs::read_to_string(&cloth).expect("the scene");
    assert!(source.contains("\"dt\" \"0.01\""));
    let changed = dir.path().join("cloth_dt.scn");
    std::fs::write(&changed, source.replacen("\"dt\" \"0.01\"", "\"dt\" \"0.02\"", 1)).expect("written");
    refused(text(&changed), &cache, &["--solve", "converged"], "steps by 0.02 s here, by 0.01 s in the cache");
    // Another setting (its damping), the time step unchanged.
    let damped = dir.path().join("cloth_damped.scn");
    let with_damping = source.replacen("\"dt\" \"0.01\"", "\"dt\" \"0.01\"\n\"damping\" \"7\"", 1);
    std::fs::write(&damped, with_damping).expect("written");
    refused(text(&damped), &cache, &["--solve", "converged"], "is set up otherwise than when the cache was baked");
    // Another frame rate or start time: the cache's frames are not this sequence's.
    refused(text(&cloth), &cache, &["--solve", "converged", "--fps", "24"], "baked for a sequence at 30 fps from 0 s");
    refused(text(&cloth), &cache, &["--solve", "converged", "--time", "0.5"], "this one is at 30 fps from 0.5 s");
    // The same scene solved another way (its settings differ: the solve is one).
    refused(text(&cloth), &cache, &["--solve", "realtime"], "set up otherwise");
    // A school baked on the GPU, drawn on the CPU.
    let school = repo("tests/scenes/school.scn");
    let on_gpu = dir.path().join("school");
    bake(text(&school), &on_gpu, &[]).expect("adapter");
    let manifest = std::fs::read_to_string(on_gpu.join("manifest.json")).expect("the manifest");
    if manifest.contains("\"GPU\"") {
        refused(text(&school), &on_gpu, &["--sim", "cpu"], "stepped on the GPU when the cache was baked");
    }
    // Not a cache at all.
    refused(text(&cloth), dir.path(), &[], "not a glint simulation cache");
}

#[test]
fn damaged_caches_are_errors_never_pictures() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = repo("tests/scenes/emitter.scn");
    let cache = dir.path().join("cache");
    let Some(_) = bake(text(&scene), &cache, &[]) else { return };
    let state = cache.join("state_000008.bin");
    let good = std::fs::read(&state).expect("a state at frame 8");
    let manifest = cache.join("manifest.json");
    let good_manifest = std::fs::read_to_string(&manifest).expect("the manifest");

    // One flipped byte in the state's data.
    let mut flipped = good.clone();
    let middle = flipped.len() / 2;
    flipped[middle] ^= 0x10;
    std::fs::write(&state, &flipped).expect("written");
    refused(text(&scene), &cache, &[], "corrupt: its hash is not the manifest's");
    // Cut short.
    std::fs::write(&state, &good[..good.len() - 100]).expect("written");
    refused(text(&scene), &cache, &[], "truncated or changed");
    // Gone.
    std::fs::remove_file(&state).expect("removed");
    refused(text(&scene), &cache, &[], "state_000008.bin: cannot read");
    // A FIFO in its place: refused before it is opened (opening one waits for a writer).
    let fifo = std::process::Command::new("mkfifo").arg(&state).status();
    if fifo.is_ok_and(|s| s.success()) {
        refused(text(&scene), &cache, &[], "state_000008.bin: not a regular file");
        std::fs::remove_file(&state).expect("removed");
    }
    std::fs::write(&state, &good).expect("restored");

    // A value of the manifest changed: its own checksum catches it.
    std::fs::write(&manifest, good_manifest.replacen("\"every\": 4", "\"every\": 5", 1)).expect("written");
    refused(text(&scene), &cache, &[], "do not match its checksum");
    // Made by another glint.
    let version = format!("\"glint\": \"{}\"", env!("CARGO_PKG_VERSION"));
    std::fs::write(&manifest, good_manifest.replacen(&version, "\"glint\": \"0.0.1\"", 1)).expect("written");
    refused(text(&scene), &cache, &[], "made by glint 0.0.1");
    // A state file named outside the cache's folder.
    let outside = good_manifest.replacen("\"state_000008.bin\"", "\"../state_000008.bin\"", 1);
    std::fs::write(&manifest, outside).expect("written");
    refused(text(&scene), &cache, &[], "do not match its checksum");
    // Not JSON.
    std::fs::write(&manifest, &good_manifest[..good_manifest.len() / 2]).expect("written");
    refused(text(&scene), &cache, &[], "not a glint simulation cache's manifest");

    // Mended, it works again.
    std::fs::write(&manifest, &good_manifest).expect("written");
    let out = dir.path().join("%02d.png");
    let args = ["render", text(&scene), "-o", text(&out), "--size", "16x16", "--frames", "12", "--frame-range", "9-11"];
    let done = ok(&[&args[..], &["--sim-cache", text(&cache)]].concat()).expect("adapter");
    assert!(stderr(&done).contains("resumed from frame 8"), "{}", stderr(&done));
}

#[test]
fn a_scene_without_simulations_bakes_an_empty_valid_cache() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = repo("tests/scenes/shapes.scn");
    let cache = dir.path().join("cache");
    let Some(_) = bake(text(&scene), &cache, &[]) else { return };
    let files: Vec<_> = std::fs::read_dir(&cache).expect("the cache").map(|e| e.expect("entry").file_name()).collect();
    assert_eq!(files, ["manifest.json"], "no state to store");
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(cache.join("manifest.json")).expect("read")).expect("JSON");
    assert_eq!(manifest["simulations"], serde_json::json!([]));
    assert_eq!(manifest["states"], serde_json::json!([]));
    let pattern = dir.path().join("%02d.png");
    let args =
        ["render", text(&scene), "-o", text(&pattern), "--size", "16x16", "--frames", "12", "--frame-range", "10"];
    let out = ok(&[&args[..], &["--sim-cache", text(&cache)]].concat()).expect("adapter");
    assert!(stderr(&out).contains("holds no state before frame 10"), "{}", stderr(&out));
    assert!(dir.path().join("10.png").is_file());
}
