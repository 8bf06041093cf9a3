//! The run's closing summary on the console: how many scenes finished, each scene's answer in
//! one line (the cheapest mode within [`JOD_MARGIN`] of the best, along the path where the scene
//! has one), where the run is, and the commands that come next. It is the last thing `aabench
//! run` prints, so under CI or redirected it is the log's last screen.

use std::path::Path;

use super::choice::{Basis, answer, viewing_conditions};
use crate::record::vocabulary::JOD_MARGIN;
use crate::record::{RunRecord, SceneRecord, Status};

/// The summary's lines, for the run whose record is at `run_json`.
pub fn closing(run: &RunRecord, run_json: &Path) -> Vec<String> {
    let count = |status: Status| run.scenes.iter().filter(|s| s.status == status).count();
    let mut lines = vec![
        String::new(),
        format!(
            "aabench {}: {} scene(s) ok, {} failed, {} interrupted, {} not run",
            run.run_id,
            count(Status::Ok),
            count(Status::Failed),
            count(Status::Interrupted),
            count(Status::NotRun)
        ),
        format!(
            "The cheapest mode within {JOD_MARGIN} JOD of the best, by JOD along the path (else the still),"
        ),
        format!("{}:", viewing_conditions(run)),
    ];
    let width = run.scenes.iter().map(|s| s.name.chars().count()).max().unwrap_or(0);
    lines.extend(run.scenes.iter().map(|scene| format!("  {:<width$}  {}", scene.name, scene_answer(scene))));
    let dir = run_json.parent().unwrap_or(run_json).display();
    lines.extend([
        format!("Run: {}", run_json.display()),
        format!("Next: aabench report {dir}    (writes its index.html)"),
        format!("      aabench compare {dir}   (against the committed baselines)"),
    ]);
    lines
}

/// Why a scene whose own record names no error did not finish ok: its modes that did not, and
/// the first one's error (`2 of 4 modes failed; fxaa: …`).
fn modes_at_fault(scene: &SceneRecord) -> String {
    let at_fault: Vec<_> = scene.modes.iter().filter(|m| m.status != Status::Ok).collect();
    let Some(first) = at_fault.first() else { return "no reason recorded".into() };
    let error = first.error.as_deref().and_then(|e| e.lines().next());
    format!(
        "{} of {} modes {}; {}: {}",
        at_fault.len(),
        scene.modes.len(),
        first.status,
        first.mode,
        error.unwrap_or("no reason recorded")
    )
}

/// `path   msaa-4x 9.660 JOD, 30.2 ms (2.04× deferred-1x1); the best, reference-4x4, 9.700`, or
/// why the scene has no answer.
fn scene_answer(scene: &SceneRecord) -> String {
    if scene.status != Status::Ok {
        let why = scene
            .error
            .as_deref()
            .and_then(|e| e.lines().next())
            .map_or_else(|| modes_at_fault(scene), String::from);
        return format!("{}: {why}", scene.status);
    }
    match Basis::of_scene(scene).into_iter().find_map(|basis| Some((basis, answer(scene, basis)?))) {
        Some((basis, found)) => {
            let on = match basis {
                Basis::Still => "still".to_string(),
                Basis::Path(0) => "path".to_string(),
                Basis::Path(index) => format!("path {}", index + 1),
            };
            format!("{on:<5}  {}", found.describe())
        }
        None => "no mode has a JOD".into(),
    }
}
