//! Which technique for this scene: for each error level that a mode on the scene's front
//! reaches, the fastest mode that reaches it. Where the scene has a camera path, the rankings
//! are the path's, one per speed (mean PSNR along it, with FLIP, flicker and the error where
//! the frame before did not see the surface beside), and the still's is labelled as the
//! still's. A temporal mode
//! (TAA) is never ranked by its still: that is 16 frames accumulated at one camera, its best
//! case.

use std::fmt::Write;

use super::html::escape;
use crate::record::{ModeRecord, ModeSequence, RunRecord, SceneRecord};
use crate::vocabulary::{Metric, PSNR_VS_TRUTH, SEQUENCE_PSNR_VS_TRUTH};

/// What a ranking measures a mode by.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Basis {
    /// The still: PSNR against the truth and the still's frame time.
    Still,
    /// The scene's sequence `index` along its camera path: the PSNR of the frames' mean MSE
    /// against the truth's frames, and the frame time along the path (the still's where the run
    /// has none).
    Path(usize),
}

impl Basis {
    /// The rankings a scene has: the path's at each speed first, where it has a path.
    pub fn of_scene(scene: &SceneRecord) -> Vec<Basis> {
        (0..scene.sequences.len()).map(Basis::Path).chain([Basis::Still]).collect()
    }

    /// `still`, or `along the path at 4 px a frame`.
    pub fn label(self, scene: &SceneRecord) -> String {
        match self {
            Basis::Still => "still".into(),
            Basis::Path(index) => {
                let speed =
                    scene.sequences.get(index).map_or_else(String::new, |s| format!(" at {}", s.speed()));
                format!("along the path{speed}")
            }
        }
    }

    /// The metric this basis ranks modes by.
    fn metric(self) -> &'static Metric {
        match self {
            Basis::Still => &PSNR_VS_TRUTH,
            Basis::Path(_) => &SEQUENCE_PSNR_VS_TRUTH,
        }
    }

    /// Whether the level `a` is better than `b` on this basis.
    fn better(self, a: f64, b: f64) -> bool {
        self.metric().better(a, b).expect("a ranking metric is gated: it has a direction")
    }

    /// A mode's level and frame time (median, ms) on this basis, where it has both and may be
    /// ranked on it.
    fn measure(self, mode: &ModeRecord) -> Option<(f64, f64)> {
        match self {
            Basis::Still => {
                let temporal = mode.parsed().is_some_and(|m| m.is_jittered());
                let level = self.metric().value(mode)?;
                (!temporal).then_some((level, mode.frame_ms.as_ref()?.median))
            }
            Basis::Path(index) => {
                let sequence = mode.sequence_at(index)?;
                let frame = sequence.frame_ms.as_ref().or(mode.frame_ms.as_ref())?;
                Some((self.metric().value_at(mode, index)?, frame.median))
            }
        }
    }

    /// The mode's sequence this basis ranks it by.
    fn sequence(self, mode: &ModeRecord) -> Option<&ModeSequence> {
        match self {
            Basis::Still => None,
            Basis::Path(index) => mode.sequence_at(index),
        }
    }

    /// Whether `mode` is on the front of this basis among `measured`: on the still's, where
    /// run.json places it (by PSNR with intervals), or where only modes left out of the ranking
    /// dominate it (TAA's still); on the path's, where no faster mode has a higher PSNR.
    fn on_front(
        self,
        (psnr, ms, mode): (f64, f64, &ModeRecord),
        measured: &[(f64, f64, &ModeRecord)],
    ) -> bool {
        match self {
            Basis::Still => mode.front.as_ref().is_some_and(|place| {
                let ranked = |id: &str| measured.iter().any(|(_, _, m)| m.mode == id);
                place.on_front || place.dominated_by.iter().all(|d| !ranked(&d.mode))
            }),
            Basis::Path(_) => !measured.iter().any(|&(p, t, _)| t < ms && self.better(p, psnr)),
        }
    }
}

/// For each PSNR that an unstalled mode on the basis's front reaches, lowest first, the fastest
/// unstalled mode (by median) that reaches it, once per mode.
pub fn fastest_by_level(scene: &SceneRecord, basis: Basis) -> Vec<(f64, &ModeRecord)> {
    let measured: Vec<(f64, f64, &ModeRecord)> = scene
        .modes
        .iter()
        .filter(|m| !m.stalled)
        .filter_map(|m| basis.measure(m).map(|(psnr, ms)| (psnr, ms, m)))
        .collect();
    let mut levels: Vec<f64> = measured
        .iter()
        .filter(|&&point| basis.on_front(point, &measured))
        .map(|&(psnr, _, _)| psnr)
        .collect();
    levels.sort_by(f64::total_cmp);
    let mut rows: Vec<(f64, &ModeRecord)> = Vec::new();
    for level in levels {
        let fastest = measured
            .iter()
            .filter(|&&(psnr, _, _)| !basis.better(level, psnr))
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some(&(_, _, mode)) = fastest
            && rows.last().is_none_or(|(_, last)| last.mode != mode.mode)
        {
            rows.push((level, mode));
        }
    }
    rows
}

/// `36.00 dB: reference-2x2 (280.7 ms, FLIP 0.0196)`; along the path with its flicker and its
/// error where the frame before did not see the surface.
pub fn technique_cell(level: f64, mode: &ModeRecord, basis: Basis) -> String {
    let level = if level.is_finite() { format!("{level:.2} dB") } else { "∞ dB".into() };
    let ms = basis.measure(mode).map_or(0.0, |(_, ms)| ms);
    let mut details = format!("{ms:.1} ms");
    match (basis, basis.sequence(mode)) {
        (Basis::Path(_), Some(sequence)) => {
            if let Some(flip) = sequence.mean_flip {
                let _ = write!(details, ", FLIP {flip:.4}");
            }
            if let Some(flicker) = sequence.flicker {
                let _ = write!(details, ", flicker {:.2}e-4", flicker * 1e4);
            }
            if let Some(mse) = sequence.ghosting.as_ref().and_then(|g| g.mse) {
                let _ = write!(details, ", disoccluded MSE {:.2}e-3", mse * 1e3);
            }
        }
        _ => {
            if let Some(flip) = mode.vs_ground_truth.as_ref().and_then(|q| q.flip) {
                let _ = write!(details, ", FLIP {flip:.4}");
            }
        }
    }
    format!("{level}: {} ({details})", mode.mode)
}

/// The rankings of every scene: per scene and basis, its cells.
fn rankings(run: &RunRecord) -> Vec<(&str, String, Vec<String>)> {
    let mut rows = Vec::new();
    for scene in &run.scenes {
        for basis in Basis::of_scene(scene) {
            let cells: Vec<String> = fastest_by_level(scene, basis)
                .iter()
                .map(|&(level, mode)| technique_cell(level, mode, basis))
                .collect();
            if !cells.is_empty() {
                rows.push((scene.name.as_str(), basis.label(scene), cells));
            }
        }
    }
    rows
}

/// What the table says, in one paragraph.
const CAPTION: &str = "For each PSNR against the truth that a mode on the scene's front reaches, the \
     fastest unstalled mode that reaches it. Along the path: the mean PSNR over the path's frames, the \
     frame time along it, mean FLIP, flicker (the change of the error along the truth's motion) and the \
     MSE where the frame before did not see the surface. The still's ranking leaves TAA out: its still \
     is 16 frames accumulated at one camera.";

/// The rankings as an HTML section.
pub(super) fn technique_table(page: &mut String, run: &RunRecord) {
    let rows = rankings(run);
    if rows.is_empty() {
        return;
    }
    let _ = writeln!(
        page,
        "<h2>Which technique for this scene</h2>\n<p>{}</p>\n<table><thead><tr><th>scene</th>\
         <th>ranked</th><th>at least … dB: the fastest mode</th></tr></thead><tbody>",
        escape(CAPTION)
    );
    for (scene, basis, cells) in rows {
        let _ = writeln!(
            page,
            "<tr><td>{}</td><td>{}</td><td>{}</td></tr>",
            escape(scene),
            escape(&basis),
            escape(&cells.join(" · "))
        );
    }
    page.push_str("</tbody></table>\n");
}

/// The rankings as a Markdown section; `cell` escapes a cell's text.
pub(super) fn technique_markdown(out: &mut String, run: &RunRecord, cell: fn(&str) -> String) {
    let rows = rankings(run);
    if rows.is_empty() {
        return;
    }
    let _ = write!(
        out,
        "\n### Which technique for this scene\n\n{CAPTION}\n\n| scene | ranked | at least … dB: the fastest \
         mode |\n|---|---|---|\n"
    );
    for (scene, basis, cells) in rows {
        let _ = writeln!(out, "| {} | {} | {} |", cell(scene), basis, cell(&cells.join(" · ")));
    }
}
