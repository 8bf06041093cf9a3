//! `aabench report`: a static, self-contained `index.html` beside a run's run.json. It opens
//! from disk with no server and loads nothing from the network: CSS inline, plots as inline
//! SVG (drawn with plotters), images by relative paths into the run folder.

pub mod html;
pub mod markdown;
pub mod plots;

use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::{Path, PathBuf};

use html::escape;
use plots::{Kind, Point, Series};

use crate::compare::{Check, Outcome, Verdict};
use crate::record::{ModeRecord, RunRecord, SceneRecord};
use crate::truth::TRUTH_ID;

/// Side of the square crop around the largest error, in pixels (smaller images: their side).
const CROP: u32 = 64;
/// How much the zoomed crop enlarges it.
const ZOOM: u32 = 4;

/// Writes `<run_dir>/index.html` (and its crops under `<run_dir>/report/`). `history` holds
/// earlier runs of the same tier, any order; the run itself is added when missing. Returns the
/// page and what it had to leave out, one line each (also said on the page).
pub fn write(
    run_dir: &Path,
    run: &RunRecord,
    verdict: Option<&Verdict>,
    history: &[RunRecord],
) -> Result<(PathBuf, Vec<String>), String> {
    let mut page = String::new();
    let mut left_out = Vec::new();
    head(&mut page, run);
    summary(&mut page, run, verdict);
    adaptive_costs(&mut page, run);
    let history = history_runs(run, history);
    for scene in &run.scenes {
        scene_section(&mut page, run_dir, scene, verdict, &history, &mut left_out)?;
    }
    page.push_str(
        "<footer>Written by <code>aabench report</code>. Times are wall-clock medians of interleaved \
         repetitions with order-statistic intervals; PSNR has peak 1 (add 48.13 dB for the paper's \
         peak-255 convention); the truth is the reference at 8×8 samples per pixel.</footer>\n</body>\n</html>\n",
    );
    let path = run_dir.join("index.html");
    crate::fs::write(&path, page.as_bytes())?;
    Ok((path, left_out))
}

fn head(page: &mut String, run: &RunRecord) {
    let _ = write!(
        page,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
         <title>aabench {}</title>\n<style>\n{}</style>\n</head>\n<body>\n",
        escape(&run.run_id),
        html::STYLE
    );
}

fn summary(page: &mut String, run: &RunRecord, verdict: Option<&Verdict>) {
    let p = &run.platform.info;
    let _ = writeln!(page, "<h1>aabench run <code>{}</code></h1>", escape(&run.run_id));
    let _ = writeln!(
        page,
        "<p class=\"meta\">{} tier · status <b>{}</b> · started {} · finished {}<br>{} · {} · {} ({} cores) · \
         LP_NUM_THREADS={} · {} build<br>platform key <code>{}</code><br>{} repetitions after {} warm-up round(s), \
         {}; extra samples: {}{}</p>",
        run.tier.name(),
        run.status,
        escape(&run.started_at),
        escape(run.finished_at.as_deref().unwrap_or("–")),
        escape(&p.adapter),
        escape(&p.driver_info),
        escape(&p.cpu_model),
        p.cpu_cores,
        escape(p.lp_num_threads.as_deref().unwrap_or("auto")),
        escape(&p.build_profile),
        escape(&run.platform.key),
        run.settings.repetitions,
        run.settings.warmup,
        escape(&run.settings.interleaving),
        escape(&run.settings.extra_samples),
        match (&run.shard, run.merged_from.is_empty()) {
            (Some(shard), _) => format!("<br>shard {} of {}", shard.index, shard.count),
            (None, false) => format!("<br>merged from {}", escape(&run.merged_from.join(", "))),
            (None, true) => String::new(),
        }
    );
    if let Some(verdict) = verdict {
        let class = if verdict.regressed { "bad" } else { "good" };
        let _ = writeln!(
            page,
            "<p class=\"verdict {class}\">Gate: <b>{}</b> — {}{}</p>",
            if verdict.regressed { "regression" } else { "no regression" },
            escape(&crate::compare::outputs::tally(verdict)),
            verdict.notes.iter().map(|n| format!("<br>{}", escape(n))).collect::<String>()
        );
    }
    technique_table(page, run);
    page.push_str("<nav>");
    for scene in &run.scenes {
        let _ = write!(page, "<a href=\"#{0}\">{0}</a> ", escape(&scene.name));
    }
    page.push_str("</nav>\n");
}

fn scene_section(
    page: &mut String,
    run_dir: &Path,
    scene: &SceneRecord,
    verdict: Option<&Verdict>,
    history: &[&RunRecord],
    left_out: &mut Vec<String>,
) -> Result<(), String> {
    let _ = writeln!(page, "<section id=\"{0}\">\n<h2>{0}</h2>", escape(&scene.name));
    let resolution = scene.resolution.map_or("?".into(), |[w, h]| format!("{w}×{h}"));
    let truth = scene.truth.as_ref().map_or("none".into(), |t| match (&t.error, t.cached) {
        (Some(error), _) => format!("failed: {}", escape(error)),
        (None, true) => format!("{} from the cache", t.id),
        (None, false) => format!(
            "{} rendered in {:.1} s in {} tile(s), peak memory {}",
            t.id,
            t.render_s.unwrap_or(0.0),
            t.tiles.unwrap_or(0),
            t.peak_rss_bytes.map_or("?".into(), |b| format!("{:.0} MiB", b as f64 / 1048576.0))
        ),
    });
    let _ = writeln!(
        page,
        "<p class=\"meta\">{resolution} · {} triangles · {} textures · status <b>{}</b>{} · ground truth: {truth}</p>",
        scene.triangles.unwrap_or(0),
        scene.textures.unwrap_or(0),
        scene.status,
        scene.error.as_ref().map_or(String::new(), |e| format!(" — {}", escape(e)))
    );
    let checks: Vec<&Check> =
        verdict.map_or_else(Vec::new, |v| v.checks.iter().filter(|c| c.scene == scene.name).collect());
    mode_table(page, scene, &checks);
    sequence_table(page, scene);
    for metric in ErrorMetric::of_scene(scene) {
        let points = error_points(scene, metric);
        if points.is_empty() {
            if metric == ErrorMetric::Mse {
                page.push_str("<p>No mode has an error against the truth to plot.</p>\n");
            }
            continue;
        }
        let title = format!("{}: {}", scene.name, metric.title());
        let plot = plots::error_against_time(&title, [metric.time_axis(), metric.axis()], &points)?;
        let _ = writeln!(page, "<figure class=\"plot\">{plot}</figure>");
    }
    verdict_table(page, &checks);
    images(page, run_dir, scene, left_out)?;
    flicker_region(page, run_dir, scene, left_out)?;
    history_plots(page, scene, history)?;
    page.push_str("</section>\n");
    Ok(())
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
fn adaptive_costs(page: &mut String, run: &RunRecord) {
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

/// The columns of a scene's mode table, in the HTML report and in Markdown alike.
pub const MODE_COLUMNS: [&str; 13] = [
    "mode",
    "frame ms",
    "interval ms",
    "×1x1",
    "samples %",
    "MSE ×1e-5 vs truth",
    "PSNR vs ref",
    "PSNR vs truth",
    "FLIP vs truth",
    "SSIM vs truth",
    "front",
    "speed-up vs ref",
    "efficiency",
];

/// The suffixes of the adaptive variants beyond the paper, in the order the report shows them.
pub const VARIANTS: [&str; 3] = ["area", "cells", "coverage"];

/// One row of the mode table, unescaped, in the order of [`MODE_COLUMNS`]; `–` where the mode
/// has no such number.
pub fn mode_cells(mode: &ModeRecord) -> [String; 13] {
    let cell = |v: Option<String>| v.unwrap_or_else(|| "–".into());
    let frame = mode.frame_ms.as_ref();
    [
        mode.mode.clone(),
        cell(frame.map(|f| format!("{:.1}", f.median))),
        cell(frame.map(|f| format!("{:.1}–{:.1}", f.ci_low, f.ci_high))),
        cell(mode.ratio_to_deferred.map(|r| format!("{r:.2}"))),
        cell(mode.samples.as_ref().map(|s| format!("{:.1}", s.shaded_percent))),
        cell(mode.vs_ground_truth.as_ref().map(|q| format!("{:.3}", q.mse_e5))),
        decibels(mode.vs_reference.as_ref()),
        decibels(mode.vs_ground_truth.as_ref()),
        cell(mode.vs_ground_truth.as_ref().and_then(|q| q.flip).map(|v| format!("{v:.4}"))),
        cell(mode.vs_ground_truth.as_ref().and_then(|q| q.ssim).map(|v| format!("{v:.4}"))),
        cell(mode.front.as_ref().map(|place| place.describe())),
        cell(mode.adaptive.as_ref().map(|a| format!("{:.2}×", a.speedup))),
        cell(mode.adaptive.as_ref().map(|a| format!("{:.2}", a.efficiency))),
    ]
}

/// The columns of a scene's table along its camera path (`sequence_cells`).
pub const SEQUENCE_COLUMNS: [&str; 9] = [
    "mode",
    "ms per frame along the path",
    "samples %",
    "PSNR along the path",
    "FLIP along the path",
    "instability ×1e-4",
    "change ratio",
    "count changes %",
    "ghosting: disoccluded % · MSE there / elsewhere ×1e-3",
];

/// A mode's row along the scene's camera path, where it has one.
pub fn sequence_cells(mode: &ModeRecord) -> Option<[String; 9]> {
    let sequence = mode.sequence.as_ref()?;
    let cell = |v: Option<String>| v.unwrap_or_else(|| "–".into());
    let psnr = sequence.mean_psnr_db.value();
    let ghosting = sequence.ghosting.as_ref().map(|g| {
        let mse = |v: Option<f64>| v.map_or("–".into(), |v| format!("{:.2}", v * 1e3));
        format!("{:.2} · {} / {}", g.disoccluded * 100.0, mse(g.mse), mse(g.mse_elsewhere))
    });
    Some([
        mode.mode.clone(),
        cell(sequence.frame_ms.as_ref().map(|f| format!("{:.1}", f.median))),
        cell(sequence.shaded_percent.map(|p| format!("{p:.1}"))),
        if psnr.is_finite() { format!("{psnr:.2}") } else { "∞".into() },
        cell(sequence.mean_flip.map(|f| format!("{f:.4}"))),
        format!("{:.3}", sequence.instability * 1e4),
        cell(sequence.change_ratio.map(|r| format!("{r:.2}"))),
        cell(sequence.count_changes.map(|c| format!("{:.2}", c * 100.0))),
        cell(ghosting),
    ])
}

/// The scene's modes along its camera path, where it has one.
fn sequence_table(page: &mut String, scene: &SceneRecord) {
    let Some(sequence) = &scene.sequence else { return };
    let rows: Vec<[String; 9]> = scene.modes.iter().filter_map(sequence_cells).collect();
    let summary = escape(&sequence_summary(sequence));
    let _ = writeln!(page, "<h3>Along the camera path</h3>\n<p class=\"meta\">{summary}</p>");
    if rows.is_empty() {
        return;
    }
    page.push_str("<table><thead><tr>");
    for column in SEQUENCE_COLUMNS {
        let _ = write!(page, "<th>{}</th>", escape(column));
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

/// One line on a scene's sequence: its path, frames and the truth's own change.
pub fn sequence_summary(sequence: &crate::record::SequenceRecord) -> String {
    let truth = sequence.truth_change.map_or("–".into(), |c| format!("{c:.3e}"));
    let mut line = format!(
        "{} path, {} of {} frames of {:.4} s; the truth's own mean squared change per frame {truth}",
        sequence.path, sequence.frames_done, sequence.frames, sequence.time_step_s
    );
    if let Some(error) = &sequence.error {
        let _ = write!(line, "; stopped: {error}");
    }
    line
}

/// A PSNR to two decimals, `∞` for identical images, `–` without a comparison.
pub fn decibels(quality: Option<&crate::metrics::Quality>) -> String {
    quality.map_or("–".into(), |q| {
        let v = q.psnr_db.value();
        if v.is_finite() { format!("{v:.2}") } else { "∞".into() }
    })
}

fn mode_table(page: &mut String, scene: &SceneRecord, checks: &[&Check]) {
    page.push_str("<table><thead><tr>");
    for column in MODE_COLUMNS {
        let _ = write!(page, "<th>{}</th>", escape(column));
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

fn verdict_table(page: &mut String, checks: &[&Check]) {
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

/// The error an error-against-run-time plot draws.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorMetric {
    /// MSE against the truth ×10⁻⁵; its front is run.json's (by PSNR, with intervals).
    Mse,
    /// Mean FLIP against the truth; its front is drawn by medians: no faster mode of the same
    /// stall has less FLIP.
    Flip,
    /// Temporal instability along the scene's camera path (`sequence.rs`); its front is drawn
    /// by medians as FLIP's.
    Instability,
}

impl ErrorMetric {
    pub fn axis(self) -> &'static str {
        match self {
            ErrorMetric::Mse => "MSE against the truth ×1e-5 (log)",
            ErrorMetric::Flip => "mean FLIP against the truth (log)",
            ErrorMetric::Instability => "temporal instability along the camera path (log)",
        }
    }

    /// What a plot of this metric is called, after the scene's name.
    pub fn title(self) -> &'static str {
        match self {
            ErrorMetric::Mse => "error against run time",
            ErrorMetric::Flip => "FLIP against run time",
            ErrorMetric::Instability => "instability against run time",
        }
    }

    /// The x axis: the still's frame time, or for instability the frame time along the path,
    /// where the mode's cost may differ from its still's (a `-stable` mode's counts).
    pub fn time_axis(self) -> &'static str {
        match self {
            ErrorMetric::Instability => "frame time along the path, ms (median and interval; log)",
            ErrorMetric::Mse | ErrorMetric::Flip => "frame time, ms (median and interval; log)",
        }
    }

    /// The frame time a mode is drawn at (see [`Self::time_axis`]); the still's where a run
    /// recorded no times along the path.
    fn time(self, mode: &ModeRecord) -> Option<&crate::stats::Summary> {
        match self {
            ErrorMetric::Instability => {
                mode.sequence.as_ref().and_then(|s| s.frame_ms.as_ref()).or(mode.frame_ms.as_ref())
            }
            ErrorMetric::Mse | ErrorMetric::Flip => mode.frame_ms.as_ref(),
        }
    }

    /// The plots a scene has: instability only where it has a camera path.
    pub fn of_scene(scene: &SceneRecord) -> Vec<ErrorMetric> {
        let mut metrics = vec![ErrorMetric::Mse, ErrorMetric::Flip];
        metrics.extend(scene.sequence.as_ref().map(|_| ErrorMetric::Instability));
        metrics
    }

    fn of(self, mode: &ModeRecord) -> Option<f64> {
        match self {
            ErrorMetric::Mse => Some(mode.vs_ground_truth.as_ref()?.mse_e5),
            ErrorMetric::Flip => mode.vs_ground_truth.as_ref()?.flip,
            ErrorMetric::Instability => Some(mode.sequence.as_ref()?.instability),
        }
    }
}

/// The modes with an error against the truth (in `metric`) and a frame time.
pub fn error_points(scene: &SceneRecord, metric: ErrorMetric) -> Vec<Point> {
    let mut points: Vec<Point> = scene
        .modes
        .iter()
        .filter_map(|mode| {
            let frame = metric.time(mode)?;
            let error = metric.of(mode)?;
            let kind = match mode.mode.split('-').next()? {
                "deferred" => Kind::Deferred,
                "fxaa" => Kind::Fxaa,
                "smaa" => Kind::Smaa,
                "taa" => Kind::Taa,
                "msaa" => Kind::Msaa,
                "reference" => Kind::Reference,
                _ if mode.mode.split('-').any(|part| VARIANTS.contains(&part) || part == "stable") => {
                    Kind::Variant
                }
                _ => Kind::Adaptive,
            };
            (error > 0.0).then(|| Point {
                label: short_label(&mode.mode),
                kind,
                stalled: mode.stalled,
                time: frame.median,
                time_low: frame.ci_low,
                time_high: frame.ci_high,
                error,
                on_front: mode.front.as_ref().is_some_and(|place| place.on_front),
            })
        })
        .collect();
    if metric != ErrorMetric::Mse {
        let dominated: Vec<bool> = points
            .iter()
            .map(|p| points.iter().any(|q| q.stalled == p.stalled && q.time < p.time && q.error < p.error))
            .collect();
        for (point, dominated) in points.iter_mut().zip(dominated) {
            point.on_front = !dominated;
        }
    }
    points
}

/// Which technique for this scene: for each PSNR against the truth that an unstalled mode on
/// the scene's front reaches, lowest first, the fastest unstalled mode (by median) that
/// reaches it, once per mode.
pub fn fastest_by_level(scene: &SceneRecord) -> Vec<(f64, &ModeRecord)> {
    let measured: Vec<(f64, f64, &ModeRecord)> = scene
        .modes
        .iter()
        .filter(|m| !m.stalled)
        .filter_map(|m| Some((m.vs_ground_truth.as_ref()?.psnr_db.value(), m.frame_ms.as_ref()?.median, m)))
        .collect();
    let mut levels: Vec<f64> = measured
        .iter()
        .filter(|(_, _, m)| m.front.as_ref().is_some_and(|place| place.on_front))
        .map(|&(psnr, _, _)| psnr)
        .collect();
    levels.sort_by(f64::total_cmp);
    let mut rows: Vec<(f64, &ModeRecord)> = Vec::new();
    for level in levels {
        let fastest =
            measured.iter().filter(|(psnr, _, _)| *psnr >= level).min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some(&(_, _, mode)) = fastest
            && rows.last().is_none_or(|(_, last)| last.mode != mode.mode)
        {
            rows.push((level, mode));
        }
    }
    rows
}

/// `fastest_by_level` of every scene as one table: a row per scene, its levels in a cell.
fn technique_table(page: &mut String, run: &RunRecord) {
    let rows: Vec<(&SceneRecord, Vec<(f64, &ModeRecord)>)> =
        run.scenes.iter().map(|s| (s, fastest_by_level(s))).filter(|(_, r)| !r.is_empty()).collect();
    if rows.is_empty() {
        return;
    }
    page.push_str(
        "<h2>Which technique for this scene</h2>\n<p>For each PSNR against the truth that a mode on the \
         scene's front reaches, the fastest unstalled mode that reaches it (frame ms, FLIP).</p>\n\
         <table><thead><tr><th>scene</th><th>at least … dB: the fastest mode</th></tr></thead><tbody>\n",
    );
    for (scene, levels) in rows {
        let cells: Vec<String> = levels.iter().map(|(level, mode)| technique_cell(*level, mode)).collect();
        let _ = writeln!(
            page,
            "<tr><td>{}</td><td>{}</td></tr>",
            escape(&scene.name),
            escape(&cells.join(" · "))
        );
    }
    page.push_str("</tbody></table>\n");
}

/// `36.00 dB: reference-2x2 (280.7 ms, FLIP 0.0196)`.
pub fn technique_cell(level: f64, mode: &ModeRecord) -> String {
    let level = if level.is_finite() { format!("{level:.2} dB") } else { "∞ dB".into() };
    let ms = mode.frame_ms.as_ref().map_or(0.0, |f| f.median);
    let flip = mode
        .vs_ground_truth
        .as_ref()
        .and_then(|q| q.flip)
        .map_or(String::new(), |f| format!(", FLIP {f:.4}"));
    format!("{level}: {} ({ms:.1} ms{flip})", mode.mode)
}

/// `adaptive-3x3-geometry-stalled` → `ada 3×3 geometry`: the series says whether it is stalled.
fn short_label(mode: &str) -> String {
    let mut parts: Vec<String> = mode.split('-').filter(|p| *p != "stalled").map(str::to_owned).collect();
    if let Some(first) = parts.first_mut() {
        *first = match first.as_str() {
            "deferred" => "1×1".into(),
            "reference" => "ref".into(),
            "adaptive" => "ada".into(),
            other => other.into(),
        };
    }
    if parts.first().is_some_and(|p| p == "1×1") {
        return "1×1".into();
    }
    parts.iter().map(|p| p.replace('x', "×")).collect::<Vec<_>>().join(" ")
}

/// A mode's FLIP error map against the truth, where it has one.
fn flip_figure(page: &mut String, mode: Option<&ModeRecord>) {
    if let Some((mode, image)) = mode.and_then(|m| Some((m, m.images.flip.as_deref()?))) {
        figure(page, image, &format!("{}: FLIP against the truth (0 black to 1 yellow)", mode.mode));
    }
}

/// The truth, deferred-1x1, and per M: reference, adaptive (and its `-area` and `-cells`
/// variants where the run has them), their differences and the sample counts, then 1:1 crops
/// around adaptive's largest error against the truth.
fn images(
    page: &mut String,
    run_dir: &Path,
    scene: &SceneRecord,
    left_out: &mut Vec<String>,
) -> Result<(), String> {
    page.push_str("<h3>Images</h3>\n<div class=\"row\">");
    if let Some(image) = scene.truth.as_ref().and_then(|t| t.image.as_deref()) {
        figure(page, image, TRUTH_ID);
    }
    for id in ["deferred-1x1", "fxaa", "smaa", "taa"] {
        if let Some(image) = scene.mode(id).and_then(|m| m.images.display.as_deref()) {
            figure(page, image, id);
        }
    }
    for (id, name) in [("fxaa", "FXAA"), ("smaa", "SMAA"), ("taa", "TAA")] {
        if let Some(image) = scene.mode(id).and_then(|m| m.images.difference.as_deref()) {
            figure(
                page,
                image,
                &format!("|{id} − deferred-1x1|: the pixels {name} changed (32 steps full scale)"),
            );
        }
    }
    for id in ["deferred-1x1", "fxaa", "smaa", "taa"] {
        flip_figure(page, scene.mode(id));
    }
    page.push_str("</div>\n");
    for m in 2..=4 {
        // The unstalled mode where the run has it: stalling changes the time, not the image.
        let pick = |id: String| scene.mode(&id).or_else(|| scene.mode(&format!("{id}-stalled")));
        let reference = pick(format!("reference-{m}x{m}"));
        let adaptive = pick(format!("adaptive-{m}x{m}"));
        let area = pick(format!("adaptive-{m}x{m}-area"));
        let cells = pick(format!("adaptive-{m}x{m}-cells"));
        let coverage = pick(format!("adaptive-{m}x{m}-coverage"));
        // 4× MSAA shades as many samples as the 2×2 grid and is compared with its reference.
        let msaa = if m == 2 { pick("msaa-4x".into()) } else { None };
        let adaptives: Vec<&ModeRecord> = [adaptive, area, cells, coverage].into_iter().flatten().collect();
        // The modes compared with the reference: the adaptive ones, then MSAA.
        let compared: Vec<&ModeRecord> = adaptives.iter().copied().chain(msaa).collect();
        if reference.is_none() && compared.is_empty() {
            continue;
        }
        page.push_str("<div class=\"row\">");
        for mode in reference.iter().chain(&compared) {
            if let Some(image) = &mode.images.display {
                figure(page, image, &mode.mode);
            }
        }
        for mode in &compared {
            if let Some(image) = &mode.images.difference {
                figure(page, image, &format!("|{} − reference| (32 steps full scale)", mode.mode));
            }
        }
        for &mode in reference.iter().chain(&compared) {
            flip_figure(page, Some(mode));
        }
        // The area variant takes the paper's samples: one heatmap serves both; cells,
        // coverage and MSAA take their own.
        for mode in [adaptive.or(area), cells, coverage, msaa].into_iter().flatten() {
            if let Some(image) = &mode.images.samples {
                figure(
                    page,
                    image,
                    &format!("{}: samples per pixel, 1 (dark) to {} (red)", mode.mode, m * m),
                );
            }
        }
        page.push_str("</div>\n");
        // The crops sit where adaptive differs most from the truth, so only a run with an
        // adaptive mode at this M has them.
        if let Some(&worst) = adaptives.first() {
            let shown: Vec<&ModeRecord> = reference.iter().copied().chain(compared.iter().copied()).collect();
            crops(page, run_dir, scene, m, &shown, worst, left_out)?;
        }
    }
    Ok(())
}

fn figure(page: &mut String, src: &str, caption: &str) {
    let _ = write!(
        page,
        "<figure><img src=\"{}\" alt=\"{1}\" loading=\"lazy\"><figcaption>{1}</figcaption></figure>",
        escape(src),
        escape(caption)
    );
}

/// 1:1 and zoomed crops of the truth and `modes` at the window where `worst` (one of them) is
/// furthest from the truth.
fn crops(
    page: &mut String,
    run_dir: &Path,
    scene: &SceneRecord,
    m: u32,
    modes: &[&ModeRecord],
    worst: &ModeRecord,
    left_out: &mut Vec<String>,
) -> Result<(), String> {
    let Some(truth_file) = scene.truth.as_ref().and_then(|t| t.image.clone()) else { return Ok(()) };
    let Some(worst_file) = worst.images.display.clone() else { return Ok(()) };
    let open = |relative: &str| open_rgba(run_dir, relative);
    let (truth, worst_image) = (open(&truth_file)?, open(&worst_file)?);
    let sources: Vec<(String, String)> = std::iter::once((TRUTH_ID.to_string(), truth_file))
        .chain(modes.iter().filter_map(|mode| Some((mode.mode.clone(), mode.images.display.clone()?))))
        .collect();
    let mut opened = Vec::new();
    for (name, file) in sources {
        let image = open(&file)?;
        if image.dimensions() != truth.dimensions() {
            // The files were replaced after the run: the crops would compare different frames.
            let (w, h) = image.dimensions();
            let reason = format!(
                "{}: no crops at {m}×{m}: {file} is {w}×{h}, the truth {}×{} (an image replaced after the run?)",
                scene.name,
                truth.width(),
                truth.height()
            );
            let _ = writeln!(page, "<p class=\"meta\">{}</p>", escape(&reason));
            left_out.push(reason);
            return Ok(());
        }
        opened.push((name, image));
    }
    let side = CROP.min(truth.width()).min(truth.height());
    let (x, y) = worst_window(&truth, &worst_image, side);
    let folder = Path::new("report").join(&scene.name);
    std::fs::create_dir_all(run_dir.join(&folder))
        .map_err(|e| format!("{}: {e}", run_dir.join(&folder).display()))?;
    let _ = write!(
        page,
        "<p class=\"meta\">Crops at ({x}, {y}), {side}×{side}: where {} differs most from the truth (1:1, then ×{ZOOM}).</p>\n<div class=\"row crops\">",
        escape(&worst.mode)
    );
    for (name, image) in opened {
        let crop = image::imageops::crop_imm(&image, x, y, side, side).to_image();
        let relative = folder.join(format!("crop-{m}x{m}-{name}.png"));
        crate::images::write_png(&run_dir.join(&relative), side, side, crop.as_raw())
            .map_err(|e| format!("{e:#}"))?;
        let src = relative.to_string_lossy().replace('\\', "/");
        let _ = write!(
            page,
            "<figure><img src=\"{0}\" width=\"{side}\" height=\"{side}\" alt=\"{1} crop\">\
             <img class=\"zoom\" src=\"{0}\" width=\"{2}\" height=\"{2}\" alt=\"{1} crop ×{ZOOM}\"><figcaption>{1}</figcaption></figure>",
            escape(&src),
            escape(&name),
            side * ZOOM
        );
    }
    page.push_str("</div>\n");
    Ok(())
}

/// The sequence's worst-flickering region: every animated mode's animation beside the truth's,
/// then a strip of its consecutive frames per mode (written under `report/<scene>/`).
fn flicker_region(
    page: &mut String,
    run_dir: &Path,
    scene: &SceneRecord,
    left_out: &mut Vec<String>,
) -> Result<(), String> {
    let Some(sequence) = &scene.sequence else { return Ok(()) };
    let Some(region) = &sequence.region else {
        if let Some(error) = &sequence.region_error {
            let _ = writeln!(page, "<p class=\"meta\">No flicker region: {}</p>", escape(error));
        }
        return Ok(());
    };
    let streams: Vec<(&str, &str)> = std::iter::once(TRUTH_ID)
        .chain(scene.modes.iter().map(|m| m.mode.as_str()))
        .filter_map(|id| {
            let stream = if id == TRUTH_ID { "truth" } else { id };
            Some((id, region.animations.get(stream)?.as_str()))
        })
        .collect();
    let (side, first, count) = (region.side, region.strip_first, region.strip_frames);
    let _ = write!(
        page,
        "<h3>Where it flickers most</h3>\n<p class=\"meta\">The {side}×{side} square at ({}, {}) where the \
         modes' error changes most from frame to frame, ×{ZOOM}: every frame of the path, forwards then \
         back, at its time step ({:.1} ms a frame). Below, frames {first}–{} side by side.</p>\n<div class=\"row crops\">",
        region.x,
        region.y,
        sequence.time_step_s * 1e3,
        first + count - 1
    );
    for (id, animation) in &streams {
        let _ = write!(
            page,
            "<figure><img class=\"zoom\" src=\"{}\" width=\"{1}\" height=\"{1}\" alt=\"{2} animated\"><figcaption>{2}</figcaption></figure>",
            escape(animation),
            side * ZOOM,
            escape(id)
        );
    }
    page.push_str("</div>\n<table class=\"strips\"><tbody>\n");
    let folder = Path::new("report").join(&scene.name);
    std::fs::create_dir_all(run_dir.join(&folder))
        .map_err(|e| format!("{}: {e}", run_dir.join(&folder).display()))?;
    for (id, animation) in streams {
        let frames = match crate::images::read_apng(&run_dir.join(animation)) {
            Ok(frames) if frames.len() >= (first + count) as usize => frames,
            Ok(frames) => {
                let reason = format!(
                    "{}: {animation} has {} frames, the strip needs {}",
                    scene.name,
                    frames.len(),
                    first + count
                );
                left_out.push(reason.clone());
                let _ = writeln!(page, "<tr><td>{}</td><td>{}</td></tr>", escape(id), escape(&reason));
                continue;
            }
            Err(error) => {
                let reason = format!("{}: {error:#}", scene.name);
                left_out.push(reason.clone());
                let _ = writeln!(page, "<tr><td>{}</td><td>{}</td></tr>", escape(id), escape(&reason));
                continue;
            }
        };
        let strip = side_by_side(&frames[first as usize..(first + count) as usize], 1, 1);
        let relative = folder.join(format!("strip-{id}.png"));
        crate::images::write_png(&run_dir.join(&relative), strip.width(), strip.height(), strip.as_raw())
            .map_err(|e| format!("{e:#}"))?;
        let _ = writeln!(
            page,
            "<tr><td>{}</td><td><img class=\"zoom\" src=\"{}\" width=\"{}\" height=\"{}\" alt=\"{0} frames {first}–{}\"></td></tr>",
            escape(id),
            escape(&relative.to_string_lossy().replace('\\', "/")),
            strip.width() * 2,
            strip.height() * 2,
            first + count - 1
        );
    }
    page.push_str("</tbody></table>\n");
    Ok(())
}

/// Images of one size side by side, each enlarged `zoom` times (nearest neighbour), `gap`
/// white pixels apart.
pub fn side_by_side(panels: &[image::RgbaImage], zoom: u32, gap: u32) -> image::RgbaImage {
    let (width, height) = panels[0].dimensions();
    let (width, height) = (width * zoom, height * zoom);
    let count = panels.len() as u32;
    let mut out = image::RgbaImage::from_pixel(count * (width + gap) - gap, height, image::Rgba([255; 4]));
    for (i, panel) in (0..).zip(panels) {
        let big = image::imageops::resize(panel, width, height, image::imageops::FilterType::Nearest);
        image::imageops::replace(&mut out, &big, i64::from(i * (width + gap)), 0);
    }
    out
}

/// Opens an image of a run by its path relative to the run's folder, as RGBA8.
pub fn open_rgba(run_dir: &Path, relative: &str) -> Result<image::RgbaImage, String> {
    image::open(run_dir.join(relative))
        .map(|i| i.to_rgba8())
        .map_err(|e| format!("{}: {e}", run_dir.join(relative).display()))
}

/// The top-left corner of the `side`×`side` window with the largest squared difference
/// between two images of one size.
pub fn worst_window(a: &image::RgbaImage, b: &image::RgbaImage, side: u32) -> (u32, u32) {
    let errors: Vec<f64> = a
        .pixels()
        .zip(b.pixels())
        .map(|(p, q)| (0..3).map(|c| (f64::from(p[c]) - f64::from(q[c])).powi(2)).sum())
        .collect();
    crate::images::largest_window(&errors, a.width(), a.height(), side)
}

/// The history to plot: runs of the run's tier, oldest first, the run itself included once.
fn history_runs<'a>(run: &'a RunRecord, history: &'a [RunRecord]) -> Vec<&'a RunRecord> {
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

fn history_plots(page: &mut String, scene: &SceneRecord, history: &[&RunRecord]) -> Result<(), String> {
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
    let adaptive: Vec<String> =
        (2..=4).flat_map(|m| [format!("adaptive-{m}x{m}"), format!("adaptive-{m}x{m}-stalled")]).collect();
    // Quality does not depend on stalling; the variants' time is charted nowhere here (the
    // error-against-time plot holds it).
    let quality: Vec<String> = (2..=4)
        .flat_map(|m| {
            std::iter::once(String::new())
                .chain(VARIANTS.map(|variant| format!("-{variant}")))
                .map(move |variant| format!("adaptive-{m}x{m}{variant}"))
        })
        .collect();
    let timed: Vec<String> =
        ["deferred-1x1", "reference-4x4", "adaptive-4x4", "reference-4x4-stalled", "adaptive-4x4-stalled"]
            .map(String::from)
            .to_vec();
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
