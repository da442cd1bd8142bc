//! Mirror of `wgsl/shared/noise.wgsl`.

use glam::{IVec3, Vec3};

/// `pcg_hash` in WGSL: the PCG hash of Jarzynski and Olano 2020 (the mirror's own copy, so
/// that a change to pelage-strands' CPU hash cannot hide a change to the shader's).
pub fn pcg_hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// `hash_to_unit` in WGSL: a float in [0, 1) from the top 24 bits of `h`.
pub fn hash_to_unit(h: u32) -> f32 {
    (h >> 8) as f32 / 16_777_216.0
}

/// `hash_cell` in WGSL.
pub fn hash_cell(c: IVec3, seed: u32) -> u32 {
    pcg_hash((c.x as u32) ^ pcg_hash((c.y as u32) ^ pcg_hash((c.z as u32) ^ seed)))
}

/// `fade` in WGSL: quintic C2 weight.
pub fn fade(t: f32) -> f32 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

/// WGSL `mix`: `a * (1 - t) + b * t`.
pub fn mix(a: f32, b: f32, t: f32) -> f32 {
    a * (1.0 - t) + b * t
}

/// `value_noise_1d` in WGSL.
pub fn value_noise_1d(x: f32, seed: u32) -> f32 {
    let i = x.floor();
    let f = x - i;
    let c = i as i32;
    let a = hash_to_unit(pcg_hash((c as u32) ^ seed));
    let b = hash_to_unit(pcg_hash((c.wrapping_add(1) as u32) ^ seed));
    mix(a, b, fade(f)) * 2.0 - 1.0
}

/// `value_noise_3d` in WGSL.
pub fn value_noise_3d(p: Vec3, seed: u32) -> f32 {
    let i = p.floor();
    let f = p - i;
    let c = IVec3::new(i.x as i32, i.y as i32, i.z as i32);
    let u = Vec3::new(fade(f.x), fade(f.y), fade(f.z));
    let n = |dx: i32, dy: i32, dz: i32| hash_to_unit(hash_cell(c + IVec3::new(dx, dy, dz), seed));
    let x00 = mix(n(0, 0, 0), n(1, 0, 0), u.x);
    let x10 = mix(n(0, 1, 0), n(1, 1, 0), u.x);
    let x01 = mix(n(0, 0, 1), n(1, 0, 1), u.x);
    let x11 = mix(n(0, 1, 1), n(1, 1, 1), u.x);
    let y0 = mix(x00, x10, u.y);
    let y1 = mix(x01, x11, u.y);
    mix(y0, y1, u.z) * 2.0 - 1.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_hashes_keep_their_known_values() {
        // The PCG hash of Jarzynski and Olano 2020, computed by a separate implementation
        // (Python, arbitrary-precision integers masked to 32 bits).
        for (v, h) in [
            (0, 129_708_002),
            (1, 2_831_084_092),
            (42, 1_223_963_391),
            (0xdead_beef, 1_730_779_506),
            (u32::MAX, 3_861_530_882),
        ] {
            assert_eq!(pcg_hash(v), h, "pcg_hash({v})");
        }
        assert_eq!(hash_to_unit(129_708_002), 506_671.0 / 16_777_216.0);
        assert_eq!(hash_to_unit(u32::MAX), 1.0 - 1.0 / 16_777_216.0);
        assert_eq!(hash_to_unit(255), 0.0);
    }

    #[test]
    fn noise_is_bounded_and_continuous() {
        let mut prev = value_noise_3d(Vec3::ZERO, 7);
        for k in 1..10_000 {
            let p = Vec3::new(k as f32 * 1e-3, k as f32 * 7e-4, -(k as f32) * 3e-4);
            let v = value_noise_3d(p, 7);
            assert!((-1.0..=1.0).contains(&v));
            assert!((v - prev).abs() < 0.02, "jump at {p}");
            prev = v;
        }
    }
}
