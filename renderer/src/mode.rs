//! Render modes and their ids: `deferred-1x1`, `smaa`, `msaa-4x`, `taa`, `reference-4x4-stalled`, `adaptive-3x3-geometry`,
//! `adaptive-3x3-area`, `adaptive-4x4-cells`, `adaptive-4x4-coverage`, `adaptive-4x4-stable`.

use std::fmt;
use std::str::FromStr;

use crate::adaptive::{Counts, Reconstruction};

/// Which of the adaptive metrics decide the sample count (the paper's Fig. 8 ablation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Metrics {
    /// max(k_d, k_n, k_s): the paper's method.
    Both,
    /// Depth variance and normal cone only.
    Geometry,
    /// Luminance range of the shade-first image only.
    Shading,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Technique {
    /// One sample per pixel.
    Deferred,
    /// One sample per pixel, then FXAA 3.11 on the display-encoded image.
    Fxaa,
    /// One sample per pixel, then SMAA 1x on the display-encoded image.
    Smaa,
    /// MSAA-based deferred shading: a w × h G-buffer of 4 samples per pixel (M = 2: as many
    /// samples as the 2×2 grid, at the rotated-grid positions), shaded per sample where they
    /// lie on more than one surface and once per pixel elsewhere.
    Msaa,
    /// Temporal anti-aliasing: one jittered sample per pixel and frame, blended into a history
    /// reprojected along per-pixel motion vectors (see `passes/taa.rs`). Its image depends on
    /// the frames before: a still is the last of [`crate::taa::WARMUP_FRAMES`] frames rendered
    /// from a reset at one camera.
    Taa,
    /// All M² samples of an M·w × M·h G-buffer shaded, box-filtered.
    Reference,
    /// Holländer et al. 2013: the same G-buffer, samples shaded where the metrics ask (in this
    /// frame alone, or also in the frame before), and the pixel reconstructed from them.
    Adaptive(Metrics, Reconstruction, Counts),
}

/// A technique at a supersampling factor, with or without the expensive (stalled) shader.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Mode {
    pub technique: Technique,
    /// Samples per pixel side: the G-buffer is M·w × M·h.
    pub m: u32,
    pub stalled: bool,
}

impl Mode {
    pub const fn new(technique: Technique, m: u32, stalled: bool) -> Mode {
        Mode { technique, m, stalled }
    }

    /// The sixteen modes that adaptive is measured against: deferred 1×1, FXAA, SMAA, 4×
    /// MSAA, TAA and reference 2×2–4×4, each plain and stalled.
    pub fn baseline_modes() -> Vec<Mode> {
        let mut modes = Vec::new();
        for stalled in [false, true] {
            modes.push(Mode::new(Technique::Deferred, 1, stalled));
            modes.push(Mode::new(Technique::Fxaa, 1, stalled));
            modes.push(Mode::new(Technique::Smaa, 1, stalled));
            modes.push(Mode::new(Technique::Msaa, 2, stalled));
            modes.push(Mode::new(Technique::Taa, 1, stalled));
            for m in 2..=4 {
                modes.push(Mode::new(Technique::Reference, m, stalled));
            }
        }
        modes
    }

    /// Adaptive 2×2–4×4 as the paper has it, plain and stalled.
    pub fn adaptive_modes() -> Vec<Mode> {
        Self::adaptive(Metrics::Both, Reconstruction::Equal, Counts::PerFrame)
    }

    /// Adaptive 2×2–4×4 with one metric each: the ablation of the paper's Fig. 8.
    pub fn ablation_modes() -> Vec<Mode> {
        let mut modes = Self::adaptive(Metrics::Geometry, Reconstruction::Equal, Counts::PerFrame);
        modes.extend(Self::adaptive(Metrics::Shading, Reconstruction::Equal, Counts::PerFrame));
        modes
    }

    /// Adaptive 2×2–4×4 beyond the paper, beside it: samples weighted by their area, samples
    /// that stand for their cells, and one sample per surface weighted by its coverage.
    pub fn variant_modes() -> Vec<Mode> {
        [Reconstruction::Area, Reconstruction::Cells, Reconstruction::Coverage]
            .into_iter()
            .flat_map(|reconstruction| Self::adaptive(Metrics::Both, reconstruction, Counts::PerFrame))
            .collect()
    }

    /// Adaptive 2×2–4×4 with counts that follow the frames before (the paper's future work),
    /// beside the paper's reconstruction and `-cells`: `adaptive-MxM-stable`,
    /// `adaptive-MxM-cells-stable`.
    pub fn stable_modes() -> Vec<Mode> {
        [Reconstruction::Equal, Reconstruction::Cells]
            .into_iter()
            .flat_map(|reconstruction| Self::adaptive(Metrics::Both, reconstruction, Counts::Stable))
            .collect()
    }

    /// The named groups of modes that `--modes` takes and `aabench modes` lists.
    pub fn groups() -> [(&'static str, Vec<Mode>); 5] {
        [
            ("baseline", Self::baseline_modes()),
            ("adaptive", Self::adaptive_modes()),
            ("ablation", Self::ablation_modes()),
            ("variant", Self::variant_modes()),
            ("stable", Self::stable_modes()),
        ]
    }

    /// Whether the mode keeps state from one frame for the next (TAA's history, a `-stable`
    /// mode's sample counts): it has frame uniforms of its own, with the previous frame's
    /// camera, and resources the graph carries into the next frame.
    pub fn carries_history(&self) -> bool {
        self.is_jittered() || self.counts() == Counts::Stable
    }

    /// Whether the mode jitters its samples from frame to frame (TAA): its frames at one camera
    /// differ, so its still is the last of a run of warm-up frames. A `-stable` mode's frames at
    /// one camera are its first frame's, bit for bit.
    pub fn is_jittered(&self) -> bool {
        self.technique == Technique::Taa
    }

    /// Where an adaptive mode's sample counts come from (`PerFrame` for every other mode).
    pub fn counts(&self) -> Counts {
        match self.technique {
            Technique::Adaptive(_, _, counts) => counts,
            _ => Counts::PerFrame,
        }
    }

    /// How an adaptive mode reconstructs its pixels (`Equal` for every other mode, whose
    /// pixels are the plain average of their samples).
    pub fn reconstruction(&self) -> Reconstruction {
        match self.technique {
            Technique::Adaptive(_, reconstruction, _) => reconstruction,
            _ => Reconstruction::Equal,
        }
    }

    /// Whether a pixel of `n` samples shades its first sample a second time: adaptive modes
    /// whose S stands for the whole pixel (see [`Reconstruction::reshades_first`]); never
    /// MSAA, whose pixels of four samples skip the shading at the centre.
    pub fn reshades_first(&self, n: u32) -> bool {
        match self.technique {
            Technique::Adaptive(_, reconstruction, _) => reconstruction.reshades_first(self.m, n),
            _ => false,
        }
    }

    fn adaptive(metrics: Metrics, reconstruction: Reconstruction, counts: Counts) -> Vec<Mode> {
        let technique = Technique::Adaptive(metrics, reconstruction, counts);
        [false, true]
            .into_iter()
            .flat_map(|stalled| (2..=4).map(move |m| Mode::new(technique, m, stalled)))
            .collect()
    }
}

impl fmt::Display for Mode {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        let name = match self.technique {
            Technique::Deferred => "deferred",
            // Post-process modes have no supersampling factor to name.
            Technique::Fxaa => return f.write_str(if self.stalled { "fxaa-stalled" } else { "fxaa" }),
            Technique::Smaa => return f.write_str(if self.stalled { "smaa-stalled" } else { "smaa" }),
            Technique::Msaa => return f.write_str(if self.stalled { "msaa-4x-stalled" } else { "msaa-4x" }),
            Technique::Taa => return f.write_str(if self.stalled { "taa-stalled" } else { "taa" }),
            Technique::Reference => "reference",
            Technique::Adaptive(..) => "adaptive",
        };
        write!(f, "{name}-{m}x{m}", m = self.m)?;
        if let Technique::Adaptive(metrics, reconstruction, counts) = self.technique {
            match metrics {
                Metrics::Both => {}
                Metrics::Geometry => f.write_str("-geometry")?,
                Metrics::Shading => f.write_str("-shading")?,
            }
            match reconstruction {
                Reconstruction::Equal => {}
                Reconstruction::Area => f.write_str("-area")?,
                Reconstruction::Cells => f.write_str("-cells")?,
                Reconstruction::Coverage => f.write_str("-coverage")?,
            }
            if counts == Counts::Stable {
                f.write_str("-stable")?;
            }
        }
        if self.stalled {
            f.write_str("-stalled")?;
        }
        Ok(())
    }
}

/// A mode id that does not parse, with the reason.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "unknown mode `{id}`: {reason} (modes look like deferred-1x1, fxaa, smaa, msaa-4x, taa, reference-4x4-stalled, adaptive-3x3, adaptive-2x2-geometry, adaptive-4x4-area, adaptive-4x4-cells, adaptive-4x4-coverage, adaptive-4x4-stable)"
)]
pub struct ModeError {
    pub id: String,
    pub reason: String,
}

impl FromStr for Mode {
    type Err = ModeError;

    fn from_str(id: &str) -> Result<Mode, ModeError> {
        let fail = |reason: &str| ModeError { id: id.to_string(), reason: reason.to_string() };
        if id.chars().any(|c| c.is_ascii_uppercase()) {
            let lower = id.to_ascii_lowercase();
            let hint = if lower.parse::<Mode>().is_ok() {
                format!(": did you mean `{lower}`?")
            } else {
                String::new()
            };
            return Err(fail(&format!("mode ids are lowercase{hint}")));
        }
        match id {
            "fxaa" => return Ok(Mode::new(Technique::Fxaa, 1, false)),
            "fxaa-stalled" => return Ok(Mode::new(Technique::Fxaa, 1, true)),
            "smaa" => return Ok(Mode::new(Technique::Smaa, 1, false)),
            "smaa-stalled" => return Ok(Mode::new(Technique::Smaa, 1, true)),
            "msaa-4x" => return Ok(Mode::new(Technique::Msaa, 2, false)),
            "msaa-4x-stalled" => return Ok(Mode::new(Technique::Msaa, 2, true)),
            "taa" => return Ok(Mode::new(Technique::Taa, 1, false)),
            "taa-stalled" => return Ok(Mode::new(Technique::Taa, 1, true)),
            _ => {}
        }
        let mut parts = id.split('-');
        let technique = parts.next().unwrap_or_default();
        if technique == "msaa" {
            return Err(fail("lavapipe renders 4× MSAA only: `msaa-4x` or `msaa-4x-stalled`"));
        }
        let size = parts.next().ok_or_else(|| fail("missing the size, e.g. `-2x2`"))?;
        let m = match size.split_once('x') {
            Some((a, b)) if a == b => a.parse::<u32>().map_err(|_| fail("the size must be MxM"))?,
            _ => return Err(fail("the size must be MxM with equal sides")),
        };
        let mut rest: Vec<&str> = parts.collect();
        let stalled = rest.last() == Some(&"stalled");
        if stalled {
            rest.pop();
        }
        let counts = if technique == "adaptive" && rest.last() == Some(&"stable") {
            rest.pop();
            Counts::Stable
        } else {
            Counts::PerFrame
        };
        let reconstruction = match (technique, rest.last()) {
            ("adaptive", Some(&"area")) => Reconstruction::Area,
            ("adaptive", Some(&"cells")) => Reconstruction::Cells,
            ("adaptive", Some(&"coverage")) => Reconstruction::Coverage,
            _ => Reconstruction::Equal,
        };
        if reconstruction != Reconstruction::Equal {
            rest.pop();
        }
        let technique = match (technique, rest.as_slice()) {
            ("deferred", []) => Technique::Deferred,
            ("reference", []) => Technique::Reference,
            ("adaptive", []) => Technique::Adaptive(Metrics::Both, reconstruction, counts),
            ("adaptive", ["geometry"]) => Technique::Adaptive(Metrics::Geometry, reconstruction, counts),
            ("adaptive", ["shading"]) => Technique::Adaptive(Metrics::Shading, reconstruction, counts),
            ("deferred" | "reference" | "adaptive", _) => return Err(fail("unexpected suffix")),
            ("fxaa", _) => return Err(fail("FXAA has no size: `fxaa` or `fxaa-stalled`")),
            ("smaa", _) => return Err(fail("SMAA has no size: `smaa` or `smaa-stalled`")),
            ("taa", _) => return Err(fail("TAA has no size: `taa` or `taa-stalled`")),
            _ => {
                return Err(fail(
                    "the technique must be deferred, fxaa, smaa, msaa, taa, reference or adaptive",
                ));
            }
        };
        if counts == Counts::Stable && reconstruction == Reconstruction::Coverage {
            return Err(fail(
                "`-coverage` picks its samples per surface, not by count: it has no `-stable` variant",
            ));
        }
        let allowed = match technique {
            Technique::Deferred | Technique::Fxaa | Technique::Smaa | Technique::Taa => 1..=1,
            Technique::Msaa => 2..=2,
            // reference-1x1 exists to check that the supersampling path equals deferred-1x1.
            Technique::Reference => 1..=4,
            Technique::Adaptive(..) => 2..=4,
        };
        if !allowed.contains(&m) {
            return Err(fail(&format!("M must be in {}..={}", allowed.start(), allowed.end())));
        }
        Ok(Mode::new(technique, m, stalled))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uppercase_ids_are_named_as_such_not_as_a_size() {
        let error = "Deferred-1X1".parse::<Mode>().unwrap_err().to_string();
        assert!(error.contains("lowercase: did you mean `deferred-1x1`?"), "{error}");
        let error = "SMAA-2X2".parse::<Mode>().unwrap_err().to_string();
        assert!(error.contains("lowercase") && !error.contains("did you mean"), "{error}");
    }

    #[test]
    fn every_listed_mode_round_trips_through_its_id() {
        let all = [
            Mode::baseline_modes(),
            Mode::adaptive_modes(),
            Mode::ablation_modes(),
            Mode::variant_modes(),
            Mode::stable_modes(),
        ]
        .concat();
        assert_eq!(all.len(), 16 + 6 + 12 + 18 + 12);
        assert!(all.iter().any(|m| m.to_string() == "fxaa-stalled"));
        assert!(all.iter().any(|m| m.to_string() == "smaa-stalled"));
        assert!(all.iter().any(|m| m.to_string() == "msaa-4x-stalled"));
        assert!(all.iter().any(|m| m.to_string() == "taa-stalled"));
        assert!(all.iter().any(|m| m.to_string() == "adaptive-3x3-area-stalled"));
        assert!(all.iter().any(|m| m.to_string() == "adaptive-4x4-cells"));
        assert!(all.iter().any(|m| m.to_string() == "adaptive-2x2-coverage-stalled"));
        assert!(all.iter().any(|m| m.to_string() == "adaptive-4x4-stable"));
        assert!(all.iter().any(|m| m.to_string() == "adaptive-3x3-cells-stable-stalled"));
        for mode in all {
            assert_eq!(mode.to_string().parse::<Mode>(), Ok(mode));
        }
        let combined = "adaptive-2x2-geometry-area".parse::<Mode>().unwrap();
        assert_eq!(
            combined.technique,
            Technique::Adaptive(Metrics::Geometry, Reconstruction::Area, Counts::PerFrame)
        );
        assert_eq!(combined.to_string(), "adaptive-2x2-geometry-area");
        let stable = "adaptive-2x2-shading-area-stable".parse::<Mode>().unwrap();
        assert_eq!(
            stable.technique,
            Technique::Adaptive(Metrics::Shading, Reconstruction::Area, Counts::Stable)
        );
        assert!(stable.carries_history() && !stable.is_jittered());
    }

    #[test]
    fn bad_ids_say_why() {
        let check = |id: &str, reason: &str| {
            let error = id.parse::<Mode>().unwrap_err();
            assert!(error.reason.contains(reason), "{id}: {error}");
        };
        check("deferred-2x2", "M must be in 1..=1");
        check("adaptive-1x1", "M must be in 2..=4");
        check("reference-5x5", "M must be in 1..=4");
        check("reference-2x3", "equal sides");
        check("fxaa3", "missing the size");
        check("fxaa-2x2", "FXAA has no size");
        check("smaa-1x1", "SMAA has no size");
        check("taa-2x2", "TAA has no size");
        check("msaa-8x", "4× MSAA only");
        check("msaa-2x2", "4× MSAA only");
        check("reference-2x2-geometry", "unexpected suffix");
        check("reference-2x2-area", "unexpected suffix");
        check("reference-2x2-cells", "unexpected suffix");
        check("adaptive-2x2-cells-area", "unexpected suffix");
        check("adaptive-2x2-area-geometry", "unexpected suffix");
        check("adaptive-2x2-stable-cells", "unexpected suffix");
        check("reference-2x2-stable", "unexpected suffix");
        check("adaptive-4x4-coverage-stable", "no `-stable` variant");
        check("supersample-2x2", "technique must be");
    }
}
