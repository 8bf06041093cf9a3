//! The display model: how code values become light (photometry) and how large a pixel looks
//! (geometry), as the reference's `display_model.py` defines them.

use serde::Deserialize;
use std::collections::BTreeMap;

use crate::Error;

const DISPLAY_MODELS_JSON: &str = include_str!("../data/display_models.json");
const COLOR_SPACES_JSON: &str = include_str!("../data/color_spaces.json");

/// The reference's default for comparisons on a desktop: a 24-inch Full HD monitor of
/// 200 cd/m², 1000:1, under 250 lux of office light, seen from 0.6 m (about 38 pixels a degree).
pub const STANDARD_FHD: &str = "standard_fhd";

/// How code values in [0, 1] become luminance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Eotf {
    /// The sRGB curve.
    Srgb,
    /// SMPTE ST 2084, absolute.
    Pq,
    /// Values are already linear, in cd/m², scaled by the exposure.
    Linear,
    /// A pure power law with this exponent.
    Gamma(f32),
}

/// A display: its photometry and its pixels per degree at the viewing distance.
#[derive(Debug, Clone)]
pub struct Display {
    /// The model's name in `display_models.json`.
    pub name: String,
    pub eotf: Eotf,
    /// RGB → XYZ of the display's primaries, by rows.
    pub rgb_to_xyz: [[f32; 3]; 3],
    /// Peak luminance, cd/m².
    pub peak: f32,
    /// Contrast, peak over black.
    pub contrast: f32,
    /// Ambient illuminance, lux.
    pub ambient_lux: f32,
    /// The screen's reflectivity.
    pub reflectivity: f32,
    pub exposure: f32,
    pub pixels_per_degree: f64,
}

#[derive(Deserialize)]
struct Model {
    resolution: [f64; 2],
    colorspace: Option<String>,
    max_luminance: f32,
    min_luminance: Option<f32>,
    contrast: Option<f32>,
    #[serde(rename = "E_ambient")]
    ambient: Option<f32>,
    k_refl: Option<f32>,
    exposure: Option<f32>,
    pixels_per_degree: Option<f64>,
    fov_diagonal: Option<f64>,
    viewing_distance_meters: Option<f64>,
    viewing_distance_inches: Option<f64>,
    diagonal_size_meters: Option<f64>,
    diagonal_size_inches: Option<f64>,
}

#[derive(Deserialize)]
struct ColorSpace {
    #[serde(rename = "EOTF")]
    eotf: String,
    #[serde(rename = "RGB2X")]
    rgb2x: Option<[f32; 3]>,
    #[serde(rename = "RGB2Y")]
    rgb2y: Option<[f32; 3]>,
    #[serde(rename = "RGB2Z")]
    rgb2z: Option<[f32; 3]>,
}

const INCH: f64 = 0.0254;

impl Display {
    /// The reference's `standard_fhd`.
    pub fn standard_fhd() -> Self {
        Self::named(STANDARD_FHD).expect("the vendored display models name standard_fhd")
    }

    /// The names of the vendored display models.
    pub fn names() -> Vec<String> {
        let models: BTreeMap<String, serde_json::Value> =
            serde_json::from_str(DISPLAY_MODELS_JSON).expect("the vendored display_models.json parses");
        models.into_keys().collect()
    }

    /// A display of the vendored models by name (`standard_fhd`, `standard_4k`, …).
    pub fn named(name: &str) -> Result<Self, Error> {
        let mut models: BTreeMap<String, Model> =
            serde_json::from_str(DISPLAY_MODELS_JSON).expect("the vendored display_models.json parses");
        let model = models.remove(name).ok_or_else(|| Error::UnknownDisplay(name.to_string()))?;
        let space_name = model.colorspace.clone().unwrap_or_else(|| "sRGB".to_string());
        let mut spaces: BTreeMap<String, ColorSpace> =
            serde_json::from_str(COLOR_SPACES_JSON).expect("the vendored color_spaces.json parses");
        let space = spaces.remove(&space_name).expect("every vendored display's colour space is vendored");
        let eotf = match space.eotf.as_str() {
            "sRGB" => Eotf::Srgb,
            "PQ" => Eotf::Pq,
            "linear" => Eotf::Linear,
            other => match other.parse::<f32>() {
                Ok(gamma) => Eotf::Gamma(gamma),
                Err(_) => {
                    return Err(Error::UnsupportedDisplay {
                        name: name.to_string(),
                        feature: format!("the EOTF {other}"),
                    });
                }
            },
        };
        let rgb_to_xyz = match (space.rgb2x, space.rgb2y, space.rgb2z) {
            (Some(x), Some(y), Some(z)) => [x, y, z],
            _ => {
                return Err(Error::UnsupportedDisplay {
                    name: name.to_string(),
                    feature: format!("the colour space {space_name}, which has no primaries"),
                });
            }
        };
        Ok(Display {
            name: name.to_string(),
            eotf,
            rgb_to_xyz,
            peak: model.max_luminance,
            contrast: model
                .min_luminance
                .map_or(model.contrast.unwrap_or(500.0), |min| model.max_luminance / min),
            ambient_lux: model.ambient.unwrap_or(0.0),
            reflectivity: model.k_refl.unwrap_or(0.005),
            exposure: model.exposure.unwrap_or(1.0),
            pixels_per_degree: model.pixels_per_degree.unwrap_or_else(|| geometry_ppd(&model)),
        })
    }

    /// The display's black level and the light its screen reflects, cd/m².
    pub fn black_and_reflection(&self) -> (f32, f32) {
        let reflected = self.ambient_lux / std::f32::consts::PI * self.reflectivity;
        (self.peak / self.contrast, reflected)
    }

    /// The luminance (or linear colour component) a code value gives, cd/m²; values outside
    /// [0, 1] are clamped, as the reference does with a warning.
    pub fn luminance(&self, code: f32) -> f32 {
        let (black, reflected) = self.black_and_reflection();
        let v = if self.eotf == Eotf::Linear { code } else { code.clamp(0.0, 1.0) };
        let scaled = |linear: f32| {
            if self.exposure == 1.0 { linear } else { (linear * self.exposure).clamp(0.0, 1.0) }
        };
        match self.eotf {
            Eotf::Srgb => (self.peak - black) * scaled(srgb_to_linear(v)) + black + reflected,
            Eotf::Gamma(gamma) => {
                (self.peak - black) * (v.powf(gamma) * self.exposure).clamp(0.0, 1.0) + black + reflected
            }
            Eotf::Pq => (pq_to_linear(v) * self.exposure).clamp(0.005, self.peak) + black + reflected,
            Eotf::Linear => (v * self.exposure).clamp(black.max(0.005), self.peak) + reflected,
        }
    }
}

/// The sRGB decoding curve.
fn srgb_to_linear(v: f32) -> f32 {
    if v > 0.04045 { ((v + 0.055) / 1.055).powf(2.4) } else { v / 12.92 }
}

/// SMPTE ST 2084 decoding, cd/m².
fn pq_to_linear(v: f32) -> f32 {
    const M: f32 = 78.84375;
    const N: f32 = 0.159_301_76;
    const C1: f32 = 0.835_937_5;
    const C2: f32 = 18.851_563;
    const C3: f32 = 18.6875;
    let t = v.powf(1.0 / M);
    10_000.0 * ((t - C1).max(0.0) / (C2 - C3 * t)).powf(1.0 / N)
}

/// Pixels per degree at the centre of the screen, from its size and viewing distance (the
/// reference's `vvdp_display_geometry`).
fn geometry_ppd(model: &Model) -> f64 {
    let [width_px, height_px] = model.resolution;
    let aspect = width_px / height_px;
    let diagonal_inches = model.diagonal_size_meters.map(|m| m / INCH).or(model.diagonal_size_inches);
    let distance = model
        .viewing_distance_meters
        .or(model.viewing_distance_inches.map(|inches| inches * INCH))
        .unwrap_or(3.0);
    let width_m = if let Some(fov) = model.fov_diagonal {
        let distance_px =
            (width_px.powi(2) + height_px.powi(2)).sqrt() / (2.0 * (fov * 0.5).to_radians().tan());
        let height_deg = (height_px / 2.0 / distance_px).atan().to_degrees() * 2.0;
        2.0 * (height_deg / 2.0).to_radians().tan() * distance * aspect
    } else {
        let diagonal_mm = diagonal_inches.unwrap_or(0.0) * 25.4;
        aspect * (diagonal_mm.powi(2) / (1.0 + aspect.powi(2))).sqrt() / 1000.0
    };
    let pixel_deg = 2.0 * (0.5 * width_m / width_px / distance).atan().to_degrees();
    1.0 / pixel_deg
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_standard_fhd_display_is_the_references() {
        let display = Display::standard_fhd();
        assert!((display.pixels_per_degree - 37.842_503_853_602_885).abs() < 1e-9);
        let (black, reflected) = display.black_and_reflection();
        assert!((black - 0.2).abs() < 1e-6 && (reflected - 0.397_887_36).abs() < 1e-6);
        assert!((display.luminance(1.0) - (200.0 + reflected)).abs() < 1e-3);
    }

    #[test]
    fn every_vendored_display_but_hlg_loads() {
        for name in Display::names() {
            match Display::named(&name) {
                Ok(display) => assert!(display.pixels_per_degree > 1.0, "{name}"),
                Err(Error::UnsupportedDisplay { feature, .. }) => assert_eq!(feature, "the EOTF HLG"),
                Err(other) => panic!("{name}: {other}"),
            }
        }
        assert!(matches!(Display::named("crt"), Err(Error::UnknownDisplay(_))));
    }
}
