//! Omnidirectional shadows of point lights: each shadow-casting light renders the scene's depth
//! into the six faces of a cube (LearnOpenGL, "Point Shadows"), one render pass per face since
//! wgpu has no geometry shaders here. Faces follow the cube-map convention of Vulkan and WGSL
//! (layers +X, −X, +Y, −Y, +Z, −Z; Vulkan spec, "Cube Map Face Selection"), so a lookup in the
//! direction from the light finds what the face rendered there. Depth is reversed (near → 1,
//! far → 0) along the face's axis, and shading turns it back into a distance along the lookup
//! ray (`shaders/lib/shadows.wgsl`).

use glam::{DMat4, DVec3, DVec4, Vec3};

use super::Light;

/// Shadow-casting lights a scene may have: their cubes are layers of one array.
pub const MAX_SHADOW_LIGHTS: usize = 8;

/// A light's shadow settings, per light in the manifest.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shadow {
    /// Texels per side of each cube face. Every shadow light of a scene shares one cube array,
    /// so they share one resolution.
    pub resolution: u32,
    /// World units a surface may lie behind the stored depth and still count as lit, against
    /// shadow acne.
    pub bias: f32,
    /// World radius of the PCF disk at the light's position; it grows with view distance as
    /// `radius · (1 + view distance / range)`.
    pub radius: f32,
}

impl Default for Shadow {
    /// LearnOpenGL's constants for a metre-scale room: a disk of 1/25 and a bias a little
    /// above the depth error of a 512² face at grazing angles there.
    fn default() -> Shadow {
        Shadow { resolution: 512, bias: 0.05, radius: 0.04 }
    }
}

/// The shadow cubes a scene needs: one per shadow-casting light (the first
/// [`MAX_SHADOW_LIGHTS`]), all at the largest resolution asked for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ShadowCubes {
    pub lights: u32,
    pub resolution: u32,
}

impl ShadowCubes {
    /// None when no light casts a shadow: no shadow pass, no cube.
    pub fn of(lights: &[Light]) -> Option<ShadowCubes> {
        let shadows: Vec<&Shadow> = lights.iter().filter_map(Light::cube).take(MAX_SHADOW_LIGHTS).collect();
        let resolution = shadows.iter().map(|s| s.resolution).max()?;
        Some(ShadowCubes { lights: shadows.len() as u32, resolution })
    }
}

/// The near plane of a light's cube as a fraction of its range: reversed f32 depth keeps its
/// relative precision everywhere, so it can sit close.
pub const NEAR_FRACTION: f64 = 1e-4;

/// (sc, tc, ma) of each face as rows over the light-relative direction r: the cube lookup
/// takes the face of the largest |r| component and reads it at s = (sc/ma + 1)/2,
/// t = (tc/ma + 1)/2.
const FACES: [[DVec3; 3]; 6] = [
    [DVec3::new(0.0, 0.0, -1.0), DVec3::new(0.0, -1.0, 0.0), DVec3::new(1.0, 0.0, 0.0)],
    [DVec3::new(0.0, 0.0, 1.0), DVec3::new(0.0, -1.0, 0.0), DVec3::new(-1.0, 0.0, 0.0)],
    [DVec3::new(1.0, 0.0, 0.0), DVec3::new(0.0, 0.0, 1.0), DVec3::new(0.0, 1.0, 0.0)],
    [DVec3::new(1.0, 0.0, 0.0), DVec3::new(0.0, 0.0, -1.0), DVec3::new(0.0, -1.0, 0.0)],
    [DVec3::new(1.0, 0.0, 0.0), DVec3::new(0.0, -1.0, 0.0), DVec3::new(0.0, 0.0, 1.0)],
    [DVec3::new(-1.0, 0.0, 0.0), DVec3::new(0.0, -1.0, 0.0), DVec3::new(0.0, 0.0, -1.0)],
];

/// World to clip space of each face of the cube around `light`, in layer order. Texture row 0
/// is the top of a rendered image (NDC y = +1) and t = 0 of a lookup, so NDC = (sc, −tc) / ma;
/// clip z gives reversed depth n·(f − ma) / (ma·(f − n)) along the face's axis.
pub fn face_matrices(light: Vec3, near: f64, far: f64) -> [[[f32; 4]; 4]; 6] {
    let origin = light.as_dvec3();
    let depth_scale = -near / (far - near);
    let depth_offset = near * far / (far - near);
    FACES.map(|[sc, tc, ma]| {
        // Rows of the matrix over (r, 1), r = p − light.
        let row = |v: DVec3, constant: f64| DVec4::new(v.x, v.y, v.z, constant - v.dot(origin));
        let rows = [row(sc, 0.0), row(-tc, 0.0), row(ma * depth_scale, depth_offset), row(ma, 0.0)];
        DMat4::from_cols(rows[0], rows[1], rows[2], rows[3]).transpose().as_mat4().to_cols_array_2d()
    })
}

/// The face a lookup in `direction` reads, and where in it (s, t ∈ [0, 1], t down): the CPU
/// twin of the cube lookup, for tests.
pub fn face_and_coordinates(direction: Vec3) -> (usize, f64, f64) {
    let r = direction.as_dvec3();
    let a = r.abs();
    let face = if a.x >= a.y && a.x >= a.z {
        if r.x >= 0.0 { 0 } else { 1 }
    } else if a.y >= a.z {
        if r.y >= 0.0 { 2 } else { 3 }
    } else if r.z >= 0.0 {
        4
    } else {
        5
    };
    let [sc, tc, ma] = FACES[face].map(|v| v.dot(r));
    (face, (sc / ma + 1.0) / 2.0, (tc / ma + 1.0) / 2.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_face_projects_its_axis_to_the_centre_at_the_right_depth() {
        let light = Vec3::new(1.0, 2.0, 3.0);
        let (near, far) = (0.01, 10.0);
        let matrices = face_matrices(light, near, far);
        let axes = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
        for (face, axis) in axes.iter().enumerate() {
            assert_eq!(face_and_coordinates(*axis), (face, 0.5, 0.5));
            let m = glam::Mat4::from_cols_array_2d(&matrices[face]);
            for (distance, depth) in [(near, 1.0), (far, 0.0)] {
                let clip = m * (light + *axis * distance as f32).extend(1.0);
                let ndc = clip / clip.w;
                assert!(ndc.x.abs() < 1e-5 && ndc.y.abs() < 1e-5, "face {face}: {ndc}");
                assert!((ndc.z - depth).abs() < 1e-4, "face {face} at {distance}: {ndc}");
            }
        }
    }

    #[test]
    fn rendered_rows_and_columns_match_the_lookup() {
        // A point off-axis lands where the lookup reads: NDC x = 2s − 1, NDC y = 1 − 2t.
        let light = Vec3::ZERO;
        let matrices = face_matrices(light, 0.01, 10.0);
        for direction in [Vec3::new(1.0, 0.5, 0.2), Vec3::new(-0.3, -1.0, 0.6), Vec3::new(0.1, 0.4, -1.0)] {
            let (face, s, t) = face_and_coordinates(direction);
            let clip = glam::Mat4::from_cols_array_2d(&matrices[face]) * direction.extend(1.0);
            let (x, y) = (clip.x / clip.w, clip.y / clip.w);
            assert!((f64::from(x) - (2.0 * s - 1.0)).abs() < 1e-6, "{direction}: x {x} s {s}");
            assert!((f64::from(y) - (1.0 - 2.0 * t)).abs() < 1e-6, "{direction}: y {y} t {t}");
        }
    }
}
