//! [`ShaderBinding`]: how one stage hands another a WGSL contract and the resources behind it.

use crate::shaders::{Redirect, ShaderSources};

/// One resource of a [`ShaderBinding`], with the binding type its WGSL declares
/// (so a consumer can build the group's layout from the producer's declaration,
/// [`ShaderBinding::layout_entries`]).
#[derive(Clone, Debug)]
pub enum BoundResource {
    /// A whole buffer declared `var<uniform>`.
    Uniform(wgpu::Buffer),
    /// A whole buffer declared `var<storage, read>`.
    Storage(wgpu::Buffer),
    /// A view of a single-sampled 2D texture declared with this sample type
    /// (`texture_depth_2d`: [`wgpu::TextureSampleType::Depth`]; `texture_2d<f32>`:
    /// [`wgpu::TextureSampleType::Float`]).
    Texture(wgpu::TextureView, wgpu::TextureSampleType),
    /// A sampler of this kind (`sampler_comparison`:
    /// [`wgpu::SamplerBindingType::Comparison`]).
    Sampler(wgpu::Sampler, wgpu::SamplerBindingType),
}

impl BoundResource {
    /// The buffer, for [`BoundResource::Uniform`] and [`BoundResource::Storage`].
    pub fn buffer(&self) -> Option<&wgpu::Buffer> {
        match self {
            Self::Uniform(b) | Self::Storage(b) => Some(b),
            _ => None,
        }
    }

    /// The layout binding type this resource is declared with.
    pub fn binding_type(&self) -> wgpu::BindingType {
        match self {
            Self::Uniform(_) => crate::pipelines::buffer_type(wgpu::BufferBindingType::Uniform),
            Self::Storage(_) => {
                crate::pipelines::buffer_type(wgpu::BufferBindingType::Storage { read_only: true })
            }
            Self::Texture(_, sample_type) => crate::pipelines::texture_2d_type(*sample_type),
            Self::Sampler(_, kind) => wgpu::BindingType::Sampler(*kind),
        }
    }

    /// The resource as a bind group entry's.
    pub fn as_binding(&self) -> wgpu::BindingResource<'_> {
        match self {
            Self::Uniform(b) | Self::Storage(b) => b.as_entire_binding(),
            Self::Texture(v, _) => wgpu::BindingResource::TextureView(v),
            Self::Sampler(s, _) => wgpu::BindingResource::Sampler(s),
        }
    }
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
/// that group's layout from the producer's declaration ([`ShaderBinding::layout`])
/// and the bind group against it ([`ShaderBinding::bind_group`]), so it never needs
/// to know which producer it got.
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
    /// The frame resources among them, by the names a [`crate::FramePlan`] gives them
    /// (`shadow.grid`, `volume.fluence`, ...): what a pass binding the module declares it
    /// reads ([`crate::PassInfo::reads`]). Uniforms, samplers and data written once at
    /// build are not frame resources and not listed.
    pub reads: Vec<String>,
}

impl ShaderBinding {
    /// The import redirect a consumer passes to the shader library: `contract`
    /// read as `module`, found in `sources`.
    pub fn redirect(&self) -> Redirect {
        Redirect::to_sources(self.contract, self.module, self.sources)
    }

    /// The layout entries of group `group` as the resources declare them (binding `i`
    /// of `resources[i]`), visible to `visibility`.
    pub fn layout_entries(
        &self,
        visibility: wgpu::ShaderStages,
    ) -> Vec<wgpu::BindGroupLayoutEntry> {
        self.resources
            .iter()
            .enumerate()
            .map(|(i, r)| wgpu::BindGroupLayoutEntry {
                binding: i as u32,
                visibility,
                ty: r.binding_type(),
                count: None,
            })
            .collect()
    }

    /// The layout of group `group` ([`ShaderBinding::layout_entries`]) created on
    /// `device`, or `None` when the module binds nothing (the group is then left out
    /// of the consumer's pipeline layout, see [`ShaderBinding::place`]).
    pub fn layout(
        &self,
        device: &wgpu::Device,
        label: &str,
        visibility: wgpu::ShaderStages,
    ) -> Option<wgpu::BindGroupLayout> {
        if self.resources.is_empty() {
            return None;
        }
        Some(
            crate::BindLayout::new(label, visibility)
                .entries(self.layout_entries(visibility))
                .build(device),
        )
    }

    /// Puts `layout` (normally [`ShaderBinding::layout`]'s) at index `group` of a
    /// consumer's pipeline `layouts`, growing it with `None`s as needed.
    pub fn place<'a>(
        &self,
        layouts: &mut Vec<Option<&'a wgpu::BindGroupLayout>>,
        layout: Option<&'a wgpu::BindGroupLayout>,
    ) {
        let group = self.group as usize;
        if layouts.len() <= group {
            layouts.resize(group + 1, None);
        }
        layouts[group] = layout;
    }

    /// A bind group for `layout` (normally [`ShaderBinding::layout`]'s), or `None`
    /// when the module binds nothing.
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
                resource: r.as_binding(),
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
