//! Cameras: the view and projection matrices every pass draws with
//! ([`CameraMatrices`], which an engine brings as they are: any handedness, reverse-Z,
//! jittered for TAA), and a y-up look-at helper that builds them ([`Camera`]).

use glam::{Mat4, Vec3, Vec4};
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

/// The narrowest and widest `fov_y` accepted, radians: 1e-4 from 0 and from π (a
/// narrower one scales clip coordinates past 32-bit floats, a wider one has no
/// perspective left).
pub const FOV_MARGIN: f32 = 1.0e-4;

/// The nearest `near` plane accepted, scene units: depths of points closer than about
/// 1e-7 of a unit to 1 cannot be told apart in 32-bit floats.
pub const MIN_NEAR: f32 = 1.0e-6;

/// The largest `far / near` accepted: beyond it the depth buffer (32-bit float) cannot
/// tell apart surfaces 1% apart at the far plane.
pub const MAX_DEPTH_RATIO: f32 = 1.0e6;

/// How close to vertical a view may be, as the sine of its angle to the y axis, before
/// [`Camera::up`] stops using y as the up vector.
const PARALLEL: f32 = 1.0e-4;

impl Camera {
    /// The up vector of the look-at: the y axis, unless the view is vertical (within an
    /// angle whose sine is 1e-4 of the y axis: a top or bottom view, where y gives no
    /// up), then -z when looking down and +z when looking up, which is where y's
    /// projection on the picture points for a camera tilted over its target from the +z
    /// side (the default camera's side): a top view has -z at the top of the picture.
    pub fn up(&self) -> Vec3 {
        let view = (self.target - self.eye).normalize_or_zero();
        if view.cross(Vec3::Y).length() > PARALLEL {
            Vec3::Y
        } else if view.y < 0.0 {
            Vec3::NEG_Z
        } else {
            Vec3::Z
        }
    }

    /// World to view transform (right-handed), up being [`Camera::up`]: y, but for a
    /// top or bottom view.
    pub fn view(&self) -> Mat4 {
        glam::camera::rh::view::look_at_mat4(self.eye, self.target, self.up())
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

    /// The view and projection matrices of this camera on a `width` x `height` target
    /// (standard depth: near maps to 0, far to 1).
    pub fn matrices(&self, width: u32, height: u32) -> CameraMatrices {
        let aspect = width.max(1) as f32 / height.max(1) as f32;
        CameraMatrices {
            view: self.view(),
            projection: self.projection(aspect),
        }
    }

    /// The same with reversed depth (near maps to 1, far to 0): more depth precision far
    /// away, with a `Greater` depth test and depth cleared to 0.
    pub fn matrices_reverse_z(&self, width: u32, height: u32) -> CameraMatrices {
        let aspect = width.max(1) as f32 / height.max(1) as f32;
        CameraMatrices {
            view: self.view(),
            projection: glam::camera::rh::proj::directx::perspective(
                self.fov_y, aspect, self.far, self.near,
            ),
        }
    }

    /// The camera orbited around its target by `angle` radians about the y axis.
    pub fn orbited(&self, angle: f32) -> Self {
        let offset = glam::Quat::from_rotation_y(angle) * (self.eye - self.target);
        Self {
            eye: self.target + offset,
            ..self.clone()
        }
    }

    /// Checks that the camera defines a usable view and projection; the error names
    /// the key (`camera.eye`, `camera.target`, `camera.fov_y`, `camera.near`,
    /// `camera.far`) and its allowed range.
    pub fn validate(&self) -> Result<(), crate::ParamError> {
        let bad = |name: &str, value: String, reason: String| crate::ParamError {
            name: name.into(),
            value,
            reason,
        };
        for (name, p) in [("camera.eye", self.eye), ("camera.target", self.target)] {
            if !p.is_finite() || p.abs().max_element() > crate::MAX_EXTENT {
                return Err(bad(
                    name,
                    format!("{p:?}"),
                    format!(
                        "every component must be finite and at most {:e} in magnitude",
                        crate::MAX_EXTENT
                    ),
                ));
            }
        }
        if (self.eye - self.target).length_squared() < 1e-12 {
            return Err(bad(
                "camera.target",
                format!("{:?}", self.target),
                format!(
                    "must differ from camera.eye = {:?}: the camera looks from the eye at the \
                     target",
                    self.eye
                ),
            ));
        }
        let pi = std::f32::consts::PI;
        if !(self.fov_y >= FOV_MARGIN && self.fov_y <= pi - FOV_MARGIN) {
            return Err(bad(
                "camera.fov_y",
                format!("{}", self.fov_y),
                format!(
                    "must be in [{FOV_MARGIN:e}, π - {FOV_MARGIN:e}] radians (the vertical field \
                     of view, about 0.006 to 179.994 degrees)"
                ),
            ));
        }
        if !(self.near >= MIN_NEAR && self.near <= crate::MAX_EXTENT) {
            return Err(bad(
                "camera.near",
                format!("{}", self.near),
                format!(
                    "must be in [{MIN_NEAR:e}, {:e}] scene units (and below camera.far)",
                    crate::MAX_EXTENT
                ),
            ));
        }
        let far_max = (self.near * MAX_DEPTH_RATIO).min(crate::MAX_EXTENT);
        if !(self.far > self.near && self.far <= far_max) {
            return Err(bad(
                "camera.far",
                format!("{}", self.far),
                format!(
                    "must be in ({}, {far_max:e}]: beyond camera.near = {} and at most \
                     {MAX_DEPTH_RATIO:e} times it (32-bit depth cannot resolve more) and \
                     {:e} scene units",
                    self.near,
                    self.near,
                    crate::MAX_EXTENT
                ),
            ));
        }
        // The ranges above keep the matrices usable; this is a safety net that names
        // the camera's keys, not the matrices.
        for (width, height) in [(1, 1), (MAX_ASPECT_SIDE, 1), (1, MAX_ASPECT_SIDE)] {
            self.matrices(width, height).validate().map_err(|e| {
                bad(
                    "camera",
                    format!(
                        "eye {:?}, target {:?}, fov_y {}, near {}, far {}",
                        self.eye, self.target, self.fov_y, self.near, self.far
                    ),
                    format!("gives no usable view: {}", e.reason),
                )
            })?;
        }
        Ok(())
    }
}

/// The most extreme aspect ratio [`Camera::validate`] tries the matrices at.
const MAX_ASPECT_SIDE: u32 = 16384;

/// The camera as every pass sees it: world to view and view to clip (wgpu's clip space,
/// depth in [0, 1]). This is what an engine hands pelage each frame, as its own render
/// graph has them: right- or left-handed, standard or reversed depth, with a sub-pixel
/// jitter in the projection for TAA. The projection must be a perspective one (the
/// ribbons' minimum width in pixels is derived from it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraMatrices {
    /// World to view.
    pub view: Mat4,
    /// View to clip.
    pub projection: Mat4,
}

impl CameraMatrices {
    /// World to clip.
    pub fn view_projection(&self) -> Mat4 {
        self.projection * self.view
    }

    /// The eye's world position (the view matrix's inverse applied to the origin).
    pub fn eye(&self) -> Vec3 {
        self.view.inverse().w_axis.truncate()
    }

    /// World units per pixel at view distance 1 on a target `height` pixels tall:
    /// `2 / (|P[1][1]| height)`, which is `2 tan(fov_y / 2) / height` for a symmetric
    /// perspective.
    pub fn pixel_scale(&self, height: u32) -> f32 {
        2.0 / (self.projection.y_axis.y.abs() * height.max(1) as f32)
    }

    /// Whether the projection maps nearer points to larger depth (reverse-Z), found by
    /// projecting two points in front of the eye.
    pub fn reverse_z(&self) -> bool {
        let (near, far) = (self.depth_at(1.0), self.depth_at(2.0));
        near > far
    }

    /// Clip depth (z / w) of the point `distance` in front of the eye.
    fn depth_at(&self, distance: f32) -> f32 {
        let clip = self.projection * Vec4::new(0.0, 0.0, self.forward_z() * distance, 1.0);
        clip.z / clip.w
    }

    /// View-space z of "in front of the eye": -1 for a right-handed projection (clip w
    /// grows as view z falls), +1 for a left-handed one.
    fn forward_z(&self) -> f32 {
        if self.projection.z_axis.w < 0.0 {
            -1.0
        } else {
            1.0
        }
    }

    /// Checks that the matrices are finite and invertible and the projection is a
    /// perspective one that puts points in front of the eye at positive w.
    pub fn validate(&self) -> Result<(), crate::ParamError> {
        let bad = |name: &str, reason: &str| crate::ParamError {
            name: name.into(),
            value: "(matrix)".into(),
            reason: reason.into(),
        };
        if !self.view.is_finite() || !self.projection.is_finite() {
            return Err(bad("camera.view", "view and projection must be finite"));
        }
        let det = self.view.determinant();
        if det.abs() <= 1e-12 {
            return Err(bad("camera.view", "must be invertible (determinant is 0)"));
        }
        if self.projection.z_axis.w == 0.0 || self.projection.w_axis.w != 0.0 {
            return Err(bad(
                "camera.projection",
                "must be a perspective projection (P[2][3] = +-1, P[3][3] = 0); \
                 orthographic projections are not supported",
            ));
        }
        if self.projection.y_axis.y == 0.0 || self.projection.determinant() == 0.0 {
            return Err(bad("camera.projection", "must be invertible"));
        }
        let (a, b) = (self.depth_at(1.0), self.depth_at(2.0));
        if !a.is_finite() || !b.is_finite() || a == b {
            return Err(bad(
                "camera.projection",
                "maps points in front of the eye to no usable depth",
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn look_at_matrices_give_back_the_camera() {
        let camera = Camera::default();
        let m = camera.matrices(320, 240);
        m.validate().unwrap();
        assert!((m.eye() - camera.eye).length() < 1e-4, "{:?}", m.eye());
        let expected = 2.0 * (camera.fov_y * 0.5).tan() / 240.0;
        assert!((m.pixel_scale(240) - expected).abs() < 1e-7);
        assert!(!m.reverse_z());
        let r = camera.matrices_reverse_z(320, 240);
        r.validate().unwrap();
        assert!(r.reverse_z());
        assert_eq!(r.view_projection().w_axis.w, m.view_projection().w_axis.w);
    }

    #[test]
    fn left_handed_and_jittered_projections_are_accepted() {
        let view =
            glam::camera::lh::view::look_at_mat4(Vec3::new(0.0, 0.0, -3.0), Vec3::ZERO, Vec3::Y);
        let mut projection = glam::camera::lh::proj::directx::perspective(0.8, 1.5, 0.1, 50.0);
        // A TAA jitter of a fraction of a pixel.
        projection.z_axis.x += 0.3 / 320.0;
        let m = CameraMatrices { view, projection };
        m.validate().unwrap();
        assert!(!m.reverse_z());
        assert!((m.eye() - Vec3::new(0.0, 0.0, -3.0)).length() < 1e-5);
    }

    #[test]
    fn unusable_matrices_are_errors() {
        let good = Camera::default().matrices(4, 3);
        let ortho = CameraMatrices {
            projection: glam::camera::rh::proj::directx::orthographic(
                -1.0, 1.0, -1.0, 1.0, 0.1, 10.0,
            ),
            ..good
        };
        assert!(
            ortho
                .validate()
                .unwrap_err()
                .to_string()
                .contains("orthographic")
        );
        let nan = CameraMatrices {
            view: Mat4::from_cols_array(&[f32::NAN; 16]),
            ..good
        };
        assert!(nan.validate().is_err());
        let singular = CameraMatrices {
            view: Mat4::ZERO,
            ..good
        };
        assert!(singular.validate().is_err());
    }
}
