//! castleCSF, the contrast sensitivity function ColorVideoVDP uses, read from the reference's
//! lookup table as `csf.py` reads it: log sensitivity on a grid of background luminance (32
//! log-spaced levels from 0.005 to 10 000 cd/m²) by spatial frequency (32 levels from 0.1 to
//! 64 cycles a degree), per channel and temporal frequency (0 and 5 Hz).

use serde::Deserialize;

const LUT_JSON: &str = include_str!("../data/csf_lut_weber_fixed_size.json");

/// The four channels of the metric, each with its own table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Channel {
    /// Achromatic, sustained (0 Hz).
    AchromaticSustained,
    /// Red–green, sustained.
    RedGreen,
    /// Yellow–violet, sustained.
    YellowViolet,
    /// Achromatic, transient (5 Hz).
    AchromaticTransient,
}

impl Channel {
    /// The channels in the metric's order; an image has the first three.
    pub const ALL: [Channel; 4] = [
        Channel::AchromaticSustained,
        Channel::RedGreen,
        Channel::YellowViolet,
        Channel::AchromaticTransient,
    ];
}

#[derive(Deserialize)]
struct Lut {
    #[serde(rename = "L_bkg")]
    background: Vec<f32>,
    rho: Vec<f32>,
    o0_c1: Vec<Vec<f32>>,
    o0_c2: Vec<Vec<f32>>,
    o0_c3: Vec<Vec<f32>>,
    o5_c1: Vec<Vec<f32>>,
}

/// The sensitivity tables.
#[derive(Debug, Clone)]
pub struct CastleCsf {
    /// log10 of the background luminance levels.
    log_background: Vec<f32>,
    /// log10 of the spatial frequencies.
    log_rho: Vec<f32>,
    /// Per channel, log10 sensitivity by [background][frequency].
    log_sensitivity: [Vec<Vec<f32>>; 4],
}

/// A table's column at one spatial frequency: log10 sensitivity per background level.
#[derive(Debug, Clone)]
pub struct AtFrequency {
    log_background_first: f32,
    log_background_last: f32,
    log_sensitivity: Vec<f32>,
}

impl CastleCsf {
    /// The vendored table.
    pub fn embedded() -> Self {
        let lut: Lut = serde_json::from_str(LUT_JSON).expect("the vendored castleCSF table parses");
        let log10 = |values: &[f32]| values.iter().map(|v| v.log10()).collect::<Vec<_>>();
        CastleCsf {
            log_background: log10(&lut.background),
            log_rho: log10(&lut.rho),
            log_sensitivity: [lut.o0_c1, lut.o0_c2, lut.o0_c3, lut.o5_c1],
        }
    }

    /// The table of `channel` at spatial frequency `rho` (cycles a degree): linear in log
    /// frequency between the grid's levels, and extrapolated linearly beyond them, as the
    /// reference's `batch_interp1d` does.
    pub fn at_frequency(&self, channel: Channel, rho: f64) -> AtFrequency {
        let table = &self.log_sensitivity[channel as usize];
        let x = (rho as f32).log10();
        let grid = &self.log_rho;
        // searchsorted (left) − 1, clamped to the grid's intervals.
        let above = grid.partition_point(|&g| g < x);
        let i = above.saturating_sub(1).min(grid.len() - 2);
        let log_sensitivity = table
            .iter()
            .map(|row| {
                let slope = (row[i + 1] - row[i]) / (grid[i + 1] - grid[i]);
                row[i] + slope * (x - grid[i])
            })
            .collect();
        AtFrequency {
            log_background_first: self.log_background[0],
            log_background_last: *self.log_background.last().expect("the table has levels"),
            log_sensitivity,
        }
    }
}

impl AtFrequency {
    /// The sensitivity at background luminance 10^`log_background`: linear in log luminance on
    /// the table's evenly spaced levels, clamped at its ends (the reference's `interp1q`).
    pub fn sensitivity(&self, log_background: f32) -> f32 {
        let values = &self.log_sensitivity;
        let last = (values.len() - 1) as f32;
        let position = ((log_background - self.log_background_first)
            / (self.log_background_last - self.log_background_first)
            * last)
            .clamp(0.0, last);
        let low = position as usize;
        let high = (low + 1).min(values.len() - 1);
        let fraction = position.fract();
        10f32.powf(values[low] * (1.0 - fraction) + values[high] * fraction)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sensitivity_is_the_table_at_its_grid_points() {
        let csf = CastleCsf::embedded();
        let lut: Lut = serde_json::from_str(LUT_JSON).unwrap();
        let column = csf.at_frequency(Channel::AchromaticSustained, f64::from(lut.rho[5]));
        let s = column.sensitivity(lut.background[7].log10());
        let expected = 10f32.powf(lut.o0_c1[7][5]);
        assert!((s / expected - 1.0).abs() < 1e-4, "{s} against {expected}");
    }
}
