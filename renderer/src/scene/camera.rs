//! The pinhole camera and the per-frame uniforms derived from it.
//!
//! Matrices are built in f64 and rounded once to f32, so debug and release builds feed the GPU
//! the same bits (LAVAPIPE.md: a constant-folded `tan` once differed by an ulp between them).

use glam::{DMat4, DVec2, DVec3, DVec4};

use super::Lighting;

/// The largest camera coordinate accepted: far beyond any scene, and far from f32's range once
/// geometry is made camera-relative.
pub const MAX_COORDINATE: f64 = 1e12;
/// The vertical fields of view accepted, in degrees.
pub const FOV_Y_DEGREES: [f64; 2] = [0.01, 179.0];

/// What is wrong with a camera: the field (`position`, `target`, `up`, `fov_y`, `near`, `far`)
/// and why.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraError {
    pub field: &'static str,
    pub message: String,
}

/// A number as a message shows it: plainly in everyday ranges, in exponent form when huge or
/// tiny (1e-300 has 300 zeros in plain form).
/// A number as messages show it: plainly between 10⁻⁴ and 10⁹, else in scientific notation (a
/// value of 10³⁰⁸ is not printed as 309 digits).
pub fn number<T>(x: T) -> String
where
    T: Copy + Into<f64> + std::fmt::Display + std::fmt::LowerExp,
{
    let value: f64 = x.into();
    if value != 0.0 && value.is_finite() && !(1e-4..1e9).contains(&value.abs()) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

pub(crate) fn vector(v: DVec3) -> String {
    format!("[{}, {}, {}]", number(v.x), number(v.y), number(v.z))
}

impl CameraError {
    /// The same error said of a camera that a glTF node carries: its fields by glTF's names,
    /// and a view or up direction as the node's transform makes it (a file camera has no
    /// target).
    pub fn of_file_camera(self) -> CameraError {
        let (field, message) = match self.field {
            "target" => (
                "view direction",
                "the camera node's transform turns its −Z axis into nothing (a scale of 0?), so it looks nowhere"
                    .to_string(),
            ),
            "up" => ("up", format!("the camera node's +Y axis {}", self.message)),
            "fov_y" => ("yfov", self.message),
            "near" => ("znear", self.message),
            "far" => ("zfar", self.message),
            other => (other, self.message),
        };
        CameraError { field, message }
    }
}

impl std::fmt::Display for CameraError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.field, self.message)
    }
}

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

    /// Checks that the renderer can draw through this camera: finite coordinates within
    /// ±[`MAX_COORDINATE`], a view direction that is neither zero (a target on top of the
    /// position) nor parallel to `up`, a field of view within `FOV_Y_DEGREES`, and
    /// 1e-6 ≤ near < far ≤ 1e12 (they reach the GPU as f32). An infinite far plane passes: the
    /// caller replaces it from the scene's bounds.
    pub fn validate(&self) -> Result<(), CameraError> {
        let fail = |field: &'static str, message: String| Err(CameraError { field, message });
        for (field, v) in [("position", self.position), ("target", self.forward), ("up", self.up)] {
            if !v.is_finite() || v.abs().max_element() > MAX_COORDINATE {
                return fail(field, format!("{} must be finite and within ±{MAX_COORDINATE:e}", vector(v)));
            }
        }
        // Relative to the position's magnitude: 1e-200 apart is "on top of it" at any scale.
        if self.forward.length() <= 1e-9 * self.position.length().max(1.0) {
            return fail(
                "target",
                format!("lies on the position {} (no view direction)", vector(self.position)),
            );
        }
        if self.up.length() == 0.0 || self.forward.normalize().cross(self.up.normalize()).length() < 1e-6 {
            return fail("up", format!("{} is zero or parallel to the view direction", vector(self.up)));
        }
        let degrees = self.fov_y.to_degrees();
        let [lowest, widest] = FOV_Y_DEGREES;
        if !(lowest..=widest).contains(&degrees) {
            return fail("fov_y", format!("{}° must be within [{lowest}°, {widest}°]", number(degrees)));
        }
        if !(1e-6..=1e9).contains(&self.near) {
            return fail("near", format!("{} must be within [1e-6, 1e9]", number(self.near)));
        }
        if !(self.far > self.near && (self.far <= 1e12 || self.far == f64::INFINITY)) {
            return fail(
                "far",
                format!("{} must be > near ({}) and at most 1e12", number(self.far), number(self.near)),
            );
        }
        Ok(())
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
    /// x: exposure; y, z: the tile's origin in the frame's pixels (the dither's grain follows
    /// frame positions).
    pub display: [f32; 4],
    /// The rendered part of the frame: a tile's NDC maps to the whole frame's as
    /// `ndc · tile.xy + tile.zw` (1, 1, 0, 0 for the whole frame; see [`Tile`]).
    pub tile: [f32; 4],
    /// From this target's clip space to the previous frame's, unjittered: a fragment's
    /// (NDC, depth, 1) maps to where its point was, up to a factor of its clip w (temporal
    /// modes; the camera's own frame otherwise).
    pub reprojection: [[f32; 4]; 4],
    /// x, y: the frame's sub-pixel jitter in pixels (a pixel's sample lies at its centre plus
    /// the jitter, x right and y down; 0 but in temporal modes); z, w: the whole frame's width
    /// and height in pixels.
    pub jitter: [f32; 4],
    /// x: 1 where the history holds earlier frames, 0 after a reset (temporal modes).
    pub history: [f32; 4],
}

/// A rectangle of the output image in pixels, rendered on its own: the ground truth renders
/// its many samples per pixel tile by tile.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Tile {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
}

impl Tile {
    /// The whole `width` × `height` frame.
    pub fn whole(width: u32, height: u32) -> Tile {
        Tile { x: 0, y: 0, width, height }
    }

    /// (scale, offset) per axis that map the tile's NDC to the frame's: NDC x runs from −1 at
    /// the left edge, y from +1 at the top.
    fn ndc_window(&self, frame_width: u32, frame_height: u32) -> (DVec2, DVec2) {
        let origin = DVec2::new(f64::from(self.x), f64::from(self.y));
        let size = DVec2::new(f64::from(self.width), f64::from(self.height));
        ndc_window(origin, size, frame_width, frame_height)
    }

    /// Clip space of the whole frame to the tile's: x' = (x − offset·w) / scale, same for y.
    fn clip_to_tile(scale: DVec2, offset: DVec2) -> DMat4 {
        DMat4::from_cols(
            DVec4::new(1.0 / scale.x, 0.0, 0.0, 0.0),
            DVec4::new(0.0, 1.0 / scale.y, 0.0, 0.0),
            DVec4::Z,
            DVec4::new(-offset.x / scale.x, -offset.y / scale.y, 0.0, 1.0),
        )
    }
}

/// [`Tile::ndc_window`] of a window at `origin` of `size` pixels, either fractional: a whole
/// frame jittered by a sub-pixel offset is the window at that offset.
fn ndc_window(origin: DVec2, size: DVec2, frame_width: u32, frame_height: u32) -> (DVec2, DVec2) {
    let (w, h) = (f64::from(frame_width), f64::from(frame_height));
    let end = origin + size;
    let scale = DVec2::new(size.x / w, size.y / h);
    let offset = DVec2::new((origin.x + end.x) / w - 1.0, 1.0 - (origin.y + end.y) / h);
    (scale, offset)
}

impl FrameUniforms {
    /// The uniforms of a whole `width` × `height` frame.
    pub fn new(camera: &Camera, lighting: &Lighting, width: u32, height: u32) -> FrameUniforms {
        Self::for_tile(camera, lighting, width, height, Tile::whole(width, height))
    }

    /// The uniforms that render only `tile` of a `width` × `height` frame, into a target of
    /// the tile's size. For the whole frame the tile transform is the identity, so the bits
    /// are those of [`Self::new`].
    pub fn for_tile(
        camera: &Camera,
        lighting: &Lighting,
        width: u32,
        height: u32,
        tile: Tile,
    ) -> FrameUniforms {
        let (scale, offset) = tile.ndc_window(width, height);
        let mut uniforms = Self::through(camera, camera, lighting, [width, height], (scale, offset));
        uniforms.display[1..3].copy_from_slice(&[tile.x as f32, tile.y as f32]);
        uniforms
    }

    /// The uniforms of a temporal mode's whole frame: its samples moved by `jitter` pixels
    /// (each within ±½), `previous` the camera of the frame before (the history's), `history`
    /// whether the history holds earlier frames. Without jitter and with `previous` the same
    /// camera, the bits are those of [`Self::new`] but for `history`.
    pub fn temporal(
        camera: &Camera,
        previous: &Camera,
        lighting: &Lighting,
        [width, height]: [u32; 2],
        jitter: DVec2,
        history: bool,
    ) -> FrameUniforms {
        let size = DVec2::new(f64::from(width), f64::from(height));
        let window = ndc_window(jitter, size, width, height);
        let mut uniforms = Self::through(camera, previous, lighting, [width, height], window);
        uniforms.jitter[..2].copy_from_slice(&[jitter.x as f32, jitter.y as f32]);
        uniforms.history[0] = if history { 1.0 } else { 0.0 };
        uniforms
    }

    /// The uniforms through `camera` of the window whose NDC maps to the frame's as
    /// `ndc · scale + offset`, `previous` the camera of the frame before; no jitter.
    fn through(
        camera: &Camera,
        previous: &Camera,
        lighting: &Lighting,
        [width, height]: [u32; 2],
        (scale, offset): (DVec2, DVec2),
    ) -> FrameUniforms {
        let aspect = f64::from(width) / f64::from(height);
        let view = camera.view();
        let view_proj = Tile::clip_to_tile(scale, offset) * camera.projection(aspect) * view;
        let tan_y = (camera.fov_y * 0.5).tan();
        let cast = |m: DMat4| m.as_mat4().to_cols_array_2d();
        let reprojection = previous.projection(aspect) * previous.view() * view_proj.inverse();
        FrameUniforms {
            view_proj: cast(view_proj),
            view: cast(view),
            inv_view: cast(view.inverse()),
            eye: camera.position.as_vec3().extend(1.0).to_array(),
            projection: [(tan_y * aspect) as f32, tan_y as f32, camera.near as f32, camera.far as f32],
            ambient: lighting.ambient.extend(0.0).to_array(),
            background: lighting.background.extend(0.0).to_array(),
            display: [lighting.exposure, 0.0, 0.0, 0.0],
            tile: [scale.x as f32, scale.y as f32, offset.x as f32, offset.y as f32],
            reprojection: cast(reprojection),
            jitter: [0.0, 0.0, width as f32, height as f32],
            history: [0.0; 4],
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
    fn a_tile_sees_its_part_of_the_frame() {
        let camera = Camera::look_at(DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO, 50.0);
        let lighting = Lighting {
            lights: Vec::new(),
            ambient: glam::Vec3::ZERO,
            background: glam::Vec3::ZERO,
            exposure: 1.0,
        };
        let whole = FrameUniforms::new(&camera, &lighting, 64, 48);
        let same = FrameUniforms::for_tile(&camera, &lighting, 64, 48, Tile::whole(64, 48));
        assert_eq!(whole, same, "the whole frame as a tile is bit-identical");
        assert_eq!(whole.tile, [1.0, 1.0, 0.0, 0.0]);

        // A point at pixel (40.5, 30.5) of the frame lands at (40.5 − 32, 30.5 − 24) of the
        // tile that starts at (32, 24), and the tile's NDC maps back through `tile`.
        let tile = Tile { x: 32, y: 24, width: 16, height: 12 };
        let part = FrameUniforms::for_tile(&camera, &lighting, 64, 48, tile);
        let project = |u: &FrameUniforms, p: DVec4| {
            let m = glam::Mat4::from_cols_array_2d(&u.view_proj).as_dmat4();
            let c = m * p;
            DVec2::new(c.x / c.w, c.y / c.w)
        };
        let to_pixel =
            |ndc: DVec2, w: f64, h: f64| DVec2::new((ndc.x + 1.0) * w / 2.0, (1.0 - ndc.y) * h / 2.0);
        let point = DVec4::new(0.7, -0.4, 0.0, 1.0);
        let in_frame = to_pixel(project(&whole, point), 64.0, 48.0);
        let in_tile = to_pixel(project(&part, point), 16.0, 12.0);
        assert!((in_tile - (in_frame - DVec2::new(32.0, 24.0))).length() < 1e-4, "{in_frame} {in_tile}");
        let ndc_tile = project(&part, point);
        let [sx, sy, ox, oy] = part.tile.map(f64::from);
        let back = DVec2::new(ndc_tile.x * sx + ox, ndc_tile.y * sy + oy);
        assert!((back - project(&whole, point)).length() < 1e-5);
    }

    #[test]
    fn degenerate_cameras_name_their_field() {
        let good = Camera::look_at(DVec3::new(0.0, 1.0, 5.0), DVec3::ZERO, 60.0);
        assert_eq!(good.validate(), Ok(()));
        let field = |camera: Camera| camera.validate().unwrap_err().field;
        assert_eq!(field(Camera { fov_y: 0.0, ..good }), "fov_y");
        assert_eq!(field(Camera { fov_y: 1e-300, ..good }), "fov_y");
        assert_eq!(field(Camera { fov_y: std::f64::consts::PI, ..good }), "fov_y");
        assert_eq!(field(Camera { near: 0.0, ..good }), "near");
        assert_eq!(field(Camera { near: 10.0, far: 5.0, ..good }), "far");
        assert_eq!(field(Camera { position: DVec3::splat(1e308), ..good }), "position");
        assert_eq!(field(Camera { position: DVec3::new(f64::NAN, 0.0, 0.0), ..good }), "position");
        assert_eq!(field(Camera { forward: DVec3::new(0.0, 0.0, -1e-200), ..good }), "target");
        assert_eq!(field(Camera { forward: DVec3::Y * 3.0, ..good }), "up");
        assert_eq!(field(Camera { up: DVec3::ZERO, ..good }), "up");
        assert_eq!(Camera { far: f64::INFINITY, ..good }.validate(), Ok(()), "the caller picks far");
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
