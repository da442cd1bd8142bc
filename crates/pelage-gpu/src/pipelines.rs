//! Small helpers every stage uses to build pipelines and bind groups.
//!
//! Library pipelines use explicit layouts: each bind group layout is written with
//! [`BindLayout`] next to the WGSL declaring it, and the pipeline is built from those
//! layouts ([`compute_pipeline_with_layouts`], or [`pipeline_layout`] for a render
//! pipeline), so the bind groups are created against layouts that exist before, and
//! independently of, any pipeline. [`compute_pipeline`] (an automatic layout) is left
//! for tools and benchmarks.

/// A bind group layout written entry by entry, in the style of the WGSL it matches.
///
/// Each method adds one entry at `binding`, visible to the stages last given to
/// [`BindLayout::new`] or [`BindLayout::visible`]. Buffers are whole-buffer bindings
/// without dynamic offsets or a minimum size; textures are single-sampled 2D.
///
/// ```ignore
/// // @group(0) @binding(0) var<uniform> u: U;
/// // @group(0) @binding(1) var<storage, read> input: array<f32>;
/// // @group(0) @binding(2) var<storage, read_write> output: array<f32>;
/// let layout = BindLayout::new("my pass", wgpu::ShaderStages::COMPUTE)
///     .uniform(0)
///     .storage(1)
///     .storage_rw(2)
///     .build(device);
/// ```
///
/// A mismatch with the shader (a uniform declared as storage, a depth texture declared
/// as float, a stage missing from the visibility) is a validation error when the
/// pipeline is created.
#[derive(Clone, Debug)]
pub struct BindLayout {
    label: String,
    visibility: wgpu::ShaderStages,
    entries: Vec<wgpu::BindGroupLayoutEntry>,
}

impl BindLayout {
    /// An empty layout named `label` whose entries are visible to `visibility`.
    pub fn new(label: &str, visibility: wgpu::ShaderStages) -> Self {
        Self {
            label: label.to_string(),
            visibility,
            entries: Vec::new(),
        }
    }

    /// Entries added from now on are visible to `visibility` (e.g. writable storage,
    /// which a vertex stage may not see).
    pub fn visible(mut self, visibility: wgpu::ShaderStages) -> Self {
        self.visibility = visibility;
        self
    }

    /// Adds an entry of type `ty` at `binding`.
    pub fn entry(mut self, binding: u32, ty: wgpu::BindingType) -> Self {
        self.entries.push(wgpu::BindGroupLayoutEntry {
            binding,
            visibility: self.visibility,
            ty,
            count: None,
        });
        self
    }

    /// Adds ready-made entries (e.g. [`crate::ShaderBinding::layout_entries`]), keeping
    /// their own visibility.
    pub fn entries(
        mut self,
        entries: impl IntoIterator<Item = wgpu::BindGroupLayoutEntry>,
    ) -> Self {
        self.entries.extend(entries);
        self
    }

    /// `var<uniform>` at `binding`.
    pub fn uniform(self, binding: u32) -> Self {
        self.entry(binding, buffer_type(wgpu::BufferBindingType::Uniform))
    }

    /// `var<storage, read>` at `binding`.
    pub fn storage(self, binding: u32) -> Self {
        self.entry(
            binding,
            buffer_type(wgpu::BufferBindingType::Storage { read_only: true }),
        )
    }

    /// `var<storage, read_write>` at `binding`.
    pub fn storage_rw(self, binding: u32) -> Self {
        self.entry(
            binding,
            buffer_type(wgpu::BufferBindingType::Storage { read_only: false }),
        )
    }

    /// A 2D texture at `binding`: `texture_2d<f32>` is
    /// [`wgpu::TextureSampleType::Float`] (filterable when a filtering sampler samples
    /// it), `texture_depth_2d` is [`wgpu::TextureSampleType::Depth`] (see
    /// [`BindLayout::depth_2d`]).
    pub fn texture_2d(self, binding: u32, sample_type: wgpu::TextureSampleType) -> Self {
        self.entry(binding, texture_2d_type(sample_type))
    }

    /// `texture_depth_2d` at `binding`.
    pub fn depth_2d(self, binding: u32) -> Self {
        self.texture_2d(binding, wgpu::TextureSampleType::Depth)
    }

    /// A sampler at `binding`: `sampler_comparison` is
    /// [`wgpu::SamplerBindingType::Comparison`].
    pub fn sampler(self, binding: u32, kind: wgpu::SamplerBindingType) -> Self {
        self.entry(binding, wgpu::BindingType::Sampler(kind))
    }

    /// The entries so far.
    pub fn layout_entries(&self) -> &[wgpu::BindGroupLayoutEntry] {
        &self.entries
    }

    /// Creates the layout on `device`.
    pub fn build(&self, device: &wgpu::Device) -> wgpu::BindGroupLayout {
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(&self.label),
            entries: &self.entries,
        });
        crate::audit::layout_created(&layout, &self.entries);
        layout
    }
}

/// A whole-buffer binding type of `ty`.
pub(crate) fn buffer_type(ty: wgpu::BufferBindingType) -> wgpu::BindingType {
    wgpu::BindingType::Buffer {
        ty,
        has_dynamic_offset: false,
        min_binding_size: None,
    }
}

/// A single-sampled 2D texture binding type of `sample_type`.
pub(crate) fn texture_2d_type(sample_type: wgpu::TextureSampleType) -> wgpu::BindingType {
    wgpu::BindingType::Texture {
        sample_type,
        view_dimension: wgpu::TextureViewDimension::D2,
        multisampled: false,
    }
}

/// A pipeline layout of `layouts`, group `i` = `layouts[i]` (`None` for a group the
/// pipeline does not use). For render pipelines: pass it as their `layout`.
pub fn pipeline_layout(
    device: &wgpu::Device,
    label: &str,
    layouts: &[Option<&wgpu::BindGroupLayout>],
) -> wgpu::PipelineLayout {
    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: layouts,
        immediate_size: 0,
    })
}

/// A compute pipeline for `entry` of `module` with the explicit bind group `layouts`
/// (group `i` = `layouts[i]`; see [`pipeline_layout`]).
pub fn compute_pipeline_with_layouts(
    device: &wgpu::Device,
    label: &str,
    module: &wgpu::ShaderModule,
    entry: &str,
    layouts: &[Option<&wgpu::BindGroupLayout>],
) -> wgpu::ComputePipeline {
    compute_pipeline_with_constants(device, label, module, entry, layouts, &[])
}

/// As [`compute_pipeline_with_layouts`], with values for the module's pipeline-overridable
/// constants (`override NAME: T;` in WGSL, e.g. a workgroup size), by name.
pub fn compute_pipeline_with_constants(
    device: &wgpu::Device,
    label: &str,
    module: &wgpu::ShaderModule,
    entry: &str,
    layouts: &[Option<&wgpu::BindGroupLayout>],
    constants: &[(&str, f64)],
) -> wgpu::ComputePipeline {
    let layout = pipeline_layout(device, label, layouts);
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(label),
        layout: Some(&layout),
        module,
        entry_point: Some(entry),
        compilation_options: wgpu::PipelineCompilationOptions {
            constants,
            ..Default::default()
        },
        cache: None,
    })
}

/// A compute pipeline with an automatic layout for `entry` of `module` (for tools and
/// benchmarks; the library's stages use [`compute_pipeline_with_layouts`]).
pub fn compute_pipeline(
    device: &wgpu::Device,
    label: &str,
    module: &wgpu::ShaderModule,
    entry: &str,
) -> wgpu::ComputePipeline {
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(label),
        layout: None,
        module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
        cache: None,
    })
}

/// A bind group for `layout` whose binding `i` is the whole of `buffers[i]`.
pub fn bind_buffers(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    buffers: &[&wgpu::Buffer],
) -> wgpu::BindGroup {
    let numbered: Vec<(u32, &wgpu::Buffer)> = buffers
        .iter()
        .enumerate()
        .map(|(i, b)| (i as u32, *b))
        .collect();
    bind_numbered(device, label, layout, &numbered)
}

/// A bind group for `layout` binding whole buffers at the given binding numbers
/// (for an entry point that uses only some of its module's bindings).
pub fn bind_numbered(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    buffers: &[(u32, &wgpu::Buffer)],
) -> wgpu::BindGroup {
    let entries: Vec<_> = buffers
        .iter()
        .map(|(binding, b)| wgpu::BindGroupEntry {
            binding: *binding,
            resource: b.as_entire_binding(),
        })
        .collect();
    crate::counters::create_bind_group(
        device,
        &wgpu::BindGroupDescriptor {
            label: Some(label),
            layout,
            entries: &entries,
        },
    )
}

/// Workgroup counts `(x, y)` covering `invocations` with groups of `group_size`,
/// folding into y when x would pass the device's per-dimension limit. Shaders
/// recover the flat index as `gid.y * num_workgroups.x * group_size + gid.x`.
pub fn dispatch_size(limits: &wgpu::Limits, invocations: u64, group_size: u32) -> (u32, u32) {
    let groups = invocations.div_ceil(u64::from(group_size.max(1)));
    let max_x = u64::from(limits.max_compute_workgroups_per_dimension.max(1));
    let x = groups.clamp(1, max_x);
    let y = groups.div_ceil(x).max(1);
    (x as u32, u32::try_from(y).unwrap_or(u32::MAX))
}
