//! The report's tables: each scene's modes (their still, and along the camera path), the gate's
//! checks, and the cost of the adaptive modes. The Markdown report takes its columns and cells
//! from here too.

use std::fmt::Write;

use super::html::escape;
use crate::compare::{Check, Outcome};
use crate::record::vocabulary::{self, Metric, Table};
use crate::record::{ModeRecord, RunRecord, SceneRecord, SequenceRecord};

/// The columns of a scene's mode table, in the HTML report and in Markdown alike: the mode and
/// its time, then the metrics with a column in the still's table, then its place on each front
/// of the still and, for adaptive modes, its cost against the reference.
pub fn mode_columns() -> Vec<String> {
    let metrics = vocabulary::columns(Table::Still).map(|(_, column)| column.header.to_string());
    let fronts = vocabulary::fronts(Table::Still).map(Metric::front_header);
    ["mode", "frame ms", "interval ms", "×1x1"]
        .map(String::from)
        .into_iter()
        .chain(metrics)
        .chain(fronts)
        .chain(["speed-up vs ref", "efficiency"].map(String::from))
        .collect()
}

/// A mode's place on the front of `metric` (along the sequence `index` for a path's) in one
/// phrase, `–` where it has none.
fn front_cell(mode: &ModeRecord, metric: &Metric, index: usize) -> String {
    mode.front(&metric.key(index)).map_or_else(|| "–".into(), |place| place.describe(metric.unit()))
}

/// One row of the mode table, unescaped, in the order of [`mode_columns`]; `–` where the mode
/// has no such number.
pub fn mode_cells(mode: &ModeRecord) -> Vec<String> {
    let cell = |v: Option<String>| v.unwrap_or_else(|| "–".into());
    let frame = mode.frame_ms.as_ref();
    let metrics =
        vocabulary::columns(Table::Still).map(|(metric, column)| vocabulary::cell(metric, column, mode, 0));
    [
        mode.mode.clone(),
        cell(frame.map(|f| format!("{:.1}", f.median))),
        cell(frame.map(|f| format!("{:.1}–{:.1}", f.ci_low, f.ci_high))),
        cell(mode.ratio_to_deferred.map(|r| format!("{r:.2}"))),
    ]
    .into_iter()
    .chain(metrics)
    .chain(vocabulary::fronts(Table::Still).map(|metric| front_cell(mode, metric, 0)))
    .chain([
        cell(mode.adaptive.as_ref().map(|a| format!("{:.2}×", a.speedup))),
        cell(mode.adaptive.as_ref().map(|a| format!("{:.2}", a.efficiency))),
    ])
    .collect()
}

/// The columns of a scene's table along its camera path ([`sequence_cells`]): the mode and its
/// time per frame, the metrics with a column in the path's table (what lag costs among them),
/// and its place on each front of the path.
pub fn sequence_columns() -> Vec<String> {
    let metrics = vocabulary::columns(Table::Path).map(|(_, column)| column.header.to_string());
    ["mode", "ms per frame along the path"]
        .map(String::from)
        .into_iter()
        .chain(metrics)
        .chain(vocabulary::fronts(Table::Path).map(Metric::front_header))
        .collect()
}

/// A mode's row along the scene's sequence `index`, where it has one.
pub fn sequence_cells(mode: &ModeRecord, index: usize) -> Option<Vec<String>> {
    let sequence = mode.sequence_at(index)?;
    let cell = |v: Option<String>| v.unwrap_or_else(|| "–".into());
    let metrics = vocabulary::columns(Table::Path)
        .map(|(metric, column)| vocabulary::cell(metric, column, mode, index));
    // A stalled mode that took its twin's frames has no time of its own along the path.
    let frame = match (&sequence.frame_ms, &sequence.frames_of) {
        (Some(frame), _) => Some(format!("{:.1}", frame.median)),
        (None, twin) => twin.as_ref().map(|twin| format!("{twin}'s frames")),
    };
    let fronts = vocabulary::fronts(Table::Path).map(|metric| front_cell(mode, metric, index));
    Some([mode.mode.clone(), cell(frame)].into_iter().chain(metrics).chain(fronts).collect())
}

/// The scene's modes along its sequence `index`.
pub(super) fn sequence_table(page: &mut String, scene: &SceneRecord, index: usize) {
    let Some(sequence) = scene.sequences.get(index) else { return };
    let rows: Vec<Vec<String>> = scene.modes.iter().filter_map(|mode| sequence_cells(mode, index)).collect();
    let summary = escape(&sequence_summary(sequence));
    let speed = escape(&sequence.speed());
    let _ = writeln!(page, "<h3>Along the camera path: {speed}</h3>\n<p class=\"meta\">{summary}</p>");
    if rows.is_empty() {
        return;
    }
    page.push_str("<table><thead><tr>");
    for column in sequence_columns() {
        let _ = write!(page, "<th>{}</th>", escape(&column));
    }
    page.push_str("</tr></thead><tbody>\n");
    for row in rows {
        page.push_str("<tr>");
        for cell in row {
            let _ = write!(page, "<td>{}</td>", escape(&cell));
        }
        page.push_str("</tr>\n");
    }
    page.push_str("</tbody></table>\n");
}

/// One line on a scene's sequence: its path, frames and warm-up, and the truth's own change
/// along its motion, the flicker of a blank image.
pub fn sequence_summary(sequence: &SequenceRecord) -> String {
    let blank = sequence.blank_flicker.map_or("–".into(), |c| format!("{:.3}", c * 1e4));
    let mut line = format!(
        "{} path at {}, {} of {} frames of {:.4} s after {}. Flicker is the mean squared change of \
         a mode's error along the truth's motion; a blank image (its error the truth's own change) \
         scores {blank} ×1e-4 here",
        sequence.path,
        sequence.speed(),
        sequence.frames_done,
        sequence.frames,
        sequence.time_step_s,
        warmup_summary(sequence)
    );
    if let Some(error) = &sequence.error {
        let _ = write!(line, "; stopped: {error}");
    }
    line
}

/// What came before the measured frames: `16 warm-up frames along the path (the window starts
/// 0.267 s into the animation so that they move)`, and where some held still, how many.
fn warmup_summary(sequence: &SequenceRecord) -> String {
    let mut text = format!("{} warm-up frames along the path", sequence.warmup_frames);
    if sequence.lead_s > 0.0 {
        let _ =
            write!(text, " (the window starts {:.3} s later than asked, so that they move)", sequence.lead_s);
    }
    if sequence.warmup_still_frames > 0 {
        let _ = write!(
            text,
            ", {} of which show the frame before's view (the path and the animation hold still there: a \
             history built on them has seen a still scene)",
            sequence.warmup_still_frames
        );
    }
    text
}

/// A PSNR to two decimals, `∞` for identical images, `–` without a comparison.
pub fn decibels(quality: Option<&crate::measure::pixels::Quality>) -> String {
    quality.map_or("–".into(), |q| vocabulary::decibels(q.psnr_db.value()))
}

pub(super) fn mode_table(page: &mut String, scene: &SceneRecord, checks: &[&Check]) {
    page.push_str("<table><thead><tr>");
    for column in mode_columns() {
        let _ = write!(page, "<th>{}</th>", escape(&column));
    }
    if !checks.is_empty() {
        page.push_str("<th>gate</th>");
    }
    page.push_str("</tr></thead><tbody>\n");
    for mode in &scene.modes {
        page.push_str("<tr>");
        for cell in mode_cells(mode) {
            let _ = write!(page, "<td>{}</td>", escape(&cell));
        }
        if !checks.is_empty() {
            match mode_outcome(checks, &mode.mode) {
                Some((outcome, details)) => {
                    let _ = write!(
                        page,
                        "<td class=\"{0}\" title=\"{1}\">{0}</td>",
                        outcome.name(),
                        escape(&details)
                    );
                }
                None => page.push_str("<td>–</td>"),
            }
        }
        if let Some(error) = &mode.error {
            let _ = write!(page, "<td class=\"failed\">{}</td>", escape(error));
        }
        page.push_str("</tr>\n");
    }
    page.push_str("</tbody></table>\n");
}

pub(super) fn verdict_table(page: &mut String, checks: &[&Check]) {
    let notable: Vec<&&Check> = checks.iter().filter(|c| c.outcome != Outcome::Unchanged).collect();
    if notable.is_empty() {
        return;
    }
    if notable.iter().all(|c| c.outcome == Outcome::New && c.metric == "status")
        && notable.len() == checks.len()
    {
        page.push_str("<p class=\"meta\">Gate: no baseline for this scene; every mode is new.</p>\n");
        return;
    }
    page.push_str("<h3>Gate</h3>\n<table><thead><tr><th>mode</th><th>metric</th><th>outcome</th><th>detail</th></tr></thead><tbody>\n");
    let mut sorted = notable;
    sorted.sort_by_key(|c| c.outcome);
    for check in sorted {
        let _ = writeln!(
            page,
            "<tr><td>{}</td><td>{}</td><td class=\"{2}\">{2}</td><td>{3}</td></tr>",
            escape(&check.mode),
            escape(&check.metric),
            check.outcome.name(),
            escape(&check.detail)
        );
    }
    page.push_str("</tbody></table>\n");
}

/// The worst outcome among a mode's checks, with every non-unchanged detail as a tooltip.
fn mode_outcome(checks: &[&Check], mode: &str) -> Option<(Outcome, String)> {
    let of_mode: Vec<&&Check> = checks.iter().filter(|c| c.mode == mode).collect();
    let worst = of_mode.iter().map(|c| c.outcome).min()?;
    let details: Vec<String> = of_mode
        .iter()
        .filter(|c| c.outcome != Outcome::Unchanged)
        .map(|c| format!("{} {}: {}", c.outcome.name(), c.metric, c.detail))
        .collect();
    Some((worst, details.join("\n")))
}

/// The headline of the adaptive modes: how far each is from the fastest it could be. Its
/// limit pays for the G-buffer, S and evaluation and shades the extra samples at the
/// reference's cost per sample; what it loses beyond that is dearer extra samples, the list
/// (evaluate + compact) and the gather.
pub(super) fn adaptive_costs(page: &mut String, run: &RunRecord) {
    let rows: Vec<(&SceneRecord, &crate::record::ModeRecord, &crate::record::AdaptiveCost)> = run
        .scenes
        .iter()
        .flat_map(|scene| scene.modes.iter().filter_map(move |m| Some((scene, m, m.adaptive.as_ref()?))))
        .collect();
    if rows.is_empty() {
        return;
    }
    page.push_str(
        "<section id=\"adaptive-cost\">\n<h2>Adaptive cost per sample</h2>\n<p class=\"meta\">Extra sample: \
         <code>shade_extra</code> per sample shaded after S, against the same-M reference's <code>shade</code> \
         per sample (1.00× is as cheap). Evaluate (with compact) and gather as shares of the frame. Limit: shadow \
         + G-buffer + S + evaluate + the extra samples at the reference's cost; efficiency = limit / frame.</p>\n\
         <table><thead><tr><th>scene</th><th>mode</th><th>speed-up vs ref</th><th>samples %</th>\
         <th>extra sample</th><th>ns / ref ns</th><th>evaluate</th><th>gather</th><th>limit ms</th>\
         <th>frame ms</th><th>efficiency</th></tr></thead><tbody>\n",
    );
    for (scene, mode, cost) in rows {
        let samples = cost.samples.as_ref();
        let cell = |v: Option<String>| v.unwrap_or_else(|| "–".into());
        let _ = writeln!(
            page,
            "<tr><td><a href=\"#{0}\">{0}</a></td><td>{1}</td><td>{2:.2}×</td><td>{3}</td><td>{4}</td><td>{5}</td>\
             <td>{6}</td><td>{7}</td><td>{8:.1}</td><td>{9}</td><td>{10:.2}</td></tr>",
            escape(&scene.name),
            escape(&mode.mode),
            cost.speedup,
            cell(mode.samples.as_ref().map(|s| format!("{:.1}", s.shaded_percent))),
            cell(samples.map(|s| format!("{:.2}×", s.extra_sample_cost))),
            cell(samples.map(|s| format!("{:.1} / {:.1}", s.extra_sample_ns, s.reference_sample_ns))),
            cell(samples.map(|s| format!("{:.0}%", 100.0 * s.evaluate_share))),
            cell(samples.map(|s| format!("{:.0}%", 100.0 * s.gather_share))),
            cost.limit_ms,
            cell(mode.frame_ms.as_ref().map(|f| format!("{:.1}", f.median))),
            cost.efficiency,
        );
    }
    page.push_str("</tbody></table>\n</section>\n");
}
