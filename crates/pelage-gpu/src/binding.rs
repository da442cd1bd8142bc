//! [`ShaderBinding`]: how one stage hands another a WGSL contract and the resources behind it.

use crate::shaders::{Redirect, ShaderSources};

/// One resource of a [`ShaderBinding`].
#[derive(Clone, Debug)]
pub enum BoundResource {
    /// A whole buffer.
    Buffer(wgpu::Buffer),
    /// A texture view.
    TextureView(wgpu::TextureView),
    /// A sampler.
    Sampler(wgpu::Sampler),
}

/// A WGSL module implementing a contract, plus the resources it binds.
///
/// The producer (say, a shadow method) names a file of its own crate's
/// [`ShaderSources`] that defines the contract's functions and declares its
/// resources at `@group(group)`, `@binding(i)` for the i-th entry of `resources`.
/// The consumer (say, the shading pass) redirects its import of the contract to
/// `module` with [`ShaderBinding::redirect`] (see
/// [`crate::ShaderLibrary::module_redirected`]; the redirect carries the producer's
/// sources, so the consumer's crate need not depend on the producer's) and builds
/// the bind group for that group from its own pipeline's layout with
/// [`ShaderBinding::bind_group`], so it never needs to know which producer it got.
#[derive(Clone, Debug)]
pub struct ShaderBinding {
    /// The contract file the consumer imports (e.g. `shadow/none.wgsl`).
    pub contract: &'static str,
    /// The file implementing it (e.g. `shadow/voxel_lookup.wgsl`).
    pub module: &'static str,
    /// The sources holding `module` and what it imports: the producer's crate's
    /// `SHADERS`.
    pub sources: &'static ShaderSources,
    /// The bind group index `module` declares its resources in.
    pub group: u32,
    /// The resources, binding `i` = `resources[i]`.
    pub resources: Vec<BoundResource>,
}

impl ShaderBinding {
    /// The import redirect a consumer passes to the shader library: `contract`
    /// read as `module`, found in `sources`.
    pub fn redirect(&self) -> Redirect {
        Redirect::to_sources(self.contract, self.module, self.sources)
    }

    /// A bind group for `layout` (the consumer's `get_bind_group_layout(self.group)`),
    /// or `None` when the module binds nothing.
    pub fn bind_group(
        &self,
        device: &wgpu::Device,
        label: &str,
        layout: &wgpu::BindGroupLayout,
    ) -> Option<wgpu::BindGroup> {
        if self.resources.is_empty() {
            return None;
        }
        let entries: Vec<wgpu::BindGroupEntry<'_>> = self
            .resources
            .iter()
            .enumerate()
            .map(|(i, r)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: match r {
                    BoundResource::Buffer(b) => b.as_entire_binding(),
                    BoundResource::TextureView(v) => wgpu::BindingResource::TextureView(v),
                    BoundResource::Sampler(s) => wgpu::BindingResource::Sampler(s),
                },
            })
            .collect();
        Some(crate::counters::create_bind_group(
            device,
            &wgpu::BindGroupDescriptor {
                label: Some(label),
                layout,
                entries: &entries,
            },
        ))
    }
}
