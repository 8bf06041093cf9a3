//! glTF import of broken and hostile files: every one is an error that names the file and the
//! part at fault, never a panic, a hang or a stack overflow. No device needed.
//!
//! Node graphs with cycles or second parents are errors naming the node, and a chain 10 000
//! nodes deep imports without recursion. Missing, escaping, special and looping files,
//! accessors and views past their data, bad index counts, non-finite positions and transforms,
//! truncated files, missing, corrupt and oversized images, and the inputs on which the gltf
//! crate itself panicked each fail with the part named, as do node scales that multiply
//! positions past ±10¹². A generated scene placed far out and scaled keeps a usable camera.
//!
//! Real-world features import with their values: `KHR_lights_punctual` lights with their node
//! transforms, material textures with their `KHR_texture_transform`s, UV sets and colour or data
//! encodings, JPEG textures, and 16-bit and grey PNGs. Extensions aabench does not read are a
//! warning when optional and an error naming them when required.

use crate::support;

use aabench_renderer::scene::load_gltf;
use serde_json::{Value, json};
use support::{Folder, error};

#[test]
fn the_test_triangle_loads() {
    let folder = Folder::new("ok");
    let scene = load_gltf(&folder.one_node("ok.gltf", |_| {})).unwrap();
    assert_eq!(scene.triangle_count(), 1);
}

#[test]
fn node_cycles_and_second_parents_are_errors_not_stack_overflows() {
    let folder = Folder::new("cycles");
    let own_child = folder.gltf("self.gltf", json!([{ "mesh": 0, "children": [0] }]), |_| {});
    assert!(error(&own_child).contains("nodes[0]: reached twice"), "{}", error(&own_child));
    let cycle =
        folder.gltf("cycle.gltf", json!([{ "mesh": 0, "children": [1] }, { "children": [0] }]), |_| {});
    assert!(error(&cycle).contains("cycle"), "{}", error(&cycle));
    let two_parents = folder.gltf(
        "parents.gltf",
        json!([{ "children": [1, 2] }, { "children": [3] }, { "children": [3] }, { "mesh": 0 }]),
        |_| {},
    );
    assert!(error(&two_parents).contains("nodes[3]: reached twice"), "{}", error(&two_parents));
}

#[test]
fn a_chain_ten_thousand_nodes_deep_imports() {
    let folder = Folder::new("deep");
    let depth = 10_000;
    let nodes: Vec<Value> = (0..depth)
        .map(|i| if i + 1 < depth { json!({ "mesh": 0, "children": [i + 1] }) } else { json!({ "mesh": 0 }) })
        .collect();
    // Each level moves its subtree: the deepest triangle sits 10 000 steps away.
    let path = folder.gltf("deep.gltf", Value::Array(nodes), |d| {
        for node in d["nodes"].as_array_mut().unwrap() {
            node["translation"] = json!([0.001, 0.0, 0.0]);
        }
    });
    let scene = load_gltf(&path).unwrap();
    assert_eq!(scene.triangle_count(), depth);
    let (lo, hi) = scene.bounds();
    assert!((hi.x - lo.x - 10.999).abs() < 1e-2, "{lo} {hi}");
}

/// A missing `.bin`, an absolute path, a URI with a scheme (`file:///etc/passwd`), a FIFO as
/// the buffer or as the file itself, and a symbolic link loop each fail naming the part. A
/// relative URI that leaves the file's folder resolves and loads, as glTF defines.
#[test]
fn missing_and_unreadable_external_files_are_named() {
    let folder = Folder::new("files");
    let missing_bin = folder.one_node("bin.gltf", |d| d["buffers"][0]["uri"] = json!("gone.bin"));
    let message = error(&missing_bin);
    assert!(
        message.contains("buffers[0].uri")
            && message.contains("gone.bin")
            && message.contains("does not exist"),
        "{message}"
    );

    let absolute = folder.one_node("absolute.gltf", |d| d["buffers"][0]["uri"] = json!("/etc/passwd"));
    assert!(error(&absolute).contains("is an absolute path"), "{}", error(&absolute));
    // A relative reference resolves against the file's folder, out of it too, as glTF says.
    std::fs::create_dir_all(folder.dir.join("models")).unwrap();
    let beside = folder.one_node("models/beside.gltf", |d| d["buffers"][0]["uri"] = json!("../tri.bin"));
    assert_eq!(load_gltf(&beside).unwrap().triangle_count(), 1);
    let scheme = folder.one_node("scheme.gltf", |d| d["buffers"][0]["uri"] = json!("file:///etc/passwd"));
    assert!(error(&scheme).contains("has a scheme"), "{}", error(&scheme));

    let fifo = folder.dir.join("fifo.bin");
    assert!(std::process::Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    let blocked = folder.one_node("fifo.gltf", |d| d["buffers"][0]["uri"] = json!("fifo.bin"));
    assert!(error(&blocked).contains("not a regular file"), "{}", error(&blocked));

    let fifo_gltf = folder.dir.join("fifo.gltf.fifo");
    assert!(std::process::Command::new("mkfifo").arg(&fifo_gltf).status().unwrap().success());
    assert!(error(&fifo_gltf).contains("not a regular file"), "{}", error(&fifo_gltf));

    let looped = folder.dir.join("loop.gltf");
    std::os::unix::fs::symlink(&looped, &looped).unwrap();
    let message = error(&looped);
    assert!(
        !message.contains("does not exist") && message.to_lowercase().contains("symbolic links"),
        "{message}"
    );
}

/// An accessor longer than its view, a view past its buffer, an index count that is not a
/// multiple of 3, NaN and infinite positions, a non-finite node transform and a truncated file
/// each fail with the accessor, view, attribute or node named.
#[test]
fn short_buffers_and_bad_geometry_say_what_is_wrong() {
    let folder = Folder::new("geometry");
    let long = folder.one_node("long.gltf", |d| d["accessors"][0]["count"] = json!(4));
    let message = error(&long);
    assert!(
        message.contains("accessors[0]") && message.contains("need 48 bytes") && message.contains("holds 36"),
        "{message}"
    );
    assert!(!message.contains("missing"), "{message}");

    let view = folder.one_node("view.gltf", |d| d["bufferViews"][0]["byteLength"] = json!(48));
    assert!(error(&view).contains("past the 36 bytes of buffers[0]"), "{}", error(&view));

    // Two indices: not a whole triangle.
    std::fs::write(folder.dir.join("indices.bin"), [0u8, 0, 1, 0]).unwrap();
    let indices = folder.one_node("indices.gltf", |d| {
        d["buffers"].as_array_mut().unwrap().push(json!({ "uri": "indices.bin", "byteLength": 4 }));
        d["bufferViews"].as_array_mut().unwrap().push(json!({ "buffer": 1, "byteLength": 4 }));
        d["accessors"]
            .as_array_mut()
            .unwrap()
            .push(json!({ "bufferView": 1, "componentType": 5123, "count": 2, "type": "SCALAR" }));
        d["meshes"][0]["primitives"][0]["indices"] = json!(1);
    });
    assert!(error(&indices).contains("2 indices, not a multiple of 3"), "{}", error(&indices));

    let nan: [f32; 9] = [0.0, 0.0, 0.0, f32::NAN, 0.0, 0.0, 0.0, f32::INFINITY, 0.0];
    std::fs::write(folder.dir.join("nan.bin"), bytemuck::cast_slice(&nan)).unwrap();
    let not_finite = folder.one_node("nan.gltf", |d| d["buffers"][0]["uri"] = json!("nan.bin"));
    assert!(error(&not_finite).contains("POSITION: vertex 1"), "{}", error(&not_finite));

    let transform = folder.one_node("scale.gltf", |d| d["nodes"][0]["scale"] = json!([1e300, 1.0, 1.0]));
    assert!(error(&transform).contains("nodes[0]: the transform is not finite"), "{}", error(&transform));
    let truncated = folder.dir.join("truncated.gltf");
    let whole = std::fs::read(folder.one_node("whole.gltf", |_| {})).unwrap();
    std::fs::write(&truncated, &whole[..whole.len() / 2]).unwrap();
    assert!(error(&truncated).contains("cannot read glTF"), "{}", error(&truncated));
}

/// A missing or corrupt image fails naming `images[0]`, and a 20000×1 PNG is refused as larger
/// than 16384×16384, from a file and from a base64 data URI alike.
#[test]
fn images_are_named_and_oversized_ones_refused_from_their_header() {
    let folder = Folder::new("images");
    let textured = |name: &str, uri: &str| {
        folder.one_node(name, |d| {
            d["images"] = json!([{ "uri": uri }]);
            d["textures"] = json!([{ "source": 0 }]);
            d["materials"] = json!([{ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } } }]);
            d["meshes"][0]["primitives"][0]["material"] = json!(0);
        })
    };
    let missing = textured("missing.gltf", "nope.png");
    assert!(
        error(&missing).contains("images[0].uri") && error(&missing).contains("nope.png"),
        "{}",
        error(&missing)
    );

    // A 20000×1 PNG: tiny on disk, too wide for any texture.
    image::RgbaImage::new(20_000, 1).save(folder.dir.join("wide.png")).unwrap();
    let wide = textured("wide.gltf", "wide.png");
    let message = error(&wide);
    assert!(
        message.contains("images[0] (uri wide.png): 20000×1 is larger than the 16384×16384"),
        "{message}"
    );

    // The same image embedded as a data URI meets the same check.
    let png = std::fs::read(folder.dir.join("wide.png")).unwrap();
    let embedded = textured("embedded.gltf", &format!("data:image/png;base64,{}", base64::encode(png)));
    let message = error(&embedded);
    assert!(message.contains("images[0] (data URI): 20000×1 is larger than the 16384×16384"), "{message}");
    let not_base64 = textured("plain.gltf", "data:image/png,rawbytes");
    assert!(error(&not_base64).contains("only base64 data URIs are read"), "{}", error(&not_base64));

    std::fs::write(folder.dir.join("corrupt.png"), b"\x89PNG\r\n\x1a\nnot really").unwrap();
    let corrupt = textured("corrupt.gltf", "corrupt.png");
    assert!(error(&corrupt).contains("images[0] (uri corrupt.png)"), "{}", error(&corrupt));
}

/// Inputs on which the gltf crate itself panicked (found by `runner/tests/fuzz.rs`): a POSITION
/// accessor that does not exist and an image with neither a buffer view nor a URI are errors
/// naming the part, and an empty image file is named as empty. An image with a buffer view but
/// no MIME type loads, its format read from its bytes.
#[test]
fn files_that_panicked_the_gltf_crate_are_errors() {
    let folder = Folder::new("crate-panics");
    let no_position = folder.one_node("position.gltf", |d| {
        d["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(34962);
    });
    let message = error(&no_position);
    assert!(
        message.contains("meshes[0].primitives[0].attributes.POSITION: accessor 34962 does not exist"),
        "{message}"
    );

    let png = folder.dir.join("tex.png");
    image::RgbaImage::new(2, 2).save(&png).unwrap();
    let png_bytes = std::fs::read(&png).unwrap();
    let textured = |name: &str, image: Value| {
        folder.one_node(name, |d| {
            d["buffers"] = json!([{ "uri": "tri.bin", "byteLength": 36 }, { "uri": "tex.png", "byteLength": png_bytes.len() }]);
            d["bufferViews"].as_array_mut().unwrap().push(json!({ "buffer": 1, "byteLength": png_bytes.len() }));
            d["images"] = json!([image.clone()]);
            d["textures"] = json!([{ "source": 0 }]);
            d["materials"] = json!([{ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } } }]);
            d["meshes"][0]["primitives"][0]["material"] = json!(0);
        })
    };
    // The spec wants a mimeType with a bufferView; the format is read from the bytes anyway.
    let scene = load_gltf(&textured("no-mime.gltf", json!({ "bufferView": 1 }))).unwrap();
    assert_eq!((scene.textures[0].width, scene.textures[0].height), (2, 2));
    let nothing = textured("no-source.gltf", json!({ "name": "empty" }));
    assert!(error(&nothing).contains("images[0]: has neither a bufferView nor a uri"), "{}", error(&nothing));
    // An empty file is named as such, not as an undetermined format.
    std::fs::write(folder.dir.join("empty.png"), b"").unwrap();
    let empty = textured("empty-image.gltf", json!({ "uri": "empty.png" }));
    assert!(
        error(&empty).contains("images[0] (uri empty.png): the image is empty (0 bytes)"),
        "{}",
        error(&empty)
    );
}

/// Accessors and references the gltf crate's readers would panic on (found by
/// `runner/tests/fuzz.rs` and its review): each is an error naming the part.
#[test]
fn accessors_the_gltf_crate_cannot_read_are_refused_by_name() {
    let folder = Folder::new("formats");
    type Edit = fn(&mut Value);
    let cases: [(&str, Edit, &str); 6] = [
        ("count0.gltf", |d| d["accessors"][0]["count"] = json!(0), "accessors[0]: count is 0"),
        (
            "stride.gltf",
            |d| d["bufferViews"][0]["byteStride"] = json!(4),
            "bufferViews[0].byteStride 4 is shorter than the 12-byte elements of accessors[0]",
        ),
        (
            "float-indices.gltf",
            |d| {
                d["accessors"].as_array_mut().unwrap().push(json!({
                    "bufferView": 0, "componentType": 5126, "count": 3, "type": "SCALAR"
                }));
                d["meshes"][0]["primitives"][0]["indices"] = json!(1);
            },
            "indices: accessors[1]: Scalar of F32 is not a format glTF allows here",
        ),
        (
            "vec2-positions.gltf",
            |d| d["accessors"][0]["type"] = json!("VEC2"),
            "attributes.POSITION: accessors[0]: Vec2 of F32 is not a format glTF allows here",
        ),
        (
            "sparse.gltf",
            |d| {
                d["accessors"][0]["sparse"] = json!({
                    "count": 1,
                    "indices": { "bufferView": 0, "componentType": 5125 },
                    "values": { "bufferView": 0 }
                });
            },
            "accessors[0]: sparse accessors are not supported",
        ),
        (
            "escape.gltf",
            |d| d["buffers"][0]["uri"] = json!("tri%FF.bin"),
            "buffers[0].uri: `tri%FF.bin`: its %-escapes do not decode to UTF-8",
        ),
    ];
    for (name, edit, expected) in cases {
        let message = error(&folder.one_node(name, edit));
        assert!(message.contains(expected), "{name}: {message}");
    }
}

/// A camera whose type names a projection object the file lacks is an error naming the camera,
/// and so is one whose field of view passes what a glTF float holds, quoted as written;
/// node scales finite in f32 that multiply positions past ±10¹² are an error naming the vertex;
/// a GLB whose header states less than its own 12 bytes is an error.
#[test]
fn cameras_without_their_projection_and_positions_beyond_range_are_errors() {
    let folder = Folder::new("projection");
    let with_camera = |name: &str, camera: Value| {
        folder.gltf(name, json!([{ "mesh": 0 }, { "camera": 0, "translation": [0, 0, 3] }]), move |d| {
            d["cameras"] = json!([camera.clone()]);
            d["scenes"][0]["nodes"] = json!([0, 1]);
        })
    };
    // The type names an object the file lacks: an error, never the crate's unwrap.
    for (name, camera) in
        [("p.gltf", json!({ "type": "perspective" })), ("o.gltf", json!({ "type": "orthographic" }))]
    {
        let path = with_camera(name, camera);
        let message = error(&path);
        assert!(message.contains("cameras[0]"), "{name}: {message}");
    }
    // An orthographic camera is skipped (no perspective camera): the scene still loads.
    let ortho = with_camera(
        "ortho.gltf",
        json!({ "type": "orthographic", "orthographic": { "xmag": 1, "ymag": 1, "znear": 0.1, "zfar": 10 } }),
    );
    assert!(load_gltf(&ortho).unwrap().camera.is_none());
    // A field of view past what a 32-bit float holds is quoted as written, not as infinity.
    let wide = with_camera(
        "wide.gltf",
        json!({ "type": "perspective", "perspective": { "yfov": 1e39, "znear": 0.1 } }),
    );
    let message = error(&wide);
    assert!(
        message.contains("cameras[0].perspective.yfov: 1e39 is past the largest number a glTF float holds"),
        "{message}"
    );

    // Scales finite in f32 that multiply up past what a position may be.
    let huge = folder.gltf(
        "huge.gltf",
        json!([{ "scale": [1e30, 1e30, 1e30], "children": [1] }, { "mesh": 0, "scale": [1e30, 1e30, 1e30] }]),
        |_| {},
    );
    let message = error(&huge);
    assert!(message.contains("vertex 1 lies at") && message.contains("beyond ±1e12"), "{message}");

    // A GLB whose header states less than its own 12 bytes.
    let glb = folder.dir.join("short.glb");
    let mut bytes = b"glTF".to_vec();
    bytes.extend_from_slice(&2u32.to_le_bytes());
    bytes.extend_from_slice(&4u32.to_le_bytes());
    std::fs::write(&glb, bytes).unwrap();
    assert!(error(&glb).contains("less than the header itself"), "{}", error(&glb));
}

/// A Cornell box placed ×1000 and 10⁵ units out scales its camera's clip planes with it (near
/// 50, far 5000) and lands on a scene origin aligned to 1024 units near 10⁵.
#[test]
fn a_placed_generated_scene_scales_its_camera_clip_planes_too() {
    use aabench_renderer::scene::generate::{Generated, Generator, Placement};
    let folder = Folder::new("placed");
    let path = folder.dir.join("cornell-mm.glb");
    let placed = Generated {
        placement: Placement { scale: 1000.0, offset: [1.0e5, 0.0, 0.0] },
        ..Generated::new(Generator::Cornell, 1)
    };
    placed.write(&path).unwrap();
    let scene = load_gltf(&path).unwrap();
    let camera = scene.camera.unwrap();
    assert!((camera.near - 50.0).abs() < 1e-9 && (camera.far - 5000.0).abs() < 1e-6, "{camera:?}");
    // Positions relative to the scene's origin, which sits on the 1024 grid near 10⁵.
    assert_eq!(scene.origin.x % 1024.0, 0.0);
    assert!((scene.origin.x - 1.0e5).abs() <= 512.0, "{}", scene.origin);
    let (lo, hi) = scene.bounds();
    assert!((hi.y - lo.y - 550.0).abs() < 1e-3, "{lo} {hi}");
}

/// Point, spot and directional lights come with their node transforms, colours, intensities,
/// ranges and cone angles; a light without a range reaches at least ten times the scene's
/// bounding diagonal. An optional extension aabench does not read is one warning; a required
/// one fails naming it; an impossible spot cone fails naming node and light; a negative
/// intensity fails as it would in a manifest.
#[test]
fn khr_lights_punctual_lights_come_with_their_node_transforms() {
    use aabench_renderer::scene::LightKind;
    let folder = Folder::new("lights");
    // A quarter turn about +X takes the light's −Z to −Y: it shines straight down.
    let down = [-std::f64::consts::FRAC_1_SQRT_2, 0.0, 0.0, std::f64::consts::FRAC_1_SQRT_2];
    let nodes = json!([
        { "mesh": 0 },
        { "translation": [1, 2, 3], "extensions": { "KHR_lights_punctual": { "light": 0 } } },
        { "translation": [0, 5, 0], "rotation": down, "extensions": { "KHR_lights_punctual": { "light": 1 } } },
        { "rotation": down, "extensions": { "KHR_lights_punctual": { "light": 2 } } }
    ]);
    let path = folder.gltf("lights.gltf", nodes, |d| {
        d["extensionsUsed"] = json!(["KHR_lights_punctual", "KHR_materials_sheen"]);
        d["extensionsRequired"] = json!(["KHR_lights_punctual"]);
        d["extensions"] = json!({ "KHR_lights_punctual": { "lights": [
            { "type": "point", "color": [1, 0.5, 0.25], "intensity": 40, "range": 12 },
            { "type": "spot", "intensity": 100, "spot": { "innerConeAngle": 0.2, "outerConeAngle": 0.5 } },
            { "type": "directional", "intensity": 3 }
        ] } });
        d["scenes"][0]["nodes"] = json!([0, 1, 2, 3]);
    });
    let scene = load_gltf(&path).unwrap();
    assert_eq!(scene.lights.len(), 3);
    let [point, spot, sun] = [&scene.lights[0], &scene.lights[1], &scene.lights[2]];
    assert_eq!(point.kind, LightKind::Point);
    assert_eq!((point.intensity, point.range, point.color), (40.0, 12.0, glam::Vec3::new(1.0, 0.5, 0.25)));
    assert!((point.position + scene.origin.as_vec3() - glam::Vec3::new(1.0, 2.0, 3.0)).length() < 1e-6);
    let LightKind::Spot { direction, inner, outer } = spot.kind else { panic!("{:?}", spot.kind) };
    assert!((direction - glam::Vec3::NEG_Y).length() < 1e-6, "{direction}");
    assert_eq!((inner, outer, spot.intensity), (0.2, 0.5, 100.0));
    // No range: the light reaches well beyond the scene (ten times its bounds' diagonal).
    assert!(spot.range.is_finite() && spot.range >= 10.0 * 2f32.sqrt() - 1e-4, "{}", spot.range);
    assert!(
        matches!(sun.kind, LightKind::Directional { direction } if (direction - glam::Vec3::NEG_Y).length() < 1e-6)
    );
    // An optional extension aabench does not read is one warning, not an error.
    assert_eq!(scene.warnings.len(), 1, "{:?}", scene.warnings);
    assert!(scene.warnings[0].contains("KHR_materials_sheen"), "{:?}", scene.warnings);

    // A required extension it does not read fails the scene, naming it.
    let required = folder.one_node("required.gltf", |d| {
        d["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
        d["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    });
    let message = error(&required);
    assert!(
        message.contains("extensionsRequired: the file requires `KHR_draco_mesh_compression`"),
        "{message}"
    );

    // A spot cone the renderer cannot draw is an error, never dropped.
    let wide = folder.gltf(
        "wide.gltf",
        json!([{ "mesh": 0 }, { "extensions": { "KHR_lights_punctual": { "light": 0 } } }]),
        |d| {
            d["extensionsUsed"] = json!(["KHR_lights_punctual"]);
            d["extensions"] = json!({ "KHR_lights_punctual": { "lights": [
            { "type": "spot", "spot": { "innerConeAngle": 0.6, "outerConeAngle": 0.5 } }
        ] } });
            d["scenes"][0]["nodes"] = json!([0, 1]);
        },
    );
    assert!(error(&wide).contains("nodes[1]: KHR_lights_punctual light 0: cone angles"), "{}", error(&wide));

    // Values are checked as a manifest's lights are.
    let negative = folder.gltf(
        "negative.gltf",
        json!([{ "mesh": 0 }, { "extensions": { "KHR_lights_punctual": { "light": 0 } } }]),
        |d| {
            d["extensionsUsed"] = json!(["KHR_lights_punctual"]);
            d["extensions"] =
                json!({ "KHR_lights_punctual": { "lights": [{ "type": "point", "intensity": -1 }] } });
            d["scenes"][0]["nodes"] = json!([0, 1]);
        },
    );
    let message = error(&negative);
    assert!(
        message.contains("KHR_lights_punctual light 0: intensity: -1 must be finite and ≥ 0"),
        "{message}"
    );
}

/// A JPEG texture (quality 95) decodes to its PNG twin with a mean difference under 2 codes
/// and no channel more than 23 codes off.
#[test]
fn a_jpeg_texture_decodes_to_its_png_twin_within_jpeg_error() {
    let folder = Folder::new("jpeg");
    let image = image::RgbImage::from_fn(64, 64, |x, y| image::Rgb([(x * 4) as u8, (y * 4) as u8, 128]));
    image.save(folder.dir.join("t.png")).unwrap();
    let mut jpeg = std::fs::File::create(folder.dir.join("t.jpg")).unwrap();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut jpeg, 95).encode_image(&image).unwrap();
    let textured = |name: &str, uri: &str| {
        let path = folder.one_node(name, |d| {
            d["images"] = json!([{ "uri": uri }]);
            d["textures"] = json!([{ "source": 0 }]);
            d["materials"] = json!([{ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } } }]);
            d["meshes"][0]["primitives"][0]["material"] = json!(0);
        });
        load_gltf(&path).unwrap().textures.remove(0)
    };
    let (png, jpg) = (textured("png.gltf", "t.png"), textured("jpg.gltf", "t.jpg"));
    assert_eq!((jpg.width, jpg.height), (64, 64));
    let differences: Vec<u32> =
        png.rgba.iter().zip(&jpg.rgba).map(|(a, b)| u32::from(a.abs_diff(*b))).collect();
    let mean = differences.iter().sum::<u32>() as f64 / differences.len() as f64;
    assert!(mean < 2.0 && *differences.iter().max().unwrap() < 24, "mean {mean}");
}

/// Texture transforms are read from the base colour and normal slots (the normal one from the
/// slot's own extension). One image used as colour and as data becomes two textures. A texture
/// on `TEXCOORD_1`, set on the slot or through the transform's override, is ignored with a
/// warning naming the material slot. A rotation of 1e39, a negative emissive strength, a normal
/// scale of 1e39 and an occlusion strength of −0.5 are errors naming the material and field.
#[test]
fn material_textures_are_read_with_their_transforms_uv_sets_and_encodings() {
    use aabench_renderer::scene::{Encoding, UvTransform};
    let folder = Folder::new("materials");
    image::RgbaImage::from_pixel(4, 4, image::Rgba([200, 100, 50, 255]))
        .save(folder.dir.join("t.png"))
        .unwrap();
    let material = |d: &mut Value, material: Value| {
        d["images"] = json!([{ "uri": "t.png" }]);
        d["textures"] = json!([{ "source": 0 }]);
        d["materials"] = json!([material]);
        d["meshes"][0]["primitives"][0]["material"] = json!(0);
    };
    let transform =
        json!({ "KHR_texture_transform": { "offset": [0.5, 0], "rotation": 0.25, "scale": [2, 3] } });
    let path = folder.one_node("all.gltf", |d| {
        d["extensionsRequired"] = json!(["KHR_texture_transform", "KHR_materials_emissive_strength"]);
        d["extensionsUsed"] = d["extensionsRequired"].clone();
        material(
            d,
            json!({
                "pbrMetallicRoughness": { "baseColorTexture": { "index": 0, "extensions": transform } },
                "normalTexture": { "index": 0, "scale": 0.5, "extensions": transform },
                "emissiveTexture": { "index": 0 },
                "emissiveFactor": [1, 0.5, 0],
                "occlusionTexture": { "index": 0, "texCoord": 1, "strength": 0.3 },
                "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": 4 } }
            }),
        );
    });
    let scene = load_gltf(&path).unwrap();
    let m = &scene.materials[0];
    let expected = UvTransform::new([0.5, 0.0], 0.25, [2.0, 3.0]);
    assert_eq!(m.texture.unwrap().transform, expected);
    assert_eq!(m.normal_texture.unwrap().transform, expected, "read from the normal texture's own extension");
    assert_eq!(m.normal_scale, 0.5);
    assert_eq!(m.emissive, [4.0, 2.0, 0.0]);
    assert!(m.emissive_texture.unwrap().transform.is_identity());
    // One image, read as colour (base, emissive) and as data (normal): two textures.
    assert_eq!(
        scene.textures.iter().map(|t| t.encoding).collect::<Vec<_>>(),
        vec![Encoding::Srgb, Encoding::Linear]
    );
    assert_eq!(m.texture.unwrap().texture, m.emissive_texture.unwrap().texture);
    // Occlusion on a second UV set is ignored, with a warning that says so.
    assert!(m.occlusion_texture.is_none());
    assert!(
        scene.warnings.iter().any(|w| w.contains("materials[0].occlusionTexture: uses TEXCOORD_1")),
        "{:?}",
        scene.warnings
    );
    // The transform's own texCoord overrides the slot's.
    let path = folder.one_node("override.gltf", |d| {
        let transform = json!({ "KHR_texture_transform": { "texCoord": 1 } });
        material(d, json!({ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0, "extensions": transform } } }));
    });
    let scene = load_gltf(&path).unwrap();
    assert!(scene.materials[0].texture.is_none() && scene.warnings[0].contains("TEXCOORD_1"));

    // Values no renderer can use are errors naming the material.
    let path = folder.one_node("huge.gltf", |d| {
        let transform = json!({ "KHR_texture_transform": { "rotation": 1e39 } });
        material(d, json!({ "normalTexture": { "index": 0, "extensions": transform } }));
    });
    let message = error(&path);
    assert!(message.contains("materials[0].normalTexture.extensions.KHR_texture_transform"), "{message}");
    let path = folder.one_node("negative.gltf", |d| {
        let strength = json!({ "KHR_materials_emissive_strength": { "emissiveStrength": -2 } });
        material(d, json!({ "emissiveFactor": [1, 1, 1], "extensions": strength }));
    });
    let message = error(&path);
    assert!(message.contains("materials[0]: emissiveFactor") && message.contains("≥ 0"), "{message}");
    // The crate checks neither a normal map's scale nor an occlusion strength.
    let path = folder
        .one_node("scale.gltf", |d| material(d, json!({ "normalTexture": { "index": 0, "scale": 1e39 } })));
    let message = error(&path);
    assert!(message.contains("materials[0].normalTexture.scale: inf must be finite"), "{message}");
    let path = folder.one_node("strength.gltf", |d| {
        material(d, json!({ "occlusionTexture": { "index": 0, "strength": -0.5 } }))
    });
    let message = error(&path);
    assert!(message.contains("materials[0].occlusionTexture.strength: -0.5 must be in [0, 1]"), "{message}");
}

/// 16-bit grey, 16-bit RGB and grey+alpha PNGs decode to exactly the texels of their 8-bit
/// twins expanded to RGBA.
#[test]
fn sixteen_bit_and_grey_textures_decode_like_their_eight_bit_rgba_twins() {
    let folder = Folder::new("depths");
    let grey8 = image::GrayImage::from_fn(16, 16, |x, y| image::Luma([(x * 16 + y) as u8]));
    let grey16 = image::ImageBuffer::<image::Luma<u16>, _>::from_fn(16, 16, |x, y| {
        image::Luma([u16::from(grey8.get_pixel(x, y)[0]) * 257])
    });
    let grey_alpha =
        image::GrayAlphaImage::from_fn(16, 16, |x, y| image::LumaA([grey8.get_pixel(x, y)[0], 77]));
    let rgb16 = image::ImageBuffer::<image::Rgb<u16>, _>::from_fn(16, 16, |x, y| {
        let v = u16::from(grey8.get_pixel(x, y)[0]) * 257;
        image::Rgb([v, v, v])
    });
    grey8.save(folder.dir.join("grey8.png")).unwrap();
    grey16.save(folder.dir.join("grey16.png")).unwrap();
    grey_alpha.save(folder.dir.join("grey-alpha.png")).unwrap();
    rgb16.save(folder.dir.join("rgb16.png")).unwrap();
    let texture = |uri: &str| {
        let path = folder.one_node(&format!("{uri}.gltf"), |d| {
            d["images"] = json!([{ "uri": uri }]);
            d["textures"] = json!([{ "source": 0 }]);
            d["materials"] = json!([{ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } } }]);
            d["meshes"][0]["primitives"][0]["material"] = json!(0);
        });
        load_gltf(&path).unwrap().textures.remove(0).rgba
    };
    let expected: Vec<u8> = grey8.pixels().flat_map(|p| [p[0], p[0], p[0], 255]).collect();
    assert_eq!(texture("grey8.png"), expected);
    assert_eq!(texture("grey16.png"), expected);
    assert_eq!(texture("rgb16.png"), expected);
    let with_alpha: Vec<u8> = grey8.pixels().flat_map(|p| [p[0], p[0], p[0], 77]).collect();
    assert_eq!(texture("grey-alpha.png"), with_alpha);
}

#[test]
fn position_accessors_without_bounds_load_with_a_warning() {
    // glTF requires min and max on POSITION accessors; Khronos' IncorrectVertexArrays sample
    // and some exporters leave them out.
    let folder = Folder::new("bounds");
    let path = folder.one_node("unbounded.gltf", |d| {
        let accessor = d["accessors"][0].as_object_mut().unwrap();
        accessor.remove("min");
        accessor.insert("max".into(), json!("not a bound"));
    });
    let scene = load_gltf(&path).unwrap();
    assert_eq!(scene.triangle_count(), 1);
    assert_eq!(scene.bounds().1, glam::Vec3::new(1.0, 1.0, 0.0), "bounds come from the data");
    assert!(
        scene.warnings.iter().any(|w| w.starts_with("accessors[0]: a POSITION accessor without")),
        "{:?}",
        scene.warnings
    );
}

/// A `data:` URI's scheme is read in any case (RFC 3986 schemes are case-insensitive), for
/// buffers and images alike. A URI of megabytes is never quoted whole: a buffer's bad base64
/// names the buffer, and a refused scheme shows the URI's start and its length.
#[test]
fn data_uris_are_read_in_any_case_and_quoted_short() {
    let folder = Folder::new("data-uri");
    let positions: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let payload = base64::encode(bytemuck::cast_slice(&positions));
    let mut png = Vec::new();
    image::RgbaImage::from_pixel(2, 2, image::Rgba([200, 100, 50, 255]))
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    let image = format!("Data:image/png;base64,{}", base64::encode(&png));
    let path = folder.one_node("upper.gltf", |d| {
        d["buffers"][0]["uri"] = json!(format!("DATA:application/octet-stream;base64,{payload}"));
        d["images"] = json!([{ "uri": image }]);
        d["textures"] = json!([{ "source": 0 }]);
        d["materials"] = json!([{ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } } }]);
        d["meshes"][0]["primitives"][0]["material"] = json!(0);
    });
    let scene = load_gltf(&path).unwrap_or_else(|e| panic!("upper-case data URIs load: {e}"));
    assert_eq!((scene.triangle_count(), scene.textures.len()), (1, 1));
    let huge = "!".repeat(2 << 20);
    let bad = folder.one_node("bad-base64.gltf", |d| {
        d["buffers"][0]["uri"] = json!(format!("data:application/octet-stream;base64,{huge}"));
    });
    let message = error(&bad);
    assert!(message.contains("buffers[0] (data URI): bad base64") && message.len() < 1000, "{message}");
    let scheme = folder.one_node("scheme.gltf", |d| d["buffers"][0]["uri"] = json!(format!("http://{huge}")));
    let message = error(&scheme);
    assert!(
        message.contains("has a scheme") && message.contains("bytes)") && message.len() < 1000,
        "{message}"
    );
}
