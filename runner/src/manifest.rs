//! Scene manifests: `scenes/*.json`, schema version 1. Parsing rejects unknown fields, and
//! every error names the file and the field (`scenes/atrium.json: lights[2].range: must be > 0`).

use std::fmt;
use std::path::{Path, PathBuf};

use aabench_renderer::AdaptiveSettings;
use aabench_renderer::adaptive::{DepthMetric, MAX_METRIC_CONSTANT, StableCounts};
use aabench_renderer::color::{ColorSettings, Dither, Tonemap, Transfer};
use aabench_renderer::scene::generate::{Generated, Generator, Placement};
use aabench_renderer::scene::{Camera, MAX_LIGHTS, MAX_SHADOW_LIGHTS, Shadow, check_light};
use glam::DVec3;
use serde::Deserialize;

use crate::gate::Tolerances;
use crate::motion::MotionSpec;

pub const SCHEMA_VERSION: u32 = 1;

/// A manifest error: the file, the field (a JSON path such as `lights[0].range`), the reason.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ManifestError {
    pub path: PathBuf,
    pub field: String,
    pub message: String,
}

impl fmt::Display for ManifestError {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        if self.field.is_empty() {
            write!(f, "{}: {}", self.path.display(), self.message)
        } else {
            write!(f, "{}: {}: {}", self.path.display(), self.field, self.message)
        }
    }
}

impl std::error::Error for ManifestError {}

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
    fn check(&self) -> Result<(), Invalid> {
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
    fn check(&self) -> Result<(), Invalid> {
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
    #[serde(default = "white")]
    pub color: [f32; 3],
    pub intensity: f32,
    pub range: f32,
    #[serde(default)]
    pub casts_shadows: bool,
    /// Shadow settings of a light that casts shadows; omitted fields take [`Shadow::default`].
    pub shadow: Option<ShadowSpec>,
}

impl LightSpec {
    /// The light's own fields, and shadow settings only on a light that casts shadows.
    fn check(&self) -> Result<(), Invalid> {
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
    pub bias: Option<f32>,
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
/// range, at most [`MAX_SHADOW_LIGHTS`], within [`MAX_SHADOW_CUBE_BYTES`], one resolution
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
                return Err((format!("{field}.{name}"), format!("{value} must be finite and ≥ 0")));
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
    pub c_depth: Option<f32>,
    pub c_normal: Option<f32>,
    pub c_shading: Option<f32>,
    pub t_min: Option<f32>,
    pub t_edge: Option<f32>,
    /// `-stable` modes: the share of the window the metric may ask for fewer without the count
    /// falling, and the most a count falls in a frame, as a share of itself.
    pub stable_hold: Option<f32>,
    pub stable_decay: Option<f32>,
}

impl AdaptiveSpec {
    /// The metric constants within [0, MAX_METRIC_CONSTANT], the thresholds within [0, 1].
    fn check(&self) -> Result<(), Invalid> {
        let adaptive = self.settings();
        let constants = [
            ("c_depth", adaptive.c_depth),
            ("c_normal", adaptive.c_normal),
            ("c_shading", adaptive.c_shading),
        ];
        for (name, value) in constants {
            if !(0.0..=MAX_METRIC_CONSTANT).contains(&value) {
                return Err((name.into(), format!("{value} must be within [0, {MAX_METRIC_CONSTANT:e}]")));
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
                return Err((name.into(), format!("{value} must be in [0, 1]")));
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

/// Whether a scene's shading needs a tonemap: `hdr` (the default) goes through the tonemap
/// pass, `ldr` straight to the transfer function, exposed and clamped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DynamicRange {
    #[default]
    Hdr,
    Ldr,
}

/// Exposure (every scene) and the tonemap curve (HDR scenes); omitted fields take
/// [`Tonemap::default`], the slides' curve.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TonemapSpec {
    /// A linear scale before tonemapping; omitted, the run meters it per scene (automatic
    /// exposure: `SceneRenderer::meter_exposure`).
    #[serde(default)]
    pub exposure: Option<f32>,
    pub mid_in: Option<f64>,
    pub mid_out: Option<f64>,
    pub hdr_max: Option<f64>,
    pub contrast: Option<f64>,
    pub shoulder: Option<f64>,
    pub crosstalk: Option<f64>,
    pub saturation: Option<f64>,
    pub cross_saturation: Option<f64>,
}

impl Default for TonemapSpec {
    fn default() -> Self {
        serde_json::from_str("{}").expect("every field has a default")
    }
}

impl TonemapSpec {
    /// The curve fields as the manifest names them, with their values where given.
    fn curve_fields(&self) -> [(&'static str, Option<f64>); 8] {
        [
            ("mid_in", self.mid_in),
            ("mid_out", self.mid_out),
            ("hdr_max", self.hdr_max),
            ("contrast", self.contrast),
            ("shoulder", self.shoulder),
            ("crosstalk", self.crosstalk),
            ("saturation", self.saturation),
            ("cross_saturation", self.cross_saturation),
        ]
    }

    pub fn settings(&self) -> Tonemap {
        let d = Tonemap::default();
        Tonemap {
            mid_in: self.mid_in.unwrap_or(d.mid_in),
            mid_out: self.mid_out.unwrap_or(d.mid_out),
            hdr_max: self.hdr_max.unwrap_or(d.hdr_max),
            contrast: self.contrast.unwrap_or(d.contrast),
            shoulder: self.shoulder.unwrap_or(d.shoulder),
            crosstalk: self.crosstalk.unwrap_or(d.crosstalk),
            saturation: self.saturation.unwrap_or(d.saturation),
            cross_saturation: self.cross_saturation.unwrap_or(d.cross_saturation),
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
pub enum TransferSpec {
    #[default]
    #[serde(rename = "srgb")]
    Srgb,
    #[serde(rename = "rec709")]
    Rec709,
    #[serde(rename = "gamma2.2")]
    Gamma22,
    #[serde(rename = "pq")]
    Pq,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DitherSpec {
    Off,
    #[default]
    Symmetric,
    Asymmetric,
}

/// How the display image is encoded: transfer function (PQ with the display's peak), bits per
/// channel and dither.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DisplaySpec {
    #[serde(default)]
    pub transfer: TransferSpec,
    /// PQ only; omitted: [`DEFAULT_PEAK_NITS`].
    pub peak_nits: Option<f64>,
    #[serde(default = "eight")]
    pub bits: u32,
    #[serde(default)]
    pub dither: DitherSpec,
}

/// The largest exposure: 2⁴⁰ (40 stops), far past any scene, and far from f32's overflow.
const MAX_EXPOSURE: f32 = 1.1e12;

/// A PQ display's peak when the manifest names none: a common HDR monitor.
pub const DEFAULT_PEAK_NITS: f64 = 1000.0;

fn eight() -> u32 {
    8
}

impl Default for DisplaySpec {
    fn default() -> Self {
        serde_json::from_str("{}").expect("every field has a default")
    }
}

/// A parsed and validated manifest. Paths are resolved against the manifest's folder.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    pub schema_version: u32,
    pub name: String,
    #[serde(default)]
    pub description: String,
    pub gltf: PathBuf,
    pub generate: Option<Generate>,
    /// Omitted: the glTF file's first perspective camera, else one framing the scene
    /// (`scenes.rs`, `framing_camera`).
    pub camera: Option<CameraSpec>,
    #[serde(default)]
    pub resolution: Resolutions,
    #[serde(default)]
    pub lights: Vec<LightSpec>,
    /// Whether the file's own lights shine beside `lights` (`keep`) or not (`replace`).
    #[serde(default)]
    pub file_lights: FileLights,
    /// When given, every point light of the file casts a shadow with these settings.
    pub file_light_shadows: Option<ShadowSpec>,
    #[serde(default = "default_ambient")]
    pub ambient: [f32; 3],
    #[serde(default = "default_background")]
    pub background: [f32; 3],
    #[serde(default = "default_stall")]
    pub stall_iterations: u32,
    /// The camera sees no geometry on purpose (a background-only test): without it, a scene
    /// with no triangle in view fails.
    #[serde(default)]
    pub empty: bool,
    #[serde(default)]
    pub adaptive: AdaptiveSpec,
    #[serde(default)]
    pub dynamic_range: DynamicRange,
    #[serde(default)]
    pub tonemap: TonemapSpec,
    #[serde(default)]
    pub display: DisplaySpec,
    /// A camera path: the scene is also rendered as a sequence (`motion.rs`).
    pub motion: Option<MotionSpec>,
    /// Tolerances of the regression gate; omitted fields take [`Tolerances::default`].
    #[serde(default)]
    pub gate: Tolerances,
    /// The file this manifest came from (not a JSON field).
    #[serde(skip)]
    pub path: PathBuf,
}

fn default_ambient() -> [f32; 3] {
    [0.03; 3]
}

fn default_background() -> [f32; 3] {
    [0.45, 0.6, 0.85]
}

fn default_stall() -> u32 {
    256
}

/// The largest stall accepted: what the stall loop can run within lavapipe's loop limit
/// (`shaders/lib/shading.wgsl`, `stall`).
pub const MAX_STALL_ITERATIONS: u32 = aabench_renderer::MAX_STALL_ITERATIONS;

/// The largest output side accepted: 4×4 supersampling must still fit lavapipe's 16384 limit.
pub const MAX_RESOLUTION: u32 = 4096;

/// A field that failed its check, relative to its section, and why.
type Invalid = (String, String);

/// Prefixes a section's failed field with the section's own path (`lights[2]`, `adaptive`).
fn within(section: &str) -> impl Fn(Invalid) -> Invalid + '_ {
    move |(field, why)| (format!("{section}.{field}"), why)
}

impl Manifest {
    /// Reads and validates a manifest file.
    pub fn load(path: &Path) -> Result<Manifest, ManifestError> {
        let unreadable = |message: String| ManifestError {
            path: path.to_path_buf(),
            field: String::new(),
            message: format!("cannot read: {message}"),
        };
        // A FIFO would block the run forever.
        crate::fs::regular_file(path).map_err(unreadable)?;
        let text = std::fs::read_to_string(path).map_err(|e| unreadable(e.to_string()))?;
        Self::parse(path, &text)
    }

    /// Parses and validates manifest text; `path` names the file in errors and anchors
    /// relative paths.
    pub fn parse(path: &Path, text: &str) -> Result<Manifest, ManifestError> {
        // Editors on some systems start UTF-8 files with a byte-order mark; JSON parsers may
        // ignore it, and this one does.
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let fail = |field: &str, message: String| ManifestError {
            path: path.to_path_buf(),
            field: field.to_string(),
            message,
        };
        let deserializer = &mut serde_json::Deserializer::from_str(text);
        let mut manifest: Manifest = serde_path_to_error::deserialize(deserializer).map_err(|e| {
            let field = e.path().to_string();
            let inner = e.into_inner();
            let field = if field == "." || field == "?" { String::new() } else { field };
            // serde_json appends "at line L column C"; keep it: it finds the spot.
            fail(&field, inner.to_string())
        })?;
        manifest.path = path.to_path_buf();
        manifest.validate().map_err(|(field, message)| fail(&field, message))?;
        Ok(manifest)
    }

    /// The colour pipeline from linear HDR to the display image.
    pub fn color_settings(&self) -> ColorSettings {
        let display = &self.display;
        ColorSettings {
            tonemap: (self.dynamic_range == DynamicRange::Hdr).then(|| self.tonemap.settings()),
            transfer: match display.transfer {
                TransferSpec::Srgb => Transfer::Srgb,
                TransferSpec::Rec709 => Transfer::Rec709,
                TransferSpec::Gamma22 => Transfer::Gamma22,
                TransferSpec::Pq => {
                    Transfer::Pq { peak_nits: display.peak_nits.unwrap_or(DEFAULT_PEAK_NITS) }
                }
            },
            bits: display.bits,
            dither: match display.dither {
                DitherSpec::Off => Dither::Off,
                DitherSpec::Symmetric => Dither::Symmetric,
                DitherSpec::Asymmetric => Dither::Asymmetric,
            },
        }
    }

    /// Bits per channel of the scene's display images as read back: 8, or 10.
    pub fn display_bits(&self) -> u32 {
        if self.display.bits <= 8 { 8 } else { 10 }
    }

    /// The glTF file: `gltf` relative to the manifest's folder, or as given where absolute.
    pub fn gltf_path(&self) -> PathBuf {
        self.path.parent().unwrap_or(Path::new(".")).join(&self.gltf)
    }

    /// What generates the glTF file, if the manifest says.
    pub fn generator(&self) -> Option<Generated> {
        let spec = self.generate.as_ref()?;
        Some(Generated {
            generator: spec.generator.parse().ok()?,
            seed: spec.seed,
            placement: Placement { scale: spec.scale, offset: spec.offset },
        })
    }

    fn validate(&self) -> Result<(), (String, String)> {
        let fail = |field: &str, message: String| Err((field.to_string(), message));
        if self.schema_version != SCHEMA_VERSION {
            return fail(
                "schema_version",
                format!("is {}, this aabench reads version {SCHEMA_VERSION}", self.schema_version),
            );
        }
        if self.name.is_empty()
            || !self
                .name
                .chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-' || c == '_')
        {
            return fail(
                "name",
                format!("`{}` must be non-empty lowercase letters, digits, - or _", self.name),
            );
        }
        if let Some(generate) = &self.generate {
            generate.check().map_err(within("generate"))?;
        }
        self.resolution.check().map_err(within("resolution"))?;
        // A file the user names is read wherever it lies; one that aabench generates is written,
        // and writes stay inside the manifest's folder.
        if self.generate.is_some() && escapes(&self.gltf) {
            return fail(
                "gltf",
                format!(
                    "`{}` leaves the manifest's folder, and `generate` would write it there: generated \
                     files stay inside the manifest's folder (a file of your own may lie anywhere: \
                     remove `generate`)",
                    self.gltf.display()
                ),
            );
        }
        if let Some(camera) = &self.camera {
            // The renderer's own check, on the camera as the manifest gives it.
            camera.camera().validate().map_err(|e| {
                let field = match e.field {
                    "fov_y" => "fov_y_degrees",
                    field => field,
                };
                (format!("camera.{field}"), e.message)
            })?;
        }
        if let Some(motion) = &self.motion {
            motion.check().map_err(within("motion"))?;
        }
        if self.lights.len() > MAX_LIGHTS {
            return fail(
                "lights",
                format!("{} lights, at most {MAX_LIGHTS} are supported", self.lights.len()),
            );
        }
        for (i, light) in self.lights.iter().enumerate() {
            light.check().map_err(within(&format!("lights[{i}]")))?;
        }
        let shadows: Vec<(String, Shadow)> = self
            .lights
            .iter()
            .enumerate()
            .filter_map(|(i, l)| Some((format!("lights[{i}].shadow"), l.shadow()?)))
            .collect();
        check_shadows(&shadows).or_else(|(field, why)| fail(&field, why))?;
        // Its settings here; how many cubes the file's point lights add is known once the
        // file is read (scenes.rs).
        if let Some(spec) = self.file_light_shadows {
            if self.file_lights == FileLights::Replace {
                return fail(
                    "file_light_shadows",
                    "is given but file_lights is replace: the file's lights do not shine".into(),
                );
            }
            check_shadows(&[("file_light_shadows".into(), spec.settings())])
                .or_else(|(field, why)| fail(&field, why))?;
        }
        for (name, value) in [("ambient", self.ambient), ("background", self.background)] {
            if !value.iter().all(|c| c.is_finite() && *c >= 0.0) {
                return fail(name, "components must be finite and ≥ 0".into());
            }
        }
        if self.stall_iterations > MAX_STALL_ITERATIONS {
            return fail(
                "stall_iterations",
                format!(
                    "{} exceeds {MAX_STALL_ITERATIONS}, the most lavapipe honours (it ends any shader \
                     invocation after 65 535 loop iterations; the stall loop takes 16 steps per iteration)",
                    self.stall_iterations
                ),
            );
        }
        self.adaptive.check().map_err(within("adaptive"))?;
        if let Some(exposure) = self.tonemap.exposure
            && !(exposure > 0.0 && exposure <= MAX_EXPOSURE)
        {
            return fail("tonemap.exposure", format!("{exposure} must be > 0 and at most {MAX_EXPOSURE:e}"));
        }
        self.validate_color()?;
        self.gate.validate()
    }

    fn validate_color(&self) -> Result<(), (String, String)> {
        let fail = |field: &str, message: String| Err((field.to_string(), message));
        if self.dynamic_range == DynamicRange::Ldr
            && let Some((field, _)) = self.tonemap.curve_fields().into_iter().find(|(_, v)| v.is_some())
        {
            return fail(
                &format!("tonemap.{field}"),
                "an LDR scene (dynamic_range \"ldr\") has no tonemap curve; only exposure applies".into(),
            );
        }
        if ![8, 10].contains(&self.display.bits) {
            return fail("display.bits", format!("{} must be 8 or 10", self.display.bits));
        }
        if self.display.peak_nits.is_some() && self.display.transfer != TransferSpec::Pq {
            return fail("display.peak_nits", "only the pq transfer has a display peak".into());
        }
        self.color_settings().validate().or_else(|error| {
            let section = if error.field == "peak_nits" { "display" } else { "tonemap" };
            fail(&format!("{section}.{}", error.field), error.message)
        })
    }
}

/// Whether a path leaves the folder it is relative to: absolute, or more `..` than folders
/// before them (judged on the text: a symbolic link on the way is `scenes::confined`'s to
/// catch).
fn escapes(path: &Path) -> bool {
    use std::path::Component;
    let mut depth = 0i64;
    for component in path.components() {
        match component {
            Component::Prefix(_) | Component::RootDir => return true,
            Component::ParentDir => depth -= 1,
            Component::Normal(_) => depth += 1,
            Component::CurDir => {}
        }
        if depth < 0 {
            return true;
        }
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    const VALID: &str = r#"{
        "schema_version": 1,
        "name": "edge",
        "gltf": "cache/edge.glb",
        "generate": { "generator": "edge", "seed": 3 },
        "resolution": { "quick": [64, 48], "nightly": [1024, 768] },
        "lights": [{ "position": [0, 1, 2], "intensity": 5, "range": 10 }]
    }"#;

    /// Parses `VALID` with `edit` applied to its JSON and expects an error naming the file,
    /// `field` and something containing `reason`.
    fn check(edit: impl Fn(&mut serde_json::Value), field: &str, reason: &str) {
        let mut json: serde_json::Value = serde_json::from_str(VALID).unwrap();
        edit(&mut json);
        let path = Path::new("scenes/edge.json");
        let error = Manifest::parse(path, &json.to_string()).expect_err("should be rejected");
        let text = error.to_string();
        assert_eq!(error.field, field, "{text}");
        assert!(text.starts_with("scenes/edge.json: "), "{text}");
        assert!(error.message.contains(reason), "{text}");
    }

    #[test]
    fn a_file_of_ones_own_is_read_from_anywhere() {
        let own = |gltf: &str| {
            let mut json: serde_json::Value = serde_json::from_str(VALID).unwrap();
            json.as_object_mut().unwrap().remove("generate");
            json["gltf"] = serde_json::json!(gltf);
            Manifest::parse(Path::new("scenes/mine.json"), &json.to_string()).unwrap().gltf_path()
        };
        assert_eq!(own("../assets/Sponza/Sponza.gltf"), Path::new("scenes/../assets/Sponza/Sponza.gltf"));
        assert_eq!(own("/data/assets/box.glb"), Path::new("/data/assets/box.glb"));
    }

    #[test]
    fn a_valid_manifest_parses_with_defaults() {
        let manifest = Manifest::parse(Path::new("scenes/edge.json"), VALID).unwrap();
        assert_eq!(manifest.gltf_path(), Path::new("scenes/cache/edge.glb"));
        assert_eq!(
            manifest.generator().map(|g| (g.generator.to_string(), g.seed, g.placement)),
            Some(("edge".into(), 3, Placement::IDENTITY))
        );
        assert_eq!(manifest.lights[0].color, [1.0; 3]);
        assert_eq!(manifest.stall_iterations, 256);
        assert_eq!(manifest.adaptive.settings(), AdaptiveSettings::default());
        assert!(manifest.camera.is_none());
        assert_eq!(manifest.gate, Tolerances::default());
        let mut json: serde_json::Value = serde_json::from_str(VALID).unwrap();
        json["gate"] = serde_json::json!({ "time_ratio": 0.2 });
        let custom = Manifest::parse(Path::new("scenes/edge.json"), &json.to_string()).unwrap();
        assert_eq!(custom.gate, Tolerances { time_ratio: 0.2, ..Tolerances::default() });
    }

    #[test]
    fn malformed_manifests_name_the_file_and_the_field() {
        use serde_json::json;
        check(|j| j["colour"] = json!(1), "colour", "unknown field `colour`");
        check(|j| j["lights"][0]["colour"] = json!([1, 1, 1]), "lights[0].colour", "unknown field `colour`");
        check(|j| j["lights"][0]["range"] = json!("far"), "lights[0].range", "invalid type");
        check(|j| j["lights"][0]["range"] = json!(0), "lights[0].range", "must be finite and > 0");
        check(|j| j["lights"][0]["intensity"] = json!(-1), "lights[0].intensity", "≥ 0");
        check(|j| j["resolution"]["quick"] = json!([0, 48]), "resolution.quick", "between 1 and 4096");
        check(|j| j["resolution"]["nightly"] = json!([1024]), "resolution.nightly", "invalid length");
        check(
            |j| {
                j.as_object_mut().unwrap().remove("gltf");
            },
            "",
            "missing field `gltf`",
        );
        check(|j| j["schema_version"] = json!(2), "schema_version", "reads version 1");
        check(|j| j["name"] = json!("Edge Scene"), "name", "lowercase");
        check(
            |j| j["generate"]["generator"] = json!("sponza"),
            "generate.generator",
            "unknown generator `sponza`",
        );
        check(
            |j| j["camera"] = json!({"position": [0, 0, 1], "target": [0, 0, 0], "fov_y_degrees": 200}),
            "camera.fov_y_degrees",
            "within [0.01°, 179°]",
        );
        check(
            |j| j["camera"] = json!({"position": [0, 0, 1], "target": [0, 0, 1], "fov_y_degrees": 60}),
            "camera.target",
            "lies on the position",
        );
        check(
            |j| j["camera"] = json!({"position": [0, 0, 1], "target": [0, 0, 0], "fov_y_degrees": 60, "near": 1, "far": 0.5}),
            "camera.far",
            "must be > near (1)",
        );
        check(
            |j| {
                j["camera"] =
                    json!({"position": [0, 0, 1], "target": [0, 0, 0], "fov_y_degrees": 60, "near": 1e-50})
            },
            "camera.near",
            "within [1e-6, 1e9]",
        );
        check(|j| j["adaptive"] = json!({"t_edge": 2}), "adaptive.t_edge", "[0, 1]");
        check(|j| j["adaptive"] = json!({"stable_hold": 1.5}), "adaptive.stable_hold", "[0, 1]");
        check(|j| j["adaptive"] = json!({"stable_decay": -1}), "adaptive.stable_decay", "[0, 1]");
        check(|j| j["adaptive"] = json!({"c_depth": -1}), "adaptive.c_depth", "within [0, 1e12]");
        check(|j| j["adaptive"] = json!({"c_normal": 1e13}), "adaptive.c_normal", "within [0, 1e12]");
        check(
            |j| j["adaptive"] = json!({"depth_metric": "linear"}),
            "adaptive.depth_metric",
            "unknown variant",
        );
        check(|j| j["stall_iterations"] = json!(1_000_001), "stall_iterations", "65 535 loop iterations");
        check(|j| j["gltf"] = json!("../elsewhere.glb"), "gltf", "generated files stay inside");
        check(|j| j["gltf"] = json!("/tmp/elsewhere.glb"), "gltf", "generated files stay inside");
        check(
            |j| j["camera"] = json!({"position": [1e300, 0, 1], "target": [0, 0, 0], "fov_y_degrees": 60}),
            "camera.position",
            "within ±1e12",
        );
        check(
            |j| {
                j["camera"] =
                    json!({"position": [0, 0, 1], "target": [0, 0, 0], "up": [0, 0, 2], "fov_y_degrees": 60})
            },
            "camera.up",
            "parallel to the view direction",
        );
        check(|j| j["adaptive"] = json!({"c_dept": 1}), "adaptive.c_dept", "unknown field `c_dept`");
        check(|j| j["tonemap"] = json!({"exposure": 0}), "tonemap.exposure", "> 0");
        check(|j| j["tonemap"] = json!({"hdr_max": 0.1}), "tonemap.hdr_max", "greater than mid_in");
        check(|j| j["tonemap"] = json!({"contrast": 0}), "tonemap.contrast", "> 0");
        check(|j| j["tonemap"] = json!({"contrast": 9, "hdr_max": 6e4}), "tonemap.contrast", "f32");
        check(|j| j["tonemap"] = json!({"exposure": 1e30}), "tonemap.exposure", "at most");
        check(|j| j["tonemap"] = json!({"hdr_max": 1e6}), "tonemap.hdr_max", "[0, 65504]");
        check(|j| j["tonemap"] = json!({"crosstalk": 1000}), "tonemap.crosstalk", "[0.01, 100]");
        check(|j| j["tonemap"] = json!({"shoulder": -2}), "tonemap.shoulder", "> 0");
        check(|j| j["tonemap"] = json!({"shoulder": 1.5}), "tonemap.shoulder", "not increasing");
        check(|j| j["tonemap"] = json!({"mid_out": 1.2}), "tonemap.mid_out", "(0, 1)");
        check(|j| j["tonemap"] = json!({"mid_in": "x"}), "tonemap.mid_in", "invalid type");
        check(
            |j| {
                j["dynamic_range"] = json!("ldr");
                j["tonemap"] = json!({"contrast": 1.2});
            },
            "tonemap.contrast",
            "LDR scene",
        );
        check(|j| j["dynamic_range"] = json!("vdr"), "dynamic_range", "unknown variant");
        check(|j| j["display"] = json!({"bits": 12}), "display.bits", "8 or 10");
        check(|j| j["display"] = json!({"transfer": "pq", "peak_nits": 0}), "display.peak_nits", "> 0");
        check(|j| j["display"] = json!({"transfer": "pq", "peak_nits": 2e4}), "display.peak_nits", "10000");
        check(|j| j["display"] = json!({"peak_nits": 400}), "display.peak_nits", "only the pq");
        check(|j| j["display"] = json!({"transfer": "gamma2.4"}), "display.transfer", "unknown variant");
        check(|j| j["display"] = json!({"dither": "blue"}), "display.dither", "unknown variant");
        check(|j| j["gate"] = json!({"psnr_db": -0.1}), "gate.psnr_db", "≥ 0");
        check(|j| j["gate"] = json!({"time_ratio": 0}), "gate.time_ratio", "> 0");
        check(|j| j["gate"] = json!({"psnr": 1}), "gate.psnr", "unknown field `psnr`");
        check(|j| j["stall_iterations"] = json!(-5), "stall_iterations", "invalid value");
        check(|j| j["ambient"] = json!([0, -1, 0]), "ambient", "≥ 0");
        let light = json!({ "position": [0, 1, 2], "intensity": 5, "range": 10 });
        check(|j| j["lights"] = json!(vec![light.clone(); 65]), "lights", "at most 64");
        // Finite in f64, infinite as the f32 the shader gets (found by tests/fuzz.rs).
        check(|j| j["lights"][0]["position"] = json!([1e308, 0, 1]), "lights[0].position", "within ±1e12");
    }

    #[test]
    fn shadow_settings_are_validated_per_light() {
        use serde_json::json;
        let shadowed = |shadow: serde_json::Value| {
            move |j: &mut serde_json::Value| {
                j["lights"][0]["casts_shadows"] = json!(true);
                j["lights"][0]["shadow"] = shadow.clone();
            }
        };
        check(shadowed(json!({"resolution": 8})), "lights[0].shadow.resolution", "[16, 4096]");
        check(shadowed(json!({"bias": -0.1})), "lights[0].shadow.bias", "≥ 0");
        check(shadowed(json!({"radius": -1})), "lights[0].shadow.radius", "≥ 0");
        check(shadowed(json!({"radious": 1})), "lights[0].shadow.radious", "unknown field `radious`");
        check(
            |j| j["lights"][0]["shadow"] = json!({"bias": 0.1}),
            "lights[0].shadow",
            "casts_shadows is false",
        );
        let light = |resolution: u32| {
            json!({ "position": [0, 1, 2], "intensity": 5, "range": 10, "casts_shadows": true,
                    "shadow": { "resolution": resolution } })
        };
        check(
            |j| j["lights"] = json!([light(512), light(256)]),
            "lights[1].shadow.resolution",
            "one resolution",
        );
        check(|j| j["lights"] = json!(vec![light(64); 9]), "lights", "at most 8");
        check(|j| j["lights"] = json!(vec![light(4096); 2]), "lights", "768 MiB, more than 512 MiB");
        // The file's point lights: their settings here, their number once the file is read.
        check(
            |j| j["file_light_shadows"] = json!({"resolution": 8}),
            "file_light_shadows.resolution",
            "[16, 4096]",
        );
        check(
            |j| {
                j["file_light_shadows"] = json!({});
                j["file_lights"] = json!("replace");
            },
            "file_light_shadows",
            "file_lights is replace",
        );
        let mut json: serde_json::Value = serde_json::from_str(VALID).unwrap();
        json["lights"] = json!(vec![light(64); 8]);
        json["file_light_shadows"] = json!({"resolution": 512});
        Manifest::parse(Path::new("scenes/edge.json"), &json.to_string())
            .expect("eight shadow lights beside a file that may have no point light");
        // Defaults, and no shadow for a light that casts none.
        let mut json: serde_json::Value = serde_json::from_str(VALID).unwrap();
        shadowed(json!({"bias": 0.2}))(&mut json);
        let manifest = Manifest::parse(Path::new("scenes/edge.json"), &json.to_string()).unwrap();
        assert_eq!(manifest.lights[0].shadow(), Some(Shadow { bias: 0.2, ..Shadow::default() }));
        let plain = Manifest::parse(Path::new("scenes/edge.json"), VALID).unwrap();
        assert_eq!(plain.lights[0].shadow(), None);
    }

    #[test]
    fn syntax_errors_give_the_line_and_column() {
        let error =
            Manifest::parse(Path::new("scenes/x.json"), "{\n  \"name\": \"x\",\n  oops\n}").unwrap_err();
        assert!(error.to_string().contains("line 3 column 3"), "{error}");
        let error = Manifest::load(Path::new("scenes/does-not-exist.json")).unwrap_err();
        assert!(error.to_string().starts_with("scenes/does-not-exist.json: cannot read"), "{error}");
    }
}
