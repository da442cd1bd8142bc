//! Tests of the mesh type: validation and the procedural builders.

use glam::{Affine3A, Quat, Vec3};
use pelage_scene::mesh::{MAX_ICOSPHERE_SUBDIVISIONS, MeshReport};
use pelage_scene::{Mesh, MeshError};

/// Every triangle's geometric normal `(b - a) × (c - a)` points the same way
/// as its three vertex normals (CCW front faces agree with the normals).
fn assert_ccw_matches_normals(mesh: &Mesh) {
    for (t, tri) in mesh.indices.chunks_exact(3).enumerate() {
        let [a, b, c] = [0, 1, 2].map(|k| mesh.positions[tri[k] as usize]);
        let face = (b - a).cross(c - a);
        for (k, &index) in tri.iter().enumerate() {
            let n = mesh.normals[index as usize];
            assert!(
                face.dot(n) > 0.0,
                "triangle {t} winds against its vertex normal {k}"
            );
        }
    }
}

fn assert_unit_normals(mesh: &Mesh) {
    assert_eq!(mesh.normals.len(), mesh.positions.len());
    for (i, n) in mesh.normals.iter().enumerate() {
        assert!(
            (n.length() - 1.0).abs() < 1e-5,
            "normal {i} = {n} is not unit"
        );
    }
}

#[test]
fn icosphere_counts_per_level() {
    for level in 0..=4u32 {
        let mesh = Mesh::icosphere(1.0, level).unwrap();
        let four_n = 4usize.pow(level);
        assert_eq!(mesh.positions.len(), 10 * four_n + 2, "level {level}");
        assert_eq!(mesh.indices.len() / 3, 20 * four_n, "level {level}");
        let report = mesh.validate().unwrap();
        assert_eq!(report.triangles, 20 * four_n);
        assert!(report.degenerate_triangles.is_empty());
    }
    let l0 = Mesh::icosphere(1.0, 0).unwrap();
    assert_eq!((l0.positions.len(), l0.indices.len() / 3), (12, 20));
    let l1 = Mesh::icosphere(1.0, 1).unwrap();
    assert_eq!((l1.positions.len(), l1.indices.len() / 3), (42, 80));
}

#[test]
fn icosphere_geometry() {
    let radius = 2.5;
    for level in 0..=3 {
        let mesh = Mesh::icosphere(radius, level).unwrap();
        assert_unit_normals(&mesh);
        for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
            assert!((p.length() - radius).abs() < 1e-4, "{p} is off the sphere");
            assert!(
                (*p / radius - *n).length() < 1e-5,
                "normal {n} is not p / r"
            );
        }
        for tri in mesh.indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|k| mesh.positions[tri[k] as usize]);
            let centroid = (a + b + c) / 3.0;
            assert!(
                (b - a).cross(c - a).dot(centroid) > 0.0,
                "triangle not CCW-outward"
            );
        }
        assert_ccw_matches_normals(&mesh);
        // Area approaches the sphere's from below.
        let area = mesh.validate().unwrap().total_area;
        let sphere = 4.0 * std::f32::consts::PI * radius * radius;
        assert!(area < sphere && area > 0.6 * sphere, "area {area}");
    }
}

#[test]
fn icosphere_rejects_bad_parameters() {
    for radius in [0.0, -1.0, f32::NAN, f32::INFINITY] {
        assert!(matches!(
            Mesh::icosphere(radius, 1),
            Err(MeshError::InvalidParameter { name: "radius", .. })
        ));
    }
    assert!(Mesh::icosphere(1.0, MAX_ICOSPHERE_SUBDIVISIONS).is_ok());
    let err = Mesh::icosphere(1.0, MAX_ICOSPHERE_SUBDIVISIONS + 1).unwrap_err();
    assert!(matches!(
        err,
        MeshError::CountOutOfRange {
            name: "subdivisions",
            ..
        }
    ));
    assert!(err.to_string().contains("subdivisions"));
}

#[test]
fn torus_normals_outward() {
    let (major, minor) = (1.0, 0.3);
    let mesh = Mesh::torus(major, minor, 24, 12).unwrap();
    assert_eq!(mesh.positions.len(), 24 * 12);
    assert_eq!(mesh.indices.len() / 3, 2 * 24 * 12);
    assert_unit_normals(&mesh);
    for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
        // The tube centre nearest to p; the normal points from it to p.
        let ring = Vec3::new(p.x, 0.0, p.z).normalize() * major;
        let out = (*p - ring).normalize();
        assert!(out.dot(*n) > 0.999, "normal {n} at {p} is not outward");
        assert!(((*p - ring).length() - minor).abs() < 1e-4);
    }
    assert_ccw_matches_normals(&mesh);
    let report = mesh.validate().unwrap();
    assert!(report.degenerate_triangles.is_empty());
    assert!(Mesh::torus(1.0, 1.0, 8, 8).is_err());
    assert!(Mesh::torus(1.0, 0.2, 2, 8).is_err());
    assert!(Mesh::torus(f32::NAN, 0.2, 8, 8).is_err());
}

#[test]
fn plane_faces_up() {
    let mesh = Mesh::plane(2.0, 3.0, 4, 6).unwrap();
    assert_eq!(mesh.positions.len(), 5 * 7);
    assert_eq!(mesh.indices.len() / 3, 2 * 4 * 6);
    assert!(mesh.normals.iter().all(|&n| n == Vec3::Y));
    assert!(mesh.positions.iter().all(|p| p.y == 0.0));
    assert_ccw_matches_normals(&mesh);
    let report = mesh.validate().unwrap();
    assert!((report.total_area - 6.0).abs() < 1e-4);
    assert_eq!(report.bounds_min, Vec3::new(-1.0, 0.0, -1.5));
    assert_eq!(report.bounds_max, Vec3::new(1.0, 0.0, 1.5));
    assert!(Mesh::plane(1.0, 1.0, 0, 1).is_err());
    assert!(Mesh::plane(-1.0, 1.0, 1, 1).is_err());
}

#[test]
fn creature_is_valid_and_in_bounds() {
    let mesh = Mesh::creature();
    let report = mesh.validate().unwrap();
    assert!(report.degenerate_triangles.is_empty());
    assert!(report.triangles <= 3000, "{} triangles", report.triangles);
    assert!(report.triangles >= 1000);
    assert_unit_normals(&mesh);
    assert_ccw_matches_normals(&mesh);
    let limit = Vec3::splat(1.2);
    assert!(
        report.bounds_min.cmpge(-limit).all(),
        "{}",
        report.bounds_min
    );
    assert!(
        report.bounds_max.cmple(limit).all(),
        "{}",
        report.bounds_max
    );
    let centre = (report.bounds_min + report.bounds_max) * 0.5;
    assert!(centre.length() < 1e-4);
    // Taller than wide is not required, but it must be a 3D shape of about unit size.
    let size = report.bounds_max - report.bounds_min;
    assert!(size.min_element() > 0.8, "size {size}");
    // Deterministic.
    assert_eq!(mesh, Mesh::creature());
}

#[test]
fn transformed_keeps_normals_and_winding() {
    let sphere = Mesh::icosphere(1.0, 2).unwrap();
    let squash = Affine3A::from_scale_rotation_translation(
        Vec3::new(2.0, 0.5, 1.0),
        Quat::from_rotation_y(0.7),
        Vec3::new(1.0, 2.0, 3.0),
    );
    let mirror = Affine3A::from_scale(Vec3::new(-1.0, 1.0, 1.0));
    for affine in [squash, mirror, squash * mirror] {
        let mesh = sphere.transformed(affine);
        assert_unit_normals(&mesh);
        assert_ccw_matches_normals(&mesh);
        mesh.validate().unwrap();
    }
}

#[test]
fn append_offsets_indices() {
    let mut a = Mesh::icosphere(1.0, 0).unwrap();
    let b = Mesh::icosphere(1.0, 0)
        .unwrap()
        .transformed(Affine3A::from_translation(Vec3::X * 3.0));
    a.append(&b).unwrap();
    assert_eq!(a.positions.len(), 24);
    assert_eq!(a.indices.len(), 120);
    assert_eq!(
        &a.indices[60..],
        &b.indices.iter().map(|i| i + 12).collect::<Vec<_>>()[..]
    );
    a.validate().unwrap();
}

#[test]
fn recompute_normals_matches_sphere() {
    let sphere = Mesh::icosphere(1.0, 3).unwrap();
    let mut mesh = sphere.clone();
    mesh.normals.clear();
    mesh.positions.push(Vec3::new(5.0, 0.0, 0.0)); // unreferenced vertex: fallback
    mesh.recompute_normals();
    assert_eq!(mesh.normals.len(), mesh.positions.len());
    for (n, exact) in mesh.normals.iter().zip(&sphere.normals) {
        assert!(n.dot(*exact) > 0.99);
    }
    let fallback = *mesh.normals.last().unwrap();
    assert!((fallback.length() - 1.0).abs() < 1e-5);
    mesh.validate().unwrap();
}

fn one_triangle() -> Mesh {
    Mesh {
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
        normals: vec![Vec3::Z; 3],
        indices: vec![0, 1, 2],
        uvs: Vec::new(),
    }
}

#[test]
fn validate_one_triangle() {
    let report = one_triangle().validate().unwrap();
    assert_eq!(
        report,
        MeshReport {
            triangles: 1,
            degenerate_triangles: vec![],
            total_area: 0.5,
            bounds_min: Vec3::ZERO,
            bounds_max: Vec3::new(1.0, 1.0, 0.0),
        }
    );
}

#[test]
fn validate_no_triangles() {
    let mut m = one_triangle();
    m.indices.clear();
    assert_eq!(m.validate(), Err(MeshError::NoTriangles));
}

#[test]
fn validate_index_count_not_multiple_of_three() {
    let mut m = one_triangle();
    m.indices.push(0);
    assert_eq!(
        m.validate(),
        Err(MeshError::IndexCountNotMultipleOfThree { count: 4 })
    );
}

#[test]
fn validate_index_out_of_range() {
    let mut m = one_triangle();
    m.indices.extend_from_slice(&[0, 2, 7]);
    let err = m.validate().unwrap_err();
    assert_eq!(
        err,
        MeshError::IndexOutOfRange {
            triangle: 1,
            corner: 2,
            index: 7,
            vertex_count: 3
        }
    );
    let text = err.to_string();
    assert!(text.contains("triangle 1") && text.contains('7'), "{text}");
}

#[test]
fn validate_normal_count_mismatch() {
    let mut m = one_triangle();
    m.normals.pop();
    assert_eq!(
        m.validate(),
        Err(MeshError::NormalCountMismatch {
            positions: 3,
            normals: 2
        })
    );
}

#[test]
fn validate_non_finite_position() {
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        let mut m = one_triangle();
        m.positions[1].y = bad;
        assert!(matches!(
            m.validate(),
            Err(MeshError::NonFinitePosition { vertex: 1, .. })
        ));
    }
}

#[test]
fn validate_position_beyond_the_largest_extent() {
    // Finite, but its square overflows f32 where the shaders take distances: refused at
    // load, naming the vertex, instead of a black mesh at run time.
    for bad in [1e38f32, -2e9, 1e19] {
        let mut m = one_triangle();
        m.positions[2].x = bad;
        let err = m.validate().unwrap_err();
        assert!(
            matches!(err, MeshError::PositionOutOfRange { vertex: 2, .. }),
            "{bad}: {err:?}"
        );
        assert!(err.to_string().contains("at most 1e9"), "{err}");
    }
    // The same triangle scaled so its largest coordinate is the limit itself is fine.
    let mut fine = one_triangle();
    let largest = fine
        .positions
        .iter()
        .map(|p| p.abs().max_element())
        .fold(0.0f32, f32::max);
    for p in &mut fine.positions {
        *p *= pelage_scene::MAX_EXTENT / largest;
    }
    fine.validate().unwrap();
}

#[test]
fn validate_non_finite_normal() {
    let mut m = one_triangle();
    m.normals[2] = Vec3::new(0.0, f32::NAN, 1.0);
    assert!(matches!(
        m.validate(),
        Err(MeshError::NonFiniteNormal { vertex: 2, .. })
    ));
}

#[test]
fn validate_zero_length_normal() {
    let mut m = one_triangle();
    m.normals[0] = Vec3::ZERO;
    assert!(matches!(
        m.validate(),
        Err(MeshError::ZeroLengthNormal { vertex: 0, .. })
    ));
}

#[test]
fn validate_all_degenerate() {
    let m = Mesh {
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::X * 2.0],
        normals: vec![Vec3::Z; 3],
        indices: vec![0, 1, 2, 0, 0, 1],
        uvs: Vec::new(),
    };
    assert_eq!(
        m.validate(),
        Err(MeshError::AllTrianglesDegenerate { triangles: 2 })
    );
}

#[test]
fn validate_reports_degenerate_among_good() {
    let mut m = Mesh::icosphere(1.0, 1).unwrap();
    // Triangle 80: a repeated index; triangle 81: three exactly collinear points.
    m.indices.extend_from_slice(&[0, 0, 1]);
    let first = m.positions.len() as u32;
    for x in [0.25, 0.5, 0.75] {
        m.positions.push(Vec3::new(x, 0.0, 0.0));
        m.normals.push(Vec3::Y);
    }
    m.indices.extend_from_slice(&[first, first + 1, first + 2]);
    let report = m.validate().unwrap();
    assert_eq!(report.triangles, 82);
    assert_eq!(report.degenerate_triangles, vec![80, 81]);
    let areas = m.triangle_areas();
    assert_eq!(areas.len(), 82);
    assert_eq!(areas[80], 0.0);
    assert_eq!(areas[81], 0.0);
    assert!(areas[..80].iter().all(|&a| a > 0.0));
}
