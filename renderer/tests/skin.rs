//! Skinned meshes, read through the gltf crate from files the project's writer makes.
//!
//! A strip bound to two joints lands where its skeleton's rest pose carries it, not where its
//! bind pose or its own node would put it; bending the second joint a quarter turn carries the
//! vertices it holds alone around the joint and those it shares halfway; the positions of the
//! frame before follow the same blend. A broken skin (a vertex without weight, a joint index past
//! the skin, joints without weights, too few inverse bind matrices, a joint outside the scene)
//! is refused naming the node, skin, primitive and field. The `walker` scene's figure moves: its
//! head keeps its shape, its feet move further than its hips, and every vertex blends joints
//! whose weights sum to one. On lavapipe its motion vectors hold each limb's own motion.

use crate::support;

use std::path::PathBuf;

use aabench_renderer::scene::generate::Generator;
use aabench_renderer::scene::load_gltf;
use aabench_renderer::scene::pose::{FileCamera, Poser};
use aabench_renderer::scene::skin::Influence;
use aabench_renderer::scene::write::{Channel, GltfWriter, MaterialDesc, MeshData, SkinDesc, glb};
use glam::{DVec3, Quat};
use serde_json::{Value, json};
use support::Folder;

/// A strip from x = 0 to 3, y = 0 to 1, facing +z: vertices at x = 0 and 1 follow the root
/// joint, those at x = 2 share it half and half with the bent joint, those at x = 3 follow the
/// bent joint alone. The root lies at z = −1 at rest though the skin was bound at z = 0; the
/// bent joint lies 2 along x from it. The mesh's own node stands 100 along x, which glTF says
/// a skinned mesh ignores. The animation `bend` turns the bent joint a quarter about z in a
/// second.
fn strip(joints: [[u16; 4]; 4], weights: [[f32; 4]; 4]) -> GltfWriter {
    strip_bound(joints, weights, BINDS)
}

/// The strip with the root's and the bent joint's inverse bind matrices `binds`.
fn strip_bound(joints: [[u16; 4]; 4], weights: [[f32; 4]; 4], binds: [[f32; 16]; 2]) -> GltfWriter {
    let mut writer = GltfWriter::new("skin test");
    let material = writer.add_material(&MaterialDesc::new("grey", [0.5; 3], 0.8));
    let bent = writer.add_joint("bent", [2.0, 0.0, 0.0], &[]);
    let root = writer.add_joint("root", [0.0, 0.0, -1.0], &[bent]);
    let mut skin = strip_skin([root, bent], joints, weights);
    skin.inverse_binds = binds.to_vec();
    writer.add_skinned_mesh("strip", &strip_mesh(), material, &skin);
    let quarter = Quat::from_rotation_z(std::f32::consts::FRAC_PI_2).to_array();
    writer.add_animation(
        "bend",
        &[Channel {
            node: bent,
            path: "rotation",
            times: vec![0.0, 1.0],
            values: [[0.0, 0.0, 0.0, 1.0], quarter].concat(),
        }],
    );
    writer
}

/// The strip's 8 vertices, two at each x from 0 to 3, and its 6 triangles.
fn strip_mesh() -> MeshData {
    let mut mesh = MeshData::default();
    for x in 0..4 {
        for y in 0..2 {
            mesh.positions.push([x as f32, y as f32, 0.0]);
            mesh.normals.push([0.0, 0.0, 1.0]);
            mesh.uvs.push([x as f32 / 3.0, y as f32]);
        }
    }
    for quad in 0..3u32 {
        let a = 2 * quad;
        mesh.indices.extend([a, a + 2, a + 1, a + 1, a + 2, a + 3]);
    }
    mesh
}

/// The strip's skin of `nodes` (root, bent), with each x's joints and weights.
fn strip_skin(nodes: [usize; 2], joints: [[u16; 4]; 4], weights: [[f32; 4]; 4]) -> SkinDesc {
    SkinDesc {
        joints: nodes.to_vec(),
        inverse_binds: BINDS.to_vec(),
        vertex_joints: joints.iter().flat_map(|j| [*j, *j]).collect(),
        vertex_weights: weights.iter().flat_map(|w| [*w, *w]).collect(),
    }
}

/// The root's inverse bind matrix (bound at the origin) and the bent joint's (2 along x).
const BINDS: [[f32; 16]; 2] = [
    [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0],
    [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, -2.0, 0.0, 0.0, 1.0],
];

const ROOT: [u16; 4] = [0, 0, 0, 0];
const SHARED: [u16; 4] = [0, 1, 0, 0];
const BENT: [u16; 4] = [1, 0, 0, 0];
const ALONE: [f32; 4] = [1.0, 0.0, 0.0, 0.0];
const HALVES: [f32; 4] = [0.5, 0.5, 0.0, 0.0];

fn good_strip() -> GltfWriter {
    strip([ROOT, ROOT, SHARED, BENT], [ALONE, ALONE, HALVES, ALONE])
}

/// The writer's file, its JSON edited, written as `name` into `folder`.
fn write_edited(folder: &Folder, name: &str, writer: &GltfWriter, edit: impl Fn(&mut Value)) -> PathBuf {
    let bytes = writer.to_glb();
    let json_length = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let mut document: Value = serde_json::from_slice(&bytes[20..20 + json_length]).unwrap();
    let bin = &bytes[20 + json_length + 8..];
    edit(&mut document);
    let path = folder.dir.join(name);
    std::fs::write(&path, glb(&document, bin)).unwrap();
    path
}

fn point(p: [f32; 3]) -> DVec3 {
    DVec3::from(p.map(f64::from))
}

#[test]
fn a_skinned_strip_rests_where_its_skeleton_does_and_bends_with_its_joint() {
    let folder = Folder::new("skin-strip");
    // The mesh's node is the last the writer added; its translation must not move the strip.
    let path = write_edited(&folder, "strip.glb", &good_strip(), |d| {
        let node = d["nodes"].as_array().unwrap().len() - 1;
        d["nodes"][node]["translation"] = json!([100.0, 0.0, 0.0]);
    });
    let mut scene = load_gltf(&path).expect("the strip loads");
    let rest: Vec<DVec3> = scene.vertices.iter().map(|v| point(v.position) + scene.origin).collect();
    for (v, p) in rest.iter().enumerate() {
        let expected = DVec3::new((v / 2) as f64, (v % 2) as f64, -1.0);
        assert!((*p - expected).length() < 1e-6, "vertex {v} at rest: {p}, expected {expected}");
    }
    assert_eq!(scene.rig.skins.len(), 1);
    scene.play(&[0]).unwrap();
    let poser = Poser::of(&scene).expect("the animation plays");
    poser.check().expect("every pose within bounds");
    let moved = poser.vertices_at(1.0);
    assert_eq!(moved.len(), 1, "one skinned range: {moved:?}");
    let bent: Vec<DVec3> = moved[0].vertices.iter().map(|v| point(v.position) + scene.origin).collect();
    // Turned a quarter about the joint at (2, 0, −1): (3, 0) to (2, 1) and (3, 1) to (1, 1);
    // (2, 1) halfway between staying and going to (1, 0).
    let expected =
        [[0.0, 0.0], [0.0, 1.0], [1.0, 0.0], [1.0, 1.0], [2.0, 0.0], [1.5, 0.5], [2.0, 1.0], [1.0, 1.0]];
    for (v, (p, [x, y])) in bent.iter().zip(expected).enumerate() {
        assert!(
            (*p - DVec3::new(x, y, -1.0)).length() < 1e-6,
            "vertex {v} bent: {p}, expected ({x}, {y}, −1)"
        );
        let normal = point(moved[0].vertices[v].normal);
        assert!((normal - DVec3::Z).length() < 1e-6, "a turn about z keeps the normal: {normal}");
    }
    // The frame before's positions are the same blend.
    let halfway = poser.vertices_at(0.5);
    let before = poser.positions_at(0.5);
    assert_eq!(before[0].0, halfway[0].first);
    for (p, v) in before[0].1.iter().zip(&halfway[0].vertices) {
        assert_eq!(*p, v.position);
    }
    let tip = point(before[0].1[6]) + scene.origin;
    let eighth = std::f64::consts::FRAC_PI_4;
    let expected = DVec3::new(2.0 + eighth.cos(), eighth.sin(), -1.0);
    assert!((tip - expected).length() < 1e-6, "an eighth turn at half time: {tip}, expected {expected}");
}

/// Each x's joints and weights, one set of the strip's.
type StripSet = ([[u16; 4]; 4], [[f32; 4]; 4]);

/// An animation that moves only a skinned mesh's own node moves nothing (its joints place it,
/// and glTF ignores that node's transform): refused as such, not as a node without geometry.
#[test]
fn an_animation_of_a_skinned_meshs_node_alone_is_refused_naming_the_skin() {
    let folder = Folder::new("skin-node-only");
    let path = write_edited(&folder, "strip.glb", &good_strip(), |d| {
        let node = d["nodes"].as_array().unwrap().len() - 1;
        d["animations"][0]["channels"][0]["target"] = json!({ "node": node, "path": "rotation" });
    });
    let mut scene = load_gltf(&path).expect("the strip loads");
    scene.play(&[0]).unwrap();
    let poser = Poser::of(&scene).expect("the animation plays");
    let error = poser.check_moves_something(FileCamera::Still).expect_err("nothing in the frame moves");
    let node = scene.rig.nodes.iter().map(|n| n.node).max().unwrap();
    let expected =
        format!("moves only nodes[{node}]: nodes[{node}] holds a skinned mesh, which its joints place");
    assert!(error.starts_with(&expected), "{error}");
}

/// The strip of `first` joints and weights, given two more sets of them (each set's accessors
/// taken from a mesh added for it and left out of the scene), loaded.
fn strip_of_three_sets(
    folder: &Folder,
    name: &str,
    first: StripSet,
    more: [StripSet; 2],
) -> aabench_renderer::scene::Scene {
    let mut writer = strip(first.0, first.1);
    let material = writer.add_material(&MaterialDesc::new("donor", [0.5; 3], 0.8));
    for (set, (joints, weights)) in more.into_iter().enumerate() {
        // Joints 0 and 1 of the skin: the root and the bent joint, as in the strip's own skin.
        writer.add_skinned_mesh(
            &format!("set {}", set + 1),
            &strip_mesh(),
            material,
            &strip_skin([1, 0], joints, weights),
        );
    }
    let path = write_edited(folder, name, &writer, |d| {
        for set in [1, 2] {
            let donor = d["meshes"][set]["primitives"][0]["attributes"].clone();
            let attributes = &mut d["meshes"][0]["primitives"][0]["attributes"];
            attributes[format!("JOINTS_{set}")] = donor["JOINTS_0"].clone();
            attributes[format!("WEIGHTS_{set}")] = donor["WEIGHTS_0"].clone();
        }
        let mesh_nodes: Vec<u64> = (d["nodes"].as_array().unwrap().iter().enumerate())
            .filter(|(_, n)| n["mesh"].as_u64().is_some_and(|m| m > 0))
            .map(|(i, _)| i as u64)
            .collect();
        d["scenes"][0]["nodes"]
            .as_array_mut()
            .unwrap()
            .retain(|n| !mesh_nodes.contains(&n.as_u64().unwrap()));
    });
    load_gltf(&path).expect("the strip loads")
}

/// A third set of joints and weights carries its share: the shared vertices' weight half on
/// the root in `WEIGHTS_0`, none in `WEIGHTS_1`, half on the bent joint in `WEIGHTS_2` bends as
/// the good strip does. Past eight joints a vertex keeps its heaviest, and the file is told.
#[test]
fn a_third_set_of_joints_and_weights_carries_its_share() {
    let folder = Folder::new("skin-sets");
    let (half, nothing) = ([0.5, 0.0, 0.0, 0.0], [0.0; 4]);
    let first = ([ROOT, ROOT, ROOT, BENT], [ALONE, ALONE, half, ALONE]);
    let more = [([ROOT; 4], [nothing; 4]), ([ROOT, ROOT, BENT, ROOT], [nothing, nothing, half, nothing])];
    let mut scene = strip_of_three_sets(&folder, "sets.glb", first, more);
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    scene.play(&[0]).unwrap();
    let poser = Poser::of(&scene).expect("the animation plays");
    let bent: Vec<DVec3> =
        poser.vertices_at(1.0)[0].vertices.iter().map(|v| point(v.position) + scene.origin).collect();
    // (2, 1) halfway between staying and going to (1, 0), as it is with both halves in one set.
    assert!((bent[5] - DVec3::new(1.5, 0.5, -1.0)).length() < 1e-6, "{:?}", bent[5]);

    // Every vertex names the root nine times, the ninth at half weight: it goes.
    let full = ([ROOT; 4], [[1.0; 4]; 4]);
    let ninth = ([ROOT; 4], [half; 4]);
    let crowded = strip_of_three_sets(&folder, "crowded.glb", full, [full, ninth]);
    let said = "attributes.JOINTS_0 to JOINTS_2: 8 vertices name more than 8 joints; each keeps its 8 \
                heaviest, dropping at most 5.9 % of a vertex's weight";
    let told = crowded.warnings.iter().any(|w| w == &format!("meshes[0] (strip) primitives[0]: {said}"));
    assert!(told, "{:?}", crowded.warnings);
}

/// A change to a written file's JSON, which breaks it.
type Edit = dyn Fn(&mut Value);

#[test]
fn a_broken_skin_is_refused_naming_the_part_at_fault() {
    let folder = Folder::new("skin-broken");
    let nothing = [0.0; 4];
    let far = [7, 0, 0, 0];
    let cases: Vec<(&str, GltfWriter, Box<Edit>, &str)> = vec![
        (
            "weightless.glb",
            strip([ROOT, ROOT, SHARED, BENT], [ALONE, nothing, HALVES, ALONE]),
            Box::new(|_| {}),
            "attributes.JOINTS and WEIGHTS: vertex 2: its weights sum to 0, so no joint carries it",
        ),
        (
            "far-joint.glb",
            strip([ROOT, ROOT, SHARED, far], [ALONE, ALONE, HALVES, ALONE]),
            Box::new(|_| {}),
            "vertex 6: joint 7 (weight 1) does not exist: the skin has 2",
        ),
        (
            "no-weights.glb",
            good_strip(),
            Box::new(|d| {
                d["meshes"][0]["primitives"][0]["attributes"].as_object_mut().unwrap().remove("WEIGHTS_0");
            }),
            "needs attributes.JOINTS_0 and WEIGHTS_0 together",
        ),
        (
            "gap.glb",
            good_strip(),
            Box::new(|d| {
                let attributes = &mut d["meshes"][0]["primitives"][0]["attributes"];
                attributes["JOINTS_2"] = attributes["JOINTS_0"].clone();
                attributes["WEIGHTS_2"] = attributes["WEIGHTS_0"].clone();
            }),
            "needs attributes.JOINTS_1 and WEIGHTS_1 together, as it has a set numbered 2",
        ),
        (
            "few-binds.glb",
            good_strip(),
            Box::new(|d| {
                let accessor = d["skins"][0]["inverseBindMatrices"].as_u64().unwrap() as usize;
                d["accessors"][accessor]["count"] = json!(1);
            }),
            "skins[0].inverseBindMatrices: accessors[",
        ),
        (
            // An inverse bind matrix undoes the joint's bind pose; one of zeros has no inverse
            // and collapses the strip's bent end to a point, at rest as in motion.
            "zero-bind.glb",
            strip_bound([ROOT, ROOT, SHARED, BENT], [ALONE, ALONE, HALVES, ALONE], [BINDS[0], [0.0; 16]]),
            Box::new(|_| {}),
            "skins[0].inverseBindMatrices: matrix 1 has no inverse (its determinant is 0)",
        ),
        (
            "stray-joint.glb",
            good_strip(),
            Box::new(|d| {
                d["nodes"].as_array_mut().unwrap().push(json!({ "name": "stray" }));
                let stray = d["nodes"].as_array().unwrap().len() - 1;
                d["skins"][0]["joints"][1] = json!(stray);
            }),
            "skins[0].joints[1]: nodes[",
        ),
    ];
    for (name, writer, edit, expected) in cases {
        let path = write_edited(&folder, name, &writer, edit);
        let message = support::error(&path);
        assert!(message.contains(expected), "{name}: {message}");
        assert!(
            message.contains("nodes[") || message.contains("meshes["),
            "{name} names the part: {message}"
        );
    }
}

#[test]
fn the_walkers_figure_bends_its_limbs_and_keeps_its_head() {
    let (mut scene, _) = support::generated(Generator::Walker);
    assert_eq!(scene.rig.skins.len(), 1, "one skinned figure");
    let skin = &scene.rig.skins[0];
    assert_eq!(skin.joints.len(), 11);
    assert_eq!(skin.influences.len(), skin.vertex_indices().count());
    assert!(skin.influences.iter().all(|i| (i.weights.iter().sum::<f32>() - 1.0).abs() < 1e-5));
    let walk = scene.animations.iter().position(|a| a.name.as_deref() == Some("walk")).unwrap();
    scene.play(&[walk]).unwrap();
    let poser = Poser::of(&scene).expect("the walk plays");
    poser.check().expect("every pose within bounds");
    let at = |t: f64| -> Vec<(usize, DVec3)> {
        let posed = poser.positions_at(t);
        posed
            .iter()
            .flat_map(|(first, p)| p.iter().enumerate().map(move |(i, p)| (first + i, point(*p))))
            .collect()
    };
    // A quarter of a stride (two strides a second).
    let (start, quarter) = (at(0.0), at(0.125));
    let head = |i: &Influence| i.weights[0] == 1.0 && i.joints[0] == 2;
    let heads: Vec<usize> = (0..start.len()).filter(|&k| head(&scene.rig.skins[0].influences[k])).collect();
    assert!(heads.len() > 100, "the head's vertices: {}", heads.len());
    // The head turns and moves rigidly: distances between its vertices keep.
    for pair in heads.windows(2).step_by(7) {
        let before = (start[pair[0]].1 - start[pair[1]].1).length();
        let after = (quarter[pair[0]].1 - quarter[pair[1]].1).length();
        assert!((before - after).abs() < 1e-4, "the head keeps its shape: {before} against {after}");
    }
    // The limbs move against the body: some vertex (a swinging foot) has moved at least 20 cm
    // further than the head, which the hips carry along.
    let head_move = quarter[heads[0]].1 - start[heads[0]].1;
    let travel = |k: usize| (quarter[k].1 - start[k].1 - head_move).length();
    let furthest = (0..start.len()).map(travel).fold(0.0, f64::max);
    assert!(furthest > 0.2, "the limbs move {furthest} m against the head");
}
