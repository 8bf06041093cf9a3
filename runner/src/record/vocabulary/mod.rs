//! Every metric a mode's record holds, in one table: its id, what people call it, where in the
//! record it is read, how the gate decides it and with which tolerance, which way is better,
//! its column in the report's tables and its error-against-run-time plot. `compare`, the
//! console, the report (HTML and Markdown), its plots and its rankings loop over [`METRICS`] or
//! name a row; a new metric is its function, one row in `rows.rs`, one record field and its test
//! (along a camera path, also its accumulator in `run/path_metrics.rs`). The times, which the gate
//! decides on intervals instead, are [`TimeMetric`].

use crate::manifest::tolerances::{QualityTolerances, Tolerance};
use crate::record::{ModeRecord, ModeSequence};

mod rows;
pub use rows::*;

/// The part of a mode's record a metric is read from. Each is present or absent as a whole: a
/// run whose mode lacks what its baseline has fails one check for it, not one per metric.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Source {
    /// The comparison with the ground truth.
    Truth,
    /// The comparison with the mode it is compared with (`Mode::compared_with`).
    Reference,
    /// The sample statistics of a mode with a sample-count map.
    Samples,
    /// The mode along the scene's camera path.
    Sequence,
}

impl Source {
    /// Whether the mode's record holds this part.
    pub fn present(self, mode: &ModeRecord) -> bool {
        match self {
            Source::Truth => mode.vs_ground_truth.is_some(),
            Source::Reference => mode.vs_reference.is_some(),
            Source::Samples => mode.samples.is_some(),
            Source::Sequence => mode.sequence().is_some(),
        }
    }

    /// The mode or truth that this part compares the mode with (`truth-8x8`, `deferred-1x1`),
    /// where it is a comparison.
    pub fn against(self, mode: &ModeRecord) -> Option<&str> {
        let quality = match self {
            Source::Truth => mode.vs_ground_truth.as_ref(),
            Source::Reference => mode.vs_reference.as_ref(),
            Source::Samples | Source::Sequence => None,
        };
        quality.map(|q| q.against.as_str())
    }

    /// The check a run fails when its mode lacks this part and the baseline's has it, and why.
    pub fn missing(self) -> (&'static str, &'static str) {
        match self {
            Source::Truth => {
                ("psnr_vs_truth", "the baseline has an error against the truth, the run has none")
            }
            Source::Reference => {
                ("psnr_vs_reference", "the baseline has an error against the reference, the run has none")
            }
            Source::Samples => ("shaded_percent", "the baseline has sample statistics, the run has none"),
            Source::Sequence => {
                ("sequence_psnr_vs_truth", "the baseline has a sequence of this mode, the run has none")
            }
        }
    }
}

/// How the gate decides a metric's change against its tolerance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Rule {
    /// A level, higher better, in `unit` (PSNR in dB, ColorVideoVDP in JOD): moved by more
    /// than the tolerance, in its unit.
    Level { unit: &'static str },
    /// An error whose value for identical images is `perfect` (0 for MSE and FLIP, 1 for SSIM):
    /// its distance from `perfect` moved by more than the tolerance, as a fraction of the
    /// baseline's distance.
    Relative { perfect: f64 },
    /// A share in percent (samples shaded): moved by more than the tolerance in percentage
    /// points, either way; more is worse.
    Points,
}

impl Rule {
    /// Which way a check's change counts as an improvement: up for a level in dB, down for an
    /// error's distance from perfect or a share of samples (see [`Rule::better`] for values).
    pub fn higher_is_better(self) -> bool {
        matches!(self, Rule::Level { .. })
    }

    /// Whether the value `a` is better than `b`: a higher level, an error nearer perfect, a
    /// smaller share.
    pub fn better(self, a: f64, b: f64) -> bool {
        match self {
            Rule::Level { .. } => a > b,
            Rule::Relative { perfect } => (a - perfect).abs() < (b - perfect).abs(),
            Rule::Points => a < b,
        }
    }

    /// The unit a check of this rule gives its change in.
    pub fn unit(self) -> &'static str {
        match self {
            Rule::Level { unit } => unit,
            Rule::Relative { .. } => "relative",
            Rule::Points => "percentage points",
        }
    }
}

/// PSNR's rule.
const DECIBELS: Rule = Rule::Level { unit: "dB" };
/// ColorVideoVDP's rule: just-objectionable differences, 10 for no visible difference.
const JOD: Rule = Rule::Level { unit: "JOD" };

/// The smallest difference of JOD that the report reads as an order: a tenth of the step at
/// which 75 % of viewers prefer the better of two images (about 53 % prefer it at 0.1), and the
/// gate's own tolerance for JOD across platforms. Modes closer than this are one answer.
pub const JOD_MARGIN: f64 = 0.1;

/// The smallest difference of PSNR against the truth that the front reads as an order: the
/// gate's PSNR tolerance across platforms, the change a second machine may show on the same
/// frames (6 % of the MSE). Modes closer than this are one quality, as [`JOD_MARGIN`] argues.
pub const PSNR_MARGIN_DB: f64 = 0.25;

/// The smallest saving of time that a ranking reads as cheaper: one mode is cheaper than
/// another where it is faster with confidence, round by round, *and* the median of their
/// ratios saves at least this share of the other's time. It is the gate's tolerance for time
/// ratios: on a 2-core VM one frame's time varies by 10–17 % from round to round, so a
/// difference of a few percent decides one way in one run and the other way in the next.
pub const TIME_MARGIN: f64 = 0.1;

/// How the gate compares a metric with its baseline.
#[derive(Debug, Clone, Copy)]
pub struct Gate {
    pub rule: Rule,
    /// The tolerance it is decided with.
    pub tolerance: Tolerance,
    /// A value as a check's detail shows it.
    pub show: fn(f64) -> String,
}

impl Gate {
    /// The tolerance in force among `tolerances`.
    pub fn threshold(&self, tolerances: &QualityTolerances) -> f64 {
        tolerances.get(self.tolerance)
    }
}

/// A metric's error-against-run-time plot: every mode at its frame time (along the path, for a
/// sequence's metric: one plot per speed) against its value.
#[derive(Debug, Clone, Copy)]
pub struct Plot {
    /// What the plot is called after the scene's name; a sequence's adds its speed.
    pub title: &'static str,
    pub axis: &'static str,
    /// A value as the axis draws it: an error, lower better, on a log scale (JOD as its
    /// distance below 10).
    pub axis_value: fn(f64) -> f64,
    /// The figure's file name after the scene's, `front-flip`; a sequence's after the first
    /// speed adds the speed's number, `front-flicker-2`.
    pub file: &'static str,
    pub front: Front,
}

/// Which modes a plot draws on its front.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Front {
    /// The modes that run.json records on the front of the metric of this id (decided with
    /// confidence, see `front.rs`); along the plot's sequence for a sequence's metric.
    Recorded(&'static str),
    /// The modes that no faster mode of the same stall beats, by medians.
    Medians,
    /// None: the metric alone does not say which mode is better.
    None,
}

/// The report's tables: the still's, and the one along the camera path.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Table {
    Still,
    Path,
}

/// A metric's column in one of the report's tables.
#[derive(Debug, Clone, Copy)]
pub struct Column {
    pub table: Table,
    pub header: &'static str,
    /// A value as its cell shows it.
    pub cell: fn(f64) -> String,
}

/// Where a metric's value is in a mode's record: anywhere in it, or in one of its sequences
/// (the scene has one per speed).
#[derive(Debug, Clone, Copy)]
pub enum Read {
    Mode(fn(&ModeRecord) -> Option<f64>),
    Along(fn(&ModeSequence) -> Option<f64>),
}

/// One metric of a mode's record.
#[derive(Debug, Clone, Copy)]
pub struct Metric {
    /// The id that checks carry: `psnr_vs_truth`.
    pub id: &'static str,
    /// What people call it, in a sentence: `PSNR against the truth`.
    pub label: &'static str,
    pub source: Source,
    /// Where its value is in a mode's record.
    pub read: Read,
    /// How the gate decides it; `None`: recorded and shown, not gated.
    pub gate: Option<Gate>,
    /// Its column in the report; `None`: gated, not tabled.
    pub column: Option<Column>,
    /// Its error-against-run-time plot; `None`: not plotted.
    pub plot: Option<Plot>,
    /// How a value reads among the details of a ranking's row (`PSNR 36.00 dB`); `None`: not
    /// among them.
    pub brief: Option<fn(f64) -> String>,
    /// Where run.json records the metric's error-against-run-time front (`front.rs`): the
    /// margin, in its unit, within which two of its values are one quality. A level's only.
    pub front_margin: Option<f64>,
}

impl Metric {
    /// Its value in `mode`'s record, where the record has it; a sequence's metric along the
    /// scene's first sequence (the gate's).
    pub fn value(&self, mode: &ModeRecord) -> Option<f64> {
        self.value_at(mode, 0)
    }

    /// `value` as the metric's column writes it (JOD to three decimals, PSNR to two, `∞` for
    /// an image equal to the truth); a metric without a column writes it as Rust does.
    pub fn written(&self, value: f64) -> String {
        self.column.map_or_else(|| value.to_string(), |column| (column.cell)(value))
    }

    /// The unit its values are in (`dB`, `JOD`, `relative` for an error), as its gate's rule
    /// names it.
    pub fn unit(&self) -> &'static str {
        self.gate.map_or("", |gate| gate.rule.unit())
    }

    /// The header of its front's column in a table: `PSNR front`.
    pub fn front_header(&self) -> String {
        format!("{} front", self.label.split(' ').next().unwrap_or(self.label))
    }

    /// Whether `a` is a better value of this metric than `b`, where the gate has a rule for it.
    pub fn better(&self, a: f64, b: f64) -> Option<bool> {
        Some(self.gate?.rule.better(a, b))
    }

    /// Its name in a baseline and in what a bless moved: the id, along each sequence after
    /// the first with the sequence's number (`flicker@2`).
    pub fn key(&self, index: usize) -> String {
        if index == 0 { self.id.to_string() } else { format!("{}@{}", self.id, index + 1) }
    }

    /// How many values it has in a mode of a scene with `sequences` sequences: one per sequence
    /// for a sequence's metric, else one.
    pub fn values_in(&self, sequences: usize) -> usize {
        if self.source == Source::Sequence { sequences } else { 1 }
    }

    /// Its value in `mode`'s record, a sequence's metric along the scene's sequence `index`.
    pub fn value_at(&self, mode: &ModeRecord, index: usize) -> Option<f64> {
        match self.read {
            Read::Mode(read) => read(mode),
            Read::Along(read) => read(mode.sequence_at(index)?),
        }
    }
}

/// A time of a mode. Times are noisy, so the gate decides each on the interval of its shift,
/// not against a tolerance: the first three against the committed baselines and the base
/// build, a pass's only against the base build.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TimeMetric {
    /// The frame time over the geometric mean of the round's other unstalled modes.
    Relative,
    /// An adaptive mode's frame time over its reference's in the same round.
    VsReference,
    /// The frame time itself.
    Frame,
    /// One pass's time over the rest of its frame.
    Pass,
}

impl TimeMetric {
    /// The id a check carries; a pass's is this and the pass's name, `pass_time:shade`.
    pub fn id(self) -> &'static str {
        match self {
            TimeMetric::Relative => "relative_time",
            TimeMetric::VsReference => "time_vs_reference",
            TimeMetric::Frame => "frame_time",
            TimeMetric::Pass => "pass_time:",
        }
    }

    /// The time metric a check's id names, where it names one.
    pub fn of(id: &str) -> Option<TimeMetric> {
        [TimeMetric::Relative, TimeMetric::VsReference, TimeMetric::Frame]
            .into_iter()
            .find(|time| time.id() == id)
            .or_else(|| id.starts_with(TimeMetric::Pass.id()).then_some(TimeMetric::Pass))
    }
}

/// The rule of an error that is 0 for identical images.
const ERROR: Rule = Rule::Relative { perfect: 0.0 };

/// The metric of id `id`.
pub fn metric(id: &str) -> Option<&'static Metric> {
    METRICS.iter().find(|metric| metric.id == id)
}

/// The metric and sequence index a key names (`flicker@2`: flicker along the second sequence),
/// the inverse of [`Metric::key`].
pub fn keyed(key: &str) -> Option<(&'static Metric, usize)> {
    let (id, index) = match key.split_once('@') {
        Some((id, number)) => (id, number.parse::<usize>().ok()?.checked_sub(1)?),
        None => (key, 0),
    };
    Some((metric(id)?, index))
}

/// The metrics with a column in `table`, in column order.
pub fn columns(table: Table) -> impl Iterator<Item = (&'static Metric, Column)> {
    METRICS.iter().filter_map(move |m| m.column.filter(|c| c.table == table).map(|c| (m, c)))
}

/// The metrics whose fronts run.json records and `table` shows: the still's against the truth,
/// the path's along it.
pub fn fronts(table: Table) -> impl Iterator<Item = &'static Metric> {
    let source = match table {
        Table::Still => Source::Truth,
        Table::Path => Source::Sequence,
    };
    METRICS.iter().filter(move |m| m.front_margin.is_some() && m.source == source)
}

/// A metric's cell for `mode` (a sequence's metric along the scene's sequence `index`): its
/// value as the column shows it, `–` where the mode has none.
pub fn cell(metric: &Metric, column: Column, mode: &ModeRecord, index: usize) -> String {
    metric.value_at(mode, index).map_or_else(|| "–".into(), column.cell)
}

/// A PSNR to two decimals, `∞` for identical images.
pub fn decibels(db: f64) -> String {
    if db.is_finite() { format!("{db:.2}") } else { "∞".into() }
}

fn decibels_3(db: f64) -> String {
    if db.is_finite() { format!("{db:.3} dB") } else { "∞ dB".into() }
}

fn mse_e5(mse: f64) -> String {
    format!("{:.4} ×1e-5", mse * 1e5)
}

fn percent(value: f64) -> String {
    format!("{value:.2}%")
}

fn one_decimal(value: f64) -> String {
    format!("{value:.1}")
}

fn jod(value: f64) -> String {
    format!("{value:.3}")
}

/// A JOD's distance below 10 (no visible difference): an error, for a log axis.
fn jod_loss(value: f64) -> f64 {
    10.0 - value
}

fn two_decimals(value: f64) -> String {
    format!("{value:.2}")
}

fn four_decimals(value: f64) -> String {
    format!("{value:.4}")
}

fn five_decimals(value: f64) -> String {
    format!("{value:.5}")
}

/// A share in [0, 1] as a percentage to two decimals.
fn hundredths_of_percent(share: f64) -> String {
    format!("{:.2}", share * 100.0)
}

/// An MSE in thousandths, to two decimals.
fn thousandths(mse: f64) -> String {
    format!("{:.2}", mse * 1e3)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_are_unique_and_every_gated_source_names_a_gated_metric_of_its_own() {
        for (i, metric) in METRICS.iter().enumerate() {
            assert!(METRICS[..i].iter().all(|m| m.id != metric.id), "{} twice", metric.id);
            assert!(
                metric.gate.is_some() || metric.column.is_some(),
                "{}: neither gated nor shown",
                metric.id
            );
        }
        for source in [Source::Truth, Source::Reference, Source::Samples, Source::Sequence] {
            let (id, _) = source.missing();
            let named = metric(id).unwrap_or_else(|| panic!("{source:?} names {id}, no metric"));
            assert!(named.source == source && named.gate.is_some(), "{id}");
        }
    }

    #[test]
    fn a_better_value_is_a_higher_level_an_error_nearer_perfect_or_a_smaller_share() {
        assert_eq!(PSNR_VS_TRUTH.better(30.0, 29.0), Some(true));
        assert_eq!(FLIP_VS_TRUTH.better(0.02, 0.01), Some(false));
        let ssim = metric("ssim_vs_truth").unwrap();
        assert_eq!(ssim.better(0.99, 0.98), Some(true), "nearer 1");
        assert_eq!(metric("shaded_percent").unwrap().better(40.0, 50.0), Some(true));
        assert_eq!(metric("change_ratio").unwrap().better(1.0, 2.0), None, "not gated: no rule");
    }

    #[test]
    fn what_lag_costs_is_a_gated_path_row_and_the_rankings_details_are_rows() {
        let lag = metric("disoccluded_mse").unwrap();
        assert_eq!(lag.source, Source::Sequence);
        assert!(lag.gate.is_some() && lag.column.is_some(), "gated and tabled");
        let briefed = |source| -> Vec<&str> {
            METRICS.iter().filter(|m| m.source == source && m.brief.is_some()).map(|m| m.id).collect()
        };
        let path = ["sequence_psnr_vs_truth", "sequence_flip_vs_truth", "flicker", "disoccluded_mse"];
        assert_eq!(briefed(Source::Sequence), path);
        assert_eq!(briefed(Source::Truth), ["psnr_vs_truth", "flip_vs_truth"]);
        assert_eq!((PSNR_VS_TRUTH.brief.unwrap())(f64::INFINITY), "PSNR ∞ dB");
        assert_eq!((lag.brief.unwrap())(8.634e-3), "disoccluded MSE 8.63e-3");
    }

    #[test]
    fn the_first_plot_is_the_stills_error_and_every_plot_has_a_direction() {
        let plotted: Vec<&Metric> = METRICS.iter().filter(|m| m.plot.is_some()).collect();
        assert_eq!(plotted[0].id, "mse_vs_truth", "the report's first plot, whose absence it reports");
        let recorded = Front::Recorded("psnr_vs_truth");
        assert_eq!(plotted[0].plot.unwrap().front, recorded, "run.json's front is by the still");
        for metric in plotted {
            assert!(metric.better(1.0, 2.0).is_some(), "{}: a front needs a direction", metric.id);
            if let Front::Recorded(id) = metric.plot.unwrap().front {
                let of = self::metric(id).unwrap();
                assert!(of.front_margin.is_some(), "{}: {id} records no front", metric.id);
                assert_eq!(of.source, metric.source, "{}: a front of the same sequence", metric.id);
            }
        }
    }

    #[test]
    fn the_fronts_are_of_levels_psnr_the_papers_and_jod_the_rankings() {
        let fronts: Vec<&str> = METRICS.iter().filter(|m| m.front_margin.is_some()).map(|m| m.id).collect();
        assert_eq!(fronts, ["psnr_vs_truth", "jod_vs_truth", "sequence_jod_vs_truth"]);
        for metric in METRICS.iter().filter(|m| m.front_margin.is_some()) {
            assert!(
                matches!(metric.gate.unwrap().rule, Rule::Level { .. }),
                "{}: a margin of a level",
                metric.id
            );
        }
    }

    #[test]
    fn a_key_names_its_metric_and_sequence() {
        let flicker = metric("flicker").unwrap();
        assert_eq!(flicker.key(1), "flicker@2");
        assert_eq!(keyed("flicker@2").map(|(m, i)| (m.id, i)), Some(("flicker", 1)));
        assert_eq!(keyed("psnr_vs_truth").map(|(m, i)| (m.id, i)), Some(("psnr_vs_truth", 0)));
        assert!(keyed("flicker@0").is_none() && keyed("flicker@x").is_none() && keyed("nothing").is_none());
    }

    #[test]
    fn the_psnr_margin_is_the_gates_tolerance_across_platforms() {
        let across = crate::manifest::tolerances::Tolerances::default().quality(false).get(Tolerance::PsnrDb);
        assert_eq!(PSNR_MARGIN_DB, across);
    }

    #[test]
    fn time_metrics_are_named_by_their_ids_and_a_pass_by_its_prefix() {
        for time in [TimeMetric::Relative, TimeMetric::VsReference, TimeMetric::Frame] {
            assert_eq!(TimeMetric::of(time.id()), Some(time));
            assert!(metric(time.id()).is_none(), "{} is no quality metric", time.id());
        }
        assert_eq!(TimeMetric::of("pass_time:shade"), Some(TimeMetric::Pass));
        assert_eq!(TimeMetric::of("psnr_vs_truth"), None);
    }

    #[test]
    fn cells_show_infinity_and_missing_values() {
        assert_eq!(decibels(f64::INFINITY), "∞");
        assert_eq!(decibels(31.256), "31.26");
        assert_eq!(decibels_3(31.2564), "31.256 dB");
        assert_eq!(mse_e5(1.23456e-5), "1.2346 ×1e-5");
    }
}
