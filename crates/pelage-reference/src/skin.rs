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

/// The skin's blend at a lattice point, as the mirror finds it: the matrix (rows of its
/// upper 3x4) and the distance from the point to the body's surface point it took the
/// weights of.
#[derive(Clone, Copy, Debug)]
pub struct LatticeBlend {
    /// The blended matrix's first three rows.
    pub rows: [glam::DVec4; 3],
    /// How far the nearest surface point is.
    pub distance: f64,
}

/// Mirror of `strands/sdf_skin.wgsl` and `pelage_strands::lattice_skin`, by brute force:
/// at every point of `lattice` (in `SdfGrid::index` order), the weights of the nearest
/// point of the triangles of `bind` not flagged in `buried` (the barycentric blend of its
/// corners' weights, each vertex's divided by their sum; only the four heaviest joints,
/// renormalised) blending `matrices`, in `f64`.
pub fn lattice_blend(
    bind: &Mesh,
    skin: &Skin,
    buried: &[bool],
    lattice: &pelage_scene::SdfGrid,
    matrices: &[Mat4],
) -> Vec<LatticeBlend> {
    use rayon::prelude::*;
    let matrices: Vec<DMat4> = matrices.iter().map(|m| m.as_dmat4()).collect();
    (0..lattice.nodes())
        .into_par_iter()
        .map(|i| {
            let p = lattice.node(lattice.node_of(i));
            let mut best = (usize::MAX, (1.0, 0.0, 0.0), f64::INFINITY);
            for (t, tri) in bind.indices.chunks_exact(3).enumerate() {
                if buried.get(t).copied().unwrap_or(false) {
                    continue;
                }
                let [a, b, c] = [0, 1, 2].map(|k| bind.positions[tri[k] as usize]);
                let (u, v, w) = crate::sdf::closest_bary(p, a, b, c);
                let q = a.as_dvec3() * u + b.as_dvec3() * v + c.as_dvec3() * w;
                let d = p.as_dvec3().distance(q);
                if d < best.2 {
                    best = (t, (u, v, w), d);
                }
            }
            let (t, (u, v, w), distance) = best;
            let mut joints: Vec<(u32, f64)> = Vec::new();
            for (k, share) in [u, v, w].into_iter().enumerate() {
                let vertex = bind.indices[3 * t + k] as usize;
                let sum: f64 = skin.weights[vertex].iter().map(|&x| f64::from(x)).sum();
                for slot in 0..4 {
                    let weight = share * f64::from(skin.weights[vertex][slot]) / sum;
                    if weight > 0.0 {
                        let j = skin.joints[vertex][slot];
                        match joints.iter_mut().find(|(k, _)| *k == j) {
                            Some((_, total)) => *total += weight,
                            None => joints.push((j, weight)),
                        }
                    }
                }
            }
            joints.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
            joints.truncate(4);
            let total: f64 = joints.iter().map(|(_, w)| w).sum();
            let mut m = DMat4::ZERO;
            for (j, w) in joints {
                m += matrices[j as usize] * (w / total);
            }
            LatticeBlend {
                rows: [0, 1, 2].map(|r| m.row(r)),
                distance,
            }
        })
        .collect()
}
