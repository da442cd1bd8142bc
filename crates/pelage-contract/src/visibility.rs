//! What stage 2 hands the shading stage for the hair: each light's visibility at every
//! strand vertex, one slice of an `f32` storage buffer per light.

use pelage_gpu::wgpu;
use pelage_scene::ParamError;

/// The frame resource naming the visibility buffer ([`Visibility::buffer`]).
pub const VISIBILITY: &str = "visibility";

/// Light reaching each strand vertex, per light: light `i`'s value for vertex `v` at float
/// `i * stride + v` of `buffer` (1 = fully lit). Stage 2's `LightVisibility` writes it;
/// an engine with its own shadows may fill it instead.
#[derive(Clone, Copy, Debug)]
pub struct Visibility<'a> {
    /// The `f32` storage buffer.
    pub buffer: &'a wgpu::Buffer,
    /// Floats per light, at least the strand vertex count (see [`Visibility::stride_for`]).
    pub stride: u32,
}

impl Visibility<'_> {
    /// Floats per light for `vertices` strand vertices: rounded up to 64, so every
    /// light's slice starts on a 256-byte boundary (the storage offset alignment).
    /// Errors when the stride does not fit a `u32`.
    pub fn stride_for(vertices: u64) -> Result<u32, ParamError> {
        u32::try_from(vertices.max(1).next_multiple_of(64)).map_err(|_| ParamError {
            name: "roots.count".into(),
            value: format!("{vertices} strand vertices"),
            reason: "too many strand vertices for one visibility buffer".into(),
        })
    }

    /// Reads the buffer back (waits for the GPU): light `i`'s visibility at the first
    /// `vertices` strand vertices for each of the first `lights` lights, as many as the
    /// buffer holds. For tests and measurements; a frame never reads it back.
    pub fn read(
        &self,
        gpu: &pelage_gpu::Gpu,
        lights: usize,
        vertices: usize,
    ) -> Result<Vec<Vec<f32>>, pelage_gpu::GpuError> {
        let bytes = pelage_gpu::read_buffer(gpu, self.buffer)?;
        // The buffer's bytes as the f32s the shader wrote (copied: a readback's bytes
        // need not be aligned for f32).
        let floats: Vec<f32> = bytemuck::pod_collect_to_vec(&bytes);
        Ok(floats
            .chunks(self.stride.max(1) as usize)
            .take(lights)
            .map(|c| c[..vertices.min(c.len())].to_vec())
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::Visibility;

    #[test]
    fn stride_starts_every_light_on_256_bytes() {
        assert_eq!(Visibility::stride_for(0).ok(), Some(64));
        assert_eq!(Visibility::stride_for(64).ok(), Some(64));
        assert_eq!(Visibility::stride_for(65).ok(), Some(128));
        assert!(Visibility::stride_for(u64::from(u32::MAX) + 1).is_err());
    }
}
