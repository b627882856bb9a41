//! World layer: a front end's scene clock ([`Player`](super::Player)): scene
//! time follows real time, but advances at most
//! [`MAX_FRAME_ADVANCE`] a frame, so a cloth slower to simulate than real time
//! plays in slow motion instead of falling further behind every frame. It keeps
//! how fast the scene actually played (scene seconds per real second), for the
//! viewer's title bar and the summary `glint view --frames` prints on quitting.

use std::time::Duration;

/// Most scene time one frame advances, seconds (each pose steps a cloth all the
/// way to the scene time).
pub const MAX_FRAME_ADVANCE: f32 = 1.0 / 30.0;

/// Scene seconds against real seconds over some span of frames.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Played {
    /// Frames in the span.
    pub frames: u32,
    /// Real time, seconds.
    pub real: f64,
    /// Scene time advanced, seconds.
    pub scene: f64,
}

impl Played {
    /// Scene seconds per real second (1 when the scene keeps up; 0 before any time passed).
    pub fn speed(&self) -> f64 {
        if self.real > 0.0 {
            self.scene / self.real
        } else {
            0.0
        }
    }

    /// Mean real time a frame, milliseconds.
    pub fn frame_ms(&self) -> f64 {
        self.real * 1e3 / f64::from(self.frames.max(1))
    }

    fn add(&mut self, real: f64, scene: f64) {
        *self = Self { frames: self.frames + 1, real: self.real + real, scene: self.scene + scene };
    }
}

/// The scene time and how it has played.
#[derive(Clone, Debug, Default)]
pub struct SceneClock {
    /// Animation and simulation time, seconds.
    pub time: f32,
    /// Since the scene (re)started.
    pub total: Played,
    /// Since [`SceneClock::take_recent`] was last called.
    recent: Played,
}

impl SceneClock {
    /// Advance by a frame that took `real`, moving scene time as `advance`
    /// says of the frame's share of it (at most [`MAX_FRAME_ADVANCE`]): the
    /// controls' pause and speed; returns the new scene time.
    pub fn tick(&mut self, real: Duration, advance: impl FnOnce(f32) -> f32) -> f32 {
        let advance = advance(real.as_secs_f32().min(MAX_FRAME_ADVANCE));
        self.time += advance;
        self.total.add(real.as_secs_f64(), f64::from(advance));
        self.recent.add(real.as_secs_f64(), f64::from(advance));
        self.time
    }

    /// The frames since the last call (for the title bar), starting a new span.
    pub fn take_recent(&mut self) -> Played {
        std::mem::take(&mut self.recent)
    }

    /// Start again from scene time 0 (a reloaded scene).
    pub fn restart(&mut self) {
        *self = Self::default();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_frames_play_at_real_time_and_slow_ones_in_slow_motion() {
        let mut clock = SceneClock::default();
        for _ in 0..10 {
            clock.tick(Duration::from_millis(20), |s| s);
        }
        assert!((clock.time - 0.2).abs() < 1e-5);
        assert!((clock.total.speed() - 1.0).abs() < 1e-5);
        let recent = clock.take_recent();
        assert_eq!(recent.frames, 10);
        assert!((recent.frame_ms() - 20.0).abs() < 1e-9);
        // A 100 ms frame advances the scene a thirtieth of a second: a third of real time.
        clock.tick(Duration::from_millis(100), |s| s);
        let slow = clock.take_recent();
        assert!((slow.speed() - 1.0 / 3.0).abs() < 1e-5, "{slow:?}");
        assert!((clock.time - (0.2 + MAX_FRAME_ADVANCE)).abs() < 1e-5);
        assert_eq!(clock.total.frames, 11);
        clock.restart();
        assert_eq!((clock.time, clock.total), (0.0, Played::default()));
        // Paused, frames pass and the scene stays; at twice the speed it runs ahead.
        clock.tick(Duration::from_millis(20), |_| 0.0);
        assert_eq!((clock.time, clock.total.frames), (0.0, 1));
        clock.tick(Duration::from_millis(20), |s| 2.0 * s);
        assert!((clock.time - 0.04).abs() < 1e-6);
    }
}
