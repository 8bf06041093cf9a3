//! The colour pipeline from linear HDR radiance to display code values, after Lottes,
//! "Advanced Techniques and Optimization of HDR/VDR Color Pipelines" (GDC 2016): a tonemap on
//! max(R, G, B) with crosstalk and saturation, a transfer function, energy-preserving dither
//! and quantization to 8 or 10 bits.
//!
//! `shaders/lib/color.wgsl` runs it on the GPU. The functions here are its CPU twins, in f64:
//! tests hold the shaders to them, and they solve the constants that the shaders take as
//! override constants (the tonemap's b and c, the dither's black and biggest step).

/// Rec. 709 luminance of a linear colour (or the luma of an encoded one, with the same weights):
/// the renderer's exposure meter, the shading metric's luma and the report's error maps weigh
/// the channels so. FXAA keeps the Rec. 601 weights its reference's luma pass gives.
pub fn luminance([r, g, b]: [f64; 3]) -> f64 {
    0.2126 * r + 0.7152 * g + 0.0722 * b
}

/// The tonemapping curve and colour controls of an HDR scene. The curve acts on the largest
/// channel: z = x^contrast, y = z / (z^shoulder · b + c), with b and c solved so that `mid_in`
/// maps to `mid_out` and `hdr_max` to 1; the colour ratio rgb / max is kept and pushed towards
/// white as the maximum nears 1 (crosstalk).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tonemap {
    pub mid_in: f64,
    pub mid_out: f64,
    pub hdr_max: f64,
    pub contrast: f64,
    pub shoulder: f64,
    /// Exponent of the tonemapped maximum that blends the ratio towards white: higher keeps
    /// colours saturated further into the highlights.
    pub crosstalk: f64,
    /// Saturation over the whole tonal range (1: unchanged).
    pub saturation: f64,
    /// The space in which crosstalk blends: the ratio is raised to 1 / cross_saturation
    /// before the blend and back after it, so brighter channels reach white first (the
    /// slides' "indirect path to white").
    pub cross_saturation: f64,
}

impl Default for Tonemap {
    /// The slides' curve (midIn 0.18, midOut 0.18, hdrMax 64, contrast 1.3, shoulder 0.995).
    /// The slides give no numbers for the colour controls; these leave mid-tone colour exactly
    /// as shaded (saturation 1) and start the path to white in the top stop.
    fn default() -> Self {
        Tonemap {
            mid_in: 0.18,
            mid_out: 0.18,
            hdr_max: 64.0,
            contrast: 1.3,
            shoulder: 0.995,
            crosstalk: 4.0,
            saturation: 1.0,
            cross_saturation: 4.0,
        }
    }
}

/// A parameter that cannot make a display image: the field (as the manifest spells it) and why.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{field}: {message}")]
pub struct ColorError {
    pub field: &'static str,
    pub message: String,
}

fn fail<T>(field: &'static str, message: String) -> Result<T, ColorError> {
    Err(ColorError { field, message })
}

/// The solved curve: what the tonemap shader takes as constants.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Curve {
    pub contrast: f64,
    pub shoulder: f64,
    pub b: f64,
    pub c: f64,
}

impl Curve {
    /// y = z / (z^shoulder · b + c) with z = x^contrast, for x ≥ 0.
    pub fn apply(&self, x: f64) -> f64 {
        let z = x.max(0.0).powf(self.contrast);
        z / (z.powf(self.shoulder) * self.b + self.c)
    }
}

impl Tonemap {
    /// Solves b and c (the slides' closed form, in f64) after checking every parameter. The
    /// curve must be increasing on [0, hdr_max], or bright pixels would come out darker than
    /// dim ones, and every constant the shader takes must stay well inside f32's range, where
    /// the shader evaluates it.
    pub fn curve(&self) -> Result<Curve, ColorError> {
        // Each field's range; the colour controls are exponents, kept to what a grade uses.
        let fields = [
            ("mid_in", self.mid_in, 1e-6, HALF_MAX),
            ("mid_out", self.mid_out, 0.0, 1.0),
            ("hdr_max", self.hdr_max, 0.0, HALF_MAX),
            ("contrast", self.contrast, 0.0, 10.0),
            ("shoulder", self.shoulder, 0.0, 10.0),
            ("crosstalk", self.crosstalk, 0.01, 100.0),
            ("saturation", self.saturation, 0.01, 100.0),
            ("cross_saturation", self.cross_saturation, 0.01, 100.0),
        ];
        for (field, value, low, high) in fields {
            if !value.is_finite() {
                return fail(field, format!("{value} is not a finite number"));
            }
            if value <= 0.0 {
                return fail(field, format!("{value} must be > 0"));
            }
            if field == "mid_out" && value >= 1.0 {
                return fail(field, format!("{value} must be in (0, 1): the curve's top is 1"));
            }
            if value < low || value > high {
                return fail(field, format!("{value} must be in [{low}, {high}]"));
            }
        }
        if self.hdr_max <= self.mid_in {
            return fail(
                "hdr_max",
                format!("{} must be greater than mid_in ({})", self.hdr_max, self.mid_in),
            );
        }
        let (a, d) = (self.contrast, self.shoulder);
        let mid = self.mid_in.powf(a);
        let max = self.hdr_max.powf(a);
        let denominator = (max.powf(d) - mid.powf(d)) * self.mid_out;
        let b = (-mid + max * self.mid_out) / denominator;
        let c = (max.powf(d) * mid - max * mid.powf(d) * self.mid_out) / denominator;
        let curve = Curve { contrast: a, shoulder: d, b, c };
        let in_f32 = |v: f64| v.is_finite() && v.abs() < 1e30 && (v == 0.0 || v.abs() > 1e-30);
        if !(in_f32(max) && in_f32(max.powf(d)) && in_f32(b) && in_f32(c)) {
            // The curve spans mid_in^contrast … hdr_max^contrast: a tiny contrast shrinks that
            // span to nothing, a huge one blows it past f32.
            let advice = if max.powf(d) == mid.powf(d) {
                "mid_in and hdr_max land on the same value, so the curve has no range: raise contrast"
            } else {
                "beyond what the shader's f32 arithmetic holds: lower contrast or hdr_max"
            };
            return fail(
                "contrast",
                format!(
                    "hdr_max^contrast = {max:e} with shoulder {d} gives b = {b:e} and c = {c:e}: {advice}"
                ),
            );
        }
        // dy/dz has the sign of b·z^d·(1 − d) + c, which is monotonic in z: positive at both
        // ends of [0, hdr_max^a] means positive throughout (and c > 0 keeps the denominator
        // away from zero).
        let slope_at = |z: f64| b * z.powf(d) * (1.0 - d) + c;
        if !(b.is_finite() && c.is_finite() && c > 0.0 && slope_at(max) > 0.0) {
            return fail(
                "shoulder",
                format!(
                    "with contrast {a}, shoulder {d}, mid_in {} → mid_out {} and hdr_max {} the curve \
                     (b = {b:.6}, c = {c:.6}) is not increasing on [0, hdr_max]; lower the shoulder or \
                     mid_out, or raise hdr_max",
                    self.mid_in, self.mid_out, self.hdr_max
                ),
            );
        }
        Ok(curve)
    }

    /// The CPU twin of `tonemap` in `lib/color.wgsl`: linear exposed HDR to linear display
    /// [0, 1]. `curve` is [`Self::curve`]'s.
    pub fn apply(&self, curve: &Curve, rgb: [f64; 3]) -> [f64; 3] {
        let rgb = rgb.map(|v| v.max(0.0));
        let peak = rgb[0].max(rgb[1]).max(rgb[2]);
        if peak <= 0.0 {
            return [0.0; 3];
        }
        let mapped = curve.apply(peak.min(self.hdr_max)).min(1.0);
        let white = mapped.powf(self.crosstalk);
        rgb.map(|v| {
            let ratio = (v / peak).max(RATIO_FLOOR).powf(self.saturation / self.cross_saturation);
            let blended = ratio + (1.0 - ratio) * white;
            blended.powf(self.cross_saturation) * mapped
        })
    }
}

/// The largest finite value of the Rgba16Float HDR target: what +Inf stands for, and the
/// largest hdr_max that means anything.
pub const HALF_MAX: f64 = 65504.0;

/// The twin of `sanitize` in shaders/lib/finite.wgsl: NaN and −Inf → 0, +Inf → [`HALF_MAX`],
/// negatives → 0, the rest clamped to [0, HALF_MAX].
pub fn sanitize(x: f64) -> f64 {
    match x {
        x if x.is_nan() => 0.0,
        x if x == f64::INFINITY => HALF_MAX,
        x => x.clamp(0.0, HALF_MAX),
    }
}

/// The smallest colour ratio the tonemap raises to a power: pow(0, y) is exp2(y · log2(0)),
/// which leans on an infinity the shader compiler may assume away.
pub const RATIO_FLOOR: f64 = 1e-12;

/// Display transfer functions: display-relative linear light [0, 1] to the encoded signal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Transfer {
    /// IEC 61966-2-1.
    Srgb,
    /// ITU-R BT.709's camera curve.
    Rec709,
    /// A pure power 1 / 2.2.
    Gamma22,
    /// SMPTE ST 2084 (PQ): absolute luminance up to 10 000 nits; linear 1 is the display's
    /// peak.
    Pq { peak_nits: f64 },
}

/// BT.709's α and β to the precision that joins its two segments (the standard's rounded
/// 1.099 and 0.018 leave a step of 2.5e-4 at the join).
const REC709_ALPHA: f64 = 1.099_296_826_809_44;
const REC709_BETA: f64 = 0.018_053_968_510_807;

const PQ_M1: f64 = 0.159_301_757_812_5;
const PQ_M2: f64 = 78.843_75;
const PQ_C1: f64 = 0.835_937_5;
const PQ_C2: f64 = 18.851_562_5;
const PQ_C3: f64 = 18.687_5;
/// PQ's encoding peak in nits.
pub const PQ_MAX_NITS: f64 = 10_000.0;

impl Transfer {
    /// Its id in the shader's `TRANSFER` override constant.
    pub fn shader_id(self) -> u32 {
        match self {
            Transfer::Srgb => 0,
            Transfer::Rec709 => 1,
            Transfer::Gamma22 => 2,
            Transfer::Pq { .. } => 3,
        }
    }

    /// Display peak as a fraction of PQ's 10 000 nits (1 for the relative transfers).
    pub fn peak_fraction(self) -> f64 {
        match self {
            Transfer::Pq { peak_nits } => peak_nits / PQ_MAX_NITS,
            _ => 1.0,
        }
    }

    pub fn validate(self) -> Result<(), ColorError> {
        match self {
            Transfer::Pq { peak_nits } if !(peak_nits.is_finite() && peak_nits > 0.0) => {
                fail("peak_nits", format!("{peak_nits} must be finite and > 0"))
            }
            Transfer::Pq { peak_nits } if peak_nits > PQ_MAX_NITS => {
                fail("peak_nits", format!("{peak_nits} exceeds PQ's {PQ_MAX_NITS} nits"))
            }
            _ => Ok(()),
        }
    }

    /// Linear (≥ 0) to signal. Defined past 1 too, where the dither's largest step needs it.
    pub fn encode(self, linear: f64) -> f64 {
        let l = linear.max(0.0);
        match self {
            Transfer::Srgb if l <= 0.003_130_8 => 12.92 * l,
            Transfer::Srgb => 1.055 * l.powf(1.0 / 2.4) - 0.055,
            Transfer::Rec709 if l < REC709_BETA => 4.5 * l,
            Transfer::Rec709 => REC709_ALPHA * l.powf(0.45) - (REC709_ALPHA - 1.0),
            Transfer::Gamma22 => l.powf(1.0 / 2.2),
            Transfer::Pq { peak_nits } => pq_encode(l * peak_nits / PQ_MAX_NITS),
        }
    }

    /// Signal to linear: the inverse of [`Self::encode`].
    pub fn decode(self, signal: f64) -> f64 {
        let v = signal.max(0.0);
        match self {
            Transfer::Srgb if v <= 0.040_45 => v / 12.92,
            Transfer::Srgb => ((v + 0.055) / 1.055).powf(2.4),
            Transfer::Rec709 if v < 4.5 * REC709_BETA => v / 4.5,
            Transfer::Rec709 => ((v + REC709_ALPHA - 1.0) / REC709_ALPHA).powf(1.0 / 0.45),
            Transfer::Gamma22 => v.powf(2.2),
            Transfer::Pq { peak_nits } => pq_decode(v) * PQ_MAX_NITS / peak_nits,
        }
    }
}

/// PQ of luminance as a fraction of 10 000 nits.
pub fn pq_encode(y: f64) -> f64 {
    let p = y.max(0.0).powf(PQ_M1);
    ((PQ_C1 + PQ_C2 * p) / (1.0 + PQ_C3 * p)).powf(PQ_M2)
}

/// Luminance as a fraction of 10 000 nits from a PQ signal.
pub fn pq_decode(signal: f64) -> f64 {
    let p = signal.max(0.0).powf(1.0 / PQ_M2);
    ((p - PQ_C1).max(0.0) / (PQ_C2 - PQ_C3 * p)).powf(1.0 / PQ_M1)
}

/// The grain added before quantization.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dither {
    Off,
    /// Uniform grain in [−1, 1].
    Symmetric,
    /// Two thirds of the grain negative in [−1/2, 0], one third positive in [0, 1]: the same
    /// mean (zero) with more of the small negative values that PQ's steep dark steps need
    /// to stop banding (the slides' asymmetric distribution).
    Asymmetric,
}

impl Dither {
    pub fn shader_id(self) -> u32 {
        match self {
            Dither::Off => 0,
            Dither::Symmetric => 1,
            Dither::Asymmetric => 2,
        }
    }
}

/// How the linear HDR image becomes the display image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ColorSettings {
    /// `None`: an LDR scene, exposed, clamped and encoded without a tonemap pass.
    pub tonemap: Option<Tonemap>,
    pub transfer: Transfer,
    /// Bits per channel of the display image: up to 8 quantize into an 8-bit target, 9 and
    /// 10 into a 10-bit one (manifests allow 8 and 10; tests use 3 to make steps visible).
    pub bits: u32,
    pub dither: Dither,
}

impl Default for ColorSettings {
    /// An HDR scene through the slides' tonemap to 8-bit sRGB, dithered.
    fn default() -> Self {
        ColorSettings {
            tonemap: Some(Tonemap::default()),
            transfer: Transfer::Srgb,
            bits: 8,
            dither: Dither::Symmetric,
        }
    }
}

/// The dither's constants for a transfer function and bit depth (the slides' "simple
/// energy-preserving dither"): `black` is the largest linear value that still quantizes to
/// zero (grain on black spans [−black, black] and stays black), `biggest` three quarters of
/// the largest linear step (at the peak). The slides write black as half the first step in
/// linear light, which is the same only where the transfer is linear near black (sRGB,
/// Rec. 709): for gamma 2.2 at 8 bits it would light 28 % of black pixels. `top` is the
/// peak's counterpart, which the slides leave out ("peaks not energy preserving"): where
/// rounding would pass the code that linear 1 takes, so no grain goes past it and clipping at
/// 1 takes no energy away (at 3 bits that error is 1 % of a gradient's mean).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DitherScale {
    pub black: f64,
    pub biggest: f64,
    pub top: f64,
}

impl ColorSettings {
    /// An LDR scene without dither: exposure, clamp and sRGB to 8 bits, as a plain renderer.
    pub fn plain() -> ColorSettings {
        ColorSettings { tonemap: None, transfer: Transfer::Srgb, bits: 8, dither: Dither::Off }
    }

    pub fn validate(&self) -> Result<(), ColorError> {
        if !(1..=10).contains(&self.bits) {
            return fail("bits", format!("{} must be in 1..=10", self.bits));
        }
        if let Some(tonemap) = &self.tonemap {
            tonemap.curve()?;
        }
        self.transfer.validate()
    }

    /// The largest code value: 255 at 8 bits, 1023 at 10.
    pub fn max_code(&self) -> u16 {
        ((1u32 << self.bits) - 1) as u16
    }

    pub fn dither_scale(&self) -> DitherScale {
        let step = 1.0 / f64::from(self.max_code());
        let t = self.transfer;
        DitherScale {
            // Just under half a step, so that f32 rounding in the shader cannot tip it over.
            black: t.decode(0.499 * step),
            biggest: 0.75 * (t.decode(t.encode(1.0) + step) - 1.0),
            top: t.decode(((t.encode(1.0) / step).round_ties_even() + 0.5) * step),
        }
    }

    /// The CPU twin of the display pass for one channel: display-relative linear light, the
    /// pixel's grain in [−1, 1] (0 without dither), to a code value.
    pub fn quantize(&self, linear: f64, grain: f64) -> u16 {
        let scale = self.dither_scale();
        let linear = linear.clamp(0.0, 1.0);
        let dithered = match self.dither {
            Dither::Off => linear,
            _ => linear + grain * (linear + scale.black).min(scale.biggest).min(scale.top - linear),
        };
        let max = f64::from(self.max_code());
        (self.transfer.encode(dithered.clamp(0.0, 1.0)) * max).round_ties_even() as u16
    }

    /// The CPU twin of `grain` in `lib/color.wgsl`: the pixel's grain for one channel.
    pub fn grain(&self, x: u32, y: u32, channel: u32) -> f64 {
        let unit = grain_unit(x, y, channel);
        match self.dither {
            Dither::Off => 0.0,
            Dither::Symmetric => 2.0 * unit - 1.0,
            Dither::Asymmetric if unit < 2.0 / 3.0 => -0.75 * unit,
            Dither::Asymmetric => 3.0 * (unit - 2.0 / 3.0),
        }
    }
}

/// PCG's output permutation as a 32-bit hash (Jarzynski & Olano 2020): one integer multiply
/// chain, no floating point, so the grain is the same bits on every device.
pub fn hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// Uniform in (0, 1), symmetric about 1/2: 24 bits of the hash of (x, y, channel).
pub fn grain_unit(x: u32, y: u32, channel: u32) -> f64 {
    let h = hash(hash(hash(x).wrapping_add(y)).wrapping_add(channel));
    (f64::from(h >> 8) + 0.5) / f64::from(1u32 << 24)
}

/// Automatic exposure's target: the log-average luminance maps to this, the tonemap's default
/// mid grey (`Tonemap::mid_in`).
pub const EXPOSURE_KEY: f64 = 0.18;

/// The range automatic exposure stays within: 2⁻²⁰ … 2²⁰ (a scene lit at 10⁶ lux, or by a
/// candle, still comes out seen).
pub const METERED_EXPOSURE_RANGE: [f32; 2] = [1.0 / 1_048_576.0, 1_048_576.0];

/// The share of the scene's pixels that may display white under automatic exposure.
pub const METERED_WHITE_SHARE: f64 = 0.02;

/// The share of the scene's pixels at the HDR target's limit that fails metering.
pub const METERED_SATURATED_SHARE: f64 = 0.01;

/// The exposure for a linear HDR image (RGBA, sanitized first) of which `scene` says which
/// pixels show the scene (the others, the background, are left out unless nothing shows it):
/// the one that maps the log-average luminance exp(mean(ln L)) of those pixels to `key`
/// (Reinhard et al.'s key value), unless that would display more than [`METERED_WHITE_SHARE`]
/// of them above `white` (the HDR value that displays white: the tonemap's `hdr_max`, or 1 where
/// the image is exposed and clamped); then the one that maps that share's brightest pixel to
/// `white`. Clamped to `range`. Black pixels are left out: no exposure shows them, and counting
/// them with a floor (Reinhard's δ) would tie the result to the light's unit, where leaving
/// them out makes it follow the light level exactly (a scene at 1000 times the light meters a
/// thousandth of the exposure). An image with no light at all meters 1. An image whose scene
/// reaches the f16 target's limit on more than [`METERED_SATURATED_SHARE`] of its pixels has
/// lost its light above that limit, which no exposure brings back: that is an error.
pub fn metered_exposure(
    hdr: &[[f32; 4]],
    scene: Option<&[bool]>,
    key: f64,
    white: f64,
    range: [f32; 2],
) -> Result<f32, String> {
    let metered = scene_pixels(hdr, scene);
    let share = saturated_share(&metered);
    if share > METERED_SATURATED_SHARE {
        return Err(format!(
            "{:.1} % of the scene's pixels reach the HDR target's limit of 65 504 at exposure 1: light \
             above it is lost, and no exposure shows it; scale the lights' intensities down",
            100.0 * share
        ));
    }
    let mut lit: Vec<f64> =
        metered.iter().copied().map(luminance).filter(|&luminance| luminance > 0.0).collect();
    if lit.is_empty() {
        return Ok(1.0);
    }
    let average = (lit.iter().map(|l| l.ln()).sum::<f64>() / lit.len() as f64).exp();
    lit.sort_by(f64::total_cmp);
    // The brightest pixel that may still display below white, counted among every metered
    // pixel (the black ones first); none where it is black.
    let rank = ((1.0 - METERED_WHITE_SHARE) * metered.len() as f64).ceil() as usize;
    let blacks = metered.len() - lit.len();
    let exposure = match rank.checked_sub(1 + blacks) {
        Some(i) => (key / average).min(white / lit[i.min(lit.len() - 1)]),
        None => key / average,
    };
    Ok((exposure as f32).clamp(range[0], range[1]))
}

/// The sanitized RGB of the pixels of `hdr` that show the scene (all of them where none does).
fn scene_pixels(hdr: &[[f32; 4]], scene: Option<&[bool]>) -> Vec<[f64; 3]> {
    let shows = |i: usize| scene.is_none_or(|covered| covered.get(i).copied().unwrap_or(false));
    let any_scene = (0..hdr.len()).any(shows);
    hdr.iter()
        .enumerate()
        .filter(|&(i, _)| !any_scene || shows(i))
        .map(|(_, p)| [p[0], p[1], p[2]].map(|c| sanitize(f64::from(c))))
        .collect()
}

/// The share of `pixels` with a channel at the HDR target's limit.
fn saturated_share(pixels: &[[f64; 3]]) -> f64 {
    let saturated = pixels.iter().filter(|p| p.iter().any(|&c| c >= HALF_MAX)).count();
    saturated as f64 / pixels.len().max(1) as f64
}

/// Whether a scene's own `exposure` shows its light (an HDR image, RGBA, of which `scene` says
/// which pixels show the scene): an error where more than [`METERED_SATURATED_SHARE`] of them
/// reach the HDR target's limit and the exposure maps that limit below `white` (the HDR value
/// that displays white), so that the light lost above the limit would show as a flat grey. An
/// exposure that displays the limit white hides the loss, and passes.
pub fn headroom(hdr: &[[f32; 4]], scene: Option<&[bool]>, exposure: f64, white: f64) -> Result<(), String> {
    if HALF_MAX * exposure >= white {
        return Ok(());
    }
    let share = saturated_share(&scene_pixels(hdr, scene));
    if share > METERED_SATURATED_SHARE {
        return Err(format!(
            "{:.1} % of the scene's pixels reach the HDR target's limit of 65 504, which exposure {:e} \
             displays below white: light above it is lost, and would show as a flat grey; scale the lights' \
             intensities down and the exposure up",
            100.0 * share,
            // The manifest's exposure is an f32: shown as written.
            exposure as f32
        ));
    }
    Ok(())
}

/// Whether the background shows as the manifest gives it: an error where a channel of its
/// radiance passes the HDR target's limit and `exposure` displays that limit below `white`, so
/// that the sky would show as a flat grey, as [`headroom`] refuses of the scene's own light (the
/// background is no pixel of the scene, so that check does not see it).
pub fn background_headroom(background: [f32; 3], exposure: f64, white: f64) -> Result<(), String> {
    if HALF_MAX * exposure >= white || background.iter().all(|&c| f64::from(c) < HALF_MAX) {
        return Ok(());
    }
    let shown: Vec<String> = background.iter().map(f32::to_string).collect();
    Err(format!(
        "[{}] passes the HDR target's limit of 65 504, which exposure {:e} displays below white: the \
         sky would show as a flat grey; scale the background down and the exposure up",
        shown.join(", "),
        // The manifest's exposure is an f32: shown as written.
        exposure as f32
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sky past the f16 limit under an exposure that displays the limit grey is refused like
    /// the scene's own light; one within the limit, or under an exposure that displays the limit
    /// white, passes.
    #[test]
    fn a_background_past_the_hdr_limit_is_refused_where_the_exposure_would_show_it_grey() {
        let error = background_headroom([1e6, 0.7, 0.95], 1e-4, 64.0).unwrap_err();
        assert!(error.starts_with("[1000000, 0.7, 0.95] passes the HDR target's limit of 65 504"), "{error}");
        assert!(error.contains("exposure 1e-4 displays below white"), "{error}");
        assert!(background_headroom([6e4, 6e4, 6e4], 1e-4, 64.0).is_ok(), "within the limit");
        assert!(background_headroom([1e6; 3], 1.0, 64.0).is_ok(), "the limit displays white");
    }

    #[test]
    fn the_curve_meets_its_two_anchors() {
        let tonemap = Tonemap::default();
        let curve = tonemap.curve().unwrap();
        assert!((curve.apply(0.18) - 0.18).abs() < 1e-12);
        assert!((curve.apply(64.0) - 1.0).abs() < 1e-12);
        // Off-default anchors too: 3 stops darker, a higher contrast.
        let dark = Tonemap { mid_out: 0.18 / 3f64.exp(), contrast: 1.6, ..tonemap };
        let curve = dark.curve().unwrap();
        assert!((curve.apply(0.18) - 0.18 / 3f64.exp()).abs() < 1e-12);
        assert!((curve.apply(64.0) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn bad_parameters_name_their_field() {
        let check = |tonemap: Tonemap, field: &str| {
            let error = tonemap.curve().unwrap_err();
            assert_eq!(error.field, field, "{error}");
        };
        let d = Tonemap::default();
        check(Tonemap { hdr_max: 0.18, ..d }, "hdr_max");
        check(Tonemap { hdr_max: 0.1, ..d }, "hdr_max");
        check(Tonemap { contrast: 0.0, ..d }, "contrast");
        check(Tonemap { shoulder: -1.0, ..d }, "shoulder");
        check(Tonemap { mid_out: 1.0, ..d }, "mid_out");
        check(Tonemap { mid_in: f64::NAN, ..d }, "mid_in");
        check(Tonemap { crosstalk: f64::INFINITY, ..d }, "crosstalk");
        // A shoulder above 1 bends the curve back down before hdr_max.
        check(Tonemap { shoulder: 1.5, ..d }, "shoulder");
        assert_eq!(Transfer::Pq { peak_nits: 0.0 }.validate().unwrap_err().field, "peak_nits");
        assert_eq!(Transfer::Pq { peak_nits: f64::NAN }.validate().unwrap_err().field, "peak_nits");
    }

    #[test]
    fn transfer_functions_invert() {
        for transfer in
            [Transfer::Srgb, Transfer::Rec709, Transfer::Gamma22, Transfer::Pq { peak_nits: 1000.0 }]
        {
            for i in 0..=1000 {
                let l = f64::from(i) / 1000.0;
                let back = transfer.decode(transfer.encode(l));
                assert!((back - l).abs() < 1e-9, "{transfer:?} at {l}: {back}");
            }
        }
    }

    #[test]
    fn pq_matches_published_code_values() {
        // SMPTE ST 2084: 0 nits → 0, 100 nits → 0.508 (code 520 of 10-bit full range),
        // 10 000 nits → 1.
        let pq = Transfer::Pq { peak_nits: PQ_MAX_NITS };
        assert_eq!(pq.encode(0.0), 0.0f64.max(pq_encode(0.0)));
        assert!(pq.encode(0.0) < 1e-6);
        assert!((pq.encode(0.01) - 0.508_078).abs() < 1e-5, "{}", pq.encode(0.01));
        assert!((pq.encode(1.0) - 1.0).abs() < 1e-12);
        assert_eq!((pq.encode(0.01) * 1023.0).round(), 520.0);
    }

    #[test]
    fn black_stays_black_under_any_grain() {
        let transfers =
            [Transfer::Srgb, Transfer::Rec709, Transfer::Gamma22, Transfer::Pq { peak_nits: 1000.0 }];
        for transfer in transfers {
            for bits in [3, 8, 10] {
                for dither in [Dither::Symmetric, Dither::Asymmetric] {
                    let color = ColorSettings { tonemap: None, transfer, bits, dither };
                    for i in 0..=200 {
                        let grain = f64::from(i) / 100.0 - 1.0;
                        assert_eq!(color.quantize(0.0, grain), 0, "{transfer:?} {bits} bits, grain {grain}");
                    }
                }
            }
        }
    }

    #[test]
    fn grain_has_zero_mean_in_both_shapes() {
        for dither in [Dither::Symmetric, Dither::Asymmetric] {
            let settings = ColorSettings { dither, ..ColorSettings::default() };
            let n = 512u32;
            let sum: f64 = (0..n * n).map(|i| settings.grain(i % n, i / n, i % 3)).sum();
            let mean = sum / f64::from(n * n);
            assert!(mean.abs() < 3e-3, "{dither:?}: {mean}");
            let range = (0..n).map(|i| settings.grain(i, 7, 0));
            assert!(range.clone().all(|g| (-1.0..=1.0).contains(&g)));
        }
    }

    #[test]
    fn metering_maps_the_log_average_to_the_key_and_follows_the_light_level() {
        let meter =
            |image: &[[f32; 4]], range| metered_exposure(image, None, EXPOSURE_KEY, 64.0, range).unwrap();
        // Half black, half grey 2 and 8: the black half is left out, the rest averages to 4.
        let mut image = vec![[0.0, 0.0, 0.0, 0.0]; 8];
        image.extend([[2.0, 2.0, 2.0, 0.0], [8.0, 8.0, 8.0, 0.0]].repeat(4));
        let exposure = meter(&image, METERED_EXPOSURE_RANGE);
        assert!((f64::from(exposure) - 0.18 / 4.0).abs() < 1e-6, "{exposure}");
        // A thousand times the light: a thousandth of the exposure.
        let bright: Vec<[f32; 4]> = image.iter().map(|p| p.map(|c| c * 1000.0)).collect();
        let ratio = f64::from(exposure) / f64::from(meter(&bright, METERED_EXPOSURE_RANGE));
        assert!((ratio - 1000.0).abs() < 1e-3, "{ratio}");
        // No light meters 1; non-finite pixels stay finite; the range holds.
        let dark = [[0.0, f32::NAN, -1.0, 0.0]; 4];
        assert_eq!(meter(&dark, METERED_EXPOSURE_RANGE), 1.0);
        assert_eq!(meter(&[[1e4; 4]], [1e-3, 1e3]), 1e-3);
        assert_eq!(meter(&[[1e-30; 4]], METERED_EXPOSURE_RANGE), METERED_EXPOSURE_RANGE[1]);
    }

    #[test]
    fn metering_reads_the_scene_not_the_background_and_keeps_its_highlights() {
        // A dim sky behind a sunlit floor: metered with the sky, the log average sinks and the
        // floor (half the frame) would display six times above white; metered on the scene,
        // the floor sits at the key.
        let mut image = vec![[1e-4, 1e-4, 1e-4, 0.0]; 50];
        image.extend(vec![[500.0, 500.0, 500.0, 0.0]; 50]);
        let scene: Vec<bool> = (0..100).map(|i| i >= 50).collect();
        let on_scene =
            metered_exposure(&image, Some(&scene), EXPOSURE_KEY, 64.0, METERED_EXPOSURE_RANGE).unwrap();
        assert!((f64::from(on_scene) - 0.18 / 500.0).abs() < 1e-9, "{on_scene}");
        // Without knowing the scene, the highlight guard still keeps the floor at white.
        let blind = metered_exposure(&image, None, EXPOSURE_KEY, 64.0, METERED_EXPOSURE_RANGE).unwrap();
        assert!((f64::from(blind) * 500.0 - 64.0).abs() < 1e-3, "{blind}");
        // A few bright pixels (a lamp, 1 % of the scene) do not darken the rest.
        let mut lamp = vec![[1.0f32, 1.0, 1.0, 0.0]; 99];
        lamp.push([1e4, 1e4, 1e4, 0.0]);
        let exposure = metered_exposure(&lamp, None, EXPOSURE_KEY, 64.0, METERED_EXPOSURE_RANGE).unwrap();
        let expected = 0.18 / (1e4f64.ln() / 100.0).exp();
        assert!((f64::from(exposure) - expected).abs() < 1e-6, "{exposure}");
        // A scene whose light reached the f16 limit is refused: no exposure brings it back.
        let clipped = vec![[f32::INFINITY; 4]; 10];
        let error = metered_exposure(&clipped, None, EXPOSURE_KEY, 64.0, METERED_EXPOSURE_RANGE).unwrap_err();
        assert!(error.contains("65 504"), "{error}");
    }
}
