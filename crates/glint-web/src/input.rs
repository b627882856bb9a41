//! The page's input, as the viewer's: W A S D and Q E move, the right mouse
//! button held looks around, the wheel changes speed, Shift moves faster; one
//! finger dragged on a touch screen orbits the view's centre.

use glam::Vec2;
use glint::scene::FlyInput;
use std::collections::HashSet;

/// What happened since the last frame.
#[derive(Default)]
pub struct Input {
    /// `KeyboardEvent.code`s held down.
    held: HashSet<String>,
    /// Whether the right button is down.
    looking: bool,
    /// Mouse movement while looking, in CSS pixels.
    look: Vec2,
    /// Wheel notches (positive: faster).
    wheel: f32,
    /// Touch drag to orbit, in CSS pixels, and where the finger last was.
    orbit: Vec2,
    touch: Option<Vec2>,
    /// Keys pressed since the last frame (not repeats), for the page's own
    /// keys: `H`, Enter and Space.
    pressed: Vec<String>,
}

impl Input {
    /// A key went down or up.
    pub fn key(&mut self, code: String, down: bool) {
        if down {
            self.held.insert(code);
        } else {
            self.held.remove(&code);
        }
    }

    /// A key was pressed (`repeat`: held down and repeating).
    pub fn key_pressed(&mut self, code: String, repeat: bool) {
        if !repeat {
            self.pressed.push(code);
        }
    }

    /// The keys pressed since the last call.
    pub fn take_pressed(&mut self) -> Vec<String> {
        std::mem::take(&mut self.pressed)
    }

    /// A mouse button went down or up (button 2 is the right one).
    pub fn button(&mut self, button: i16, down: bool) {
        if button == 2 {
            self.looking = down;
        }
    }

    /// The mouse moved by `delta`.
    pub fn mouse_moved(&mut self, delta: Vec2) {
        if self.looking {
            self.look += delta;
        }
    }

    /// The wheel turned by `delta_y` (browser units: negative is away from the user).
    pub fn wheel(&mut self, delta_y: f64) {
        self.wheel -= delta_y.signum() as f32;
    }

    /// A finger touched at `at`, moved there, or (`None`) lifted.
    pub fn touch(&mut self, at: Option<Vec2>) {
        if let (Some(now), Some(before)) = (at, self.touch) {
            self.orbit += now - before;
        }
        self.touch = at;
    }

    /// The frame's movement, wheel notches and orbit drag, leaving the held keys.
    pub fn take(&mut self) -> (FlyInput, f32, Vec2) {
        let axis = |plus: &str, minus: &str| f32::from(self.held.contains(plus)) - f32::from(self.held.contains(minus));
        let fly = FlyInput {
            forward: axis("KeyW", "KeyS"),
            right: axis("KeyD", "KeyA"),
            up: axis("KeyE", "KeyQ"),
            fast: self.held.contains("ShiftLeft") || self.held.contains("ShiftRight"),
            look: std::mem::take(&mut self.look),
        };
        (fly, std::mem::take(&mut self.wheel), std::mem::take(&mut self.orbit))
    }
}
