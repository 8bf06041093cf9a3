//! Moving objects along a real path on lavapipe, before a still camera: the `crossing` scene's
//! crate sliding across a brick wall, and the `walker` scene's skinned figure walking across it,
//! each with its truth at 8×8 and its geometry from the renderer's probe.
//!
//! TAA follows the crate by its motion vectors: fed motion vectors that leave the crate's motion
//! out (the frame before posed where the frame is, as a renderer that tracks only its camera
//! would), it flickers 1.7 times as much and errs 1.8 times as much at the crate's moving edges.
//! It follows the figure's limbs by their skinned positions of the frame before alike. The
//! trail each uncovers is measured: every frame pair has disoccluded pixels, and TAA's error on
//! them (its ghosting) is several times deferred-1x1's. A manifest that picks an animation the
//! file lacks, or one that cannot play, is refused naming the manifest, the field, the file and
//! the animation.

use crate::support;

use aabench::measure::temporal::{self, Flow, Geometry, PairError};
use aabench_renderer::scene::Camera;
use aabench_renderer::scene::generate::Generator;
use aabench_renderer::{DisplayImage, Mode, PreparedMode, SceneRenderer};
use serde_json::json;

const WIDTH: u32 = 128;
const HEIGHT: u32 = 96;
const FRAMES: usize = 6;
const STEP: f64 = 1.0 / 60.0;

/// A generated scene with its animation `name` playing, on a renderer of its own, and its
/// camera.
fn playing(generator: Generator, name: &str) -> (SceneRenderer, Camera) {
    let mut scene = support::generated_scene(generator);
    let index = scene.animations.iter().position(|a| a.name.as_deref() == Some(name));
    scene.play(&[index.expect("the scene carries its animation")]).unwrap();
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

/// TAA along the scene's path with the objects' motion in its motion vectors and without, and
/// deferred-1x1, each measured against the truth along the flows; every flow uncovers some of
/// the wall.
fn three_ways(generator: Generator, name: &str) -> [PairError; 3] {
    let (mut renderer, camera) = playing(generator, name);
    let (truth, flows) = truth_along(&mut renderer, &camera);
    for (pair, flow) in flows.iter().enumerate() {
        assert!(flow.disoccluded_share() > 0.001, "{generator}, pair {pair}: the object uncovers the wall");
    }
    let taa = renderer.prepare("taa".parse::<Mode>().unwrap()).unwrap();
    let deferred = renderer.prepare("deferred-1x1".parse::<Mode>().unwrap()).unwrap();
    let followed = measure(&along(&mut renderer, &taa, true), &truth, &flows);
    let blind = measure(&along(&mut renderer, &taa, false), &truth, &flows);
    let plain = measure(&along(&mut renderer, &deferred, true), &truth, &flows);
    for (label, e) in
        [("taa", &followed), ("taa, objects' motion left out", &blind), ("deferred-1x1", &plain)]
    {
        println!(
            "{generator}: {label:30} flicker {:.3e}  MSE disoccluded {:.3e}, at moving edges {:.3e}, elsewhere {:.3e}",
            mean(e.flicker),
            mean(e.disoccluded),
            mean(e.edges),
            mean(e.elsewhere)
        );
    }
    [followed, blind, plain]
}

#[test]
fn taa_follows_a_moving_object_by_its_motion_vectors_and_its_trail_is_measured() {
    let [followed, blind, plain] = three_ways(Generator::Crossing, "crossing");
    assert!(mean(blind.flicker) > 1.5 * mean(followed.flicker), "motion vectors keep the crate steady");
    assert!(mean(blind.edges) > 1.5 * mean(followed.edges), "and its edges sharp");
    assert!(
        mean(followed.disoccluded) > 3.0 * mean(plain.disoccluded),
        "TAA's trail is measured as ghosting"
    );
}

#[test]
fn taa_follows_a_walking_figures_limbs_by_their_skinned_motion() {
    let [followed, blind, plain] = three_ways(Generator::Walker, "walk");
    assert!(
        mean(blind.flicker) > 1.2 * mean(followed.flicker),
        "skinned motion vectors keep the figure steady"
    );
    assert!(mean(blind.edges) > 1.2 * mean(followed.edges), "and its limbs' edges sharp");
    assert!(
        mean(followed.disoccluded) > 2.0 * mean(plain.disoccluded),
        "TAA's trail behind the figure is measured as ghosting"
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

/// A grey panel from x = −1 to 5 m, 2 m tall, facing +z; the file's camera 3 m before it (node 1),
/// which the animation `fly` carries 6 m along x in a second (a 16:9 camera: the tests' 4:3 frames
/// span three quarters of its width); an empty node (node 2), which the
/// animation `idle` lifts; an orthographic camera (node 3) and a second perspective one (node 4),
/// which the animation `look` lifts. Written as `fly.gltf` into the workspace's scenes.
fn write_flying_camera(space: &support::Workspace) {
    let square: [[f32; 3]; 6] = [
        [-1.0, -1.0, 0.0],
        [5.0, -1.0, 0.0],
        [5.0, 1.0, 0.0],
        [-1.0, -1.0, 0.0],
        [5.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ];
    let times = [0.0f32, 1.0];
    let fly = [[0.0f32, 0.0, 3.0], [6.0, 0.0, 3.0]];
    let lift = [[0.0f32, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let floats: Vec<f32> = [square.as_flattened(), &times, fly.as_flattened(), lift.as_flattened()].concat();
    let bytes: Vec<u8> = floats.iter().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(space.dir.join("scenes/fly.bin"), &bytes).unwrap();
    let view =
        |offset: usize, length: usize| json!({ "buffer": 0, "byteOffset": offset, "byteLength": length });
    let document = json!({
        "asset": { "version": "2.0" },
        "buffers": [{ "uri": "fly.bin", "byteLength": bytes.len() }],
        "bufferViews": [view(0, 72), view(72, 8), view(80, 24), view(104, 24)],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": 6, "type": "VEC3", "min": [-1, -1, 0], "max": [5, 1, 0] },
            { "bufferView": 1, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0], "max": [1] },
            { "bufferView": 2, "componentType": 5126, "count": 2, "type": "VEC3" },
            { "bufferView": 3, "componentType": 5126, "count": 2, "type": "VEC3" }
        ],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0 } }] }],
        "cameras": [
            { "type": "perspective", "perspective": { "yfov": 0.8, "aspectRatio": 1.7778, "znear": 0.1, "zfar": 50 } },
            { "type": "orthographic", "orthographic": { "xmag": 1, "ymag": 1, "znear": 0.1, "zfar": 50 } },
            { "type": "perspective", "perspective": { "yfov": 0.5, "znear": 0.1 } }
        ],
        "nodes": [
            { "mesh": 0 }, { "camera": 0, "translation": [0, 0, 3] }, { "name": "marker" },
            { "camera": 1, "translation": [0, 0, 4] }, { "camera": 2, "translation": [0, 0, 5] }
        ],
        "scenes": [{ "nodes": [0, 1, 2, 3, 4] }],
        "animations": [
            { "name": "fly", "channels": [{ "sampler": 0, "target": { "node": 1, "path": "translation" } }],
              "samplers": [{ "input": 1, "output": 2 }] },
            { "name": "idle", "channels": [{ "sampler": 0, "target": { "node": 2, "path": "translation" } }],
              "samplers": [{ "input": 1, "output": 3 }] },
            { "name": "look",
              "channels": [
                  { "sampler": 0, "target": { "node": 3, "path": "translation" } },
                  { "sampler": 0, "target": { "node": 4, "path": "translation" } }
              ],
              "samplers": [{ "input": 1, "output": 3 }] }
        ]
    });
    std::fs::write(space.dir.join("scenes/fly.gltf"), document.to_string()).unwrap();
}

#[test]
fn an_animated_camera_moves_the_view_and_an_animation_that_moves_nothing_is_refused() {
    let space = support::Workspace::new("moving-camera");
    write_flying_camera(&space);
    let manifest = |name: &str, animation: &str, path: &str| {
        space.manifest(name, "crossing", |m| {
            m.as_object_mut().unwrap().remove("generate");
            m["gltf"] = json!("fly.gltf");
            m["motion"] = json!({ "path": path, "animation": { "name": animation } });
        })
    };
    let run = |manifest: std::path::PathBuf| {
        space.run(&["run", manifest.to_str().unwrap(), "--tier", "quick", "--modes", "deferred-1x1"])
    };
    // 6 m a second at 3 m, 1/60 s a frame, 48 px for 2 · 3 · tan 0.4 m: 1.89 px a frame; the
    // panel's left edge crosses the view.
    let flying = run(manifest("flying", "fly", "static"));
    assert_eq!(flying.status.code(), Some(0), "{}", support::stderr(&flying));
    let record = space.record();
    let sequence = &support::scene(&record, "flying")["sequences"][0];
    let speed = sequence["measured_speed"]["median"].as_f64().expect("a measured speed");
    assert!((speed - 1.89).abs() < 0.15, "the view moves as the camera's node: {speed} px a frame");
    assert!(sequence["truth_change"].as_f64().unwrap() > 0.0, "the frames change");
    let warnings = support::scene(&record, "flying")["warnings"].to_string();
    assert!(
        warnings.contains(
            "cameras[0].aspectRatio is 1.778, and aabench keeps the camera's vertical field of view at the \
             manifest's resolution: resolution.quick (64×48) spans 75 % of its width and resolution.nightly \
             (128×96) spans 75 % of its width"
        ),
        "{warnings}"
    );
    let refused = |manifest, parts: &[&str]| {
        let output = run(manifest);
        assert_eq!(output.status.code(), Some(3), "the scene fails");
        let stderr = support::stderr(&output);
        for part in parts {
            assert!(stderr.contains(part), "names {part}: {stderr}");
        }
    };
    refused(
        manifest("orbiting", "fly", "orbit"),
        &["orbiting.json", "motion.path", "orbit", "fly.gltf", "static"],
    );
    refused(
        manifest("idle", "idle", "static"),
        &[
            "idle.json",
            "animations[1] (\"idle\")",
            "moves only nodes[2], which hold no geometry and no camera",
        ],
    );
    // Cameras it moves that the frames are not rendered from are named as such.
    refused(
        manifest("look", "look", "static"),
        &[
            "moves only nodes[3], nodes[4]: ",
            "nodes[3] holds an orthographic camera, and aabench renders from the file's first perspective camera",
            "nodes[4] holds a camera after the first",
        ],
    );
    let replaced = space.manifest("replaced", "crossing", |m| {
        m.as_object_mut().unwrap().remove("generate");
        m["gltf"] = json!("fly.gltf");
        m["camera"] = json!({ "position": [2.0, 0.0, 4.0], "target": [2.0, 0.0, 0.0], "fov_y_degrees": 45 });
        m["motion"] = json!({ "path": "static", "animation": { "name": "fly" } });
    });
    refused(
        replaced,
        &["moves only nodes[1]: nodes[1] holds the file's camera, which the manifest's `camera` replaces"],
    );
}

/// An animation that starts with the sequence would hold its first key through the warm-up: the
/// window starts 16 frames into it instead, so that TAA's history and ColorVideoVDP's filters
/// have seen the crate move (the still is the window's first frame, posed there). Started a
/// second in, it needs no lead. Too short for the warm-up and the longest window both, the
/// window keeps its motion, and the warm-up's still frames are counted and warned about.
#[test]
fn an_animation_warms_up_in_motion_and_a_warm_up_that_cannot_move_says_so() {
    let space = support::Workspace::new("moving-warmup");
    let run = |name: &str, motion: serde_json::Value| {
        let manifest = space.manifest(name, "crossing", |m| m["motion"] = motion.clone());
        // One run's record at a time.
        let _ = std::fs::remove_dir_all(space.dir.join("reports"));
        let output = space.run(&[
            "run",
            manifest.to_str().unwrap(),
            "--modes",
            "deferred-1x1,taa",
            "--repetitions",
            "1",
        ]);
        assert_eq!(output.status.code(), Some(0), "{}", support::stderr(&output));
        let record = space.record();
        (support::scene(&record, name)["sequences"][0].clone(), support::stderr(&output))
    };
    let frames = json!({"quick": 4, "nightly": 4});
    let (led, _) = run("led", json!({"path": "static", "frames": frames, "animation": {"name": "crossing"}}));
    assert!((led["lead_s"].as_f64().unwrap() - 16.0 * STEP).abs() < 1e-12, "{led}");
    assert_eq!((led["warmup_frames"].as_u64(), led.get("warmup_still_frames")), (Some(16), None));
    let moving = led["measured_speed"]["moving"].as_f64().unwrap();
    assert!(moving > 0.0 && moving < 0.2, "the crate moves, the wall does not: {moving}");
    let (later, _) = run(
        "later",
        json!({"path": "static", "frames": frames, "animation": {"name": "crossing", "start_s": 1.0}}),
    );
    assert!(later.get("lead_s").is_none(), "{later}");
    // The crate slides for 2 s: a nightly window of 121 frames leaves no room for a lead, and
    // the warm-up holds the first key (its first frame counts as moving).
    let (held, stderr) = run(
        "held",
        json!({"path": "static", "frames": {"quick": 4, "nightly": 121}, "animation": {"name": "crossing"}}),
    );
    assert!(held.get("lead_s").is_none(), "{held}");
    assert_eq!(held["warmup_still_frames"], 15, "{held}");
    assert!(stderr.contains("15 of the 16 warm-up frames hold still"), "{stderr}");
}

/// The `walker` scene's file with its walk split into one animation per channel (`walk.0`, …),
/// as exporters that write an action per joint do, and the whole walk beside them as `whole`:
/// an alternative that drives every joint the parts drive. Written as `split.gltf` and
/// `split.bin` into the workspace's scenes; returns the number of parts.
fn write_split_walker(space: &support::Workspace) -> usize {
    let source = space.dir.join("walker-source.glb");
    Generator::Walker.write(1, &source).unwrap();
    let glb = std::fs::read(&source).unwrap();
    let chunk = |at: usize| {
        let length = u32::from_le_bytes(glb[at..at + 4].try_into().unwrap()) as usize;
        (&glb[at + 8..at + 8 + length], at + 8 + length)
    };
    let (json, next) = chunk(12);
    let (bin, _) = chunk(next);
    let mut document: serde_json::Value = serde_json::from_slice(json).unwrap();
    let walk = (document["animations"].as_array().unwrap().iter())
        .find(|a| a["name"] == "walk")
        .expect("the walker walks")
        .clone();
    let channels = walk["channels"].as_array().unwrap();
    let mut animations: Vec<serde_json::Value> = (channels.iter().enumerate())
        .map(|(c, channel)| {
            let sampler = walk["samplers"][channel["sampler"].as_u64().unwrap() as usize].clone();
            let mut channel = channel.clone();
            channel["sampler"] = json!(0);
            json!({ "name": format!("walk.{c}"), "channels": [channel], "samplers": [sampler] })
        })
        .collect();
    let parts = animations.len();
    let mut whole = walk.clone();
    whole["name"] = json!("whole");
    animations.push(whole);
    document["animations"] = json!(animations);
    document["buffers"][0]["uri"] = json!("split.bin");
    std::fs::write(space.dir.join("scenes/split.bin"), bin).unwrap();
    std::fs::write(space.dir.join("scenes/split.gltf"), document.to_string()).unwrap();
    parts
}

#[test]
fn a_walk_split_into_an_animation_per_joint_plays_together_as_the_whole_walk() {
    let space = support::Workspace::new("moving-split");
    let parts = write_split_walker(&space);
    assert!(parts > 3, "the walk moves several joints: {parts} channels");
    let manifest = |name: &str, animation: serde_json::Value| {
        space.manifest(name, "walker", |m| {
            m.as_object_mut().unwrap().remove("generate");
            m["gltf"] = json!("split.gltf");
            m["motion"] =
                json!({ "path": "static", "frames": { "quick": 4, "nightly": 4 }, "animation": animation });
        });
    };
    let names: Vec<String> = (0..parts).map(|c| format!("walk.{c}")).collect();
    manifest("whole", json!({ "name": "whole" }));
    manifest("parts", json!({ "name": names }));
    manifest("one-part", json!({ "name": "walk.1" }));
    manifest("everything", json!({ "all": true }));
    let output = space.run(&["run", "scenes", "--tier", "quick", "--modes", "deferred-1x1"]);
    let stderr = support::stderr(&output);
    assert_eq!(output.status.code(), Some(3), "one scene fails, the others run: {stderr}");
    let record = space.record();
    let sequence = |scene: &str| {
        let scene = support::scene(&record, scene);
        assert_eq!(scene["status"], "ok", "{scene}");
        (
            scene["sequences"][0].clone(),
            support::mode(scene, "deferred-1x1")["sequences"][0]["hashes"].clone(),
        )
    };
    // Played on one clock, the parts pose the figure frame for frame as the whole walk does.
    let ((whole, whole_hashes), (together, together_hashes)) = (sequence("whole"), sequence("parts"));
    assert!(whole["truth_change"].as_f64().unwrap() > 0.0, "the figure walks");
    assert_eq!(whole_hashes.as_array().map(Vec::len), Some(4), "{whole_hashes}");
    assert_eq!(together_hashes, whole_hashes, "the parts together are the walk");
    assert_eq!(whole["animation"], "whole");
    assert_eq!(together["animation"], format!("walk.0 and {} more", parts - 1));
    // One part alone moves one joint, and the run says which parts stand at rest; the whole
    // walk drives what that part drives, so it is another action, not a part.
    let (_, alone) = sequence("one-part");
    assert_ne!(alone, whole_hashes, "one joint moves, not the figure");
    let warnings = support::scene(&record, "one-part")["warnings"].to_string();
    let expected = format!(
        r#"motion.animation plays animations[1] (\"walk.1\") but not animations[0] (\"walk.0\") and {} more, which move other parts of the same figure or nodes"#,
        parts - 2
    );
    assert!(warnings.contains(&expected), "{warnings}");
    assert!(!warnings.contains("whole"), "an alternative is not a missing part: {warnings}");
    // All of them at once drive each joint twice: refused, naming both channels.
    let everything = support::scene(&record, "everything");
    assert_eq!(everything["status"], "failed");
    let error = everything["error"].as_str().unwrap();
    for part in [
        "everything.json: motion.animation: ",
        "split.gltf: animations[0] (\"walk.0\") channels[0] and ",
        " (\"whole\") channels[0] both animate the ",
        "pick one of them",
    ] {
        assert!(error.contains(part), "names {part}: {error}");
    }
}
