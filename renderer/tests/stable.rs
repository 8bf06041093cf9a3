//! `-stable` adaptive modes: at a still camera they render the paper's frames bit for bit, and
//! when the camera moves their sample counts are their CPU twin's — the metric's count of this
//! frame combined by `StableCounts::next` with the count the pixel's surface had in the frame
//! before, found by reprojecting the pixel's nearest sample.

mod support;

use aabench_renderer::adaptive::STABLE_DEPTH_TOLERANCE;
use aabench_renderer::scene::Camera;
use aabench_renderer::{GBufferImages, StableCounts};
use glam::DVec2;
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

#[test]
fn stable_counts_when_the_camera_moves_are_their_cpu_twins() {
    let (width, height, m) = (128u32, 96u32, 4u32);
    let (mut renderer, before, _gpu) = thin_renderer(width, height);
    let stable = renderer.prepare("adaptive-4x4-stable".parse().unwrap()).unwrap();
    let paper = renderer.prepare("adaptive-4x4".parse().unwrap()).unwrap();
    stable.reset_history();
    stable.render().unwrap();
    // The first frame after a reset takes the metric's counts alone: these are what it keeps.
    let counts_before = stable.read_sample_counts().unwrap().unwrap();
    let gbuffer_before = stable.read_gbuffer().unwrap();

    // The camera moves sideways: points move by up to a few pixels, each by its own amount, and
    // the fences uncover what lay behind them.
    let side = before.forward.cross(before.up).normalize();
    let after = Camera { position: before.position + side * 0.12, ..before };
    renderer.set_camera(&after).unwrap();
    stable.render().unwrap();
    let counts = stable.read_sample_counts().unwrap().unwrap();
    let gbuffer = stable.read_gbuffer().unwrap();
    paper.render().unwrap();
    let now = paper.read_sample_counts().unwrap().unwrap();

    let rule = StableCounts::default();
    let size = DVec2::new(f64::from(width), f64::from(height));
    let tolerance = f64::from(STABLE_DEPTH_TOLERANCE);
    let (mut checked, mut near_a_boundary, mut held, mut hidden, mut moved) = (0, 0, 0, 0, 0.0f64);
    for y in 0..height {
        for x in 0..width {
            let p = (y * width + x) as usize;
            assert!(counts[p] >= now[p], "pixel ({x}, {y}): a count never falls below the metric's");
            // A window without a surface reprojects its first sample at the far plane.
            let here = window(&gbuffer, m, [x, y]);
            let (texel, depth) = here.nearest.unwrap_or(([x * m, y * m], after.far));
            let centre = DVec2::new(f64::from(texel[0]) + 0.5, f64::from(texel[1]) + 0.5) / f64::from(m);
            let (then, depth_then) = project(&before, size, unproject(&after, size, centre, depth));
            moved = moved.max((then - centre).length());
            let inside = then.x >= 0.0 && then.y >= 0.0 && then.x < size.x && then.y < size.y;
            let kept = inside.then(|| {
                let q = [then.x.floor() as u32, then.y.floor() as u32];
                (
                    f32::from(counts_before[(q[1] * width + q[0]) as usize]),
                    window(&gbuffer_before, m, q).deepest,
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
                near_a_boundary += 1;
                continue;
            }
            let history = kept.filter(|&(_, deepest)| seen(deepest)).map(|(count, _)| count);
            hidden += usize::from(kept.is_some() && history.is_none());
            let expected = rule.next(m, f32::from(now[p]), history).ceil() as u8;
            assert_eq!(counts[p], expected, "pixel ({x}, {y}): metric {} history {history:?}", now[p]);
            checked += 1;
            held += usize::from(counts[p] > now[p]);
        }
    }
    eprintln!(
        "{checked} pixels checked, {near_a_boundary} within a hair of a boundary, {held} holding a count \
         above the metric's, {hidden} whose point was hidden the frame before, largest motion {moved:.2} px"
    );
    assert!(moved > 1.0 && moved < 8.0, "the camera moves points by a few pixels: {moved}");
    assert!(near_a_boundary * 100 < checked, "{near_a_boundary} of {checked} near a boundary");
    assert!(held > 100, "the history holds counts above the metric's on {held} pixels");
    assert!(hidden >= 5, "the move uncovers surfaces on {hidden} pixels");
}
