//! The CPU mirror of `strands/skin.wgsl`: linear blend skinning of a bind pose, in `f64`.
//!
//! Not a loop-for-loop twin: it computes the same quantity another way, so that a shared
//! mistake is unlikely. Weights are normalised here from the skin as given; the blended
//! matrix is built in `f64`; normals are transformed by the blended 3x3's inverse
//! transpose (the shader uses the cofactor, which differs by the determinant's factor,
//! gone after normalising; the two agree for a positive determinant).

use glam::{DMat3, DMat4, DVec3, Mat4, Vec3};
use pelage_scene::{Mesh, Skin};

/// `bind` skinned by `skin` with `matrices` (one per joint): positions `Σ w_k M_k p`,
/// normals `(Σ w_k M_k)^-T n` normalised, with each vertex's weights divided by their sum.
/// A joint index past `matrices` panics: the mirror is only fed validated skins.
pub fn skin_mesh(bind: &Mesh, skin: &Skin, matrices: &[Mat4]) -> Mesh {
    let matrices: Vec<DMat4> = matrices.iter().map(|m| m.as_dmat4()).collect();
    let mut positions = Vec::with_capacity(bind.positions.len());
    let mut normals = Vec::with_capacity(bind.normals.len());
    for v in 0..bind.positions.len() {
        let sum: f64 = skin.weights[v].iter().map(|&w| f64::from(w)).sum();
        let mut blended = DMat4::ZERO;
        for k in 0..4 {
            let w = f64::from(skin.weights[v][k]) / sum;
            // A slot of weight 0 adds nothing, as in the shader.
            if w != 0.0 {
                blended += matrices[skin.joints[v][k] as usize] * w;
            }
        }
        let p = blended.transform_point3(bind.positions[v].as_dvec3());
        let linear = DMat3::from_mat4(blended);
        let n: DVec3 = linear.inverse().transpose() * bind.normals[v].as_dvec3();
        positions.push(p.as_vec3());
        normals.push(n.normalize().as_vec3());
    }
    Mesh {
        positions,
        normals,
        indices: bind.indices.clone(),
        uvs: bind.uvs.clone(),
    }
}

/// The size of `mesh` the skinning tolerance is relative to: its bounding box's diagonal.
pub fn mesh_size(mesh: &Mesh) -> f32 {
    let (lo, hi): (Vec3, Vec3) = mesh.bounds();
    (hi - lo).length()
}
