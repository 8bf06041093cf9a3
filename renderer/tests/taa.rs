//! TAA: motion vectors that reproject each pixel to where its point was (the camera's motion,
//! and a moving object's own, in a jittered frame), a history that belongs to its mode alone,
//! and an image that converges below deferred-1x1's error on a still camera.

use crate::support;

use aabench_renderer::scene::Camera;
use aabench_renderer::{DisplayImage, GBufferImages, taa};
use glam::{DVec2, DVec3};
use support::{project, thin_renderer, unproject};

#[test]
fn motion_vectors_reproject_each_pixel_to_where_its_point_was_within_a_sixteenth_of_a_pixel() {
    let (width, height) = (128u32, 96u32);
    let (mut renderer, before, _gpu) = thin_renderer(width, height);
    let taa = renderer.prepare("taa".parse().unwrap()).expect("prepare taa");
    let deferred = renderer.prepare("deferred-1x1".parse().unwrap()).expect("prepare deferred");
    assert!(deferred.read_motion().unwrap().is_none(), "only temporal modes write motion");
    let motion_target = |mode: &aabench_renderer::PreparedMode| {
        mode.graph().allocations.iter().any(|a| a.holds.iter().any(|port| port == "gbuffer.gb_motion"))
    };
    assert!(motion_target(&taa) && !motion_target(&deferred), "only the graphs that read motion write it");

    // The camera moves sideways and turns a little: points move by a few pixels, each by its
    // own amount (parallax).
    let side = before.forward.cross(before.up).normalize();
    let after = Camera {
        position: before.position + side * 0.15,
        forward: before.forward + before.up * 0.02,
        ..before
    };
    taa.reset_history();
    taa.render().unwrap();
    renderer.set_camera(&after).unwrap();
    taa.render().unwrap();
    let motion = taa.read_motion().unwrap().expect("taa writes motion");
    let gbuffer = taa.read_gbuffer().unwrap();

    let size = DVec2::new(f64::from(width), f64::from(height));
    let (checked, worst, largest) = check_motion(&motion, &gbuffer, |sample, depth, _| {
        project(&before, size, unproject(&after, size, sample, depth))
    });
    assert!(checked > (width * height) as usize / 2, "only {checked} pixels see geometry");
    assert!(largest > 2.0, "the points moved at most {largest} pixels: the test moves too little");
    eprintln!("{checked} pixels, moved up to {largest:.2} px, reprojected within {worst:.5} px");
}

/// Checks each covered pixel's motion vector (of a frame jittered by `taa::jitter(1)`) against
/// its sample's point: where `then_of` (the sample's place and depth now, and its material)
/// says the point lay in the frame before, and its depth then. Returns the pixels checked, the
/// largest error and the largest motion, in pixels.
fn check_motion(
    motion: &[[f32; 4]],
    gbuffer: &GBufferImages,
    mut then_of: impl FnMut(DVec2, f64, f32) -> (DVec2, f64),
) -> (usize, f64, f64) {
    let [jx, jy] = taa::jitter(1);
    let (mut checked, mut worst, mut largest) = (0, 0.0f64, 0.0f64);
    for y in 0..gbuffer.height {
        for x in 0..gbuffer.width {
            let i = (y * gbuffer.width + x) as usize;
            let material = gbuffer.normal_material[i][3];
            if material < 0.0 {
                continue;
            }
            // The frame's sample lies at the pixel's centre plus the jitter.
            let sample = DVec2::new(f64::from(x) + 0.5 + jx, f64::from(y) + 0.5 + jy);
            let (then, depth_then) = then_of(sample, gbuffer.depth[i], material);
            let expected = sample - then;
            let [mx, my, mz, _] = motion[i].map(f64::from);
            let error = (DVec2::new(mx, my) - expected).length();
            assert!(
                error <= 1.0 / 16.0,
                "pixel ({x}, {y}): motion ({mx}, {my}), its point moved {expected}: {error} pixels apart"
            );
            assert!(
                (mz - depth_then).abs() <= 1e-3 * depth_then,
                "pixel ({x}, {y}): depth then {mz} vs {depth_then}"
            );
            checked += 1;
            worst = worst.max(error);
            largest = largest.max(expected.length());
        }
    }
    (checked, worst, largest)
}

#[test]
fn jittered_motion_vectors_hold_a_moving_objects_own_motion() {
    // The crossing scene's crate slides before a still camera: TAA's jittered frame holds, on
    // the crate and its bars, the projection of the crate's slide since the frame before, and
    // zero on the wall.
    let (width, height) = (128u32, 96u32);
    let (mut renderer, camera, track, moving, _guard) = support::crossing_playing(width, height);
    let taa = renderer.prepare("taa".parse().unwrap()).unwrap();
    let (t0, t1) = (0.0, 1.0 / 60.0);
    taa.reset_history();
    renderer.pose(t0, t0).unwrap();
    taa.render().unwrap();
    renderer.pose(t1, t0).unwrap();
    taa.render().unwrap();
    let motion = taa.read_motion().unwrap().expect("taa writes motion");
    let gbuffer = taa.read_gbuffer().unwrap();
    let [x0, y0, z0, _] = track.sample(t0);
    let [x1, y1, z1, _] = track.sample(t1);
    let slide = DVec3::new(x1 - x0, y1 - y0, z1 - z0);
    let size = DVec2::new(f64::from(width), f64::from(height));
    let (mut on_crate, mut still) = (0, 0);
    let (checked, worst, largest) = check_motion(&motion, &gbuffer, |sample, depth, material| {
        let point = unproject(&camera, size, sample, depth);
        let moves = moving.contains(&material);
        if moves {
            on_crate += 1
        } else {
            still += 1
        }
        project(&camera, size, if moves { point - slide } else { point })
    });
    eprintln!(
        "{checked} pixels ({on_crate} on the crate), moved up to {largest:.2} px, within {worst:.5} px"
    );
    assert!(on_crate > 200 && still > 2000, "the crate and the wall are both in view: {on_crate}, {still}");
    assert!(largest > 1.5 && largest < 4.0, "the crate moves about 2 px a frame: {largest}");
}

/// Mean squared error of two display images in [0, 1] units.
fn mse(a: &DisplayImage, b: &DisplayImage) -> f64 {
    let scale = f64::from(a.max_code());
    let sum: f64 = a
        .rgba
        .chunks_exact(4)
        .zip(b.rgba.chunks_exact(4))
        .flat_map(|(p, q)| (0..3).map(move |c| ((f64::from(p[c]) - f64::from(q[c])) / scale).powi(2)))
        .sum();
    sum / (a.rgba.len() / 4 * 3) as f64
}

#[test]
fn taa_converges_below_deferred_error_on_a_still_camera() {
    let (width, height) = (128u32, 96u32);
    let (mut renderer, _, _gpu) = thin_renderer(width, height);
    let truth = renderer.render_truth(8, u64::MAX).unwrap().images.display;
    let deferred = renderer.prepare("deferred-1x1".parse().unwrap()).unwrap();
    deferred.render().unwrap();
    let deferred_error = mse(&deferred.read_display().unwrap(), &truth);
    let taa = renderer.prepare("taa".parse().unwrap()).unwrap();
    // The first frame after a reset has no history: it is deferred-1x1's, jittered.
    taa.reset_history();
    taa.render().unwrap();
    let first = mse(&taa.read_display().unwrap(), &truth);
    taa.render_still().unwrap();
    let settled = mse(&taa.read_display().unwrap(), &truth);
    eprintln!(
        "MSE against the truth: deferred-1x1 {deferred_error:.3e}, taa frame 1 {first:.3e}, taa after {} frames {settled:.3e}",
        taa::WARMUP_FRAMES
    );
    assert!(
        settled < deferred_error,
        "taa after its warm-up: MSE {settled:.3e}, deferred-1x1 {deferred_error:.3e}"
    );
    assert!(settled < first, "the history lowers the error: {settled:.3e} vs {first:.3e} on the first frame");
}

#[test]
fn each_taa_mode_keeps_its_own_history() {
    let (width, height) = (96u32, 64u32);
    let (mut renderer, _, _gpu) = thin_renderer(width, height);
    let alone = renderer.prepare("taa".parse().unwrap()).unwrap();
    alone.render_still().unwrap();
    let expected = alone.read_display().unwrap();
    drop(alone);

    // The same mode beside its stalled twin and deferred-1x1, rendered in turn as the runner's
    // rounds and sequences do: the others must not touch its history.
    let modes: Vec<_> = ["taa", "taa-stalled", "deferred-1x1"]
        .iter()
        .map(|id| renderer.prepare(id.parse().unwrap()).unwrap())
        .collect();
    for mode in &modes {
        mode.reset_history();
    }
    let mut last = None;
    for _ in 0..taa::WARMUP_FRAMES {
        for (index, mode) in modes.iter().enumerate() {
            mode.render().unwrap();
            // Modes share their other targets: read the image before the next mode renders.
            if index == 0 {
                last = Some(mode.read_display().unwrap());
            }
        }
    }
    assert!(last == Some(expected), "taa's image changed when other modes ran between its frames");
    assert!(renderer.target_bytes() > 0);
}
