//! The regression gate's tolerances: documented defaults, overridable per scene in the
//! manifest's `gate` section, and recorded with every scene of a run so that `compare` judges a
//! run by the tolerances it was run with.

use std::sync::LazyLock;

use serde::de::{self, MapAccess, SeqAccess, Visitor};
use serde::ser::SerializeMap;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// The fewest timed frames of a mode, on each side, from which a time check against committed
/// baselines is decided. With fewer, the interval is the few ratios themselves: one frame a
/// side gave false regressions in 3 of 4 compares of a build with itself.
pub const MIN_FRAMES: usize = 5;

/// A quality tolerance: how far one kind of quality number may move, on the baselines' own
/// platform and against another's. Each metric of [`crate::record::vocabulary::METRICS`] that the gate
/// decides names one; the sample histogram has its own.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Tolerance {
    /// PSNR (against the truth and against the same-M reference), in dB.
    PsnrDb,
    /// MSE (and errors of squared code values: flicker, instability), as a fraction of the
    /// baseline's.
    MseRelative,
    /// Samples % of adaptive modes, in percentage points.
    ShadedPercent,
    /// Total-variation distance between the normalized sample-count histograms (0 to 1).
    Histogram,
    /// Mean FLIP against the truth, as a fraction of the baseline's.
    FlipRelative,
    /// 1 − SSIM against the truth (the dissimilarity), as a fraction of the baseline's.
    SsimRelative,
    /// ColorVideoVDP's JOD against the truth (the still's and along a path), in JOD.
    Jod,
}

/// A quality tolerance's fields in a manifest's `gate` section and its defaults.
struct Row {
    field: &'static str,
    cross_field: &'static str,
    default: f64,
    cross_default: f64,
}

impl Tolerance {
    pub const ALL: [Tolerance; 7] = [
        Tolerance::PsnrDb,
        Tolerance::MseRelative,
        Tolerance::ShadedPercent,
        Tolerance::Histogram,
        Tolerance::FlipRelative,
        Tolerance::SsimRelative,
        Tolerance::Jod,
    ];

    /// Its fields and defaults: tight on the baselines' platform, where quality is nearly
    /// deterministic; wider across platforms, where they still catch a 0.5 dB drop.
    const fn row(self) -> Row {
        let (field, cross_field, default, cross_default) = match self {
            Tolerance::PsnrDb => ("psnr_db", "psnr_db_cross_platform", 0.02, 0.25),
            Tolerance::MseRelative => ("mse_relative", "mse_relative_cross_platform", 0.005, 0.06),
            Tolerance::ShadedPercent => ("shaded_percent", "shaded_percent_cross_platform", 0.05, 0.5),
            Tolerance::Histogram => ("histogram", "histogram_cross_platform", 0.002, 0.01),
            Tolerance::FlipRelative => ("flip_relative", "flip_relative_cross_platform", 0.005, 0.06),
            Tolerance::SsimRelative => ("ssim_relative", "ssim_relative_cross_platform", 0.005, 0.06),
            // The port is deterministic: on the baselines' platform the same bits score the
            // same to 10⁻⁶. Across platforms 0.1 JOD is a tenth of the difference at which 75 %
            // of observers prefer the better image.
            Tolerance::Jod => ("jod", "jod_cross_platform", 0.01, 0.1),
        };
        Row { field, cross_field, default, cross_default }
    }
}

/// How far a metric may move before `compare` calls it improved or regressed.
///
/// Quality is nearly deterministic on one platform (lavapipe gives the same bits on every
/// machine with the same Mesa), so its tolerances are tight; against a baseline of another
/// platform key the cross-platform tolerances apply. Times are noisy: a time metric moves only
/// when the whole confidence interval of its change is past the threshold. In a manifest's
/// `gate` section and in a record each quality tolerance is two fields, `psnr_db` and
/// `psnr_db_cross_platform`; omitted fields take their defaults.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerances {
    /// Each [`Tolerance`] in the order of [`Tolerance::ALL`], on the baselines' own platform.
    pub same_platform: [f64; 7],
    /// Each [`Tolerance`] in the order of [`Tolerance::ALL`], against another platform.
    pub cross_platform: [f64; 7],
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
            same_platform: Tolerance::ALL.map(|t| t.row().default),
            cross_platform: Tolerance::ALL.map(|t| t.row().cross_default),
            time_ratio: 0.10,
            absolute_time: 0.40,
        }
    }
}

impl Tolerances {
    /// Every field as `gate` spells it, with its value: each quality tolerance and its
    /// cross-platform twin, then the time tolerances.
    fn fields(&self) -> Vec<(&'static str, f64)> {
        let mut fields = Vec::with_capacity(14);
        for (i, tolerance) in Tolerance::ALL.iter().enumerate() {
            let row = tolerance.row();
            fields.push((row.field, self.same_platform[i]));
            fields.push((row.cross_field, self.cross_platform[i]));
        }
        fields.push(("time_ratio", self.time_ratio));
        fields.push(("absolute_time", self.absolute_time));
        fields
    }

    /// The field `name` as `gate` spells it, to be set.
    fn field_mut(&mut self, name: &str) -> Option<&mut f64> {
        match name {
            "time_ratio" => return Some(&mut self.time_ratio),
            "absolute_time" => return Some(&mut self.absolute_time),
            _ => {}
        }
        let i = Tolerance::ALL.iter().position(|t| t.row().field == name || t.row().cross_field == name)?;
        Some(if Tolerance::ALL[i].row().field == name {
            &mut self.same_platform[i]
        } else {
            &mut self.cross_platform[i]
        })
    }

    /// Checks every tolerance; `Err((field, reason))` names the first bad one.
    pub fn validate(&self) -> Result<(), (String, String)> {
        for (name, value) in self.fields() {
            let time = matches!(name, "time_ratio" | "absolute_time");
            let (sound, bound) = if time { (value > 0.0, "> 0") } else { (value >= 0.0, "≥ 0") };
            if !(value.is_finite() && sound) {
                return Err((format!("gate.{name}"), format!("{value} must be finite and {bound}")));
            }
        }
        Ok(())
    }

    /// The quality tolerances that apply against a baseline of the same or another platform.
    pub fn quality(&self, same_platform: bool) -> QualityTolerances {
        QualityTolerances(if same_platform { self.same_platform } else { self.cross_platform })
    }
}

/// The quality tolerances in force for one comparison.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QualityTolerances([f64; 7]);

impl QualityTolerances {
    pub fn get(&self, tolerance: Tolerance) -> f64 {
        self.0[Tolerance::ALL.iter().position(|&t| t == tolerance).expect("every tolerance is in ALL")]
    }
}

/// Every field name, for serde's "expected one of" message.
static FIELDS: LazyLock<Vec<&'static str>> =
    LazyLock::new(|| Tolerances::default().fields().into_iter().map(|(name, _)| name).collect());

impl Serialize for Tolerances {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let fields = self.fields();
        let mut map = serializer.serialize_map(Some(fields.len()))?;
        for (name, value) in fields {
            map.serialize_entry(name, &value)?;
        }
        map.end()
    }
}

impl<'de> Deserialize<'de> for Tolerances {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserializer.deserialize_struct("Tolerances", &FIELDS, TolerancesVisitor)
    }
}

/// A field's name, refused as serde's derive refuses it where it names no tolerance.
struct Field(&'static str);

impl<'de> Deserialize<'de> for Field {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct FieldVisitor;
        impl Visitor<'_> for FieldVisitor {
            type Value = Field;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("field identifier")
            }
            fn visit_str<E: de::Error>(self, name: &str) -> Result<Field, E> {
                FIELDS
                    .iter()
                    .find(|&&f| f == name)
                    .map(|&f| Field(f))
                    .ok_or_else(|| E::unknown_field(name, &FIELDS))
            }
        }
        deserializer.deserialize_identifier(FieldVisitor)
    }
}

struct TolerancesVisitor;

impl<'de> Visitor<'de> for TolerancesVisitor {
    type Value = Tolerances;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("struct Tolerances")
    }

    /// The fields in their order, as serde's derive reads an array; missing ones take defaults.
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Tolerances, A::Error> {
        let mut tolerances = Tolerances::default();
        for name in FIELDS.iter() {
            match seq.next_element()? {
                Some(value) => *tolerances.field_mut(name).expect("a known field") = value,
                None => break,
            }
        }
        Ok(tolerances)
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Tolerances, A::Error> {
        let mut tolerances = Tolerances::default();
        let mut seen = Vec::new();
        while let Some(Field(name)) = map.next_key()? {
            if seen.contains(&name) {
                return Err(de::Error::duplicate_field(name));
            }
            seen.push(name);
            *tolerances.field_mut(name).expect("a known field") = map.next_value()?;
        }
        Ok(tolerances)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tolerances_read_and_write_their_fields_by_name_with_defaults_for_the_rest() {
        let text = serde_json::to_string(&Tolerances::default()).unwrap();
        assert!(
            text.starts_with(r#"{"psnr_db":0.02,"psnr_db_cross_platform":0.25,"mse_relative":0.005"#),
            "{text}"
        );
        assert!(text.ends_with(r#""time_ratio":0.1,"absolute_time":0.4}"#), "{text}");
        let read: Tolerances = serde_json::from_str(&text).unwrap();
        assert_eq!(read, Tolerances::default());
        let custom: Tolerances =
            serde_json::from_str(r#"{"flip_relative_cross_platform": 0.5, "time_ratio": 0.2}"#).unwrap();
        assert_eq!(custom.quality(false).get(Tolerance::FlipRelative), 0.5);
        assert_eq!(custom.quality(true).get(Tolerance::FlipRelative), 0.005);
        assert_eq!(custom.time_ratio, 0.2);
        let unknown = serde_json::from_str::<Tolerances>(r#"{"psnr": 1}"#).unwrap_err().to_string();
        assert!(unknown.contains("unknown field `psnr`, expected one of `psnr_db`"), "{unknown}");
        let twice = serde_json::from_str::<Tolerances>(r#"{"psnr_db": 1, "psnr_db": 2}"#).unwrap_err();
        assert!(twice.to_string().contains("duplicate field `psnr_db`"), "{twice}");
        // As serde's derive did: an array gives the fields in order.
        let listed: Tolerances = serde_json::from_str("[0.5, 0.75]").unwrap();
        assert_eq!(
            (listed.quality(true).get(Tolerance::PsnrDb), listed.quality(false).get(Tolerance::PsnrDb)),
            (0.5, 0.75)
        );
        assert_eq!(listed.time_ratio, 0.1);
    }
}
