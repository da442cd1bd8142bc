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
    /// Unit vector pointing from the scene towards the light, or an error for a zero or
    /// non-finite direction, or a colour or intensity out of range (see
    /// [`check_radiance`]).
    pub fn to_light(&self) -> Result<Vec3, crate::ParamError> {
        let d = -self.direction;
        if !d.is_finite() || d.length_squared() < 1e-12 {
            return Err(crate::ParamError {
                name: "light.direction".into(),
                value: format!("{:?}", self.direction),
                reason: "must be a finite, non-zero vector".into(),
            });
        }
        check_radiance("light.", self.color, self.intensity)?;
        Ok(d.normalize())
    }
}

/// The largest colour x intensity a light may have, per channel: the shaders multiply it
/// by the hair's scattering (and a point light's by `1 / max(distance², 1e-4)`) and sum
/// up to [`MAX_LIGHTS`] of them in 32-bit floats, which stays finite from this bound.
pub const MAX_RADIANCE: f32 = 1.0e6;

/// Checks a light's `color` (every channel finite and >= 0), its `intensity` (finite
/// and >= 0) and their product (every channel at most [`MAX_RADIANCE`]: each factor
/// may be in range while their product overflows to infinity). Errors name
/// `{prefix}color` or `{prefix}intensity`.
pub fn check_radiance(prefix: &str, color: Vec3, intensity: f32) -> Result<(), crate::ParamError> {
    let bad = |field: &str, value: String, reason: String| crate::ParamError {
        name: format!("{prefix}{field}"),
        value,
        reason,
    };
    if !color.is_finite() || color.min_element() < 0.0 {
        return Err(bad(
            "color",
            format!("{color:?}"),
            "every channel must be finite and >= 0".into(),
        ));
    }
    if !intensity.is_finite() || intensity < 0.0 {
        return Err(bad(
            "intensity",
            intensity.to_string(),
            "must be finite and >= 0".into(),
        ));
    }
    let radiance = color.as_dvec3() * f64::from(intensity);
    if radiance.max_element() > f64::from(MAX_RADIANCE) {
        return Err(bad(
            "intensity",
            format!("{intensity} (times color {color:?}: {radiance:?})"),
            format!(
                "color x intensity must be at most {MAX_RADIANCE:e} in every channel \
                 (larger values overflow 32-bit floats in the shaders)"
            ),
        ));
    }
    Ok(())
}

/// A point light: radiance falls off with the square of the distance.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PointLight {
    /// Position in world space.
    pub position: Vec3,
    /// Linear RGB colour.
    pub color: Vec3,
    /// Multiplier on `color`: the irradiance at distance 1 (it falls off as 1 / distance²).
    pub intensity: f32,
}

impl Default for PointLight {
    fn default() -> Self {
        Self {
            position: Vec3::new(-1.5, 1.2, -2.0),
            color: Vec3::ONE,
            intensity: 6.0,
        }
    }
}

/// The most lights a scene may have.
pub const MAX_LIGHTS: usize = 4;

/// One light of a scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Light {
    /// Parallel light from one direction.
    Directional(DirectionalLight),
    /// Light from a point, falling off with the square of the distance.
    Point(PointLight),
}

impl Default for Light {
    fn default() -> Self {
        Self::Directional(DirectionalLight::default())
    }
}

impl Light {
    /// Checks the light; the error names `lights[index].<field>`.
    pub fn validate(&self, index: usize) -> Result<(), crate::ParamError> {
        let rename = |mut e: crate::ParamError| {
            e.name = format!("lights[{index}].{}", e.name.trim_start_matches("light."));
            e
        };
        match self {
            Self::Directional(d) => d.to_light().map(|_| ()).map_err(rename),
            Self::Point(p) => {
                if !p.position.is_finite() || p.position.abs().max_element() > crate::MAX_EXTENT {
                    return Err(crate::ParamError {
                        name: format!("lights[{index}].position"),
                        value: format!("{:?}", p.position),
                        reason: format!(
                            "every component must be finite and at most {:e} in magnitude",
                            crate::MAX_EXTENT
                        ),
                    });
                }
                check_radiance(&format!("lights[{index}]."), p.color, p.intensity)
            }
        }
    }

    /// Checks a scene's lights: 1 to [`MAX_LIGHTS`] of them, each valid.
    pub fn validate_all(lights: &[Light]) -> Result<(), crate::ParamError> {
        if lights.is_empty() || lights.len() > MAX_LIGHTS {
            return Err(crate::ParamError {
                name: "lights".into(),
                value: format!("{} lights", lights.len()),
                reason: format!("a scene needs 1 to {MAX_LIGHTS} lights"),
            });
        }
        lights
            .iter()
            .enumerate()
            .try_for_each(|(i, l)| l.validate(i))
    }

    /// The directional light that stands in for this one when fitting a shadow to hair
    /// around `target`: itself, or for a point light the direction from its position to
    /// `target` (an orthographic light space: exact for distant point lights, an
    /// approximation for near ones).
    pub fn as_directional(&self, target: Vec3) -> DirectionalLight {
        match self {
            Self::Directional(d) => d.clone(),
            Self::Point(p) => DirectionalLight {
                direction: target - p.position,
                color: p.color,
                intensity: p.intensity,
            },
        }
    }

    /// [`Light::as_directional`], checked: a point light at `target` (the centre of the
    /// hair's box, which its shadow is fitted around) has no direction to cast a shadow
    /// along, and is refused naming `lights[index].position`. Other errors name the
    /// light's keys as [`Light::validate`] does.
    pub fn shadow_light(
        &self,
        index: usize,
        target: Vec3,
    ) -> Result<DirectionalLight, crate::ParamError> {
        self.validate(index)?;
        let light = self.as_directional(target);
        if let Self::Point(p) = self {
            let d = light.direction;
            if !d.is_finite() || d.length_squared() < 1e-12 {
                return Err(crate::ParamError {
                    name: format!("lights[{index}].position"),
                    value: format!("{:?}", p.position),
                    reason: format!(
                        "a point light's shadow is cast along the direction from the light \
                         to the centre of the hair's box, {target:?}: the light must not sit \
                         at that centre"
                    ),
                });
            }
        }
        Ok(light)
    }

    /// Seed 003's Fig. 31 set-up: a white key light from above and beside the camera, and
    /// a warm point light behind the hair (seen from the camera) that outlines it.
    pub fn key_and_back(camera: &crate::Camera) -> Vec<Light> {
        let view = (camera.target - camera.eye).normalize_or(Vec3::NEG_Z);
        let side = view.cross(Vec3::Y).normalize_or(Vec3::X);
        let key = DirectionalLight {
            direction: (view - 0.6 * side - 0.7 * Vec3::Y).normalize_or(Vec3::NEG_Y),
            color: Vec3::ONE,
            intensity: 1.6,
        };
        let back = PointLight {
            position: camera.target + 2.5 * view + 1.2 * Vec3::Y + 0.4 * side,
            color: Vec3::new(1.0, 0.85, 0.65),
            intensity: 14.0,
        };
        vec![Light::Directional(key), Light::Point(back)]
    }
}
