//! Tests of the `.scn` loader: every error class with its line, limits, and
//! what a valid file becomes.

use super::*;
use crate::scene::{AlphaMode, BlendState, Compare, Cull, Motion, ShadingModel};

fn parse(text: &str) -> Result<SceneDesc, Diagnostic> {
    parse_scene(Path::new("dir/t.scn"), text)
}

#[test]
fn every_classname_parses() {
    let scene = parse(
        r#"
{ "classname" "world"
"sky_top" "0.2 0.4 0.8"
"sky_bottom" "0.8 0.9 1"
"ambient" "0.1 0.1 0.1" }
{ "classname" "camera"
"origin" "0 5 10"
"target" "0 0 0"
"fov" "50" }
{ "classname" "light_directional"
"direction" "-1 -1 -1" }
{ "classname" "light_point"
"origin" "0 2 0"
"range" "5" }
{ "classname" "material"
"name" "red"
"base_color" "1 0 0 0.5"
"alpha_mode" "blend" }
{ "classname" "entity"
"mesh" "cube"
"material" "red"
"origin" "1 2 3"
"scale" "2" }
{ "classname" "entity"
"mesh" "cube"
"material" "red" }
{ "classname" "instances"
"mesh" "sphere"
"count" "100"
"layout" "random"
"extent" "10 0 10"
"seed" "7" }
"#,
    )
    .unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert!(matches!(scene.environment.background, Background::Gradient { .. }));
    assert_eq!(scene.cameras.len(), 1);
    assert_eq!(scene.lights.len(), 2);
    assert_eq!(scene.materials[0].material.alpha_mode, AlphaMode::Blend);
    assert_eq!(scene.materials[0].material.base_color.w, 0.5);
    // Two cube entities with one material gather into one task.
    assert_eq!(scene.entities.len(), 2);
    assert_eq!(scene.entities[0].transforms.len(), 2);
    assert_eq!(scene.entities[0].transforms[0].w_axis.truncate(), Vec3::new(1.0, 2.0, 3.0));
    assert_eq!(scene.entities[1].transforms.len(), 100);
    assert_eq!(scene.instance_count(), 102);
}

#[test]
fn angles_are_pitch_yaw_roll() {
    // Yaw 90° turns −Z (forward) to −X; pitch 90° turns it up to +Y.
    assert!((rotation(Vec3::new(0.0, 90.0, 0.0)) * Vec3::NEG_Z).abs_diff_eq(Vec3::NEG_X, 1e-6));
    assert!((rotation(Vec3::new(90.0, 0.0, 0.0)) * Vec3::NEG_Z).abs_diff_eq(Vec3::Y, 1e-6));
}

#[test]
fn material_states_shading_and_fog() {
    let scene = parse(
        "{ \"classname\" \"world\"\n\"fog_density\" \"0.1\" }\n{\n\"classname\" \"material\"\n\"name\" \"glow\"\n\"alpha_mode\" \"blend\"\n\"blend\" \"additive\"\n\"cull\" \"none\"\n\"stencil_compare\" \"equal\"\n\"stencil_ref\" \"3\"\n\"shading\" \"unlit\"\n\"fog\" \"0\"\n}\n{ \"classname\" \"material\"\n\"name\" \"plain\" }\n",
    )
    .unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert_eq!(scene.environment.fog.map(|f| f.density), Some(0.1));
    let glow = &scene.materials[0].material;
    let states = glow.states.expect("explicit states");
    assert_eq!(states.blend, BlendState::Additive);
    assert!(!states.depth.write, "derived from alpha_mode blend, not overridden");
    assert_eq!((states.raster.cull, states.stencil.compare, states.stencil.reference), (Cull::None, Compare::Equal, 3));
    assert_eq!((glow.shading, glow.fog), (ShadingModel::Unlit, false));
    assert_eq!(scene.materials[1].material.states, None, "no state keys: derived at draw time");
    let err = parse("{\n\"classname\" \"material\"\n\"name\" \"m\"\n\"stencil_ref\" \"300\"\n}\n").unwrap_err();
    assert_eq!(err.line, Some(4));
    assert!(err.message.contains("0..=255"), "{err}");
}

#[test]
fn unknown_keys_warn_with_their_line() {
    let scene = parse("{\n\"classname\" \"entity\"\n\"mesh\" \"cube\"\n\"colour\" \"1 0 0\"\n}\n").unwrap();
    assert_eq!(scene.warnings.len(), 1);
    assert_eq!(scene.warnings[0].line, Some(4));
    assert!(scene.warnings[0].message.contains("unknown key 'colour'"));
}

/// A `material` block named m with `extra` from its fourth line.
fn motion(extra: &str) -> String {
    format!("{{\n\"classname\" \"material\"\n\"name\" \"m\"\n{extra}\n}}")
}

#[test]
fn materials_move_with_their_keys_and_the_world_sets_the_wind() {
    let text = format!(
        "{{ \"classname\" \"world\"\n\"wind\" \"0.5\"\n\"wind_direction\" \"0 2\" }}\n{}\n{}\n{}",
        motion("\"motion\" \"wind\"\n\"sway_base\" \"-0.5\""),
        motion("\"motion\" \"flap\"\n\"flap_rate\" \"3\"").replace("\"m\"", "\"f\""),
        motion("\"motion\" \"circle\"\n\"walk_radius\" \"1 4\"\n\"walk_speed\" \"2\"").replace("\"m\"", "\"c\""),
    );
    let scene = parse(&text).unwrap();
    let motions: Vec<_> = scene.materials.iter().map(|m| m.material.motion).collect();
    assert_eq!(
        motions,
        [
            Some(Motion::Wind { sway: 0.3, base: -0.5 }),
            Some(Motion::Flap { amplitude: 0.8, rate: 3.0 }),
            Some(Motion::Circle { radius: glam::Vec2::new(1.0, 4.0), speed: 2.0 }),
        ]
    );
    let wind = scene.environment.wind;
    assert_eq!((wind.strength, wind.direction), (0.5, glam::Vec2::Y));
    let far = parse(&motion("\"far_field\" \"6 130\"")).unwrap();
    assert_eq!(far.materials[0].material.far_field, crate::scene::FarField::new(6.0, 130.0));
    assert!(scene.materials.iter().all(|m| m.material.far_field.is_none()));
}

#[test]
fn time_of_day_moves_the_first_directional_light_and_the_sky_or_adds_a_sun() {
    let day = crate::scene::Daylight::at(9.0);
    let lit = parse(
        "{ \"classname\" \"light_point\"\n\"origin\" \"0 1 0\" }\n\
         { \"classname\" \"light_directional\"\n\"direction\" \"0 -1 0\" }\n\
         { \"classname\" \"world\"\n\"time_of_day\" \"9\"\n\"glare\" \"2\" }",
    )
    .unwrap();
    assert_eq!(lit.lights.len(), 2);
    assert_eq!(lit.lights[1].kind, crate::scene::LightKind::Directional { direction: day.sun_direction });
    assert_eq!((lit.lights[1].color, lit.lights[1].intensity), (day.sun_color, day.sun_intensity));
    assert_eq!(lit.environment.background, Background::Gradient { top: day.sky_top, bottom: day.sky_bottom });
    assert_eq!((lit.environment.ambient, lit.environment.glare), (day.ambient, 2.0));
    let unlit = parse("{ \"classname\" \"world\"\n\"time_of_day\" \"9\" }").unwrap();
    assert_eq!(unlit.lights.len(), 1, "a sun is added");
    assert!(matches!(unlit.lights[0].kind, crate::scene::LightKind::Directional { .. }));
}

/// An `instances` block of 100 cubes with `extra` on its fifth line.
fn tiled(extra: &str) -> String {
    format!("{{\n\"classname\" \"instances\"\n\"mesh\" \"cube\"\n\"count\" \"100\"\n{extra}\n}}")
}

#[test]
fn the_world_environment_is_the_sky_or_an_image_counted_in_texture_memory() {
    let sky = parse("{ \"classname\" \"world\"\n\"environment\" \"sky\"\n\"environment_rotation\" \"90\" }").unwrap();
    let light = sky.environment.light.expect("lit by the sky");
    assert_eq!(light.source, crate::scene::EnvironmentSource::Sky);
    assert!((light.rotation - std::f32::consts::FRAC_PI_2).abs() < 1e-6 && light.intensity == 1.0);
    assert!(parse("{ \"classname\" \"world\" }").unwrap().environment.light.is_none());
    // An image, from a file set: its id is the scene's, its pixels count against the memory.
    let env = crate::asset::EnvironmentImage::uniform(glam::Vec3::ONE);
    let mut hdr = Vec::new();
    let rgb: Vec<image::Rgb<f32>> = env.pixels().pixels().copied().collect();
    image::codecs::hdr::HdrEncoder::new(&mut hdr).encode(&rgb, 8, 4).unwrap();
    let set = std::sync::Arc::new(crate::asset::FileSet::default());
    set.insert(Path::new("dir/sky.hdr"), hdr);
    let text = "{ \"classname\" \"world\"\n\"environment\" \"sky.hdr\"\n\"environment_intensity\" \"2\" }";
    let options = |memory| LoadOptions {
        files: crate::asset::Files::Memory(set.clone()),
        texture_memory: memory,
        ..Default::default()
    };
    let desc = parse_scene_with(Path::new("dir/t.scn"), text, options(1 << 20)).unwrap();
    let image = desc.environment_image.as_ref().expect("the image");
    assert_eq!(image.pixels().dimensions(), (8, 4));
    let light = desc.environment.light.expect("lit by it");
    assert_eq!((light.source, light.intensity), (crate::scene::EnvironmentSource::Image(image.id()), 2.0));
    let err = parse_scene_with(Path::new("dir/t.scn"), text, options(100)).unwrap_err();
    assert_eq!(err.line, Some(2), "{err}");
    assert!(err.message.contains("texture memory"), "{err}");
}

#[test]
fn a_camera_takes_ambient_occlusion_with_its_radius_and_intensity() {
    let camera = |keys: &str| format!("{{\n\"classname\" \"camera\"\n{keys}\n}}");
    let on = parse(&camera("\"ssao\" \"1\"\n\"ssao_radius\" \"2\"\n\"ssao_intensity\" \"1.5\"")).unwrap();
    let settings = on.camera_views[0].ambient_occlusion.expect("on");
    assert_eq!((settings.radius, settings.intensity), (2.0, 1.5));
    assert_eq!(on.camera_view(0).ambient_occlusion, Some(settings), "the view has it");
    let defaults = parse(&camera("\"ssao\" \"1\"")).unwrap().camera_views[0].ambient_occlusion;
    assert_eq!(defaults, Some(crate::scene::AmbientOcclusion::default()));
    for keys in ["\"ssao\" \"0\"\n\"ssao_radius\" \"2\"", ""] {
        let off = parse(&camera(keys)).unwrap();
        assert!(off.camera_views[0].ambient_occlusion.is_none() && off.warnings.is_empty(), "{keys}");
    }
    for (keys, expected) in [
        ("\"ssao\" \"yes\"", "expected 0 or 1"),
        ("\"ssao\" \"1\"\n\"ssao_radius\" \"0\"", "ssao_radius"),
        ("\"ssao\" \"1\"\n\"ssao_intensity\" \"-1\"", "ssao_intensity"),
        ("\"ssao\" \"1\"\n\"ssao_radius\" \"nan\"", "ssao_radius"),
    ] {
        let err = parse(&camera(keys)).unwrap_err();
        assert!(err.line.is_some_and(|l| l >= 3) && err.message.contains(expected), "{keys}: {err}");
    }
}

#[test]
fn a_camera_takes_the_error_its_levels_of_detail_may_make() {
    let camera = |keys: &str| format!("{{\n\"classname\" \"camera\"\n{keys}\n}}");
    let scene = parse(&camera("\"lod_error\" \"2.5\"")).unwrap();
    assert_eq!(scene.camera_views[0].lod_error, Some(2.5));
    assert_eq!(scene.camera_view(0).lod_error, 2.5, "the view has it");
    let plain = parse(&camera("")).unwrap();
    assert_eq!(plain.camera_view(0).lod_error, crate::scene::DEFAULT_LOD_ERROR);
    for keys in ["\"lod_error\" \"-1\"", "\"lod_error\" \"nan\"", "\"lod_error\" \"1e9\""] {
        let err = parse(&camera(keys)).unwrap_err();
        assert!(err.line == Some(3) && err.message.contains("lod_error"), "{keys}: {err}");
    }
}

#[test]
fn tiled_instances_are_an_entity_of_their_own_with_their_tiles_and_density() {
    let both = format!(
        "{}\n{}",
        tiled("\"tiles\" \"4\"\n\"density\" \"0.5\"\n\"tile_padding\" \"0.25\"\n\"layout\" \"random\""),
        tiled("\"layout\" \"random\"")
    );
    let scene = parse(&both).unwrap();
    assert_eq!(scene.entities.len(), 2, "the tiled block is not gathered with the other");
    let e = &scene.entities[0];
    let tiles = e.tiles.as_ref().expect("tiles");
    assert_eq!((e.density, tiles.padding(), e.transforms.len()), (0.5, 0.25, 100));
    let ranges: Vec<_> = tiles.ranges(100).collect();
    assert_eq!((ranges.len(), ranges.last().map(|r| r.end)), (16, Some(100)));
    // The default extent is 10 × 10 around the origin: 2.5 × 2.5 cells.
    for (t, range) in ranges.iter().enumerate() {
        for m in &e.transforms[range.start as usize..range.end as usize] {
            let (col, row) = ((m.w_axis.x + 5.0) / 2.5, (m.w_axis.z + 5.0) / 2.5);
            assert_eq!((col.floor() as usize).min(3) + 4 * (row.floor() as usize).min(3), t);
        }
    }
    assert!(scene.entities[1].tiles.is_none() && scene.entities[1].density == 1.0);
    assert!(!e.compact && !scene.entities[1].compact);
    let compact = parse(&tiled("\"tiles\" \"2\"\n\"compact\" \"1\"")).unwrap();
    assert!(compact.entities[0].compact);
}

#[test]
fn semantic_errors_name_file_line_and_expectation() {
    let cases = [
        ("{\n\"classname\" \"spaceship\"\n}", 2, "unknown classname"),
        ("{\n\"mesh\" \"cube\"\n}", 1, "no \"classname\""),
        ("{\n\"classname\" \"entity\"\n}", 1, "missing the required key \"mesh\""),
        ("{\n\"classname\" \"entity\"\n\"mesh\" \"cube\"\n\"origin\" \"1 x 3\"\n}", 4, "bad number 'x'"),
        ("{\n\"classname\" \"entity\"\n\"mesh\" \"cube\"\n\"origin\" \"1 2\"\n}", 4, "found 2 numbers"),
        ("{\n\"classname\" \"entity\"\n\"mesh\" \"blobby\"\n}", 3, "unknown mesh 'blobby'"),
        ("{\n\"classname\" \"entity\"\n\"mesh\" \"cube\"\n\"material\" \"gold\"\n}", 4, "unknown material 'gold'"),
        ("{\n\"classname\" \"instances\"\n\"mesh\" \"cube\"\n\"count\" \"-5\"\n}", 4, "expected 0 or more"),
        (
            "{\n\"classname\" \"instances\"\n\"mesh\" \"cube\"\n\"count\" \"99999999999\"\n}",
            4,
            "more than glint allows",
        ),
        ("{\n\"classname\" \"instances\"\n\"mesh\" \"cube\"\n\"count\" \"lots\"\n}", 4, "expected a whole number"),
        ("{\n\"classname\" \"material\"\n\"name\" \"m\"\n\"diffuse_map\" \"nope.png\"\n}", 4, "nope.png: cannot read"),
        (
            "{\n\"classname\" \"material\"\n\"name\" \"m\"\n\"alpha_mode\" \"glass\"\n}",
            4,
            "expected one of: opaque, mask, blend",
        ),
        ("{\n\"classname\" \"material\"\n\"name\" \"m\"\n\"smoothness\" \"2\"\n}", 4, "expected a value in 0..=1"),
        ("{\n\"classname\" \"camera\"\n\"near\" \"10\"\n\"far\" \"1\"\n}", 1, "must be greater than"),
        ("{\n\"classname\" \"camera\"\n\"viewport\" \"0.5 0 0.6 1\"\n}", 3, "not a rectangle inside the image"),
        ("{\n\"classname\" \"camera\"\n\"viewport\" \"-0.1 0 0.5 1\"\n}", 3, "x and y must be at least 0"),
        ("{\n\"classname\" \"camera\"\n\"viewport\" \"0 0 0 1\"\n}", 3, "not a rectangle inside the image"),
        ("{\n\"classname\" \"camera\"\n\"viewport\" \"0 0 1\"\n}", 3, "found 3 numbers"),
        (
            "{\n\"classname\" \"camera\"\n\"post\" \"bloom glow\"\n}",
            3,
            "'glow' is not a post effect, expected effects among: bloom,",
        ),
        ("{\n\"classname\" \"camera\"\n\"output\" \"tv\"\n}", 3, "unknown render target 'tv'"),
        (
            "{\n\"classname\" \"material\"\n\"name\" \"m\"\n\"diffuse_map\" \"target:tv\"\n}",
            4,
            "unknown render target 'tv'",
        ),
        ("{\n\"classname\" \"render_target\"\n\"name\" \"tv\"\n\"size\" \"0 10\"\n}", 4, "expected two whole numbers"),
        ("{\n\"classname\" \"render_target\"\n\"name\" \"tv\"\n\"size\" \"4096 10\"\n}", 4, "in 1..=2048"),
        ("{\n\"classname\" \"render_target\"\n\"size\" \"8 8\"\n}", 1, "missing the required key \"name\""),
        (
            "{\n\"classname\" \"render_target\"\n\"name\" \"tv\"\n\"size\" \"8 8\"\n\"format\" \"float\"\n}",
            5,
            "expected one of: ldr, hdr",
        ),
        ("{\n\"classname\" \"camera\"\n\"post\" \"fxaa fxaa\"\n}", 3, "'fxaa' is named twice"),
        ("{\n\"classname\" \"camera\"\n\"tonemap\" \"filmic\"\n}", 3, "expected one of: none, reinhard, aces, agx"),
        ("{\n\"classname\" \"camera\"\n\"exposure\" \"40\"\n}", 3, "expected a value in -20..=20"),
        ("{\n\"classname\" \"camera\"\n\"vignette\" \"2\"\n}", 3, "expected a value in 0..=1"),
        ("{\n\"classname\" \"camera\"\n\"smaa\" \"best\"\n}", 3, "expected one of: low, medium, high, ultra"),
        ("{\n\"classname\" \"light_point\"\n\"origin\" \"0 0 inf\"\n}", 3, "not a finite number"),
        (&tiled("\"tiles\" \"0\""), 5, "\"tiles\" is '0', expected a whole number in 1..=256"),
        (&tiled("\"tiles\" \"257\""), 5, "expected a whole number in 1..=256"),
        (&tiled("\"tiles\" \"4\"\n\"density\" \"1.5\""), 6, "\"density\" is 1.5, expected a value in 0..=1"),
        (&tiled("\"tiles\" \"4\"\n\"tile_padding\" \"-1\""), 6, "expected a value in 0..=1000000"),
        (&tiled("\"density\" \"0.5\""), 1, "\"density\", \"tile_padding\" and \"compact\" need \"tiles\""),
        (&tiled("\"compact\" \"1\""), 1, "need \"tiles\""),
        (&tiled("\"tiles\" \"2\"\n\"compact\" \"yes\""), 6, "\"compact\""),
        (&motion("\"motion\" \"dance\""), 4, "expected one of: none, wind, flap, circle, swim"),
        (&motion("\"sway\" \"0.2\""), 4, "sway is a key of \"motion\" \"wind\", which this material does not have"),
        (&motion("\"motion\" \"wind\"\n\"flap_rate\" \"2\""), 5, "flap_rate is a key of \"motion\" \"flap\""),
        (&motion("\"motion\" \"circle\"\n\"walk_radius\" \"2 1\""), 5, "0 <= min <= max <= 10000"),
        (&motion("\"motion\" \"flap\"\n\"flap_rate\" \"-1\""), 5, "expected a value in 0..=100"),
        ("{\n\"classname\" \"world\"\n\"wind\" \"3\"\n}", 3, "\"wind\" is 3, expected a value in 0..=2"),
        ("{\n\"classname\" \"world\"\n\"wind_direction\" \"0 0\"\n}", 3, "must not be 0 0"),
        ("{\n\"classname\" \"world\"\n\"glare\" \"5\"\n}", 3, "\"glare\" is 5, expected a value in 0..=4"),
        ("{\n\"classname\" \"world\"\n\"time_of_day\" \"25\"\n}", 3, "expected a value in 0..=24"),
        (&motion("\"edge_fade\" \"5 2\""), 4, "0 <= inner < outer <= 1000000"),
        (&motion("\"far_field\" \"8 8\""), 4, "0 < start < end <= 1000000"),
        (&motion("\"far_field\" \"0 8\""), 4, "0 < start < end <= 1000000"),
        (&motion("\"far_field\" \"8\""), 4, "2 numbers (start end)"),
        ("{\n\"classname\" \"world\"\n\"sky_blur\" \"0.5\"\n}", 1, "\"sky_blur\" needs \"environment\""),
        ("{\n\"classname\" \"world\"\n\"environment\" \"sky\"\n\"sky_blur\" \"2\"\n}", 4, "expected a value in 0..=1"),
        ("{\n\"classname\" \"world\"\n\"environment\" \"none.hdr\"\n}", 3, "\"environment\": "),
    ];
    for (text, line, want) in cases {
        let err = parse(text).unwrap_err();
        assert_eq!(err.line, Some(line), "{text:?}: {err}");
        assert!(err.message.contains(want), "{text:?}: {err}");
        assert!(err.to_string().starts_with(&format!("dir/t.scn:{line}: ")), "{err}");
    }
}

#[test]
fn cameras_with_viewports_are_the_views_and_without_any_the_first_camera_is() {
    let camera = |extra: &str| format!("{{\n\"classname\" \"camera\"\n\"origin\" \"0 1 5\"\n{extra}}}\n");
    let none = parse(&format!("{}{}", camera(""), camera(""))).unwrap();
    assert!(none.camera_views.iter().all(|c| c.viewport.is_none() && c.post.is_empty()));
    let views = none.views(&[]);
    assert_eq!((views.len(), views[0].viewport), (1, crate::scene::Viewport::FULL), "the first camera alone");
    let text =
        format!("{}{}{}", camera(""), camera("\"viewport\" \"0.5 0 0.5 1\"\n"), camera("\"viewport\" \"0 0 0.5 1\"\n"));
    let split = parse(&text).unwrap();
    let views = split.views(&[]);
    assert_eq!(views.len(), 2, "only the cameras with a viewport, in file order");
    assert_eq!(views[0].viewport, crate::scene::Viewport { x: 0.5, y: 0.0, width: 0.5, height: 1.0 });
    assert_eq!(views[1].viewport.x, 0.0);
    assert!(views.iter().all(|v| v.culling == crate::scene::Culling::Gpu));
    // A post chain, in the listed order, with each effect's settings.
    let keys = "\"post\" \"tonemap bloom edges smaa\"\n\"tonemap\" \"agx\"\n\"exposure\" \"1.5\"\n\"bloom_threshold\" \"2\"\n\"edge_color\" \"1 0 0\"\n\"smaa\" \"ultra\"\n";
    let chain = parse(&camera(keys)).unwrap().camera_view(0).post;
    use crate::scene::{PostEffect, SmaaPreset, Tonemap};
    assert_eq!(
        chain,
        [
            PostEffect::Tonemap { operator: Tonemap::Agx, exposure: 1.5 },
            PostEffect::Bloom { threshold: 2.0, intensity: 0.5 },
            PostEffect::Edges { color: glam::Vec3::X, threshold: 0.4 },
            PostEffect::Smaa { preset: SmaaPreset::Ultra },
        ]
    );
    let smaa = parse(&camera("\"post\" \"smaa\"\n")).unwrap().camera_view(0).post;
    assert_eq!(smaa, [PostEffect::Smaa { preset: SmaaPreset::High }], "the high preset unless one is named");
}

#[test]
fn render_targets_are_drawn_by_their_cameras_and_shown_by_materials() {
    let target =
        |name: &str| format!("{{\n\"classname\" \"render_target\"\n\"name\" \"{name}\"\n\"size\" \"64 32\"\n}}\n");
    let camera = |extra: &str| format!("{{\n\"classname\" \"camera\"\n\"origin\" \"0 1 5\"\n{extra}}}\n");
    let shows = |name: &str, target: &str| {
        format!("{{\n\"classname\" \"material\"\n\"name\" \"{name}\"\n\"diffuse_map\" \"target:{target}\"\n}}\n")
    };
    let text = [target("a"), target("b"), camera(""), camera("\"output\" \"b\"\n"), shows("screen", "b")].concat();
    let scene = parse(&text).unwrap();
    assert_eq!(scene.render_targets.len(), 2);
    assert_eq!((scene.render_targets[1].size, scene.render_targets[1].hdr), ((64, 32), false));
    assert_eq!(scene.camera_views[1].output, Some(1));
    // No file textures: target b's texture is the second after them.
    assert_eq!(scene.materials[0].diffuse_map, Some(1));
    // Placed, the targets got ids 7 and 9: camera 1 draws into target b's.
    let ids = [crate::scene::RenderTargetId(7), crate::scene::RenderTargetId(9)];
    let views = scene.views(&ids);
    assert_eq!(views.len(), 2, "the target's camera, then the first camera into the image");
    assert_eq!((views[0].output, views[1].output), (Some(ids[1]), None));
    assert_eq!(scene.views(&ids[..1]).len(), 1, "a target without an id: its camera is left out");
    // Cameras that each show the other's target: a cycle, at a camera's line.
    let cycle = [
        target("a"),
        target("b"),
        camera("\"output\" \"a\"\n"),
        camera("\"output\" \"b\"\n"),
        shows("m1", "a"),
        shows("m2", "b"),
    ]
    .concat();
    let err = parse(&cycle).unwrap_err();
    assert!(err.message.contains("a cycle of render targets"), "{err}");
    assert!(matches!(err.line, Some(11) | Some(16)), "at a camera block: {err}");
    // A camera showing only its own target is no cycle: it leaves the screen out.
    let own = [target("a"), camera("\"output\" \"a\"\n"), shows("m1", "a")].concat();
    assert!(parse(&own).is_ok());
}

#[test]
fn more_lights_than_a_frame_holds_is_an_error_at_the_extra_light() {
    let light = "{\n\"classname\" \"light_point\"\n\"origin\" \"0 1 0\"\n}\n";
    let most = crate::scene::MAX_CLUSTERED_LIGHTS;
    assert_eq!(parse(&light.repeat(most)).unwrap().lights.len(), most);
    let err = parse(&light.repeat(most + 1)).unwrap_err();
    assert_eq!(err.line, Some(4 * most + 1));
    assert!(err.message.contains("more than 4096 lights"), "{err}");
}

/// 10⁶ material blocks (and entities naming the last of them, and one block
/// of 10⁵ repeated keys), timed and printed: a benchmark, not a timed test.
/// `cargo test --release -p glint --lib scn::tests::load_benchmark -- --ignored --nocapture`
#[test]
#[ignore = "benchmark: run in release with --ignored --nocapture"]
fn load_benchmark_materials_and_long_blocks() {
    use std::fmt::Write;
    for n in [100_000usize, 1_000_000] {
        let mut text = String::with_capacity(n * 64);
        for i in 0..n {
            let _ = write!(text, "{{\n\"classname\" \"material\"\n\"name\" \"m{i}\"\n\"diffuse\" \"0.5\"\n}}\n");
        }
        for i in 0..1000 {
            let _ =
                write!(text, "{{\n\"classname\" \"entity\"\n\"mesh\" \"cube\"\n\"material\" \"m{}\"\n}}\n", n - 1 - i);
        }
        let start = std::time::Instant::now();
        let scene = parse(&text).unwrap();
        let elapsed = start.elapsed();
        assert_eq!((scene.materials.len(), scene.entities.len()), (n, 1000));
        eprintln!("{n} material blocks + 1000 entities ({} MB): {:.3} s", text.len() >> 20, elapsed.as_secs_f64());
    }
    let pairs = 100_000;
    let text = format!("{{\n\"classname\" \"world\"\n{}}}\n", "\"ambient\" \"0.1 0.1 0.1\"\n".repeat(pairs));
    let start = std::time::Instant::now();
    let scene = parse(&text).unwrap();
    let elapsed = start.elapsed();
    assert_eq!(scene.warnings.len(), pairs - 1);
    eprintln!("one block of {pairs} repeated keys: {:.3} s", elapsed.as_secs_f64());
}

#[test]
fn names_resolve_through_the_map_and_repeats_are_reported() {
    let mut text = String::new();
    for i in 0..50 {
        text.push_str(&format!(
            "{{\n\"classname\" \"material\"\n\"name\" \"m{i}\"\n\"diffuse\" \"{}\"\n}}\n",
            i as f32 / 100.0
        ));
    }
    text.push_str("{\n\"classname\" \"entity\"\n\"mesh\" \"cube\"\n\"material\" \"m37\"\n}\n");
    let scene = parse(&text).unwrap();
    let task = scene.entities[0].material.expect("named");
    assert_eq!((task, scene.materials[task].material.diffuse), (37, 0.37));
    // The same name again is an error at its "name" line (after 255 lines of blocks).
    let again = format!("{text}{{\n\"classname\" \"material\"\n\"name\" \"m12\"\n}}\n");
    let err = parse(&again).unwrap_err();
    assert_eq!(err.line, Some(258), "{err}");
    assert!(err.message.contains("material 'm12' is defined twice"), "{err}");
    // Repeated keys warn once per earlier copy, unknown ones once each.
    let scene = parse("{\n\"classname\" \"world\"\n\"ambient\" \"1 1 1\"\n\"ambient\" \"0 0 0\"\n\"x\" \"1\"\n\"ambient\" \"0.5 0.5 0.5\"\n}\n").unwrap();
    let lines: Vec<_> = scene.warnings.iter().map(|w| (w.line, w.message.contains("given again"))).collect();
    assert_eq!(lines, [(Some(3), true), (Some(4), true), (Some(5), false)]);
    assert_eq!(scene.environment.ambient, Vec3::splat(0.5));
}

#[test]
fn distinct_blobs_are_capped_by_their_vertices_before_any_is_built() {
    let blob = |detail: u32, seed: u32| {
        format!(
            "{{\n\"classname\" \"entity\"\n\"mesh\" \"blob\"\n\"detail\" \"{detail}\"\n\"mesh_seed\" \"{seed}\"\n}}\n"
        )
    };
    let fits = (MAX_SCENE_BLOB_VERTICES / blob_vertex_count(1024)) as u32;
    assert!(fits >= 1);
    // The same blob a hundred times is one mesh.
    assert!(parse(&blob(1024, 7).repeat(100)).is_ok());
    let most: String = (0..fits).map(|seed| blob(1024, seed)).collect();
    assert!(parse(&most).is_ok());
    let err = parse(&format!("{most}{}", blob(1024, fits))).unwrap_err();
    assert_eq!(err.line, Some(6 * fits as usize + 3), "{err}");
    assert!(err.message.contains("distinct blobs"), "{err}");
    // Small blobs fit by the thousand.
    let small: String = (0..1000).map(|seed| blob(16, seed)).collect();
    assert!(parse(&small).is_ok());
}

#[test]
fn total_instances_are_capped_across_blocks() {
    let block = "{\n\"classname\" \"instances\"\n\"mesh\" \"cube\"\n\"count\" \"1500000\"\n\"extent\" \"0 0 0\"\n}\n";
    let err = parse(&format!("{block}{block}")).unwrap_err();
    assert_eq!(err.line, Some(10));
    assert!(err.message.contains("3000000 instances"), "{err}");
}

#[test]
fn the_world_chooses_every_cameras_transparency_and_the_options_override_it() {
    use crate::scene::Transparency;
    let text = "{ \"classname\" \"world\"\n\"transparency\" \"exact\" }\n{ \"classname\" \"camera\" }\n";
    let scene = parse(text).expect("scene");
    assert_eq!(scene.transparency, Transparency::Exact);
    assert_eq!(scene.camera_view(0).transparency, Transparency::Exact);
    assert!(!scene.has_transparency(), "nothing blended in it");
    assert_eq!(parse("{ \"classname\" \"camera\" }\n").expect("scene").transparency, Transparency::Sorted);
    let bad = parse("{ \"classname\" \"world\"\n\"transparency\" \"fast\" }\n").unwrap_err().to_string();
    assert!(bad.contains("t.scn:2") && bad.contains("sorted, weighted, exact"), "{bad}");
    let options = LoadOptions { transparency: Some(Transparency::Weighted), ..LoadOptions::default() };
    let scene = parse_scene_with(Path::new("dir/t.scn"), text, options).expect("scene");
    assert_eq!(scene.camera_view(0).transparency, Transparency::Weighted, "the options' choice");
}
