//! Lights.

use glam::Vec3;
use serde::{Deserialize, Serialize};

/// A directional light, such as the sun.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DirectionalLight {
    /// Direction the light travels in (from the light towards the scene); normalised on use.
    pub direction: Vec3,
    /// Linear RGB radiance scale.
    pub color: Vec3,
    /// Multiplier on `color`.
    pub intensity: f32,
}

impl Default for DirectionalLight {
    fn default() -> Self {
        Self {
            direction: Vec3::new(-0.85, -0.6, 0.1),
            color: Vec3::ONE,
            intensity: 1.8,
        }
    }
}

impl DirectionalLight {
    /// Unit vector pointing from the scene towards the light, or an error for a zero or non-finite direction.
    pub fn to_light(&self) -> Result<Vec3, crate::ParamError> {
        let d = -self.direction;
        if !d.is_finite() || d.length_squared() < 1e-12 {
            return Err(crate::ParamError {
                name: "light.direction".into(),
                value: format!("{:?}", self.direction),
                reason: "must be a finite, non-zero vector".into(),
            });
        }
        if !self.color.is_finite() || !self.intensity.is_finite() || self.intensity < 0.0 {
            return Err(crate::ParamError {
                name: "light.intensity".into(),
                value: format!("{:?} x {}", self.color, self.intensity),
                reason: "colour and intensity must be finite and >= 0".into(),
            });
        }
        Ok(d.normalize())
    }
}
