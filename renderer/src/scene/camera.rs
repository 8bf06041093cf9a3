//! The pinhole camera and the per-frame uniforms derived from it.
//!
//! Matrices are built in f64 and rounded once to f32, so debug and release builds feed the GPU
//! the same bits (LAVAPIPE.md: a constant-folded `tan` once differed by an ulp between them).

use glam::{DMat4, DVec3, DVec4};

use super::Lighting;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    pub position: DVec3,
    /// Viewing direction; need not be normalized.
    pub forward: DVec3,
    pub up: DVec3,
    /// Vertical field of view in radians.
    pub fov_y: f64,
    pub near: f64,
    pub far: f64,
}

impl Camera {
    pub fn look_at(position: DVec3, target: DVec3, fov_y_degrees: f64) -> Camera {
        Camera {
            position,
            forward: target - position,
            up: DVec3::Y,
            fov_y: fov_y_degrees.to_radians(),
            near: 0.05,
            far: 500.0,
        }
    }

    /// World to view: right-handed, the camera looks down −z.
    pub fn view(&self) -> DMat4 {
        let f = self.forward.normalize();
        let s = f.cross(self.up).normalize();
        let u = s.cross(f);
        let e = self.position;
        DMat4::from_cols(
            DVec4::new(s.x, u.x, -f.x, 0.0),
            DVec4::new(s.y, u.y, -f.y, 0.0),
            DVec4::new(s.z, u.z, -f.z, 0.0),
            DVec4::new(-s.dot(e), -u.dot(e), f.dot(e), 1.0),
        )
    }

    /// View to clip with reversed depth (near → 1, far → 0) for precision far away.
    pub fn projection(&self, aspect: f64) -> DMat4 {
        let t = (self.fov_y * 0.5).tan();
        let (n, f) = (self.near, self.far);
        DMat4::from_cols(
            DVec4::new(1.0 / (t * aspect), 0.0, 0.0, 0.0),
            DVec4::new(0.0, 1.0 / t, 0.0, 0.0),
            DVec4::new(0.0, 0.0, n / (f - n), -1.0),
            DVec4::new(0.0, 0.0, n * f / (f - n), 0.0),
        )
    }
}

/// The `Frame` uniform block of `shaders/lib/common.wgsl`, field for field.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FrameUniforms {
    pub view_proj: [[f32; 4]; 4],
    pub view: [[f32; 4]; 4],
    pub inv_view: [[f32; 4]; 4],
    pub eye: [f32; 4],
    /// tan(fov_y/2)·aspect, tan(fov_y/2), near, far.
    pub projection: [f32; 4],
    pub ambient: [f32; 4],
    pub background: [f32; 4],
    /// x: exposure.
    pub display: [f32; 4],
}

impl FrameUniforms {
    pub fn new(camera: &Camera, lighting: &Lighting, width: u32, height: u32) -> FrameUniforms {
        let aspect = f64::from(width) / f64::from(height);
        let view = camera.view();
        let view_proj = camera.projection(aspect) * view;
        let tan_y = (camera.fov_y * 0.5).tan();
        let cast = |m: DMat4| m.as_mat4().to_cols_array_2d();
        FrameUniforms {
            view_proj: cast(view_proj),
            view: cast(view),
            inv_view: cast(view.inverse()),
            eye: camera.position.as_vec3().extend(1.0).to_array(),
            projection: [(tan_y * aspect) as f32, tan_y as f32, camera.near as f32, camera.far as f32],
            ambient: lighting.ambient.extend(0.0).to_array(),
            background: lighting.background.extend(0.0).to_array(),
            display: [lighting.exposure, 0.0, 0.0, 0.0],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reversed_depth_maps_near_to_one_and_far_to_zero() {
        let camera = Camera { near: 0.5, far: 80.0, ..Camera::look_at(DVec3::ZERO, -DVec3::Z, 60.0) };
        let clip = |z: f64| {
            let p = camera.projection(4.0 / 3.0) * DVec4::new(0.0, 0.0, z, 1.0);
            p.z / p.w
        };
        assert!((clip(-0.5) - 1.0).abs() < 1e-12);
        assert!(clip(-80.0).abs() < 1e-12);
        assert!(clip(-10.0) > clip(-20.0));
    }

    #[test]
    fn view_moves_the_eye_to_the_origin_looking_down_minus_z() {
        let camera = Camera::look_at(DVec3::new(1.0, 2.0, 3.0), DVec3::new(1.0, 2.0, -7.0), 60.0);
        let eye = camera.view() * DVec4::new(1.0, 2.0, 3.0, 1.0);
        let ahead = camera.view() * DVec4::new(1.0, 2.0, 0.0, 1.0);
        assert!(eye.truncate().length() < 1e-12);
        assert!((ahead.truncate() - DVec3::new(0.0, 0.0, -3.0)).length() < 1e-12);
    }
}
