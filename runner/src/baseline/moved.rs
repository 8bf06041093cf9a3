//! What a bless moved: the new baselines against the ones they replace, value by value — every
//! metric of the vocabulary (along each sequence too), the sample statistics and every output
//! hash — so that a commit that blesses says what it changed, and a reviewer sees at once
//! whether the paper's bits moved. Times move with every measurement and are left out.

use std::fmt::Write;

use crate::baseline::{Baseline, BlessedMode, BlessedSamples};
use crate::record::is_paper;
use crate::record::vocabulary::METRICS;

/// One value of a mode that the bless changed.
#[derive(Debug, Clone, PartialEq)]
pub struct Moved {
    pub scene: String,
    pub mode: String,
    /// The metric's id (a sequence's after the first with its number, `flicker@2`), or the
    /// sample statistic's name.
    pub value: String,
    pub old: String,
    pub new: String,
}

/// A mode whose output hash moved.
#[derive(Debug, Clone, PartialEq)]
pub struct HashMoved {
    pub scene: String,
    pub mode: String,
    /// Whether it is the paper's mode, whose bits the gate enforces.
    pub paper: bool,
    pub old: String,
    pub new: String,
}

/// Everything a bless moved.
#[derive(Debug, Default)]
pub struct Changes {
    pub moved: Vec<Moved>,
    pub hashes: Vec<HashMoved>,
    /// Scenes and modes on one side only: `atrium: a new scene`, `thin taa: new`,
    /// `thin fxaa: no longer blessed`.
    pub presence: Vec<String>,
    /// The output hashes compared, on both sides.
    pub compared: usize,
}

impl Changes {
    pub fn nothing_moved(&self) -> bool {
        self.moved.is_empty() && self.hashes.is_empty() && self.presence.is_empty()
    }
}

/// The `new` baselines against the `old` ones they replace (a scene without an old one is new).
pub fn between(old: &[Baseline], new: &[Baseline]) -> Changes {
    let mut changes = Changes::default();
    for now in new {
        let Some(then) = old.iter().find(|b| b.scene == now.scene) else {
            changes.presence.push(format!("{}: a new scene ({} modes)", now.scene, now.modes.len()));
            continue;
        };
        let sequences = now.sequences.len().max(then.sequences.len());
        for (id, mode) in &now.modes {
            match then.mode(id) {
                Some(old_mode) => compare_mode(&now.scene, id, mode, old_mode, sequences, &mut changes),
                None => changes.presence.push(format!("{} {id}: new", now.scene)),
            }
        }
        for id in then.modes.keys().filter(|id| now.mode(id).is_none()) {
            changes.presence.push(format!("{} {id}: no longer blessed", now.scene));
        }
    }
    changes
}

/// One mode's output hash, metrics and sample statistics, old against new.
fn compare_mode(
    scene: &str,
    id: &str,
    now: &BlessedMode,
    then: &BlessedMode,
    sequences: usize,
    changes: &mut Changes,
) {
    if let (Some(new), Some(old)) = (&now.output_hash, &then.output_hash) {
        changes.compared += 1;
        if new != old {
            let (old, new, paper) = (old.clone(), new.clone(), is_paper(id));
            changes.hashes.push(HashMoved { scene: scene.into(), mode: id.into(), paper, old, new });
        }
    }
    let mut push = |value: String, old: String, new: String| {
        if old != new {
            changes.moved.push(Moved { scene: scene.into(), mode: id.into(), value, old, new });
        }
    };
    for metric in &METRICS {
        for index in 0..metric.values_in(sequences) {
            push(metric.key(index), shown(then.value_at(metric, index)), shown(now.value_at(metric, index)));
        }
    }
    for (name, read) in SAMPLE_VALUES {
        let read = |mode: &BlessedMode| mode.samples.as_ref().map_or_else(|| "–".to_string(), read);
        push(format!("samples.{name}"), read(then), read(now));
    }
}

/// A sample statistic as a bless shows it.
type SampleValue = fn(&BlessedSamples) -> String;

/// The sample statistics a bless reports beside the vocabulary's `shaded_percent`: the work
/// done and the distribution.
const SAMPLE_VALUES: [(&str, SampleValue); 4] = [
    ("reshaded", |s| s.reshaded.to_string()),
    ("work_percent", |s| s.work_percent.to_string()),
    ("full_pixels", |s| s.full_pixels.to_string()),
    ("histogram", |s| format!("{:?}", s.histogram)),
];

/// A value exactly (the shortest text that reads back to the same number), `–` where absent.
fn shown(value: Option<f64>) -> String {
    value.map_or_else(|| "–".into(), |v| v.to_string())
}

/// The changes as Markdown, headed by what was blessed from which runs.
pub fn markdown(changes: &Changes, heading: &str) -> String {
    let mut out = format!("# What the bless moved\n\n{heading}\n\n");
    if changes.nothing_moved() {
        let _ = writeln!(
            out,
            "Nothing moved: every one of the {} output hashes, every metric and every sample statistic \
             is as the baselines held (times aside).",
            changes.compared
        );
        return out;
    }
    let paper: Vec<String> =
        changes.hashes.iter().filter(|h| h.paper).map(|h| format!("**{} {}**", h.scene, h.mode)).collect();
    let mut sections = vec![format!(
        "Output hashes moved in {} of {} modes; the paper's mode: {}.",
        changes.hashes.len(),
        changes.compared,
        if paper.is_empty() { "none moved".to_string() } else { paper.join(", ") }
    )];
    if !changes.presence.is_empty() {
        sections.push(changes.presence.iter().map(|line| format!("- {line}")).collect::<Vec<_>>().join("\n"));
    }
    if !changes.hashes.is_empty() {
        let mut table = String::from("| scene | mode | output hash |\n|---|---|---|");
        for hash in &changes.hashes {
            let mode =
                if hash.paper { format!("**{}** (the paper's)", hash.mode) } else { hash.mode.clone() };
            let _ = write!(table, "\n| {} | {mode} | {} → {} |", hash.scene, hash.old, hash.new);
        }
        sections.push(table);
    }
    if !changes.moved.is_empty() {
        let mut table = String::from("| scene | mode | value | old | new |\n|---|---|---|---|---|");
        for m in &changes.moved {
            let _ = write!(table, "\n| {} | {} | {} | {} | {} |", m.scene, m.mode, m.value, m.old, m.new);
        }
        sections.push(table);
    }
    out.push_str(&sections.join("\n\n"));
    out.push('\n');
    out
}
