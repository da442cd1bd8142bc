//! The mesh as the GPU sees it: storage buffers an engine can own.

use pelage_gpu::{Gpu, wgpu};
use pelage_scene::Mesh;

use crate::{ContractError, Result};

/// The frame resource naming the [`MeshBuffers`], which the caller may rewrite every frame.
pub const MESH: &str = "mesh";

/// A triangle mesh in storage buffers.
///
/// `positions` and `normals` hold tightly packed `f32 x3` (12 bytes per vertex),
/// `indices` a `u32` triangle list. Every stage reads them as
/// `array<f32>` / `array<u32>` storage; the opaque pass also pulls its vertices
/// from them, so nothing needs vertex buffers.
#[derive(Debug)]
pub struct MeshBuffers {
    /// Vertex positions, `f32 x3` each.
    pub positions: wgpu::Buffer,
    /// Vertex normals, `f32 x3` each (need not be normalised).
    pub normals: wgpu::Buffer,
    /// Triangle list, three `u32` per triangle.
    pub indices: wgpu::Buffer,
    /// Number of vertices.
    pub vertex_count: u32,
    /// Number of triangles.
    pub triangle_count: u32,
    /// A world box the mesh stays in (every pose, for a skinned mesh): shadow maps of
    /// the mesh cover it.
    pub bounds: (glam::Vec3, glam::Vec3),
}

impl MeshBuffers {
    /// Uploads a validated mesh. Buffers get `STORAGE | COPY_DST | COPY_SRC` so they can be rewritten per frame.
    pub fn upload(gpu: &Gpu, mesh: &Mesh) -> Result<Self> {
        mesh.validate()?;
        let positions: Vec<f32> = mesh.positions.iter().flat_map(|p| p.to_array()).collect();
        let normals: Vec<f32> = mesh.normals.iter().flat_map(|n| n.to_array()).collect();
        let usage = wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_DST
            | wgpu::BufferUsages::COPY_SRC;
        for (what, bytes) in [
            ("mesh positions", positions.len() * 4),
            ("mesh indices", mesh.indices.len() * 4),
        ] {
            gpu.check_storage_size(what, bytes as u64)?;
        }
        let make = |label: &str, contents: &[u8]| {
            pelage_gpu::create_buffer_init(
                &gpu.device,
                &wgpu::util::BufferInitDescriptor {
                    label: Some(label),
                    contents,
                    usage,
                },
            )
        };
        Ok(Self {
            positions: make("pelage mesh positions", bytemuck::cast_slice(&positions)),
            normals: make("pelage mesh normals", bytemuck::cast_slice(&normals)),
            indices: make("pelage mesh indices", bytemuck::cast_slice(&mesh.indices)),
            vertex_count: mesh.positions.len() as u32,
            bounds: mesh.bounds(),
            triangle_count: (mesh.indices.len() / 3) as u32,
        })
    }

    /// Wraps buffers the caller owns. They must hold `vertex_count` `f32 x3`
    /// positions and normals and `triangle_count` `u32 x3` triangles, and have `STORAGE`
    /// usage; `bounds` is a world box the mesh stays in, in every pose the caller will
    /// write (finite, min <= max).
    pub fn from_buffers(
        positions: wgpu::Buffer,
        normals: wgpu::Buffer,
        indices: wgpu::Buffer,
        vertex_count: u32,
        triangle_count: u32,
        bounds: (glam::Vec3, glam::Vec3),
    ) -> Result<Self> {
        if !(bounds.0.is_finite() && bounds.1.is_finite() && bounds.0.cmple(bounds.1).all()) {
            return Err(pelage_scene::ParamError::new(
                "mesh.bounds",
                bounds,
                "must be a finite box with min <= max",
            )
            .into());
        }
        let need = |what: &str, buf: &wgpu::Buffer, bytes: u64| -> Result<()> {
            if buf.size() < bytes || !buf.usage().contains(wgpu::BufferUsages::STORAGE) {
                return Err(ContractError::MeshMismatch {
                    buffers: format!("{what}: {} bytes, usage {:?}", buf.size(), buf.usage()),
                    mesh: format!("needs at least {bytes} bytes with STORAGE usage"),
                });
            }
            Ok(())
        };
        need("positions", &positions, u64::from(vertex_count) * 12)?;
        need("normals", &normals, u64::from(vertex_count) * 12)?;
        need("indices", &indices, u64::from(triangle_count) * 12)?;
        Ok(Self {
            positions,
            normals,
            indices,
            vertex_count,
            triangle_count,
            bounds,
        })
    }

    /// Errors unless the buffers hold as many vertices and triangles as `mesh` (the CPU
    /// mesh roots are sampled on).
    pub fn check_matches(&self, mesh: &Mesh) -> Result<()> {
        if self.vertex_count as usize != mesh.positions.len()
            || self.triangle_count as usize != mesh.indices.len() / 3
        {
            return Err(ContractError::MeshMismatch {
                buffers: format!(
                    "{} vertices, {} triangles",
                    self.vertex_count, self.triangle_count
                ),
                mesh: format!(
                    "{} vertices, {} triangles",
                    mesh.positions.len(),
                    mesh.indices.len() / 3
                ),
            });
        }
        Ok(())
    }

    /// Rewrites positions and normals (same vertex count), e.g. after skinning on the CPU.
    pub fn update(&self, queue: &wgpu::Queue, mesh: &Mesh) -> Result<()> {
        if mesh.positions.len() != self.vertex_count as usize
            || mesh.normals.len() != mesh.positions.len()
        {
            return Err(ContractError::MeshMismatch {
                buffers: format!("{} vertices", self.vertex_count),
                mesh: format!(
                    "{} positions, {} normals",
                    mesh.positions.len(),
                    mesh.normals.len()
                ),
            });
        }
        let positions: Vec<f32> = mesh.positions.iter().flat_map(|p| p.to_array()).collect();
        let normals: Vec<f32> = mesh.normals.iter().flat_map(|n| n.to_array()).collect();
        queue.write_buffer(&self.positions, 0, bytemuck::cast_slice(&positions));
        queue.write_buffer(&self.normals, 0, bytemuck::cast_slice(&normals));
        Ok(())
    }
}
