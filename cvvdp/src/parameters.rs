//! The calibrated model: the reference's `cvvdp_parameters.json`, read once.
//!
//! Only the base model's choices are ported (`masking_model` "mult-mutual", `contrast`
//! "weber_g1", `csf` "weber_fixed_size", `dclamp_type` "soft", cross-channel masking on,
//! Bloch integration off); [`Parameters::embedded`] checks that the vendored file makes them.

use serde::Deserialize;

/// The reference's parameter file, as vendored.
const PARAMETERS_JSON: &str = include_str!("../data/cvvdp_parameters.json");

/// The constants of ColorVideoVDP's base model, as `f32` (the reference holds them in
/// single-precision tensors and computes in single precision).
#[derive(Debug, Clone, Deserialize)]
pub struct Parameters {
    /// The calibration's version, "0.5.7".
    pub version: String,
    /// The exponent of the contrast difference in the masking model.
    pub mask_p: f32,
    /// The masking signal's scale, log10.
    pub mask_c: f32,
    /// The masking signal's exponent, per channel (achromatic sustained, red–green,
    /// yellow–violet, achromatic transient).
    pub mask_q: [f32; 4],
    /// The phase-uncertainty blur's σ in pixels of each band.
    pub pu_dilate: f32,
    /// The p-norm over the pixels of a band.
    pub beta: f32,
    /// The p-norm over frames.
    pub beta_t: f32,
    /// The p-norm over the temporal and chromatic channels.
    pub beta_tch: f32,
    /// The p-norm over the spatial bands.
    pub beta_sch: f32,
    /// The CSF's correction in dB (negative: less sensitive).
    pub sensitivity_correction: f32,
    /// JOD = 10 − `jod_a` · Q^`jod_exp`.
    pub jod_a: f32,
    pub jod_exp: f32,
    /// The chromatic channels' weight in the pooling.
    pub ch_chrom_w: f32,
    /// The transient channel's weight in the pooling.
    pub ch_trans_w: f32,
    /// The temporal filters' σ and β per channel.
    pub sigma_tf: [f32; 4],
    pub beta_tf: [f32; 4],
    /// Cross-channel masking weights, log2, a 4 × 4 matrix by rows (from channel, to channel).
    pub xcm_weights: [f32; 16],
    /// The baseband's weight per channel.
    pub baseband_weight: [f32; 4],
    /// The soft clamp of differences, log10 of its maximum.
    pub d_max: f32,
    /// The integration correction applied to images (a single frame).
    pub image_int: f32,
    masking_model: String,
    contrast: String,
    csf: String,
    dclamp_type: String,
    xchannel_masking: String,
    #[serde(rename = "Bloch_int")]
    bloch_int: String,
    local_adapt: String,
}

impl Parameters {
    /// The vendored base model.
    ///
    /// # Panics
    /// If the vendored file does not parse or names a model this port does not implement: a
    /// build defect, caught by the crate's tests.
    pub fn embedded() -> Self {
        let parameters: Parameters =
            serde_json::from_str(PARAMETERS_JSON).expect("the vendored cvvdp_parameters.json parses");
        let choices = [
            (&parameters.masking_model, "mult-mutual"),
            (&parameters.contrast, "weber_g1"),
            (&parameters.csf, "weber_fixed_size"),
            (&parameters.dclamp_type, "soft"),
            (&parameters.xchannel_masking, "on"),
            (&parameters.bloch_int, "off"),
            (&parameters.local_adapt, "gpyr"),
        ];
        for (value, ported) in choices {
            assert_eq!(value, ported, "the vendored model makes a choice this port does not implement");
        }
        parameters
    }

    /// The channels' weights in the pooling: achromatic sustained, red–green, yellow–violet,
    /// achromatic transient.
    pub fn channel_weights(&self) -> [f32; 4] {
        [1.0, self.ch_chrom_w, self.ch_chrom_w, self.ch_trans_w]
    }

    /// The cross-channel masking weight from channel `from` to channel `to`, 2^w.
    pub fn cross_channel_weight(&self, from: usize, to: usize) -> f32 {
        2f32.powf(self.xcm_weights[4 * from + to])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_vendored_model_parses_and_is_the_base_model() {
        let parameters = Parameters::embedded();
        assert_eq!(parameters.version, "0.5.7");
        assert!((parameters.mask_p - 2.264_355_2).abs() < 1e-6);
        assert_eq!(parameters.channel_weights()[0], 1.0);
    }
}
