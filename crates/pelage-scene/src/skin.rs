//! Skinned meshes: per vertex up to four joints and their weights ([`Skin`]), and a
//! procedural two-joint rig that bends and twists a mesh over time ([`SkinBend`], the
//! scene file's `[skin]` table).
//!
//! Skinning itself (linear blend skinning of positions and normals) runs on the GPU in
//! stage 1 (`pelage_strands::MeshSkin`); this module is the CPU data it reads.

use glam::{Mat4, Quat, Vec3};
use serde::{Deserialize, Serialize};

use crate::params::{extent, finite_vec, non_negative};
use crate::{Mesh, ParamError};

/// The most joints one [`Skin`] may name (the joint-matrix buffer holds one `mat4x4<f32>`
/// each: 64 KiB, WebGPU's smallest storage binding is far larger).
pub const MAX_JOINTS: u32 = 1024;

/// How far the weights of a vertex may sum from 1 before [`Skin::validate`] refuses them
/// (relative); within it they are normalised (divided by their sum) on upload.
pub const WEIGHT_SUM_TOLERANCE: f32 = 0.01;

/// Per vertex up to four joints and their weights: the input of linear blend skinning,
/// `p' = Σ w_k M[j_k] p`, with `M` the joint matrices of the frame (a joint's world
/// transform times its inverse bind matrix, as glTF defines them).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Skin {
    /// Four joint indices per vertex (unused slots: any joint below `joint_count`, weight 0).
    pub joints: Vec<[u32; 4]>,
    /// Four weights per vertex, each finite and >= 0, summing to 1 within
    /// [`WEIGHT_SUM_TOLERANCE`] (normalised on upload: see [`Skin::normalized_weights`]).
    pub weights: Vec<[f32; 4]>,
    /// Number of joint matrices the frame supplies (1..=[`MAX_JOINTS`]).
    pub joint_count: u32,
}

impl Skin {
    /// Checks the skin against a mesh of `vertex_count` vertices: one joint set and one
    /// weight set per vertex, every joint index below `joint_count`, every weight finite
    /// and >= 0, each vertex's weights summing to 1 within [`WEIGHT_SUM_TOLERANCE`]. The
    /// error names the field and vertex (`skin.joints[17][2]`).
    pub fn validate(&self, vertex_count: usize) -> Result<(), ParamError> {
        if self.joint_count == 0 || self.joint_count > MAX_JOINTS {
            return Err(ParamError::new(
                "skin.joint_count",
                self.joint_count,
                &format!("must be in 1..={MAX_JOINTS}"),
            ));
        }
        for (name, len) in [
            ("skin.joints", self.joints.len()),
            ("skin.weights", self.weights.len()),
        ] {
            if len != vertex_count {
                return Err(ParamError::new(
                    name,
                    format!("{len} entries"),
                    &format!("needs one per mesh vertex ({vertex_count})"),
                ));
            }
        }
        for (v, (joints, weights)) in self.joints.iter().zip(&self.weights).enumerate() {
            for (k, &j) in joints.iter().enumerate() {
                if j >= self.joint_count {
                    return Err(ParamError::new(
                        &format!("skin.joints[{v}][{k}]"),
                        j,
                        &format!(
                            "must be below the joint count ({}): a joint index past the joint matrices",
                            self.joint_count
                        ),
                    ));
                }
            }
            for (k, &w) in weights.iter().enumerate() {
                if !(w.is_finite() && w >= 0.0) {
                    return Err(ParamError::new(
                        &format!("skin.weights[{v}][{k}]"),
                        w,
                        "must be a finite number >= 0",
                    ));
                }
            }
            let sum: f32 = weights.iter().sum();
            if (sum - 1.0).abs() > WEIGHT_SUM_TOLERANCE {
                return Err(ParamError::new(
                    &format!("skin.weights[{v}]"),
                    weights,
                    &format!(
                        "must sum to 1 (within {WEIGHT_SUM_TOLERANCE}; they sum to {sum}): \
                         weights that do not are refused, not guessed at"
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The weights divided by their sum (what the GPU reads): a validated skin's sums are
    /// within [`WEIGHT_SUM_TOLERANCE`] of 1, and this makes them 1 to float precision.
    pub fn normalized_weights(&self) -> Vec<[f32; 4]> {
        self.weights
            .iter()
            .map(|w| {
                let sum: f32 = w.iter().sum();
                w.map(|x| x / sum)
            })
            .collect()
    }

    /// Checks joint matrices for this skin: exactly `joint_count` of them, every element
    /// finite. The error names `skin.joint_matrices[i]`.
    pub fn check_matrices(&self, matrices: &[Mat4]) -> Result<(), ParamError> {
        if matrices.len() != self.joint_count as usize {
            return Err(ParamError::new(
                "skin.joint_matrices",
                format!("{} matrices", matrices.len()),
                &format!("needs one per joint ({})", self.joint_count),
            ));
        }
        check_finite_matrices(matrices)
    }
}

/// Errors naming `skin.joint_matrices[i]` unless every element of every matrix is finite.
pub fn check_finite_matrices(matrices: &[Mat4]) -> Result<(), ParamError> {
    for (i, m) in matrices.iter().enumerate() {
        if !m.is_finite() {
            return Err(ParamError::new(
                &format!("skin.joint_matrices[{i}]"),
                m,
                "every element must be finite",
            ));
        }
    }
    Ok(())
}

/// A procedural two-joint rig (the scene file's `[skin]` table): joint 0 holds the mesh
/// still; joint 1, at `origin`, carries the part of the mesh on the `axis` side of it,
/// bending it about `bend_axis` through `origin` and twisting it about `axis`, each a sine
/// of its amplitude and frequency. Vertices within `blend` of the plane through `origin`
/// across `axis` blend the two joints (a smoothstep of their distance along `axis`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SkinBend {
    /// The joint the mesh bends at.
    pub origin: Vec3,
    /// The direction from `origin` into the part that moves (need not be unit; not zero).
    pub axis: Vec3,
    /// The axis the moving part bends about (need not be unit; not zero).
    pub bend_axis: Vec3,
    /// Half the width of the blend zone along `axis`, scene units (> 0).
    pub blend: f32,
    /// Amplitude of the bend, radians.
    pub bend: f32,
    /// Bends per second.
    pub bend_frequency: f32,
    /// Amplitude of the twist about `axis`, radians.
    pub twist: f32,
    /// Twists per second.
    pub twist_frequency: f32,
}

impl Default for SkinBend {
    /// The creature's head and forequarters turning from side to side and twisting: the
    /// joint at the shoulders, the blend zone a quarter unit each side.
    fn default() -> Self {
        Self {
            origin: Vec3::new(0.0, 0.1, 0.2),
            axis: Vec3::Z,
            bend_axis: Vec3::Y,
            blend: 0.25,
            bend: 0.6,
            bend_frequency: 0.5,
            twist: 0.3,
            twist_frequency: 0.7,
        }
    }
}

impl SkinBend {
    /// Checks every field; the error names the first bad one (`skin.blend`).
    pub fn validate(&self) -> Result<(), ParamError> {
        finite_vec("skin.origin", self.origin)?;
        for (name, v) in [("skin.axis", self.axis), ("skin.bend_axis", self.bend_axis)] {
            finite_vec(name, v)?;
            if v.length() < 1e-6 {
                return Err(ParamError::new(
                    name,
                    v,
                    "must be a direction (longer than 1e-6)",
                ));
            }
        }
        extent("skin.blend", self.blend)?;
        for (name, v) in [
            ("skin.bend", self.bend),
            ("skin.bend_frequency", self.bend_frequency),
            ("skin.twist", self.twist),
            ("skin.twist_frequency", self.twist_frequency),
        ] {
            non_negative(name, v)?;
            if v > 1000.0 {
                return Err(ParamError::new(name, v, "must be in [0, 1000]"));
            }
        }
        Ok(())
    }

    /// The rig's [`Skin`] on `mesh`: two joints, vertex weights a smoothstep of the
    /// distance along `axis` from `origin` over `[-blend, blend]`.
    pub fn skin(&self, mesh: &Mesh) -> Skin {
        let axis = self.axis.normalize_or_zero();
        let weights = mesh
            .positions
            .iter()
            .map(|&p| {
                let x = ((p - self.origin).dot(axis) / self.blend * 0.5 + 0.5).clamp(0.0, 1.0);
                let w1 = x * x * (3.0 - 2.0 * x);
                [1.0 - w1, w1, 0.0, 0.0]
            })
            .collect();
        Skin {
            joints: vec![[0, 1, 0, 0]; mesh.positions.len()],
            weights,
            joint_count: 2,
        }
    }

    /// The rotation of joint 1 at time `t` (seconds): the bend after the twist.
    pub fn rotation(&self, t: f32) -> Quat {
        let tau = std::f32::consts::TAU;
        let bend = self.bend * (tau * self.bend_frequency * t).sin();
        let twist = self.twist * (tau * self.twist_frequency * t).sin();
        Quat::from_axis_angle(self.bend_axis.normalize_or_zero(), bend)
            * Quat::from_axis_angle(self.axis.normalize_or_zero(), twist)
    }

    /// The joint matrices at time `t`: joint 0 the identity, joint 1 the rotation about
    /// `origin`.
    pub fn joint_matrices(&self, t: f32) -> [Mat4; 2] {
        let turn = Mat4::from_translation(self.origin)
            * Mat4::from_quat(self.rotation(t))
            * Mat4::from_translation(-self.origin);
        [Mat4::IDENTITY, turn]
    }

    /// A box holding `bounds` in every pose: the box itself (joint 0) and the box around
    /// the sphere about `origin` through its farthest corner (joint 1); a blended vertex
    /// lies between the two, inside their union's box.
    pub fn reach(&self, (lo, hi): (Vec3, Vec3)) -> (Vec3, Vec3) {
        let r = (lo - self.origin)
            .abs()
            .max((hi - self.origin).abs())
            .length();
        (
            lo.min(self.origin - Vec3::splat(r)),
            hi.max(self.origin + Vec3::splat(r)),
        )
    }
}
