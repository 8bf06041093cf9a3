//! The manifest's colour sections: the dynamic range, exposure and tonemap curve, and how the
//! display image is encoded.

use aabench_renderer::color::Tonemap;
use serde::Deserialize;

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
    #[serde(default, deserialize_with = "super::narrow::option")]
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
    pub(super) fn curve_fields(&self) -> [(&'static str, Option<f64>); 8] {
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
#[derive(Debug, Clone, PartialEq, Deserialize)]
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
    /// The display ColorVideoVDP judges on, one of its named models (`aabench_cvvdp::Display::
    /// names`); omitted: [`DisplaySpec::jod_display`]'s default for the transfer.
    #[serde(default)]
    pub jod_display: Option<String>,
}

/// The largest exposure: 2⁴⁰ (40 stops), far past any scene, and far from f32's overflow.
pub(super) const MAX_EXPOSURE: f32 = 1.1e12;

/// A PQ display's peak when the manifest names none: a common HDR monitor.
pub const DEFAULT_PEAK_NITS: f64 = 1000.0;

/// ColorVideoVDP's display when the manifest names none: its standard Full HD monitor for a
/// display-referred transfer, its standard HDR monitor for PQ.
pub const DEFAULT_JOD_DISPLAY: &str = aabench_cvvdp::display::STANDARD_FHD;
pub const DEFAULT_HDR_JOD_DISPLAY: &str = "standard_hdr_pq";

impl DisplaySpec {
    /// The ColorVideoVDP display model a scene's JOD is judged on.
    pub fn jod_display(&self) -> &str {
        match (&self.jod_display, self.transfer) {
            (Some(name), _) => name,
            (None, TransferSpec::Pq) => DEFAULT_HDR_JOD_DISPLAY,
            (None, _) => DEFAULT_JOD_DISPLAY,
        }
    }
}

/// Whether ColorVideoVDP's display model `name` exists and decodes a display image of
/// `transfer`: a PQ image on a PQ display, any other on a display of sRGB or gamma code values.
pub fn check_jod_display(name: &str, transfer: TransferSpec) -> Result<(), String> {
    let display = aabench_cvvdp::Display::named(name)
        .map_err(|error| format!("{error}; one of: {}", aabench_cvvdp::Display::names().join(", ")))?;
    let pq_display = display.eotf == aabench_cvvdp::Eotf::Pq;
    match (transfer == TransferSpec::Pq, pq_display) {
        (true, false) => {
            Err(format!("`{name}` does not decode PQ; a pq display needs a PQ model such as standard_hdr_pq"))
        }
        (false, true) => Err(format!("`{name}` decodes PQ, and this display's transfer is not pq")),
        _ if display.eotf == aabench_cvvdp::Eotf::Linear => {
            Err(format!("`{name}` takes linear values, not code values"))
        }
        _ => Ok(()),
    }
}

fn eight() -> u32 {
    8
}

impl Default for DisplaySpec {
    fn default() -> Self {
        serde_json::from_str("{}").expect("every field has a default")
    }
}
