//! Render modes and their ids: `deferred-1x1`, `smaa`, `msaa-4x`, `taa`, `reference-4x4-stalled`, `adaptive-3x3-geometry`,
//! `adaptive-3x3-area`, `adaptive-4x4-cells`, `adaptive-4x4-coverage`, `adaptive-4x4-stable`.

use std::fmt;
use std::str::FromStr;

use crate::technique::Technique;
use crate::technique::adaptive::{self, Counts, Metrics, Reconstruction};

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

    /// The modes that adaptive is measured against: each of [`Technique::COMPARED`] at each of
    /// its sizes (the reference from 2×2), plain and stalled.
    pub fn baseline_modes() -> Vec<Mode> {
        let mut modes = Vec::new();
        for stalled in [false, true] {
            for technique in Technique::COMPARED {
                // reference-1x1 renders deferred-1x1's image: no group lists it.
                let listed = technique.sizes().filter(|&m| technique != Technique::Reference || m > 1);
                modes.extend(listed.map(|m| Mode::new(technique, m, stalled)));
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

    /// Whether the mode keeps state from one frame for the next ([`Technique::carries_history`]).
    pub fn carries_history(&self) -> bool {
        self.technique.carries_history()
    }

    /// Whether the mode jitters its samples from frame to frame ([`Technique::is_jittered`]). A
    /// `-stable` mode's frames at one camera are its first frame's, bit for bit.
    pub fn is_jittered(&self) -> bool {
        self.technique.is_jittered()
    }

    /// The mode whose image this one's is compared with, at the same M and stall
    /// ([`Technique::compared_with`]): for FXAA, SMAA and TAA deferred-1x1, which is the 1×1
    /// reference bit for bit; for adaptive modes and 4× MSAA the reference at their M.
    pub fn compared_with(&self) -> Option<Mode> {
        let technique = self.technique.compared_with()?;
        Some(Mode::new(technique, self.m, self.stalled))
    }

    /// A short name for a plot's point, without the stall (the plot's series says it):
    /// `adaptive-3x3-geometry-stalled` → `ada 3×3 geometry`.
    pub fn short_label(&self) -> String {
        let m = self.m;
        match self.technique {
            Technique::Deferred => "1×1".into(),
            Technique::Msaa => "msaa 4×".into(),
            Technique::Reference => format!("ref {m}×{m}"),
            Technique::Adaptive(metrics, reconstruction, counts) => {
                let words = adaptive::id_suffixes(metrics, reconstruction, counts);
                std::iter::once(format!("ada {m}×{m}"))
                    .chain(words.into_iter().map(String::from))
                    .collect::<Vec<_>>()
                    .join(" ")
            }
            technique => technique.name().into(),
        }
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

    /// Whether a pixel of `n` samples shades its first sample a second time, in a scene with
    /// or without textures: adaptive modes whose S stands for the whole pixel or filters its
    /// textures (see [`Reconstruction::reshades_first`]); never MSAA, whose pixels of four
    /// samples skip the shading at the centre.
    pub fn reshades_first(&self, n: u32, textured: bool) -> bool {
        match self.technique {
            Technique::Adaptive(_, reconstruction, _) => reconstruction.reshades_first(self.m, n, textured),
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
        if let Technique::Adaptive(metrics, reconstruction, counts) = self.technique {
            let variant = adaptive::Variant { metrics, reconstruction, counts };
            return f.write_str(&adaptive::mode_id(variant, self.m, self.stalled));
        }
        match self.technique.fixed_id() {
            Some(id) => f.write_str(id)?,
            None => write!(f, "{}-{m}x{m}", self.technique.name(), m = self.m)?,
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
            return Err(fail(&uppercase_reason(id)));
        }
        let (plain, stalled) = match id.strip_suffix("-stalled") {
            Some(plain) => (plain, true),
            None => (id, false),
        };
        if plain.split('-').any(|word| word == "stalled") {
            return Err(fail("`-stalled` comes once, at the end"));
        }
        let mut words = plain.split('-');
        let name = words.next().unwrap_or_default();
        // A technique of one size is its own id, plain or stalled, and nothing else.
        let fixed_technique =
            Technique::COMPARED.into_iter().find(|t| t.fixed_id().is_some() && t.name() == name);
        if let Some(technique) = fixed_technique {
            let fixed = technique.fixed_id().expect("found by its fixed id");
            return if plain == fixed {
                Ok(Mode::new(technique, *technique.sizes().start(), stalled))
            } else {
                Err(fail(&format!("{}: `{fixed}` or `{fixed}-stalled`", technique.fixed_id_rule())))
            };
        }
        let size = words.next().ok_or_else(|| fail("missing the size, e.g. `-2x2`"))?;
        let m = match size.split_once('x') {
            Some((a, b)) if a == b => a.parse::<u32>().map_err(|_| fail("the size must be MxM"))?,
            _ => return Err(fail("the size must be MxM with equal sides")),
        };
        let rest: Vec<&str> = words.collect();
        let technique = match (name, rest.as_slice()) {
            ("deferred", []) => Technique::Deferred,
            ("reference", []) => Technique::Reference,
            ("adaptive", suffixes) => {
                let (metrics, reconstruction, counts) = adaptive::parse_suffixes(suffixes).map_err(fail)?;
                Technique::Adaptive(metrics, reconstruction, counts)
            }
            ("deferred" | "reference", _) => return Err(fail("unexpected suffix")),
            _ => return Err(fail(&technique_reason())),
        };
        let allowed = technique.sizes();
        if !allowed.contains(&m) {
            return Err(fail(&format!("M must be in {}..={}", allowed.start(), allowed.end())));
        }
        Ok(Mode::new(technique, m, stalled))
    }
}

/// Why an id with capitals does not parse, with the lowercase id where that one does.
fn uppercase_reason(id: &str) -> String {
    let lower = id.to_ascii_lowercase();
    let hint =
        if lower.parse::<Mode>().is_ok() { format!(": did you mean `{lower}`?") } else { String::new() };
    format!("mode ids are lowercase{hint}")
}

/// What an unknown first word of an id is told: the techniques there are.
fn technique_reason() -> String {
    let names: Vec<&str> =
        Technique::COMPARED.iter().map(|t| t.name()).chain(std::iter::once("adaptive")).collect();
    let (last, others) = names.split_last().expect("techniques");
    format!("the technique must be {} or {last}", others.join(", "))
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
    fn every_listed_mode_round_trips_through_its_id_and_no_group_lists_one_twice() {
        let all: Vec<Mode> = Mode::groups().into_iter().flat_map(|(_, modes)| modes).collect();
        for (i, mode) in all.iter().enumerate() {
            assert_eq!(mode.to_string().parse::<Mode>(), Ok(*mode), "{mode}");
            assert!(!all[..i].contains(mode), "{mode} is listed twice");
        }
        // Every compared technique, each adaptive variant and both stalls have their modes.
        for technique in Technique::COMPARED {
            for stalled in [false, true] {
                let listed = |m: &Mode| m.technique == technique && m.stalled == stalled;
                assert!(Mode::baseline_modes().iter().any(listed), "{technique:?} stalled {stalled}");
            }
            if let Some(id) = technique.fixed_id() {
                assert_eq!(id.parse::<Mode>().map(|m| m.technique), Ok(technique));
                assert_eq!(format!("{id}-stalled").parse::<Mode>().map(|m| m.stalled), Ok(true));
            }
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
        assert_eq!(
            "adaptive-3x3-geometry-stalled".parse::<Mode>().unwrap().short_label(),
            "ada 3×3 geometry"
        );
        assert_eq!(
            "msaa-4x".parse::<Mode>().unwrap().compared_with().map(|m| m.to_string()),
            Some("reference-2x2".into())
        );
        assert_eq!(
            "taa-stalled".parse::<Mode>().unwrap().compared_with().map(|m| m.to_string()),
            Some("deferred-1x1-stalled".into())
        );
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
        check("supersample-2x2", "technique must be deferred, fxaa, smaa, msaa, taa, reference or adaptive");
        check("taa-stalled-stalled", "`-stalled` comes once, at the end");
        check("adaptive-2x2-stalled-area", "`-stalled` comes once, at the end");
    }
}
