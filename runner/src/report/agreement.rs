//! What people see against squared error, along each camera path: the unstalled modes ordered
//! by ColorVideoVDP's JOD and by PSNR, the rank correlation of the two orders, and the pair of
//! modes they order most differently, with what shows why: the pair's error as animations at
//! the square where the modes flicker most, its flicker, and its distortion maps.
//!
//! The usual reason is that squared error weighs an error that changes from frame to frame
//! (aliasing that shimmers as the camera moves) like a steady one of the same energy (blur, a
//! lag that follows the motion), and a viewer does not: the animations of the error show it.

use std::fmt::Write;
use std::path::Path;

use super::ZOOM;
use super::html::escape;
use super::images::figure;
use crate::measure::pixels::COARSE_SIGMA_PX;
use crate::measure::stats::spearman;
use crate::record::vocabulary::{self, JOD_MARGIN, SEQUENCE_JOD_VS_TRUTH, SEQUENCE_PSNR_VS_TRUTH};
use crate::record::{ModeRecord, SceneRecord, SequenceRecord};
use crate::run::truth::TRUTH_ID;

/// The smallest differences that count as an order: [`JOD_MARGIN`] and a tenth of a decibel.
const PSNR_MARGIN_DB: f64 = 0.1;

/// How much the error animations amplify the difference of code values.
const ERROR_GAIN: f64 = 4.0;

/// One mode's two measures along one path.
#[derive(Debug, Clone, Copy)]
pub struct Scored<'a> {
    pub mode: &'a ModeRecord,
    pub jod: f64,
    pub psnr_db: f64,
}

/// The unstalled modes with both measures along sequence `index` (a stalled mode's frames are
/// its twin's), in the run's order.
pub fn scored(scene: &SceneRecord, index: usize) -> Vec<Scored<'_>> {
    scene
        .modes
        .iter()
        .filter(|mode| !mode.stalled)
        .filter_map(|mode| {
            let sequence = mode.sequence_at(index)?;
            let psnr_db = sequence.mean_psnr_db.value();
            (!psnr_db.is_nan()).then_some(Scored { mode, jod: sequence.jod?, psnr_db })
        })
        .collect()
}

/// `scored` best first by JOD, and best first by PSNR.
pub fn orders<'a>(scored: &[Scored<'a>]) -> [Vec<Scored<'a>>; 2] {
    let mut by_jod = scored.to_vec();
    by_jod.sort_by(|a, b| b.jod.total_cmp(&a.jod));
    let mut by_psnr = scored.to_vec();
    by_psnr.sort_by(|a, b| b.psnr_db.total_cmp(&a.psnr_db));
    [by_jod, by_psnr]
}

/// Spearman's rank correlation of the modes' JOD and PSNR.
pub fn rank_correlation(scored: &[Scored]) -> Option<f64> {
    let (jods, psnrs): (Vec<f64>, Vec<f64>) = scored.iter().map(|s| (s.jod, s.psnr_db)).unzip();
    spearman(&jods, &psnrs)
}

/// Two modes the measures order oppositely, each by at least its margin: PSNR prefers
/// `psnr_pick`, ColorVideoVDP `jod_pick`.
#[derive(Debug, Clone, Copy)]
pub struct AtOdds<'a> {
    pub psnr_pick: Scored<'a>,
    pub jod_pick: Scored<'a>,
}

/// Of the pairs the two measures order oppositely, the one a viewer separates most (the
/// largest difference of JOD); `None` where the measures agree on every pair.
pub fn most_at_odds<'a>(scored: &[Scored<'a>]) -> Option<AtOdds<'a>> {
    let mut best: Option<AtOdds<'a>> = None;
    for &psnr_pick in scored {
        for &jod_pick in scored {
            let opposite = psnr_pick.psnr_db - jod_pick.psnr_db >= PSNR_MARGIN_DB
                && jod_pick.jod - psnr_pick.jod >= JOD_MARGIN;
            let wider = best.is_none_or(|b| jod_pick.jod - psnr_pick.jod > b.jod_pick.jod - b.psnr_pick.jod);
            if opposite && wider {
                best = Some(AtOdds { psnr_pick, jod_pick });
            }
        }
    }
    best
}

impl AtOdds<'_> {
    /// The disagreement and its likely causes, from the measures along sequence `index`:
    /// whether the error PSNR prefers changes more along the motion (flicker), and whether it is
    /// coarser where the modes flicker most (the `coarse_share` row). Numbers read as their
    /// rows write them.
    pub fn explanation(&self, index: usize) -> String {
        let (a, b) = (self.psnr_pick, self.jod_pick);
        let (name_a, name_b) = (&a.mode.mode, &b.mode.mode);
        let [db, jod] = [&SEQUENCE_PSNR_VS_TRUTH, &SEQUENCE_JOD_VS_TRUTH];
        let mut text = format!(
            "PSNR prefers {name_a} ({} dB against {}); a viewer, by ColorVideoVDP, {name_b} ({} JOD against {}).",
            db.written(a.psnr_db),
            db.written(b.psnr_db),
            jod.written(b.jod),
            jod.written(a.jod)
        );
        let along = |s: &Scored, id: &str| {
            let metric = vocabulary::metric(id).expect("a row of the vocabulary");
            metric.value_at(s.mode, index).map(|value| (value, metric))
        };
        let mut explained = false;
        if let (Some((fa, flicker)), Some((fb, _))) = (along(&a, "flicker"), along(&b, "flicker"))
            && fa > 1.1 * fb
        {
            let how_much = if fb > 0.0 {
                format!("{:.1}× as much as {name_b}'s", fa / fb)
            } else {
                format!("where {name_b}'s does not change")
            };
            let _ = write!(
                text,
                " {name_a}'s error changes along the motion {how_much} ({}: {} against {}): the eye sees an \
                 error that shimmers more than a steady one of the same energy, and squared error weighs them \
                 alike.",
                flicker.column.map_or(flicker.label, |column| column.header),
                flicker.written(fa),
                flicker.written(fb)
            );
            explained = true;
        }
        if let (Some((ca, coarse)), Some((cb, _))) = (along(&a, "coarse_share"), along(&b, "coarse_share"))
            && ca > 1.25 * cb
        {
            let _ = write!(
                text,
                " {name_a}'s error is coarser where the modes flicker most: {} % of its energy survives a \
                 blur of σ {COARSE_SIGMA_PX} px, against {} % of {name_b}'s, and the eye sees coarse error \
                 far better than the pixel-scale error that squared error weighs alike.",
                coarse.written(ca),
                coarse.written(cb)
            );
            explained = true;
        }
        if !explained {
            text.push_str(
                " Neither flicker nor the coarseness of the error explains it: the difference lies in where \
                 the error falls and how much the scene's own contrast masks it there; the maps show where.",
            );
        }
        text
    }
}

/// Per path, the two orders side by side with their rank correlation, and where they differ,
/// the pair most at odds with its animations and maps.
pub(super) fn section(
    page: &mut String,
    run_dir: &Path,
    scene: &SceneRecord,
    left_out: &mut Vec<String>,
) -> Result<(), String> {
    for (index, sequence) in scene.sequences.iter().enumerate() {
        let scored = scored(scene, index);
        if scored.len() < 2 {
            continue;
        }
        let _ = writeln!(
            page,
            "<h3>What a viewer sees against squared error: {}</h3>",
            escape(&sequence.speed())
        );
        orders_table(page, &scored);
        match most_at_odds(&scored) {
            None => page.push_str("<p class=\"meta\">JOD and PSNR order these modes alike.</p>\n"),
            Some(odds) => {
                let _ = writeln!(page, "<p>{}</p>", escape(&odds.explanation(index)));
                evidence(page, run_dir, scene, sequence, index, odds, left_out)?;
            }
        }
    }
    Ok(())
}

/// The two orders as one table, a rank a row, one click away, its correlation in the summary.
fn orders_table(page: &mut String, scored: &[Scored]) {
    let rho = rank_correlation(scored);
    let _ = writeln!(
        page,
        "<details><summary>The modes best first by JOD along the path and by its mean PSNR; Spearman's rank \
         correlation of the two: {}</summary>\n<table><thead><tr><th>rank</th><th>by JOD</th><th>JOD</th>\
         <th>by PSNR</th><th>dB</th></tr></thead><tbody>",
        rho.map_or("–".into(), |r| format!("{r:.2}"))
    );
    let [by_jod, by_psnr] = orders(scored);
    for (rank, (j, p)) in by_jod.iter().zip(&by_psnr).enumerate() {
        let _ = writeln!(
            page,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            rank + 1,
            escape(&j.mode.mode),
            SEQUENCE_JOD_VS_TRUTH.written(j.jod),
            escape(&p.mode.mode),
            SEQUENCE_PSNR_VS_TRUTH.written(p.psnr_db)
        );
    }
    page.push_str("</tbody></table></details>\n");
}

/// The pair's frames and error, animated at the sequence's flicker square, and their
/// distortion maps.
fn evidence(
    page: &mut String,
    run_dir: &Path,
    scene: &SceneRecord,
    sequence: &SequenceRecord,
    index: usize,
    odds: AtOdds,
    left_out: &mut Vec<String>,
) -> Result<(), String> {
    let pair = [odds.psnr_pick.mode, odds.jod_pick.mode];
    if let Some(region) = &sequence.region {
        let animation = |id: &str| region.animations.get(id).cloned();
        let streams: Vec<(&str, Option<String>)> = std::iter::once((TRUTH_ID, animation("truth")))
            .chain(pair.iter().map(|m| (m.mode.as_str(), animation(&m.mode))))
            .collect();
        let _ = write!(
            page,
            "<p class=\"meta\">At the {0}×{0} square at ({1}, {2}) where the modes flicker most, ×{ZOOM}: the \
             truth and the two modes, then each mode's difference from the truth ×{ERROR_GAIN}, frame by frame.</p>\
             \n<div class=\"row crops\">",
            region.side, region.x, region.y
        );
        for (id, file) in &streams {
            if let Some(file) = file {
                zoomed(page, file, region.side, id);
            }
        }
        if let Some(truth) = &streams[0].1 {
            for (id, file) in streams[1..].iter().filter_map(|(id, f)| Some((*id, f.as_deref()?))) {
                let written = error_animation(run_dir, scene, index, id, [truth, file], sequence.time_step_s);
                match written {
                    Ok(error) => zoomed(page, &error, region.side, &format!("|{id} − truth| ×{ERROR_GAIN}")),
                    Err(reason) => left_out.push(format!("{}: {reason}", scene.name)),
                }
            }
        }
        page.push_str("</div>\n");
    }
    let maps: Vec<(&ModeRecord, &str, u32)> = pair
        .iter()
        .filter_map(|m| {
            let s = m.sequence_at(index)?;
            Some((*m, s.jod_map.as_deref()?, s.jod_worst_frame?))
        })
        .collect();
    if !maps.is_empty() {
        page.push_str("<div class=\"row\">");
        for (mode, map, frame) in maps {
            figure(page, map, &format!("{}: distortion at frame {frame}, its worst", mode.mode));
        }
        page.push_str("</div>\n");
    }
    Ok(())
}

/// A square animation, enlarged ×ZOOM, with its caption.
fn zoomed(page: &mut String, src: &str, side: u32, caption: &str) {
    let _ = write!(
        page,
        "<figure><img class=\"zoom\" src=\"{}\" width=\"{1}\" height=\"{1}\" alt=\"{2}\"><figcaption>{2}</figcaption></figure>",
        escape(src),
        side * ZOOM,
        escape(caption)
    );
}

/// Writes the animation of `|mode − truth| × ERROR_GAIN` from the two animations of the
/// square, as `report/<scene>/error-<n>-<mode>.png`; its path relative to the run folder.
fn error_animation(
    run_dir: &Path,
    scene: &SceneRecord,
    index: usize,
    mode: &str,
    [truth, file]: [&str; 2],
    delay_s: f64,
) -> Result<String, String> {
    let read = |relative: &str| {
        crate::files::images::read_apng(&run_dir.join(relative)).map_err(|e| format!("{e:#}"))
    };
    let (truth_frames, frames) = (read(truth)?, read(file)?);
    let same = truth_frames.len() == frames.len()
        && truth_frames.first().map(image::RgbaImage::dimensions)
            == frames.first().map(image::RgbaImage::dimensions);
    if !same || frames.is_empty() {
        return Err(format!("{file} and {truth} differ in frames or size: no error animation for {mode}"));
    }
    let (width, height) = frames[0].dimensions();
    let errors: Vec<Vec<u8>> = truth_frames.iter().zip(&frames).map(|(t, m)| amplified_error(t, m)).collect();
    let relative = Path::new("report").join(&scene.name).join(format!("error-{}-{mode}.png", index + 1));
    let path = run_dir.join(&relative);
    if let Some(folder) = path.parent() {
        std::fs::create_dir_all(folder).map_err(|e| format!("{}: {e}", folder.display()))?;
    }
    crate::files::images::write_apng(&path, width, height, &errors, delay_s).map_err(|e| format!("{e:#}"))?;
    Ok(relative.to_string_lossy().replace('\\', "/"))
}

/// `|mode − truth| × ERROR_GAIN` per colour channel of two frames of one size, opaque.
fn amplified_error(truth: &image::RgbaImage, mode: &image::RgbaImage) -> Vec<u8> {
    truth
        .pixels()
        .zip(mode.pixels())
        .flat_map(|(t, m)| {
            let channel = |c: usize| (f64::from(t[c].abs_diff(m[c])) * ERROR_GAIN).min(255.0) as u8;
            [channel(0), channel(1), channel(2), 255]
        })
        .collect()
}

/// Per scene and path, as Markdown rows: the two orders, their correlation, and the pair most
/// at odds with the sentence that explains it; `cell` escapes a cell's text.
pub(super) fn markdown(out: &mut String, scenes: &[SceneRecord], cell: fn(&str) -> String) {
    let mut rows = String::new();
    for scene in scenes {
        for (index, sequence) in scene.sequences.iter().enumerate() {
            let scored = scored(scene, index);
            if scored.len() < 2 {
                continue;
            }
            let [by_jod, by_psnr] = orders(&scored);
            let listed = |order: &[Scored], value: fn(&Scored) -> String| {
                order.iter().map(|s| format!("{} {}", s.mode.mode, value(s))).collect::<Vec<_>>().join(", ")
            };
            let odds = most_at_odds(&scored).map_or("they agree".into(), |odds| odds.explanation(index));
            let _ = writeln!(
                rows,
                "| {} | {} | {} | {} | {} | {} |",
                cell(&scene.name),
                cell(&sequence.speed()),
                cell(&listed(&by_jod, |s| SEQUENCE_JOD_VS_TRUTH.written(s.jod))),
                cell(&listed(&by_psnr, |s| SEQUENCE_PSNR_VS_TRUTH.written(s.psnr_db))),
                rank_correlation(&scored).map_or("–".into(), |r| format!("{r:.2}")),
                cell(&odds)
            );
        }
    }
    if rows.is_empty() {
        return;
    }
    let _ = write!(
        out,
        "\n### What a viewer sees against squared error\n\nAlong each path, the unstalled modes best first by \
         ColorVideoVDP's JOD and by mean PSNR (dB), Spearman's rank correlation of the two orders (ρ), and the \
         pair of modes they order most differently (by at least {JOD_MARGIN} JOD and {PSNR_MARGIN_DB} dB). \
         The HTML report animates that pair's error.\n\n| scene | path | by JOD | by PSNR | ρ | most at odds |\n\
         |---|---|---|---|---|---|\n{rows}"
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_amplified_error_is_the_difference_times_the_gain_clamped() {
        let truth = image::RgbaImage::from_raw(2, 1, vec![10, 20, 30, 255, 0, 0, 0, 255]).unwrap();
        let mode = image::RgbaImage::from_raw(2, 1, vec![12, 10, 30, 255, 200, 0, 0, 255]).unwrap();
        assert_eq!(amplified_error(&truth, &mode), vec![8, 40, 0, 255, 255, 0, 0, 255]);
    }

    /// A mode with one path along which its error has the flicker and the coarse share given.
    fn record(id: &str, flicker: f64, coarse_share: f64) -> ModeRecord {
        let along = serde_json::json!({
            "mse": [], "psnr_db": [], "mean_psnr_db": 30.0, "instability": 0.0, "hashes": [],
            "flicker": flicker, "coarse_share": coarse_share
        });
        let json = serde_json::json!({
            "mode": id, "m": 1, "stalled": false, "status": "ok", "passes": [], "images": {}, "sequences": [along]
        });
        serde_json::from_value(json).unwrap()
    }

    #[test]
    fn the_pair_most_at_odds_is_the_widest_opposite_one_beyond_both_margins() {
        let [sharp, blurred, near_sharp, best] =
            ["sharp", "blurred", "near-sharp", "best"].map(|id| record(id, 1e-4, 0.3));
        let scored = |mode, jod, psnr_db| Scored { mode, jod, psnr_db };
        let modes = [
            scored(&sharp, 5.0, 30.0),
            scored(&blurred, 6.5, 28.0),
            scored(&near_sharp, 5.05, 29.95),
            scored(&best, 9.0, 35.0),
        ];
        let odds = most_at_odds(&modes).unwrap();
        assert_eq!(
            (odds.psnr_pick.mode.mode.as_str(), odds.jod_pick.mode.mode.as_str()),
            ("sharp", "blurred")
        );
        // Orders that agree, and an opposite pair within a margin, are no disagreement.
        assert!(most_at_odds(&[modes[0], modes[3]]).is_none());
        assert!(most_at_odds(&[modes[0], modes[2]]).is_none(), "0.05 dB and 0.05 JOD apart");
        assert!(most_at_odds(&[scored(&sharp, 5.0, 30.0), scored(&blurred, 5.05, 28.0)]).is_none());
        let text = odds.explanation(0);
        let said = "PSNR prefers sharp (30.00 dB against 28.00); a viewer, by ColorVideoVDP, blurred (6.500 JOD against 5.000).";
        assert!(text.starts_with(said), "{text}");
        assert!(text.contains("Neither flicker nor"), "{text}");
    }

    #[test]
    fn the_explanation_reads_flicker_and_coarseness_from_the_record_as_their_rows_write_them() {
        let explain = |[flicker_a, coarse_a]: [f64; 2], [flicker_b, coarse_b]: [f64; 2]| {
            let (sharp, blurred) =
                (record("sharp", flicker_a, coarse_a), record("blurred", flicker_b, coarse_b));
            let odds = AtOdds {
                psnr_pick: Scored { mode: &sharp, jod: 5.0, psnr_db: 30.0 },
                jod_pick: Scored { mode: &blurred, jod: 6.5, psnr_db: 28.0 },
            };
            odds.explanation(0)
        };
        let coarser = explain([1e-4, 0.6], [1e-4, 0.2]);
        assert!(
            coarser.contains("sharp's error is coarser") && coarser.contains("60 % of its energy"),
            "{coarser}"
        );
        assert!(coarser.contains("against 20 % of blurred's"), "{coarser}");
        assert!(
            !explain([1e-4, 0.2], [1e-4, 0.6]).contains("coarser"),
            "the JOD pick's coarser error explains nothing"
        );
        let shimmers = explain([3e-4, 0.2], [1e-4, 0.2]);
        let said = "sharp's error changes along the motion 3.0× as much as blurred's (flicker ×1e-4: 3.000 against 1.000)";
        assert!(shimmers.contains(said), "{shimmers}");
    }
}
