//! Which technique for this scene, by what people see: ColorVideoVDP's JOD against the truth.
//! Modes within [`JOD_MARGIN`] of the best are one quality: the answer is its cheapest mode,
//! and the ranking under it names the cheapest mode of each quality below, among the modes
//! cheaper than the row above. Cheaper means faster with confidence by at least
//! [`TIME_MARGIN`]: a viewer's 0.1 JOD and the machine's 10 % are the smallest differences a
//! ranking claims, so that a second run on the same machine gives the same rows. Where the scene has a camera path,
//! the rankings are the path's, one per speed (JOD of the frames as a video), with PSNR, FLIP,
//! flicker and ghosting one click away; the still's is labelled as the still's. A temporal mode
//! (TAA) is never ranked by its still: that is 16 frames accumulated at one camera, its best
//! case.

use std::fmt::Write;

use super::html::escape;
use crate::measure::stats::Summary;
use crate::record::front::FrontPoint;
use crate::record::vocabulary::{
    JOD_MARGIN, JOD_VS_TRUTH, METRICS, Metric, SEQUENCE_JOD_VS_TRUTH, Source, TIME_MARGIN,
};
use crate::record::{ModeRecord, ModeSequence, RunRecord, SceneRecord};

/// What a ranking measures a mode by.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Basis {
    /// The still: JOD against the truth and the still's frame time.
    Still,
    /// The scene's sequence `index` along its camera path: the JOD of the frames as a video
    /// against the truth's, and the frame time along the path (the still's where the run has
    /// none).
    Path(usize),
}

impl Basis {
    /// The rankings a scene has: the path's at each speed first, where it has a path.
    pub fn of_scene(scene: &SceneRecord) -> Vec<Basis> {
        (0..scene.sequences.len()).map(Basis::Path).chain([Basis::Still]).collect()
    }

    /// `still`, or `along the path: 1.8 px a frame (median; 3.7 nominal)`.
    pub fn label(self, scene: &SceneRecord) -> String {
        match self {
            Basis::Still => "still".into(),
            Basis::Path(index) => {
                let speed =
                    scene.sequences.get(index).map_or_else(String::new, |s| format!(": {}", s.speed()));
                format!("along the path{speed}")
            }
        }
    }

    /// The metric this basis ranks modes by.
    fn metric(self) -> &'static Metric {
        match self {
            Basis::Still => &JOD_VS_TRUTH,
            Basis::Path(_) => &SEQUENCE_JOD_VS_TRUTH,
        }
    }

    /// A mode's level and frame time on this basis, where it has both (a finite level) and may
    /// be ranked on it.
    fn measure(self, mode: &ModeRecord) -> Option<(f64, &Summary)> {
        let measured = match self {
            Basis::Still => {
                let temporal = mode.parsed().is_some_and(|m| m.is_jittered());
                let level = self.metric().value(mode)?;
                (!temporal).then_some((level, mode.frame_ms.as_ref()?))
            }
            Basis::Path(index) => {
                let sequence = mode.sequence_at(index)?;
                let frame = sequence.frame_ms.as_ref().or(mode.frame_ms.as_ref())?;
                Some((self.metric().value_at(mode, index)?, frame))
            }
        };
        measured.filter(|(level, _)| level.is_finite())
    }

    /// The sequence this basis ranks modes along (0 for the still).
    fn index(self) -> usize {
        match self {
            Basis::Still => 0,
            Basis::Path(index) => index,
        }
    }

    /// The mode's sequence this basis ranks it by.
    fn sequence(self, mode: &ModeRecord) -> Option<&ModeSequence> {
        match self {
            Basis::Still => None,
            Basis::Path(index) => mode.sequence_at(index),
        }
    }
}

/// A row of a ranking: the cheapest mode of a class of modes that a viewer could hardly tell
/// apart, with its own level and median frame time, and the modes of the class that are as
/// cheap (no mode of the class is cheaper than them: faster with confidence by at least
/// [`TIME_MARGIN`] of their time).
#[derive(Debug, Clone)]
pub struct Row<'a> {
    pub level: f64,
    pub mode: &'a ModeRecord,
    pub ms: f64,
    pub as_cheap: Vec<&'a ModeRecord>,
}

/// A mode a ranking may list: its level and time on the basis, and its point for comparing
/// times round by round.
#[derive(Debug, Clone, Copy)]
struct Candidate<'a> {
    level: f64,
    ms: f64,
    mode: &'a ModeRecord,
    point: FrontPoint<'a>,
}

impl Candidate<'_> {
    /// Whether this mode is cheaper than `other`: faster with confidence, round by round (or
    /// frame by frame along the path), and by at least [`TIME_MARGIN`] of the other's time.
    fn cheaper_than(&self, other: &Candidate) -> bool {
        self.point.cheaper_by(&other.point, TIME_MARGIN)
    }
}

/// The unstalled modes measured on `basis`, in the plan's order.
fn candidates(scene: &SceneRecord, basis: Basis) -> Vec<Candidate<'_>> {
    (scene.modes.iter())
        .filter(|mode| !mode.stalled)
        .filter_map(|mode| {
            let (level, time) = basis.measure(mode)?;
            let point = FrontPoint::of(mode, basis.metric(), basis.index())?;
            Some(Candidate { level, ms: time.median, mode, point })
        })
        .collect()
}

/// The ranking on `basis`, cheapest first, built from the top: every unstalled mode within
/// [`JOD_MARGIN`] of the best is one quality, named by its cheapest mode (the answer); then the
/// same among the modes below that quality that are cheaper than that one; and so on. Times
/// are compared round by round, as the fronts compare them (`front.rs`), and a mode is cheaper
/// than another only where it is faster with confidence by at least [`TIME_MARGIN`]: the
/// cheapest of a quality are the modes none of it is cheaper than, and where several are, the
/// first in the plan's order (the simpler technique: a reference before adaptive, the paper's
/// adaptive before its variants) names the row and the others stand beside it as `≈`. From row
/// to row the level and the time rise, and a mode 5 % faster and 0.05 JOD worse than another
/// makes no row of its own; the last row is the answer.
pub fn ranking(scene: &SceneRecord, basis: Basis) -> Vec<Row<'_>> {
    let mut left = candidates(scene, basis);
    let mut rows = Vec::new();
    while let Some(top) = left.iter().map(|c| c.level).max_by(f64::total_cmp) {
        let class: Vec<Candidate> = left.iter().filter(|c| within_margin(c.level, top)).copied().collect();
        let beaten = |c: &Candidate| class.iter().any(|other| other.cheaper_than(c));
        let cheapest: Vec<Candidate> = class.iter().filter(|c| !beaten(c)).copied().collect();
        // Paired comparisons need not be transitive: should every mode of the class be beaten
        // (a cycle), its first names the row.
        let Some(named) = cheapest.first().or(class.first()).copied() else { break };
        let as_cheap = cheapest.iter().skip(1).map(|c| c.mode).collect();
        rows.push(Row { level: named.level, mode: named.mode, ms: named.ms, as_cheap });
        left.retain(|c| !within_margin(c.level, top) && c.cheaper_than(&named));
    }
    rows.reverse();
    rows
}

/// Whether `level` is within [`JOD_MARGIN`] below `top` (a margin of exactly 0.1 JOD between
/// two-decimal scores counts as within, whatever their last bits).
fn within_margin(level: f64, top: f64) -> bool {
    top - level <= JOD_MARGIN + 1e-9
}

/// A ranking's answer: the cheapest unstalled mode whose level is within [`JOD_MARGIN`] of the
/// best one's, the best, and what the answer costs against deferred-1x1 on the same basis.
#[derive(Debug, Clone, Copy)]
pub struct Answer<'a> {
    pub mode: &'a ModeRecord,
    pub level: f64,
    pub ms: f64,
    pub best: &'a ModeRecord,
    pub best_level: f64,
    /// Its frame time over deferred-1x1's, where deferred-1x1 was measured on the basis.
    pub vs_deferred: Option<f64>,
}

impl Answer<'_> {
    /// `msaa-4x 9.660 JOD, 30.2 ms (2.04× deferred-1x1); the best, reference-4x4, 9.700`.
    pub fn describe(&self) -> String {
        let cost = self.vs_deferred.map_or_else(String::new, |r| format!(" ({r:.2}× deferred-1x1)"));
        let best = if self.best_level <= self.level {
            "the best".to_string()
        } else {
            format!("the best, {}, {}", self.best.mode, jod(self.best_level))
        };
        format!("{} {} JOD, {:.1} ms{cost}; {best}", self.mode.mode, jod(self.level), self.ms)
    }
}

/// The answer on `basis`: the top row of its [`ranking`], the cheapest unstalled mode within
/// [`JOD_MARGIN`] of the best; no answer where no mode was measured on it.
pub fn answer(scene: &SceneRecord, basis: Basis) -> Option<Answer<'_>> {
    Answer::of(scene, basis, &ranking(scene, basis).pop()?)
}

impl<'a> Answer<'a> {
    /// The answer that `top`, the top row of the scene's ranking on `basis`, gives.
    fn of(scene: &'a SceneRecord, basis: Basis, top: &Row<'a>) -> Option<Answer<'a>> {
        let measured: Vec<(f64, f64, &ModeRecord)> = (scene.modes.iter())
            .filter(|m| !m.stalled)
            .filter_map(|m| basis.measure(m).map(|(level, time)| (level, time.median, m)))
            .collect();
        let &(best_level, _, best) =
            measured.iter().max_by(|a, b| a.0.total_cmp(&b.0).then(b.1.total_cmp(&a.1)))?;
        let deferred = measured.iter().find(|(_, _, m)| m.mode == "deferred-1x1").map(|&(_, ms, _)| ms);
        Some(Answer {
            mode: top.mode,
            level: top.level,
            ms: top.ms,
            best,
            best_level,
            vs_deferred: deferred.map(|d| top.ms / d),
        })
    }
}

/// `reference-2x2 9.210 JOD, 40.1 ms`: a row's recommendation, with the modes as cheap as it
/// (`msaa-4x (≈ adaptive-2x2) 9.620 JOD, 20.0 ms`).
fn recommendation(row: &Row) -> String {
    let names: Vec<&str> = row.as_cheap.iter().map(|m| m.mode.as_str()).collect();
    let ties = if names.is_empty() { String::new() } else { format!(" (≈ {})", names.join(", ")) };
    format!("{}{ties} {} JOD, {:.1} ms", row.mode.mode, jod(row.level), row.ms)
}

/// A level of JOD as the JOD's row writes it.
fn jod(level: f64) -> String {
    JOD_VS_TRUTH.written(level)
}

/// `reference-2x2: 9.210 JOD, 40.1 ms, PSNR 36.00 dB, FLIP 0.0196`: the row's recommendation,
/// then each metric of the basis's part of the record that reads among a row's details
/// (`Metric::brief`): along the path its flicker and its error where the frame before had the
/// surface hidden too.
pub fn technique_cell(row: &Row, basis: Basis) -> String {
    let mode = row.mode;
    let (source, index) = match (basis, basis.sequence(mode)) {
        (Basis::Path(index), Some(_)) => (Source::Sequence, index),
        _ => (Source::Truth, 0),
    };
    let details = METRICS
        .iter()
        .filter(|metric| metric.source == source)
        .filter_map(|metric| Some((metric.brief?)(metric.value_at(mode, index)?)));
    std::iter::once(recommendation(row)).chain(details).collect::<Vec<_>>().join(", ")
}

/// One ranking: a scene's rows on one basis, and its answer.
struct Ranking<'a> {
    scene: &'a str,
    basis: String,
    rows: Vec<Row<'a>>,
    answer: String,
    details: Vec<String>,
    recommended: Vec<String>,
}

/// The rankings of every scene, per scene and basis.
fn rankings(run: &RunRecord) -> Vec<Ranking<'_>> {
    let mut out = Vec::new();
    for scene in &run.scenes {
        for basis in Basis::of_scene(scene) {
            let rows = ranking(scene, basis);
            let Some(found) = rows.last().and_then(|top| Answer::of(scene, basis, top)) else { continue };
            out.push(Ranking {
                scene: &scene.name,
                basis: basis.label(scene),
                answer: found.describe(),
                details: rows.iter().map(|row| technique_cell(row, basis)).collect(),
                recommended: rows.iter().map(recommendation).collect(),
                rows,
            });
        }
    }
    out
}

/// What the table says, in one paragraph, with the viewing conditions its rankings assume.
fn caption(run: &RunRecord) -> String {
    format!(
        "Ranked by ColorVideoVDP's JOD against the truth (10: no visible difference; of two modes 1 JOD \
         apart, 75 % of viewers prefer the better), {}, along the camera path at each speed where \
         the scene has one, at steady state (after 16 warm-up frames). Modes within {JOD_MARGIN} JOD of the \
         best are one quality (of two modes {JOD_MARGIN} JOD apart, about 53 % of viewers prefer the \
         better). The answer is its cheapest unstalled mode, with its time against deferred-1x1; each \
         line names, from the cheapest up, the cheapest mode of each quality below, among the modes \
         faster than the one above by at least {margin:.0} % with confidence (round by round), with \
         its own JOD and frame time (≈: modes of its quality that no mode of it is that much faster \
         than; the first in the plan's order names the step); the chart draws them, JOD across and \
         time up. The details \
         add PSNR, mean FLIP, flicker (the change of the error along the truth's motion) and the MSE \
         where the frame before had the surface hidden. The still's ranking leaves TAA out: its still \
         is 16 frames accumulated at one camera.",
        viewing_conditions(run),
        margin = TIME_MARGIN * 100.0
    )
}

/// Scenes judged on one display at one distance, and the widths of their frames.
struct Viewing<'a> {
    display: &'a str,
    pixels_per_degree: f64,
    widths: Vec<u32>,
    scenes: Vec<&'a str>,
}

impl Viewing<'_> {
    /// `on standard_fhd at 37.8 pixels a degree (a 256-pixel-wide frame 6.8° across, a
    /// 160-pixel-wide one 4.2° across)`.
    fn describe(&self) -> String {
        let sizes: Vec<String> = (self.widths.iter().enumerate())
            .map(|(i, &w)| {
                let what = if i == 0 { "frame" } else { "one" };
                format!("a {w}-pixel-wide {what} {:.1}° across", f64::from(w) / self.pixels_per_degree)
            })
            .collect();
        format!("on {} at {:.1} pixels a degree ({})", self.display, self.pixels_per_degree, sizes.join(", "))
    }
}

/// The viewing conditions a run's rankings assume: `as seen on standard_fhd at 37.8 pixels a
/// degree (…)`; where scenes are judged on different displays or distances, each group names
/// its scenes.
pub fn viewing_conditions(run: &RunRecord) -> String {
    let mut groups: Vec<Viewing> = Vec::new();
    for scene in &run.scenes {
        let (Some(display), Some(ppd), Some([width, _])) =
            (scene.jod_display.as_deref(), scene.pixels_per_degree, scene.resolution)
        else {
            continue;
        };
        match groups.iter_mut().find(|g| (g.display, g.pixels_per_degree) == (display, ppd)) {
            Some(group) => {
                if !group.widths.contains(&width) {
                    group.widths.push(width);
                }
                group.scenes.push(&scene.name);
            }
            None => groups.push(Viewing {
                display,
                pixels_per_degree: ppd,
                widths: vec![width],
                scenes: vec![&scene.name],
            }),
        }
    }
    match groups.as_slice() {
        [] => "as seen on the scenes' displays".into(),
        [one] => format!("as seen {}", one.describe()),
        _ => {
            let each: Vec<String> =
                groups.iter().map(|g| format!("{} {}", g.scenes.join(", "), g.describe())).collect();
            format!("as seen: {}", each.join("; "))
        }
    }
}

/// A small step chart of a ranking: JOD across (from the lowest level to 10), frame time up
/// (log), a dot per row with its mode in a tooltip.
fn step_chart(rows: &[Row]) -> String {
    let (width, height, pad) = (180.0, 48.0, 4.0);
    let low = rows.iter().map(|r| r.level).fold(10.0f64, f64::min).min(9.5) - 0.1;
    let times: Vec<f64> = rows.iter().map(|r| r.ms.max(1e-3).ln()).collect();
    let (t_low, t_high) =
        times.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &t| (a.min(t), b.max(t)));
    let x = |jod: f64| pad + (jod - low) / (10.0 - low) * (width - 2.0 * pad);
    let y = |t: f64| {
        height
            - pad
            - if t_high > t_low { (t - t_low) / (t_high - t_low) } else { 0.5 } * (height - 2.0 * pad)
    };
    let mut path = String::new();
    for (i, (row, &t)) in rows.iter().zip(&times).enumerate() {
        let next = rows.get(i + 1).map_or(10.0, |r| r.level);
        let _ = if i == 0 {
            write!(path, "M{:.1} {:.1}", x(row.level), y(t))
        } else {
            write!(path, " V{:.1}", y(t))
        };
        let _ = write!(path, " H{:.1}", x(next));
    }
    let mut svg = format!(
        "<svg class=\"steps\" width=\"{width}\" height=\"{height}\" viewBox=\"0 0 {width} {height}\"><path d=\"{path}"
    );
    svg.push_str("\" fill=\"none\" stroke=\"#1f77b4\"/>");
    for (row, &t) in rows.iter().zip(&times) {
        let _ = write!(
            svg,
            "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"2.5\"><title>{}</title></circle>",
            x(row.level),
            y(t),
            escape(&recommendation(row))
        );
    }
    svg.push_str("</svg>");
    svg
}

/// The rankings as an HTML section: a line a scene and basis, its chart, and the details one
/// click away.
pub(super) fn technique_table(page: &mut String, run: &RunRecord) {
    let rankings = rankings(run);
    if rankings.is_empty() {
        return;
    }
    let _ = writeln!(
        page,
        "<h2>Which technique for this scene</h2>\n<p>{}</p>\n<table><thead><tr><th>scene</th>\
         <th>ranked</th><th>answer</th><th>the cheapest mode of each quality, cheapest first</th>\
         <th>time against JOD</th></tr>\
         </thead><tbody>",
        escape(&caption(run))
    );
    for ranking in rankings {
        let _ = writeln!(
            page,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}<details><summary>details</summary>{}</details></td><td>{}</td></tr>",
            escape(ranking.scene),
            escape(&ranking.basis),
            escape(&ranking.answer),
            escape(&ranking.recommended.join(" → ")),
            ranking.details.iter().map(|d| format!("<div>{}</div>", escape(d))).collect::<String>(),
            step_chart(&ranking.rows)
        );
    }
    page.push_str("</tbody></table>\n");
}

/// The rankings as a Markdown section; `cell` escapes a cell's text.
pub(super) fn technique_markdown(out: &mut String, run: &RunRecord, cell: fn(&str) -> String) {
    let rankings = rankings(run);
    if rankings.is_empty() {
        return;
    }
    let _ = write!(
        out,
        "\n### Which technique for this scene\n\n{}\n\n| scene | ranked | answer | the cheapest mode of \
         each quality, cheapest first | details |\n|---|---|---|---|---|\n",
        caption(run)
    );
    for ranking in rankings {
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {} |",
            cell(ranking.scene),
            ranking.basis,
            cell(&ranking.answer),
            cell(&ranking.recommended.join(" → ")),
            cell(&ranking.details.join(" · "))
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::pixels::{Decibels, Quality};

    /// The five rounds' drift of the machine's speed, which every mode of a round shares.
    const DRIFT: [f64; 5] = [1.0, 1.2, 0.8, 1.1, 0.9];

    /// An unstalled mode timed at `ms` in every round (times the round's drift) whose still
    /// scores `jod` against the truth.
    fn timed(id: &str, ms: f64, jod: f64) -> ModeRecord {
        rounds(id, DRIFT.map(|drift| ms * drift), jod)
    }

    /// An unstalled mode timed `samples`, one a round, whose still scores `jod`.
    fn rounds(id: &str, samples: [f64; 5], jod: f64) -> ModeRecord {
        let json = serde_json::json!({ "mode": id, "m": 1, "stalled": false, "status": "ok", "passes": [], "images": {} });
        let mut mode: ModeRecord = serde_json::from_value(json).unwrap();
        mode.frame_ms = Summary::new(samples.to_vec());
        mode.vs_ground_truth = Some(Quality {
            against: "truth-8x8".into(),
            mse: 1e-4,
            mse_e5: 10.0,
            psnr_db: Decibels::from_f64(40.0),
            psnr_paper_db: Decibels::from_f64(88.1),
            max_abs_diff: 1,
            flip: None,
            ssim: None,
            jod: Some(jod),
        });
        mode
    }

    fn scene(modes: Vec<ModeRecord>) -> SceneRecord {
        let json = serde_json::json!({
            "name": "s", "manifest": "s.json", "status": "ok", "stall_iterations": 16, "gate": {}, "modes": []
        });
        SceneRecord { modes, ..serde_json::from_value(json).unwrap() }
    }

    #[test]
    fn the_answer_is_the_cheapest_mode_a_viewer_could_hardly_tell_from_the_best_and_tops_the_ranking() {
        let modes = vec![
            timed("deferred-1x1", 10.0, 8.0),
            timed("msaa-4x", 20.0, 9.62),
            // Faster than msaa-4x in two rounds and slower in three, 0.01 JOD below it: as fast,
            // one quality.
            rounds("smaa", [19.5, 25.0, 16.5, 21.5, 18.5], 9.61),
            // 1 % faster and 0.001 JOD worse than reference-2x2: no level of its own.
            timed("adaptive-2x2", 29.7, 9.649),
            timed("reference-2x2", 30.0, 9.65),
            timed("reference-4x4", 90.0, 9.70),
        ];
        let ranked = scene(modes);
        let found = answer(&ranked, Basis::Still).unwrap();
        assert_eq!((found.mode.mode.as_str(), found.best.mode.as_str()), ("msaa-4x", "reference-4x4"));
        assert_eq!(found.vs_deferred, Some(2.0));
        let rows = ranking(&ranked, Basis::Still);
        let named: Vec<(&str, f64)> = rows.iter().map(|row| (row.mode.mode.as_str(), row.level)).collect();
        assert_eq!(named, [("deferred-1x1", 8.0), ("msaa-4x", 9.62)], "the answer tops the ranking");
        assert_eq!(recommendation(&rows[1]), "msaa-4x (≈ smaa) 9.620 JOD, 20.0 ms");
        // A mode 4 times cheaper than the answer and 0.09 JOD below it is not hidden: it is the
        // next quality down.
        let cheap = scene(vec![
            timed("reference-4x4", 90.0, 9.70),
            timed("msaa-4x", 20.0, 9.61),
            timed("fxaa", 5.0, 9.52),
            timed("deferred-1x1", 4.0, 8.0),
        ]);
        let named: Vec<&str> =
            ranking(&cheap, Basis::Still).iter().map(|row| row.mode.mode.as_str()).collect();
        assert_eq!(named, ["deferred-1x1", "fxaa", "msaa-4x"]);
        let with_nan = scene(vec![timed("smaa", 1.0, f64::NAN), timed("deferred-1x1", 4.0, 8.0)]);
        assert_eq!(
            answer(&with_nan, Basis::Still).map(|a| a.mode.mode.as_str()),
            Some("deferred-1x1"),
            "no level, no rank"
        );
        assert_eq!(
            found.describe(),
            "msaa-4x 9.620 JOD, 20.0 ms (2.00× deferred-1x1); the best, reference-4x4, 9.700"
        );
        // Beyond the margin, the best answers for itself.
        let far = scene(vec![timed("deferred-1x1", 10.0, 8.0), timed("reference-4x4", 90.0, 9.70)]);
        assert!(answer(&far, Basis::Still).unwrap().describe().ends_with("; the best"));
        assert!(answer(&scene(Vec::new()), Basis::Still).is_none(), "no mode, no answer");
    }

    #[test]
    fn a_row_needs_a_mode_faster_in_its_rounds_and_ties_go_to_the_plans_first() {
        // reference-2x2 is cheaper than msaa-4x by its median, but slower in two of five rounds:
        // no cheaper choice the rounds can show, so no row; deferred-1x1 is one.
        let modes = vec![
            timed("deferred-1x1", 10.0, 8.0),
            timed("msaa-4x", 20.0, 9.86),
            rounds("reference-2x2", [19.0, 25.0, 15.0, 23.0, 17.5], 9.64),
            timed("reference-3x3", 45.0, 9.93),
        ];
        let cornell = scene(modes);
        let named: Vec<&str> =
            (ranking(&cornell, Basis::Still).iter()).map(|row| row.mode.mode.as_str()).collect();
        assert_eq!(named, ["deferred-1x1", "msaa-4x"]);
        // adaptive-4x4 and its variant cost the same within the rounds' noise, one quality: the
        // first in the plan's order names the row whichever median is lower.
        let modes = vec![
            rounds("adaptive-4x4", [40.0, 49.0, 31.0, 45.0, 35.5], 9.30),
            timed("adaptive-4x4-area", 39.5, 9.31),
        ];
        let atrium = scene(modes);
        let rows = ranking(&atrium, Basis::Still);
        assert_eq!(recommendation(&rows[0]), "adaptive-4x4 (≈ adaptive-4x4-area) 9.300 JOD, 40.0 ms");
    }

    #[test]
    fn a_saving_under_the_time_margin_makes_no_step_and_names_no_row_however_sure() {
        // smaa is 5 % faster than msaa-4x in every round, 0.2 JOD below it: faster with
        // confidence, but too small a saving to be a step; fxaa, 20 % faster, is one.
        let modes = vec![
            timed("deferred-1x1", 10.0, 8.0),
            timed("fxaa", 16.0, 9.2),
            timed("smaa", 19.0, 9.4),
            timed("msaa-4x", 20.0, 9.6),
        ];
        let steps = scene(modes);
        let named: Vec<&str> =
            ranking(&steps, Basis::Still).iter().map(|row| row.mode.mode.as_str()).collect();
        assert_eq!(named, ["deferred-1x1", "fxaa", "msaa-4x"]);
        // Within a quality, a mode 5 % faster in every round stands beside the plan's first; one
        // 15 % faster names the row alone.
        let quality = |adaptive_ms: f64| {
            let modes = vec![timed("reference-2x2", 30.0, 9.65), timed("adaptive-2x2", adaptive_ms, 9.64)];
            recommendation(&ranking(&scene(modes), Basis::Still)[0])
        };
        assert_eq!(quality(28.5), "reference-2x2 (≈ adaptive-2x2) 9.650 JOD, 30.0 ms");
        assert_eq!(quality(25.5), "adaptive-2x2 9.640 JOD, 25.5 ms");
        let gate = crate::manifest::tolerances::Tolerances::default();
        assert_eq!(TIME_MARGIN, gate.time_ratio, "the margin is the gate's tolerance for time ratios");
    }
}
