//! A free camera like Unreal's viewport: a position, a heading (yaw) and a
//! pitch, moved each frame by input any windowing layer can fill in.

use super::Camera;
use glam::{Vec2, Vec3};

/// Radians turned per pixel of mouse movement.
const LOOK_RADIANS_PER_PIXEL: f32 = 0.003;
/// Pitch stops this short of straight up or down, so the view never flips.
const MAX_PITCH: f32 = 89.0 * std::f32::consts::PI / 180.0;
/// Speed multiplier while "fast" (Shift) is held.
const FAST: f32 = 4.0;
/// Speed change per wheel step.
const WHEEL_STEP: f32 = 1.25;

/// One frame's input: movement axes in −1..=1 and the mouse movement used to look.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FlyInput {
    /// +1 forward along the view (W), −1 back (S).
    pub forward: f32,
    /// +1 right (D), −1 left (A).
    pub right: f32,
    /// +1 up the world's Y (E), −1 down (Q).
    pub up: f32,
    /// Move four times faster (Shift).
    pub fast: bool,
    /// Mouse movement in pixels while looking (right button held); +x turns right, +y looks down.
    pub look: Vec2,
}

/// A free-flying camera: where it is, which way it faces and how fast it moves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlyCamera {
    /// Eye position.
    pub position: Vec3,
    /// Heading in radians about +Y; 0 faces −Z, positive turns left.
    pub yaw: f32,
    /// Radians above the horizon (within ±89°).
    pub pitch: f32,
    /// Units per second.
    pub speed: f32,
}

impl FlyCamera {
    /// Start where `camera` is, facing where it looks, moving `speed` units a second.
    pub fn from_camera(camera: &Camera, speed: f32) -> Self {
        let dir = (camera.target - camera.eye).normalize_or(Vec3::NEG_Z);
        Self {
            position: camera.eye,
            yaw: (-dir.x).atan2(-dir.z),
            pitch: dir.y.clamp(-1.0, 1.0).asin().clamp(-MAX_PITCH, MAX_PITCH),
            speed,
        }
    }

    /// Unit vector the camera faces.
    pub fn forward(&self) -> Vec3 {
        let (sin_yaw, cos_yaw) = self.yaw.sin_cos();
        let (sin_pitch, cos_pitch) = self.pitch.sin_cos();
        Vec3::new(-sin_yaw * cos_pitch, sin_pitch, -cos_yaw * cos_pitch)
    }

    /// Unit vector to the camera's right, level with the horizon.
    pub fn right(&self) -> Vec3 {
        let (sin_yaw, cos_yaw) = self.yaw.sin_cos();
        Vec3::new(cos_yaw, 0.0, -sin_yaw)
    }

    /// Turn by the input's mouse movement, then move for `dt` seconds.
    pub fn update(&mut self, dt: f32, input: &FlyInput) {
        self.yaw -= input.look.x * LOOK_RADIANS_PER_PIXEL;
        self.pitch = (self.pitch - input.look.y * LOOK_RADIANS_PER_PIXEL).clamp(-MAX_PITCH, MAX_PITCH);
        let direction = self.forward() * input.forward + self.right() * input.right + Vec3::Y * input.up;
        let speed = if input.fast { self.speed * FAST } else { self.speed };
        self.position += direction.clamp_length_max(1.0) * speed * dt;
    }

    /// Scale the speed by `steps` wheel notches (positive faster), within 0.01..=10,000 units a second.
    pub fn change_speed(&mut self, steps: f32) {
        self.speed = (self.speed * WHEEL_STEP.powf(steps)).clamp(0.01, 10_000.0);
    }

    /// Turn by `look` (pixels, as [`FlyInput::look`]) around `center`, keeping
    /// the distance to it: a touch-drag orbit.
    pub fn orbit(&mut self, center: Vec3, look: Vec2) {
        let distance = center.distance(self.position);
        self.yaw -= look.x * LOOK_RADIANS_PER_PIXEL;
        self.pitch = (self.pitch - look.y * LOOK_RADIANS_PER_PIXEL).clamp(-MAX_PITCH, MAX_PITCH);
        self.position = center - self.forward() * distance;
    }

    /// `camera`'s projection seen from this camera's position and direction.
    pub fn apply(&self, camera: &Camera) -> Camera {
        camera.looking_at(self.position, self.position + self.forward())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_orbit_keeps_the_centre_in_view_at_its_distance() {
        let camera = Camera::perspective(60.0, 0.1, 100.0).looking_at(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO);
        let mut fly = FlyCamera::from_camera(&camera, 1.0);
        // A quarter turn to the right at 0.003 rad a pixel.
        fly.orbit(Vec3::ZERO, Vec2::new(std::f32::consts::FRAC_PI_2 / LOOK_RADIANS_PER_PIXEL, 0.0));
        assert!(close(fly.position, Vec3::new(-5.0, 0.0, 0.0)), "{:?}", fly.position);
        assert!(close(fly.forward(), Vec3::X), "faces the centre: {:?}", fly.forward());
        // Dragging down looks down from above, and never past the pole.
        fly.orbit(Vec3::ZERO, Vec2::new(0.0, 10_000.0));
        assert!((fly.position.length() - 5.0).abs() < 1e-4 && fly.position.y > 4.9, "{:?}", fly.position);
    }

    fn close(a: Vec3, b: Vec3) -> bool {
        a.abs_diff_eq(b, 1e-5)
    }

    #[test]
    fn starts_facing_where_the_camera_looks() {
        let camera =
            Camera::perspective(60.0, 0.1, 100.0).looking_at(Vec3::new(1.0, 2.0, 3.0), Vec3::new(-2.0, 0.0, 1.0));
        let fly = FlyCamera::from_camera(&camera, 2.0);
        assert!(close(fly.forward(), (camera.target - camera.eye).normalize()), "{:?}", fly.forward());
        let again = fly.apply(&camera);
        assert!(close(again.eye, camera.eye));
        assert!(close((again.target - again.eye).normalize(), fly.forward()));
        assert_eq!(again.projection, camera.projection);
    }

    #[test]
    fn moves_along_view_right_and_world_up() {
        let camera = Camera::perspective(60.0, 0.1, 100.0).looking_at(Vec3::ZERO, Vec3::NEG_Z);
        let mut fly = FlyCamera::from_camera(&camera, 2.0);
        fly.update(0.5, &FlyInput { forward: 1.0, ..Default::default() });
        assert!(close(fly.position, Vec3::new(0.0, 0.0, -1.0)), "{:?}", fly.position);
        fly.update(1.0, &FlyInput { right: 1.0, fast: true, ..Default::default() });
        assert!(close(fly.position, Vec3::new(8.0, 0.0, -1.0)), "Shift is 4x: {:?}", fly.position);
        fly.update(1.0, &FlyInput { up: -1.0, ..Default::default() });
        assert!(close(fly.position, Vec3::new(8.0, -2.0, -1.0)), "{:?}", fly.position);
        // Diagonals are no faster than straight lines.
        let before = fly.position;
        fly.update(1.0, &FlyInput { forward: 1.0, right: 1.0, ..Default::default() });
        assert!(((fly.position - before).length() - 2.0).abs() < 1e-5);
    }

    #[test]
    fn mouse_turns_right_and_looks_down_within_limits() {
        let camera = Camera::perspective(60.0, 0.1, 100.0).looking_at(Vec3::ZERO, Vec3::NEG_Z);
        let mut fly = FlyCamera::from_camera(&camera, 1.0);
        fly.update(0.0, &FlyInput { look: Vec2::new(100.0, 0.0), ..Default::default() });
        assert!(fly.forward().x > 0.2, "moving the mouse right turns right: {:?}", fly.forward());
        fly.update(0.0, &FlyInput { look: Vec2::new(0.0, 1e6), ..Default::default() });
        assert!((fly.pitch + MAX_PITCH).abs() < 1e-6, "looking down stops short of straight down");
        assert!(fly.apply(&camera).view().is_finite());
    }

    #[test]
    fn wheel_scales_speed_within_bounds() {
        let mut fly = FlyCamera::from_camera(&Camera::perspective(60.0, 0.1, 100.0), 1.0);
        fly.change_speed(2.0);
        assert!((fly.speed - 1.5625).abs() < 1e-5);
        fly.change_speed(-1000.0);
        assert_eq!(fly.speed, 0.01);
    }
}
