//! Random subsets: the nearest fragment of each of k random strand subsets per pixel
//! (`shade/oit/random_subsets.wgsl`).

use pelage_gpu::{Gpu, wgpu, zeroed_storage};

use super::require_feature;
use super::sliced::{
    OitTile, PassContext, PassKind, Sliced, SlicedMethod, rows_per_slice, sliced_hair_pass,
};
use crate::draw::{Common, HairInputs};

/// Hunz 2016's random subsets: 8k bytes per pixel.
#[derive(Debug)]
pub struct RandomSubsets(SlicedMethod);

impl RandomSubsets {
    /// Builds the method with `k` subsets for `width` x `height` targets. Needs
    /// `SHADER_INT64_ATOMIC_MIN_MAX`.
    pub fn new(
        gpu: &Gpu,
        inputs: &HairInputs<'_>,
        k: u32,
        width: u32,
        height: u32,
    ) -> crate::Result<Self> {
        super::refuse_reverse_z(inputs, "random_subsets")?;
        pelage_scene::Transparency::RandomSubsets { k }.validate()?;
        require_feature(
            gpu,
            "random subsets",
            wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX,
        )?;
        let common = Common::new(gpu, inputs, 1, inputs.params.min_pixels.max(1.0))?;
        let slot_bytes = 8 * u64::from(k);
        let rows = rows_per_slice(gpu, "random subset slots", width, height, slot_bytes)?;
        let base = OitTile {
            reverse_z: u32::from(inputs.target.reverse_z),
            width,
            k,
            ..Default::default()
        };
        let mut sliced = Sliced::new(gpu, base, height, rows)?;
        let pixels = u64::from(width) * u64::from(sliced.rows);
        let usage = wgpu::BufferUsages::STORAGE;
        sliced.buffers = vec![(
            2,
            zeroed_storage(gpu, "pelage subset slots", pixels * slot_bytes, usage)?,
        )];
        let module = common.module(gpu, "shade/oit/random_subsets.wgsl")?;
        let ctx = PassContext {
            gpu,
            common: &common,
            inputs,
            module: &module,
        };
        sliced.add_hair_pass(
            &ctx,
            "shade: subsets fill",
            "fs_fill",
            PassKind::Storage,
            &[0, 1, 2],
        )?;
        sliced.add_resolve_pass(
            gpu,
            &inputs.target,
            &module,
            "shade: subsets resolve",
            "fs_resolve",
            &[0, 2],
        )?;
        Ok(Self(SlicedMethod {
            name: "random_subsets",
            common,
            sliced,
        }))
    }
}

sliced_hair_pass!(RandomSubsets);
