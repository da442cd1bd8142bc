//! Small helpers every stage uses to build pipelines and bind groups.

/// A compute pipeline with an automatic layout for `entry` of `module`.
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
