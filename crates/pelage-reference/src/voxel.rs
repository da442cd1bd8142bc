//! Mirror of `wgsl/shadow/voxel_scan.wgsl` and of the front keys of
//! `wgsl/shadow/light_common.wgsl`.

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

/// The key the splat keeps (by `atomicMax`) for a column whose density begins at `start`
/// (grid units along the light): the complement of the depth in 16.16 fixed point, so
/// the least depth wins and an empty column keeps 0.
pub fn front_key(start: f32) -> u32 {
    u32::MAX - (start.clamp(0.0, 32768.0) * 65536.0) as u32
}

/// The depth a front key stands for (what the scan writes), `empty` for an empty column.
pub fn front_of_key(key: u32, empty: f32) -> f32 {
    if key == 0 {
        empty
    } else {
        (u32::MAX - key) as f32 / 65536.0
    }
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

    #[test]
    fn the_least_front_wins_and_round_trips() {
        let keys = [front_key(3.25), front_key(0.5), front_key(7.0)];
        let kept = keys.into_iter().max().unwrap();
        assert_eq!(front_of_key(kept, 99.0), 0.5);
        assert_eq!(front_of_key(front_key(-1.0), 99.0), 0.0);
        assert_eq!(front_of_key(0, 99.0), 99.0);
        assert!((front_of_key(front_key(511.123), 0.0) - 511.123).abs() < 1.0 / 65536.0);
    }
}
