//! A mode's places on its scene's error-against-run-time fronts, as run.json records them: one
//! per metric of the vocabulary with a front margin, by the metric's key (`psnr_vs_truth`, the
//! paper's; `jod_vs_truth` and `sequence_jod_vs_truth`, the rankings'). `front.rs` decides them.

use std::collections::BTreeMap;

use serde::{Deserialize, Deserializer, Serialize};

use crate::measure::pixels::Decibels;

/// What a front decided of a mode, against the modes of its scene with the same stall.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FrontVerdict {
    /// Every mode as good as it (within the metric's margin, or better) is slower with
    /// confidence.
    Front,
    /// A mode as good as it is faster with confidence.
    Behind,
    /// Neither: a mode as good as it whose time the rounds do not tell from its own.
    Undecided,
}

/// A mode's place on one front.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrontPlace {
    pub verdict: FrontVerdict,
    /// Behind: the modes that put it behind. Undecided: the modes whose time the rounds do not
    /// tell from its own. The largest gain first, then the fastest. Empty on the front.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub against: Vec<Rival>,
}

/// Another mode of the scene as good as this one, within the margin or better.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Rival {
    pub mode: String,
    /// Its frame time over this mode's: the median of the ratios of the rounds both timed.
    pub time_ratio: f64,
    /// Its value of the metric less this mode's, in the metric's unit (dB, JOD): at least minus
    /// the margin; infinite where it is exact and this mode is not.
    pub gain: Decibels,
}

impl FrontPlace {
    /// One phrase: `on the front`, `behind reference-3x3 (+6.28 dB, 0.69× time) and 3 more`,
    /// `undecided against fxaa (-0.02 JOD, 0.98× time)`; `unit` is the metric's.
    pub fn describe(&self, unit: &str) -> String {
        let Some(first) = self.against.first() else {
            return "on the front".into();
        };
        let others = match self.against.len() - 1 {
            0 => String::new(),
            1 => " and 1 more".into(),
            n => format!(" and {n} more"),
        };
        let word = if self.verdict == FrontVerdict::Behind { "behind" } else { "undecided against" };
        let gain = first.gain.value();
        format!("{word} {} ({gain:+.2} {unit}, {:.2}× time){others}", first.mode, first.time_ratio)
    }

    /// The same in a few characters, for a table: `front`, `behind X`, `~X` (undecided).
    pub fn brief(&self) -> String {
        match (self.verdict, self.against.first()) {
            (FrontVerdict::Behind, Some(rival)) => format!("behind {}", rival.mode),
            (FrontVerdict::Undecided, Some(rival)) => format!("~{}", rival.mode),
            _ => "front".into(),
        }
    }
}

/// A mode's places by metric key, read from a record of this aabench or of one from before,
/// which held one place, on the PSNR front: `{"on_front": false, "dominated_by": [...]}`.
pub(super) fn keyed_or_legacy<'de, D: Deserializer<'de>>(
    deserializer: D,
) -> Result<BTreeMap<String, FrontPlace>, D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum Stored {
        Keyed(BTreeMap<String, FrontPlace>),
        Legacy(LegacyPlace),
    }
    #[derive(Deserialize)]
    struct LegacyPlace {
        on_front: bool,
        #[serde(default)]
        dominated_by: Vec<LegacyDominator>,
    }
    #[derive(Deserialize)]
    struct LegacyDominator {
        mode: String,
        time_ratio: f64,
        psnr_gain_db: Decibels,
    }
    Ok(match Option::<Stored>::deserialize(deserializer)? {
        Some(Stored::Keyed(places)) => places,
        Some(Stored::Legacy(place)) => {
            let verdict = if place.on_front { FrontVerdict::Front } else { FrontVerdict::Behind };
            let against = (place.dominated_by.into_iter())
                .map(|d| Rival { mode: d.mode, time_ratio: d.time_ratio, gain: d.psnr_gain_db })
                .collect();
            BTreeMap::from([("psnr_vs_truth".to_string(), FrontPlace { verdict, against })])
        }
        None => BTreeMap::new(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Deserialize)]
    struct Holder {
        #[serde(default, alias = "front", deserialize_with = "keyed_or_legacy")]
        fronts: BTreeMap<String, FrontPlace>,
    }

    #[test]
    fn a_record_from_before_reads_as_its_psnr_front() {
        let old = r#"{"front": {"on_front": false, "dominated_by": [
            {"mode": "deferred-1x1", "time_ratio": 0.4, "psnr_gain_db": "inf"}]}}"#;
        let read: Holder = serde_json::from_str(old).unwrap();
        let place = &read.fronts["psnr_vs_truth"];
        assert_eq!(place.verdict, FrontVerdict::Behind);
        assert_eq!(place.describe("dB"), "behind deferred-1x1 (+inf dB, 0.40× time)");
        let on: Holder = serde_json::from_str(r#"{"front": {"on_front": true}}"#).unwrap();
        assert_eq!(on.fronts["psnr_vs_truth"].verdict, FrontVerdict::Front);
        let none: Holder = serde_json::from_str("{}").unwrap();
        assert!(none.fronts.is_empty());
    }

    #[test]
    fn places_round_trip_by_key_and_read_in_a_phrase() {
        let rival =
            |mode: &str, gain| Rival { mode: mode.into(), time_ratio: 0.98, gain: Decibels::from_f64(gain) };
        let places = BTreeMap::from([
            (
                "jod_vs_truth".to_string(),
                FrontPlace { verdict: FrontVerdict::Undecided, against: vec![rival("fxaa", -0.02)] },
            ),
            ("psnr_vs_truth".to_string(), FrontPlace { verdict: FrontVerdict::Front, against: vec![] }),
        ]);
        let json = serde_json::to_string(&places).unwrap();
        assert!(json.contains(r#""verdict":"undecided""#), "{json}");
        let read: Holder = serde_json::from_str(&format!(r#"{{"fronts": {json}}}"#)).unwrap();
        assert_eq!(read.fronts, places);
        assert_eq!(places["jod_vs_truth"].describe("JOD"), "undecided against fxaa (-0.02 JOD, 0.98× time)");
        assert_eq!(places["jod_vs_truth"].brief(), "~fxaa");
        assert_eq!(places["psnr_vs_truth"].describe("dB"), "on the front");
    }
}
