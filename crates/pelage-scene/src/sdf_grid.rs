//! The grid of a body's signed distance field (`pelage_strands::BodySdf`): where its
//! nodes are, from the mesh's box and [`DynamicsParams::sdf_resolution`](crate::DynamicsParams::sdf_resolution).

use glam::{UVec3, Vec3};

use crate::ParamError;

/// The fewest nodes along the longest axis of a body's distance field (below it the
/// margin alone fills the grid).
pub const MIN_SDF_RESOLUTION: u32 = 16;

/// The most nodes along any axis pelage accepts (a device may allow fewer:
/// `max_texture_dimension_3d`, 2 048 on WebGPU's defaults; 512³ float nodes are 0.5 GB).
pub const MAX_SDF_RESOLUTION: u32 = 512;

/// Cells of margin around the mesh's box on every side: a strand vertex within a cell of
/// the surface is always inside the grid, where the field is interpolated from nodes on
/// both sides of the surface.
pub const SDF_MARGIN_CELLS: u32 = 2;

/// Cells around the surface within which the field's distance is exact (the narrow band
/// each triangle writes itself: the nodes of its box grown by this many cells that lie
/// this near its plane; farther nodes take the nearest surface point that sweeps over a
/// coarser grid find, an approximation: `pelage_strands::BodySdf`).
pub const SDF_BAND_CELLS: u32 = 2;

/// Where the nodes of a body's signed distance field are: `dims` nodes per axis, node
/// `(i, j, k)` at `origin + cell · (i, j, k)`, cubic cells. The field is sampled
/// trilinearly between nodes; a point outside the grid is outside the body.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SdfGrid {
    /// Position of node `(0, 0, 0)`.
    pub origin: Vec3,
    /// Edge of a cell, scene units.
    pub cell: f32,
    /// Nodes along each axis (at most the resolution; at least `2 · SDF_MARGIN_CELLS + 2`).
    pub dims: UVec3,
}

impl SdfGrid {
    /// The grid over the box `bounds` grown by [`SDF_MARGIN_CELLS`] on every side, with
    /// `resolution` nodes along its longest axis. Refuses a resolution outside
    /// `[MIN_SDF_RESOLUTION, MAX_SDF_RESOLUTION]` (named `dynamics.sdf_resolution`) and a
    /// box that is not finite or is a point (named `mesh.bounds`).
    pub fn new(bounds: (Vec3, Vec3), resolution: u32) -> Result<Self, ParamError> {
        check_resolution(resolution)?;
        let (lo, hi) = bounds;
        let size = hi - lo;
        let longest = size.max_element();
        if !(lo.is_finite() && hi.is_finite() && size.min_element() >= 0.0 && longest > 0.0) {
            return Err(ParamError::new(
                "mesh.bounds",
                bounds,
                "a body's distance field needs a finite box of non-zero size",
            ));
        }
        let margin = SDF_MARGIN_CELLS as f32;
        let cell = longest / (resolution - 1 - 2 * SDF_MARGIN_CELLS) as f32;
        let nodes =
            |s: f32| ((s / cell).ceil() as u32 + 1 + 2 * SDF_MARGIN_CELLS).clamp(2, resolution);
        let dims = UVec3::new(nodes(size.x), nodes(size.y), nodes(size.z));
        // Centred on the box: the leftover of the rounding is shared on both sides.
        let span = (dims - UVec3::ONE).as_vec3() * cell;
        let origin = (lo + hi) * 0.5 - span * 0.5;
        debug_assert!(origin.cmple(lo - Vec3::splat(margin * cell * 0.99)).all());
        Ok(Self { origin, cell, dims })
    }

    /// Nodes in the grid.
    pub fn nodes(&self) -> usize {
        self.dims.x as usize * self.dims.y as usize * self.dims.z as usize
    }

    /// The position of node `(i, j, k)`.
    pub fn node(&self, i: UVec3) -> Vec3 {
        self.origin + i.as_vec3() * self.cell
    }

    /// The index of node `(i, j, k)` in the field (x fastest, then y, then z).
    pub fn index(&self, i: UVec3) -> usize {
        (i.z as usize * self.dims.y as usize + i.y as usize) * self.dims.x as usize + i.x as usize
    }

    /// The node of `index` ([`SdfGrid::index`]'s inverse).
    pub fn node_of(&self, index: usize) -> UVec3 {
        let (x, y) = (self.dims.x as usize, self.dims.y as usize);
        UVec3::new(
            (index % x) as u32,
            (index / x % y) as u32,
            (index / (x * y)) as u32,
        )
    }

    /// The distance within which every node's value is exact (the narrow band:
    /// [`SDF_BAND_CELLS`] cells).
    pub fn band(&self) -> f32 {
        SDF_BAND_CELLS as f32 * self.cell
    }
}

/// Checks a distance-field resolution (0 is "off" and passes): `dynamics.sdf_resolution`
/// must be 0 or in `[MIN_SDF_RESOLUTION, MAX_SDF_RESOLUTION]`.
pub fn check_sdf_resolution(resolution: u32) -> Result<(), ParamError> {
    if resolution == 0 {
        return Ok(());
    }
    check_resolution(resolution)
}

fn check_resolution(resolution: u32) -> Result<(), ParamError> {
    if !(MIN_SDF_RESOLUTION..=MAX_SDF_RESOLUTION).contains(&resolution) {
        return Err(ParamError::new(
            "dynamics.sdf_resolution",
            resolution,
            &format!(
                "must be 0 (no body distance field) or in \
                 [{MIN_SDF_RESOLUTION}, {MAX_SDF_RESOLUTION}] nodes along the mesh's longest axis"
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_covers_the_box_with_its_margin() {
        let bounds = (Vec3::new(-1.0, 0.0, -0.25), Vec3::new(1.0, 0.5, 0.25));
        let grid = SdfGrid::new(bounds, 64).unwrap();
        assert_eq!(grid.dims.x, 64);
        assert!((grid.cell - 2.0 / 59.0).abs() < 1e-6);
        let far = grid.node(grid.dims - UVec3::ONE);
        let margin = Vec3::splat(SDF_MARGIN_CELLS as f32 * grid.cell * 0.99);
        assert!(grid.origin.cmple(bounds.0 - margin).all(), "{grid:?}");
        assert!(far.cmpge(bounds.1 + margin).all(), "{grid:?}");
        for i in [0, 17, grid.nodes() - 1] {
            assert_eq!(grid.index(grid.node_of(i)), i);
        }
    }

    #[test]
    fn bad_resolution_and_box_are_named() {
        let b = (Vec3::ZERO, Vec3::ONE);
        for r in [1, MIN_SDF_RESOLUTION - 1, MAX_SDF_RESOLUTION + 1, u32::MAX] {
            let e = SdfGrid::new(b, r).unwrap_err();
            assert!(e.to_string().contains("dynamics.sdf_resolution"), "{e}");
        }
        assert!(check_sdf_resolution(0).is_ok());
        let e = SdfGrid::new((Vec3::ONE, Vec3::ONE), 32).unwrap_err();
        assert!(e.to_string().contains("mesh.bounds"), "{e}");
        let e = SdfGrid::new((Vec3::ZERO, Vec3::NAN), 32).unwrap_err();
        assert!(e.to_string().contains("mesh.bounds"), "{e}");
    }
}
