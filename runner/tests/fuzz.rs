//! Fuzzing the loaders: valid seed files, randomly mutated (JSON values replaced, removed,
//! duplicated and spliced; keys the seeds lack inserted; binary words overwritten; bits
//! flipped; files cut short), fed to the glTF importer (as GLB, as `.gltf` with a `.bin` beside
//! it, or with the buffer embedded as a data URI) and to the manifest loader (parse,
//! validation, generation, import, camera and lights). Every input must end in a result that
//! keeps the loader's promises or in an error that names the file: never a panic, never a
//! hang, never a file written outside the manifest's folder. No device needed.
//!
//! Each input is loaded on its own thread with a 20 s limit. A loaded scene must keep the
//! loader's promises (finite vertices, indices in range, whole triangles, textures of their
//! stated size, a valid camera, finite lights); an error must name the file.
//!
//! `AABENCH_FUZZ_CASES` sets the number of inputs per loader (default 10 000, about ten
//! seconds, which is what CI runs) and `AABENCH_FUZZ_SEED` the random seed (default: the
//! clock); both are printed, and a printed seed given back repeats the run. A failing input
//! stays in the temporary folder and proptest shrinks it to the fewest mutations that still
//! fail. 200 000 inputs per loader once ran with 0 panics and 0 hangs
//! (`AABENCH_FUZZ_CASES=200000`, 221 s).
//!
//! The fuzzer found five panics, each fixed with a test: four in the gltf crate (now in
//! `renderer/tests/import.rs`) and a light at 10³⁰⁸, finite in f64 and infinite in f32
//! (manifest positions are now bounded to ±10¹², a unit test of `src/manifest/`). A review
//! of its reach found four more that the first mutations could not produce (a short stride, a
//! count of 0, %-escapes, multiplied node scales), which the insert mutation now can.

use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Duration;

use aabench::manifest::Manifest;
use aabench::plan::Tier;
use aabench::run::render_settings;
use aabench::run::scenes;
use aabench_renderer::ExtraSamples;
use aabench_renderer::scene::generate::Generator;
use aabench_renderer::scene::write::{GltfWriter, MaterialDesc, MeshData, glb};
use aabench_renderer::scene::{LightKind, MAX_TEXTURE_SIDE, Scene, load_gltf};
use glam::DVec3;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestCaseError, TestRng, TestRunner};
use serde_json::{Value, json};

/// Longer than any honest load of these small files takes, by orders of magnitude.
const HANG: Duration = Duration::from_secs(20);

/// Numbers, strings and shapes that break parsers: limits of every integer width glTF uses,
/// floats at and beyond f32's range, paths that leave the folder, URIs with schemes.
fn interesting_value(pick: usize) -> Value {
    let values = [
        json!(0),
        json!(1),
        json!(-1),
        json!(2),
        json!(3),
        json!(255),
        json!(65_535),
        json!(65_536),
        json!(i32::MAX),
        json!(2_147_483_648u64),
        json!(u32::MAX),
        json!(4_294_967_296u64),
        json!(9_007_199_254_740_993u64),
        json!(-9_007_199_254_740_993i64),
        json!(0.5),
        json!(-0.0),
        json!(1e-45),
        json!(3.5e38),
        json!(1e308),
        json!(-1e308),
        json!(5126),
        json!(5125),
        json!(5123),
        json!(5121),
        json!(34962),
        json!(""),
        json!("VEC3"),
        json!("SCALAR"),
        json!("MAT4"),
        json!("MASK"),
        json!("BLEND"),
        json!("orthographic"),
        json!("../outside.bin"),
        json!("/nonexistent-aabench/x.glb"),
        json!("file:///etc/hostname"),
        json!("%2e%2e/x.bin"),
        json!("data:application/octet-stream;base64,AAAA"),
        json!("data:image/png;base64,iVBORw0KGgo="),
        json!("data:,"),
        json!("KHR_materials_unlit"),
        json!("cornell"),
        json!("world"),
        json!("hdr"),
        json!("pq"),
        json!("asymmetric"),
        json!("own.glb"),
        json!("fuzz.json"),
        json!(null),
        json!(true),
        json!([]),
        json!({}),
        json!([0, 0, 0]),
        json!([1e308, -1e308, 0]),
        json!([0, 0, 0, 0]),
        json!([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0]),
        json!([0, 1, 2, 3, 4, 5, 6, 7]),
        json!({ "count": 1, "indices": { "bufferView": 0, "componentType": 5125 }, "values": { "bufferView": 0 } }),
        json!({ "KHR_texture_transform": { "offset": [0.5, 0], "scale": [2, 2], "rotation": 1e30 } }),
        json!({ "KHR_lights_punctual": { "light": 0 } }),
        json!(["KHR_draco_mesh_compression"]),
        json!({ "xmag": 1, "ymag": 0, "znear": 0, "zfar": -1 }),
        json!({ "yfov": 0, "znear": 0 }),
        json!({ "index": 0, "texCoord": 7 }),
    ];
    values[pick % values.len()].clone()
}

/// Words written over binary data: NaN, ±Inf, f32 limits, denormals, huge indices.
const INTERESTING_WORDS: [u32; 12] = [
    0,
    1,
    3,
    0xFFFF_FFFF,
    0x7FC0_0000,
    0x7F80_0000,
    0xFF80_0000,
    0x7F7F_FFFF,
    0x0000_0001,
    0x8000_0000,
    0x0000_FFFF,
    1_000_000,
];

#[derive(Debug, Clone)]
enum Mutation {
    /// The `node`-th JSON value (pre-order) becomes an interesting one.
    Replace { node: usize, value: usize },
    /// The `node`-th JSON value is removed from its object or array.
    Remove { node: usize },
    /// The `node`-th JSON value is appended once more to the array or object holding it.
    Duplicate { node: usize },
    /// The `to`-th JSON value becomes a copy of the `from`-th.
    Splice { from: usize, to: usize },
    /// A key the format knows, with an interesting value, is added to the `node`-th object.
    Insert { node: usize, key: usize, value: usize },
    /// Four bytes of the binary buffer are overwritten with an interesting word.
    Word { offset: usize, word: usize },
    /// One bit of the written file is flipped.
    Bit { offset: usize, bit: u8 },
    /// The written file is cut short.
    Truncate { keep: usize },
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        4 => (any::<usize>(), any::<usize>()).prop_map(|(node, value)| Mutation::Replace { node, value }),
        2 => any::<usize>().prop_map(|node| Mutation::Remove { node }),
        1 => any::<usize>().prop_map(|node| Mutation::Duplicate { node }),
        1 => (any::<usize>(), any::<usize>()).prop_map(|(from, to)| Mutation::Splice { from, to }),
        3 => (any::<usize>(), any::<usize>(), any::<usize>())
            .prop_map(|(node, key, value)| Mutation::Insert { node, key, value }),
        2 => (any::<usize>(), any::<usize>()).prop_map(|(offset, word)| Mutation::Word { offset, word }),
        1 => (any::<usize>(), 0u8..8).prop_map(|(offset, bit)| Mutation::Bit { offset, bit }),
        1 => any::<usize>().prop_map(|keep| Mutation::Truncate { keep }),
    ]
}

#[derive(Debug, Clone, Copy)]
enum Container {
    Glb,
    /// `.gltf` with the buffer in `fuzz.bin` beside it.
    Separate,
    /// `.gltf` with the buffer as a base64 data URI.
    Embedded,
}

#[derive(Debug, Clone)]
struct Input {
    seed: usize,
    container: Container,
    mutations: Vec<Mutation>,
}

fn input(seeds: usize) -> impl Strategy<Value = Input> {
    let container = prop_oneof![Just(Container::Glb), Just(Container::Separate), Just(Container::Embedded)];
    (0..seeds, container, prop::collection::vec(mutation(), 1..6))
        .prop_map(|(seed, container, mutations)| Input { seed, container, mutations })
}

/// A seed: the JSON document and the binary buffer of a valid file.
#[derive(Debug, Clone)]
struct Seed {
    document: Value,
    bin: Vec<u8>,
}

impl Seed {
    fn from_glb(glb: &[u8]) -> Seed {
        let chunk = |at: usize| {
            let length = u32::from_le_bytes(glb[at..at + 4].try_into().unwrap()) as usize;
            (&glb[at + 8..at + 8 + length], at + 8 + length)
        };
        let (json, next) = chunk(12);
        let (bin, _) = chunk(next);
        Seed { document: serde_json::from_slice(json).unwrap(), bin: bin.to_vec() }
    }
}

/// Small valid files that between them use every part of glTF the importer reads: a textured,
/// alpha-masked, double-sided material, indexed meshes, a camera, a placed root node, and the
/// generator's Cornell box and degenerate scene.
fn seeds() -> Vec<Seed> {
    let mut writer = GltfWriter::new("fuzz seed");
    let mut png = Vec::new();
    image::RgbaImage::from_fn(4, 4, |x, y| image::Rgba([(x * 60) as u8, (y * 60) as u8, 128, 200]))
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    let texture = writer.add_png("checker", &png);
    let leaf = writer.add_material(
        &MaterialDesc::new("leaf", [0.2, 0.8, 0.2], 0.5).textured(texture).masked(0.5).double_sided(),
    );
    let plain = writer.add_material(&MaterialDesc::new("plain", [0.8, 0.8, 0.8], 0.3).metallic(1.0));
    let quad = MeshData {
        positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
        normals: vec![[0.0, 0.0, 1.0]; 4],
        uvs: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
        indices: vec![0, 1, 2, 0, 2, 3],
    };
    writer.add_mesh("leaf", &quad, leaf);
    writer.add_mesh("plain", &quad, plain);
    writer.add_camera(DVec3::new(0.5, 0.5, 3.0), DVec3::new(0.5, 0.5, 0.0), 45.0, 0.1, 100.0);
    writer.place(2.0, [1e5, 0.0, -3.0]);
    let mut textured = Seed::from_glb(&writer.to_glb());
    add_lights(&mut textured.document);
    add_material_maps(&mut textured.document);
    let mut seeds = vec![textured];
    for generator in [Generator::Cornell, Generator::Degenerate] {
        seeds.push(Seed::from_glb(&generator.build(1).to_glb()));
    }
    seeds
}

/// Metallic-roughness, normal, emissive and occlusion textures with their factors and UV transforms on the second
/// material, so mutations reach every texture slot.
fn add_material_maps(document: &mut Value) {
    let transform =
        json!({ "KHR_texture_transform": { "offset": [0.5, 0], "rotation": 0.3, "scale": [2, 2] } });
    let material = &mut document["materials"][1];
    material["normalTexture"] = json!({ "index": 0, "scale": 0.5, "extensions": transform });
    material["occlusionTexture"] = json!({ "index": 0, "strength": 0.5, "extensions": transform });
    material["emissiveTexture"] = json!({ "index": 0, "extensions": transform });
    material["pbrMetallicRoughness"]["metallicRoughnessTexture"] = json!({ "index": 0 });
    material["emissiveFactor"] = json!([1.0, 0.5, 0.0]);
    material["extensions"] = json!({ "KHR_materials_emissive_strength": { "emissiveStrength": 2.0 } });
    document["extensionsUsed"] =
        json!(["KHR_lights_punctual", "KHR_texture_transform", "KHR_materials_emissive_strength"]);
}

/// KHR_lights_punctual's three kinds on nodes of their own, so mutations reach the lights.
fn add_lights(document: &mut Value) {
    document["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    document["extensions"] = json!({ "KHR_lights_punctual": { "lights": [
        { "type": "point", "color": [1, 0.8, 0.6], "intensity": 20, "range": 30 },
        { "type": "spot", "intensity": 50, "spot": { "innerConeAngle": 0.2, "outerConeAngle": 0.6 } },
        { "type": "directional", "intensity": 2 }
    ] } });
    let nodes = document["nodes"].as_array_mut().expect("nodes");
    let first = nodes.len();
    for light in 0..3 {
        nodes.push(json!({
            "translation": [0.5, 2.0, 1.0],
            "rotation": [-0.5, 0.0, 0.0, 0.866],
            "extensions": { "KHR_lights_punctual": { "light": light } }
        }));
    }
    let roots = document["scenes"][0]["nodes"].as_array_mut().expect("scene nodes");
    roots.extend((first..first + 3).map(|n| json!(n)));
}

/// Every JSON value in pre-order, as a path of keys and indices from the root.
fn paths(value: &Value) -> Vec<Vec<Step>> {
    let mut out = vec![Vec::new()];
    let mut stack = vec![(Vec::new(), value)];
    while let Some((path, value)) = stack.pop() {
        let children: Vec<(Step, &Value)> = match value {
            Value::Object(map) => map.iter().map(|(k, v)| (Step::Key(k.clone()), v)).collect(),
            Value::Array(items) => items.iter().enumerate().map(|(i, v)| (Step::Index(i), v)).collect(),
            _ => Vec::new(),
        };
        for (step, child) in children {
            let mut child_path: Vec<Step> = path.clone();
            child_path.push(step);
            out.push(child_path.clone());
            stack.push((child_path, child));
        }
    }
    out
}

#[derive(Debug, Clone)]
enum Step {
    Key(String),
    Index(usize),
}

fn at<'a>(root: &'a mut Value, path: &[Step]) -> &'a mut Value {
    path.iter().fold(root, |value, step| match step {
        Step::Key(key) => &mut value[key.as_str()],
        Step::Index(i) => &mut value[*i],
    })
}

fn at_ref<'a>(root: &'a Value, path: &[Step]) -> &'a Value {
    path.iter().fold(root, |value, step| match step {
        Step::Key(key) => &value[key.as_str()],
        Step::Index(i) => &value[*i],
    })
}

/// Keys of glTF and of manifests that seeds may lack: optional fields, extensions, the other
/// projection, sparse storage.
const KNOWN_KEYS: [&str; 36] = [
    "byteStride",
    "byteOffset",
    "count",
    "sparse",
    "normalized",
    "mimeType",
    "uri",
    "bufferView",
    "extensions",
    "extensionsRequired",
    "extensionsUsed",
    "orthographic",
    "perspective",
    "type",
    "matrix",
    "scale",
    "rotation",
    "translation",
    "children",
    "camera",
    "mesh",
    "indices",
    "material",
    "mode",
    "NORMAL",
    "TEXCOORD_0",
    "TANGENT",
    "baseColorTexture",
    "texCoord",
    "sampler",
    "alphaMode",
    "generate",
    "normalTexture",
    "occlusionTexture",
    "emissiveTexture",
    "strength",
];

fn mutate_json(document: &mut Value, mutation: &Mutation) {
    let all = paths(document);
    let pick = |n: usize| &all[n % all.len()];
    match *mutation {
        Mutation::Replace { node, value } => *at(document, pick(node)) = interesting_value(value),
        Mutation::Insert { node, key, value } => {
            let objects: Vec<&Vec<Step>> = all.iter().filter(|p| at_ref(document, p).is_object()).collect();
            if objects.is_empty() {
                return;
            }
            if let Value::Object(map) = at(document, objects[node % objects.len()]) {
                map.insert(KNOWN_KEYS[key % KNOWN_KEYS.len()].to_string(), interesting_value(value));
            }
        }
        Mutation::Splice { from, to } => {
            let copy = at(document, pick(from)).clone();
            *at(document, pick(to)) = copy;
        }
        Mutation::Remove { node } | Mutation::Duplicate { node } => {
            let path = pick(node);
            let Some((last, parent)) = path.split_last() else { return };
            let copy = at(document, path).clone();
            let duplicate = matches!(mutation, Mutation::Duplicate { .. });
            match (at(document, parent), last) {
                (Value::Object(map), Step::Key(key)) if duplicate => {
                    map.insert(format!("{key}_copy"), copy);
                }
                (Value::Object(map), Step::Key(key)) => {
                    map.remove(key);
                }
                (Value::Array(items), Step::Index(_)) if duplicate => items.push(copy),
                (Value::Array(items), Step::Index(i)) => {
                    items.remove(*i);
                }
                _ => {}
            }
        }
        _ => {}
    }
}

/// Writes the mutated input into `folder`; returns the file to import.
fn write_input(folder: &Path, seed: &Seed, input: &Input) -> PathBuf {
    let mut document = seed.document.clone();
    let mut bin = seed.bin.clone();
    for mutation in &input.mutations {
        mutate_json(&mut document, mutation);
        if let Mutation::Word { offset, word } = *mutation
            && bin.len() >= 4
        {
            let at = (offset % (bin.len() - 3)) & !3;
            bin[at..at + 4].copy_from_slice(&INTERESTING_WORDS[word % INTERESTING_WORDS.len()].to_le_bytes());
        }
    }
    let (path, mut bytes) = match input.container {
        Container::Glb => (folder.join("fuzz.glb"), glb(&document, &bin)),
        Container::Separate => {
            std::fs::write(folder.join("fuzz.bin"), &bin).unwrap();
            set_buffer_uri(&mut document, "fuzz.bin");
            (folder.join("fuzz.gltf"), serde_json::to_vec(&document).unwrap())
        }
        Container::Embedded => {
            let uri = format!("data:application/octet-stream;base64,{}", base64::encode(&bin));
            set_buffer_uri(&mut document, &uri);
            (folder.join("fuzz.gltf"), serde_json::to_vec(&document).unwrap())
        }
    };
    mutate_bytes(&mut bytes, &input.mutations);
    std::fs::write(&path, bytes).unwrap();
    path
}

/// The mutations that act on the written file: flipped bits, a cut.
fn mutate_bytes(bytes: &mut Vec<u8>, mutations: &[Mutation]) {
    for mutation in mutations {
        match *mutation {
            Mutation::Bit { offset, bit } if !bytes.is_empty() => {
                let at = offset % bytes.len();
                bytes[at] ^= 1 << bit;
            }
            Mutation::Truncate { keep } => bytes.truncate(keep % (bytes.len() + 1)),
            _ => {}
        }
    }
}

fn set_buffer_uri(document: &mut Value, uri: &str) {
    if let Some(buffer) =
        document.get_mut("buffers").and_then(|b| b.get_mut(0)).and_then(Value::as_object_mut)
    {
        buffer.insert("uri".to_string(), json!(uri));
    }
}

/// What an imported scene promises the renderer, whatever the file said.
fn check_scene(scene: &Scene) -> Result<(), String> {
    let finite = |v: &[f32]| v.iter().all(|x| x.is_finite());
    for (i, vertex) in scene.vertices.iter().enumerate() {
        if !finite(&vertex.position) || !finite(&vertex.normal) || !finite(&vertex.uv) {
            return Err(format!("vertex {i} is not finite: {vertex:?}"));
        }
        if vertex.material as usize >= scene.materials.len() {
            return Err(format!(
                "vertex {i} names material {} of {}",
                vertex.material,
                scene.materials.len()
            ));
        }
    }
    if !scene.indices.len().is_multiple_of(3) {
        return Err(format!("{} indices, not whole triangles", scene.indices.len()));
    }
    if let Some(index) = scene.indices.iter().find(|&&i| i as usize >= scene.vertices.len()) {
        return Err(format!("index {index} of {} vertices", scene.vertices.len()));
    }
    let drawn: u32 = scene.draws.iter().map(|(_, range)| range.len() as u32).sum();
    if drawn as usize != scene.indices.len()
        || scene.draws.iter().any(|(_, r)| r.end as usize > scene.indices.len())
    {
        return Err(format!("draws {:?} do not cover {} indices", scene.draws, scene.indices.len()));
    }
    for material in &scene.materials {
        if material.textures().any(|t| t.texture >= scene.textures.len()) {
            return Err(format!("material {} names a missing texture", material.name));
        }
        let transforms = material.textures().flat_map(|t| t.transform.rows.into_iter().flatten());
        let factors =
            [material.normal_scale, material.occlusion_strength].into_iter().chain(material.emissive);
        if !transforms.chain(factors).all(f32::is_finite) || material.emissive.iter().any(|&c| c < 0.0) {
            return Err(format!("material {}: a factor or UV transform is not finite", material.name));
        }
    }
    let tangents_fit = scene.tangents.is_empty() || scene.tangents.len() == scene.vertices.len();
    if !tangents_fit || !scene.tangents.iter().flatten().all(|c| c.is_finite()) {
        return Err(format!(
            "{} tangents for {} vertices, or not finite",
            scene.tangents.len(),
            scene.vertices.len()
        ));
    }
    for texture in &scene.textures {
        let side_ok = (1..=MAX_TEXTURE_SIDE).contains(&texture.width)
            && (1..=MAX_TEXTURE_SIDE).contains(&texture.height);
        if !side_ok || texture.rgba.len() != texture.width as usize * texture.height as usize * 4 {
            return Err(format!(
                "texture {}×{} with {} bytes",
                texture.width,
                texture.height,
                texture.rgba.len()
            ));
        }
    }
    if !scene.origin.is_finite() {
        return Err(format!("origin {}", scene.origin));
    }
    for light in &scene.lights {
        let sound = light.position.is_finite()
            && light.color.is_finite()
            && light.intensity.is_finite()
            && light.range.is_finite()
            && light.range > 0.0
            && match light.kind {
                LightKind::Point => true,
                LightKind::Spot { direction, inner, outer } => {
                    direction.is_normalized()
                        && 0.0 <= inner
                        && inner < outer
                        && outer <= std::f32::consts::FRAC_PI_2
                }
                LightKind::Directional { direction } => direction.is_normalized(),
            };
        if !sound {
            return Err(format!("light {light:?}"));
        }
    }
    Ok(())
}

/// Runs `work` on its own thread: a panic or a hang becomes an error of this input.
fn guarded<T: Send + 'static>(
    work: impl FnOnce() -> Result<T, String> + Send + 'static,
) -> Result<T, String> {
    let (send, receive) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = send.send(work());
    });
    match receive.recv_timeout(HANG) {
        Ok(outcome) => outcome,
        Err(mpsc::RecvTimeoutError::Timeout) => Err(format!("no answer in {HANG:?}: a hang")),
        Err(mpsc::RecvTimeoutError::Disconnected) => Err("the loader panicked".to_string()),
    }
}

/// An error is a fine answer to a broken input if it names the file.
fn refused(message: String, path: &Path) -> Result<bool, String> {
    match message.contains(&path.display().to_string()) {
        true => Ok(false),
        false => Err(format!("the error does not name the file: {message}")),
    }
}

/// Feeds `cases` inputs from `strategy` through `load` (Ok(true): loaded and sound; Ok(false):
/// refused with an error that names the file) and returns how many loaded and how many were
/// refused. Panics with the shrunk input when one panicked, hung or broke a promise.
fn fuzz<I: std::fmt::Debug>(
    what: &str,
    folder: &Path,
    strategy: impl Strategy<Value = I>,
    load: impl Fn(&I) -> Result<bool, String>,
) {
    let cases = std::env::var("AABENCH_FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(10_000);
    // A fresh seed each run explores new inputs; it is printed so any run can be repeated.
    let seed: u64 =
        std::env::var("AABENCH_FUZZ_SEED").ok().and_then(|v| v.parse().ok()).unwrap_or_else(|| {
            std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap_or_default().as_nanos()
                as u64
        });
    let mut seed_bytes = [0u8; 32];
    seed_bytes[..8].copy_from_slice(&seed.to_le_bytes());
    let rng = TestRng::from_seed(RngAlgorithm::ChaCha, &seed_bytes);
    let counts = std::cell::Cell::new([0u32; 2]);
    let config = Config { cases, failure_persistence: None, ..Config::default() };
    let mut runner = TestRunner::new_with_rng(config, rng);
    let result = runner.run(&strategy, |input| {
        let loaded = load(&input).map_err(TestCaseError::fail)?;
        let mut count = counts.get();
        count[usize::from(!loaded)] += 1;
        counts.set(count);
        Ok(())
    });
    if let Err(failure) = result {
        panic!(
            "{what}: {failure} (input left in {}; repeat with AABENCH_FUZZ_SEED={seed})",
            folder.display()
        );
    }
    let [loaded, refused] = counts.get();
    eprintln!(
        "fuzzed {what} with {cases} inputs (AABENCH_FUZZ_SEED={seed}): {loaded} loaded, {refused} refused, 0 panics, 0 hangs"
    );
    // A harness whose mutations all broke the file would test only the parser's front door.
    assert!(loaded > cases / 20, "{what}: only {loaded} of {cases} mutated inputs loaded");
    assert!(refused > cases / 20, "{what}: only {refused} of {cases} mutated inputs were refused");
}

fn temporary_folder(name: &str) -> PathBuf {
    let folder = std::env::temp_dir().join(format!("aabench-fuzz-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&folder);
    std::fs::create_dir_all(&folder).unwrap();
    folder
}

/// The glTF importer on mutated seeds (a textured, masked, placed file with a camera, the
/// generated Cornell box and degenerate scene) written as GLB, `.gltf` + `.bin` and `.gltf`
/// with a data URI: every input loads into a sound scene or is refused naming the file, and
/// more than 5% of inputs end each way.
#[test]
fn mutated_gltf_files_are_errors_or_sound_scenes_never_panics_or_hangs() {
    let folder = temporary_folder("gltf");
    let seeds = seeds();
    for (i, seed) in seeds.iter().enumerate() {
        let path = folder.join(format!("seed{i}.glb"));
        std::fs::write(&path, glb(&seed.document, &seed.bin)).unwrap();
        check_scene(&load_gltf(&path).expect("every seed is a valid file")).unwrap();
    }
    fuzz("the glTF importer", &folder, input(seeds.len()), |input| {
        let path = write_input(&folder, &seeds[input.seed], input);
        let owned = path.clone();
        guarded(move || match load_gltf(&owned) {
            Ok(scene) => check_scene(&scene).map(|()| true).map_err(|e| format!("imported, but {e}")),
            Err(error) => refused(error.to_string(), &owned),
        })
        .map_err(|e| format!("{}: {e}", path.display()))
    });
    let _ = std::fs::remove_dir_all(&folder);
}

/// Generators whose files take milliseconds to write: a mutated seed or placement regenerates.
const CHEAP_GENERATORS: [&str; 6] = ["cornell", "degenerate", "subpixel", "plane", "crossing", "walker"];

/// The suite's manifests (their generators swapped for cheap ones where needed), plus one that
/// renders a user's own file (the textured seed) with the file's camera.
fn manifest_seeds(folder: &Path) -> Vec<Value> {
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let mut paths: Vec<PathBuf> = std::fs::read_dir(&scenes)
        .unwrap()
        .map(|entry| entry.unwrap().path())
        .filter(|path| path.extension().is_some_and(|e| e == "json"))
        .collect();
    paths.sort();
    let mut manifests: Vec<Value> =
        paths.iter().map(|path| serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()).collect();
    for manifest in &mut manifests {
        if let Some(generator) = manifest.pointer_mut("/generate/generator")
            && !CHEAP_GENERATORS.contains(&generator.as_str().unwrap())
        {
            *generator = json!("cornell");
        }
    }
    let own = &seeds()[0];
    std::fs::write(folder.join("own.glb"), glb(&own.document, &own.bin)).unwrap();
    manifests.push(json!({
        "schema_version": 1,
        "name": "own",
        "gltf": "own.glb",
        "resolution": { "quick": [16, 12], "nightly": [32, 24] },
        "lights": [{ "position": [1.0, 2.0, 3.0], "color": [1, 1, 1], "intensity": 10.0, "range": 20.0 }]
    }));
    manifests
}

/// What a loaded manifest promises the renderer: a valid camera, finite lights, settings that
/// can be built for every tier, inputs that can be hashed.
fn check_manifest(manifest: &Manifest) -> Result<bool, String> {
    for tier in [Tier::Quick, Tier::Nightly] {
        for extra in [ExtraSamples::Compact, ExtraSamples::Loop] {
            render_settings(manifest, tier, extra);
        }
    }
    let loaded = match scenes::load(manifest) {
        Ok(loaded) => loaded,
        Err(error) => return refused(format!("{error:#}"), &manifest.path),
    };
    check_scene(&loaded.scene)?;
    loaded.camera.validate().map_err(|e| format!("loaded, but the camera is invalid: {e}"))?;
    if let Some(light) =
        loaded.lighting.lights.iter().find(|l| !(l.position.is_finite() && l.color.is_finite()))
    {
        return Err(format!("loaded, but a light is not finite: {light:?}"));
    }
    aabench::plan::inputs::SceneInputs::of(manifest)
        .map_err(|e| format!("loaded, but the inputs cannot be hashed: {e:#}"))?;
    Ok(true)
}

/// The manifest loader on mutated copies of the suite's manifests and of one for a user's own
/// file: every input loads into a sound scene with a valid camera, finite lights and hashable
/// inputs, or is refused naming the file; more than 5% of inputs end each way; and nothing is
/// written beside the manifests' folder or at the absolute path the mutations offer.
#[test]
fn mutated_manifests_are_errors_or_sound_scenes_and_never_write_outside_their_folder() {
    let outside = temporary_folder("manifest");
    let folder = outside.join("inside");
    std::fs::create_dir_all(&folder).unwrap();
    let seeds = manifest_seeds(&folder);
    for (i, seed) in seeds.iter().enumerate() {
        let path = folder.join(format!("seed{i}.json"));
        std::fs::write(&path, serde_json::to_vec(seed).unwrap()).unwrap();
        let manifest = Manifest::load(&path).unwrap_or_else(|e| panic!("seed {i}: {e}"));
        assert_eq!(check_manifest(&manifest), Ok(true), "seed {i} ({}) loads", manifest.name);
    }
    let strategy = (0..seeds.len(), prop::collection::vec(mutation(), 1..6));
    fuzz("the manifest loader", &folder, strategy, |(seed, mutations)| {
        let mut manifest = seeds[*seed].clone();
        for mutation in mutations {
            mutate_json(&mut manifest, mutation);
        }
        let mut bytes = serde_json::to_vec_pretty(&manifest).unwrap();
        mutate_bytes(&mut bytes, mutations);
        let path = folder.join("fuzz.json");
        std::fs::write(&path, bytes).unwrap();
        let owned = path.clone();
        guarded(move || match Manifest::load(&owned) {
            Ok(manifest) => check_manifest(&manifest),
            Err(error) => refused(error.to_string(), &owned),
        })
        .map_err(|e| format!("{}: {e}", path.display()))
    });
    let written: Vec<_> = std::fs::read_dir(&outside).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(written, ["inside"], "nothing is written beside the manifests' folder");
    assert!(!Path::new("/nonexistent-aabench").exists(), "nothing is written at an absolute path");
    let _ = std::fs::remove_dir_all(&outside);
}
