//! Flicker along the truth's motion, fed the cases that would fool a temporal measure, each on
//! a real path rendered on lavapipe: the `thin` scene (wires, fine stripes and checks) under a
//! pan of four pixels a frame, its truth at 8×8 and its geometry from the renderer's probe.
//!
//! (a) The truth's first frame, frozen, flickers far more than reference-4x4: an image that
//!     stays put while the scene moves is not steady. (b) The truth blurred (σ = 1.5 px) adds
//!     no flicker beyond the truth's own change along the motion (what a black image scores:
//!     the truth's fine stripes and checks alias into moiré that no interpolation predicts),
//!     and its error per frame is far worse than deferred-1x1's: blur is steady, and the error
//!     says what it costs. (c) The truth moved by a random sub-pixel offset each frame flickers
//!     far more than reference-4x4, and more than the blur (without motion compensation the
//!     blur, whose whole image moves, would score four times the shake). (d) deferred-1x1 flickers more than reference-4x4. (e) TAA
//!     whose history does not follow motion flickers more than TAA.
//!
//! Under a pan of an eighth of a pixel a frame, flicker still ranks the frozen frame below
//! reference-4x4. Every case's numbers are printed, with the measure without motion
//! compensation (`instability`) beside.

use crate::support;

use aabench::manifest::motion::MotionSpec;
use aabench::measure::temporal::{self, Flow, Geometry, PairError};
use aabench_renderer::scene::Camera;
use aabench_renderer::scene::generate::Generator;
use aabench_renderer::{DisplayImage, PreparedMode, SceneRenderer};

const WIDTH: u32 = 128;
const HEIGHT: u32 = 96;
const FRAMES: usize = 6;
/// The pans' speeds: the middle of the view moves this many pixels a frame.
const TYPICAL: f64 = 4.0;
const SLOW: f64 = 0.125;

/// The `thin` scene under the default rig, on a renderer of its own, and its camera.
fn thin() -> (SceneRenderer, Camera) {
    let scene = support::generated_scene(Generator::Thin);
    let mut camera = scene.camera.expect("generated scenes carry a camera");
    camera.far = camera.far.min(500.0);
    (support::plain_renderer(&scene, &camera, [WIDTH, HEIGHT], 0.05), camera)
}

/// The pan's cameras: the view turning about the up axis, the middle of the view moving
/// `pixels_per_frame`, as a manifest states it.
fn cameras(base: &Camera, pixels_per_frame: f64) -> Vec<Camera> {
    let speeds = serde_json::json!({"quick": [pixels_per_frame], "nightly": [pixels_per_frame]});
    let spec: MotionSpec =
        serde_json::from_value(serde_json::json!({"path": "pan", "pixels_per_frame": speeds})).unwrap();
    spec.check().unwrap();
    let [pace] = spec.paces(Some(&[pixels_per_frame]), base.fov_y, HEIGHT)[..] else { panic!("one pace") };
    let timeline = spec.timeline(0, None);
    spec.cameras(base, 5.0, &timeline, timeline.frames(FRAMES as u32), pace.rate).unwrap()
}

/// Renders `mode` along the path: the first frame as a still (a temporal mode's warm-up), the
/// others one frame each.
fn along(renderer: &mut SceneRenderer, path: &[Camera], mode: &PreparedMode) -> Vec<DisplayImage> {
    path.iter()
        .enumerate()
        .map(|(frame, camera)| {
            renderer.set_camera(camera).unwrap();
            if frame == 0 { mode.render_still() } else { mode.render() }.unwrap();
            mode.read_display().unwrap()
        })
        .collect()
}

/// A display image's pixel (x, y), channel c, clamped to the frame, as a value in [0, 255].
fn at(image: &DisplayImage, x: i64, y: i64, c: usize) -> f64 {
    let (x, y) = (x.clamp(0, i64::from(WIDTH) - 1), y.clamp(0, i64::from(HEIGHT) - 1));
    f64::from(image.rgba[4 * (y * i64::from(WIDTH) + x) as usize + c])
}

/// `image` with each value from `value(x, y, c)`, rounded.
fn remap(image: &DisplayImage, value: impl Fn(i64, i64, usize) -> f64) -> DisplayImage {
    let mut out = image.clone();
    for (i, pixel) in out.rgba.chunks_exact_mut(4).enumerate() {
        let (x, y) = ((i % WIDTH as usize) as i64, (i / WIDTH as usize) as i64);
        for (c, v) in pixel[..3].iter_mut().enumerate() {
            *v = value(x, y, c).round().clamp(0.0, 255.0) as u16;
        }
    }
    out
}

/// `image` blurred by a Gaussian of `sigma` pixels, edges clamped.
fn blurred(image: &DisplayImage, sigma: f64) -> DisplayImage {
    let radius = (3.0 * sigma).ceil() as i64;
    let weights: Vec<f64> =
        (-radius..=radius).map(|d| (-(d * d) as f64 / (2.0 * sigma * sigma)).exp()).collect();
    let total: f64 = weights.iter().sum();
    let pass = |image: &DisplayImage, dx: i64, dy: i64| {
        remap(image, |x, y, c| {
            (-radius..=radius)
                .zip(&weights)
                .map(|(d, w)| w * at(image, x + d * dx, y + d * dy, c))
                .sum::<f64>()
                / total
        })
    };
    pass(&pass(image, 1, 0), 0, 1)
}

/// `image` moved by (dx, dy) pixels, resampled bilinearly.
fn shifted(image: &DisplayImage, [dx, dy]: [f64; 2]) -> DisplayImage {
    remap(image, |x, y, c| {
        let (sx, sy) = (x as f64 - dx, y as f64 - dy);
        let (x0, y0) = (sx.floor(), sy.floor());
        let (fx, fy) = (sx - x0, sy - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        (1.0 - fy) * ((1.0 - fx) * at(image, x0, y0, c) + fx * at(image, x0 + 1, y0, c))
            + fy * ((1.0 - fx) * at(image, x0, y0 + 1, c) + fx * at(image, x0 + 1, y0 + 1, c))
    })
}

/// A mode's frames measured against the truth's: flicker along the flows, the mean MSE per frame
/// and the uncompensated change of error (`instability`).
#[derive(Debug)]
struct Measured {
    flicker: f64,
    mse: f64,
    instability: f64,
}

fn measure(frames: &[DisplayImage], truth: &[DisplayImage], flows: &[Flow]) -> Measured {
    let mut sums = PairError::default();
    let mut map = vec![0.0; (WIDTH * HEIGHT) as usize];
    let value = |v: u16| f64::from(v) / 255.0;
    let (mut mse, mut instability) = (0.0, 0.0);
    for f in 0..frames.len() {
        let pairs = frames[f].rgba.chunks_exact(4).zip(truth[f].rgba.chunks_exact(4));
        mse += pairs.flat_map(|(a, t)| (0..3).map(move |c| (value(a[c]) - value(t[c])).powi(2))).sum::<f64>();
        if f > 0 {
            sums.add(&flows[f - 1].error([&frames[f], &truth[f]], [&frames[f - 1], &truth[f - 1]], &mut map));
            let changes = aabench::measure::temporal::pixel_changes_of_error(
                &frames[f].rgba,
                &frames[f - 1].rgba,
                &truth[f].rgba,
                &truth[f - 1].rgba,
            );
            instability += changes.map(|v| v as f64 / 255.0 / 255.0).sum::<f64>();
        }
    }
    let values = f64::from(WIDTH * HEIGHT * 3);
    Measured {
        flicker: temporal::mean(sums.flicker).unwrap(),
        mse: mse / values / frames.len() as f64,
        instability: instability / values / (frames.len() - 1) as f64,
    }
}

/// Every case along one path: the modes rendered, and the truth frozen, black, blurred and
/// moved at random.
struct Cases {
    deferred: Measured,
    reference: Measured,
    taa: Measured,
    unreprojected: Measured,
    frozen: Measured,
    steady: Measured,
    blur: Measured,
    jittered: Measured,
}

/// The truth and the geometry of every frame along `path`.
fn truth_along(renderer: &mut SceneRenderer, path: &[Camera]) -> (Vec<DisplayImage>, Vec<Geometry>) {
    let probe = renderer.prepare_geometry().unwrap();
    let (mut truth, mut geometry) = (Vec::new(), Vec::new());
    for (frame, camera) in path.iter().enumerate() {
        renderer.set_camera(camera).unwrap();
        truth.push(renderer.render_truth(8, 256 << 20).unwrap().images.display);
        if frame == 0 { probe.render_still() } else { probe.render() }.unwrap();
        let gbuffer = probe.read_gbuffer().unwrap();
        let motion = probe.read_motion().unwrap().unwrap();
        let then = &path[frame.saturating_sub(1)];
        geometry.push(Geometry::from_probe(&gbuffer, &motion, [camera, then]));
    }
    (truth, geometry)
}

/// Measures every case along a pan at `pixels_per_frame`, and prints the numbers.
fn cases(renderer: &mut SceneRenderer, base: &Camera, pixels_per_frame: f64) -> Cases {
    let path = cameras(base, pixels_per_frame);
    let (truth, geometry) = truth_along(renderer, &path);
    let flows: Vec<Flow> = (1..FRAMES).map(|f| Flow::between(&geometry[f], &geometry[f - 1])).collect();
    let middle = (WIDTH / 2 + HEIGHT / 2 * WIDTH) as usize;
    let moved = f64::from(geometry[1].motion[middle][0]).hypot(f64::from(geometry[1].motion[middle][1]));
    assert!((moved / pixels_per_frame - 1.0).abs() < 0.1, "the middle moved {moved} pixels a frame");

    let mut rendered = |id: &str, broken: bool| {
        let prepared = renderer.prepare(id.parse().unwrap()).unwrap();
        let prepared = if broken { prepared.without_reprojection() } else { prepared };
        let frames = along(renderer, &path, &prepared);
        measure(&frames, &truth, &flows)
    };
    let (deferred, reference) = (rendered("deferred-1x1", false), rendered("reference-4x4", false));
    let (taa, unreprojected) = (rendered("taa", false), rendered("taa", true));
    // A fixed sequence of offsets within ±½ pixel (a linear congruential generator).
    let mut seed = 12345u64;
    let mut offset = || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let jittered: Vec<DisplayImage> = truth.iter().map(|t| shifted(t, [offset(), offset()])).collect();
    let blur: Vec<DisplayImage> = truth.iter().map(|t| blurred(t, 1.5)).collect();
    let cases = Cases {
        deferred,
        reference,
        taa,
        unreprojected,
        frozen: measure(&vec![truth[0].clone(); FRAMES], &truth, &flows),
        // A black image's error is the truth itself: its flicker is the truth's own change
        // along the motion, what an image that does not follow the truth's moiré scores.
        steady: measure(&vec![remap(&truth[0], |_, _, _| 0.0); FRAMES], &truth, &flows),
        blur: measure(&blur, &truth, &flows),
        jittered: measure(&jittered, &truth, &flows),
    };
    eprintln!("a pan of {pixels_per_frame} pixels a frame:");
    for (name, m) in [
        ("deferred-1x1", &cases.deferred),
        ("reference-4x4", &cases.reference),
        ("taa", &cases.taa),
        ("taa, history not reprojected", &cases.unreprojected),
        ("the truth's first frame, frozen", &cases.frozen),
        ("black: the truth's own change", &cases.steady),
        ("the truth blurred, σ = 1.5 px", &cases.blur),
        ("the truth moved by random sub-pixel offsets", &cases.jittered),
    ] {
        eprintln!(
            "{name:>44}: flicker {:.3e}  MSE {:.3e}  instability {:.3e}",
            m.flicker, m.mse, m.instability
        );
    }
    cases
}

#[test]
fn flicker_is_not_fooled_by_a_frozen_frame_blur_or_a_history_that_does_not_follow_motion() {
    let (mut renderer, base) = thin();
    let Cases { deferred, reference, taa, unreprojected, frozen, steady, blur, jittered } =
        cases(&mut renderer, &base, TYPICAL);
    // (a)
    assert!(frozen.flicker > 10.0 * reference.flicker, "a frozen frame: {frozen:?} vs {reference:?}");
    // (b) Blur adds no flicker beyond the truth's own change, and its error shows what it costs.
    assert!(blur.flicker <= steady.flicker, "blur: {blur:?} vs the truth's own {steady:?}");
    assert!(blur.mse > 3.0 * deferred.mse, "blur's error is worse: {blur:?} vs {deferred:?}");
    // (c) And more than the steady blur: without motion compensation the blur, whose whole
    // image moves 4 pixels a frame, would score four times the random shake.
    assert!(jittered.flicker > 4.0 * reference.flicker, "random offsets: {jittered:?} vs {reference:?}");
    assert!(jittered.flicker > blur.flicker, "random offsets: {jittered:?} vs blur {blur:?}");
    // (d)
    assert!(deferred.flicker > 2.0 * reference.flicker, "{deferred:?} vs {reference:?}");
    // (e)
    assert!(unreprojected.flicker > 2.0 * taa.flicker, "{unreprojected:?} vs {taa:?}");

    // Slowly, a frozen frame drifts by an eighth of a pixel a frame, and changes little from one
    // frame to the next: flicker still ranks it below reference-4x4.
    let slow = cases(&mut renderer, &base, SLOW);
    assert!(slow.frozen.flicker > 1.5 * slow.reference.flicker, "{:?} vs {:?}", slow.frozen, slow.reference);
    assert!(
        slow.deferred.flicker > 2.0 * slow.reference.flicker,
        "{:?} vs {:?}",
        slow.deferred,
        slow.reference
    );
}
