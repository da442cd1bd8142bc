//! What stage 1 writes and every later stage reads: the strand buffers, what they look
//! like, and the per-strand record (`StrandRoot`, `wgsl/shared/strand.wgsl`).

use encase::ShaderType;
use glam::{Vec2, Vec3};
use pelage_gpu::wgpu;
use pelage_scene::{GrowthParams, ParamError};

use crate::StrandLayout;

/// The frame resource naming [`StrandBuffers::vertices`] in a [`FramePlan`](pelage_gpu::FramePlan).
pub const STRAND_VERTICES: &str = "strands.vertices";
/// The frame resource naming [`StrandBuffers::roots`] (stage 1 rewrites their widths).
pub const STRAND_ROOTS: &str = "strands.roots";

/// One strand's root and per-strand attributes, as the GPU reads them (`StrandRoot` in WGSL).
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct StrandRoot {
    /// Triangle the root sits on.
    pub triangle: u32,
    /// The strand's own hash seed.
    pub seed: u32,
    /// Barycentrics (u, v) of the root for the triangle's first and second corner; w = 1 - u - v.
    pub bary: Vec2,
    /// Strand length, scene units, jitter and length map applied.
    pub length: f32,
    /// Width at the root, scene units.
    pub width: f32,
    /// Gust phase as a fraction of `WindParams::phase_spread`, in [0, 1).
    pub phase: f32,
    /// Tilt of the root direction away from the normal, radians.
    pub tilt: f32,
    /// Azimuth of that tilt around the normal, radians.
    pub azimuth: f32,
    /// Linear RGB colour.
    pub color: Vec3,
    /// The strand's region: 0 for `[hair.growth]`, `k` for its `k`-th region
    /// (`GrowthParams::regions`); the growth pass reads its shape by it.
    pub region: u32,
}

/// What the strands look like to the passes that draw or shadow them: fixed for the
/// life of the stage 1 method (the level of detail widens strands through the drawn
/// roots' `width`, not here).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StrandStyle {
    /// Representative root width, world units: the grown width, or a groom's mean root
    /// width (what density estimates, such as the voxel grid's finest cell, scale with).
    pub width: f32,
    /// Widest root width of any strand, world units (what bounds must be padded by).
    pub max_width: f32,
    /// Tip width as a fraction of the root width.
    pub tip_width: f32,
    /// Opacity of one strand in [0, 1].
    pub opacity: f32,
}

impl StrandStyle {
    /// The style of strands grown with `growth`.
    pub fn of(growth: &GrowthParams) -> Self {
        Self {
            width: growth.width,
            max_width: growth.width,
            tip_width: growth.tip_width,
            opacity: growth.opacity,
        }
    }

    /// Refuses non-finite or out-of-range values, naming them.
    pub fn validate(&self) -> Result<(), ParamError> {
        let positive = |name: &str, v: f32| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(ParamError::new(name, v, "must be finite and positive"))
            }
        };
        positive("strands.style.width", self.width)?;
        positive("strands.style.max_width", self.max_width)?;
        let unit = |name: &str, v: f32| {
            if (0.0..=1.0).contains(&v) {
                Ok(())
            } else {
                Err(ParamError::new(name, v, "must be in [0, 1]"))
            }
        };
        unit("strands.style.tip_width", self.tip_width)?;
        unit("strands.style.opacity", self.opacity)
    }
}

/// What stage 1 produces: the buffers later stages bind without any readback, and all
/// they need to know about them, so that no later stage reads stage 1's parameters.
/// Each frame's [`StrandLayout`] travels separately, in the [`StrandFrame`](crate::StrandFrame) that
/// stage 1's `prepare` returns.
#[derive(Debug)]
pub struct StrandBuffers {
    /// `strand_count * (segments + 1)` `vec4<f32>`: xyz = position, w = strand parameter in [0, 1].
    /// Strand `i`'s vertices start at `i * (segments + 1)`; tangents come from neighbours.
    pub vertices: wgpu::Buffer,
    /// One `StrandRoot` per strand: width, colour, seed and the root itself. Stage 1
    /// rewrites `width` every frame with the level of detail's width scale.
    pub roots: wgpu::Buffer,
    /// Number of strands (the capacity; each frame's [`StrandLayout`] says how many it holds).
    pub strand_count: u32,
    /// Segments per strand at full detail (every strand has the same count).
    pub segments: u32,
    /// Widths and opacity of the strands.
    pub style: StrandStyle,
    /// A world box every vertex stays in, at any time and level of detail, for the
    /// wind the method was built with (shadow grids and maps size themselves by it).
    pub reach: (Vec3, Vec3),
}

impl StrandBuffers {
    /// Buffers holding `strand_count` strands of `segments` segments of `style`, staying
    /// inside `reach`. Errors when the vertex buffer is too small for them, `style` is
    /// out of range, or `reach` is not a finite box.
    pub fn new(
        vertices: wgpu::Buffer,
        roots: wgpu::Buffer,
        strand_count: u32,
        segments: u32,
        style: StrandStyle,
        reach: (Vec3, Vec3),
    ) -> Result<Self, ParamError> {
        style.validate()?;
        let need = u64::from(strand_count) * u64::from(segments + 1) * 16;
        if vertices.size() < need {
            return Err(ParamError::new(
                "strands.vertices",
                vertices.size(),
                &format!(
                    "must hold {strand_count} x {} vec4<f32> = {need} bytes",
                    segments + 1
                ),
            ));
        }
        if !(reach.0.is_finite() && reach.1.is_finite() && reach.0.cmple(reach.1).all()) {
            return Err(ParamError::new(
                "strands.reach",
                reach,
                "must be a finite box with min <= max",
            ));
        }
        Ok(Self {
            vertices,
            roots,
            strand_count,
            segments,
            style,
            reach,
        })
    }

    /// Vertices per strand at full detail.
    pub fn vertices_per_strand(&self) -> u32 {
        self.segments + 1
    }

    /// Bytes of the vertex buffer.
    pub fn vertex_bytes(&self) -> u64 {
        self.vertices.size()
    }

    /// The layout of every strand at full detail.
    pub fn full_layout(&self) -> StrandLayout {
        StrandLayout {
            strands: self.strand_count,
            segments: self.segments,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_region_fits_in_the_padding_of_a_64_byte_root() {
        assert_eq!(StrandRoot::min_size().get(), 64);
        assert_eq!(<StrandRoot as encase::ShaderSize>::SHADER_SIZE.get(), 64);
    }
}
