//! `glint render` sequences: animated GIF and PNG output, the turntable camera,
//! and frame ranges that a render farm can split a sequence into.

mod common;

use common::*;
use std::path::Path;

/// Render `scene` with `args` added, or `None` where no adapter lets it run.
fn render(scene: &str, out: &Path, args: &[&str]) -> Option<std::process::Output> {
    let mut all = vec!["render", scene, "-o", out.to_str().expect("path"), "--msaa", "1"];
    all.extend_from_slice(args);
    let out = glint(&all);
    if no_adapter(&out) {
        return None;
    }
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    Some(out)
}

fn rgba(path: &Path) -> image::RgbaImage {
    image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgba8()
}

/// The frames of an animation file, decoded.
fn frames_of(decoder: impl image::AnimationDecoder<'static>) -> Vec<image::Frame> {
    decoder.into_frames().collect_frames().expect("the animation decodes")
}

fn open(path: &Path) -> std::io::BufReader<std::fs::File> {
    std::io::BufReader::new(std::fs::File::open(path).expect("written"))
}

/// Mean absolute difference of the colour channels, 0..=255.
fn mean_difference(a: &image::RgbaImage, b: &image::RgbaImage) -> f64 {
    assert_eq!(a.dimensions(), b.dimensions());
    let sum: u64 =
        a.pixels().zip(b.pixels()).flat_map(|(p, q)| (0..3).map(move |c| u64::from(p.0[c].abs_diff(q.0[c])))).sum();
    sum as f64 / (3 * a.width() * a.height()) as f64
}

#[test]
fn gif_and_apng_hold_the_frames_rendered_one_by_one() {
    let model = repo("tests/models/animated.gltf");
    let model = model.to_str().expect("path");
    let dir = tempfile::tempdir().expect("temp dir");
    let sequence = ["--size", "48x32", "--frames", "4", "--fps", "4"];
    let Some(_) = render(model, &dir.path().join("f/%d.png"), &sequence) else { return };
    let pngs: Vec<_> = (0..4).map(|k| rgba(&dir.path().join(format!("f/{k}.png")))).collect();
    assert_ne!(pngs[0], pngs[3], "the model moves over the sequence");

    render(model, &dir.path().join("clip.png"), &[&sequence[..], &["--apng"]].concat()).expect("adapter");
    let apng = image::codecs::png::PngDecoder::new(open(&dir.path().join("clip.png"))).expect("a PNG");
    assert!(apng.is_apng().expect("readable"), "an animated PNG");
    let frames = frames_of(apng.apng().expect("APNG frames"));
    assert_eq!(frames.len(), 4);
    for (k, frame) in frames.iter().enumerate() {
        assert_eq!(frame.buffer(), &pngs[k], "APNG frame {k} is the PNG rendered alone, pixel for pixel");
        assert_eq!(frame.delay().numer_denom_ms(), (250, 1), "a quarter second each at 4 fps");
    }

    render(model, &dir.path().join("clip.gif"), &sequence).expect("adapter");
    let gif = image::codecs::gif::GifDecoder::new(open(&dir.path().join("clip.gif"))).expect("a GIF");
    let frames = frames_of(gif);
    assert_eq!(frames.len(), 4);
    for (k, frame) in frames.iter().enumerate() {
        // A GIF has 256 colours a frame: each frame is near its own PNG, and
        // nearer to it than to any other frame.
        let own = mean_difference(frame.buffer(), &pngs[k]);
        assert!(own < 3.0, "GIF frame {k} is {own:.2} from its PNG");
        for (j, other) in pngs.iter().enumerate().filter(|(j, p)| *j != k && **p != pngs[k]) {
            assert!(mean_difference(frame.buffer(), other) > own, "GIF frame {k} is nearer PNG {j}");
        }
        assert_eq!(frame.delay().numer_denom_ms(), (250, 1));
    }
}

#[test]
fn a_turntable_orbits_the_camera_once_over_the_sequence() {
    let model = repo("tests/models/cutout.obj");
    let model = model.to_str().expect("path");
    let dir = tempfile::tempdir().expect("temp dir");
    let png = |k: u32| rgba(&dir.path().join(format!("t/{k}.png")));
    let args = ["--size", "40x40", "--frames", "4", "--turntable"];
    let Some(_) = render(model, &dir.path().join("t/%d.png"), &args) else { return };
    render(model, &dir.path().join("still.png"), &["--size", "40x40"]).expect("adapter");
    assert_eq!(png(0), rgba(&dir.path().join("still.png")), "frame 0 is the camera as the scene puts it");
    let turned = (1..4).map(|k| mean_difference(&png(0), &png(k))).collect::<Vec<_>>();
    assert!(turned.iter().all(|&d| d > 0.5), "each quarter turn shows the model from another side: {turned:?}");
    // Frame 2 alone (the half turn) is turned by its place in the whole sequence.
    let half = dir.path().join("half/%d.png");
    render(model, &half, &["--size", "40x40", "--frames", "4", "--frame-range", "2..3", "--turntable"])
        .expect("adapter");
    assert_eq!(rgba(&dir.path().join("half/2.png")), png(2), "a turntable's range is posed as the whole run");
}

/// Render frames `0..6` of `scene` whole and as the ranges 0..2, 2-3,4 and
/// 5-5:1 (glint's form and a farm's) into separate folders, with `more`
/// arguments: every frame is the same, numbered the same. Returns the whole
/// run's frames (none without an adapter).
fn split_ranges_equal_the_whole_run(scene: &str, time: &str, more: &[&str]) -> Vec<image::RgbaImage> {
    let dir = tempfile::tempdir().expect("temp dir");
    let sequence = [&["--size", "48x48", "--frames", "6", "--fps", "5", "--time", time], more].concat();
    let Some(_) = render(scene, &dir.path().join("whole/%02d.png"), &sequence) else { return Vec::new() };
    for (k, range) in ["0..2", "2-3,4", "5-5:1"].iter().enumerate() {
        let folder = dir.path().join(format!("part{k}/%02d.png"));
        render(scene, &folder, &[&sequence[..], &["--frame-range", range]].concat()).expect("adapter");
    }
    let whole: Vec<_> = (0..6).map(|f| rgba(&dir.path().join(format!("whole/{f:02}.png")))).collect();
    assert_ne!(whole[0], whole[5], "{scene}: the scene moves over the sequence");
    for (part, frames) in [(0, 0..2), (1, 2..5), (2, 5..6)] {
        let listed = std::fs::read_dir(dir.path().join(format!("part{part}"))).expect("folder").count();
        assert_eq!(listed, frames.len(), "{scene}: part {part} holds only its frames");
        for f in frames {
            let got = rgba(&dir.path().join(format!("part{part}/{f:02}.png")));
            assert!(got == whole[f], "{scene}: frame {f} of part {part} differs from the whole run's");
        }
    }
    whole
}

#[test]
fn a_split_cloth_sequence_equals_the_whole_run() {
    split_ranges_equal_the_whole_run("tests/scenes/cloth_debug.scn", "0", &[]);
}

#[test]
fn a_split_particle_sequence_equals_the_whole_run() {
    split_ranges_equal_the_whole_run("tests/scenes/emitter.scn", "0.5", &[]);
}

#[test]
fn a_split_school_sequence_equals_the_whole_run() {
    split_ranges_equal_the_whole_run("tests/scenes/school.scn", "0", &[]);
}

#[test]
fn a_split_accumulated_sequence_equals_the_whole_run() {
    // Each frame 4 sub-frames at its time: the school and its emitter, which
    // step on the GPU, step once a frame, and chunks still equal the whole run.
    let whole = split_ranges_equal_the_whole_run("tests/scenes/school.scn", "0", &["--spp", "4"]);
    let Some(first) = whole.first() else { return };
    let dir = tempfile::tempdir().expect("temp dir");
    let one = dir.path().join("one.png");
    render("tests/scenes/school.scn", &one, &["--size", "48x48"]).expect("adapter");
    let difference = mean_difference(first, &rgba(&one));
    assert!(difference > 0.05 && difference < 30.0, "4 samples smooth the edges of 1 ({difference})");
}

#[test]
fn a_chunk_past_the_posing_budget_steps_there_a_frame_at_a_time() {
    // An emitter stepping every 0.1 ms: frame 12 of a sequence at 1 fps is
    // 120,000 steps from its start, more than one pose may take (100,000),
    // but each frame is 10,000 steps on from the last, as the whole run goes.
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = dir.path().join("fine.scn");
    let text = "{\n\"classname\" \"camera\"\n\"origin\" \"0 1 4\"\n\"target\" \"0 1 0\" }\n\
                { \"classname\" \"emitter\"\n\"rate\" \"40\"\n\"lifetime\" \"0.5 1.5\"\n\"speed\" \"1 2\"\n\
                \"size\" \"0.2\"\n\"dt\" \"0.0001\"\n\"seed\" \"9\" }\n";
    std::fs::write(&scene, text).expect("written");
    let scene = scene.to_str().expect("path");
    let alone = glint(&["render", scene, "-o", dir.path().join("alone.png").to_str().expect("path"), "--time", "12"]);
    if no_adapter(&alone) {
        return;
    }
    assert_eq!(alone.status.code(), Some(1), "{}", stderr(&alone));
    assert!(stderr(&alone).contains("more than the 100000 steps one pose may take"), "{}", stderr(&alone));
    for backend in ["vulkan", "gl"] {
        let sequence = ["--size", "32x32", "--frames", "13", "--fps", "1"];
        let run = |folder: &str, more: &[&str]| {
            let out = dir.path().join(format!("{backend}/{folder}/%02d.png"));
            let args =
                [&["render", scene, "-o", out.to_str().expect("path"), "--msaa", "1"], &sequence[..], more].concat();
            let o = glint_with(&args, &[("WGPU_BACKEND", backend)]);
            assert_eq!(o.status.code(), Some(0), "{backend}: {}", stderr(&o));
        };
        run("whole", &[]);
        run("chunk", &["--frame-range", "12"]);
        let frame = |folder: &str| rgba(&dir.path().join(format!("{backend}/{folder}/12.png")));
        assert!(frame("whole") == frame("chunk"), "{backend}: the chunk's frame 12 differs from the whole run's");
        assert_ne!(frame("whole"), rgba(&dir.path().join(format!("{backend}/whole/11.png"))), "the particles move");
    }
}

#[test]
fn sequence_arguments_are_checked_before_any_frame() {
    let model = repo("tests/models/animated.gltf");
    let model = model.to_str().expect("path");
    let dir = tempfile::tempdir().expect("temp dir");
    let out = |name: &str| dir.path().join(name).to_str().expect("path").to_owned();
    let cases: [(&[&str], &str); 11] = [
        (&["-o", &out("a.png"), "--spp", "0"], "0 is not in 1..=4096"),
        (&["-o", &out("a.png"), "--post", "tonemap blur"], "--post: 'blur' is not a post effect"),
        (&["-o", &out("a.png"), "--spp", "4097"], "4097 is not in 1..=4096"),
        (&["-o", &out("a.gif"), "--apng"], "--apng writes a PNG"),
        (&["-o", &out("a.png"), "--frames", "3"], "several frames need a numbered output"),
        (
            &["-o", &out("%d.png"), "--frames", "3", "--frame-range", "2..4"],
            "reaches frame 3, past the sequence's 3 frames",
        ),
        (&["-o", &out("%d.png"), "--frames", "3", "--frame-range", "2..2"], "'2..2' is empty"),
        (&["-o", &out("%d.png"), "--frames", "3", "--frame-range", "2-1"], "runs backwards (2 is after 1)"),
        (&["-o", &out("%d.png"), "--frames", "3", "--frame-range", "0-2:0"], "a step of 0"),
        (&["-o", &out("a.gif"), "--frames", "3", "--skip-existing"], "an animation is written whole"),
        (&["-o", "/nonexistent/dir/a.gif", "--frames", "2"], "/nonexistent/dir/a.gif: cannot create"),
    ];
    for (args, want) in cases {
        let o = glint(&[&["render", model, "--size", "8x8"], args].concat());
        if no_adapter(&o) {
            return;
        }
        assert_eq!(o.status.code(), Some(1), "{args:?}: {}", stderr(&o));
        assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));
        assert!(stderr(&o).contains(want), "{args:?}: '{}' should say '{want}'", stderr(&o));
    }
    // A full device is a write error naming it, not a panic or an exit 0.
    if Path::new("/dev/full").exists() {
        let o = glint(&["render", model, "--size", "8x8", "--frames", "2", "-o", "/dev/full", "--apng"]);
        assert_write_failed(&o, "/dev/full");
    }
}

#[test]
fn a_rerun_chunk_skips_the_frames_on_disk_and_prints_a_line_a_frame() {
    let scene = "tests/scenes/emitter.scn";
    let dir = tempfile::tempdir().expect("temp dir");
    let frames = dir.path().join("f/%d.png");
    let sequence = ["--size", "32x32", "--frames", "4", "--fps", "5", "--time", "0.5"];
    let Some(first) = render(scene, &frames, &sequence) else { return };
    // Not a terminal: a line a frame, for a farm's log.
    let lines: Vec<String> = stderr(&first).lines().filter(|l| l.starts_with("frame ")).map(str::to_owned).collect();
    assert_eq!(lines.len(), 4, "{}", stderr(&first));
    assert!(lines[1].starts_with("frame 1: time 0.7000 s, drawn and written in "), "{}", lines[1]);
    let path = |k: u32| dir.path().join(format!("f/{k}.png"));
    let before: Vec<_> = (0..4).map(|k| rgba(&path(k))).collect();
    let written = |k: u32| std::fs::metadata(path(k)).and_then(|m| m.modified()).expect("written");
    let times: Vec<_> = (0..4).map(written).collect();
    std::fs::remove_file(path(2)).expect("removed");
    let again = render(scene, &frames, &[&sequence[..], &["--skip-existing"]].concat()).expect("adapter");
    let text = stderr(&again);
    let lines: Vec<&str> = text.lines().filter(|l| l.starts_with("frame ")).collect();
    assert_eq!(lines.len(), 1, "only the missing frame: {text}");
    assert!(lines[0].starts_with("frame 2: "), "{}", lines[0]);
    assert_eq!(rgba(&path(2)), before[2], "drawn again as in the whole run");
    for k in [0, 1, 3] {
        assert_eq!(written(k), times[k as usize], "frame {k} was left alone");
    }
    let all_there = render(scene, &frames, &[&sequence[..], &["--skip-existing"]].concat()).expect("adapter");
    assert!(stderr(&all_there).contains("nothing to render"), "{}", stderr(&all_there));
    let leftovers = std::fs::read_dir(dir.path().join("f")).expect("folder").count();
    assert_eq!(leftovers, 4, "no .part files left behind");
}
