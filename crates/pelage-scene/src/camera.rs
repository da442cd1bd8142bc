//! A perspective camera.

use glam::{Mat4, Vec3};
use serde::{Deserialize, Serialize};

/// A perspective camera looking from `eye` at `target`, y up.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Camera {
    /// Position of the eye.
    pub eye: Vec3,
    /// Point looked at.
    pub target: Vec3,
    /// Vertical field of view, radians.
    pub fov_y: f32,
    /// Near plane distance (> 0).
    pub near: f32,
    /// Far plane distance (> near).
    pub far: f32,
}

impl Default for Camera {
    fn default() -> Self {
        Self {
            eye: Vec3::new(2.2, 0.9, 2.9),
            target: Vec3::new(0.0, 0.0, 0.0),
            fov_y: 40f32.to_radians(),
            near: 0.05,
            far: 20.0,
        }
    }
}

impl Camera {
    /// World to view transform (right-handed, y up).
    pub fn view(&self) -> Mat4 {
        glam::camera::rh::view::look_at_mat4(self.eye, self.target, Vec3::Y)
    }

    /// View to clip transform for wgpu's [0, 1] depth range.
    pub fn projection(&self, aspect: f32) -> Mat4 {
        // wgpu's clip space: z in [0, 1], y up (glam's "directx" convention).
        glam::camera::rh::proj::directx::perspective(self.fov_y, aspect, self.near, self.far)
    }

    /// World to clip transform.
    pub fn view_projection(&self, aspect: f32) -> Mat4 {
        self.projection(aspect) * self.view()
    }

    /// The camera orbited around its target by `angle` radians about the y axis.
    pub fn orbited(&self, angle: f32) -> Self {
        let offset = glam::Quat::from_rotation_y(angle) * (self.eye - self.target);
        Self {
            eye: self.target + offset,
            ..self.clone()
        }
    }

    /// Checks that the camera defines a usable projection.
    pub fn validate(&self) -> Result<(), crate::ParamError> {
        let bad = |name: &str, value: String, reason: &str| crate::ParamError {
            name: name.into(),
            value,
            reason: reason.into(),
        };
        if !self.eye.is_finite() || !self.target.is_finite() {
            return Err(bad(
                "camera.eye",
                format!("{:?}", self.eye),
                "eye and target must be finite",
            ));
        }
        if (self.eye - self.target).length_squared() < 1e-12 {
            return Err(bad(
                "camera.target",
                format!("{:?}", self.target),
                "must differ from the eye",
            ));
        }
        if !(self.fov_y > 0.0 && self.fov_y < std::f32::consts::PI) {
            return Err(bad(
                "camera.fov_y",
                format!("{}", self.fov_y),
                "must be in (0, π) radians",
            ));
        }
        if !(self.near > 0.0 && self.far > self.near && self.far.is_finite()) {
            return Err(bad(
                "camera.near",
                format!("{} .. {}", self.near, self.far),
                "needs 0 < near < far < inf",
            ));
        }
        Ok(())
    }
}
