//! A moving object along a real path on lavapipe: the `crossing` scene's crate sliding across a
//! brick wall before a still camera, its truth at 8×8 and its geometry from the renderer's probe.
//!
//! TAA follows the crate by its motion vectors: fed motion vectors that leave the crate's motion
//! out (the frame before posed where the frame is, as a renderer that tracks only its camera
//! would), it flickers 1.7 times as much and errs 1.8 times as much at the crate's moving edges. The trail the crate uncovers is measured:
//! every frame pair has disoccluded pixels, and TAA's error on them (its ghosting) is several
//! times deferred-1x1's. A manifest that picks an animation the file lacks, or one that cannot
//! play, is refused naming the manifest, the field, the file and the animation.

mod support;

use aabench::temporal::{self, Flow, Geometry, PairError};
use aabench_renderer::scene::Camera;
use aabench_renderer::scene::generate::Generator;
use aabench_renderer::{DisplayImage, Mode, PreparedMode, SceneRenderer};
use serde_json::json;

const WIDTH: u32 = 128;
const HEIGHT: u32 = 96;
const FRAMES: usize = 6;
const STEP: f64 = 1.0 / 60.0;

/// The `crossing` scene with its animation playing, on a renderer of its own, and its camera.
fn crossing() -> (SceneRenderer, Camera) {
    let mut scene = support::generated_scene(Generator::Crossing);
    scene.playing = scene.animations.iter().position(|a| a.name.as_deref() == Some("crossing"));
    assert!(scene.playing.is_some(), "the scene carries its animation");
    let camera = scene.camera.expect("generated scenes carry a camera");
    (support::plain_renderer(&scene, &camera, [WIDTH, HEIGHT], 0.1), camera)
}

/// Poses frame `frame`: the animation at its time, with the frame before's time where motion
/// vectors hold the objects' motion, and the frame's own where they do not.
fn pose(renderer: &mut SceneRenderer, frame: usize, object_motion: bool) {
    let (now, then) = (frame as f64 * STEP, frame.saturating_sub(1) as f64 * STEP);
    renderer.pose(now, if object_motion { then } else { now }).unwrap();
}

/// Renders `mode` along the path, the first frame as a still.
fn along(renderer: &mut SceneRenderer, mode: &PreparedMode, object_motion: bool) -> Vec<DisplayImage> {
    (0..FRAMES)
        .map(|frame| {
            pose(renderer, frame, object_motion);
            if frame == 0 { mode.render_still() } else { mode.render() }.unwrap();
            mode.read_display().unwrap()
        })
        .collect()
}

/// The truth and the flows between consecutive frames.
fn truth_along(renderer: &mut SceneRenderer, camera: &Camera) -> (Vec<DisplayImage>, Vec<Flow>) {
    let probe = renderer.prepare_geometry().unwrap();
    let (mut truth, mut geometry) = (Vec::new(), Vec::<Geometry>::new());
    for frame in 0..FRAMES {
        pose(renderer, frame, true);
        truth.push(renderer.render_truth(8, 256 << 20).unwrap().images.display);
        if frame == 0 { probe.render_still() } else { probe.render() }.unwrap();
        let gbuffer = probe.read_gbuffer().unwrap();
        let motion = probe.read_motion().unwrap().unwrap();
        geometry.push(Geometry::from_probe(&gbuffer, &motion, [camera, camera]));
    }
    let flows = geometry.windows(2).map(|pair| Flow::between(&pair[1], &pair[0])).collect();
    (truth, flows)
}

/// A mode's errors along the flows, summed over the frame pairs.
fn measure(frames: &[DisplayImage], truth: &[DisplayImage], flows: &[Flow]) -> PairError {
    let mut sums = PairError::default();
    let mut map = vec![0.0; (WIDTH * HEIGHT) as usize];
    for f in 1..frames.len() {
        sums.add(&flows[f - 1].error([&frames[f], &truth[f]], [&frames[f - 1], &truth[f - 1]], &mut map));
    }
    sums
}

fn mean(sum: (f64, u64)) -> f64 {
    temporal::mean(sum).expect("some pixels")
}

#[test]
fn taa_follows_a_moving_object_by_its_motion_vectors_and_its_trail_is_measured() {
    let (mut renderer, camera) = crossing();
    let (truth, flows) = truth_along(&mut renderer, &camera);
    for (pair, flow) in flows.iter().enumerate() {
        assert!(flow.disoccluded_share() > 0.001, "pair {pair}: the crate uncovers the wall");
    }
    let taa = renderer.prepare("taa".parse::<Mode>().unwrap()).unwrap();
    let deferred = renderer.prepare("deferred-1x1".parse::<Mode>().unwrap()).unwrap();
    let followed = measure(&along(&mut renderer, &taa, true), &truth, &flows);
    let blind = measure(&along(&mut renderer, &taa, false), &truth, &flows);
    let plain = measure(&along(&mut renderer, &deferred, true), &truth, &flows);
    for (name, e) in [("taa", &followed), ("taa, objects' motion left out", &blind), ("deferred-1x1", &plain)]
    {
        println!(
            "{name:30} flicker {:.3e}  MSE disoccluded {:.3e}, at moving edges {:.3e}, elsewhere {:.3e}",
            mean(e.flicker),
            mean(e.disoccluded),
            mean(e.edges),
            mean(e.elsewhere)
        );
    }
    assert!(mean(blind.flicker) > 1.5 * mean(followed.flicker), "motion vectors keep the crate steady");
    assert!(mean(blind.edges) > 1.5 * mean(followed.edges), "and its edges sharp");
    assert!(
        mean(followed.disoccluded) > 3.0 * mean(plain.disoccluded),
        "TAA's trail is measured as ghosting"
    );
}

#[test]
fn a_manifest_that_picks_a_missing_or_broken_animation_is_refused_by_name() {
    let space = support::Workspace::new("moving-pick");
    let refusal = |manifest: std::path::PathBuf| {
        let output =
            space.run(&["run", manifest.to_str().unwrap(), "--tier", "quick", "--modes", "deferred-1x1"]);
        assert_eq!(output.status.code(), Some(3), "the scene fails");
        support::stderr(&output)
    };
    let missing = space.manifest("missing", "crossing", |m| {
        m["motion"] = json!({ "path": "static", "animation": { "name": "walk" } });
    });
    let stderr = refusal(missing);
    for part in ["missing.json", "motion.animation.name", "crossing.glb", "animations[0] (\"crossing\")"] {
        assert!(stderr.contains(part), "names {part}: {stderr}");
    }
    // A triangle whose animation's keyframe times run backwards.
    let positions = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let times = [1.0f32, 0.5];
    let translations = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0];
    let bytes: Vec<u8> =
        [&positions[..], &times, &translations].concat().iter().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(space.dir.join("scenes/back.bin"), &bytes).unwrap();
    let document = json!({
        "asset": { "version": "2.0" },
        "buffers": [{ "uri": "back.bin", "byteLength": bytes.len() }],
        "bufferViews": [
            { "buffer": 0, "byteLength": 36 },
            { "buffer": 0, "byteOffset": 36, "byteLength": 8 },
            { "buffer": 0, "byteOffset": 44, "byteLength": 24 }
        ],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0] },
            { "bufferView": 1, "componentType": 5126, "count": 2, "type": "SCALAR" },
            { "bufferView": 2, "componentType": 5126, "count": 2, "type": "VEC3" }
        ],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0 } }] }],
        "nodes": [{ "mesh": 0 }],
        "scenes": [{ "nodes": [0] }],
        "animations": [{
            "name": "back",
            "channels": [{ "sampler": 0, "target": { "node": 0, "path": "translation" } }],
            "samplers": [{ "input": 1, "output": 2 }]
        }]
    });
    std::fs::write(space.dir.join("scenes/back.gltf"), document.to_string()).unwrap();
    let broken = space.manifest("broken", "crossing", |m| {
        m.as_object_mut().unwrap().remove("generate");
        m["gltf"] = json!("back.gltf");
        m["camera"] =
            json!({ "position": [0.3, 0.3, 2.0], "target": [0.3, 0.3, 0.0], "fov_y_degrees": 60.0 });
        m["motion"] = json!({ "path": "static", "animation": { "index": 0 } });
    });
    let stderr = refusal(broken);
    for part in [
        "broken.json",
        "motion.animation",
        "back.gltf",
        "animations[0] (\"back\")",
        "channels[0]",
        "must increase",
    ] {
        assert!(stderr.contains(part), "names {part}: {stderr}");
    }
    let both = space.manifest("both", "crossing", |m| {
        m["motion"] = json!({ "path": "static", "animation": { "name": "crossing", "index": 0 } });
    });
    assert!(refusal(both).contains("motion.animation.index"));
}
