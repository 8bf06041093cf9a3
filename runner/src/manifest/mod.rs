//! Scene manifests: `scenes/*.json`, schema version 1. Parsing rejects unknown fields, and
//! every error names the file and the field (`scenes/atrium.json: lights[2].range: must be > 0`).
//! The sections of the scene itself are in `sections.rs`, the colour sections in `display.rs`,
//! the camera path in `motion/` and the gate's tolerances in `tolerances.rs`.

mod display;
pub mod motion;
mod narrow;
mod sections;
pub mod tolerances;

pub use display::{
    DEFAULT_PEAK_NITS, DisplaySpec, DitherSpec, DynamicRange, TonemapSpec, TransferSpec, check_jod_display,
};
pub use sections::{
    AdaptiveSpec, CameraSpec, DepthMetricSpec, FileLights, Generate, LightSpec, Resolutions, ShadowSpec,
    check_shadows,
};

use std::fmt;
use std::path::{Path, PathBuf};

use aabench_renderer::color::{ColorSettings, Dither, Transfer};
use aabench_renderer::scene::generate::{Generated, Placement};
use aabench_renderer::scene::{MAX_LIGHTS, Shadow};
use serde::Deserialize;

use display::MAX_EXPOSURE;
use motion::MotionSpec;
use tolerances::Tolerances;

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
    #[serde(default = "default_ambient", deserialize_with = "narrow::triple")]
    pub ambient: [f32; 3],
    #[serde(default = "default_background", deserialize_with = "narrow::triple")]
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
    /// A camera path: the scene is also rendered as a sequence (`motion/mod.rs`).
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
pub(crate) type Invalid = (String, String);

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
        crate::files::regular_file(path).map_err(unreadable)?;
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

    fn validate(&self) -> Result<(), Invalid> {
        self.validate_identity()?;
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
        self.validate_lights()?;
        for (name, value) in [("ambient", self.ambient), ("background", self.background)] {
            if !value.iter().all(|c| c.is_finite() && *c >= 0.0) {
                return Err((name.into(), "components must be finite and ≥ 0".into()));
            }
        }
        if self.stall_iterations > MAX_STALL_ITERATIONS {
            return Err((
                "stall_iterations".into(),
                format!(
                    "{} exceeds {MAX_STALL_ITERATIONS}, the most lavapipe honours (it ends any shader \
                     invocation after 65 535 loop iterations; the stall loop takes 16 steps per iteration)",
                    self.stall_iterations
                ),
            ));
        }
        self.adaptive.check().map_err(within("adaptive"))?;
        if let Some(exposure) = self.tonemap.exposure
            && !(exposure > 0.0 && exposure <= MAX_EXPOSURE)
        {
            let why = format!("{exposure} must be > 0 and at most {MAX_EXPOSURE:e}");
            return Err(("tonemap.exposure".into(), why));
        }
        self.validate_color()?;
        self.gate.validate()
    }

    /// The schema, the name, and the file: where a generated one may be written.
    fn validate_identity(&self) -> Result<(), Invalid> {
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
        Ok(())
    }

    /// The lights and their shadows, and the shadows of the file's lights.
    fn validate_lights(&self) -> Result<(), Invalid> {
        let fail = |field: &str, message: String| Err((field.to_string(), message));
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
        check_shadows(&shadows)?;
        // Its settings here; how many cubes the file's point lights add is known once the
        // file is read (scenes.rs).
        if let Some(spec) = self.file_light_shadows {
            if self.file_lights == FileLights::Replace {
                return fail(
                    "file_light_shadows",
                    "is given but file_lights is replace: the file's lights do not shine".into(),
                );
            }
            check_shadows(&[("file_light_shadows".into(), spec.settings())])?;
        }
        Ok(())
    }

    fn validate_color(&self) -> Result<(), Invalid> {
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
        if let Err(why) = display::check_jod_display(self.display.jod_display(), self.display.transfer) {
            return fail("display.jod_display", why);
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
mod tests;
