//! Mirror of `wgsl/shadow/voxel_scan.wgsl`.

/// The exclusive prefix sum of one column of u32 fixed-point densities, saturating at
/// `u32::MAX`, converted to optical depth: `out[z] = (sum of densities[..z]) * inv_scale`.
pub fn exclusive_scan_column(densities: &[u32], inv_scale: f32) -> Vec<f32> {
    let mut running = 0u32;
    densities
        .iter()
        .map(|&d| {
            let out = running as f32 * inv_scale;
            running = running.saturating_add(d);
            out
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exclusive_and_saturating() {
        assert_eq!(exclusive_scan_column(&[2, 4, 8], 0.5), vec![0.0, 1.0, 3.0]);
        let s = exclusive_scan_column(&[u32::MAX - 1, 5, 7], 1.0);
        assert_eq!(s[2], u32::MAX as f32);
    }
}
