//! Accumulated stills (`glint render --spp`, [`SubFrame`]): sub-frames with
//! the camera jittered within the pixel, averaged in HDR before the post
//! chain. On thin diagonal bars without MSAA, 16 samples come much closer to
//! a 256-sample accumulation than one sample does, and so does SMAA on bars
//! a few pixels wide; stills are the same every time; bright edges show the
//! average was taken before clamping; sub-frames out of order are errors. On
//! Vulkan, GL and the WebGL2 path.

mod common;

use glam::{Mat4, Quat, Vec3, Vec4};
use glint::asset::ShapeKind;
use glint::render::RenderError;
use glint::scene::{Background, PostEffect, ShadingModel, SmaaPreset};
use glint::{
    Camera, Entity, Environment, FrameInput, Gpu, Lighting, Material, OffscreenTarget, Renderer, SubFrame, View,
};

/// Side of the test images, in pixels.
const SIZE: u32 = 64;

/// The GPUs the tests draw on: the default one, GL, and GL within WebGL2's limits.
fn gpus() -> Vec<(&'static str, &'static Gpu)> {
    let all = [("default", common::gpu()), ("GL", common::gl_gpu()), ("GL, WebGL2 limits", common::gl_webgl2_gpu())];
    all.into_iter().filter_map(|(name, gpu)| Some((name, gpu?))).collect()
}

/// Five thin bars (0.02 units wide, about half a pixel) at shallow and steep
/// angles, unlit with linear value `value`, on black, seen face on by an
/// orthographic camera 2 units high.
fn bars(renderer: &mut Renderer, value: f32) -> Vec<Entity> {
    wide_bars(renderer, value, 0.02)
}

/// The bars, `width` units wide (a pixel is 1/32).
fn wide_bars(renderer: &mut Renderer, value: f32, width: f32) -> Vec<Entity> {
    let cube = renderer.add_shape(ShapeKind::Cube.mesh());
    let material = renderer.add_material(Material {
        shading: ShadingModel::Unlit,
        base_color: Vec4::new(value, value, value, 1.0),
        ..Material::default()
    });
    [(-0.6, 0.3), (-0.3, 0.7), (0.0, 0.45), (0.3, 1.2), (0.6, 0.15)]
        .into_iter()
        .map(|(x, angle)| {
            let place = Mat4::from_scale_rotation_translation(
                Vec3::new(width, 2.4, 0.02),
                Quat::from_rotation_z(angle),
                Vec3::new(x, 0.0, 0.0),
            );
            Entity::new(cube, material, place)
        })
        .collect()
}

/// The bars of `value` through `post` as a still of `samples` sub-frames
/// (1: a frame of its own), without MSAA.
fn still(gpu: &Gpu, value: f32, post: Vec<PostEffect>, samples: u32) -> image::RgbaImage {
    wide_still(gpu, (value, 0.02), post, samples)
}

/// As [`still`], of bars `width` units wide.
fn wide_still(gpu: &Gpu, (value, width): (f32, f32), post: Vec<PostEffect>, samples: u32) -> image::RgbaImage {
    let mut renderer = Renderer::new(gpu);
    let entities = wide_bars(&mut renderer, value, width);
    let camera = Camera::orthographic(2.0, 0.1, 20.0).looking_at(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO);
    let views = [View::new(camera).with_post(post)];
    let environment = Environment { background: Background::Color(Vec3::ZERO), ..Default::default() };
    let mut target = OffscreenTarget::new(gpu, SIZE, SIZE, 1).expect("target");
    for index in 0..samples {
        let input = FrameInput::new(&entities, Lighting::new(&[], environment))
            .views(&views)
            .sample(SubFrame { index, count: samples });
        renderer.render_frame(input, &mut target).expect("sub-frame");
    }
    target.read_rgba8(gpu).expect("readback")
}

/// The red channel of each pixel, 0..1, as stored (sRGB-encoded).
fn values(image: &image::RgbaImage) -> Vec<f64> {
    image.pixels().map(|p| f64::from(p.0[0]) / 255.0).collect()
}

/// The red channel of each pixel, 0..1, decoded to linear light.
fn linear(image: &image::RgbaImage) -> Vec<f64> {
    let decode = |c: f64| if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) };
    values(image).into_iter().map(decode).collect()
}

/// The pixels on an edge: neither black nor white in `reference`, or
/// differing between any of `images`.
fn edge_pixels(reference: &[f64], images: &[&[f64]]) -> Vec<usize> {
    (0..reference.len())
        .filter(|&k| {
            let partial = reference[k] > 0.02 && reference[k] < 0.98;
            partial || images.iter().any(|i| (i[k] - reference[k]).abs() > 0.02)
        })
        .collect()
}

/// The mean absolute difference of `image` from `reference` over `pixels`.
fn mean_error(image: &[f64], reference: &[f64], pixels: &[usize]) -> f64 {
    pixels.iter().map(|&k| (image[k] - reference[k]).abs()).sum::<f64>() / pixels.len() as f64
}

#[test]
fn sixteen_samples_come_close_to_two_hundred_and_fifty_six() {
    for (name, gpu) in gpus() {
        let reference = values(&still(gpu, 1.0, Vec::new(), 256));
        let one = values(&still(gpu, 1.0, Vec::new(), 1));
        let sixteen = values(&still(gpu, 1.0, Vec::new(), 16));
        let edges = edge_pixels(&reference, &[&one, &sixteen]);
        assert!(edges.len() > 200, "{name}: the bars' edges cover {} pixels", edges.len());
        let (e1, e16) = (mean_error(&one, &reference, &edges), mean_error(&sixteen, &reference, &edges));
        eprintln!("{name}: mean error over {} edge pixels: 1 sample {e1:.4}, 16 samples {e16:.4}", edges.len());
        assert!(e1 > 0.1, "{name}: one sample aliases the half-pixel bars ({e1:.4})");
        assert!(e16 < e1 / 3.0, "{name}: 16 samples {e16:.4} against 1 sample {e1:.4}");
        // Partly covered pixels: coverage shows as grey, not as steps of black and white.
        let grey = reference.iter().filter(|&&v| v > 0.1 && v < 0.9).count();
        let grey_one = one.iter().filter(|&&v| v > 0.1 && v < 0.9).count();
        assert!(grey > 100 && grey_one == 0, "{name}: {grey} grey pixels accumulated, {grey_one} in one sample");
    }
}

#[test]
fn a_still_is_the_same_every_time_and_one_sample_is_a_plain_frame() {
    for (name, gpu) in gpus() {
        let (a, b) = (still(gpu, 1.0, Vec::new(), 8), still(gpu, 1.0, Vec::new(), 8));
        assert!(a == b, "{name}: two 8-sample stills differ");
        let one = still(gpu, 1.0, Vec::new(), 1);
        let mut renderer = Renderer::new(gpu);
        let entities = bars(&mut renderer, 1.0);
        let camera = Camera::orthographic(2.0, 0.1, 20.0).looking_at(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO);
        let environment = Environment { background: Background::Color(Vec3::ZERO), ..Default::default() };
        let mut target = OffscreenTarget::new(gpu, SIZE, SIZE, 1).expect("target");
        renderer.render(&entities, View::new(camera), Lighting::new(&[], environment), &mut target).expect("frame");
        assert!(one == target.read_rgba8(gpu).expect("readback"), "{name}: SubFrame::ONE is not a plain frame");
        assert!(a != one, "{name}: 8 samples drew what one does");
    }
}

#[test]
fn sub_frames_are_averaged_in_hdr_before_the_post_chain() {
    // Bars 4x brighter than white: averaged in HDR and then clamped, a pixel
    // a quarter covered is white; clamped first, it would be the same grey
    // as bars of 1.0. The same through a Reinhard tonemap, which maps the
    // average, not the average of mapped values.
    let reinhard = vec![PostEffect::Tonemap { operator: glint::scene::Tonemap::Reinhard, exposure: 0.0 }];
    for (name, gpu) in gpus() {
        for post in [Vec::new(), reinhard.clone()] {
            let bright = linear(&still(gpu, 4.0, post.clone(), 16));
            let plain = linear(&still(gpu, 1.0, post.clone(), 16));
            let grey = (0..plain.len()).filter(|&k| plain[k] > 0.05 && plain[k] < 0.45).collect::<Vec<_>>();
            let brighter = grey.iter().filter(|&&k| bright[k] > plain[k] + 0.08).count();
            eprintln!("{name}, {} effects: {brighter} of {} grey edge pixels brighter", post.len(), grey.len());
            assert!(grey.len() > 50 && brighter * 10 > grey.len() * 9, "{name}: {brighter} of {}", grey.len());
            if post.is_empty() {
                let white = grey.iter().filter(|&&k| plain[k] >= 0.25 && bright[k] > 0.98).count();
                let quarter = grey.iter().filter(|&&k| plain[k] >= 0.25).count();
                assert_eq!(white, quarter, "{name}: pixels a quarter covered by 4.0 clamp to white");
            }
        }
    }
}

#[test]
fn pixels_on_an_edge_take_the_share_of_them_it_covers() {
    // A white square whose left edge runs 0.3 of a pixel into column 40 and
    // whose top edge runs 0.6 of a pixel up into row 20, on black: 256
    // sub-frames cover each pixel evenly, so a pixel's light is the share of
    // it the square covers (the jitter's scale and direction, both ways).
    let pixel = 2.0 / SIZE as f32;
    let (left, top) = (-1.0 + 40.3 * pixel, 1.0 - 20.4 * pixel);
    for (name, gpu) in gpus() {
        let mut renderer = Renderer::new(gpu);
        let cube = renderer.add_shape(ShapeKind::Cube.mesh());
        let white = Material { shading: ShadingModel::Unlit, base_color: Vec4::ONE, ..Material::default() };
        let material = renderer.add_material(white);
        let place = Mat4::from_scale_rotation_translation(
            Vec3::new(20.0, 20.0, 0.02),
            Quat::IDENTITY,
            Vec3::new(left + 10.0, top - 10.0, 0.0),
        );
        let entities = [Entity::new(cube, material, place)];
        let camera = Camera::orthographic(2.0, 0.1, 20.0).looking_at(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO);
        let views = [View::new(camera)];
        let environment = Environment { background: Background::Color(Vec3::ZERO), ..Default::default() };
        let mut target = OffscreenTarget::new(gpu, SIZE, SIZE, 1).expect("target");
        for index in 0..256 {
            let input = FrameInput::new(&entities, Lighting::new(&[], environment))
                .views(&views)
                .sample(SubFrame { index, count: 256 });
            renderer.render_frame(input, &mut target).expect("sub-frame");
        }
        let image = linear(&target.read_rgba8(gpu).expect("readback"));
        let at = |x: u32, y: u32| image[(y * SIZE + x) as usize];
        for (x, y, share) in [(40, 40, 0.7), (50, 20, 0.6), (40, 20, 0.42), (39, 40, 0.0), (41, 40, 1.0), (50, 19, 0.0)]
        {
            let got = at(x, y);
            assert!((got - share).abs() < 0.03, "{name}: pixel ({x}, {y}) holds {got:.3}, covered {share}");
        }
    }
}

#[test]
fn sub_frames_out_of_order_are_errors() {
    let Some(gpu) = common::gpu() else { return };
    let mut renderer = Renderer::new(gpu);
    let entities = bars(&mut renderer, 1.0);
    let views = [View::new(Camera::orthographic(2.0, 0.1, 20.0).looking_at(Vec3::Z * 5.0, Vec3::ZERO))];
    let mut target = OffscreenTarget::new(gpu, SIZE, SIZE, 1).expect("target");
    let mut draw = |index, count| {
        let input = FrameInput::new(&entities, Lighting::new(&[], Environment::default()))
            .views(&views)
            .sample(SubFrame { index, count });
        renderer.render_frame(input, &mut target).map(|_| ())
    };
    let message = |r: Result<(), RenderError>| match r {
        Err(e @ RenderError::SubFrameOutOfOrder { .. }) => e.to_string(),
        other => panic!("expected a sub-frame error, got {other:?}"),
    };
    assert!(message(draw(3, 8)).contains("drew no sub-frame 0"));
    for (index, count) in [(8, 8), (5, 1), (0, 0), (u32::MAX, 8), (0, glint::render::MAX_SUB_FRAMES + 1)] {
        assert!(message(draw(index, count)).contains("below the count"), "{index} of {count}");
    }
    draw(0, 8).expect("sub-frame 0");
    draw(1, 8).expect("sub-frame 1");
    assert!(message(draw(3, 8)).contains("expected sub-frame 2 of 8 next"));
    // The failed frame's commands were dropped: the still starts again.
    assert!(message(draw(2, 8)).contains("drew no sub-frame 0"));
    (0..4).try_for_each(|k| draw(k, 4)).expect("a still of 4 after the broken one");
}

#[test]
fn smaa_comes_closer_to_two_hundred_and_fifty_six_samples_than_one_sample() {
    // Bars about three pixels wide: long edges at shallow and steep angles,
    // what SMAA reconstructs (sub-pixel bars break into dashes no filter of
    // one sample can join). Every preset, with FXAA and 16 samples for scale.
    let width = 0.1;
    for (name, gpu) in gpus() {
        let reference = values(&wide_still(gpu, (1.0, width), Vec::new(), 256));
        let one = values(&wide_still(gpu, (1.0, width), Vec::new(), 1));
        let edges = edge_pixels(&reference, &[&one]);
        assert!(edges.len() > 300, "{name}: the bars' edges cover {} pixels", edges.len());
        let error = |post: Vec<PostEffect>, samples| {
            mean_error(&values(&wide_still(gpu, (1.0, width), post, samples)), &reference, &edges)
        };
        let e1 = mean_error(&one, &reference, &edges);
        let (fxaa, sixteen) = (error(vec![PostEffect::Fxaa], 1), error(Vec::new(), 16));
        let smaa = SmaaPreset::ALL.map(|preset| error(vec![PostEffect::Smaa { preset }], 1));
        eprintln!(
            "{name}: mean error over {} edge pixels: 1 sample {e1:.4}, FXAA {fxaa:.4}, SMAA low/medium/high/ultra \
             {:.4}/{:.4}/{:.4}/{:.4}, 16 samples {sixteen:.4}",
            edges.len(),
            smaa[0],
            smaa[1],
            smaa[2],
            smaa[3]
        );
        for (preset, e) in SmaaPreset::ALL.iter().zip(smaa) {
            assert!(e < e1 / 2.5, "{name}: SMAA {} {e:.4} against 1 sample {e1:.4}", preset.name());
            assert!(e < fxaa, "{name}: SMAA {} {e:.4} against FXAA {fxaa:.4}", preset.name());
        }
        assert!(sixteen < e1 / 3.0, "{name}: 16 samples {sixteen:.4} against 1 sample {e1:.4}");
    }
}
