//! Earlier runs of the same tier: read from a history folder and plotted per scene.

use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::{Path, PathBuf};

use aabench_renderer::{Mode, Technique};

use super::plots::{self, Series};
use crate::record::{ModeRecord, RunRecord, SceneRecord};

/// The history to plot: runs of the run's tier, oldest first, the run itself included once.
pub(super) fn history_runs<'a>(run: &'a RunRecord, history: &'a [RunRecord]) -> Vec<&'a RunRecord> {
    if history.is_empty() {
        return Vec::new();
    }
    let mut runs: BTreeMap<(&str, &str), &RunRecord> = history
        .iter()
        .filter(|r| r.tier == run.tier)
        .map(|r| ((r.started_at.as_str(), r.run_id.as_str()), r))
        .collect();
    runs.insert((run.started_at.as_str(), run.run_id.as_str()), run);
    runs.into_values().collect()
}

pub(super) fn history_plots(
    page: &mut String,
    scene: &SceneRecord,
    history: &[&RunRecord],
) -> Result<(), String> {
    if history.len() < 2 {
        return Ok(());
    }
    let labels: Vec<String> =
        history.iter().map(|r| r.run_id.get(4..13).unwrap_or(&r.run_id).to_string()).collect();
    let mode_of = |run: &RunRecord, id: &str| -> Option<ModeRecord> {
        run.scenes.iter().find(|s| s.name == scene.name)?.mode(id).cloned()
    };
    let series = |ids: &[String], value: &dyn Fn(&ModeRecord) -> Option<f64>| -> Vec<Series> {
        ids.iter()
            .map(|id| Series {
                name: id.clone(),
                values: history.iter().map(|run| mode_of(run, id).as_ref().and_then(value)).collect(),
            })
            .filter(|s| s.values.iter().any(Option::is_some))
            .collect()
    };
    let ids = |modes: &[Mode]| modes.iter().map(Mode::to_string).collect::<Vec<_>>();
    let paper = |m: u32, stalled: bool| Mode::new(super::PAPER, m, stalled);
    let adaptive = ids(&(2..=4).flat_map(|m| [paper(m, false), paper(m, true)]).collect::<Vec<_>>());
    // Quality does not depend on stalling; the variants' time is charted nowhere here (the
    // error-against-time plot holds it).
    let quality = ids(&(2..=4).flat_map(super::reconstructions).collect::<Vec<_>>());
    let reference = |stalled| Mode::new(Technique::Reference, 4, stalled);
    let timed = ids(&[
        Mode::new(Technique::Deferred, 1, false),
        reference(false),
        paper(4, false),
        reference(true),
        paper(4, true),
    ]);
    let charts = [
        (
            "speed-up over the same-M reference",
            "×",
            series(&adaptive, &|m| m.adaptive.as_ref().map(|a| a.speedup)),
        ),
        (
            "PSNR against the truth",
            "dB",
            series(&quality, &|m| {
                m.vs_ground_truth.as_ref().map(|q| q.psnr_db.value()).filter(|v| v.is_finite())
            }),
        ),
        (
            "frame time (absolute: drifts between processes)",
            "ms",
            series(&timed, &|m| m.frame_ms.as_ref().map(|f| f.median)),
        ),
    ];
    let _ = writeln!(page, "<h3>History ({} runs)</h3>\n<div class=\"row\">", history.len());
    for (title, unit, lines) in charts {
        if lines.is_empty() {
            continue;
        }
        let _ = write!(
            page,
            "<figure class=\"plot\">{}</figure>",
            plots::history(&format!("{}: {title}", scene.name), unit, &labels, &lines)?
        );
    }
    page.push_str("</div>\n");
    Ok(())
}

/// Reads the runs of a history folder: `*.json` run records in it, and `*/run.json`. Files
/// that do not read as runs of this schema (older aabench versions, strays) are skipped with a
/// warning each, so one bad file does not stop the nightly report.
pub fn load_history(dir: &Path) -> Result<(Vec<RunRecord>, Vec<String>), String> {
    let entries = std::fs::read_dir(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let mut files: Vec<PathBuf> = entries
        .filter_map(|entry| entry.ok().map(|e| e.path()))
        .filter_map(|path| {
            if path.is_dir() {
                Some(path.join("run.json")).filter(|p| p.is_file())
            } else {
                path.extension().is_some_and(|ext| ext == "json").then_some(path)
            }
        })
        .collect();
    files.sort();
    let (mut runs, mut skipped) = (Vec::new(), Vec::new());
    for file in files {
        match crate::record::load_run(&file) {
            Ok((run, _)) => runs.push(run),
            Err(message) => skipped.push(format!("history: skipped {message}")),
        }
    }
    Ok((runs, skipped))
}
