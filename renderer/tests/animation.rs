//! Moving objects: glTF animations read through the gltf crate, played, and seen by the motion
//! vectors.
//!
//! A translation, a rotation and a scale track of the test triangle pose its vertices where the
//! keyframes say, through a parent node too. Broken animation data (an unknown channel path or
//! interpolation, samplers whose lengths disagree, NaN keyframes, times that do not increase,
//! morph weights, outputs in formats glTF forbids, indices past the file's lists, two channels of
//! one node's property, a scale that turns a node inside out, a node flattened at rest) costs
//! the file nothing: it loads, and the animation says what is wrong, naming itself and the part
//! at fault. Every pose an animation takes, at its keyframes and along a cubic spline between
//! them, is held to the bounds of a scene at rest. On lavapipe, the `crossing` scene's crate moves,
//! and the geometry probe's motion vectors on it are its projected motion to a fiftieth of a
//! pixel while the wall behind stays still.

use crate::support;

use std::path::{Path, PathBuf};

use aabench_renderer::scene::generate::Generator;
use aabench_renderer::scene::load_gltf;
use aabench_renderer::scene::pose::Poser;
use glam::{DVec2, DVec3};
use serde_json::{Value, json};
use support::Folder;

/// The test triangle (node 0, under a parent node 1) with one animation `slide` of one channel:
/// `path` of `node`, keyframe `times` and float `values` (`width` floats each) sampled by
/// `interpolation`, their data in a second buffer; then `edit`.
struct Channel<'a> {
    path: &'a str,
    node: usize,
    interpolation: &'a str,
    times: &'a [f32],
    values: &'a [f32],
    width: usize,
}

impl Channel<'_> {
    fn write(&self, folder: &Folder, name: &str, edit: impl Fn(&mut Value)) -> PathBuf {
        let mut bytes: Vec<u8> = bytemuck::cast_slice(self.times).to_vec();
        let offset = bytes.len();
        bytes.extend_from_slice(bytemuck::cast_slice(self.values));
        let bin = format!("{name}.bin");
        std::fs::write(folder.dir.join(&bin), &bytes).unwrap();
        let kind = ["SCALAR", "VEC2", "VEC3", "VEC4"][self.width - 1];
        let nodes = json!([{ "mesh": 0 }, { "children": [0] }]);
        folder.gltf(name, nodes, |d| {
            d["scenes"] = json!([{ "nodes": [1] }]);
            d["buffers"].as_array_mut().unwrap().push(json!({ "uri": bin, "byteLength": bytes.len() }));
            let views = d["bufferViews"].as_array_mut().unwrap();
            views.push(json!({ "buffer": 1, "byteLength": offset }));
            views.push(json!({ "buffer": 1, "byteOffset": offset, "byteLength": bytes.len() - offset }));
            let accessors = d["accessors"].as_array_mut().unwrap();
            accessors.push(json!({ "bufferView": 1, "componentType": 5126, "count": self.times.len(), "type": "SCALAR" }));
            let count = self.values.len() / self.width;
            accessors.push(json!({ "bufferView": 2, "componentType": 5126, "count": count, "type": kind }));
            d["animations"] = json!([{
                "name": "slide",
                "channels": [{ "sampler": 0, "target": { "node": self.node, "path": self.path } }],
                "samplers": [{ "input": 1, "output": 2, "interpolation": self.interpolation }]
            }]);
            edit(d);
        })
    }
}

fn slide<'a>(times: &'a [f32], values: &'a [f32]) -> Channel<'a> {
    Channel { path: "translation", node: 1, interpolation: "LINEAR", times, values, width: 3 }
}

/// The test triangle's corners posed by its file's first animation at `time`.
fn posed(path: &Path, time: f64) -> Vec<DVec3> {
    let mut scene = load_gltf(path).expect("the file loads");
    assert!(scene.animations[0].tracks.is_ok(), "{:?}", scene.animations[0].tracks);
    scene.play(&[0]).unwrap();
    let poser = Poser::of(&scene).expect("an animation plays");
    let moved = poser.vertices_at(time);
    assert_eq!(moved.len(), 1, "the one node with vertices moves");
    moved[0].vertices.iter().map(|v| DVec3::from(v.position.map(f64::from))).collect()
}

#[test]
fn translation_rotation_and_scale_tracks_pose_the_vertices_through_a_parent() {
    let folder = Folder::new("animation-tracks");
    let close = |a: DVec3, b: DVec3| (a - b).length() < 1e-6;
    // Halfway along a slide of 2 in x: the corner (1, 0, 0) lies at (2, 0, 0).
    let path = slide(&[0.0, 1.0], &[0.0, 0.0, 0.0, 2.0, 0.0, 0.0]).write(&folder, "slide.gltf", |_| {});
    let corners = posed(&path, 0.5);
    assert!(close(corners[1], DVec3::new(2.0, 0.0, 0.0)), "{corners:?}");
    // Held after the last keyframe.
    assert!(close(posed(&path, 7.0)[1], DVec3::new(3.0, 0.0, 0.0)));
    // A quarter turn about z, stepped: before the second keyframe nothing turns, after it (1, 0, 0)
    // lies at (0, 1, 0).
    let (s, c) = std::f32::consts::FRAC_PI_4.sin_cos();
    let quarter = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, s, c];
    let turn = Channel { path: "rotation", interpolation: "STEP", width: 4, ..slide(&[0.0, 1.0], &quarter) };
    let path = turn.write(&folder, "turn.gltf", |_| {});
    assert!(close(posed(&path, 0.9)[1], DVec3::X));
    assert!(close(posed(&path, 1.0)[1], DVec3::Y));
    // A scale along a cubic spline with flat tangents: at a quarter of the way, 15.625 % of the
    // way from 1 to 3.
    let flat = [0.0f32; 3];
    let values: Vec<f32> = [flat, [1.0; 3], flat, flat, [3.0; 3], flat].concat();
    let grow = Channel { path: "scale", interpolation: "CUBICSPLINE", ..slide(&[0.0, 1.0], &values) };
    let path = grow.write(&folder, "grow.gltf", |_| {});
    let x = posed(&path, 0.25)[1].x;
    assert!((x - (1.0 + 2.0 * 0.15625)).abs() < 1e-6, "{x}");
}

/// Why the file's first animation may not play: its first pose beyond the bounds of a scene at
/// rest, or none.
fn pose_error(path: &Path) -> Option<String> {
    let mut scene = load_gltf(path).expect("the file loads");
    scene.play(&[0]).unwrap();
    Poser::of(&scene).expect("an animation plays").check().err()
}

#[test]
fn every_pose_an_animation_takes_is_held_to_the_bounds_of_a_scene_at_rest() {
    let folder = Folder::new("animation-bounds");
    let far = slide(&[0.0, 1.0], &[0.0, 0.0, 0.0, 1e30, 0.0, 0.0]).write(&folder, "far.gltf", |_| {});
    let error = pose_error(&far).expect("a keyframe 10³⁰ away");
    let said =
        "channels[0] (translation of nodes[1]), keyframe 1 (t = 1 s), carries the vertices of nodes[0] to";
    assert!(error.starts_with(said) && error.contains("beyond ±1e12"), "{error}");
    let grow = Channel { path: "scale", ..slide(&[0.0, 2.0], &[1.0, 1.0, 1.0, 1e30, 1.0, 1.0]) };
    let error = pose_error(&grow.write(&folder, "grow.gltf", |_| {})).expect("a scale of 10³⁰");
    assert!(error.contains("(scale of nodes[1]), keyframe 1 (t = 2 s)"), "{error}");
    // Both keys at the origin, the first's out-tangent huge: the spline passes far beyond
    // between them, where a check of the keys alone would not look.
    let flat = [0.0f32; 3];
    let values: Vec<f32> = [flat, flat, [3e38, 0.0, 0.0], flat, flat, flat].concat();
    let cubic = Channel { interpolation: "CUBICSPLINE", ..slide(&[0.0, 1.0], &values) };
    let error = pose_error(&cubic.write(&folder, "tangent.gltf", |_| {})).expect("a tangent of 3·10³⁸");
    assert!(error.contains("halfway between keyframes 0 and 1 (t = 0.5 s)"), "{error}");
    // Equal tangents, 3·10¹⁶ each, at keys on the origin: halfway the spline is back at the
    // origin, but a fifth of the way and four fifths (u = (3 ∓ √3)/6) it is 2.9·10¹⁵ away.
    let tangent = [3e16f32, 0.0, 0.0];
    let values: Vec<f32> = [flat, flat, tangent, tangent, flat, flat].concat();
    let cubic = Channel { interpolation: "CUBICSPLINE", ..slide(&[0.0, 1.0], &values) };
    let error =
        pose_error(&cubic.write(&folder, "equal-tangents.gltf", |_| {})).expect("an overshoot of 2.9·10¹⁵");
    assert!(error.contains("where the spline between keyframes 0 and 1 turns (t = 0.211"), "{error}");
    // Two channels, keyed at the same times: the first slides the parent a little, the second
    // carries the triangle's own node 10³⁰ away. Checked at the first's keyframe 1, the pose is
    // out, and the error names the second, which puts it out alone.
    let values = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1e30, 0.0, 0.0];
    let two = slide(&[0.0, 1.0], &values).write(&folder, "two.gltf", |d| {
        d["accessors"][2]["count"] = json!(2);
        let far =
            json!({ "bufferView": 2, "byteOffset": 24, "componentType": 5126, "count": 2, "type": "VEC3" });
        d["accessors"].as_array_mut().unwrap().push(far);
        let accessor = d["accessors"].as_array().unwrap().len() - 1;
        let animation = &mut d["animations"][0];
        animation["samplers"].as_array_mut().unwrap().push(json!({ "input": 1, "output": accessor }));
        let channel = json!({ "sampler": 1, "target": { "node": 0, "path": "translation" } });
        animation["channels"].as_array_mut().unwrap().push(channel);
    });
    let error = pose_error(&two).expect("a node 10³⁰ away");
    assert!(error.starts_with("channels[1] (translation of nodes[0]), keyframe 1 (t = 1 s)"), "{error}");
    // Within the bounds, every pose passes.
    let near = slide(&[0.0, 1.0], &[0.0, 0.0, 0.0, 1e11, 0.0, 0.0]).write(&folder, "near.gltf", |_| {});
    assert_eq!(pose_error(&near), None);
}

#[test]
fn broken_animations_cost_the_file_nothing_and_say_what_is_wrong() {
    let folder = Folder::new("animation-broken");
    let two = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0];
    type Edit = fn(&mut Value);
    let cases: Vec<(&str, Channel, Edit, &str)> = vec![
        ("path.gltf", Channel { path: "spin", ..slide(&[0.0, 1.0], &two) }, |_| {}, "target.path"),
        (
            "interpolation.gltf",
            Channel { interpolation: "SMOOTH", ..slide(&[0.0, 1.0], &two) },
            |_| {},
            "interpolation",
        ),
        ("lengths.gltf", slide(&[0.0, 1.0, 2.0], &two), |_| {}, "need 3 output values"),
        (
            "cubic.gltf",
            Channel { interpolation: "CUBICSPLINE", ..slide(&[0.0, 1.0], &two) },
            |_| {},
            "need 6 output values",
        ),
        ("nan-time.gltf", slide(&[0.0, f32::NAN], &two), |_| {}, "not finite"),
        (
            "nan-value.gltf",
            slide(&[0.0, 1.0], &[0.0, f32::NAN, 0.0, 1.0, 0.0, 0.0]),
            |_| {},
            "output value 0",
        ),
        ("order.gltf", slide(&[1.0, 0.5], &two), |_| {}, "must increase"),
        (
            "weights.gltf",
            Channel { path: "weights", width: 1, ..slide(&[0.0, 1.0], &[0.0, 1.0]) },
            |_| {},
            "morph target weights",
        ),
        (
            "mirror.gltf",
            Channel { path: "scale", ..slide(&[0.0, 1.0], &[1.0, 1.0, 1.0, -1.0, 1.0, 1.0]) },
            |_| {},
            "inside out",
        ),
        ("node.gltf", Channel { node: 7, ..slide(&[0.0, 1.0], &two) }, |_| {}, "node 7 does not exist"),
        (
            "accessor.gltf",
            slide(&[0.0, 1.0], &two),
            |d| d["animations"][0]["samplers"][0]["output"] = json!(9),
            "accessor 9 does not exist",
        ),
        (
            "flat.gltf",
            slide(&[0.0, 1.0], &two),
            |d| d["nodes"][1]["scale"] = json!([0, 0, 0]),
            "scale of zero",
        ),
        (
            "format.gltf",
            slide(&[0.0, 1.0], &two),
            |d| d["accessors"][2]["componentType"] = json!(5123),
            "not a format glTF allows",
        ),
        (
            "doubled.gltf",
            slide(&[0.0, 1.0], &two),
            |d| {
                let channel = d["animations"][0]["channels"][0].clone();
                d["animations"][0]["channels"].as_array_mut().unwrap().push(channel);
            },
            "channels[0] and channels[1] both animate the translation of nodes[1], which glTF forbids",
        ),
    ];
    for (name, channel, edit, expected) in cases {
        let path = channel.write(&folder, name, edit);
        let scene = load_gltf(&path).unwrap_or_else(|e| panic!("{name}: the file still loads: {e}"));
        let error = scene.animations[0].tracks.as_ref().expect_err(name);
        assert!(error.contains(expected), "{name}: {error}");
        let label = "animations[0] (\"slide\"): cannot be played";
        assert!(scene.warnings.iter().any(|w| w.contains(label)), "{name}: {:?}", scene.warnings);
        assert_eq!(scene.triangle_count(), 1, "{name}: the geometry is all there");
    }
}

#[test]
fn a_moving_objects_motion_vectors_hold_its_projected_motion_and_the_wall_stays_still() {
    let (gpu, _guard) = support::gpu();
    let (mut scene, camera) = support::generated(Generator::Crossing);
    let index = scene.animations.iter().position(|a| a.name.as_deref() == Some("crossing")).unwrap();
    scene.play(&[index]).unwrap();
    let (width, height) = (128u32, 96u32);
    let settings = support::settings(width, height);
    let mut renderer =
        aabench_renderer::SceneRenderer::new(gpu, &scene, &camera, &support::lit(), settings).unwrap();
    let probe = renderer.prepare_geometry().unwrap();
    let (t0, t1) = (0.0, 1.0 / 60.0);
    renderer.pose(t0, t0).unwrap();
    probe.render_still().unwrap();
    renderer.pose(t1, t0).unwrap();
    probe.render().unwrap();
    let motion = probe.read_motion().unwrap().expect("the probe writes motion");
    // A point on the crate's front between two bars, where it lies at each time (the file's
    // track: from x = −0.9 at 5.77 m/s, y = −0.6; the front 0.2 m before the crate's centre).
    let track = &scene.animations[index].tracks.as_ref().unwrap()[0];
    let point = |t: f64| {
        let [x, y, z, _] = track.sample(t);
        DVec3::new(x + 0.08, y, z + 0.2)
    };
    let size = DVec2::new(f64::from(width), f64::from(height));
    let (now, _) = support::project(&camera, size, point(t1));
    let (then, depth_then) = support::project(&camera, size, point(t0));
    let pixel = (now.y.floor() as usize) * width as usize + now.x.floor() as usize;
    let [mx, my, depth, _] = motion[pixel];
    let expected = now - then;
    println!("crate: motion ({mx}, {my}) px, expected {expected}; depth then {depth}, expected {depth_then}");
    assert!(expected.x > 1.5, "the crate moves about 2 px a frame at {width}×{height}: {expected}");
    assert!((f64::from(mx) - expected.x).abs() < 0.02 && (f64::from(my) - expected.y).abs() < 0.02);
    assert!((f64::from(depth) - depth_then).abs() < 1e-3 * depth_then);
    // The wall above the crate does not move.
    let wall = motion[4 * width as usize + width as usize / 2];
    assert!(wall[0].abs() < 1e-4 && wall[1].abs() < 1e-4, "{wall:?}");
}

#[test]
fn a_normal_mapped_node_moves_the_vertices_its_tangents_split_off() {
    let folder = Folder::new("animation-split");
    image::RgbaImage::from_pixel(4, 4, image::Rgba([128, 128, 255, 255]))
        .save(folder.dir.join("n.png"))
        .unwrap();
    // Two triangles about the edge 0–2 whose U runs opposite ways: MikkTSpace gives the
    // shared corners two tangents, and splits them into copies at the end of the vertex list.
    let positions = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]];
    let normals = [[0.0f32, 0.0, 1.0]; 4];
    let uvs = [[0.0f32, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 0.0]];
    let indices = [0u32, 1, 2, 0, 2, 3];
    let (times, translations) = ([0.0f32, 1.0], [[0.0f32, 0.0, 0.0], [2.0, 0.0, 0.0]]);
    let parts: [&[u8]; 6] = [
        bytemuck::cast_slice(&positions),
        bytemuck::cast_slice(&normals),
        bytemuck::cast_slice(&uvs),
        bytemuck::cast_slice(&indices),
        bytemuck::cast_slice(&times),
        bytemuck::cast_slice(&translations),
    ];
    let mut views = Vec::new();
    let mut bytes = Vec::new();
    for part in parts {
        views.push(json!({ "buffer": 0, "byteOffset": bytes.len(), "byteLength": part.len() }));
        bytes.extend_from_slice(part);
    }
    std::fs::write(folder.dir.join("split.bin"), &bytes).unwrap();
    let accessor = |view: usize, component: u32, count: usize, kind: &str| json!({ "bufferView": view, "componentType": component, "count": count, "type": kind });
    let mut position = accessor(0, 5126, 4, "VEC3");
    position["min"] = json!([-1, 0, 0]);
    position["max"] = json!([1, 1, 0]);
    let document = json!({
        "asset": { "version": "2.0" },
        "buffers": [{ "uri": "split.bin", "byteLength": bytes.len() }],
        "bufferViews": views,
        "accessors": [
            position, accessor(1, 5126, 4, "VEC3"), accessor(2, 5126, 4, "VEC2"),
            accessor(3, 5125, 6, "SCALAR"), accessor(4, 5126, 2, "SCALAR"), accessor(5, 5126, 2, "VEC3")
        ],
        "images": [{ "uri": "n.png" }],
        "textures": [{ "source": 0 }],
        "materials": [{ "normalTexture": { "index": 0 } }],
        "meshes": [{ "primitives": [{
            "attributes": { "POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2 }, "indices": 3, "material": 0
        }] }],
        "nodes": [{ "mesh": 0 }],
        "scenes": [{ "nodes": [0] }],
        "animations": [{
            "name": "slide",
            "channels": [{ "sampler": 0, "target": { "node": 0, "path": "translation" } }],
            "samplers": [{ "input": 4, "output": 5 }]
        }]
    });
    let path = folder.dir.join("split.gltf");
    std::fs::write(&path, document.to_string()).unwrap();
    let mut scene = load_gltf(&path).unwrap();
    assert!(scene.vertices.len() > 4, "the tangents split vertices: {}", scene.vertices.len());
    scene.play(&[0]).unwrap();
    let moved = Poser::of(&scene).unwrap().vertices_at(0.5);
    let mut covered: Vec<usize> = moved.iter().flat_map(|m| m.first..m.first + m.vertices.len()).collect();
    covered.sort_unstable();
    assert_eq!(covered, (0..scene.vertices.len()).collect::<Vec<_>>(), "every vertex and copy moves");
    for m in &moved {
        for (posed, rest) in m.vertices.iter().zip(&scene.vertices[m.first..]) {
            assert_eq!(posed.position[0], rest.position[0] + 1.0, "moved halfway along the slide");
        }
    }
}
