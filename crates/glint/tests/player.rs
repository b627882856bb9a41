//! The front ends' frame loop ([`Player`]): one frame each call, one
//! submission, the scene clock as the controls say, the fly camera only while
//! the camera is free.

mod common;

use glint::scene::FlyInput;
use glint::world::{Controls, Moves, Player, MAX_FRAME_ADVANCE};
use glint::{OffscreenTarget, Renderer, World};
use std::time::Duration;

const SCENE: &str = r#"
{ "classname" "camera"
"origin" "0 1 5" }
{ "classname" "camera"
"origin" "5 1 0" }
{ "classname" "light_directional"
"direction" "0 -1 0"
"shadows" "1" }
{ "classname" "entity"
"mesh" "cube" }
"#;

#[test]
fn a_player_frame_is_one_submission_and_plays_the_clock_and_the_fly_camera_as_the_controls_say() {
    let Some(gpu) = common::gpu() else { return };
    let desc = glint::asset::parse_scene("player.scn".as_ref(), SCENE).expect("scene");
    let mut controls = Controls::new(&desc, 1.0);
    let mut renderer = Renderer::new(gpu);
    let mut world = World::place(desc, &mut renderer).expect("placed");
    let views = world.views(None);
    let mut player = Player::new(&views[0].camera);
    let mut target = OffscreenTarget::new(gpu, 48, 32, 1).expect("target");
    let forward = Moves { fly: FlyInput { forward: 1.0, ..FlyInput::default() }, ..Moves::default() };
    let mut frame = |player: &mut Player, controls: &mut Controls, real_ms: u64, moves: Moves| {
        let (world, drawn) = ((&mut world, &mut renderer), (&views[..], &mut target));
        player.frame(world, controls, drawn, (Duration::from_millis(real_ms), moves), Vec::new()).expect("frame")
    };
    controls.toggle_free_camera();
    assert!(controls.free_camera(), "the free camera first");
    let start = player.fly.position;
    let output = frame(&mut player, &mut controls, 20, forward);
    assert_eq!((output.submits, output.views.len()), (1, 1), "one view, one submission");
    assert!((player.clock.time - 0.02).abs() < 1e-6, "real time: {}", player.clock.time);
    assert!(player.fly.position.z < start.z, "flown forward: {:?} from {start:?}", player.fly.position);
    // A slow frame advances the scene by at most a thirtieth of a second.
    frame(&mut player, &mut controls, 500, Moves::default());
    assert!((player.clock.time - (0.02 + MAX_FRAME_ADVANCE)).abs() < 1e-6, "{}", player.clock.time);
    // Paused, the clock stays; a scene camera chosen, the fly camera stays.
    controls.set("paused", 1.0).expect("paused");
    controls.set("camera", 1.0).expect("the second scene camera");
    let (time, flown) = (player.clock.time, player.fly.position);
    frame(&mut player, &mut controls, 20, forward);
    assert_eq!((player.clock.time, player.fly.position), (time, flown));
    // Restart: the clock starts again from 0.
    controls.set("paused", 0.0).expect("playing");
    controls.set("restart", 1.0).expect("restart");
    frame(&mut player, &mut controls, 20, Moves::default());
    assert_eq!(player.clock.time, 0.0);
}
