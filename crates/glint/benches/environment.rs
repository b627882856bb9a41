//! Image-based lighting's costs, as wall time of work waited for on the GPU
//! (on lavapipe that is the GPU time; on a real GPU it includes a submission's
//! round trip): prefiltering a 1024 × 512 environment, and the showcase at
//! 1280 × 720 with its environment and without (its gradient sky and ambient
//! light instead), in alternating rounds so both see the same machine.
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
    let mut scenes = [(lit, Vec::new()), (plain, Vec::new())];
    let mut renderers: Vec<(Renderer, Vec<glint::Entity>)> = (scenes.iter())
        .map(|(desc, _)| {
            let mut renderer = Renderer::new(&gpu);
            let entities = renderer.place_scene(desc).entities;
            (renderer, entities)
        })
        .collect();
    for round in 0..=ROUNDS {
        for ((desc, times), (renderer, entities)) in scenes.iter_mut().zip(&mut renderers) {
            for _ in 0..FRAMES {
                let t = Instant::now();
                let view = glint::View::new(desc.cameras[0]);
                renderer.render(entities.iter(), view, desc.lighting(), &mut target).expect("frame");
                wait(&gpu);
                if round > 0 {
                    times.push(t.elapsed().as_secs_f64() * 1e3);
                }
            }
        }
    }
    let [(_, with), (_, without)] = scenes;
    let with = summary("showcase 1280x720 with its environment, frame", with);
    let without = summary("showcase 1280x720 without it, frame", without);
    println!("the environment adds {:+.1} % to the frame", (with / without - 1.0) * 100.0);
}
