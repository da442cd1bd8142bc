//! Hunz 2016's DBK-buffer: a depth pre-pass, a linked list of the fragments within a
//! depth shift behind the nearest hair, the rest drawn opaque behind it
//! (`shade/oit/dbk.wgsl`).

use pelage_gpu::{Gpu, wgpu, zeroed_storage};

use super::a_buffer::list_buffers;
use super::sliced::{OitTile, PassContext, PassKind, SlicedMethod, sliced_hair_pass};
use crate::draw::{Common, HairInputs};

/// The DBK-buffer: 8 bytes per pixel (head, nearest depth) plus 16 bytes per node.
#[derive(Debug)]
pub struct Dbk(SlicedMethod);

impl Dbk {
    /// Builds the DBK-buffer for `width` x `height` targets: a layer `depth_shift` thick
    /// (scene units along the view axis), a pool of `nodes_per_pixel` nodes per pixel,
    /// `resolve_k` sorted per pixel.
    pub fn new(
        gpu: &Gpu,
        inputs: &HairInputs<'_>,
        depth_shift: f32,
        nodes_per_pixel: f32,
        resolve_k: u32,
        width: u32,
        height: u32,
    ) -> crate::Result<Self> {
        super::refuse_reverse_z(inputs, "dbk")?;
        super::require_feature(gpu, "the DBK-buffer", wgpu::Features::empty())?;
        pelage_scene::Transparency::Dbk {
            depth_shift,
            nodes_per_pixel,
            resolve_k,
        }
        .validate()?;
        let common = Common::new(gpu, inputs, 1, inputs.params.min_pixels.max(1.0))?;
        let base = OitTile {
            reverse_z: u32::from(inputs.target.reverse_z),
            width,
            k: resolve_k,
            depth_shift,
            ..Default::default()
        };
        let mut sliced = list_buffers(gpu, "DBK node pool", base, nodes_per_pixel, width, height)?;
        let pixels = u64::from(width) * u64::from(sliced.rows);
        let usage = wgpu::BufferUsages::STORAGE;
        sliced.buffers.push((
            5,
            zeroed_storage(gpu, "pelage dbk nearest", pixels * 4, usage)?,
        ));
        let module = common.module(gpu, "shade/oit/dbk.wgsl")?;
        let ctx = PassContext {
            gpu,
            common: &common,
            inputs,
            module: &module,
        };
        sliced.add_hair_pass(
            &ctx,
            "shade: dbk nearest",
            "fs_nearest",
            PassKind::DepthOnly,
            &[0, 1, 5],
        )?;
        sliced.add_hair_pass(
            &ctx,
            "shade: dbk fill",
            "fs_fill",
            PassKind::Storage,
            &[0, 1, 2, 3, 4, 5],
        )?;
        sliced.add_hair_pass(
            &ctx,
            "shade: dbk fallback",
            "fs_fallback",
            PassKind::OpaqueHair,
            &[0, 5],
        )?;
        sliced.add_resolve_pass(
            gpu,
            &inputs.target,
            &module,
            "shade: dbk resolve",
            "fs_resolve",
            &[0, 2, 3, 4, 5],
        )?;
        Ok(Self(SlicedMethod {
            name: "dbk",
            common,
            sliced,
        }))
    }
}

sliced_hair_pass!(Dbk);
