//! The viewer under a virtual X display (Xvfb): windows that resize, minimise
//! and take screenshots, scripted key actions, the overlay (its panels draw,
//! `H` hides them) and the scene's controls changing what they claim.

mod common;

use common::*;
use std::path::Path;
use std::process::Command;

/// `glint view SCENE ARGS…` under a virtual X display (`xvfb-run`), or `None`
/// (with a message) where there is no xvfb-run or no GPU adapter and
/// `GLINT_REQUIRE_ADAPTER=1` does not ask for them.
fn view_under_xvfb(scene: &Path, args: &[String]) -> Option<std::process::Output> {
    view_under_xvfb_on(scene, args, None)
}

/// [`view_under_xvfb`] on wgpu's `backend` (`WGPU_BACKEND`) where given.
fn view_under_xvfb_on(scene: &Path, args: &[String], backend: Option<&str>) -> Option<std::process::Output> {
    let required = std::env::var("GLINT_REQUIRE_ADAPTER").as_deref() == Ok("1");
    if Command::new("xvfb-run").arg("--help").output().is_err() {
        assert!(!required, "GLINT_REQUIRE_ADAPTER=1 but xvfb-run is missing (apt-get install xvfb xauth)");
        eprintln!("skipping: no xvfb-run (apt-get install xvfb xauth)");
        return None;
    }
    let out = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 640x480x24", env!("CARGO_BIN_EXE_glint"), "view"])
        .arg(scene)
        .args(args)
        .current_dir(repo(""))
        .env("NODEVICE_SELECT", "1")
        .envs(backend.map(|b| ("WGPU_BACKEND", b)))
        .output()
        .expect("run xvfb-run");
    if out.status.code() == Some(2) && !required {
        eprintln!("skipping: no GPU adapter ({})", stderr(&out));
        return None;
    }
    Some(out)
}

/// The viewer under a virtual X display: a few frames, a resize, minimise and
/// restore, a screenshot on the way and one on quitting.
#[test]
fn view_runs_under_xvfb_resizes_and_takes_screenshots() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (mid, last, offscreen) =
        (dir.path().join("mid.png"), dir.path().join("last.png"), dir.path().join("offscreen.png"));
    let scene = repo("tests/scenes/lights.scn");
    let args = ["--size", "96x64", "--msaa", "1", "--frames", "10", "--at", "1:overlay=off"]
        .into_iter()
        .chain(["--at", "3:resize=120x80", "--at", "5:minimize", "--at", "7:restore"])
        .map(str::to_owned)
        .chain(["--at".into(), format!("8:screenshot={}", mid.display())])
        .chain(["--screenshot".into(), last.display().to_string()]);
    let Some(out) = view_under_xvfb(&scene, &args.collect::<Vec<_>>()) else { return };
    let scene = scene.to_str().expect("path");
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    // On quitting it says how fast the scene played: at most real time.
    let summary = stderr(&out).lines().find(|l| l.contains("frames drawn in")).map(str::to_owned);
    let summary = summary.unwrap_or_else(|| panic!("no summary: {}", stderr(&out)));
    let speed: f64 = summary
        .rsplit(", ")
        .next()
        .and_then(|s| s.strip_suffix("x real time"))
        .expect(&summary)
        .parse()
        .expect(&summary);
    assert!(summary.starts_with("glint view: ") && (0.0..=1.001).contains(&speed), "{summary}");
    for png in [&mid, &last] {
        let image = image::open(png).unwrap_or_else(|e| panic!("{}: {e}\n{}", png.display(), stderr(&out))).into_rgb8();
        assert_eq!(image.dimensions(), (120, 80), "{}: the frame follows the resized window", png.display());
    }
    // Untouched, the fly camera starts as the scene's camera: the viewer's frame is
    // what `glint render` draws at that size.
    let args = ["render", scene, "-o", offscreen.to_str().expect("path"), "--size", "120x80", "--msaa", "1"];
    assert_eq!(glint(&args).status.code(), Some(0));
    let (a, b) = (image::open(&last).expect("png").into_rgb8(), image::open(&offscreen).expect("png").into_rgb8());
    let differing = a.pixels().zip(b.pixels()).filter(|(p, q)| p.0.iter().zip(q.0).any(|(x, y)| x.abs_diff(y) > 8));
    assert!(differing.count() < 20, "the viewer's last frame differs from glint render's");
    let lit = a.pixels().filter(|p| p.0.iter().any(|&c| c > 60)).count();
    assert!(lit > 120 * 80 / 4, "the frame shows the lit floor: {lit} bright pixels");
}

#[test]
fn the_viewer_changes_density_and_time_of_day_per_frame() {
    let dir = tempfile::tempdir().expect("tempdir");
    let shot = |name: &str| dir.path().join(format!("{name}.png"));
    let at = |frame: u32, action: String| ["--at".to_owned(), format!("{frame}:{action}")];
    let args = ["--size", "96x64", "--msaa", "1", "--frames", "7", "--at", "1:overlay=off"]
        .map(str::to_owned)
        .into_iter()
        .chain(at(2, format!("screenshot={}", shot("full").display())))
        .chain(at(3, "density=0".into()))
        .chain(at(4, format!("screenshot={}", shot("bare").display())))
        .chain(at(5, "time_of_day=23".into()))
        .chain(at(6, format!("screenshot={}", shot("night").display())));
    let Some(out) = view_under_xvfb(&repo("tests/scenes/tiles.scn"), &args.collect::<Vec<_>>()) else { return };
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(stderr(&out).contains("density 0.0") && stderr(&out).contains("time of day 23:00"), "{}", stderr(&out));
    let [full, bare, night] = ["full", "bare", "night"].map(|n| image::open(shot(n)).expect("png").into_rgb8());
    let green = |i: &image::RgbImage| {
        i.pixels()
            .filter(|p| u16::from(p.0[1]) > u16::from(p.0[0]) + 30 && u16::from(p.0[1]) > u16::from(p.0[2]) + 30)
            .count()
    };
    assert!(
        green(&full) > 96 * 64 / 8 && green(&bare) < green(&full) / 20,
        "cones gone: {} then {}",
        green(&full),
        green(&bare)
    );
    let light = |i: &image::RgbImage| i.pixels().map(|p| p.0.iter().map(|&c| u64::from(c)).sum::<u64>()).sum::<u64>();
    assert!(light(&night) * 2 < light(&bare), "night falls");
}

/// The viewer runs a scene's fish and bubbles live: two screenshots some
/// frames apart differ.
#[test]
fn view_runs_the_aquarium_live() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (early, late) = (dir.path().join("early.png"), dir.path().join("late.png"));
    let args: Vec<String> = ["--size", "96x64", "--msaa", "1", "--frames", "12", "--at", "1:overlay=off", "--at"]
        .into_iter()
        .map(str::to_owned)
        .chain([format!("2:screenshot={}", early.display()), "--screenshot".into(), late.display().to_string()])
        .collect();
    let Some(out) = view_under_xvfb(&repo("scenes/aquarium.scn"), &args) else { return };
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let (a, b) = (image::open(&early).expect("png").into_rgb8(), image::open(&late).expect("png").into_rgb8());
    let moved =
        a.pixels().zip(b.pixels()).filter(|(p, q)| p.0.iter().zip(q.0).any(|(x, y)| x.abs_diff(y) > 24)).count();
    assert!(moved > 20, "the fish swam: {moved} pixels changed");
}

/// `--at FRAME:ACTION` arguments.
fn at(frame: u32, action: &str) -> [String; 2] {
    ["--at".to_owned(), format!("{frame}:{action}")]
}

/// What a scripted `stats=PATH` wrote: the scene time, whether the overlay
/// was shown, the frame's command submissions and each view's statistics.
fn read_stats(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).expect("one JSON object")
}

/// The overlay draws over the frame, on Vulkan and on GL: a screenshot with
/// it differs from the same frame of the paused scene without it.
#[test]
fn the_overlay_draws_and_h_hides_it() {
    for backend in [None, Some("gl")] {
        overlay_draws_and_hides(backend);
    }
}

fn overlay_draws_and_hides(backend: Option<&str>) {
    let dir = tempfile::tempdir().expect("tempdir");
    let shot = |name: &str| dir.path().join(format!("{name}.png"));
    let args: Vec<String> = ["--size", "640x360", "--msaa", "1", "--frames", "8"]
        .map(str::to_owned)
        .into_iter()
        .chain(at(1, "set=paused=1"))
        .chain(at(4, &format!("screenshot={}", shot("with").display())))
        .chain(at(5, "overlay=off"))
        .chain(at(7, &format!("screenshot={}", shot("without").display())))
        .collect();
    let Some(out) = view_under_xvfb_on(&repo("tests/scenes/lights.scn"), &args, backend) else { return };
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    if backend == Some("gl") {
        assert!(stderr(&out).contains("(Gl)"), "drawn on GL: {}", stderr(&out));
    }
    let (with, without) =
        (image::open(shot("with")).expect("png").into_rgb8(), image::open(shot("without")).expect("png").into_rgb8());
    let differing =
        with.pixels().zip(without.pixels()).filter(|(p, q)| p.0.iter().zip(q.0).any(|(x, y)| x.abs_diff(y) > 24));
    let changed = differing.count();
    assert!(changed > 640 * 360 / 10, "{backend:?}: the panels cover part of the frame: {changed} pixels differ");
    // The overlay's CPU time is reported beside the frame's.
    let summary = stderr(&out);
    assert!(summary.contains("the overlay took"), "{summary}");
}

/// Each control changes what it claims, as the statistics show: shadows off
/// leaves no shadow views, pausing stops the scene clock, and a lower
/// density draws fewer instances.
#[test]
fn the_controls_change_what_they_claim() {
    let dir = tempfile::tempdir().expect("tempdir");
    let stats = |name: &str| dir.path().join(format!("{name}.json"));
    let args: Vec<String> = ["--size", "96x64", "--msaa", "1", "--frames", "14"]
        .map(str::to_owned)
        .into_iter()
        .chain(at(3, &format!("stats={}", stats("before").display())))
        .chain(at(3, "set=shadows=0"))
        .chain(at(6, &format!("stats={}", stats("after").display())))
        .chain(at(7, "set=paused=1"))
        .chain(at(9, &format!("stats={}", stats("paused").display())))
        .chain(at(12, &format!("stats={}", stats("still").display())))
        .collect();
    let Some(out) = view_under_xvfb(&repo("tests/scenes/cloth_debug.scn"), &args) else { return };
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let [before, after, paused, still] = ["before", "after", "paused", "still"].map(|n| read_stats(&stats(n)));
    let view = |s: &serde_json::Value, key: &str| s["views"][0][key].as_u64().unwrap_or_else(|| panic!("{key} in {s}"));
    assert!(view(&before, "shadow_views") > 0, "the scene's sun casts shadows: {before}");
    // A displayed frame (views, overlay, blit onto the window) is one submission.
    for s in [&before, &after, &paused, &still] {
        assert_eq!((s["overlay"].as_bool(), s["submits"].as_u64()), (Some(true), Some(1)), "{s}");
    }
    assert_eq!(view(&after, "shadow_views"), 0, "shadows off: no shadow views");
    assert_eq!(paused["time"], still["time"], "paused, the clock stays");
    assert!(after["time"].as_f64() > before["time"].as_f64(), "playing, it moves");

    let args: Vec<String> = ["--size", "96x64", "--msaa", "1", "--frames", "6", "--cull", "cpu"]
        .map(str::to_owned)
        .into_iter()
        .chain(at(2, &format!("stats={}", stats("full").display())))
        .chain(at(2, "set=density=0.25"))
        .chain(at(5, &format!("stats={}", stats("sparse").display())))
        .collect();
    let Some(out) = view_under_xvfb(&repo("tests/scenes/tiles.scn"), &args) else { return };
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let [full, sparse] = ["full", "sparse"].map(|n| read_stats(&stats(n)));
    let (full, sparse) = (view(&full, "instances_drawn"), view(&sparse, "instances_drawn"));
    assert!(sparse * 2 < full && sparse > 0, "a quarter of every tile: {full} then {sparse}");

    // The cloth's debug view off: its edge ribbons and pin markers go.
    let args: Vec<String> = ["--size", "96x64", "--msaa", "1", "--frames", "6"]
        .map(str::to_owned)
        .into_iter()
        .chain(at(2, &format!("stats={}", stats("debug").display())))
        .chain(at(3, "set=cloth_debug=0"))
        .chain(at(5, &format!("stats={}", stats("plain").display())))
        .collect();
    let Some(out) = view_under_xvfb(&repo("tests/scenes/cloth_debug.scn"), &args) else { return };
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let [debug, plain] = ["debug", "plain"].map(|n| read_stats(&stats(n)));
    let entities = |s: &serde_json::Value| view(s, "entities_submitted");
    assert_eq!((entities(&debug), entities(&plain)), (4, 2), "floor, cloth, edges, pins; then floor and cloth");

    // A control the scene lacks is bad input, named.
    let bad: Vec<String> = ["--frames", "3"].map(str::to_owned).into_iter().chain(at(2, "set=warp=1")).collect();
    let Some(out) = view_under_xvfb(&repo("tests/scenes/tiles.scn"), &bad) else { return };
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(stderr(&out).contains("tiles.scn: no control 'warp'"), "{}", stderr(&out));
}

/// The sun size and samples-per-pixel controls (the overlay's and the web
/// page's): hard shadows at size 0, soft at the scene's, and a frame of 16
/// samples per pixel is what `glint render --spp 16` draws.
#[test]
fn the_viewer_softens_shadows_and_accumulates_stills_by_its_controls() {
    let dir = tempfile::tempdir().expect("tempdir");
    let shot = |name: &str| dir.path().join(format!("{name}.png"));
    let at = |frame: u32, action: String| ["--at".to_owned(), format!("{frame}:{action}")];
    let args = ["--size", "96x96", "--msaa", "1", "--frames", "7", "--at", "1:overlay=off"]
        .map(str::to_owned)
        .into_iter()
        .chain(at(1, "set=sun_size=0".into()))
        .chain(at(2, format!("screenshot={}", shot("hard").display())))
        .chain(at(3, "set=sun_size=4".into()))
        .chain(at(4, format!("screenshot={}", shot("soft").display())))
        .chain(at(5, "set=sun_size=6".into()))
        .chain(at(5, "set=samples=2".into()))
        .chain(at(6, format!("screenshot={}", shot("still").display())));
    let scene = repo("tests/scenes/soft_shadows.scn");
    let Some(out) = view_under_xvfb(&scene, &args.collect::<Vec<_>>()) else { return };
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let [hard, soft, still] = ["hard", "soft", "still"].map(|n| image::open(shot(n)).expect("png").into_luma8());
    // Steep steps between neighbouring pixels: hard shadows' edges (and the
    // silhouettes, the same in every picture) make them; penumbrae and
    // accumulated sub-frames spread them out.
    let steep = |i: &image::GrayImage| {
        let (w, h) = i.dimensions();
        let step = |a: u32, b: u32, c: u32, d: u32| i.get_pixel(a, b).0[0].abs_diff(i.get_pixel(c, d).0[0]) > 100;
        let across = (0..h).flat_map(|y| (1..w).map(move |x| (x, y))).filter(|&(x, y)| step(x - 1, y, x, y));
        let down = (1..h).flat_map(|y| (0..w).map(move |x| (x, y))).filter(|&(x, y)| step(x, y - 1, x, y));
        across.count() + down.count()
    };
    let (h, s, a) = (steep(&hard), steep(&soft), steep(&still));
    assert!(s * 5 < h * 4 && a < s, "steep steps: hard {h}, soft {s}, 16 samples {a}");
    let rendered = shot("rendered");
    let scene = scene.to_str().expect("path");
    let args = ["render", scene, "-o", rendered.to_str().expect("path"), "--size", "96x96", "--msaa", "1"];
    let o = glint(&[&args[..], &["--spp", "16"]].concat());
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let rendered = image::open(&rendered).expect("png").into_luma8();
    let differing = still.pixels().zip(rendered.pixels()).filter(|(p, q)| p.0[0].abs_diff(q.0[0]) > 8).count();
    assert!(differing < 20, "the viewer's 16-sample frame differs from glint render --spp 16 in {differing} pixels");
}

/// The anti-aliasing control (the overlay's and the web page's): "none"
/// draws what `glint render --post tonemap` does, "SMAA high" what the
/// scene's own `tonemap smaa` chain does.
#[test]
fn the_viewer_chooses_its_anti_aliasing_by_its_control() {
    let dir = tempfile::tempdir().expect("tempdir");
    let shot = |name: &str| dir.path().join(format!("{name}.png"));
    let at = |frame: u32, action: String| ["--at".to_owned(), format!("{frame}:{action}")];
    let args = ["--size", "96x96", "--msaa", "1", "--frames", "5", "--at", "1:overlay=off"]
        .map(str::to_owned)
        .into_iter()
        .chain(at(1, "set=antialiasing=1".into()))
        .chain(at(2, format!("screenshot={}", shot("none").display())))
        .chain(at(3, "set=antialiasing=5".into()))
        .chain(at(4, format!("screenshot={}", shot("smaa").display())));
    let scene = repo("tests/scenes/smaa.scn");
    let Some(out) = view_under_xvfb(&scene, &args.collect::<Vec<_>>()) else { return };
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let [none, smaa] = ["none", "smaa"].map(|n| image::open(shot(n)).expect("png").into_rgb8());
    let differing = |a: &image::RgbImage, b: &image::RgbImage| {
        a.pixels().zip(b.pixels()).filter(|(p, q)| p.0.iter().zip(q.0).any(|(x, y)| x.abs_diff(y) > 8)).count()
    };
    let scene = scene.to_str().expect("path");
    for (name, post, shown) in [("rendered_none", "tonemap", &none), ("rendered_smaa", "tonemap smaa", &smaa)] {
        let file = shot(name);
        let args = ["render", scene, "-o", file.to_str().expect("path"), "--size", "96x96", "--msaa", "1"];
        let o = glint(&[&args[..], &["--post", post]].concat());
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let rendered = image::open(&file).expect("png").into_rgb8();
        let off = differing(shown, &rendered);
        assert!(off < 10, "the viewer's frame differs from glint render --post '{post}' in {off} pixels");
    }
    let smoothed = differing(&none, &smaa);
    assert!(smoothed > 30, "SMAA changes the edges' pixels: {smoothed}");
}
