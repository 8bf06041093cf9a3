//! `-stable` adaptive modes: at a still camera they render the paper's frames bit for bit, and
//! when the camera moves their sample counts are their CPU twin's — the metric's count of this
//! frame combined by `StableCounts::next` with the count the pixel's surface had in the frame
//! before, found by reprojecting the pixel's nearest sample; and when an object moves before a
//! still camera, the same twin with the point's place in the frame before taken from the
//! object's track.

use crate::support;

use aabench_renderer::adaptive::STABLE_DEPTH_TOLERANCE;
use aabench_renderer::scene::Camera;
use aabench_renderer::{GBufferImages, SceneRenderer, StableCounts};
use glam::{DVec2, DVec3};
use support::{project, thin_renderer, unproject};

#[test]
fn at_a_still_camera_stable_modes_render_the_papers_frames_bit_for_bit() {
    let (mut renderer, _, _gpu) = thin_renderer(96, 64);
    for (paper, stable) in
        [("adaptive-4x4", "adaptive-4x4-stable"), ("adaptive-3x3-cells", "adaptive-3x3-cells-stable")]
    {
        let paper = renderer.prepare(paper.parse().unwrap()).unwrap();
        paper.render().unwrap();
        let expected = paper.read_images().unwrap();
        let stable = renderer.prepare(stable.parse().unwrap()).unwrap();
        assert!(
            stable.graph().passes.iter().any(|pass| pass == "count_history"),
            "{}: {:?}",
            stable.mode,
            stable.graph().passes
        );
        // The first frame after a reset has no history, the later ones the same camera's.
        stable.reset_history();
        for frame in 0..3 {
            stable.render().unwrap();
            let images = stable.read_images().unwrap();
            assert!(images.display == expected.display, "{} frame {frame}: display differs", stable.mode);
            assert_eq!(images.sample_counts, expected.sample_counts, "{} frame {frame}", stable.mode);
        }
    }
}

/// A window's depths as `evaluate_stable` reads them: its nearest sample (the first of the
/// smallest depth in row-major order; `None` where no surface covers the window) and its deepest
/// depth (`None` where a sample sees the background).
struct Window {
    nearest: Option<([u32; 2], f64)>,
    deepest: Option<f64>,
}

fn window(gbuffer: &GBufferImages, m: u32, pixel: [u32; 2]) -> Window {
    let mut w = Window { nearest: None, deepest: Some(0.0) };
    for i in 0..m * m {
        let texel = [pixel[0] * m + i % m, pixel[1] * m + i / m];
        let index = (texel[1] * gbuffer.width + texel[0]) as usize;
        // The background's depth reads back as the far plane's; its material says it is none.
        if gbuffer.normal_material[index][3] < 0.0 {
            w.deepest = None;
            continue;
        }
        let depth = gbuffer.depth[index];
        if w.nearest.is_none_or(|(_, d)| depth < d) {
            w.nearest = Some((texel, depth));
        }
        w.deepest = w.deepest.map(|d| d.max(depth));
    }
    w
}

/// Two frames of a `-stable` mode and what its CPU twin needs: the counts and G-buffer of the
/// frame before (the first after a reset) and of the frame, and the paper's counts of the frame.
struct TwoFrames {
    size: [u32; 2],
    m: u32,
    counts_before: Vec<u8>,
    gbuffer_before: GBufferImages,
    counts: Vec<u8>,
    gbuffer: GBufferImages,
    now: Vec<u8>,
}

/// What the twin found: pixels checked, those left out within a rounding hair of a boundary,
/// those holding a count above the metric's, those whose point was hidden the frame before,
/// and the largest motion in pixels.
#[derive(Debug, Default)]
struct Twin {
    checked: usize,
    near_a_boundary: usize,
    held: usize,
    hidden: usize,
    moved: f64,
}

/// Checks every pixel's count against the twin: the metric's count of this frame combined by
/// `StableCounts::next` with the count the pixel's surface had in the frame before, found where
/// `then_of` (a point's place and depth now, and the material there) says its point lay.
/// Windows without a surface reproject their first sample at the far plane `far`.
fn check_against_twin(
    frames: &TwoFrames,
    far: f64,
    then_of: impl Fn(DVec2, f64, f32) -> (DVec2, f64),
) -> Twin {
    let TwoFrames { size: [width, height], m, .. } = *frames;
    let rule = StableCounts::default();
    let tolerance = f64::from(STABLE_DEPTH_TOLERANCE);
    let mut twin = Twin::default();
    for y in 0..height {
        for x in 0..width {
            let p = (y * width + x) as usize;
            let (counts, now) = (&frames.counts, &frames.now);
            assert!(counts[p] >= now[p], "pixel ({x}, {y}): a count never falls below the metric's");
            let here = window(&frames.gbuffer, m, [x, y]);
            let (texel, depth) = here.nearest.unwrap_or(([x * m, y * m], far));
            let centre = DVec2::new(f64::from(texel[0]) + 0.5, f64::from(texel[1]) + 0.5) / f64::from(m);
            let material =
                frames.gbuffer.normal_material[(texel[1] * frames.gbuffer.width + texel[0]) as usize][3];
            let (then, depth_then) = then_of(centre, depth, material);
            twin.moved = twin.moved.max((then - centre).length());
            let inside =
                then.x >= 0.0 && then.y >= 0.0 && then.x < f64::from(width) && then.y < f64::from(height);
            let kept = inside.then(|| {
                let q = [then.x.floor() as u32, then.y.floor() as u32];
                (
                    f32::from(frames.counts_before[(q[1] * width + q[0]) as usize]),
                    window(&frames.gbuffer_before, m, q).deepest,
                )
            });
            // The point was hidden there where it lay deeper than every sample of that pixel;
            // the background is deeper than any.
            let seen = |deepest: Option<f64>| match (here.nearest, deepest) {
                (_, None) => true,
                (None, Some(_)) => false,
                (Some(_), Some(deepest)) => depth_then <= deepest * (1.0 + tolerance),
            };
            // Where the reprojection or the depth test lies within a rounding hair of a
            // boundary, f32 on the GPU and f64 here may fall on different sides.
            let hair = |v: f64| (v - v.round()).abs() < 1e-3;
            let depth_hair = |deepest: Option<f64>| {
                here.nearest.is_some()
                    && deepest.is_some_and(|d| (depth_then / d - 1.0 - tolerance).abs() < 1e-4)
            };
            if hair(then.x) || hair(then.y) || kept.is_some_and(|(_, deepest)| depth_hair(deepest)) {
                twin.near_a_boundary += 1;
                continue;
            }
            let history = kept.filter(|&(_, deepest)| seen(deepest)).map(|(count, _)| count);
            twin.hidden += usize::from(kept.is_some() && history.is_none());
            let expected = rule.next(m, f32::from(now[p]), history).ceil() as u8;
            assert_eq!(counts[p], expected, "pixel ({x}, {y}): metric {} history {history:?}", now[p]);
            twin.checked += 1;
            twin.held += usize::from(counts[p] > now[p]);
        }
    }
    eprintln!("{twin:?}");
    twin
}

/// Renders `stable` from a reset, lets `change` move the camera or the scene, and renders it
/// and `paper` again.
fn two_frames(
    renderer: &mut SceneRenderer,
    [stable, paper]: [&str; 2],
    size: [u32; 2],
    change: impl FnOnce(&mut SceneRenderer),
) -> TwoFrames {
    let stable = renderer.prepare(stable.parse().unwrap()).unwrap();
    let paper = renderer.prepare(paper.parse().unwrap()).unwrap();
    stable.reset_history();
    stable.render().unwrap();
    // The first frame after a reset takes the metric's counts alone: these are what it keeps.
    let counts_before = stable.read_sample_counts().unwrap().unwrap();
    let gbuffer_before = stable.read_gbuffer().unwrap();
    change(renderer);
    stable.render().unwrap();
    let counts = stable.read_sample_counts().unwrap().unwrap();
    let gbuffer = stable.read_gbuffer().unwrap();
    paper.render().unwrap();
    let now = paper.read_sample_counts().unwrap().unwrap();
    TwoFrames { size, m: 4, counts_before, gbuffer_before, counts, gbuffer, now }
}

#[test]
fn stable_counts_when_the_camera_moves_are_their_cpu_twins() {
    let (width, height) = (128u32, 96u32);
    let (mut renderer, before, _gpu) = thin_renderer(width, height);
    // The camera moves sideways: points move by up to a few pixels, each by its own amount, and
    // the fences uncover what lay behind them.
    let side = before.forward.cross(before.up).normalize();
    let after = Camera { position: before.position + side * 0.12, ..before };
    let frames = two_frames(&mut renderer, ["adaptive-4x4-stable", "adaptive-4x4"], [width, height], |r| {
        r.set_camera(&after).unwrap()
    });
    let size = DVec2::new(f64::from(width), f64::from(height));
    let twin = check_against_twin(&frames, after.far, |centre, depth, _| {
        project(&before, size, unproject(&after, size, centre, depth))
    });
    assert!(twin.moved > 1.0 && twin.moved < 8.0, "the camera moves points by a few pixels: {twin:?}");
    assert!(twin.near_a_boundary * 100 < twin.checked, "{twin:?}");
    assert!(twin.held > 100, "the history holds counts above the metric's: {twin:?}");
    assert!(twin.hidden >= 5, "the move uncovers surfaces: {twin:?}");
}

#[test]
fn stable_counts_when_an_object_moves_are_their_cpu_twins() {
    // The crossing scene's crate slides before a still camera: a point on the crate (or its
    // bars) lay where the crate's track was a frame before, every other point where it is.
    let (width, height) = (128u32, 96u32);
    let (mut renderer, camera, track, moving, _guard) = support::crossing_playing(width, height);
    let (t0, t1) = (0.0, 1.0 / 60.0);
    renderer.pose(t0, t0).unwrap();
    let frames = two_frames(&mut renderer, ["adaptive-4x4-stable", "adaptive-4x4"], [width, height], |r| {
        r.pose(t1, t0).unwrap()
    });
    let [x0, y0, z0, _] = track.sample(t0);
    let [x1, y1, z1, _] = track.sample(t1);
    let slide = DVec3::new(x1 - x0, y1 - y0, z1 - z0);
    let size = DVec2::new(f64::from(width), f64::from(height));
    let twin = check_against_twin(&frames, camera.far, |centre, depth, material| {
        let point = unproject(&camera, size, centre, depth);
        let before = if moving.contains(&material) { point - slide } else { point };
        project(&camera, size, before)
    });
    assert!(twin.moved > 1.0 && twin.moved < 4.0, "the crate moves about 2 px a frame: {twin:?}");
    assert!(twin.near_a_boundary * 100 < twin.checked, "{twin:?}");
    assert!(twin.held > 20, "the history holds counts above the metric's: {twin:?}");
    assert!(twin.hidden >= 5, "the crate uncovers the wall: {twin:?}");
}
