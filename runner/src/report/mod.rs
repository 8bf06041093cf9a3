//! `aabench report`: a static, self-contained `index.html` beside a run's run.json. It opens
//! from disk with no server and loads nothing from the network: CSS inline, plots as inline
//! SVG (drawn with plotters), images by relative paths into the run folder. The page is built
//! here from its tables (`tables.rs`, and which technique for each scene in `choice.rs`), plots
//! (`points.rs`, `plots.rs`), images (`images.rs`), what a viewer sees against squared error
//! (`agreement.rs`) and history (`history.rs`); `markdown.rs` writes the same tables as Markdown.

mod agreement;
mod choice;
mod history;
pub mod html;
mod images;
pub mod markdown;
pub mod plots;
mod points;
mod summary;
mod tables;

pub use choice::{Answer, Basis, Row, answer, ranking, technique_cell};
pub use history::load_history;
pub use images::{open_rgba, side_by_side, worst_window};
pub use points::{ErrorPlot, error_points};
pub use summary::closing;
pub use tables::{decibels, mode_cells, mode_columns, sequence_cells, sequence_columns, sequence_summary};

use std::fmt::Write;
use std::path::{Path, PathBuf};

use aabench_renderer::{Counts, Metrics, Mode, Reconstruction, Technique};
use html::escape;

use crate::compare::{Check, Verdict};
use crate::record::{RunRecord, SceneRecord};

/// Side of the square crop around the largest error, in pixels (smaller images: their side).
const CROP: u32 = 64;
/// How much the zoomed crop enlarges it.
const ZOOM: u32 = 4;

/// The paper's adaptive supersampling: both metrics, samples alike, counts per frame.
const PAPER: Technique = Technique::PAPER;

/// The paper's adaptive mode at `m` and its reconstructions beyond the paper, unstalled:
/// `adaptive-MxM`, `-area`, `-cells`, `-coverage`.
fn reconstructions(m: u32) -> [Mode; 4] {
    [Reconstruction::Equal, Reconstruction::Area, Reconstruction::Cells, Reconstruction::Coverage].map(
        |reconstruction| {
            Mode::new(Technique::Adaptive(Metrics::Both, reconstruction, Counts::PerFrame), m, false)
        },
    )
}

/// The techniques that engineers ship instead of supersampling, each unstalled at its size:
/// deferred-1x1, fxaa, smaa, msaa-4x, taa. A technique added to [`Technique::COMPARED`] joins
/// every table and figure that shows them.
fn competitors() -> Vec<Mode> {
    Technique::COMPARED
        .into_iter()
        .filter(|t| *t != Technique::Reference)
        .map(|t| Mode::new(t, *t.sizes().start(), false))
        .collect()
}

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
    let (run, mut left_out) = images::without_missing_images(run_dir, run);
    let run = &run;
    head(&mut page, run);
    summary(&mut page, run, verdict);
    tables::adaptive_costs(&mut page, run);
    let history = history::history_runs(run, history);
    for scene in &run.scenes {
        scene_section(&mut page, run_dir, scene, verdict, &history, &mut left_out)?;
    }
    page.push_str(
        "<footer>Written by <code>aabench report</code>. Times are wall-clock medians of interleaved \
         repetitions with order-statistic intervals; PSNR has peak 1 (add 48.13 dB for the paper's \
         peak-255 convention); the truth is the reference at 8×8 samples per pixel.</footer>\n</body>\n</html>\n",
    );
    let path = run_dir.join("index.html");
    crate::files::write(&path, page.as_bytes())?;
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

/// How the run's modes took their rounds, for people: `15 repetitions`, or the rule.
fn rounds(settings: &crate::record::RunSettings) -> String {
    match &settings.confidence {
        None => format!("{} repetitions", settings.repetitions),
        Some(rule) => format!(
            "{}–{} rounds by confidence (until a mode's median interval is at most {} % of it wide, or its \
             scene's frames took {} s)",
            rule.floor,
            rule.most,
            rule.width * 100.0,
            rule.budget_s
        ),
    }
}

fn summary(page: &mut String, run: &RunRecord, verdict: Option<&Verdict>) {
    let p = &run.platform.info;
    let _ = writeln!(page, "<h1>aabench run <code>{}</code></h1>", escape(&run.run_id));
    let _ = writeln!(
        page,
        "<p class=\"meta\">{} tier · status <b>{}</b> · started {} · finished {}<br>{} · {} · {} ({} cores) · \
         LP_NUM_THREADS={} · {} build<br>platform key <code>{}</code><br>{} after {} warm-up round(s), \
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
        rounds(&run.settings),
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
    choice::technique_table(page, run);
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
    tables::mode_table(page, scene, &checks);
    for index in 0..scene.sequences.len() {
        tables::sequence_table(page, scene, index);
    }
    for (index, error_plot) in ErrorPlot::of_scene(scene).into_iter().enumerate() {
        let points = error_points(scene, error_plot);
        if points.is_empty() {
            if index == 0 {
                page.push_str("<p>No mode has an error against the truth to plot.</p>\n");
            }
            continue;
        }
        let title = format!("{}: {}", scene.name, error_plot.title(scene));
        let plot = plots::error_against_time(&title, [error_plot.time_axis(), error_plot.axis()], &points)?;
        let _ = writeln!(page, "<figure class=\"plot\">{plot}</figure>");
    }
    tables::verdict_table(page, &checks);
    images::images(page, run_dir, scene, left_out)?;
    images::flicker_region(page, run_dir, scene, left_out)?;
    agreement::section(page, run_dir, scene, left_out)?;
    images::jod_maps(page, scene);
    history::history_plots(page, scene, history)?;
    page.push_str("</section>\n");
    Ok(())
}
