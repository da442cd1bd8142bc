//! Random subsets: the nearest fragment of each of k random strand subsets per pixel
//! (`shade/oit/random_subsets.wgsl`).

use pelage_gpu::{Gpu, GpuTimer, wgpu, zeroed_storage};
use pelage_scene::{Camera, DirectionalLight};

use super::sliced::{OitTile, PassKind, Sliced, rows_per_slice};
use super::{HairPass, require_feature};
use crate::draw::{Common, HairInputs, TargetViews};

/// Hunz 2016's random subsets: 8k bytes per pixel.
#[derive(Debug)]
pub struct RandomSubsets {
    common: Common,
    sliced: Sliced,
}

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
            width,
            k,
            ..Default::default()
        };
        let mut sliced = Sliced::new(gpu, base, height, rows)?;
        let pixels = u64::from(width) * u64::from(sliced.rows);
        sliced.buffers = vec![(
            2,
            zeroed_storage(
                gpu,
                "pelage subset slots",
                pixels * slot_bytes,
                wgpu::BufferUsages::STORAGE,
            )?,
        )];
        let module = common.module(gpu, "shade/oit/random_subsets.wgsl")?;
        sliced.add_hair_pass(
            gpu,
            &common,
            inputs,
            &module,
            "shade: subsets fill",
            "fs_fill",
            PassKind::Storage,
            &[0, 1, 2],
        )?;
        sliced.add_resolve_pass(
            gpu,
            &module,
            "shade: subsets resolve",
            "fs_resolve",
            &[0, 2],
        )?;
        Ok(Self { common, sliced })
    }
}

impl HairPass for RandomSubsets {
    fn name(&self) -> &'static str {
        "random_subsets"
    }

    fn set_frame(
        &self,
        queue: &wgpu::Queue,
        camera: &Camera,
        light: &DirectionalLight,
        width: u32,
        height: u32,
    ) -> crate::Result<()> {
        self.common.set_frame(queue, camera, light, width, height)
    }

    fn encode(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        target: &TargetViews<'_>,
        mut timer: Option<&mut GpuTimer>,
    ) -> crate::Result<()> {
        self.common
            .encode_mesh(encoder, target, None, timer.as_deref_mut());
        self.sliced.encode(gpu, encoder, target, timer)
    }

    fn memory_bytes(&self) -> u64 {
        self.sliced.memory_bytes()
    }

    fn slices(&self) -> u32 {
        self.sliced.count
    }
}
