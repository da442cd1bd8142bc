//! The body's signed distance field (`BodySdf`, `wgsl/strands/sdf.wgsl`) against the CPU
//! mirror's exact distances, and its bad input.

use pelage_reference::sdf::exact_field;
use pelage_scene::Mesh;
use pelage_strands::{BodySdf, MeshBuffers};

mod common;
use common::gpu;

/// The GPU field of `mesh` at `resolution` and the exact one, with the grid's band and
/// the largest error (in cells) inside and outside the band.
fn compare(mesh: &Mesh, resolution: u32) -> (f32, f32, usize) {
    let gpu = gpu();
    let buffers = MeshBuffers::upload(&gpu, mesh).unwrap();
    let sdf = BodySdf::new(&gpu, &buffers, mesh.bounds(), resolution).unwrap();
    sdf.build(&gpu).unwrap();
    let field = sdf.read(&gpu).unwrap();
    let grid = *sdf.grid();
    let exact = exact_field(mesh, &grid, f32::MAX);
    assert_eq!(field.len(), exact.len());
    let (mut band_err, mut far_err, mut sign_flips) = (0.0f32, 0.0f32, 0);
    for (g, e) in field.iter().zip(&exact) {
        // Magnitudes: where the sign flips (see the callers), the distance is still
        // that of a triangle about as near.
        let err = (g.abs() - e.abs()).abs() / grid.cell;
        if e.abs() <= grid.band() {
            band_err = band_err.max(err);
            assert_eq!(g.signum(), e.signum(), "band node: gpu {g}, exact {e}");
        } else {
            far_err = far_err.max(err);
            sign_flips += usize::from(g.signum() != e.signum());
        }
    }
    eprintln!(
        "{} nodes {:?}, cell {}: band error {band_err:e} cells, far error {far_err:e} cells, \
         {sign_flips} far sign flips",
        grid.nodes(),
        grid.dims,
        grid.cell
    );
    (band_err, far_err, sign_flips)
}

#[test]
fn the_head_field_is_exact_in_the_band_and_close_beyond() {
    let head = Mesh::icosphere(0.5, 3).unwrap();
    let (band, far, flips) = compare(&head, 48);
    // Measured: 2.7e-6 cells in the band (float rounding), 0.032 beyond.
    assert!(band < 1e-4, "band error {band} cells");
    assert!(far < 0.1, "far error {far} cells");
    assert_eq!(flips, 0);
}

#[test]
fn the_creature_field_is_exact_in_the_band_and_close_beyond() {
    let creature = Mesh::creature();
    let (band, far, flips) = compare(&creature, 40);
    // Measured: 1.6e-6 cells in the band, 0.041 beyond; 2 of 28 160 nodes flip sign. The
    // creature's parts overlap unwelded, so inside the body a buried part's surface
    // faces outward: a node about as far from it as from the body's own surface takes
    // either side, and jump flooding may hold the other (never in the band).
    assert!(band < 1e-4, "band error {band} cells");
    assert!(far < 0.1, "far error {far} cells");
    assert!(flips <= 28, "{flips} far sign flips (at most 0.1% of the nodes)");
}
