//! Meshes between Bevy and pelage: positions, normals, indices and UVs survive the round
//! trip, and Bevy's UVs (top-left origin) become pelage's (bottom-left origin).

use bevy::asset::RenderAssetUsages;
use bevy::mesh::{Indices, Mesh, PrimitiveTopology};
use bevy_pelage::{bevy_mesh, pelage_mesh};

#[test]
fn the_creature_round_trips_with_its_uvs() {
    let creature = pelage::scene::Mesh::creature();
    assert!(creature.has_uvs());
    let back = pelage_mesh(&bevy_mesh(&creature)).unwrap();
    assert_eq!(back.positions, creature.positions);
    assert_eq!(back.normals, creature.normals);
    assert_eq!(back.indices, creature.indices);
    assert_eq!(back.uvs.len(), creature.uvs.len());
    let worst = back
        .uvs
        .iter()
        .zip(&creature.uvs)
        .map(|(a, b)| (*a - *b).abs().max_element())
        .fold(0.0f32, f32::max);
    assert!(worst < 1e-6, "UVs moved by {worst}");
    // A mesh without UVs stays without.
    let sphere = pelage::scene::Mesh::icosphere(1.0, 1).unwrap();
    assert!(pelage_mesh(&bevy_mesh(&sphere)).unwrap().uvs.is_empty());
}

/// One triangle whose corners carry `uvs` as Bevy's `ATTRIBUTE_UV_0`.
fn triangle(uvs: bevy::mesh::VertexAttributeValues) -> Mesh {
    Mesh::new(
        PrimitiveTopology::TriangleList,
        RenderAssetUsages::default(),
    )
    .with_inserted_attribute(
        Mesh::ATTRIBUTE_POSITION,
        vec![[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
    )
    .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, vec![[0.0f32, 0.0, 1.0]; 3])
    .with_inserted_attribute(Mesh::ATTRIBUTE_UV_0, uvs)
    .with_inserted_indices(Indices::U32(vec![0, 1, 2]))
}

#[test]
fn bevy_uvs_are_flipped_to_a_bottom_left_origin_and_nan_is_refused() {
    let uvs = vec![[0.0f32, 0.0], [1.0, 0.0], [0.25, 1.0]];
    let mesh = pelage_mesh(&triangle(uvs.into())).unwrap();
    // Bevy's (0, 0) is a texture's top-left corner: pelage's (0, 1).
    assert_eq!(
        mesh.uvs,
        vec![
            glam::Vec2::new(0.0, 1.0),
            glam::Vec2::new(1.0, 1.0),
            glam::Vec2::new(0.25, 0.0)
        ]
    );
    // (Bevy itself refuses UV_0 in another format than Float32x2.)
    let nan = vec![[f32::NAN, 0.0], [1.0, 0.0], [0.0, 1.0]];
    assert!(pelage_mesh(&triangle(nan.into())).is_err());
}
