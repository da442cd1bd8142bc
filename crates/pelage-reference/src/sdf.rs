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
    for tri in mesh.indices.chunks_exact(3) {
        let Some((d, inside, _)) = nearest_on(mesh, tri, p) else {
            continue;
        };
        if best.is_some_and(|(bd, _)| d > bd) {
            continue;
        }
        best = Some(match best {
            Some((bd, was_inside)) if d == bd => (d, was_inside && inside),
            _ => (d, inside),
        });
    }
    let (d, inside) = best?;
    Some(if inside { -d as f32 } else { d as f32 })
}

/// The point of triangle `tri` (three indices into `mesh`) nearest `p`: its distance,
/// whether `p` is behind the mesh's normal there (the vertex normals interpolated), and
/// its barycentrics. `None` when a corner is not finite.
fn nearest_on(mesh: &Mesh, tri: &[u32], p: Vec3) -> Option<(f64, bool, (f64, f64, f64))> {
    let [a, b, c] = [0, 1, 2].map(|k| mesh.positions[tri[k] as usize]);
    if !(a.is_finite() && b.is_finite() && c.is_finite()) {
        return None;
    }
    let (u, v, w) = closest_bary(p, a, b, c);
    let q = a.as_dvec3() * u + b.as_dvec3() * v + c.as_dvec3() * w;
    let pd = p.as_dvec3();
    let [na, nb, nc] = [0, 1, 2].map(|k| mesh.normals[tri[k] as usize].as_dvec3());
    let inside = (pd - q).dot(na * u + nb * v + nc * w) < 0.0;
    Some((pd.distance(q), inside, (u, v, w)))
}

/// The exact field of `mesh` on every node of `grid` (in [`SdfGrid::index`] order);
/// `far` where no triangle is finite. Brute force: `O(nodes · triangles)`.
pub fn exact_field(mesh: &Mesh, grid: &SdfGrid, far: f32) -> Vec<f32> {
    (0..grid.nodes())
        .into_par_iter()
        .map(|i| signed_distance(mesh, grid.node(grid.node_of(i))).unwrap_or(far))
        .collect()
}

/// The parts of `mesh`: each triangle's part, numbered from 0 (triangles sharing a vertex
/// index are in one part), by repeated relabelling until no label changes (the GPU's
/// preparation, `pelage_strands::burial`, joins vertices with a union-find instead).
/// `None` when an index is past the vertices.
pub fn triangle_parts(mesh: &Mesh) -> Option<Vec<usize>> {
    let vertices = mesh.positions.len();
    if mesh.indices.iter().any(|&i| i as usize >= vertices) {
        return None;
    }
    // Every vertex starts as its own label; each triangle takes its corners' least.
    let mut label: Vec<usize> = (0..vertices).collect();
    loop {
        let mut changed = false;
        for tri in mesh.indices.chunks_exact(3) {
            let least = tri.iter().map(|&i| label[i as usize]).min().unwrap_or(0);
            for &i in tri {
                if label[i as usize] != least {
                    label[i as usize] = least;
                    changed = true;
                }
            }
        }
        if !changed {
            break;
        }
    }
    let mut number = std::collections::BTreeMap::new();
    Some(
        mesh.indices
            .chunks_exact(3)
            .map(|tri| {
                let next = number.len();
                *number.entry(label[tri[0] as usize]).or_insert(next)
            })
            .collect(),
    )
}

/// Each part of `mesh` (`parts`: each triangle's, [`triangle_parts`]) as a mesh of its
/// own: the same vertices, that part's triangles.
fn part_meshes(mesh: &Mesh, parts: &[usize]) -> Vec<Mesh> {
    let count = parts.iter().max().map_or(0, |&p| p + 1);
    (0..count)
        .map(|k| {
            let mut m = mesh.clone();
            m.indices = mesh
                .indices
                .chunks_exact(3)
                .zip(parts)
                .filter(|(_, p)| **p == k)
                .flat_map(|(tri, _)| tri.iter().copied())
                .collect();
            m
        })
        .collect()
}

/// Mirror of `pelage_strands::burial`: how deep each vertex lies inside another part of
/// `mesh`, the most over the other parts of the distance to that part's nearest triangle
/// signed by its winding number (inside at ½ or more), never below minus the mesh's
/// longest edge (`pelage_strands::burial`'s floor; it measures only parts whose box
/// grown by that edge holds the vertex, which changes nothing above the floor). Every
/// part is measured here, in f64.
pub fn burial(mesh: &Mesh) -> Vec<f32> {
    let longest = mesh
        .indices
        .chunks_exact(3)
        .filter(|tri| tri.iter().all(|&i| (i as usize) < mesh.positions.len()))
        .flat_map(|tri| {
            let [a, b, c] = [0, 1, 2].map(|k| mesh.positions[tri[k] as usize]);
            [a.distance(b), b.distance(c), c.distance(a)]
        })
        .filter(|d| d.is_finite())
        .fold(0.0f32, f32::max);
    let floor = -longest.max(f32::MIN_POSITIVE);
    let Some(parts) = triangle_parts(mesh) else {
        return vec![floor; mesh.positions.len()];
    };
    let meshes = part_meshes(mesh, &parts);
    let count = meshes.len();
    let mut vertex_part = vec![usize::MAX; mesh.positions.len()];
    for (tri, &k) in mesh.indices.chunks_exact(3).zip(&parts) {
        for &i in tri {
            vertex_part[i as usize] = k;
        }
    }
    (0..mesh.positions.len())
        .into_par_iter()
        .map(|v| {
            let p = mesh.positions[v];
            if vertex_part[v] == usize::MAX || !p.is_finite() {
                return floor;
            }
            (0..count)
                .filter(|&k| k != vertex_part[v])
                .filter_map(|k| {
                    let d = f64::from(signed_distance(&meshes[k], p)?.abs());
                    let inside = winding_number(&meshes[k], p) >= 0.5;
                    Some((if inside { d } else { -d }) as f32)
                })
                .fold(floor, f32::max)
        })
        .collect()
}

/// Mirror of the GPU field's sign and distance near the surface (`BodySdf::of_body`,
/// the splat and finish of `strands/sdf.wgsl`): over every triangle of `mesh`, the
/// nearest point and the side of the normal there; a nearest point whose corners'
/// `burial` (one per vertex, [`burial`]) interpolates to a depth above 0 says "inside"
/// where the point is nearer than that depth (the node is in the other part), and else,
/// where it says "outside", gives only a distance. Inside at the distance of the nearest
/// vote that decides a side when it says inside (an exact tie between sides: outside);
/// else outside at the nearest of every vote. `None` when no triangle is finite.
pub fn union_signed_distance(mesh: &Mesh, burial: &[f32], p: Vec3) -> Option<f32> {
    // (distance, inside) of the nearest deciding vote; the nearest distance of all.
    let mut deciding: Option<(f64, bool)> = None;
    let mut any = f64::INFINITY;
    for tri in mesh.indices.chunks_exact(3) {
        let Some((d, side, (u, v, w))) = nearest_on(mesh, tri, p) else {
            continue;
        };
        let [ba, bb, bc] = [0, 1, 2].map(|k| f64::from(burial[tri[k] as usize]));
        let depth = ba * u + bb * v + bc * w;
        // Nearer a buried point than it is deep: inside that other part.
        let inside = side || depth > d;
        any = any.min(d);
        if !inside && depth > 0.0 {
            continue;
        }
        deciding = Some(match deciding {
            Some((bd, was_inside)) if d == bd => (d, was_inside && inside),
            Some((bd, was_inside)) if d > bd => (bd, was_inside),
            _ => (d, inside),
        });
    }
    if !any.is_finite() {
        return None;
    }
    Some(match deciding {
        Some((d, true)) => -d as f32,
        _ => any as f32,
    })
}

/// [`union_signed_distance`] on every node of `grid` (in [`SdfGrid::index`] order), the
/// burial computed here ([`burial`]); `far` where no triangle is finite.
pub fn union_field(mesh: &Mesh, grid: &SdfGrid, far: f32) -> Vec<f32> {
    let burial = burial(mesh);
    (0..grid.nodes())
        .into_par_iter()
        .map(|i| union_signed_distance(mesh, &burial, grid.node(grid.node_of(i))).unwrap_or(far))
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

/// How deep each of `points` is inside `mesh`, for collision tests: the signed distance
/// to each part of the mesh ([`triangle_parts`]; the nearest triangle's distance, signed
/// by the side of its normal, [`signed_distance`]), the least over the parts, negated
/// (> 0 inside). For one closed part that is its exact signed distance; for overlapping
/// parts, inside wherever a part holds the point, at least as deep as the part that holds
/// it deepest (a part's surface buried in another decides nothing for a point inside
/// that other part). `-inf` where no triangle is finite.
pub fn depths(mesh: &Mesh, points: &[Vec3]) -> Vec<f32> {
    let parts = triangle_parts(mesh).unwrap_or_else(|| vec![0; mesh.indices.len() / 3]);
    let meshes = part_meshes(mesh, &parts);
    // Each part's bounding ball (centre, radius): no point of the part is nearer `p` than
    // `|p - centre| - radius`, so a part whose bound is no less than the least signed
    // distance so far cannot lower it (the bound is exact pruning, not an estimate).
    let balls: Vec<(Vec3, f32)> = meshes
        .iter()
        .map(|m| {
            let used: Vec<Vec3> = m.indices.iter().map(|&i| m.positions[i as usize]).collect();
            let (lo, hi) = used.iter().fold(
                (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
                |(lo, hi), &q| (lo.min(q), hi.max(q)),
            );
            let centre = (lo + hi) * 0.5;
            let radius = used
                .iter()
                .map(|q| q.distance(centre))
                .fold(0.0f32, f32::max);
            (centre, radius)
        })
        .collect();
    points
        .par_iter()
        .map(|&p| {
            // Nearest ball first, so that the far parts are pruned.
            let mut order: Vec<(f32, usize)> = balls
                .iter()
                .enumerate()
                .map(|(k, (c, r))| (p.distance(*c) - r, k))
                .collect();
            order.sort_by(|a, b| a.0.total_cmp(&b.0));
            let mut least = f32::INFINITY;
            for (bound, k) in order {
                // A non-finite ball (a NaN corner) prunes nothing.
                if bound.is_finite() && bound >= least {
                    break;
                }
                if let Some(d) = signed_distance(&meshes[k], p) {
                    least = least.min(d);
                }
            }
            least
        })
        .map(|d| if d.is_finite() { -d } else { f32::NEG_INFINITY })
        .collect()
}

/// [`winding_number`] at each of `points` (in parallel), for tests that judge a field's
/// side against it.
pub fn winding_numbers(mesh: &Mesh, points: &[Vec3]) -> Vec<f64> {
    points
        .par_iter()
        .map(|&p| winding_number(mesh, p))
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

/// `mesh` without its [`buried_triangles`] (`pelage_strands::body_triangles`: the surface the
/// skin's lattice takes each point's nearest triangle from; the field splats every triangle).
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

    /// Two unit spheres overlapping unwelded, their centres 1.2 apart: the +x pole of the
    /// first is 0.8 deep in the second, and just beyond it, inside the second only, the
    /// nearest triangle (the first's surface, buried) says "outside"; the union's rule
    /// says "inside", and outside both, in the valley above the junction, "outside".
    #[test]
    fn overlapping_parts_are_one_body() {
        let mut mesh = Mesh::icosphere(1.0, 3).unwrap();
        let mut other = mesh.clone();
        other
            .positions
            .iter_mut()
            .for_each(|p| *p += Vec3::new(1.2, 0.0, 0.0));
        mesh.append(&other).unwrap();
        let parts = triangle_parts(&mesh).unwrap();
        assert_eq!(parts.iter().max(), Some(&1));
        let burial = burial(&mesh);
        let pole = |p: Vec3| {
            (0..mesh.positions.len())
                .min_by(|&a, &b| {
                    mesh.positions[a]
                        .distance(p)
                        .total_cmp(&mesh.positions[b].distance(p))
                })
                .unwrap()
        };
        let deep = burial[pole(Vec3::X)];
        assert!((deep - 0.8).abs() < 0.01, "{deep}");
        assert!(burial[pole(-Vec3::X)] < 0.0);
        let near_pole = Vec3::new(1.05, 0.0, 0.0);
        assert!(signed_distance(&mesh, near_pole).unwrap() > 0.0);
        let d = union_signed_distance(&mesh, &burial, near_pole).unwrap();
        assert!(d < 0.0, "{d}");
        let valley = Vec3::new(0.6, 0.9, 0.0);
        assert!(winding_number(&mesh, valley) < 0.5);
        assert!(union_signed_distance(&mesh, &burial, valley).unwrap() > 0.0);
        // And the depths of collision tests count a point inside either part.
        assert!(depths(&mesh, &[near_pole])[0] > 0.0);
    }
}
