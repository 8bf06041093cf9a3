//! The scene's results as the terminal shows them: a small table per scene.

use crate::metrics::Quality;
use crate::progress::Progress;
use crate::record::SceneRecord;
use crate::truth::TruthRecord;

/// Prints a scene's results as a small table.
pub(super) fn report_scene(progress: &Progress, scene: &SceneRecord) {
    let resolution = scene.resolution.map_or(String::new(), |[w, h]| format!(" {w}×{h}"));
    match &scene.error {
        Some(error) if scene.modes.is_empty() => {
            progress.line(&format!("[{}] FAILED: {error}", scene.name));
            return;
        }
        _ => progress.line(&format!(
            "[{}]{resolution} {} triangles, ground truth {}",
            scene.name,
            scene.triangles.unwrap_or(0),
            scene.truth.as_ref().map_or("none".into(), truth_summary)
        )),
    }
    progress.line(&format!(
        "  {:<28} {:>10} {:>21} {:>8} {:>9} {:>9} {:>10} {:>10}  {}",
        "mode",
        "median ms",
        "interval ms",
        "×1x1",
        "samples%",
        "PSNR ref",
        "PSNR truth",
        "FLIP truth",
        "front"
    ));
    let db = |q: &Option<Quality>| q.as_ref().map_or("-".into(), |q| format!("{:.2}", q.psnr_db.value()));
    for mode in &scene.modes {
        let Some(frame) = &mode.frame_ms else {
            progress.line(&format!("  {:<28} {}", mode.mode, mode.error.as_deref().unwrap_or("no frames")));
            continue;
        };
        progress.line(&format!(
            "  {:<28} {:>10.1} {:>21} {:>8} {:>9} {:>9} {:>10} {:>10}  {}{}",
            mode.mode,
            frame.median,
            format!("[{:.1}, {:.1}]", frame.ci_low, frame.ci_high),
            mode.ratio_to_deferred.map_or("-".into(), |r| format!("{r:.2}")),
            mode.samples.as_ref().map_or("-".into(), |s| format!("{:.1}", s.shaded_percent)),
            db(&mode.vs_reference),
            db(&mode.vs_ground_truth),
            mode.vs_ground_truth.as_ref().and_then(|q| q.flip).map_or("-".into(), |f| format!("{f:.4}")),
            mode.front.as_ref().map_or("-".into(), |place| place.describe()),
            mode.error.as_ref().map_or(String::new(), |e| format!("  ({e})")),
        ));
    }
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
