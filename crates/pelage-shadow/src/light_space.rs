//! The orthonormal frame of a directional light.

use glam::{Mat4, Vec3, Vec4};

/// Light space of a directional light: `x` and `y` across the light, `z` along
/// the direction the light travels (depth grows away from the light).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSpace {
    /// First axis across the light.
    pub x: Vec3,
    /// Second axis across the light.
    pub y: Vec3,
    /// Direction the light travels.
    pub z: Vec3,
}

impl LightSpace {
    /// The frame for a light whose unit direction towards the light is `to_light`.
    pub fn new(to_light: Vec3) -> Self {
        let z = -to_light.normalize_or(Vec3::NEG_Y);
        let up = if z.y.abs() < 0.99 { Vec3::Y } else { Vec3::X };
        let x = up.cross(z).normalize();
        let y = z.cross(x);
        Self { x, y, z }
    }

    /// Coordinates of world point `p` in this frame.
    pub fn project(&self, p: Vec3) -> Vec3 {
        Vec3::new(p.dot(self.x), p.dot(self.y), p.dot(self.z))
    }

    /// Light-space bounds of a world-space box.
    pub fn bounds_of(&self, min: Vec3, max: Vec3) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for i in 0..8 {
            let corner = Vec3::new(
                if i & 1 == 0 { min.x } else { max.x },
                if i & 2 == 0 { min.y } else { max.y },
                if i & 4 == 0 { min.z } else { max.z },
            );
            let p = self.project(corner);
            lo = lo.min(p);
            hi = hi.max(p);
        }
        (lo, hi)
    }

    /// Orthographic world-to-clip transform covering the light-space box `lo..hi`
    /// (x and y to [-1, 1], z to [0, 1]).
    pub fn orthographic(&self, lo: Vec3, hi: Vec3) -> Mat4 {
        let center = 0.5 * (lo + hi);
        let half = (0.5 * (hi - lo)).max(Vec3::splat(1e-6));
        let depth = (hi.z - lo.z).max(1e-6);
        Mat4::from_cols(
            Vec4::new(self.x.x / half.x, self.y.x / half.y, self.z.x / depth, 0.0),
            Vec4::new(self.x.y / half.x, self.y.y / half.y, self.z.y / depth, 0.0),
            Vec4::new(self.x.z / half.x, self.y.z / half.y, self.z.z / depth, 0.0),
            Vec4::new(-center.x / half.x, -center.y / half.y, -lo.z / depth, 1.0),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_is_orthonormal_for_every_direction() {
        for to_light in [Vec3::Y, Vec3::NEG_Y, Vec3::X, Vec3::new(-0.5, -0.8, -0.35)] {
            let f = LightSpace::new(to_light.normalize());
            assert!((f.x.length() - 1.0).abs() < 1e-5 && (f.y.length() - 1.0).abs() < 1e-5);
            assert!(
                f.x.dot(f.y).abs() < 1e-5 && f.x.dot(f.z).abs() < 1e-5 && f.y.dot(f.z).abs() < 1e-5
            );
            assert!((f.z + to_light.normalize()).length() < 1e-5);
        }
    }

    #[test]
    fn orthographic_maps_the_box_to_clip_space() {
        let f = LightSpace::new(Vec3::new(0.3, 0.8, -0.2).normalize());
        let (lo, hi) = f.bounds_of(Vec3::splat(-1.0), Vec3::splat(2.0));
        let m = f.orthographic(lo, hi);
        for corner in [
            Vec3::splat(-1.0),
            Vec3::splat(2.0),
            Vec3::new(-1.0, 2.0, -1.0),
        ] {
            let c = m.project_point3(corner);
            assert!(c.x.abs() <= 1.0 + 1e-5 && c.y.abs() <= 1.0 + 1e-5, "{c}");
            assert!((-1e-5..=1.0 + 1e-5).contains(&c.z), "{c}");
        }
        // Nearer the light = smaller depth.
        let near = m.project_point3(Vec3::splat(0.5) + f.z * -1.0).z;
        let far = m.project_point3(Vec3::splat(0.5) + f.z * 1.0).z;
        assert!(near < far);
    }
}
