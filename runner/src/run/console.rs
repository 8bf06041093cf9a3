//! The scene's results as the terminal shows them: a line naming the scene, its resolution and
//! its camera path, then a table of its modes that fits 120 columns, with JOD (of the still
//! and along the path) beside PSNR. The run's closing summary is `report::closing`.

use crate::record::TruthRecord;
use crate::record::vocabulary::{self, JOD_VS_TRUTH, SEQUENCE_JOD_VS_TRUTH};
use crate::record::{FrontPlace, ModeRecord, SceneRecord};
use crate::run::progress::Progress;

/// The widest line the table is laid out for.
const WIDTH: usize = 120;

/// The table's quality columns, after the times: each a row of the vocabulary, its values
/// written as the row writes them everywhere (a path's along the first speed), under a header
/// short enough for the terminal, right-aligned in a width.
const QUALITY_COLUMNS: [(&str, &str, usize); 6] = [
    ("shaded_percent", "smp%", 5),
    ("psnr_vs_truth", "PSNR", 6),
    ("flip_vs_truth", "FLIP", 6),
    ("jod_vs_truth", "JOD", 5),
    ("sequence_jod_vs_truth", "pJOD", 5),
    ("sequence_psnr_vs_truth", "pPSNR", 6),
];

/// Prints a scene's results: its line, then its table.
pub(super) fn report_scene(progress: &Progress, scene: &SceneRecord) {
    for line in scene_lines(scene) {
        progress.line(&line);
    }
}

/// The scene's lines and table, as printed.
fn scene_lines(scene: &SceneRecord) -> Vec<String> {
    let resolution = scene.resolution.map_or(String::new(), |[w, h]| format!(" {w}×{h}"));
    if let (Some(error), true) = (&scene.error, scene.modes.is_empty()) {
        return vec![format!("[{}]{resolution} FAILED: {error}", scene.name)];
    }
    let path = match scene.sequences.len() {
        0 => "no camera path".to_string(),
        1 => format!("path: {}", scene.sequences[0].speed()),
        n => format!("path: {} (the first of {n} speeds: the table's)", scene.sequences[0].speed()),
    };
    let truth = scene.truth.as_ref().map_or("none".into(), truth_summary);
    let mut lines = vec![
        format!("[{}]{resolution} · {path}", scene.name),
        format!("  {} triangles · ground truth {truth}", scene.triangles.unwrap_or(0)),
    ];
    if let Some(error) = &scene.error {
        lines.push(format!("  FAILED: {error}"));
    }
    // The mode column is as wide as the scene's longest id.
    let width = scene.modes.iter().map(|m| m.mode.chars().count()).max().unwrap_or(0).max(4);
    let headers: String = QUALITY_COLUMNS.iter().map(|(_, header, w)| format!(" {header:>w$}")).collect();
    lines.push(format!("  {:<width$} {:>7} {:>5} {:>5}{headers}  front", "mode", "ms", "±", "×1x1"));
    // The front the rankings read: JOD's, along the path where the scene has one.
    let front = if scene.sequences.is_empty() { JOD_VS_TRUTH.key(0) } else { SEQUENCE_JOD_VS_TRUTH.key(0) };
    lines.extend(scene.modes.iter().flat_map(|mode| mode_lines(mode, width, &front)));
    lines.push(
        "  ± half the interval · smp% samples shaded · still PSNR, FLIP, JOD against the truth · pJOD, \
         pPSNR along the path"
            .into(),
    );
    let along = if scene.sequences.is_empty() { "" } else { " along the path" };
    lines.push(format!("  front: on the JOD front{along}, behind a mode, or ~ undecided against one"));
    lines
}

/// A mode's row, its id padded to `width` and the row cut to [`WIDTH`], and its error on a line
/// of its own, whole.
fn mode_lines(mode: &ModeRecord, width: usize, front: &str) -> Vec<String> {
    let error = mode.error.as_ref().map(|e| format!("    {}: {e}", mode.mode));
    let Some(frame) = &mode.frame_ms else {
        return vec![error.unwrap_or_else(|| format!("    {}: no frames", mode.mode))];
    };
    let spread = (frame.ci_high - frame.ci_low) / 2.0 / frame.median.max(f64::MIN_POSITIVE);
    let front = mode.front(front).map_or_else(|| "–".into(), FrontPlace::brief);
    let ratio = mode.ratio_to_deferred.map_or_else(|| "–".into(), |r| format!("{r:.2}"));
    let quality: String =
        QUALITY_COLUMNS.iter().map(|&(id, _, w)| format!(" {:>w$}", quality_cell(id, mode))).collect();
    let row = format!(
        "  {:<width$} {:>7.1} {:>4.0}% {ratio:>5}{quality}  {front}",
        mode.mode,
        frame.median,
        spread * 100.0,
    );
    std::iter::once(clip(row)).chain(error).collect()
}

/// The cell of the vocabulary's metric `id` for `mode`, as the metric's column writes it.
fn quality_cell(id: &str, mode: &ModeRecord) -> String {
    let metric = vocabulary::metric(id).expect("the console's columns are rows of the vocabulary");
    let column = metric.column.expect("the console's columns are columns of the report");
    vocabulary::cell(metric, column, mode, 0)
}

/// A row cut to [`WIDTH`] characters, with `…` where it was cut.
fn clip(row: String) -> String {
    if row.chars().count() <= WIDTH {
        return row;
    }
    row.chars().take(WIDTH - 1).chain(['…']).collect()
}

/// How the truth was obtained, for the printed summary.
fn truth_summary(truth: &TruthRecord) -> String {
    match (&truth.error, truth.cached, truth.render_s) {
        (Some(error), _, _) => format!("FAILED: {error}"),
        (None, true, _) => format!("{} (cached)", truth.id),
        (None, false, Some(seconds)) => format!("{} (rendered in {seconds:.1} s)", truth.id),
        (None, false, None) => truth.id.clone(),
    }
}
