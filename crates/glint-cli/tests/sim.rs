//! `glint sim` as a user meets it: cloth trajectories and benchmarks, the
//! published mesh format, fish schools and particle emitters, their JSON and
//! their bad input (no GPU needed but where a test says so).

mod common;

use common::*;
use std::path::Path;

/// The CSV a `glint sim cloth` run wrote: header and rows of numbers.
fn read_trajectory(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).expect("trajectory written");
    let mut lines = text.lines();
    let header = lines.next().expect("a header").split(',').map(str::to_owned).collect();
    let rows = lines.map(|l| l.split(',').map(|v| v.parse().expect("a number")).collect()).collect();
    (header, rows)
}

#[test]
fn sim_cloth_bench_prints_one_json_object_for_either_solve() {
    for solve in ["converged", "realtime"] {
        let args = ["sim", "cloth", "--sheet", "0.2,0.1", "--resolution", "9,5", "--fix", "x<=0.05", "--steps", "5"];
        let out = glint(&[&args[..], &["--solve", solve, "--bench", "--json"]].concat());
        assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
        let text = String::from_utf8(out.stdout).expect("utf-8");
        assert_eq!(text.lines().count(), 1, "one object: {text}");
        let report: serde_json::Value = serde_json::from_str(&text).expect("JSON");
        assert_eq!(report["solve"], solve);
        assert_eq!((report["nodes"].as_u64(), report["steps"].as_u64()), (Some(45), Some(5)), "{report}");
        assert!(report["steps_per_second"].as_f64().is_some_and(|v| v > 0.0), "{report}");
        let newton = report["newton_iterations_per_step"].as_f64().expect("newton iterations");
        let factorizations = report["factorizations_per_step"].as_f64().expect("factorisations");
        assert!(factorizations > 0.0 && factorizations <= newton, "{report}");
        if solve == "realtime" {
            // At most three iterations a step, unless a step was halved, each
            // on a fresh factor.
            let substeps = report["substeps_per_step"].as_f64().expect("substeps");
            assert!(newton <= 3.0 * substeps && factorizations == newton, "{report}");
        }
    }
    assert_ne!(
        glint(&["sim", "cloth", "--sheet", "1,1", "--resolution", "3,3", "--json"]).status.code(),
        Some(0),
        "--json needs --bench"
    );
}

#[test]
fn sim_cloth_gpu_times_its_steps_beside_both_cpu_solves_and_says_how_far_it_ends() {
    // A strip hanging from one end, swinging down for 10 steps.
    let sheet = ["sim", "cloth", "--sheet", "0.4,0.1", "--resolution", "9,3", "--fix", "x<=0.01", "--steps", "10"];
    let out = glint(&[&sheet[..], &["--gpu", "--vs-cpu", "--bench", "--json"]].concat());
    if no_adapter(&out) {
        return;
    }
    if stderr(&out).contains("compute path") {
        eprintln!("this adapter has no compute: {}", stderr(&out));
        return;
    }
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let r: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    let (gpu, realtime, converged) = (&r["gpu"], &r["realtime"], &r["converged"]);
    let solves = [gpu, realtime, converged].map(|side| side["solve"].as_str());
    assert_eq!(solves, [Some("gpu"), Some("realtime"), Some("converged")], "{r}");
    assert_eq!((gpu["nodes"].as_u64(), gpu["steps"].as_u64()), (Some(27), Some(10)), "{r}");
    assert_eq!(gpu["newton_iterations_per_step"].as_f64(), Some(60.0), "the default sweeps: {r}");
    assert!(gpu["colours"].as_u64().is_some_and(|c| (2..=13).contains(&c)), "{r}");
    let speed = |side: &serde_json::Value| side["steps_per_second"].as_f64().expect("a number");
    let speedup = r["gpu_speedup_over_converged"].as_f64().expect("a number");
    assert!((speedup - speed(gpu) / speed(converged)).abs() < 1e-9 * speedup, "{r}");
    // The free end has fallen about 5 cm; the GPU's inexact steps leave its
    // nodes 0.7 cm from the converged solve's on average, 1.3 cm at most.
    let (mean, worst) = (r["gpu_from_converged_mean_m"].as_f64(), r["gpu_from_converged_worst_m"].as_f64());
    assert!(mean.is_some_and(|m| m < 0.01) && worst.is_some_and(|w| w < 0.03), "{r}");
    // Its trajectory, read back each step.
    let dir = tempfile::tempdir().expect("temp dir");
    let csv = dir.path().join("gpu.csv");
    let out = glint(&[&sheet[..], &["--gpu", "--iterations", "20", "--out", csv.to_str().expect("path")]].concat());
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let (header, rows) = read_trajectory(&csv);
    assert_eq!((header.len(), rows.len()), (2 + 27 * 3, 10));
    assert!((rows[9][1] - 0.1).abs() < 1e-9, "time {}", rows[9][1]);
    // The free end fell; the pinned one did not move.
    assert!(rows[9][2 + 3 * 8 + 2] < -0.01 && rows[9][2 + 2] == 0.0, "{:?}", &rows[9][..6]);
    // What it refuses.
    for (args, says) in [
        (&["--gpu", "--integrator", "static"][..], "a static solve"),
        (&["--iterations", "5"][..], "--gpu"),
        (&["--gpu", "--acceleration", "1"][..], "0 <= ρ < 1"),
        (&["--gpu", "--solve", "realtime"][..], "cannot be used with"),
        (&["--solve", "gpu"][..], "the GPU solve is --gpu here"),
    ] {
        let out = glint(&[&sheet[..], args].concat());
        assert_ne!(out.status.code(), Some(0), "{args:?}");
        assert!(stderr(&out).contains(says), "{args:?}: {}", stderr(&out));
    }
}

#[test]
fn sim_cloth_writes_one_csv_row_per_step_and_benchmarks() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("traj.csv");
    let csv_arg = csv.to_str().unwrap();
    // A 0.2 m × 0.1 m sheet of 5 × 3 nodes clamped by its first two columns
    // (x = 0 and 0.05: one column alone is a hinge, which has no well-posed
    // static equilibrium near flat), writing `csv`.
    let sheet = |more: &[&str]| {
        let common =
            ["sim", "cloth", "--sheet", "0.2,0.1", "--resolution", "5,3", "--fix", "x<=0.05", "--out", csv_arg];
        glint(&[&common[..], more].concat())
    };
    let out = sheet(&[
        "--thickness",
        "1e-3",
        "--young",
        "1e6",
        "--poisson",
        "0.3",
        "--density",
        "200",
        "--gravity",
        "0 0 -9.81",
        "--dt",
        "0.01",
        "--steps",
        "4",
        "--integrator",
        "implicit-euler",
        "--bench",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let (header, rows) = read_trajectory(&csv);
    assert_eq!(header.len(), 2 + 3 * 15);
    assert_eq!(&header[..5], ["step", "t", "x1", "y1", "z1"]);
    assert_eq!(header.last().unwrap(), "z15");
    assert_eq!(rows.len(), 4);
    for (k, row) in rows.iter().enumerate() {
        assert_eq!(row[0], (k + 1) as f64);
        assert!((row[1] - 0.01 * (k + 1) as f64).abs() < 1e-12, "time {}", row[1]);
    }
    // Node 1 (x = 0) is pinned; node 5 (the far corner) falls.
    let last = rows.last().unwrap();
    assert_eq!(&last[2..5], [0.0, 0.0, 0.0]);
    assert!(last[2 + 3 * 4 + 2] < -1e-4, "the free corner falls: z5 = {}", last[2 + 3 * 4 + 2]);
    let report = String::from_utf8_lossy(&out.stdout);
    assert!(report.contains("15 nodes (6 pinned)") && report.contains("steps/s"), "{report}");
    assert!(report.contains("Newton iterations/step"), "{report}");

    // A static solve writes one row: the equilibrium (of a stiffer plate, whose
    // tip sags about 1.5 mm rather than as far as it is long).
    let out = sheet(&["--integrator", "static", "--young", "1e9"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let (_, rows) = read_trajectory(&csv);
    assert_eq!(rows.len(), 1);
    assert!(rows[0][2 + 3 * 4 + 2] < 0.0, "the free corner sags");
}

#[test]
fn sim_cloth_reads_the_published_mesh_format_and_rejects_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = dir.path().join("plate.txt");
    std::fs::write(&mesh, "# two triangles\n*Nodes\n0,0,0\n1,0,0\n1,1,0\n0,1,0\n*Triangles\n1,2,3\n1,3,4\n").unwrap();
    let out = glint(&["sim", "cloth", "--mesh", mesh.to_str().unwrap(), "--fix", "nodes 1 2", "--steps", "2"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));

    std::fs::write(&mesh, "*Nodes\n0,0,0\n1,0,0\n*Triangles\n1,2,7\n").unwrap();
    let out = glint(&["sim", "cloth", "--mesh", mesh.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let errors = error_lines(&out);
    assert!(errors.len() == 1 && errors[0].contains("plate.txt:5: node 7"), "{errors:?}");

    for (args, says) in [
        (&["sim", "cloth", "--sheet", "1,1", "--resolution", "3,3", "--fix", "w<1"][..], "expected AXIS OP NUMBER"),
        (&["sim", "cloth", "--sheet", "1,1", "--resolution", "1,3"], "--resolution 2..=257"),
        (&["sim", "cloth", "--sheet", "1,1", "--resolution", "3,3", "--dt", "0"], "above 0"),
        (&["sim", "cloth", "--sheet", "1,1", "--resolution", "3,3", "--fix", "nodes 10"], "past the 9 nodes"),
        (&["sim", "cloth", "--sheet", "1,1", "--resolution", "3,3", "--collider", "sphere 0 0 0"], "not a collider"),
        (&["sim", "cloth", "--resolution", "3,3"], "required"),
    ] {
        let out = glint(args);
        assert_eq!(out.status.code(), Some(1), "{args:?}");
        assert!(stderr(&out).contains(says), "{args:?}: {}", stderr(&out));
    }
}

#[test]
fn sim_school_prints_its_statistics_and_benchmark_as_json() {
    let out = glint(&["sim", "school", "--fish", "3000", "--steps", "20", "--bench", "--json"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let r: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    assert_eq!((r["fish"].as_u64(), r["steps"].as_u64(), r["path"].as_str()), (Some(3000), Some(20), Some("cpu")));
    let (ms, rate) = (r["ms_per_step"].as_f64().unwrap(), r["steps_per_second"].as_f64().unwrap());
    assert!(ms > 0.0 && (rate * ms - 1000.0).abs() < 1e-6 * rate * ms, "{r}");
    assert!(r["mean_speed"].as_f64().unwrap() >= 1.0 - 1e-6, "{r}");
    let plain = glint(&["sim", "school", "--fish", "500", "--steps", "5", "--predator"]);
    assert!(String::from_utf8_lossy(&plain.stdout).starts_with("500 fish after 5 steps: mean speed"));
    assert_eq!(glint(&["sim", "school", "--fish", "0"]).status.code(), Some(1));
    assert_eq!(glint(&["sim", "school", "--json"]).status.code(), Some(1), "--json needs --bench");
}

#[test]
fn sim_school_vs_cpu_times_both_paths_from_one_start() {
    let out = glint(&["sim", "school", "--gpu", "--vs-cpu", "--fish", "3000", "--steps", "6", "--bench", "--json"]);
    if no_adapter(&out) {
        return;
    }
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let r: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    let (gpu, cpu) = (&r["gpu"], &r["cpu"]);
    assert_eq!((gpu["path"].as_str(), cpu["path"].as_str()), (Some("gpu"), Some("cpu")), "{r}");
    let ms = |side: &serde_json::Value| side["ms_per_step"].as_f64().expect("a number");
    let speedup = r["gpu_speedup"].as_f64().expect("a number");
    assert!((speedup - ms(cpu) / ms(gpu)).abs() < 1e-9 * speedup, "{r}");
    // One start, the same rules and neighbours: the two schools agree.
    let stat = |side: &serde_json::Value, key: &str| side[key].as_f64().expect("a number");
    for key in ["mean_speed", "polarisation", "nearest"] {
        assert!((stat(gpu, key) - stat(cpu, key)).abs() < 1e-3 * stat(cpu, key).abs().max(1.0), "{key}: {r}");
    }
    let text = glint(&["sim", "school", "--gpu", "--vs-cpu", "--fish", "500", "--steps", "2", "--bench"]);
    assert!(String::from_utf8_lossy(&text.stdout).contains("the gpu's steps: "), "{}", stderr(&text));
    assert_eq!(glint(&["sim", "school", "--vs-cpu", "--bench"]).status.code(), Some(1), "--vs-cpu needs --gpu");
}

#[test]
fn sim_chooses_where_a_scene_s_school_steps_for_render_explain_and_bench() {
    let dir = tempfile::tempdir().expect("temp dir");
    let png = dir.path().join("school.png");
    let (scene, png) = (repo("tests/scenes/school.scn"), png.to_str().expect("path").to_owned());
    let scene = scene.to_str().expect("path");
    let render =
        |sim: &str| glint(&["render", scene, "-o", &png, "--size", "48x48", "--time", "0.5", "--stats", "--sim", sim]);
    let out = render("cpu");
    if no_adapter(&out) {
        return;
    }
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let stats: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(stats["simulations"]["schools"], serde_json::json!({"cpu": 1, "gpu": 0}), "{stats}");
    // Asked for the GPU: there where the adapter computes (it culls on the GPU), else the CPU.
    let stats: serde_json::Value = serde_json::from_slice(&render("gpu").stdout).expect("JSON");
    let computes = stats["culling"] == "gpu";
    let expected =
        if computes { serde_json::json!({"cpu": 0, "gpu": 1}) } else { serde_json::json!({"cpu": 1, "gpu": 0}) };
    assert_eq!(stats["simulations"]["schools"], expected, "{stats}");
    let explained = glint(&["explain", scene, "--size", "48x48", "--time", "0.5", "--sim", "cpu"]);
    assert!(
        String::from_utf8_lossy(&explained.stdout).contains("simulations: school on the CPU"),
        "{}",
        stderr(&explained)
    );
    // bench --live --vs-cpu: the frame as asked, then every school on the CPU, in one run.
    let args =
        ["bench", scene, "--live", "30", "--frames", "2", "--warmup", "1", "--size", "48x48", "--json", "--vs-cpu"];
    let r: serde_json::Value = serde_json::from_slice(&glint(&args).stdout).expect("JSON");
    assert_eq!(r["live"]["simulations"]["schools"], expected, "{r}");
    assert_eq!(r["cpu_sim"]["simulations"]["schools"]["cpu"], 1, "{r}");
    let ms = |side: &str| r[side]["frame_ms_median"].as_f64().expect("a number");
    let speedup = r["sim"]["frame_speedup"].as_f64().expect("a number");
    assert!((speedup - ms("cpu_sim") / ms("live")).abs() < 1e-9 * speedup, "{r}");
    assert_eq!(glint(&["bench", scene, "--vs-cpu"]).status.code(), Some(1), "--vs-cpu needs --live");
    let still = glint(&["bench", scene, "--sim", "gpu"]);
    assert_eq!(still.status.code(), Some(1), "--sim needs --live on bench");
    assert!(stderr(&still).contains("--sim needs --live"), "{}", stderr(&still));
    // Bad choices are usage errors, said of the flag or the file's line.
    let bad = glint(&["render", scene, "-o", &png, "--sim", "fpga"]);
    assert_eq!(bad.status.code(), Some(1));
    assert!(stderr(&bad).contains("--sim"), "{}", stderr(&bad));
    let text = std::fs::read_to_string(scene)
        .expect("scene")
        .replace("\"seed\" \"4\" }", "\"seed\" \"4\"\n\"sim\" \"fpga\" }");
    let broken = dir.path().join("broken.scn");
    std::fs::write(&broken, text.replace("../../assets", &repo("assets").display().to_string())).expect("write");
    let out = glint(&["--allow-outside-assets", "check", broken.to_str().expect("path")]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(stderr(&out).contains("broken.scn:") && stderr(&out).contains("sim"), "{}", stderr(&out));
}

#[test]
fn sim_particles_times_an_emitter_on_the_cpu() {
    let out = glint(&["sim", "particles", "--alive", "20000", "--steps", "5", "--alpha", "--json"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let r: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    assert_eq!((r["path"].as_str(), r["blend"].as_str()), (Some("cpu"), Some("alpha")));
    // Rate × lifetime, within a particle of the schedule's rounding.
    assert!((r["alive"].as_i64().unwrap() - 20000).abs() <= 1, "{r}");
    assert!(r["ms_per_step"].as_f64().unwrap() > 0.0);
}
