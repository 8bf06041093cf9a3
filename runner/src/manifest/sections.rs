//! The manifest's sections of the scene itself: resolutions, the generated file, the camera, the
//! lights and their shadows, and the adaptive metric's constants. Each checks its own fields;
//! a failure names the field within its section.

use aabench_renderer::AdaptiveSettings;
use aabench_renderer::adaptive::{DepthMetric, MAX_METRIC_CONSTANT, StableCounts};
use aabench_renderer::scene::generate::Generator;
use aabench_renderer::scene::{Camera, MAX_SHADOW_LIGHTS, Shadow, check_light, number};
use glam::DVec3;
use serde::Deserialize;

use super::{Invalid, MAX_RESOLUTION};

/// Output resolution per tier; omitted: 256×192 quick, 1024×768 nightly (the paper's).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Resolutions {
    #[serde(default = "quick_resolution")]
    pub quick: [u32; 2],
    #[serde(default = "nightly_resolution")]
    pub nightly: [u32; 2],
}

fn quick_resolution() -> [u32; 2] {
    [256, 192]
}

fn nightly_resolution() -> [u32; 2] {
    [1024, 768]
}

impl Resolutions {
    /// Each tier's size within [1, MAX_RESOLUTION] a side; the field is the tier.
    pub(super) fn check(&self) -> Result<(), Invalid> {
        for (tier, [width, height]) in [("quick", self.quick), ("nightly", self.nightly)] {
            if width == 0 || height == 0 || width > MAX_RESOLUTION || height > MAX_RESOLUTION {
                return Err((
                    tier.into(),
                    format!("{width}×{height} must be between 1 and {MAX_RESOLUTION} on each side"),
                ));
            }
        }
        Ok(())
    }
}

impl Default for Resolutions {
    fn default() -> Self {
        Resolutions { quick: quick_resolution(), nightly: nightly_resolution() }
    }
}

/// What becomes of the glTF file's own (`KHR_lights_punctual`) lights.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FileLights {
    /// The file's lights shine, and the manifest's `lights` are added to them.
    #[default]
    Keep,
    /// Only the manifest's `lights` shine.
    Replace,
}

/// How to make the glTF file when it is missing or stale.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Generate {
    pub generator: String,
    #[serde(default)]
    pub seed: u64,
    /// Uniform scale of the whole scene (1000: metres become millimetres), in [1e-6, 1e6].
    #[serde(default = "unit_scale")]
    pub scale: f64,
    /// Where the scaled scene's origin goes, each coordinate within ±1e9.
    #[serde(default)]
    pub offset: [f64; 3],
}

fn unit_scale() -> f64 {
    1.0
}

#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSpec {
    pub position: [f64; 3],
    pub target: [f64; 3],
    #[serde(default = "default_up")]
    pub up: [f64; 3],
    pub fov_y_degrees: f64,
    #[serde(default = "default_near")]
    pub near: f64,
    /// Omitted: just beyond the farthest corner of the scene's bounds.
    pub far: Option<f64>,
}

impl Generate {
    /// A known generator, a scale within [1e-6, 1e6] and an offset within ±1e9.
    pub(super) fn check(&self) -> Result<(), Invalid> {
        self.generator.parse::<Generator>().map_err(|message| ("generator".to_string(), message))?;
        if !(1e-6..=1e6).contains(&self.scale) {
            return Err(("scale".into(), format!("{} must be within [1e-6, 1e6]", self.scale)));
        }
        if !self.offset.iter().all(|c| c.abs() <= 1e9) {
            return Err(("offset".into(), format!("{:?} must be finite, each within ±1e9", self.offset)));
        }
        Ok(())
    }
}

impl CameraSpec {
    /// The renderer's camera; an omitted far plane is infinite until the scene's bounds set it.
    pub fn camera(&self) -> Camera {
        Camera {
            position: DVec3::from(self.position),
            forward: DVec3::from(self.target) - DVec3::from(self.position),
            up: DVec3::from(self.up),
            fov_y: self.fov_y_degrees.to_radians(),
            near: self.near,
            far: self.far.unwrap_or(f64::INFINITY),
        }
    }
}

fn default_up() -> [f64; 3] {
    [0.0, 1.0, 0.0]
}

fn default_near() -> f64 {
    0.05
}

#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightSpec {
    /// In the file's coordinates (f64: a scene placed far out keeps its lights where they are).
    pub position: [f64; 3],
    #[serde(default = "white", deserialize_with = "super::narrow::triple")]
    pub color: [f32; 3],
    #[serde(deserialize_with = "super::narrow::f32")]
    pub intensity: f32,
    #[serde(deserialize_with = "super::narrow::f32")]
    pub range: f32,
    #[serde(default)]
    pub casts_shadows: bool,
    /// Shadow settings of a light that casts shadows; omitted fields take [`Shadow::default`].
    pub shadow: Option<ShadowSpec>,
}

impl LightSpec {
    /// The light's own fields, and shadow settings only on a light that casts shadows.
    pub(super) fn check(&self) -> Result<(), Invalid> {
        check_light(DVec3::from(self.position), self.color, self.intensity, Some(self.range))
            .map_err(|(name, why)| (name.to_string(), why))?;
        if self.shadow.is_some() && !self.casts_shadows {
            return Err(("shadow".into(), "is given but casts_shadows is false".into()));
        }
        Ok(())
    }

    /// The light's shadow, when it casts one.
    pub fn shadow(&self) -> Option<Shadow> {
        self.casts_shadows.then(|| self.shadow.unwrap_or_default().settings())
    }
}

/// A shadow-casting light's cube: resolution of each face, depth bias and PCF radius (world
/// units; see [`Shadow`]).
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShadowSpec {
    pub resolution: Option<u32>,
    #[serde(default, deserialize_with = "super::narrow::option")]
    pub bias: Option<f32>,
    #[serde(default, deserialize_with = "super::narrow::option")]
    pub radius: Option<f32>,
}

impl ShadowSpec {
    pub fn settings(&self) -> Shadow {
        let d = Shadow::default();
        Shadow {
            resolution: self.resolution.unwrap_or(d.resolution),
            bias: self.bias.unwrap_or(d.bias),
            radius: self.radius.unwrap_or(d.radius),
        }
    }
}

/// Bytes all of a scene's shadow cubes may take (f32 depth, six faces each): every mode and
/// every ground-truth tile holds them beside its own targets.
const MAX_SHADOW_CUBE_BYTES: u64 = 512 << 20;

/// Texels per side of a shadow cube face.
const SHADOW_RESOLUTIONS: std::ops::RangeInclusive<u32> = 16..=4096;

/// Checks the shadows of a scene's lights, each named by its settings' field: every setting in
/// range, at most [`MAX_SHADOW_LIGHTS`], within `MAX_SHADOW_CUBE_BYTES`, one resolution
/// for all (their cubes are layers of one array). On failure, the field and why.
pub fn check_shadows(shadows: &[(String, Shadow)]) -> Result<(), (String, String)> {
    for (field, shadow) in shadows {
        if !SHADOW_RESOLUTIONS.contains(&shadow.resolution) {
            let (lo, hi) = (SHADOW_RESOLUTIONS.start(), SHADOW_RESOLUTIONS.end());
            return Err((
                format!("{field}.resolution"),
                format!("{} must be in [{lo}, {hi}]", shadow.resolution),
            ));
        }
        for (name, value) in [("bias", shadow.bias), ("radius", shadow.radius)] {
            if !(value >= 0.0 && value.is_finite()) {
                return Err((format!("{field}.{name}"), format!("{} must be finite and ≥ 0", number(value))));
            }
        }
    }
    if shadows.len() > MAX_SHADOW_LIGHTS {
        return Err((
            "lights".into(),
            format!("{} lights cast shadows, at most {MAX_SHADOW_LIGHTS} may", shadows.len()),
        ));
    }
    let cube_bytes: u64 = shadows.iter().map(|(_, s)| 6 * 4 * u64::from(s.resolution).pow(2)).sum();
    if cube_bytes > MAX_SHADOW_CUBE_BYTES {
        return Err((
            "lights".into(),
            format!(
                "the shadow cubes take {} MiB, more than {} MiB: lower the shadow resolution",
                cube_bytes >> 20,
                MAX_SHADOW_CUBE_BYTES >> 20
            ),
        ));
    }
    if let (Some((first, a)), Some((field, b))) =
        (shadows.first(), shadows.iter().find(|(_, s)| s.resolution != shadows[0].1.resolution))
    {
        return Err((
            format!("{field}.resolution"),
            format!(
                "{} differs from {first}'s {}: all shadow cubes of a scene are layers of one array, so they \
                 share one resolution",
                b.resolution, a.resolution
            ),
        ));
    }
    Ok(())
}

fn white() -> [f32; 3] {
    [1.0; 3]
}

/// The adaptive metric constants; omitted fields take [`AdaptiveSettings::default`].
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AdaptiveSpec {
    /// `relative` (the default: unit-free) or `world` (the paper's literal units²).
    pub depth_metric: Option<DepthMetricSpec>,
    /// Omitted: the default of the depth metric in use.
    #[serde(default, deserialize_with = "super::narrow::option")]
    pub c_depth: Option<f32>,
    #[serde(default, deserialize_with = "super::narrow::option")]
    pub c_normal: Option<f32>,
    #[serde(default, deserialize_with = "super::narrow::option")]
    pub c_shading: Option<f32>,
    #[serde(default, deserialize_with = "super::narrow::option")]
    pub c_shadow: Option<f32>,
    #[serde(default, deserialize_with = "super::narrow::option")]
    pub t_min: Option<f32>,
    #[serde(default, deserialize_with = "super::narrow::option")]
    pub t_edge: Option<f32>,
    /// `-stable` modes: the share of the window the metric may ask for fewer without the count
    /// falling, and the most a count falls in a frame, as a share of itself.
    #[serde(default, deserialize_with = "super::narrow::option")]
    pub stable_hold: Option<f32>,
    #[serde(default, deserialize_with = "super::narrow::option")]
    pub stable_decay: Option<f32>,
}

impl AdaptiveSpec {
    /// The metric constants within [0, MAX_METRIC_CONSTANT], the thresholds within [0, 1].
    pub(super) fn check(&self) -> Result<(), Invalid> {
        let adaptive = self.settings();
        let constants = [
            ("c_depth", adaptive.c_depth),
            ("c_normal", adaptive.c_normal),
            ("c_shading", adaptive.c_shading),
            ("c_shadow", adaptive.c_shadow),
        ];
        for (name, value) in constants {
            if !(0.0..=MAX_METRIC_CONSTANT).contains(&value) {
                return Err((
                    name.into(),
                    format!("{} must be within [0, {MAX_METRIC_CONSTANT:e}]", number(value)),
                ));
            }
        }
        let shares = [
            ("t_min", adaptive.t_min),
            ("t_edge", adaptive.t_edge),
            ("stable_hold", adaptive.stable.hold),
            ("stable_decay", adaptive.stable.decay),
        ];
        for (name, value) in shares {
            if !(0.0..=1.0).contains(&value) {
                return Err((name.into(), format!("{} must be in [0, 1]", number(value))));
            }
        }
        Ok(())
    }

    pub fn settings(&self) -> AdaptiveSettings {
        let d = AdaptiveSettings::default();
        let depth_metric = match self.depth_metric {
            Some(DepthMetricSpec::World) => DepthMetric::World,
            Some(DepthMetricSpec::Relative) | None => DepthMetric::Relative,
        };
        AdaptiveSettings {
            depth_metric,
            c_depth: self.c_depth.unwrap_or(depth_metric.default_c_depth()),
            c_normal: self.c_normal.unwrap_or(d.c_normal),
            c_shading: self.c_shading.unwrap_or(d.c_shading),
            c_shadow: self.c_shadow.unwrap_or(d.c_shadow),
            t_min: self.t_min.unwrap_or(d.t_min),
            t_edge: self.t_edge.unwrap_or(d.t_edge),
            stable: StableCounts {
                hold: self.stable_hold.unwrap_or(d.stable.hold),
                decay: self.stable_decay.unwrap_or(d.stable.decay),
            },
            ..d
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DepthMetricSpec {
    Relative,
    World,
}
