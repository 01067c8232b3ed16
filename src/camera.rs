//! A pinhole camera: eye, target, up and a vertical field of view.
//!
//! Pixel `(x, y)` (y down, as in images) covers the square `[x, x+1) × [y, y+1)` of the image
//! plane; the 2D sample `u` places the ray inside it, so the pixel filter is a box and a pixel's
//! value is the average radiance over its area. Right-handed: image right is `forward × up`.

use glam::{UVec2, Vec2, Vec3};

/// The camera's placement, as written in `scene.toml`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraDesc {
    pub eye: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub fov_deg: f32,
}

/// A camera set up for an image size, ready to generate rays.
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    eye: Vec3,
    forward: Vec3,
    /// Image right, scaled to the half-width of the image plane at distance 1.
    right: Vec3,
    /// Image up, scaled to the half-height of the image plane at distance 1.
    up: Vec3,
    inv_size: Vec2,
}

impl Camera {
    /// Set up `desc` for a `width × height` image; `None` if the placement is degenerate
    /// (eye at target, up parallel to the view direction, fov outside (0°, 180°)).
    pub fn new(desc: &CameraDesc, width: u32, height: u32) -> Option<Camera> {
        let forward = (desc.target - desc.eye).try_normalize()?;
        let right = forward.cross(desc.up).try_normalize()?;
        let up = right.cross(forward);
        if !(desc.fov_deg > 0.0 && desc.fov_deg < 180.0) || width == 0 || height == 0 {
            return None;
        }
        let half_h = (desc.fov_deg.to_radians() * 0.5).tan();
        let half_w = half_h * width as f32 / height as f32;
        Some(Camera {
            eye: desc.eye,
            forward,
            right: right * half_w,
            up: up * half_h,
            inv_size: Vec2::new(1.0 / width as f32, 1.0 / height as f32),
        })
    }

    /// The ray through `pixel + u` (u ∈ [0,1)²): origin and unit direction.
    #[inline]
    pub fn generate_ray(&self, pixel: UVec2, u: Vec2) -> (Vec3, Vec3) {
        let p = (pixel.as_vec2() + u) * self.inv_size; // [0,1)², y down
        let sx = 2.0 * p.x - 1.0;
        let sy = 1.0 - 2.0 * p.y;
        let d = self.forward + self.right * sx + self.up * sy;
        (self.eye, d.normalize())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_ray_looks_at_target_and_right_is_right() {
        let desc = CameraDesc {
            eye: Vec3::new(0.0, 0.0, 5.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_deg: 90.0,
        };
        let cam = Camera::new(&desc, 2, 2).unwrap();
        let (_, d) = cam.generate_ray(UVec2::new(1, 1), Vec2::ZERO);
        assert!((d - Vec3::NEG_Z).length() < 1e-6);
        // The right edge of the image, middle row: 45° to the right, i.e. toward +x.
        let (_, d) = cam.generate_ray(UVec2::new(1, 1), Vec2::new(1.0, 0.0));
        assert!((d - Vec3::new(1.0, 0.0, -1.0).normalize()).length() < 1e-6);
        // Top row looks up.
        let (_, d) = cam.generate_ray(UVec2::new(1, 0), Vec2::new(0.0, 0.0));
        assert!((d - Vec3::new(0.0, 1.0, -1.0).normalize()).length() < 1e-6);
        assert!(Camera::new(
            &CameraDesc {
                up: Vec3::NEG_Z,
                ..desc
            },
            2,
            2
        )
        .is_none());
    }
}
