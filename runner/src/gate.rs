//! The regression gate's tolerances: documented defaults, overridable per scene in the
//! manifest's `gate` section, and recorded with every scene of a run so that `compare` judges a
//! run by the tolerances it was run with.

use serde::{Deserialize, Serialize};

/// How far a metric may move before `compare` calls it improved or regressed.
///
/// Quality is nearly deterministic on one platform (lavapipe gives the same bits on every
/// machine with the same Mesa), so its tolerances are tight; against a baseline of another
/// platform key the `*_cross_platform` tolerances apply, which still catch a 0.5 dB drop.
/// Times are noisy: a time metric moves only when the whole confidence interval of its change
/// is past the threshold.
/// The fewest timed frames of a mode, on each side, from which a time check against committed
/// baselines is decided. With fewer, the interval is the few ratios themselves: one frame a
/// side gave false regressions in 3 of 4 compares of a build with itself.
pub const MIN_FRAMES: usize = 5;

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Tolerances {
    /// PSNR (against the truth and against the same-M reference), in dB.
    pub psnr_db: f64,
    pub psnr_db_cross_platform: f64,
    /// MSE, as a fraction of the baseline's.
    pub mse_relative: f64,
    pub mse_relative_cross_platform: f64,
    /// Samples % of adaptive modes, in percentage points.
    pub shaded_percent: f64,
    pub shaded_percent_cross_platform: f64,
    /// Total-variation distance between the normalized sample-count histograms (0 to 1).
    pub histogram: f64,
    pub histogram_cross_platform: f64,
    /// Mean FLIP against the truth, as a fraction of the baseline's.
    pub flip_relative: f64,
    pub flip_relative_cross_platform: f64,
    /// 1 − SSIM against the truth (the dissimilarity), as a fraction of the baseline's.
    pub ssim_relative: f64,
    pub ssim_relative_cross_platform: f64,
    /// In-run time ratios (a mode against deferred-1x1, adaptive-MxM against reference-MxM),
    /// as a fraction: 0.1 flags a ratio 10% above the baseline's.
    pub time_ratio: f64,
    /// Absolute frame times, as a fraction: wide, since these machines drift 15–30% between
    /// processes. Never gated against another platform.
    pub absolute_time: f64,
}

impl Default for Tolerances {
    fn default() -> Self {
        Tolerances {
            psnr_db: 0.02,
            psnr_db_cross_platform: 0.25,
            mse_relative: 0.005,
            mse_relative_cross_platform: 0.06,
            shaded_percent: 0.05,
            shaded_percent_cross_platform: 0.5,
            histogram: 0.002,
            histogram_cross_platform: 0.01,
            flip_relative: 0.005,
            flip_relative_cross_platform: 0.06,
            ssim_relative: 0.005,
            ssim_relative_cross_platform: 0.06,
            time_ratio: 0.10,
            absolute_time: 0.40,
        }
    }
}

impl Tolerances {
    /// Checks every tolerance; `Err((field, reason))` names the first bad one.
    pub fn validate(&self) -> Result<(), (String, String)> {
        let fields = [
            ("psnr_db", self.psnr_db),
            ("psnr_db_cross_platform", self.psnr_db_cross_platform),
            ("mse_relative", self.mse_relative),
            ("mse_relative_cross_platform", self.mse_relative_cross_platform),
            ("shaded_percent", self.shaded_percent),
            ("shaded_percent_cross_platform", self.shaded_percent_cross_platform),
            ("histogram", self.histogram),
            ("histogram_cross_platform", self.histogram_cross_platform),
            ("flip_relative", self.flip_relative),
            ("flip_relative_cross_platform", self.flip_relative_cross_platform),
            ("ssim_relative", self.ssim_relative),
            ("ssim_relative_cross_platform", self.ssim_relative_cross_platform),
        ];
        for (name, value) in fields {
            if !(value.is_finite() && value >= 0.0) {
                return Err((format!("gate.{name}"), format!("{value} must be finite and ≥ 0")));
            }
        }
        for (name, value) in [("time_ratio", self.time_ratio), ("absolute_time", self.absolute_time)] {
            if !(value.is_finite() && value > 0.0) {
                return Err((format!("gate.{name}"), format!("{value} must be finite and > 0")));
            }
        }
        Ok(())
    }

    /// The quality tolerances that apply against a baseline of the same or another platform.
    pub fn quality(&self, same_platform: bool) -> QualityTolerances {
        if same_platform {
            QualityTolerances {
                psnr_db: self.psnr_db,
                mse_relative: self.mse_relative,
                shaded_percent: self.shaded_percent,
                histogram: self.histogram,
                flip_relative: self.flip_relative,
                ssim_relative: self.ssim_relative,
            }
        } else {
            QualityTolerances {
                psnr_db: self.psnr_db_cross_platform,
                mse_relative: self.mse_relative_cross_platform,
                shaded_percent: self.shaded_percent_cross_platform,
                histogram: self.histogram_cross_platform,
                flip_relative: self.flip_relative_cross_platform,
                ssim_relative: self.ssim_relative_cross_platform,
            }
        }
    }
}

/// The quality tolerances in force for one comparison.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QualityTolerances {
    pub psnr_db: f64,
    pub mse_relative: f64,
    pub shaded_percent: f64,
    pub histogram: f64,
    pub flip_relative: f64,
    pub ssim_relative: f64,
}
