//! GPU skinning as stage 1's input: linear blend skinning of a mesh's bind pose into its
//! [`MeshBuffers`] every frame (`wgsl/strands/skin.wgsl`), recorded before the stage 1
//! method that reads them.

use encase::ShaderType;
use glam::{Mat4, UVec4, Vec4};
use pelage_gpu::{
    BindLayout, Gpu, GpuTimer, PassInfo, UniformBuffer, bind_buffers,
    compute_pipeline_with_layouts, dispatch_size, read_buffer, storage_buffer, wgpu,
    zeroed_storage,
};
use pelage_scene::{Mesh, Skin};

use crate::{MESH, MeshBuffers};

/// Workgroup size of `skin.wgsl`.
const WORKGROUP: u32 = 64;

/// The timestamp label of the skinning pass.
pub const SKIN_LABEL: &str = "strands: skin";
/// The frame resource of the skin pass's count of vertices it kept at their bind pose
/// (their skinned position was not finite).
pub const SKIN_NON_FINITE: &str = "strands.skin_non_finite";

/// The uniforms of `skin.wgsl` (`SkinUniforms` there).
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub(crate) struct SkinUniforms {
    /// Vertices skinned.
    pub vertex_count: u32,
    /// Joint matrices in the joint-matrix buffer.
    pub joint_count: u32,
}

/// Linear blend skinning on the GPU: the bind pose of a mesh, per vertex four joints and
/// weights ([`Skin`]), and a joint-matrix buffer the caller writes every frame
/// ([`MeshSkin::set_joint_matrices`], or its own `queue.write_buffer` or copy into
/// [`MeshSkin::joint_matrices`]); [`MeshSkin::encode`] skins positions and normals into
/// the [`MeshBuffers`] that stage 1 reads, so roots ride the skinned surface and a
/// simulation takes them as its moving anchors.
///
/// Positions are `Σ w_k M_k p`; normals the blended matrix's cofactor (its inverse
/// transpose times its determinant) times `n`, normalised. Linear blend skinning only: no
/// dual quaternions, so a joint twisted far (past about 90°) pinches its blend zone (the
/// candy-wrapper artefact), as in every LBS engine.
///
/// Bad input: [`MeshSkin::new`] refuses a skin whose joint indices reach past its joint
/// count, whose weights are negative or not finite or do not sum to 1 (within
/// [`pelage_scene::WEIGHT_SUM_TOLERANCE`]; those within are normalised);
/// [`MeshSkin::set_joint_matrices`] refuses a non-finite matrix. Matrices written to the
/// buffer directly are not checked: a vertex whose skinned position or normal is not
/// finite is written at its bind pose and counted ([`MeshSkin::non_finite_vertices`]).
#[derive(Debug)]
pub struct MeshSkin {
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    joint_matrices: wgpu::Buffer,
    non_finite: wgpu::Buffer,
    skin: Skin,
    vertex_count: u32,
    limits: wgpu::Limits,
}

impl MeshSkin {
    /// Uploads `bind` (the bind pose; its vertex count must be `mesh`'s) and `skin`, with
    /// every joint matrix the identity, and builds the pass writing into `mesh`.
    pub fn new(gpu: &Gpu, bind: &Mesh, skin: &Skin, mesh: &MeshBuffers) -> crate::Result<Self> {
        bind.validate()?;
        mesh.check_matches(bind)?;
        skin.validate(bind.positions.len())?;
        let storage = wgpu::BufferUsages::STORAGE;
        let positions: Vec<f32> = bind.positions.iter().flat_map(|p| p.to_array()).collect();
        let normals: Vec<f32> = bind.normals.iter().flat_map(|n| n.to_array()).collect();
        let joints: Vec<UVec4> = skin.joints.iter().map(|j| UVec4::from_array(*j)).collect();
        let weights: Vec<Vec4> = (skin.normalized_weights().iter())
            .map(|w| Vec4::from_array(*w))
            .collect();
        let bind_positions =
            storage_buffer(gpu, "pelage skin bind positions", &positions, storage)?;
        let bind_normals = storage_buffer(gpu, "pelage skin bind normals", &normals, storage)?;
        let joints = storage_buffer(gpu, "pelage skin joints", &joints, storage)?;
        let weights = storage_buffer(gpu, "pelage skin weights", &weights, storage)?;
        let identity = vec![Mat4::IDENTITY; skin.joint_count as usize];
        let joint_matrices = storage_buffer(gpu, "pelage skin joint matrices", &identity, storage)?;
        let non_finite = zeroed_storage(gpu, "pelage skin non-finite vertices", 4, storage)?;
        // The joint matrices are written by the caller (CPU or its own copies), never by
        // a pelage pass.
        pelage_gpu::audit::constant(&[
            &bind_positions,
            &bind_normals,
            &joints,
            &weights,
            &joint_matrices,
        ]);
        pelage_gpu::audit::name_buffer(&non_finite, SKIN_NON_FINITE);
        let uniforms = UniformBuffer::new(
            gpu,
            "pelage skin uniforms",
            &SkinUniforms {
                vertex_count: mesh.vertex_count,
                joint_count: skin.joint_count,
            },
        )?;
        let module = crate::SHADERS.library().module(gpu, "strands/skin.wgsl")?;
        let (pipeline, bind_group) = gpu.scoped(|device| {
            let layout = BindLayout::new(SKIN_LABEL, wgpu::ShaderStages::COMPUTE)
                .uniform(0)
                .storage(1)
                .storage(2)
                .storage(3)
                .storage(4)
                .storage(5)
                .storage_rw(6)
                .storage_rw(7)
                .storage_rw(8)
                .build(device);
            let pipeline = compute_pipeline_with_layouts(
                device,
                SKIN_LABEL,
                &module,
                "main",
                &[Some(&layout)],
            );
            let bind_group = bind_buffers(
                device,
                SKIN_LABEL,
                &layout,
                &[
                    &uniforms.buffer,
                    &bind_positions,
                    &bind_normals,
                    &joints,
                    &weights,
                    &joint_matrices,
                    &mesh.positions,
                    &mesh.normals,
                    &non_finite,
                ],
            );
            (pipeline, bind_group)
        })?;
        Ok(Self {
            pipeline,
            bind_group,
            joint_matrices,
            non_finite,
            skin: skin.clone(),
            vertex_count: mesh.vertex_count,
            limits: gpu.limits().clone(),
        })
    }

    /// Writes the joint matrices of the next frame (one per joint, each a joint's world
    /// transform times its inverse bind matrix). A wrong count or a non-finite element is
    /// an error naming `skin.joint_matrices[i]`, and nothing is written.
    pub fn set_joint_matrices(&self, queue: &wgpu::Queue, matrices: &[Mat4]) -> crate::Result<()> {
        self.skin.check_matrices(matrices)?;
        pelage_gpu::write_storage(
            queue,
            "pelage skin joint matrices",
            &self.joint_matrices,
            matrices,
        )?;
        Ok(())
    }

    /// The joint-matrix buffer (`array<mat4x4<f32>>`, column-major, `STORAGE | COPY_DST`):
    /// an engine may write or copy its own matrices into it instead of
    /// [`MeshSkin::set_joint_matrices`] (unchecked: see [`MeshSkin::non_finite_vertices`]).
    pub fn joint_matrices(&self) -> &wgpu::Buffer {
        &self.joint_matrices
    }

    /// The skin (joints and weights as given; the GPU reads them normalised).
    pub fn skin(&self) -> &Skin {
        &self.skin
    }

    /// Records the skinning pass: clears the non-finite counter, then skins every vertex
    /// into the mesh buffers. Record it before the stage 1 pass of the frame.
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>) {
        encoder.clear_buffer(&self.non_finite, 0, None);
        let timestamp_writes = timer.and_then(|t| t.compute_pass(SKIN_LABEL));
        let mut compute = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(SKIN_LABEL),
            timestamp_writes,
        });
        compute.set_pipeline(&self.pipeline);
        pelage_gpu::set_bind_group(&mut compute, 0, &self.bind_group);
        let groups = dispatch_size(&self.limits, u64::from(self.vertex_count), WORKGROUP);
        compute.dispatch_workgroups(groups.0, groups.1, 1);
    }

    /// The pass [`MeshSkin::encode`] records: it writes [`MESH`].
    pub fn pass(&self) -> PassInfo {
        PassInfo::new(SKIN_LABEL).writes([MESH, SKIN_NON_FINITE])
    }

    /// The vertices the last frame run wrote at their bind pose because their skinned
    /// position or normal was not finite (a NaN or infinite matrix written straight into
    /// [`MeshSkin::joint_matrices`]). Waits for the GPU: for tests and diagnostics.
    pub fn non_finite_vertices(&self, gpu: &Gpu) -> crate::Result<u32> {
        let bytes = read_buffer(gpu, &self.non_finite)?;
        Ok(bytes
            .get(..4)
            .map_or(0, |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]])))
    }
}
