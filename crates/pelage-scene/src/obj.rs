//! Wavefront OBJ loading (through `tobj`) into a validated [`Mesh`].
//!
//! All objects and groups of the file are merged into one mesh; polygons are
//! triangulated; points and lines are ignored; materials are ignored. Texture
//! coordinates (`vt`) are kept as [`Mesh::uvs`] when every face corner has one: a
//! position used with several UVs (a seam) becomes one vertex per UV (as `tobj`'s
//! `single_index` splits it). A file whose faces mix corners with and without a
//! `vt` index is refused with the line ([`ObjError::MixedUvs`]). Before `tobj` sees the text, every face index is
//! checked against the number of vertices, texture coordinates and normals
//! the file defines, so a bad index is reported with its line number (and
//! cannot reach the arithmetic in `tobj` that could overflow).

use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};

use crate::mesh::{Mesh, MeshError};

/// Why an OBJ file could not be turned into a mesh.
#[derive(Debug, thiserror::Error)]
pub enum ObjError {
    /// The file could not be read.
    #[error("could not read OBJ file {}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The file is not UTF-8 text.
    #[error(
        "{source_name} is not UTF-8 text (invalid byte at offset {offset}); an OBJ file must be a text file"
    )]
    NotText {
        /// The file path, or `"in-memory OBJ text"`.
        source_name: String,
        /// Byte offset of the first invalid byte.
        offset: usize,
    },
    /// `tobj` could not parse the text.
    #[error("could not parse {source_name}: {source}; check that it is a valid Wavefront OBJ file")]
    Parse {
        /// The file path, or `"in-memory OBJ text"`.
        source_name: String,
        /// The parser's error.
        #[source]
        source: tobj::LoadError,
    },
    /// A face refers to an element that does not exist.
    #[error(
        "{source_name}, line {line}: face index {index} refers to a {kind} that does not exist ({count} {} defined; OBJ indices start at 1 and negative ones count back from the last one defined so far)", counted(*.count, .kind)
    )]
    FaceIndexOutOfRange {
        /// The file path, or `"in-memory OBJ text"`.
        source_name: String,
        /// Line number, starting at 1.
        line: usize,
        /// `"vertex"`, `"texture coordinate"` or `"normal"`.
        kind: &'static str,
        /// The index as written in the file.
        index: i64,
        /// How many elements of that kind are defined (in the file, or before
        /// the line for a negative index).
        count: usize,
    },
    /// Some face corners have a texture coordinate index and others do not.
    #[error(
        "{source_name}, line {line}: a face corner {} a texture coordinate index but one on line {first_line} {}; give every face corner a `vt` index (f v/vt or v/vt/vn) or none",
        if *.has_uv { "has" } else { "lacks" }, if *.has_uv { "lacks one" } else { "has one" }
    )]
    MixedUvs {
        /// The file path, or `"in-memory OBJ text"`.
        source_name: String,
        /// The line of the corner that differs from the first face's, starting at 1.
        line: usize,
        /// Whether that corner has a texture coordinate index.
        has_uv: bool,
        /// The line of the first face.
        first_line: usize,
    },
    /// The file has no triangles (no faces with three or more vertices).
    #[error(
        "{source_name} has no faces (no 'f' lines with three or more vertices); pelage needs a surface"
    )]
    NoFaces {
        /// The file path, or `"in-memory OBJ text"`.
        source_name: String,
    },
    /// The merged mesh is not valid (for example NaN positions or only
    /// zero-area faces).
    #[error("{source_name} gives an unusable mesh: {source}")]
    Invalid {
        /// The file path, or `"in-memory OBJ text"`.
        source_name: String,
        /// What [`Mesh::validate`] reported.
        #[source]
        source: MeshError,
    },
    /// The merged mesh has more vertices than `u32` indices can address.
    #[error(
        "{source_name} has {vertices} vertices after merging, more than u32 indices can address"
    )]
    TooManyVertices {
        /// The file path, or `"in-memory OBJ text"`.
        source_name: String,
        /// The vertex count.
        vertices: u64,
    },
}

const IN_MEMORY: &str = "in-memory OBJ text";

/// "1 vertex is", "3 vertices are", "2 normals are": `count` elements of `kind`.
fn counted(count: usize, kind: &str) -> String {
    match (count, kind) {
        (1, _) => format!("{kind} is"),
        (_, "vertex") => "vertices are".to_string(),
        _ => format!("{kind}s are"),
    }
}

/// Loads the OBJ file at `path` into one validated mesh (all objects merged).
///
/// Normals come from the file when every vertex of every face has one (they
/// are normalised); otherwise, or when a file normal is zero or not finite,
/// all normals are recomputed with [`Mesh::recompute_normals`]. Material
/// libraries are not read. At most [`MAX_OBJ_FILE_BYTES`](crate::MAX_OBJ_FILE_BYTES)
/// are read.
pub fn load_obj(path: &Path) -> Result<Mesh, ObjError> {
    let bytes = crate::limits::read_capped(path, crate::MAX_OBJ_FILE_BYTES, "OBJ files").map_err(
        |source| ObjError::Io {
            path: path.to_path_buf(),
            source,
        },
    )?;
    let source_name = format!("OBJ file {}", path.display());
    let text = std::str::from_utf8(&bytes).map_err(|e| ObjError::NotText {
        source_name: source_name.clone(),
        offset: e.valid_up_to(),
    })?;
    parse(text, source_name)
}

/// Parses OBJ text held in memory into one validated mesh, like [`load_obj`]
/// (`mtllib` lines are ignored).
pub fn parse_obj(text: &str) -> Result<Mesh, ObjError> {
    parse(text, IN_MEMORY.to_owned())
}

fn parse(text: &str, source_name: String) -> Result<Mesh, ObjError> {
    check_face_indices(text, &source_name)?;
    // Spelled out in full, plus `..Default::default()` for fields that
    // optional tobj features (merging, reordering) add.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let mut reader = std::io::Cursor::new(text.as_bytes());
    let (models, _materials) = tobj::load_obj_buf(&mut reader, &options, |_| {
        Ok((Vec::new(), Default::default()))
    })
    .map_err(|source| ObjError::Parse {
        source_name: source_name.clone(),
        source,
    })?;

    let mut mesh = Mesh::default();
    let mut all_normals = true;
    for model in &models {
        let m = &model.mesh;
        let positions: &[f32] = &m.positions;
        let normals: &[f32] = &m.normals;
        let part_positions: Vec<Vec3> = positions.chunks_exact(3).map(vec3).collect();
        let part_normals: Vec<Vec3> = normals.chunks_exact(3).map(vec3).collect();
        if part_normals.len() != part_positions.len() {
            all_normals = false;
        }
        let mut part_uvs: Vec<Vec2> = m
            .texcoords
            .chunks_exact(2)
            .map(|c| Vec2::new(c[0], c[1]))
            .collect();
        // A part without UVs leaves the merged mesh without any (see `Mesh::append`).
        if part_uvs.len() != part_positions.len() {
            part_uvs.clear();
        }
        let part = Mesh {
            positions: part_positions,
            normals: part_normals,
            indices: m.indices.clone(),
            uvs: part_uvs,
        };
        // Normals are rebuilt below if any part lacks them, so a
        // misaligned normal array is never used.
        mesh.append(&part).map_err(|_| ObjError::TooManyVertices {
            source_name: source_name.clone(),
            vertices: (mesh.positions.len() as u64).saturating_add(part.positions.len() as u64),
        })?;
    }
    if mesh.indices.len() < 3 {
        return Err(ObjError::NoFaces { source_name });
    }

    let normalised: Option<Vec<Vec3>> = if all_normals {
        mesh.normals.iter().map(|n| n.try_normalize()).collect()
    } else {
        None
    };
    match normalised {
        Some(normals) => mesh.normals = normals,
        None => mesh.recompute_normals(),
    }
    mesh.validate().map_err(|source| ObjError::Invalid {
        source_name: source_name.clone(),
        source,
    })?;
    Ok(mesh)
}

/// A `Vec3` from a 3-float chunk (missing components read as 0; the callers
/// pass `chunks_exact(3)` chunks).
fn vec3(c: &[f32]) -> Vec3 {
    let mut it = c.iter().copied();
    let mut next = || it.next().unwrap_or(0.0);
    Vec3::new(next(), next(), next())
}

/// Checks that every index on every `f` and `l` line resolves to an element
/// the file defines, the way `tobj` resolves it (positive: 1-based into all
/// elements of the file; negative: relative to the elements defined so far;
/// 0 is never valid). Texture and normal indices are only checked when the file
/// has texture coordinates / normals at all (otherwise `tobj` ignores them).
/// Tokens that do not parse as integers are left for `tobj` to refuse.
fn check_face_indices(text: &str, source_name: &str) -> Result<(), ObjError> {
    const KINDS: [&str; 3] = ["vertex", "texture coordinate", "normal"];
    struct Reference {
        line: usize,
        kind: usize,
        index: i64,
        resolved: Option<usize>,
        count_so_far: usize,
    }
    let mut counts = [0usize; 3];
    let mut references = Vec::new();
    // (line, has a vt index) of the first face corner, and the first corner that differs.
    let mut first_corner: Option<(usize, bool)> = None;
    let mut mixed: Option<(usize, bool)> = None;
    for (line_number, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => counts[0] += 1,
            Some("vt") => counts[1] += 1,
            Some("vn") => counts[2] += 1,
            // `tobj` parses `l` like `f` and turns an `l` with three or
            // more vertices into triangles even with `ignore_lines`, so its
            // indices reach the same arithmetic.
            Some(keyword @ ("f" | "l")) => {
                for word in words {
                    if keyword == "f" {
                        let has_uv = word.split('/').nth(1).is_some_and(|t| !t.is_empty());
                        match first_corner {
                            None => first_corner = Some((line_number + 1, has_uv)),
                            Some((_, first)) if first != has_uv && mixed.is_none() => {
                                mixed = Some((line_number + 1, has_uv));
                            }
                            _ => {}
                        }
                    }
                    for (kind, part) in word.split('/').take(3).enumerate() {
                        if part.is_empty() {
                            continue;
                        }
                        let Ok(index) = part.parse::<isize>() else {
                            continue;
                        };
                        let count_so_far = counts.get(kind).copied().unwrap_or(0);
                        let resolved = match index {
                            0 => None,
                            i if i < 0 => count_so_far.checked_sub(i.unsigned_abs()),
                            i => Some(i.unsigned_abs() - 1),
                        };
                        references.push(Reference {
                            line: line_number + 1,
                            kind,
                            index: index as i64,
                            resolved,
                            count_so_far,
                        });
                    }
                }
            }
            _ => {}
        }
    }
    if let (Some((first_line, _)), Some((line, has_uv))) = (first_corner, mixed) {
        if counts[1] > 0 {
            return Err(ObjError::MixedUvs {
                source_name: source_name.to_owned(),
                line,
                has_uv,
                first_line,
            });
        }
    }
    for r in references {
        let total = counts.get(r.kind).copied().unwrap_or(0);
        if r.kind != 0 && total == 0 {
            continue;
        }
        if r.resolved.is_none_or(|i| i >= total) {
            return Err(ObjError::FaceIndexOutOfRange {
                source_name: source_name.to_owned(),
                line: r.line,
                kind: KINDS.get(r.kind).copied().unwrap_or("element"),
                index: r.index,
                count: if r.index < 0 { r.count_so_far } else { total },
            });
        }
    }
    Ok(())
}
