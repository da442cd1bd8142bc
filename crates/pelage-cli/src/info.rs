//! `pelage info`: the adapter, the optional features pelage uses, and the limits that
//! bound what it can render.

use pelage::gpu::{Gpu, wgpu};
use pelage::scene::Named;

use crate::error::CliError;

/// The optional features pelage asks for ([`pelage::gpu::WANTED_FEATURES`], which a test
/// keeps equal to this list) and what each one enables. A device made by [`Gpu::headless`] has exactly those of these the
/// adapter offers.
const FEATURES: &[(wgpu::Features, &str, &str)] = &[
    (
        wgpu::Features::TIMESTAMP_QUERY,
        "TIMESTAMP_QUERY",
        "GPU time per pass (render, animate, labs)",
    ),
    (
        wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS,
        "TIMESTAMP_QUERY_INSIDE_ENCODERS",
        "timing between passes",
    ),
    (
        wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES,
        "TIMESTAMP_QUERY_INSIDE_PASSES",
        "timing inside passes",
    ),
    (
        wgpu::Features::FLOAT32_BLENDABLE,
        "FLOAT32_BLENDABLE",
        "deep opacity maps with float32 layers",
    ),
    (
        wgpu::Features::SHADER_INT64,
        "SHADER_INT64",
        "64-bit fragment slots (k-buffer, random subsets)",
    ),
    (
        wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX,
        "SHADER_INT64_ATOMIC_MIN_MAX",
        "random subsets (--oit random_subsets)",
    ),
    (
        wgpu::Features::SHADER_INT64_ATOMIC_ALL_OPS,
        "SHADER_INT64_ATOMIC_ALL_OPS",
        "the k-buffer (--oit k_buffer)",
    ),
];

/// Bytes of one strand vertex (`vec4<f32>`).
const VERTEX_BYTES: u64 = 16;
/// Bytes per k-buffer slot and per A-buffer / DBK node.
const SLOT_BYTES: u64 = 8;
const NODE_BYTES: u64 = 16;

fn mib(bytes: u64) -> String {
    format!("{:.0} MiB", bytes as f64 / (1024.0 * 1024.0))
}

/// Prints what `Gpu::headless` finds.
pub fn run() -> Result<(), CliError> {
    let gpu = Gpu::headless()?;
    println!("adapter");
    match &gpu.adapter_info {
        Some(info) => {
            println!("  name         {}", info.name);
            println!("  backend      {:?}", info.backend);
            println!("  device type  {:?}", info.device_type);
            let driver = match (info.driver.is_empty(), info.driver_info.is_empty()) {
                (true, true) => "unknown".to_string(),
                (false, true) => info.driver.clone(),
                (true, false) => info.driver_info.clone(),
                (false, false) => format!("{} ({})", info.driver, info.driver_info),
            };
            println!("  driver       {driver}");
            println!(
                "  vendor       {:#06x}, device {:#06x}",
                info.vendor, info.device
            );
        }
        None => println!("  unknown"),
    }
    println!("  (WGPU_BACKEND=vulkan|gl|metal|dx12 picks another backend)");

    let features = gpu.features();
    println!("features pelage uses");
    for (feature, name, purpose) in FEATURES {
        let present = if features.contains(*feature) {
            "yes"
        } else {
            "no "
        };
        println!("  {present}  {name:<32} {purpose}");
    }

    let limits = gpu.limits();
    // Every per-pixel and per-vertex buffer is one storage binding.
    let binding = limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size);
    println!("limits");
    println!(
        "  max_storage_buffer_binding_size     {:>12} ({})",
        limits.max_storage_buffer_binding_size,
        mib(limits.max_storage_buffer_binding_size)
    );
    println!(
        "  max_buffer_size                     {:>12} ({})",
        limits.max_buffer_size,
        mib(limits.max_buffer_size)
    );
    println!(
        "  max_texture_dimension_2d            {:>12}",
        limits.max_texture_dimension_2d
    );
    println!(
        "  max_compute_workgroups_per_dimension {:>11}",
        limits.max_compute_workgroups_per_dimension
    );
    println!(
        "  max_compute_invocations_per_workgroup {:>10}",
        limits.max_compute_invocations_per_workgroup
    );
    println!(
        "  max_storage_buffers_per_shader_stage {:>11}",
        limits.max_storage_buffers_per_shader_stage
    );
    println!(
        "  max_bind_groups                     {:>12}",
        limits.max_bind_groups
    );

    println!("what that means");
    let root_bytes = {
        use pelage::gpu::encase::ShaderType;
        pelage::strands::StrandRoot::min_size().get()
    };
    let vertices = binding / VERTEX_BYTES;
    println!(
        "  strand vertices in one buffer: {vertices} ({} strands of 8 segments, {} of 16)",
        vertices / 9,
        vertices / 17
    );
    println!(
        "  strand roots in one buffer: {} ({root_bytes} B each)",
        binding / root_bytes
    );
    // n x n x (n + 1) cells of 4 bytes (the extra layer holds the column totals).
    let cells = binding / 4;
    let mut n = (cells as f64).cbrt().floor() as u64;
    while n > 1 && n * n * (n + 1) > cells {
        n -= 1;
    }
    println!("  largest cubic voxel grid: {n}³ (4 B a cell; scene files allow up to 512)");
    let (w, h) = (1920u64, 1080u64);
    let k = binding / (w * h * SLOT_BYTES);
    if k == 0 {
        println!("  k-buffer at 1920x1080: sliced for any k");
    } else {
        println!(
            "  largest k-buffer at 1920x1080 without slicing: k = {k} (larger k is drawn in \
             horizontal slices)"
        );
    }
    println!(
        "  A-buffer / DBK pool: {} nodes of {NODE_BYTES} B ({:.1} per pixel at 1920x1080 without slicing)",
        binding / NODE_BYTES,
        (binding / NODE_BYTES) as f64 / (w * h) as f64
    );
    println!(
        "  largest image, shadow map or deep opacity map side: {} px",
        limits.max_texture_dimension_2d
    );
    let available = pelage::shade::supported_methods(&gpu);
    let missing: Vec<&str> = pelage::scene::Transparency::NAMES
        .iter()
        .map(|m| m.name)
        .filter(|name| !available.contains(name))
        .collect();
    if missing.is_empty() {
        println!("  every transparency method is available");
    } else {
        println!(
            "  not available on this adapter: --oit {} (these work: {})",
            missing.join(", "),
            available.join(", ")
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_feature_list_is_what_pelage_requests() {
        let listed = FEATURES
            .iter()
            .fold(wgpu::Features::empty(), |all, (f, _, _)| all | *f);
        assert_eq!(listed, pelage::gpu::WANTED_FEATURES);
    }
}
