//! The explained frame ([`Renderer::set_explaining`]) is the frame: its draw
//! calls and draws add up to each view's `FrameStats`, in every pass, on every
//! path (culled on the GPU or CPU, Vulkan and GL, drawn as on WebGL2, naive),
//! and every batch's decoded key agrees with what it draws.

mod common;

use glint::render::{FrameCalls, FrameMode, PassType};
use glint::{FrameStats, Gpu, OffscreenTarget, Renderer, World};

/// Three frames of `scene` at `time`, built as `mode`, explained: each view's
/// statistics and the last frame's calls (and its outline).
fn explained(gpu: &Gpu, scene: &str, time: f32, mode: FrameMode) -> (Vec<FrameStats>, FrameCalls, Vec<String>) {
    let desc = glint::asset::load_scene(&common::repo_root().join(scene)).expect("scene loads");
    let mut renderer = Renderer::new(gpu);
    renderer.set_mode(mode);
    renderer.set_explaining(true);
    let mut world = World::place(desc, &mut renderer).expect("placed");
    let views = world.views(None);
    let mut target = OffscreenTarget::new(gpu, 96, 64, 1).expect("target");
    world.pose(time, &mut renderer).expect("posed");
    let mut stats = Vec::new();
    for _ in 0..3 {
        stats = world.draw(&mut renderer, &views, &mut target).expect("frame");
    }
    renderer.wait_for_counts(&mut stats);
    let calls = renderer.explained().expect("explaining").clone();
    (stats, calls, renderer.frame_outline().to_vec())
}

/// Every check of the explained frame against its statistics.
fn check(scene: &str, stats: &[FrameStats], calls: &FrameCalls, outline: &[String], naive: bool) {
    assert!(!calls.passes.is_empty(), "{scene}: passes written down");
    for pass in &calls.passes {
        assert!(
            outline.contains(&pass.group),
            "{scene}: pass '{}' in group '{}' of the outline",
            pass.name,
            pass.group
        );
        if pass.kind == PassType::Compute {
            assert!(pass.draw_calls.is_empty(), "{scene}: a compute pass draws nothing");
        }
    }
    for (k, s) in stats.iter().enumerate() {
        let forward: Vec<_> = calls.draw_calls(k, false).collect();
        let early = forward.iter().filter(|c| !c.late);
        assert_eq!(early.clone().count() as u32, s.draw_calls, "{scene} view {k}: draw calls");
        assert_eq!(early.map(|c| c.draws).sum::<u32>(), s.draws, "{scene} view {k}: draws");
        assert_eq!(forward.iter().filter(|c| c.late).count() as u32, s.late_draw_calls, "{scene} view {k}: late calls");
        let shadow: Vec<_> = calls.draw_calls(k, true).collect();
        assert_eq!(shadow.len() as u32, s.passes.shadow.draw_calls, "{scene} view {k}: shadow calls");
        assert_eq!(shadow.iter().map(|c| c.draws).sum::<u32>(), s.passes.shadow.draws, "{scene} view {k}");
        for call in forward.iter().chain(&shadow) {
            if call.what == "batches" {
                assert_eq!(call.batches.len() as u32, call.draws, "{scene}: a batch is a draw");
                assert_eq!(call.instances, call.batches.iter().map(|b| u64::from(b.instances)).sum::<u64>());
            }
            let mut changed_and_kept = [call.changed.clone(), call.kept.clone()].concat();
            changed_and_kept.sort();
            changed_and_kept.dedup();
            assert_eq!(changed_and_kept.len(), call.changed.len() + call.kept.len(), "{scene}: set or kept, not both");
            for b in &call.batches {
                let key = u64::from_str_radix(b.key.trim_start_matches("0x"), 16).expect("hex key");
                assert_eq!((key >> 56) as u8, b.stage, "{scene}: the stage is the key's top byte");
                if !naive {
                    assert_eq!(b.blended, b.features.iter().any(|f| f == "ALPHA_BLEND"), "{scene}: {b:?}");
                    assert_eq!(b.blended, b.texture_set.is_none(), "{scene}: binned keys hold the texture set");
                }
                assert!(!b.material_name.is_empty() && !b.mesh_name.starts_with("shape "), "{scene}: named: {b:?}");
                assert!(
                    b.queue == "opaque"
                        || b.queue == "alpha-test"
                        || b.queue == "transparent"
                        || b.queue.starts_with("render_order")
                );
            }
        }
        // Within a pass, batches come in key order for the stage (the optimized frame sorts).
        if !naive {
            for pass in calls.of_view(k).into_iter().filter(|p| !p.is_shadow()) {
                let stages: Vec<u8> =
                    pass.draw_calls.iter().filter(|c| !c.late).flat_map(|c| &c.batches).map(|b| b.stage).collect();
                assert!(stages.windows(2).all(|w| w[0] <= w[1]), "{scene} '{}': stages in order {stages:?}", pass.name);
            }
        }
    }
}

/// The scenes: two views with a render target, post and point-light
/// shadows; blended and stencilled states; particles; a cloth and sun shadows.
const SCENES: [(&str, f32); 4] = [
    ("scenes/monitor.scn", 0.0),
    ("tests/scenes/states.scn", 0.0),
    ("tests/scenes/emitter.scn", 1.0),
    ("tests/scenes/cloth_debug.scn", 0.2),
];

#[test]
fn explained_calls_add_up_to_the_frame_stats_on_every_path() {
    let gpus = [("default", common::gpu()), ("GL", common::gl_gpu()), ("WebGL2 limits", common::webgl2_gpu())];
    for (name, gpu) in gpus {
        let Some(gpu) = gpu else { return };
        for (scene, time) in SCENES {
            let (stats, calls, outline) = explained(gpu, scene, time, FrameMode::Optimized);
            check(&format!("{scene} on {name}"), &stats, &calls, &outline, false);
        }
    }
}

#[test]
fn the_naive_frame_is_one_call_per_instance_and_explained_as_such() {
    let Some(gpu) = common::gpu() else { return };
    let (stats, calls, outline) = explained(gpu, "tests/scenes/states.scn", 0.0, FrameMode::Naive);
    check("naive states.scn", &stats, &calls, &outline, true);
    let batches: Vec<_> = calls.draw_calls(0, false).filter(|c| c.what == "batches").collect();
    assert_eq!(batches.len() as u64, stats[0].instances_submitted, "one draw_indexed per instance");
    assert!(batches.iter().all(|c| c.command == "draw_indexed" && c.instances == 1 && c.kept.is_empty()));
}

#[test]
fn explaining_stops_and_leaves_nothing() {
    let Some(gpu) = common::gpu() else { return };
    let mut renderer = Renderer::new(gpu);
    assert!(renderer.explained().is_none(), "not explaining");
    renderer.set_explaining(true);
    renderer.set_explaining(false);
    assert!(renderer.explained().is_none());
}
