//! World layer: [`Player`], the loop a front end runs once a displayed frame,
//! the same in the viewer (`glint view`) and on the web page: the fly camera
//! moved by what the user did, the scene clock advanced as the controls say,
//! the controls applied, the world posed, and its views drawn in one frame
//! with the front end's own work after them (an overlay, the blit onto a
//! window or canvas).

use super::{Controls, SceneClock, World};
use crate::scene::{Camera, FlyCamera, FlyInput, View};
use crate::{AfterViews, FrameOutput, OffscreenTarget, Renderer};
use glam::{Vec2, Vec3};
use std::time::Duration;

/// Most real time one frame moves the fly camera, seconds (a frame after a
/// stall does not throw it across the scene).
const MAX_FLY_STEP: f32 = 0.25;

/// What the user did since the last frame.
#[derive(Clone, Copy, Debug, Default)]
pub struct Moves {
    /// Keys and mouse look for the fly camera.
    pub fly: FlyInput,
    /// Mouse-wheel steps: the fly camera's speed.
    pub wheel: f32,
    /// A drag that orbits the fly camera around a point (the web page's touch
    /// drag): the point and the drag.
    pub orbit: Option<(Vec3, Vec2)>,
}

/// A world shown live: its scene clock and the free (fly) camera.
#[derive(Clone, Debug)]
pub struct Player {
    /// The scene time and how it has played.
    pub clock: SceneClock,
    /// The free camera, moving the first view into the window while the
    /// controls leave the camera free.
    pub fly: FlyCamera,
}

impl Player {
    /// A player at scene time 0, its fly camera at `camera`.
    pub fn new(camera: &Camera) -> Self {
        Self { clock: SceneClock::default(), fly: fly_at(camera) }
    }

    /// Put the fly camera at `camera` (a scene camera chosen again).
    pub fn fly_from(&mut self, camera: &Camera) {
        self.fly = fly_at(camera);
    }

    /// One displayed frame, `real` after the last: the fly camera moved by
    /// `moves` (while the camera is free), the scene clock advanced as
    /// `controls` say (pause, speed, restart), the controls applied and the
    /// world posed; then `views` (changed as the controls say, the first into
    /// the window flown) drawn into `target` with `after` in the same frame.
    pub fn frame(
        &mut self,
        (world, renderer): (&mut World, &mut Renderer),
        controls: &mut Controls,
        (views, target): (&[View], &mut OffscreenTarget),
        (real, moves): (Duration, Moves),
        after: Vec<&mut dyn AfterViews>,
    ) -> Result<FrameOutput, crate::Error> {
        if controls.free_camera() {
            if moves.wheel != 0.0 {
                self.fly.change_speed(moves.wheel);
            }
            self.fly.update(real.as_secs_f32().min(MAX_FLY_STEP), &moves.fly);
            if let Some((centre, drag)) = moves.orbit.filter(|(_, drag)| *drag != Vec2::ZERO) {
                self.fly.orbit(centre, drag);
            }
        }
        let mut restart = false;
        let time = self.clock.tick(real, |share| {
            let (advance, pressed) = controls.advance(share);
            restart = pressed;
            advance
        });
        if restart {
            // Animations and simulations start again from the beginning.
            self.clock.restart();
        }
        let time = if restart { 0.0 } else { time };
        controls.apply(world, renderer);
        world.pose(time, renderer)?;
        let mut views = controls.views(views.to_vec());
        if let Some(flown) = views.iter_mut().find(|v| v.output.is_none()).filter(|_| controls.free_camera()) {
            flown.camera = self.fly.apply(&flown.camera);
        }
        // The work's borrows, shortened to this frame's views'.
        let after = after.into_iter().map(|work| -> &mut dyn AfterViews { work }).collect();
        Ok(world.draw_still_then(renderer, (&views, target), after, controls.samples_per_pixel())?)
    }
}

/// A fly camera at `camera`, moving at half its distance to its target a second.
fn fly_at(camera: &Camera) -> FlyCamera {
    FlyCamera::from_camera(camera, 0.5 * (camera.target - camera.eye).length().max(1.0))
}
