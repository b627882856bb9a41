//! Time of day, the sun glare and a ground fading into the sky
//! (`tests/scenes/glare.scn`): the glare brightens the view toward the sun
//! and is drawn last without a depth test; the hour moves sun and sky.

mod common;

use glint::{OffscreenTarget, Renderer, World};

/// The scene, changed by `edit`, at 256 × 256 with 4× MSAA.
fn picture(gpu: &glint::Gpu, edit: impl FnOnce(&mut glint::asset::SceneDesc)) -> (image::RgbaImage, glint::FrameStats) {
    let mut desc = common::load_scene(&common::repo_root().join("tests/scenes/glare.scn"));
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
    edit(&mut desc);
    let mut renderer = Renderer::new(gpu);
    let mut world = World::place(desc, &mut renderer).expect("placed");
    world.pose(0.5, &mut renderer).expect("posed");
    let mut target = OffscreenTarget::new(gpu, 256, 256, 4).expect("target");
    let mut stats = world.draw(&mut renderer, &world.views(None), &mut target).expect("frame");
    (target.read_rgba8(gpu).expect("readback"), stats.remove(0))
}

/// Mean brightness of the pixels `keep` selects.
fn brightness(image: &image::RgbaImage, keep: impl Fn(u32, u32) -> bool) -> f64 {
    let pixels: Vec<f64> = (image.enumerate_pixels())
        .filter(|(x, y, _)| keep(*x, *y))
        .map(|(_, _, p)| p.0[..3].iter().map(|&c| f64::from(c)).sum::<f64>() / 3.0)
        .collect();
    pixels.iter().sum::<f64>() / pixels.len().max(1) as f64
}

#[test]
fn the_glare_brightens_the_view_toward_the_sun_over_everything() {
    let Some(gpu) = common::gpu() else { return };
    let (glare, with) = picture(gpu, |_| {});
    let (plain, without) = picture(gpu, |d| d.environment.glare = 0.0);
    assert_eq!(with.draws, without.draws + 1, "the glare is one more draw");
    // The sun is low ahead, up and to the left (about pixel 80, 65).
    let near_sun = |x: u32, y: u32| (x as i32 - 80).abs() < 30 && (y as i32 - 65).abs() < 30;
    let (lit, unlit) = (brightness(&glare, near_sun), brightness(&plain, near_sun));
    assert!(lit > unlit + 20.0, "toward the sun: {lit:.1} with the glare, {unlit:.1} without");
    let corner = |x: u32, y: u32| x < 24 && y > 232;
    assert!(brightness(&glare, corner) - brightness(&plain, corner) < 6.0, "little glare away from the sun");
    common::assert_matches_reference("glare_on", &glare);
    common::assert_matches_reference("glare_off", &plain);
}

#[test]
fn the_hour_moves_sun_and_sky_together() {
    let Some(gpu) = common::gpu() else { return };
    let (noon, _) = picture(gpu, |d| d.set_time_of_day(12.0).unwrap());
    let (night, _) = picture(gpu, |d| d.set_time_of_day(23.0).unwrap());
    let everywhere = |_, _| true;
    assert!(brightness(&noon, everywhere) > 2.0 * brightness(&night, everywhere), "night is dark");
    common::assert_matches_reference("glare_noon", &noon);
}

#[test]
fn the_webgl2_path_and_gl_draw_the_glare_alike() {
    for gpu in [common::gl_gpu(), common::webgl2_gpu()].into_iter().flatten() {
        let (glare, _) = picture(gpu, |_| {});
        common::assert_matches_reference("glare_on", &glare);
    }
}

#[test]
fn a_sun_added_while_shadows_are_off_leaves_each_light_its_own_shadows() {
    let Some(gpu) = common::gpu() else { return };
    // A shadowed point light and no sun: the hour adds one, first.
    let text = "{\n\"classname\" \"light_point\"\n\"origin\" \"0 2 0\"\n\"shadows\" \"1\"\n}\n";
    let desc = glint::asset::parse_scene(std::path::Path::new("t.scn"), text).expect("scene");
    let mut renderer = Renderer::new(gpu);
    let mut world = World::place(desc, &mut renderer).expect("placed");
    world.set_shadows(false);
    world.set_time_of_day(12.0).expect("room for a sun");
    world.set_shadows(true);
    let lights = &world.desc().lights;
    assert_eq!(lights.len(), 2);
    assert!(matches!(lights[0].kind, glint::scene::LightKind::Directional { .. }) && lights[0].shadows.is_none());
    assert!(lights[1].shadows.is_some(), "the point light's shadows came back to it");
}
