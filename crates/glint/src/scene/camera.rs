//! Beginner layer: [`Camera`], where a view looks from and its
//! [`Projection`] (perspective or orthographic).

use glam::{Mat4, Vec3};

/// How the camera projects.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Perspective with a vertical field of view in radians.
    Perspective {
        /// Vertical field of view, radians.
        fov_y: f32,
        /// Near plane distance (> 0).
        near: f32,
        /// Far plane distance (> near).
        far: f32,
    },
    /// Orthographic showing `height` world units vertically.
    Orthographic {
        /// Visible height in world units (width follows the aspect ratio).
        height: f32,
        /// Near plane distance.
        near: f32,
        /// Far plane distance.
        far: f32,
    },
}

/// A camera: where it is, where it looks, and how it projects. Its matrices go
/// in the Camera block (`@group(1)`), written only when they change.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub eye: Vec3,
    /// Point looked at.
    pub target: Vec3,
    /// Up direction (need not be exactly perpendicular).
    pub up: Vec3,
    /// Projection.
    pub projection: Projection,
}

impl Camera {
    /// A perspective camera with vertical field of view `fov_y_degrees`, at the origin
    /// looking down −Z; place it with [`Camera::looking_at`].
    pub fn perspective(fov_y_degrees: f32, near: f32, far: f32) -> Self {
        Self {
            eye: Vec3::ZERO,
            target: Vec3::NEG_Z,
            up: Vec3::Y,
            projection: Projection::Perspective { fov_y: fov_y_degrees.to_radians(), near, far },
        }
    }

    /// An orthographic camera showing `height` world units vertically.
    pub fn orthographic(height: f32, near: f32, far: f32) -> Self {
        Self { projection: Projection::Orthographic { height, near, far }, ..Self::perspective(60.0, near, far) }
    }

    /// The same camera moved to `eye`, looking at `target`, Y up.
    pub fn looking_at(mut self, eye: Vec3, target: Vec3) -> Self {
        self.eye = eye;
        self.target = target;
        self.up = if (target - eye).normalize_or_zero().cross(Vec3::Y).length_squared() < 1e-8 {
            Vec3::Z // looking straight up or down: any horizontal up works
        } else {
            Vec3::Y
        };
        self
    }

    /// World-to-view matrix (right-handed, looking down −Z).
    pub fn view(&self) -> Mat4 {
        glam::camera::rh::view::look_at_mat4(self.eye, self.target, self.up)
    }

    /// View-to-clip matrix for `aspect` = width / height (wgpu clip space, z in 0..1).
    pub fn projection(&self, aspect: f32) -> Mat4 {
        use glam::camera::rh::proj::directx;
        match self.projection {
            Projection::Perspective { fov_y, near, far } => directx::perspective(fov_y, aspect, near, far),
            Projection::Orthographic { height, near, far } => {
                let (h, w) = (height * 0.5, height * 0.5 * aspect);
                directx::orthographic(-w, w, -h, h, near, far)
            }
        }
    }

    /// Far plane distance.
    pub fn far(&self) -> f32 {
        match self.projection {
            Projection::Perspective { far, .. } | Projection::Orthographic { far, .. } => far,
        }
    }
}
