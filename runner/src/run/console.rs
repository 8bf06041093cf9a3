//! The scene's results as the terminal shows them: a line naming the scene, its resolution and
//! its camera path, then a table of its modes that fits 120 columns, with JOD (of the still
//! and along the path) beside PSNR. The run's closing summary is `report::closing`.

use crate::record::TruthRecord;
use crate::record::vocabulary::{JOD_VS_TRUTH, SEQUENCE_JOD_VS_TRUTH};
use crate::record::{FrontPlace, ModeRecord, SceneRecord};
use crate::run::progress::Progress;

/// The widest line the table is laid out for.
const WIDTH: usize = 120;

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
    lines.push(format!(
        "  {:<width$} {:>7} {:>5} {:>5} {:>5} {:>6} {:>6} {:>5} {:>5} {:>6}  {}",
        "mode", "ms", "±", "×1x1", "smp%", "PSNR", "FLIP", "JOD", "pJOD", "pPSNR", "front"
    ));
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
    let or_dash = |value: Option<String>| value.unwrap_or_else(|| "-".into());
    let decibels = |db: f64| if db.is_finite() { format!("{db:.2}") } else { "∞".into() };
    let truth = mode.vs_ground_truth.as_ref();
    let path = mode.sequence();
    let spread = (frame.ci_high - frame.ci_low) / 2.0 / frame.median.max(f64::MIN_POSITIVE);
    let front = mode.front(front).map(FrontPlace::brief);
    let row = format!(
        "  {:<width$} {:>7.1} {:>4.0}% {:>5} {:>5} {:>6} {:>6} {:>5} {:>5} {:>6}  {}",
        mode.mode,
        frame.median,
        spread * 100.0,
        or_dash(mode.ratio_to_deferred.map(|r| format!("{r:.2}"))),
        or_dash(mode.samples.as_ref().map(|s| format!("{:.1}", s.shaded_percent))),
        or_dash(truth.map(|q| decibels(q.psnr_db.value()))),
        or_dash(truth.and_then(|q| q.flip).map(|f| format!("{f:.4}"))),
        or_dash(truth.and_then(|q| q.jod).map(|j| format!("{j:.2}"))),
        or_dash(path.and_then(|s| s.jod).map(|j| format!("{j:.2}"))),
        or_dash(path.map(|s| decibels(s.mean_psnr_db.value()))),
        or_dash(front),
    );
    std::iter::once(clip(row)).chain(error).collect()
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
