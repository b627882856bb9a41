//! Image-based lighting's costs, as wall time of work waited for on the GPU
//! (on lavapipe that is the GPU time; on a real GPU it includes a submission's
//! round trip): prefiltering a 1024 × 512 environment, and the showcase at
//! 1280 × 720 with its environment, without (its gradient sky and ambient
//! light instead), and with its environment and screen-space ambient occlusion,
//! in alternating rounds so all see the same machine; with ambient occlusion,
//! its passes' share of the frame's GPU time (timestamp queries, where the
//! adapter has them), and the depth pre-pass's, which draws the view's depth
//! for the forward pass as well (`render/passes/ambient_occlusion.rs`).
//! Run: `cargo bench -p glint --bench environment` (median, min and max of each).

use glint::asset::EnvironmentImage;
use glint::{Gpu, OffscreenTarget, Renderer};
use std::time::Instant;

const ROUNDS: usize = 5;
const FRAMES: usize = 4;

fn wait(gpu: &Gpu) {
    gpu.device.poll(wgpu::PollType::wait_indefinitely()).expect("the GPU finished");
}

fn summary(name: &str, mut ms: Vec<f64>) -> f64 {
    ms.sort_by(f64::total_cmp);
    let median = ms[ms.len() / 2];
    println!("{name}: median {median:.1} ms (min {:.1}, max {:.1}, {} runs)", ms[0], ms[ms.len() - 1], ms.len());
    median
}

fn main() {
    let gpu = Gpu::headless().expect("an adapter");
    println!("adapter: {}", gpu.info().name);
    // Two environments, alternated so each prefilter has work to do.
    let make = |k: f32| {
        EnvironmentImage::from_fn("bench", 1024, 512, move |d| {
            let sun = d.dot(glam::Vec3::new(0.4, 0.5, -0.77).normalize()).max(0.0).powi(200) * 500.0;
            glam::Vec3::new(0.3 + 0.2 * d.y + k, 0.4 + 0.3 * d.y, 0.6 + 0.4 * d.y) + glam::Vec3::splat(sun)
        })
    };
    let images = [make(0.0), make(0.1)];
    let mut renderer = Renderer::new(&gpu);
    let ids = images.iter().map(|i| renderer.add_environment(i)).collect::<Vec<_>>();
    wait(&gpu);
    let mut prefilter = Vec::new();
    for round in 0..=2 * ROUNDS {
        let light = glint::scene::EnvironmentLight::new(glint::scene::EnvironmentSource::Image(ids[round % 2]));
        let environment = glint::Environment { light: Some(light), ..Default::default() };
        let t = Instant::now();
        assert!(renderer.prefilter_environment(&glint::Lighting::new(&[], environment)).expect("prefiltered"));
        wait(&gpu);
        // The first also builds the pipelines and the BRDF table.
        if round > 0 {
            prefilter.push(t.elapsed().as_secs_f64() * 1e3);
        }
    }
    summary("prefilter 1024x512 (specular levels + harmonics)", prefilter);

    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let options = glint::asset::LoadOptions { asset_roots: vec![root.clone()], ..Default::default() };
    let lit = glint::asset::load_scene_with(&root.join("scenes/showcase.scn"), options).expect("the showcase");
    let mut plain = lit.clone();
    plain.environment.light = None;
    let mut target = OffscreenTarget::new(&gpu, 1280, 720, 1).expect("target");
    let views = [
        glint::View::new(lit.cameras[0]),
        glint::View::new(plain.cameras[0]),
        glint::View::new(lit.cameras[0]).with_ambient_occlusion(Some(Default::default())),
    ];
    let mut scenes = [(lit.clone(), Vec::new()), (plain, Vec::new()), (lit, Vec::new())];
    let mut renderers: Vec<(Renderer, Vec<glint::Entity>)> = (scenes.iter())
        .map(|(desc, _)| {
            let mut renderer = Renderer::new(&gpu);
            let entities = renderer.place_scene(desc).entities;
            (renderer, entities)
        })
        .collect();
    let timed = renderers[2].0.enable_gpu_timing();
    // Per timed frame: ambient occlusion's GPU time and the frame's.
    let mut shares = Vec::new();
    for round in 0..=ROUNDS {
        for (k, ((desc, times), (renderer, entities))) in scenes.iter_mut().zip(&mut renderers).enumerate() {
            for _ in 0..FRAMES {
                let t = Instant::now();
                renderer.render(entities.iter(), views[k].clone(), desc.lighting(), &mut target).expect("frame");
                wait(&gpu);
                if round > 0 {
                    times.push(t.elapsed().as_secs_f64() * 1e3);
                }
                let gpu_times = renderer.read_gpu_times().filter(|_| round > 0 && timed && k == 2);
                if let Some(g) = gpu_times {
                    let total = g.shadow_ms.unwrap_or(0.0) + g.forward_ms + g.post_ms.iter().sum::<f64>();
                    let (ao, depth) = (g.ambient_occlusion_ms.unwrap_or(0.0), g.depth_prepass_ms.unwrap_or(0.0));
                    shares.push((ao, depth, g.forward_ms, total + ao + depth));
                }
            }
        }
    }
    let [(_, with), (_, without), (_, occluded)] = scenes;
    let with = summary("showcase 1280x720 with its environment, frame", with);
    let without = summary("showcase 1280x720 without it, frame", without);
    println!("the environment adds {:+.1} % to the frame", (with / without - 1.0) * 100.0);
    let occluded = summary("showcase 1280x720 with its environment and ambient occlusion, frame", occluded);
    println!("ambient occlusion adds {:+.1} % to the frame (wall time)", (occluded / with - 1.0) * 100.0);
    if shares.is_empty() {
        println!("no GPU timestamps on this adapter: no GPU share");
        return;
    }
    let ao = summary("ambient occlusion passes (occlusion, blur), GPU", shares.iter().map(|s| s.0).collect());
    let depth = summary("depth pre-pass (the view's depth, shared with the forward pass), GPU", {
        shares.iter().map(|s| s.1).collect()
    });
    summary("forward pass (testing the pre-pass's depth for equality), GPU", shares.iter().map(|s| s.2).collect());
    let frame = summary("the frame's passes with it, GPU", shares.iter().map(|s| s.3).collect());
    println!("ambient occlusion's share of the frame's GPU time: {:.1} %", ao / frame * 100.0);
    println!("the depth pre-pass's share: {:.1} %", depth / frame * 100.0);
}
