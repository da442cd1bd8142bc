//! Mirror of `wgsl/strands/sdf.wgsl` (`pelage_strands::BodySdf`): the exact signed
//! distance from a point to a mesh, by brute force over its triangles, and the field of
//! every node of an [`SdfGrid`]. Also the ground truth of collision tests (how deep a
//! strand vertex is inside the body).

use glam::Vec3;
use pelage_scene::{Mesh, SdfGrid};
use rayon::prelude::*;

/// Barycentrics `(u, v, w)` of the point of triangle `abc` nearest `p` (Ericson,
/// Real-Time Collision Detection 5.1.5), computed in `f64`.
pub fn closest_bary(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> (f64, f64, f64) {
    let (p, a, b, c) = (p.as_dvec3(), a.as_dvec3(), b.as_dvec3(), c.as_dvec3());
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return (1.0, 0.0, 0.0);
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return (0.0, 1.0, 0.0);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (1.0 - v, v, 0.0);
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return (0.0, 0.0, 1.0);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (1.0 - w, 0.0, w);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (0.0, 1.0 - w, w);
    }
    let denom = va + vb + vc;
    if denom.abs() <= f64::MIN_POSITIVE {
        let (da, db, dc) = (p.distance(a), p.distance(b), p.distance(c));
        return if da <= db && da <= dc {
            (1.0, 0.0, 0.0)
        } else if db <= dc {
            (0.0, 1.0, 0.0)
        } else {
            (0.0, 0.0, 1.0)
        };
    }
    let (v, w) = (vb / denom, vc / denom);
    (1.0 - v - w, v, w)
}

/// The exact signed distance from `p` to `mesh` (negative inside): the distance to the
/// nearest triangle with a finite corner, signed by the side of the mesh's normal (the
/// vertex normals interpolated at the nearest point) that `p` lies on; where triangles
/// tie for nearest and disagree, outside (as the GPU's keys). `None` when no triangle
/// is finite.
pub fn signed_distance(mesh: &Mesh, p: Vec3) -> Option<f32> {
    let mut best: Option<(f64, bool)> = None;
    let pd = p.as_dvec3();
    for tri in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|k| mesh.positions[tri[k] as usize]);
        if !(a.is_finite() && b.is_finite() && c.is_finite()) {
            continue;
        }
        let (u, v, w) = closest_bary(p, a, b, c);
        let q = a.as_dvec3() * u + b.as_dvec3() * v + c.as_dvec3() * w;
        let d = pd.distance(q);
        if best.is_some_and(|(bd, _)| d > bd) {
            continue;
        }
        let [na, nb, nc] = [0, 1, 2].map(|k| mesh.normals[tri[k] as usize].as_dvec3());
        let inside = (pd - q).dot(na * u + nb * v + nc * w) < 0.0;
        best = Some(match best {
            Some((bd, was_inside)) if d == bd => (d, was_inside && inside),
            _ => (d, inside),
        });
    }
    let (d, inside) = best?;
    Some(if inside { -d as f32 } else { d as f32 })
}

/// The exact field of `mesh` on every node of `grid` (in [`SdfGrid::index`] order);
/// `far` where no triangle is finite. Brute force: `O(nodes · triangles)`.
pub fn exact_field(mesh: &Mesh, grid: &SdfGrid, far: f32) -> Vec<f32> {
    (0..grid.nodes())
        .into_par_iter()
        .map(|i| signed_distance(mesh, grid.node(grid.node_of(i))).unwrap_or(far))
        .collect()
}

/// The collision step's read of the field (`body_sample_at` in `strands/simulate.wgsl`,
/// in the space the field was built in), written again here to measure what it misses
/// over exact nodes (`the_standoff_sits_in_the_tail_of_what_the_read_misses`; the
/// shader's own read is checked only through the collision tests' depths): the
/// trilinear interpolation of the 8 nodes around `p` on `grid` (`node` gives a node's
/// value), capped by each node's value plus the way to it (a distance field moves at
/// most as fast as the point). `None` outside the grid (read as outside the body).
pub fn read(grid: &SdfGrid, mut node: impl FnMut(glam::UVec3) -> f32, p: Vec3) -> Option<f32> {
    let x = (p - grid.origin) / grid.cell;
    let top = (grid.dims - glam::UVec3::ONE).as_vec3();
    if !x.is_finite() || x.cmplt(Vec3::ZERO).any() || x.cmpgt(top).any() {
        return None;
    }
    let i = x.floor().as_uvec3().min(grid.dims - glam::UVec3::splat(2));
    let f = x - i.as_vec3();
    let (mut value, mut cap) = (0.0, f32::INFINITY);
    for corner in 0..8u32 {
        let o = glam::UVec3::new(corner & 1, (corner >> 1) & 1, corner >> 2);
        let v = node(i + o);
        let weight: f32 = (0..3)
            .map(|k| if o[k] == 1 { f[k] } else { 1.0 - f[k] })
            .product();
        value += weight * v;
        cap = cap.min(v + grid.cell * (f - o.as_vec3()).length());
    }
    Some(value.min(cap))
}

/// How deep each of `points` is inside `mesh` (the exact signed distance, negated: > 0
/// inside), for collision tests.
pub fn depths(mesh: &Mesh, points: &[Vec3]) -> Vec<f32> {
    points
        .par_iter()
        .map(|&p| signed_distance(mesh, p).map_or(f32::NEG_INFINITY, |d| -d))
        .collect()
}

/// The generalized winding number of `mesh` at `p` (Jacobson et al. 2013: the solid
/// angles of its triangles over 4π, Van Oosterom and Strackee's formula): 1 inside a
/// closed, outward-wound mesh, 0 outside, ½ on its surface, and the sum of the parts'
/// where closed parts overlap (a point on one part's surface inside another: 1½).
pub fn winding_number(mesh: &Mesh, p: Vec3) -> f64 {
    let p = p.as_dvec3();
    let mut total = 0.0;
    for tri in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|k| mesh.positions[tri[k] as usize].as_dvec3() - p);
        let (la, lb, lc) = (a.length(), b.length(), c.length());
        let det = a.dot(b.cross(c));
        let div = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
        if det.is_finite() && div.is_finite() {
            total += 2.0 * det.atan2(div);
        }
    }
    total / (4.0 * std::f64::consts::PI)
}

/// Which triangles of `mesh` are buried inside another of its parts (mirror of
/// `pelage_strands::body_triangles`, by another road): every corner's winding number
/// over the whole mesh at least 1 (its own closed part gives about ½ on its surface,
/// another closed part holding it 1 more).
pub fn buried_triangles(mesh: &Mesh) -> Vec<bool> {
    let inside: Vec<bool> = mesh
        .positions
        .par_iter()
        .map(|&p| p.is_finite() && winding_number(mesh, p) >= 1.0)
        .collect();
    mesh.indices
        .chunks_exact(3)
        .map(|tri| tri.iter().all(|&i| inside[i as usize]))
        .collect()
}

/// `mesh` without its [`buried_triangles`]: the surface `BodySdf::of_body` builds from.
pub fn body_surface(mesh: &Mesh) -> Mesh {
    let buried = buried_triangles(mesh);
    let mut out = mesh.clone();
    out.indices = mesh
        .indices
        .chunks_exact(3)
        .zip(&buried)
        .filter(|(_, b)| !**b)
        .flat_map(|(tri, _)| tri.iter().copied())
        .collect();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_icosahedron_is_negative_inside_and_positive_outside() {
        // Circumradius 1: the inradius is 0.7947, a face's centre that far from the centre.
        let ico = Mesh::icosphere(1.0, 0).unwrap();
        let d = signed_distance(&ico, Vec3::ZERO).unwrap();
        assert!((d + 0.794_654_5).abs() < 1e-5, "{d}");
        let d = signed_distance(&ico, Vec3::new(0.0, 3.0, 0.0)).unwrap();
        assert!((2.0..2.21).contains(&d), "{d}");
        assert!((winding_number(&ico, Vec3::ZERO) - 1.0).abs() < 1e-9);
        assert!(winding_number(&ico, Vec3::new(0.0, 3.0, 0.0)).abs() < 1e-9);
        let mut broken = ico.clone();
        broken.positions.iter_mut().for_each(|p| *p = Vec3::NAN);
        assert_eq!(signed_distance(&broken, Vec3::ZERO), None);
    }
}
