//! Triangle meshes: the surface fur grows from.
//!
//! A [`Mesh`] is an indexed triangle list with one unit normal per position.
//! Front faces wind counter-clockwise when seen from outside, so
//! `(b - a) × (c - a)` points the same way as the vertex normals.
//! [`Mesh::validate`] checks all of that before a mesh is handed to the GPU;
//! the procedural builders ([`Mesh::icosphere`], [`Mesh::torus`],
//! [`Mesh::plane`], [`Mesh::creature`]) always produce valid meshes.

use std::collections::HashMap;

use glam::{Affine3A, DVec3, Mat3A, Vec2, Vec3};
use serde::{Deserialize, Serialize};

/// Highest subdivision level [`Mesh::icosphere`] accepts (20 · 4⁸ ≈ 1.3 million triangles).
pub const MAX_ICOSPHERE_SUBDIVISIONS: u32 = 8;

/// Highest segment / subdivision count per direction that [`Mesh::torus`] and
/// [`Mesh::plane`] accept (about a million vertices at most).
pub const MAX_GRID_SEGMENTS: u32 = 1024;

/// Relative area below which a triangle counts as degenerate: a triangle is
/// degenerate when its area is below this factor times the squared diagonal
/// of the mesh's bounding box.
pub const DEGENERATE_AREA_FACTOR: f64 = 1e-12;

/// Normals shorter than this are treated as zero length by [`Mesh::validate`].
const MIN_NORMAL_LENGTH: f32 = 1e-6;

/// An indexed triangle mesh: triangle list, counter-clockwise front faces,
/// one unit-length normal per position, and optionally one texture coordinate per
/// position.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Unit vertex normals, one per position, pointing out of the front faces.
    pub normals: Vec<Vec3>,
    /// Triangle list: three indices into `positions` per triangle, CCW = front.
    pub indices: Vec<u32>,
    /// Texture coordinates, one per position, or none at all (empty). `(0, 0)` is the
    /// bottom-left corner of a texture and `(1, 1)` its top-right, as in OBJ files;
    /// outside [0, 1] a texture repeats.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub uvs: Vec<Vec2>,
}

/// What [`Mesh::validate`] found in a mesh that is usable.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshReport {
    /// Number of triangles (`indices.len() / 3`), degenerate ones included.
    pub triangles: usize,
    /// Indices of triangles with zero or near-zero area (below
    /// [`DEGENERATE_AREA_FACTOR`] × bounding-box diagonal²). Not fatal:
    /// callers skip them (root sampling gives them no weight).
    pub degenerate_triangles: Vec<u32>,
    /// Sum of all triangle areas.
    pub total_area: f32,
    /// Component-wise minimum of all positions.
    pub bounds_min: Vec3,
    /// Component-wise maximum of all positions.
    pub bounds_max: Vec3,
}

/// Why a mesh is unusable, or why a procedural mesh could not be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MeshError {
    /// The mesh has no triangles at all.
    #[error("mesh has no triangles (indices is empty); give it at least one triangle")]
    NoTriangles,
    /// The index list does not describe whole triangles.
    #[error(
        "mesh has {count} indices, which is not a multiple of 3; a triangle list needs three indices per triangle"
    )]
    IndexCountNotMultipleOfThree {
        /// Length of `indices`.
        count: usize,
    },
    /// A triangle refers to a vertex that does not exist.
    #[error(
        "triangle {triangle} (corner {corner}) uses vertex index {index}, but the mesh has only {vertex_count} positions; fix the index buffer"
    )]
    IndexOutOfRange {
        /// Triangle number (index into `indices` divided by 3).
        triangle: usize,
        /// Corner of the triangle, 0..3.
        corner: usize,
        /// The offending vertex index.
        index: u32,
        /// Number of positions in the mesh.
        vertex_count: usize,
    },
    /// Positions and normals differ in count.
    #[error(
        "mesh has {positions} positions but {normals} normals; there must be exactly one normal per position (call recompute_normals to rebuild them)"
    )]
    NormalCountMismatch {
        /// Number of positions.
        positions: usize,
        /// Number of normals.
        normals: usize,
    },
    /// Texture coordinates are given, but not one per position.
    #[error(
        "mesh has {positions} positions but {uvs} texture coordinates; give one per position or none"
    )]
    UvCountMismatch {
        /// Number of positions.
        positions: usize,
        /// Number of texture coordinates.
        uvs: usize,
    },
    /// A texture coordinate is NaN or infinite.
    #[error(
        "texture coordinate {vertex} is not finite ({value}); every UV must be a finite number"
    )]
    NonFiniteUv {
        /// Vertex index.
        vertex: usize,
        /// The value found.
        value: Vec2,
    },
    /// A position is NaN or infinite.
    #[error("position {vertex} is not finite ({value}); every coordinate must be a finite number")]
    NonFinitePosition {
        /// Vertex index.
        vertex: usize,
        /// The value found.
        value: Vec3,
    },
    /// A coordinate is larger than [`crate::MAX_EXTENT`] in magnitude.
    #[error(
        "position {vertex} is {value}: coordinates must be at most {:e} in magnitude (larger ones \
         overflow 32-bit floats where distances are squared); scale the mesh down",
        crate::MAX_EXTENT
    )]
    PositionOutOfRange {
        /// Vertex index.
        vertex: usize,
        /// The value found.
        value: Vec3,
    },
    /// A normal is NaN or infinite.
    #[error(
        "normal {vertex} is not finite ({value}); fix it or call recompute_normals to rebuild the normals"
    )]
    NonFiniteNormal {
        /// Vertex index.
        vertex: usize,
        /// The value found.
        value: Vec3,
    },
    /// A normal has (near) zero length, so it has no direction.
    #[error(
        "normal {vertex} has zero length ({value}); normals must be unit length (call recompute_normals to rebuild them)"
    )]
    ZeroLengthNormal {
        /// Vertex index.
        vertex: usize,
        /// The value found.
        value: Vec3,
    },
    /// Every triangle has (near) zero area: there is no surface to grow on.
    #[error(
        "{} zero or near-zero area; the mesh has no surface (check its scale and that its vertices are not all collinear)",
        if *triangles == 1 { "the mesh's only triangle has".to_string() } else { format!("all {triangles} triangles of the mesh have") }
    )]
    AllTrianglesDegenerate {
        /// Number of triangles.
        triangles: usize,
    },
    /// A builder parameter is NaN, infinite, or out of its allowed range.
    #[error("{builder}: {name} = {value} is invalid; it must be {requirement}")]
    InvalidParameter {
        /// The builder that refused the parameter (e.g. `"Mesh::torus"`).
        builder: &'static str,
        /// Name of the parameter.
        name: &'static str,
        /// The value given.
        value: f32,
        /// What the parameter must be.
        requirement: &'static str,
    },
    /// A segment or subdivision count is outside its allowed range.
    #[error("{builder}: {name} = {value} is out of range; it must be between {min} and {max}")]
    CountOutOfRange {
        /// The builder that refused the parameter.
        builder: &'static str,
        /// Name of the parameter.
        name: &'static str,
        /// The value given.
        value: u32,
        /// Smallest allowed value.
        min: u32,
        /// Largest allowed value.
        max: u32,
    },
    /// The mesh would have more vertices than a `u32` index can address.
    #[error(
        "mesh would have {vertices} vertices, more than a u32 index can address ({max}); split it into several meshes"
    )]
    TooManyVertices {
        /// Vertex count that was needed.
        vertices: u64,
        /// Largest vertex count allowed.
        max: u64,
    },
}

impl Mesh {
    /// Number of whole triangles (`indices.len() / 3`).
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Checks everything the GPU stages rely on and measures the mesh.
    ///
    /// Errors (checked in this order): no triangles, index count not a
    /// multiple of 3, positions/normals count mismatch, UVs given but not one per
    /// position, a NaN/infinite UV, a NaN/infinite
    /// position, a NaN/infinite or zero-length normal, an index out of range,
    /// and every triangle degenerate. Degenerate triangles among good ones
    /// are reported in [`MeshReport::degenerate_triangles`], not refused.
    /// Normals only need a non-zero length here; the builders and loaders of
    /// this crate produce unit normals.
    pub fn validate(&self) -> Result<MeshReport, MeshError> {
        if self.indices.is_empty() {
            return Err(MeshError::NoTriangles);
        }
        if !self.indices.len().is_multiple_of(3) {
            return Err(MeshError::IndexCountNotMultipleOfThree {
                count: self.indices.len(),
            });
        }
        if self.positions.len() != self.normals.len() {
            return Err(MeshError::NormalCountMismatch {
                positions: self.positions.len(),
                normals: self.normals.len(),
            });
        }
        if !self.uvs.is_empty() && self.uvs.len() != self.positions.len() {
            return Err(MeshError::UvCountMismatch {
                positions: self.positions.len(),
                uvs: self.uvs.len(),
            });
        }
        if let Some((vertex, &value)) = self.uvs.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(MeshError::NonFiniteUv { vertex, value });
        }
        for (vertex, &value) in self.positions.iter().enumerate() {
            if !value.is_finite() {
                return Err(MeshError::NonFinitePosition { vertex, value });
            }
            if value.abs().max_element() > crate::MAX_EXTENT {
                return Err(MeshError::PositionOutOfRange { vertex, value });
            }
        }
        for (vertex, &value) in self.normals.iter().enumerate() {
            if !value.is_finite() {
                return Err(MeshError::NonFiniteNormal { vertex, value });
            }
            if value.length() < MIN_NORMAL_LENGTH {
                return Err(MeshError::ZeroLengthNormal { vertex, value });
            }
        }
        let vertex_count = self.positions.len();
        for (triangle, tri) in self.indices.chunks_exact(3).enumerate() {
            for (corner, &index) in tri.iter().enumerate() {
                let in_range = usize::try_from(index).is_ok_and(|i| i < vertex_count);
                if !in_range {
                    return Err(MeshError::IndexOutOfRange {
                        triangle,
                        corner,
                        index,
                        vertex_count,
                    });
                }
            }
        }

        let (bounds_min, bounds_max) = self.bounds();
        let diagonal = (bounds_max.as_dvec3() - bounds_min.as_dvec3()).length_squared();
        let threshold = DEGENERATE_AREA_FACTOR * diagonal;
        let mut degenerate_triangles = Vec::new();
        let mut total_area = 0.0f64;
        let mut triangles = 0usize;
        for (triangle, tri) in self.indices.chunks_exact(3).enumerate() {
            triangles += 1;
            let area = self.triangle_area_f64(tri).unwrap_or(0.0);
            // `<=` so that a zero-size bounding box makes every triangle degenerate.
            if area.is_nan() || area <= threshold {
                degenerate_triangles.push(u32::try_from(triangle).unwrap_or(u32::MAX));
            } else {
                total_area += area;
            }
        }
        if degenerate_triangles.len() == triangles {
            return Err(MeshError::AllTrianglesDegenerate { triangles });
        }
        Ok(MeshReport {
            triangles,
            degenerate_triangles,
            total_area: total_area as f32,
            bounds_min,
            bounds_max,
        })
    }

    /// Area of one triangle given its three indices, computed in `f64` so that
    /// the degeneracy test is not dominated by `f32` rounding. `None` when an
    /// index is out of range.
    fn triangle_area_f64(&self, tri: &[u32]) -> Option<f64> {
        let corner = |k: usize| -> Option<DVec3> {
            let index = usize::try_from(*tri.get(k)?).ok()?;
            self.positions.get(index).map(|p| p.as_dvec3())
        };
        let (a, b, c) = (corner(0)?, corner(1)?, corner(2)?);
        Some(0.5 * (b - a).cross(c - a).length())
    }

    /// Area of every triangle, in triangle order (`indices.len() / 3`
    /// entries; a trailing partial triangle is ignored). A triangle with an
    /// out-of-range index gets area 0.
    pub fn triangle_areas(&self) -> Vec<f32> {
        self.indices
            .chunks_exact(3)
            .map(|tri| self.triangle_area_f64(tri).unwrap_or(0.0) as f32)
            .collect()
    }

    /// Component-wise minimum and maximum of all positions (referenced or
    /// not). `(Vec3::ZERO, Vec3::ZERO)` for a mesh without positions; NaN
    /// coordinates are ignored.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut iter = self.positions.iter();
        let Some(&first) = iter.next() else {
            return (Vec3::ZERO, Vec3::ZERO);
        };
        iter.fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p)))
    }

    /// Replaces the normals by area-weighted vertex normals: each triangle
    /// adds `(b - a) × (c - a)` (twice its area times its unit normal) to its
    /// three corners, then every sum is normalised.
    ///
    /// Fallback for vertices whose sum is zero (unreferenced, or used only by
    /// degenerate or mutually cancelling triangles): the direction from the
    /// centre of the mesh's bounding box to the vertex, and `+Y` if the
    /// vertex sits at that centre. Triangles with out-of-range indices are
    /// skipped. Afterwards there is exactly one unit normal per position
    /// (unless positions are NaN or infinite).
    pub fn recompute_normals(&mut self) {
        let mut sums = vec![DVec3::ZERO; self.positions.len()];
        for tri in self.indices.chunks_exact(3) {
            let corner = |k: usize| -> Option<(usize, DVec3)> {
                let index = usize::try_from(*tri.get(k)?).ok()?;
                self.positions.get(index).map(|p| (index, p.as_dvec3()))
            };
            let (Some((ia, a)), Some((ib, b)), Some((ic, c))) = (corner(0), corner(1), corner(2))
            else {
                continue;
            };
            let weighted = (b - a).cross(c - a);
            if !weighted.is_finite() {
                continue;
            }
            for index in [ia, ib, ic] {
                if let Some(sum) = sums.get_mut(index) {
                    *sum += weighted;
                }
            }
        }
        let (lo, hi) = self.bounds();
        let centre = (lo + hi) * 0.5;
        self.normals = sums
            .iter()
            .zip(&self.positions)
            .map(|(sum, &p)| {
                sum.try_normalize()
                    .map(|n| n.as_vec3())
                    .or_else(|| (p - centre).try_normalize())
                    .unwrap_or(Vec3::Y)
            })
            .collect();
    }

    /// Appends `other` to this mesh: its vertices go after this mesh's and
    /// its indices are offset accordingly. Overlapping parts are fine. The result
    /// has texture coordinates when both parts have them (or this mesh is empty);
    /// otherwise it has none.
    ///
    /// Errors with [`MeshError::TooManyVertices`] (and leaves `self`
    /// unchanged) when the result would need indices beyond `u32`.
    pub fn append(&mut self, other: &Mesh) -> Result<(), MeshError> {
        let total = (self.positions.len() as u64).saturating_add(other.positions.len() as u64);
        let max = u64::from(u32::MAX);
        let offset = u32::try_from(self.positions.len())
            .ok()
            .filter(|_| total <= max)
            .ok_or(MeshError::TooManyVertices {
                vertices: total,
                max,
            })?;
        if self.positions.is_empty() {
            self.uvs = other.uvs.clone();
        } else if self.has_uvs() && other.has_uvs() {
            self.uvs.extend_from_slice(&other.uvs);
        } else {
            self.uvs.clear();
        }
        self.positions.extend_from_slice(&other.positions);
        self.normals.extend_from_slice(&other.normals);
        // Cannot overflow: every valid index is below `total <= u32::MAX`;
        // out-of-range indices of `other` saturate and stay out of range.
        self.indices
            .extend(other.indices.iter().map(|&i| i.saturating_add(offset)));
        Ok(())
    }

    /// Returns a copy with positions transformed by `affine` and normals by
    /// its inverse transpose (then renormalised). A transform that mirrors
    /// (negative determinant) also flips the winding of every triangle so
    /// that front faces stay counter-clockwise. A singular transform gives
    /// non-finite or zero normals, which [`Mesh::validate`] reports.
    pub fn transformed(&self, affine: Affine3A) -> Mesh {
        let linear: Mat3A = affine.matrix3;
        let normal_matrix = linear.inverse().transpose();
        let positions = self
            .positions
            .iter()
            .map(|&p| affine.transform_point3(p))
            .collect();
        let normals = self
            .normals
            .iter()
            .map(|&n| (normal_matrix * n).normalize_or_zero())
            .collect();
        let mut indices = self.indices.clone();
        if linear.determinant() < 0.0 {
            for tri in indices.chunks_exact_mut(3) {
                tri.swap(1, 2);
            }
        }
        Mesh {
            positions,
            normals,
            indices,
            uvs: self.uvs.clone(),
        }
    }

    /// Whether the mesh has texture coordinates (one per position).
    pub fn has_uvs(&self) -> bool {
        !self.uvs.is_empty() && self.uvs.len() == self.positions.len()
    }

    /// The texture coordinate at barycentrics `bary` (of the triangle's first, second
    /// and third corner) of triangle `tri`; `None` without UVs or for a triangle or
    /// index out of range.
    pub fn uv_at(&self, tri: usize, bary: [f32; 3]) -> Option<Vec2> {
        if !self.has_uvs() {
            return None;
        }
        let corners = self.indices.get(tri * 3..tri * 3 + 3)?;
        let mut uv = Vec2::ZERO;
        for (&index, w) in corners.iter().zip(bary) {
            uv += *self.uvs.get(index as usize)? * w;
        }
        Some(uv)
    }

    /// A sphere of `radius` centred at the origin, made from an icosahedron
    /// whose triangles are split into four `subdivisions` times, with the new
    /// edge midpoints projected onto the sphere. Shared vertices are not
    /// duplicated: level `n` has `10·4ⁿ + 2` vertices and `20·4ⁿ` triangles
    /// (level 0: 12 and 20, level 1: 42 and 80). Normals are exact sphere
    /// normals.
    ///
    /// Errors: `radius` not finite or not > 0, `subdivisions` above
    /// [`MAX_ICOSPHERE_SUBDIVISIONS`].
    pub fn icosphere(radius: f32, subdivisions: u32) -> Result<Mesh, MeshError> {
        const BUILDER: &str = "Mesh::icosphere";
        check_positive(BUILDER, "radius", radius)?;
        check_count(
            BUILDER,
            "subdivisions",
            subdivisions,
            0,
            MAX_ICOSPHERE_SUBDIVISIONS,
        )?;
        let (mut directions, mut indices) = icosahedron();
        for _ in 0..subdivisions {
            indices = subdivide(&mut directions, &indices);
        }
        Ok(Mesh {
            positions: directions.iter().map(|&d| d * radius).collect(),
            normals: directions,
            indices,
            uvs: Vec::new(),
        })
    }

    /// A torus around the Y axis, centred at the origin: the tube of radius
    /// `minor_radius` follows a circle of radius `major_radius` in the XZ
    /// plane. `major_segments` × `minor_segments` vertices (the seams are
    /// shared, not duplicated), twice as many triangles, outward normals.
    ///
    /// Errors: radii not finite or not > 0, `minor_radius >= major_radius`
    /// (the tube would cross itself), segment counts outside
    /// 3..=[`MAX_GRID_SEGMENTS`].
    pub fn torus(
        major_radius: f32,
        minor_radius: f32,
        major_segments: u32,
        minor_segments: u32,
    ) -> Result<Mesh, MeshError> {
        const BUILDER: &str = "Mesh::torus";
        check_positive(BUILDER, "major_radius", major_radius)?;
        check_positive(BUILDER, "minor_radius", minor_radius)?;
        if minor_radius >= major_radius {
            return Err(MeshError::InvalidParameter {
                builder: BUILDER,
                name: "minor_radius",
                value: minor_radius,
                requirement: "smaller than major_radius (otherwise the tube crosses itself)",
            });
        }
        check_count(
            BUILDER,
            "major_segments",
            major_segments,
            3,
            MAX_GRID_SEGMENTS,
        )?;
        check_count(
            BUILDER,
            "minor_segments",
            minor_segments,
            3,
            MAX_GRID_SEGMENTS,
        )?;
        // Both counts are <= 1024, so every product below fits in u32.
        let vertex_count = major_segments * minor_segments;
        let mut positions = Vec::with_capacity(vertex_count as usize);
        let mut normals = Vec::with_capacity(vertex_count as usize);
        for i in 0..major_segments {
            let u = std::f32::consts::TAU * i as f32 / major_segments as f32;
            let (sin_u, cos_u) = u.sin_cos();
            let centre = Vec3::new(major_radius * cos_u, 0.0, major_radius * sin_u);
            for j in 0..minor_segments {
                let v = std::f32::consts::TAU * j as f32 / minor_segments as f32;
                let (sin_v, cos_v) = v.sin_cos();
                let normal = Vec3::new(cos_v * cos_u, sin_v, cos_v * sin_u).normalize();
                positions.push(centre + minor_radius * normal);
                normals.push(normal);
            }
        }
        let vertex = |i: u32, j: u32| (i % major_segments) * minor_segments + (j % minor_segments);
        let mut indices = Vec::with_capacity(vertex_count as usize * 6);
        for i in 0..major_segments {
            for j in 0..minor_segments {
                let a = vertex(i, j);
                let b = vertex(i + 1, j);
                let c = vertex(i + 1, j + 1);
                let d = vertex(i, j + 1);
                // (d - a) × (b - a) points out of the tube.
                indices.extend_from_slice(&[a, d, c, a, c, b]);
            }
        }
        Ok(Mesh {
            positions,
            normals,
            indices,
            uvs: Vec::new(),
        })
    }

    /// A flat rectangle in the XZ plane at `y = 0`, centred at the origin,
    /// `size_x` by `size_z`, split into `subdivisions_x` × `subdivisions_z`
    /// quads (two triangles each), facing `+Y`. Its UVs run from `(0, 0)` at
    /// `(-size_x/2, -size_z/2)` to `(1, 1)` at `(size_x/2, size_z/2)`.
    ///
    /// Errors: sizes not finite or not > 0, subdivision counts outside
    /// 1..=[`MAX_GRID_SEGMENTS`].
    pub fn plane(
        size_x: f32,
        size_z: f32,
        subdivisions_x: u32,
        subdivisions_z: u32,
    ) -> Result<Mesh, MeshError> {
        const BUILDER: &str = "Mesh::plane";
        check_positive(BUILDER, "size_x", size_x)?;
        check_positive(BUILDER, "size_z", size_z)?;
        check_count(
            BUILDER,
            "subdivisions_x",
            subdivisions_x,
            1,
            MAX_GRID_SEGMENTS,
        )?;
        check_count(
            BUILDER,
            "subdivisions_z",
            subdivisions_z,
            1,
            MAX_GRID_SEGMENTS,
        )?;
        // Both counts are <= 1024, so every product below fits in u32.
        let columns = subdivisions_x + 1;
        let rows = subdivisions_z + 1;
        let mut positions = Vec::with_capacity((columns * rows) as usize);
        let mut uvs = Vec::with_capacity((columns * rows) as usize);
        for k in 0..rows {
            let v = k as f32 / subdivisions_z as f32;
            for i in 0..columns {
                let u = i as f32 / subdivisions_x as f32;
                positions.push(Vec3::new(size_x * (u - 0.5), 0.0, size_z * (v - 0.5)));
                uvs.push(Vec2::new(u, v));
            }
        }
        let normals = vec![Vec3::Y; positions.len()];
        let mut indices = Vec::with_capacity((subdivisions_x * subdivisions_z * 6) as usize);
        for k in 0..subdivisions_z {
            for i in 0..subdivisions_x {
                let a = k * columns + i;
                let b = a + 1;
                let d = a + columns;
                let c = d + 1;
                // (d - a) × (c - a) points up (+Y).
                indices.extend_from_slice(&[a, d, c, a, c, b]);
            }
        }
        Ok(Mesh {
            positions,
            normals,
            indices,
            uvs,
        })
    }

    /// The built-in default scene: a small four-legged furry creature (body,
    /// head, snout, two ears, four legs, a tail), y up, facing `+Z`, centred
    /// on its bounding box at the origin and within about `[-1.2, 1.2]³`.
    /// Made of scaled and rotated icospheres appended into one mesh
    /// (overlapping, not welded); 2720 triangles, none degenerate.
    ///
    /// Its UVs are its side view, the same on both flanks: `u` runs from the tail
    /// (`-Z`, 0) to the nose (`+Z`, 1) and `v` from the feet (0) to the ear tips (1)
    /// over the bounding box, so a texture map over it is painted on a picture of the
    /// creature seen from its left side (`+X`), nose to the right.
    pub fn creature() -> Mesh {
        use glam::{Quat, Vec3 as V};
        // (radii, rotation, centre, subdivision level) of each part.
        let parts: [(V, Quat, V, u32); 10] = [
            // body
            (
                V::new(0.5, 0.42, 0.7),
                Quat::IDENTITY,
                V::new(0.0, -0.1, -0.15),
                3,
            ),
            // head
            (V::splat(0.36), Quat::IDENTITY, V::new(0.0, 0.32, 0.5), 2),
            // snout
            (
                V::new(0.15, 0.12, 0.14),
                Quat::IDENTITY,
                V::new(0.0, 0.24, 0.82),
                1,
            ),
            // ears, tilted outwards
            (
                V::new(0.1, 0.22, 0.05),
                Quat::from_rotation_z(-0.35),
                V::new(0.2, 0.66, 0.45),
                2,
            ),
            (
                V::new(0.1, 0.22, 0.05),
                Quat::from_rotation_z(0.35),
                V::new(-0.2, 0.66, 0.45),
                2,
            ),
            // tail, raised
            (
                V::new(0.12, 0.12, 0.3),
                Quat::from_rotation_x(0.6),
                V::new(0.0, 0.12, -0.88),
                1,
            ),
            // legs
            (
                V::new(0.12, 0.22, 0.12),
                Quat::IDENTITY,
                V::new(0.28, -0.5, 0.25),
                1,
            ),
            (
                V::new(0.12, 0.22, 0.12),
                Quat::IDENTITY,
                V::new(-0.28, -0.5, 0.25),
                1,
            ),
            (
                V::new(0.12, 0.22, 0.12),
                Quat::IDENTITY,
                V::new(0.28, -0.5, -0.5),
                1,
            ),
            (
                V::new(0.12, 0.22, 0.12),
                Quat::IDENTITY,
                V::new(-0.28, -0.5, -0.5),
                1,
            ),
        ];
        let mut mesh = Mesh::default();
        for (radii, rotation, centre, level) in parts {
            // Fixed, valid parameters: these calls cannot fail; a failure
            // would only drop the part.
            let Ok(sphere) = Mesh::icosphere(1.0, level) else {
                continue;
            };
            let part = sphere.transformed(Affine3A::from_scale_rotation_translation(
                radii, rotation, centre,
            ));
            if mesh.append(&part).is_err() {
                break;
            }
        }
        let (lo, hi) = mesh.bounds();
        let centre = (lo + hi) * 0.5;
        for p in &mut mesh.positions {
            *p -= centre;
        }
        let size = (hi - lo).max(Vec3::splat(f32::MIN_POSITIVE));
        mesh.uvs = mesh
            .positions
            .iter()
            .map(|p| {
                let q = (*p + centre - lo) / size;
                Vec2::new(q.z, q.y)
            })
            .collect();
        mesh
    }
}

/// The 12 unit vertices and 20 CCW-outward triangles of a regular icosahedron.
fn icosahedron() -> (Vec<Vec3>, Vec<u32>) {
    let t = (1.0 + 5.0f32.sqrt()) / 2.0;
    let raw = [
        Vec3::new(-1.0, t, 0.0),
        Vec3::new(1.0, t, 0.0),
        Vec3::new(-1.0, -t, 0.0),
        Vec3::new(1.0, -t, 0.0),
        Vec3::new(0.0, -1.0, t),
        Vec3::new(0.0, 1.0, t),
        Vec3::new(0.0, -1.0, -t),
        Vec3::new(0.0, 1.0, -t),
        Vec3::new(t, 0.0, -1.0),
        Vec3::new(t, 0.0, 1.0),
        Vec3::new(-t, 0.0, -1.0),
        Vec3::new(-t, 0.0, 1.0),
    ];
    let directions = raw.iter().map(|v| v.normalize()).collect();
    let indices = vec![
        0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, //
        1, 5, 9, 5, 11, 4, 11, 10, 2, 10, 7, 6, 7, 1, 8, //
        3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, //
        4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1,
    ];
    (directions, indices)
}

/// Splits every triangle into four, adding each edge's midpoint (projected
/// onto the unit sphere) once; returns the new index list.
fn subdivide(directions: &mut Vec<Vec3>, indices: &[u32]) -> Vec<u32> {
    let mut cache: HashMap<(u32, u32), u32> = HashMap::with_capacity(indices.len() / 2);
    let mut midpoint = |a: u32, b: u32, directions: &mut Vec<Vec3>| -> u32 {
        let key = (a.min(b), a.max(b));
        if let Some(&m) = cache.get(&key) {
            return m;
        }
        let pa = directions.get(a as usize).copied().unwrap_or(Vec3::Y);
        let pb = directions.get(b as usize).copied().unwrap_or(Vec3::Y);
        // The subdivision level is capped, so the vertex count stays far below u32::MAX.
        let m = u32::try_from(directions.len()).unwrap_or(u32::MAX);
        directions.push((pa + pb).normalize_or(Vec3::Y));
        cache.insert(key, m);
        m
    };
    let mut out = Vec::with_capacity(indices.len() * 4);
    for tri in indices.chunks_exact(3) {
        let &[a, b, c] = tri else { continue };
        let ab = midpoint(a, b, directions);
        let bc = midpoint(b, c, directions);
        let ca = midpoint(c, a, directions);
        out.extend_from_slice(&[a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca]);
    }
    out
}

fn check_positive(builder: &'static str, name: &'static str, value: f32) -> Result<(), MeshError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(MeshError::InvalidParameter {
            builder,
            name,
            value,
            requirement: "a finite number greater than 0",
        })
    }
}

fn check_count(
    builder: &'static str,
    name: &'static str,
    value: u32,
    min: u32,
    max: u32,
) -> Result<(), MeshError> {
    if (min..=max).contains(&value) {
        Ok(())
    } else {
        Err(MeshError::CountOutOfRange {
            builder,
            name,
            value,
            min,
            max,
        })
    }
}
