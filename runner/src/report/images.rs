//! The report's images: each scene's modes and their differences, crops where adaptive differs
//! most from the truth, and the square where the modes flicker most along the camera path.

use std::fmt::Write;
use std::path::Path;

use aabench_renderer::{Mode, Technique};

use super::html::escape;
use super::{CROP, ZOOM};
use crate::record::{ModeRecord, RunRecord, SceneRecord};
use crate::run::truth::TRUTH_ID;

/// A copy of `run` without the images that are not files in its folder (a folder or nothing
/// where an image should be), so that the page links only what opens, and a line for each.
pub(super) fn without_missing_images(run_dir: &Path, run: &RunRecord) -> (RunRecord, Vec<String>) {
    let mut run = run.clone();
    let mut left_out = Vec::new();
    for scene in &mut run.scenes {
        let truth = scene.truth.as_mut().map(|truth| &mut truth.image);
        let modes = scene.modes.iter_mut().flat_map(|mode| {
            let images = &mut mode.images;
            [
                &mut images.display,
                &mut images.hdr,
                &mut images.samples,
                &mut images.difference,
                &mut images.flip,
            ]
        });
        for slot in truth.into_iter().chain(modes) {
            let Some(path) = slot.as_deref().map(|relative| run_dir.join(relative)) else { continue };
            if !path.is_file() {
                let what = if path.is_dir() { "a folder" } else { "nothing" };
                left_out.push(format!(
                    "{}: {}: {what} where an image should be: left out",
                    scene.name,
                    path.display()
                ));
                *slot = None;
            }
        }
    }
    (run, left_out)
}

/// A mode's FLIP error map against the truth, where it has one.
fn flip_figure(page: &mut String, mode: Option<&ModeRecord>) {
    if let Some((mode, image)) = mode.and_then(|m| Some((m, m.images.flip.as_deref()?))) {
        figure(page, image, &format!("{}: FLIP against the truth (0 black to 1 yellow)", mode.mode));
    }
}

/// The truth and the one-sample modes, then per M the reference, adaptive and its variants and
/// the other modes compared with the reference: their images, differences, FLIP maps and sample
/// counts, and 1:1 crops around adaptive's largest error against the truth.
pub(super) fn images(
    page: &mut String,
    run_dir: &Path,
    scene: &SceneRecord,
    left_out: &mut Vec<String>,
) -> Result<(), String> {
    page.push_str("<h3>Images</h3>\n<div class=\"row\">");
    if let Some(image) = scene.truth.as_ref().and_then(|t| t.image.as_deref()) {
        figure(page, image, TRUTH_ID);
    }
    one_sample_row(page, scene);
    page.push_str("</div>\n");
    for m in 2..=4 {
        supersampled_row(page, run_dir, scene, m, left_out)?;
    }
    Ok(())
}

/// deferred-1x1 and the modes that post-process or blend its image (FXAA, SMAA, TAA): their
/// images, the pixels each changed, and their FLIP maps.
fn one_sample_row(page: &mut String, scene: &SceneRecord) {
    let deferred = Mode::new(Technique::Deferred, 1, false);
    let refined = Technique::COMPARED.into_iter().filter(|t| t.compared_with() == Some(Technique::Deferred));
    let shown: Vec<(Technique, &ModeRecord)> = std::iter::once(Technique::Deferred)
        .chain(refined)
        .filter_map(|technique| Some((technique, scene.mode_of(Mode::new(technique, 1, false))?)))
        .collect();
    for (_, mode) in &shown {
        if let Some(image) = &mode.images.display {
            figure(page, image, &mode.mode);
        }
    }
    // deferred-1x1's own difference is against the truth; the others' show what they changed.
    for (technique, mode) in shown.iter().filter(|(technique, _)| *technique != Technique::Deferred) {
        if let Some(image) = &mode.images.difference {
            let caption = format!(
                "|{} − {deferred}|: the pixels {} changed (32 steps full scale)",
                mode.mode,
                technique.label()
            );
            figure(page, image, &caption);
        }
    }
    for (_, mode) in &shown {
        flip_figure(page, Some(mode));
    }
}

/// The row of M: the reference, the adaptive modes (the paper's and its reconstructions) and the
/// other modes compared with the reference (4× MSAA at 2×2), each unstalled where the run has it
/// (stalling changes the time, not the image); then the crops.
fn supersampled_row(
    page: &mut String,
    run_dir: &Path,
    scene: &SceneRecord,
    m: u32,
    left_out: &mut Vec<String>,
) -> Result<(), String> {
    let pick = |mode: Mode| scene.mode_of(mode).or_else(|| scene.mode_of(Mode { stalled: true, ..mode }));
    let reference = pick(Mode::new(Technique::Reference, m, false));
    let [adaptive, area, cells, coverage] = super::reconstructions(m).map(pick);
    let others: Vec<&ModeRecord> = Technique::COMPARED
        .into_iter()
        .filter(|t| t.compared_with() == Some(Technique::Reference) && t.sizes().contains(&m))
        .filter_map(|t| pick(Mode::new(t, m, false)))
        .collect();
    let adaptives: Vec<&ModeRecord> = [adaptive, area, cells, coverage].into_iter().flatten().collect();
    let compared: Vec<&ModeRecord> = adaptives.iter().copied().chain(others.iter().copied()).collect();
    if reference.is_none() && compared.is_empty() {
        return Ok(());
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
    // The area variant takes the paper's samples: one heatmap serves both; cells, coverage and
    // the others take their own.
    let counted = [adaptive.or(area), cells, coverage].into_iter().flatten().chain(others.iter().copied());
    for mode in counted {
        if let Some(image) = &mode.images.samples {
            figure(page, image, &format!("{}: samples per pixel, 1 (dark) to {} (red)", mode.mode, m * m));
        }
    }
    page.push_str("</div>\n");
    // The crops sit where adaptive differs most from the truth, so only a run with an adaptive
    // mode at this M has them.
    if let Some(&worst) = adaptives.first() {
        let shown: Vec<&ModeRecord> = reference.iter().copied().chain(compared.iter().copied()).collect();
        crops(page, run_dir, scene, m, &shown, worst, left_out)?;
    }
    Ok(())
}

pub(super) fn figure(page: &mut String, src: &str, caption: &str) {
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
        crate::files::images::write_png(&run_dir.join(&relative), side, side, crop.as_raw())
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
pub(super) fn flicker_region(
    page: &mut String,
    run_dir: &Path,
    scene: &SceneRecord,
    left_out: &mut Vec<String>,
) -> Result<(), String> {
    let Some(sequence) = scene.sequence() else { return Ok(()) };
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
        match strip(run_dir, &folder, id, animation, first..first + count) {
            Ok((relative, width, height)) => {
                let _ = writeln!(
                    page,
                    "<tr><td>{}</td><td><img class=\"zoom\" src=\"{}\" width=\"{}\" height=\"{}\" alt=\"{0} frames {first}–{}\"></td></tr>",
                    escape(id),
                    escape(&relative),
                    width * 2,
                    height * 2,
                    first + count - 1
                );
            }
            Err(Strip::LeftOut(reason)) => {
                let reason = format!("{}: {reason}", scene.name);
                let _ = writeln!(page, "<tr><td>{}</td><td>{}</td></tr>", escape(id), escape(&reason));
                left_out.push(reason);
            }
            Err(Strip::Failed(error)) => return Err(error),
        }
    }
    page.push_str("</tbody></table>\n");
    Ok(())
}

/// Each mode's distortion map along the scene's first path: the frame where ColorVideoVDP
/// found it furthest from the truth, where the run wrote one.
pub(super) fn jod_maps(page: &mut String, scene: &SceneRecord) {
    let maps: Vec<(&str, &str, u32)> = scene
        .modes
        .iter()
        .filter_map(|mode| {
            let sequence = mode.sequence_at(0)?;
            Some((mode.mode.as_str(), sequence.jod_map.as_deref()?, sequence.jod_worst_frame?))
        })
        .collect();
    if maps.is_empty() {
        return;
    }
    page.push_str(
        "<h3>Where a viewer sees the difference</h3>\n<p class=\"meta\">Per mode, ColorVideoVDP's \
         distortion map of the path's frame it found furthest from the truth: black where no \
         difference shows, yellow at 10 JOD below the truth or more.</p>\n<div class=\"row\">",
    );
    for (mode, map, frame) in maps {
        figure(page, map, &format!("{mode}, frame {frame}"));
    }
    page.push_str("</div>\n");
}

/// Why a strip is missing: its animation cannot give it (the page says so), or it could not be
/// written (the report fails).
enum Strip {
    LeftOut(String),
    Failed(String),
}

/// Writes the strip of `frames` of a stream's animation under `folder` of the run: its path
/// relative to the run's folder and its size.
fn strip(
    run_dir: &Path,
    folder: &Path,
    id: &str,
    animation: &str,
    frames: std::ops::Range<u32>,
) -> Result<(String, u32, u32), Strip> {
    let all = crate::files::images::read_apng(&run_dir.join(animation))
        .map_err(|e| Strip::LeftOut(format!("{e:#}")))?;
    if all.len() < frames.end as usize {
        let reason = format!("{animation} has {} frames, the strip needs {}", all.len(), frames.end);
        return Err(Strip::LeftOut(reason));
    }
    let strip = side_by_side(&all[frames.start as usize..frames.end as usize], 1, 1);
    let relative = folder.join(format!("strip-{id}.png"));
    crate::files::images::write_png(&run_dir.join(&relative), strip.width(), strip.height(), strip.as_raw())
        .map_err(|e| Strip::Failed(format!("{e:#}")))?;
    Ok((relative.to_string_lossy().replace('\\', "/"), strip.width(), strip.height()))
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
    crate::files::images::largest_window(&errors, a.width(), a.height(), side)
}
