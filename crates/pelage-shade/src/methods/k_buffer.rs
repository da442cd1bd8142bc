//! The k-buffer: the k nearest fragments per pixel by 64-bit atomicMax insertion, the
//! rest blended approximately (`shade/oit/k_buffer.wgsl`).

use pelage_gpu::{Gpu, wgpu, zeroed_storage};

use super::require_feature;
use super::sliced::{
    OitTile, PassContext, PassKind, Sliced, SlicedMethod, rows_per_slice, sliced_hair_pass,
};
use crate::draw::{Common, HairInputs};

/// Bytes per pixel of the approximate tail (`shade/oit/tail.wgsl`: 5 words).
pub(crate) const TAIL_BYTES: u64 = 20;

/// The bounded k-buffer: 8k + 20 bytes per pixel.
#[derive(Debug)]
pub struct KBuffer(SlicedMethod);

impl KBuffer {
    /// Builds the k-buffer for `width` x `height` targets. Needs
    /// `SHADER_INT64_ATOMIC_ALL_OPS` (the insertion reads back what atomicMax displaced).
    pub fn new(
        gpu: &Gpu,
        inputs: &HairInputs<'_>,
        k: u32,
        width: u32,
        height: u32,
    ) -> crate::Result<Self> {
        super::refuse_reverse_z(inputs, "k_buffer")?;
        pelage_scene::Transparency::KBuffer { k }.validate()?;
        require_feature(
            gpu,
            "the k-buffer",
            wgpu::Features::SHADER_INT64_ATOMIC_ALL_OPS,
        )?;
        let common = Common::new(gpu, inputs, 1, inputs.params.min_pixels.max(1.0))?;
        let slot_bytes = 8 * u64::from(k);
        let rows = rows_per_slice(gpu, "k-buffer slots", width, height, slot_bytes)?;
        let base = OitTile {
            reverse_z: u32::from(inputs.target.reverse_z),
            width,
            k,
            ..Default::default()
        };
        let mut sliced = Sliced::new(gpu, base, height, rows)?;
        let pixels = u64::from(width) * u64::from(sliced.rows);
        let usage = wgpu::BufferUsages::STORAGE;
        sliced.buffers = vec![
            (
                2,
                zeroed_storage(gpu, "pelage k-buffer slots", pixels * slot_bytes, usage)?,
            ),
            (
                8,
                zeroed_storage(gpu, "pelage oit tail", pixels * TAIL_BYTES, usage)?,
            ),
        ];
        let module = common.module(gpu, "shade/oit/k_buffer.wgsl")?;
        let ctx = PassContext {
            gpu,
            common: &common,
            inputs,
            module: &module,
        };
        sliced.add_hair_pass(
            &ctx,
            "shade: k-buffer fill",
            "fs_fill",
            PassKind::Storage,
            &[0, 1, 2, 8],
        )?;
        sliced.add_resolve_pass(
            gpu,
            &inputs.target,
            &module,
            "shade: k-buffer resolve",
            "fs_resolve",
            &[0, 2, 8],
        )?;
        Ok(Self(SlicedMethod {
            name: "k_buffer",
            common,
            sliced,
        }))
    }
}

sliced_hair_pass!(KBuffer);
