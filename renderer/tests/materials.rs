//! Materials beyond base colour, judged on rendered pixels: normal maps (the file's tangents and
//! MikkTSpace's), emission with `KHR_materials_emissive_strength`, occlusion on the ambient
//! term, and `KHR_texture_transform`. Each scene is a glTF file written here: one quad that
//! exactly fills a 64×64 view.
//!
//! The assertions are on display codes: a normal map shows its bumps under a grazing light and
//! follows glTF's tangent space, whether the tangents come from the file or from MikkTSpace;
//! MikkTSpace splits vertices where mirrored UVs meet and leaves finite (or, on a collapsed
//! primitive, zero) tangents; emission, occlusion and metallic-roughness textures give the
//! codes their factors predict; `KHR_texture_transform` moves, turns and scales a texture as
//! the extension defines; and textures packed into shared pages render as if each had a layer
//! of its own. How materials and their textures are imported is tested in `tests/import.rs`.

use crate::support;

use aabench_renderer::scene::write::glb;
use aabench_renderer::scene::{Camera, Light, LightKind, Lighting, Scene, UvTransform, load_gltf};
use aabench_renderer::{FrameImages, SceneRenderer};
use glam::{DVec3, Vec3};
use serde_json::{Value, json};
use support::*;

const SIDE: u32 = 64;

/// The quad's UVs at corners (−1, −1), (1, −1), (1, 1), (−1, 1): u along +x, v down the image,
/// so the texture appears upright.
const UPRIGHT: [[f32; 2]; 4] = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];

/// A quad from (−1, −1, 0) to (1, 1, 0) facing +Z, with `material` (JSON; its textures index
/// `images`, embedded as PNG, in order), `uvs` and optionally one tangent for every vertex.
struct Quad {
    material: Value,
    images: Vec<Vec<u8>>,
    uvs: [[f32; 2]; 4],
    tangent: Option<[f32; 4]>,
    /// The node's scale.
    scale: [f32; 3],
}

impl Quad {
    fn new(material: Value) -> Quad {
        Quad { material, images: Vec::new(), uvs: UPRIGHT, tangent: None, scale: [1.0; 3] }
    }

    /// Writes the quad as a GLB file into a folder of its own, imports it through the importer
    /// as a user's file would be, and removes the folder.
    fn import(&self, name: &str) -> Scene {
        let positions: [[f32; 3]; 4] =
            [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]];
        let normals = [[0.0f32, 0.0, 1.0]; 4];
        let indices: [u32; 6] = [0, 1, 2, 0, 2, 3];
        let mut bin = Vec::new();
        let mut views = Vec::new();
        let mut view = |bytes: &[u8]| {
            bin.resize(bin.len().next_multiple_of(4), 0);
            views.push(json!({ "buffer": 0, "byteOffset": bin.len(), "byteLength": bytes.len() }));
            bin.extend_from_slice(bytes);
            views.len() - 1
        };
        let mut accessors = vec![
            json!({ "bufferView": view(bytemuck::cast_slice(&positions)), "componentType": 5126, "count": 4,
                    "type": "VEC3", "min": [-1, -1, 0], "max": [1, 1, 0] }),
            json!({ "bufferView": view(bytemuck::cast_slice(&normals)), "componentType": 5126, "count": 4, "type": "VEC3" }),
            json!({ "bufferView": view(bytemuck::cast_slice(&self.uvs)), "componentType": 5126, "count": 4, "type": "VEC2" }),
            json!({ "bufferView": view(bytemuck::cast_slice(&indices)), "componentType": 5125, "count": 6, "type": "SCALAR" }),
        ];
        let mut attributes = json!({ "POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2 });
        if let Some(tangent) = self.tangent {
            let tangents = [tangent; 4];
            accessors
                .push(json!({ "bufferView": view(bytemuck::cast_slice(&tangents)), "componentType": 5126,
                                   "count": 4, "type": "VEC4" }));
            attributes["TANGENT"] = json!(4);
        }
        let images: Vec<Value> = self
            .images
            .iter()
            .map(|png| json!({ "bufferView": view(png), "mimeType": "image/png" }))
            .collect();
        let textures: Vec<Value> = (0..images.len()).map(|i| json!({ "source": i })).collect();
        let mut document = json!({
            "asset": { "version": "2.0" },
            "extensionsUsed": ["KHR_texture_transform", "KHR_materials_emissive_strength"],
            "buffers": [{ "byteLength": bin.len().next_multiple_of(4) }],
            "bufferViews": views,
            "accessors": accessors,
            "materials": [self.material],
            "meshes": [{ "primitives": [{ "attributes": attributes, "indices": 3, "material": 0 }] }],
            "nodes": [{ "mesh": 0, "scale": self.scale }],
            "scenes": [{ "nodes": [0] }],
            "scene": 0
        });
        if !images.is_empty() {
            document["images"] = json!(images);
            document["textures"] = json!(textures);
        }
        let dir = std::env::temp_dir().join(format!("aabench-materials-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(format!("{name}.glb"));
        std::fs::write(&path, glb(&document, &bin)).unwrap();
        let scene = load_gltf(&path);
        let _ = std::fs::remove_dir_all(&dir);
        scene.unwrap()
    }

    /// The quad seen head-on, filling the frame, at `mode`.
    fn render(&self, name: &str, lighting: &Lighting) -> FrameImages {
        let scene = self.import(name);
        let camera = Camera::look_at(DVec3::new(0.0, 0.0, 1.0), DVec3::ZERO, 90.0);
        let (gpu, _guard) = gpu();
        let mut renderer = SceneRenderer::new(gpu, &scene, &camera, lighting, settings(SIDE, SIDE)).unwrap();
        render(&mut renderer, "deferred-1x1")
    }
}

/// An RGBA8 PNG of `width`×`height` texels from `texel(x, y)`.
fn png(width: u32, height: u32, texel: impl Fn(u32, u32) -> [u8; 4]) -> Vec<u8> {
    let image = image::RgbaImage::from_fn(width, height, |x, y| image::Rgba(texel(x, y)));
    let mut bytes = Vec::new();
    image.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png).unwrap();
    bytes
}

/// A normal map texel for the tangent-space normal `n` (unit).
fn encode_normal(n: Vec3) -> [u8; 4] {
    let code = |c: f32| ((c * 0.5 + 0.5) * 255.0).round() as u8;
    [code(n.x), code(n.y), code(n.z), 255]
}

/// A grey, rough, non-metallic material with `extra` fields merged in.
fn grey(extra: Value) -> Value {
    let mut material = json!({
        "pbrMetallicRoughness": { "baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0 }
    });
    material.as_object_mut().unwrap().extend(extra.as_object().unwrap().clone());
    material
}

/// Only a directional light shining along `direction`: no ambient, black background.
fn sun(direction: Vec3) -> Lighting {
    let light = Light {
        kind: LightKind::Directional { direction: direction.normalize() },
        position: Vec3::ZERO,
        color: Vec3::ONE,
        intensity: 2.0,
        range: 100.0,
        shadow: None,
    };
    Lighting { lights: vec![light], ambient: Vec3::ZERO, background: Vec3::ZERO, exposure: 1.0 }
}

fn dark() -> Lighting {
    Lighting { lights: Vec::new(), ambient: Vec3::ZERO, background: Vec3::ZERO, exposure: 1.0 }
}

/// The display image's code of `channel` at (x, y).
fn code(image: &FrameImages, x: u32, y: u32, channel: usize) -> u16 {
    image.display.rgba[(y * image.width + x) as usize * 4 + channel]
}

fn mean_green(image: &FrameImages) -> f64 {
    image.display.rgba.chunks_exact(4).map(|p| f64::from(p[1])).sum::<f64>() / f64::from(SIDE * SIDE)
}

/// A normal map of eight stripes, tilted alternately towards +X and −X, under a grazing light
/// from +X: neighbouring stripes are more than 60 codes apart, while the same plane without
/// the map is even within 2 codes.
#[test]
fn a_normal_mapped_plane_lit_from_the_side_shows_its_bumps() {
    // Eight stripes of one texel each, their normals tilted alternately towards +X and −X.
    let tilt = Vec3::new(0.6, 0.0, 0.8);
    let stripes =
        png(8, 8, |x, _| encode_normal(if x % 2 == 0 { tilt } else { tilt * Vec3::new(-1.0, 1.0, 1.0) }));
    let mapped =
        Quad { images: vec![stripes], ..Quad::new(grey(json!({ "normalTexture": { "index": 0 } }))) };
    // Light from +X, grazing the plane.
    let lighting = sun(Vec3::new(-1.0, 0.0, -0.2));
    let image = mapped.render("stripes", &lighting);
    // Stripe k covers columns 8k..8k+8; their centres sit on texel centres.
    let centre = |k: u32| code(&image, 8 * k + 4, 32, 1);
    for k in (0..8).step_by(2) {
        assert!(centre(k) > centre(k + 1) + 60, "stripe {k}: {} vs {}", centre(k), centre(k + 1));
    }
    // Without the map the plane is even, and as dim as a grazing light makes it.
    let flat = Quad::new(grey(json!({}))).render("flat", &lighting);
    let greens: Vec<u16> = flat.display.rgba.chunks_exact(4).map(|p| p[1]).collect();
    let (lo, hi) = (*greens.iter().min().unwrap(), *greens.iter().max().unwrap());
    assert!(hi - lo <= 2, "flat plane: {lo}..{hi}");
    assert!(centre(1) < lo && centre(0) > hi + 40, "bumps: {} / {} around flat {lo}", centre(0), centre(1));
}

/// A map tilted towards the image's +Y brightens a plane lit from above (glTF's tangent space,
/// +Y up) by more than 30 codes of mean green. MikkTSpace's tangents give an image within 1
/// code of the file's tangent `[1, 0, 0, 1]`, and a file tangent with `w = −1` darkens the
/// plane instead.
#[test]
fn normal_maps_follow_gltf_tangent_space_with_file_or_mikktspace_tangents() {
    // Every normal tilted towards the texture's +Y (up in the image), lit from above: glTF's
    // tangent space (+X right, +Y up) brightens the plane; the opposite convention darkens it.
    let up = png(4, 4, |_, _| encode_normal(Vec3::new(0.0, 0.6, 0.8)));
    let material = grey(json!({ "normalTexture": { "index": 0 } }));
    let lighting = sun(Vec3::new(0.0, -1.0, -0.5));
    let flat = mean_green(&Quad::new(grey(json!({}))).render("flat-above", &lighting));
    let generated = Quad { images: vec![up.clone()], ..Quad::new(material.clone()) };
    let from_file =
        Quad { images: vec![up.clone()], tangent: Some([1.0, 0.0, 0.0, 1.0]), ..Quad::new(material.clone()) };
    let generated = generated.render("up-generated", &lighting);
    let from_file = from_file.render("up-file", &lighting);
    assert!(mean_green(&generated) > flat + 30.0, "MikkTSpace: {} vs flat {flat}", mean_green(&generated));
    assert!(max_step(&generated, &from_file) <= 1, "file and MikkTSpace tangents agree");
    // A file tangent with w = −1 flips the bitangent: the same map now leans away.
    let flipped = Quad { images: vec![up], tangent: Some([1.0, 0.0, 0.0, -1.0]), ..Quad::new(material) };
    let flipped = flipped.render("up-flipped", &lighting);
    assert!(mean_green(&flipped) < flat - 30.0, "w = −1: {} vs flat {flat}", mean_green(&flipped));
}

/// MikkTSpace splits exactly the two shared vertices of a quad whose second triangle is
/// mirrored in UV (four vertices become six, with opposite handedness per triangle). On a
/// primitive collapsed by a zero-scale node it leaves zero tangents instead of underflowing,
/// and on UVs without area it leaves finite tangents.
#[test]
fn mikktspace_splits_vertices_where_mirrored_uvs_meet() {
    let flat_map = png(2, 2, |_, _| encode_normal(Vec3::Z));
    let quad = |uvs| Quad {
        images: vec![flat_map.clone()],
        uvs,
        ..Quad::new(grey(json!({ "normalTexture": { "index": 0 } })))
    };
    // Upright UVs: one tangent per vertex, along +u = +X, bitangent up the image (w = 1).
    let scene = quad(UPRIGHT).import("upright");
    assert_eq!(scene.vertices.len(), 4);
    for t in &scene.tangents {
        assert!((Vec3::from_slice(&t[..3]) - Vec3::X).length() < 1e-5 && t[3] == 1.0, "{t:?}");
    }
    // The second triangle (corners 0, 2, 3) mirrored in UV space: its corners at the shared
    // vertices 0 and 2 need the other handedness, so those vertices split.
    let scene = quad([[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [2.0, 0.0]]).import("mirrored");
    assert_eq!(scene.vertices.len(), 6, "two shared vertices split");
    let handedness = |triangle: usize| {
        let corners = &scene.indices[3 * triangle..3 * triangle + 3];
        corners.iter().map(|&i| scene.tangents[i as usize][3]).collect::<Vec<f32>>()
    };
    assert_eq!((handedness(0), handedness(1)), (vec![1.0; 3], vec![-1.0; 3]));
    // A node scaled to zero (how exporters hide objects): every triangle collapses, which
    // MikkTSpace cannot take (it underflows); the tangents are zero.
    let hidden = Quad { scale: [0.0; 3], ..quad(UPRIGHT) };
    let scene = hidden.import("hidden");
    assert!(scene.tangents.iter().all(|t| *t == [0.0; 4]));
    // Degenerate UVs (no area): MikkTSpace has no direction to give; tangents stay finite.
    let scene = quad([[0.0, 1.0], [0.0, 1.0], [0.0, 0.0], [0.0, 0.0]]).import("no-uv-area");
    assert_eq!(scene.tangents.len(), scene.vertices.len());
    assert!(scene.tangents.iter().flatten().all(|c| c.is_finite()));
}

/// With no light, an emissive factor of (1, 0.5, 0.25) at `KHR_materials_emissive_strength`
/// 0.5 gives linear 0.5, 0.25 and 0.125: codes 188, 137 and 99, each within 1 code. An emissive
/// texture that is black on one half masks the emission to 0 there, and the same quad without
/// emission is black.
#[test]
fn an_emissive_quad_in_an_unlit_scene_is_bright() {
    let black = json!({ "baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0 });
    let glowing = Quad::new(json!({
        "pbrMetallicRoughness": black,
        "emissiveFactor": [1.0, 0.5, 0.25],
        "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": 0.5 } }
    }));
    let image = glowing.render("emissive", &dark());
    // Linear 0.5, 0.25 and 0.125 through the sRGB transfer: codes 188, 137 and 99.
    for (channel, expected) in [(0, 188), (1, 137), (2, 99)] {
        let value = code(&image, 32, 32, channel);
        assert!(value.abs_diff(expected) <= 1, "channel {channel}: {value}, expected {expected}");
    }
    // An emissive texture, black on its left half, masks the emission there.
    let half = png(64, 64, |x, _| if x < 32 { [0, 0, 0, 255] } else { [255, 255, 255, 255] });
    let textured = Quad {
        images: vec![half],
        ..Quad::new(json!({
            "pbrMetallicRoughness": black,
            "emissiveFactor": [1.0, 0.5, 0.25],
            "emissiveTexture": { "index": 0 }
        }))
    };
    let image = textured.render("emissive-texture", &dark());
    assert_eq!(code(&image, 4, 32, 0), 0, "left half");
    assert_eq!(code(&image, 60, 32, 0), 255, "right half");
    // Without emission the same quad is black.
    let plain = Quad::new(json!({ "pbrMetallicRoughness": black })).render("not-emissive", &dark());
    assert!(plain.display.rgba.chunks_exact(4).all(|p| p[..3] == [0, 0, 0]));
}

/// Where the occlusion texture is 0, strength 1 takes the ambient term to code 0 and strength
/// 0.5 to code 188 (linear 0.5, within 1 code); where it is 1, the ambient term is untouched.
#[test]
fn occlusion_darkens_the_ambient_term_by_its_strength() {
    // Red 0 on the left half, 255 on the right; green, which glTF does not read, the reverse.
    let occlusion = png(64, 64, |x, _| if x < 32 { [0, 255, 0, 255] } else { [255, 0, 0, 255] });
    let ambient = Lighting { lights: Vec::new(), ambient: Vec3::ONE, background: Vec3::ZERO, exposure: 1.0 };
    let white = json!({ "baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0 });
    let occluded = |strength: f32| {
        let quad = Quad {
            images: vec![occlusion.clone()],
            ..Quad::new(json!({
                "pbrMetallicRoughness": white,
                "occlusionTexture": { "index": 0, "strength": strength }
            }))
        };
        quad.render(&format!("occlusion-{strength}"), &ambient)
    };
    let full = occluded(1.0);
    assert_eq!((code(&full, 4, 32, 1), code(&full, 60, 32, 1)), (0, 255));
    // Half strength: ambient × 0.5 where occluded, sRGB code 188.
    let half = occluded(0.5);
    assert!(code(&half, 4, 32, 1).abs_diff(188) <= 1, "{}", code(&half, 4, 32, 1));
    assert_eq!(code(&half, 60, 32, 1), 255);
}

/// A metallic-roughness texture with metalness 0 on one half and 1 on the other renders each
/// half within 1 code of the untextured dielectric and the untextured metal. The rough metal
/// is more than 40 codes darker than the dielectric: it has no diffuse light.
#[test]
fn a_metallic_roughness_texture_multiplies_the_factors() {
    // Metalness (blue) 0 on the left half, 1 on the right; roughness (green) 1 everywhere.
    let metal_rough = png(64, 64, |x, _| [0, 255, if x < 32 { 0 } else { 255 }, 255]);
    let lighting = sun(Vec3::new(0.0, 0.0, -1.0));
    let material = |metallic: f32, textured: bool| {
        let mut pbr = json!({ "baseColorFactor": [0.9, 0.9, 0.9, 1.0], "metallicFactor": metallic, "roughnessFactor": 1.0 });
        if textured {
            pbr["metallicRoughnessTexture"] = json!({ "index": 0 });
        }
        let images = if textured { vec![metal_rough.clone()] } else { Vec::new() };
        Quad { images, ..Quad::new(json!({ "pbrMetallicRoughness": pbr })) }
    };
    let mapped = material(1.0, true).render("metal-rough", &lighting);
    let dielectric = material(0.0, false).render("dielectric", &lighting);
    let metal = material(1.0, false).render("metal", &lighting);
    // Left: metalness 1 × 0, as the dielectric; right: 1 × 1, as the metal.
    assert!(code(&mapped, 8, 32, 1).abs_diff(code(&dielectric, 8, 32, 1)) <= 1);
    assert!(code(&mapped, 56, 32, 1).abs_diff(code(&metal, 56, 32, 1)) <= 1);
    assert!(
        code(&dielectric, 8, 32, 1) > code(&metal, 56, 32, 1) + 40,
        "a rough metal shows no diffuse light"
    );
}

/// An offset of 3/64 moves a 64-texel checker exactly 3 pixels: every pixel is within 1 code
/// of its neighbour 3 pixels over in the untransformed image. Rotation and scale give the image
/// of the same UVs transformed on the CPU, within 2 codes.
#[test]
fn a_texture_transform_moves_the_texture_as_the_extension_defines() {
    // A 64×64 checker of 8-texel squares: one texel per pixel across the 64-pixel view.
    let checker =
        png(64, 64, |x, y| if (x / 8 + y / 8) % 2 == 0 { [255, 255, 255, 255] } else { [0, 0, 0, 255] });
    let textured = |transform: Option<Value>, uvs: [[f32; 2]; 4], name: &str| {
        let mut info = json!({ "index": 0 });
        if let Some(transform) = transform {
            info["extensions"] = json!({ "KHR_texture_transform": transform });
        }
        let material = json!({ "pbrMetallicRoughness": { "baseColorTexture": info, "metallicFactor": 0.0 } });
        let quad = Quad { images: vec![checker.clone()], uvs, ..Quad::new(material) };
        let ambient =
            Lighting { lights: Vec::new(), ambient: Vec3::ONE, background: Vec3::ZERO, exposure: 1.0 };
        quad.render(name, &ambient)
    };
    let plain = textured(None, UPRIGHT, "checker");
    // An offset of 3/64 in u moves the checker three texels (pixels) to the left.
    let moved = textured(Some(json!({ "offset": [3.0 / 64.0, 0.0] })), UPRIGHT, "checker-offset");
    let mut compared = 0;
    for y in 0..SIDE {
        for x in 0..SIDE - 3 {
            assert!(code(&moved, x, y, 0).abs_diff(code(&plain, x + 3, y, 0)) <= 1, "({x}, {y})");
            compared += 1;
        }
    }
    assert!(compared > 3000);
    assert!(max_step(&moved, &plain) > 200, "the offset moved the checker by a square");
    // Rotation and scale: the same image as UVs transformed on the CPU by the extension's matrix.
    let transform = UvTransform::new([0.1, 0.3], 0.7, [2.0, 0.5]);
    let rotated = textured(
        Some(json!({ "offset": [0.1, 0.3], "rotation": 0.7, "scale": [2.0, 0.5] })),
        UPRIGHT,
        "checker-rotated",
    );
    let baked = textured(None, UPRIGHT.map(|uv| transform.apply(uv)), "checker-baked");
    assert!(max_step(&rotated, &baked) <= 2, "{}", max_step(&rotated, &baked));
    assert!(max_step(&rotated, &plain) > 200);
}

/// The rotation's direction is the one Khronos' TextureTransformTest sample marks green, which
/// was checked by rendering that file (`docs/own-scene.md`); this pins it against a change.
#[test]
fn the_uv_transform_turns_the_way_the_khronos_sample_expects() {
    // u′ = cos r · sx·u + sin r · sy·v + ox, v′ = −sin r · sx·u + cos r · sy·v + oy: the
    // direction Khronos' TextureTransformTest sample marks green (checked by rendering it).
    let t = UvTransform::new([0.5, 0.25], std::f32::consts::FRAC_PI_2, [2.0, 3.0]);
    let [u, v] = t.apply([1.0, 0.0]);
    assert!((u - 0.5).abs() < 1e-6 && (v + 1.75).abs() < 1e-6, "({u}, {v})");
    let [u, v] = t.apply([0.0, 1.0]);
    assert!((u - 3.5).abs() < 1e-6 && (v - 0.25).abs() < 1e-6, "({u}, {v})");
    assert!(UvTransform::new([0.0; 2], 0.0, [1.0; 2]).is_identity());
}

/// A solid 16² texture packed beside a red one renders within 1 code of the same texture
/// alone, magnified 4× and minified 2×, 3× and 16× with repeats, and the texture memory is
/// what the layers and pages predict. The 3× case sits between two mip levels, where trilinear
/// filtering reads the coarser level too: a margin of half a texel of the finer level once let
/// 51 codes of red through there. A packed checker differs from its unpacked twin by more than
/// 2 codes in fewer than 5% of channel values: its repeat seams clamp instead of blending
/// across, which shows only on pixels that straddle a seam.
#[test]
fn textures_of_different_sizes_packed_in_pages_look_as_if_each_had_a_layer() {
    // The checker fills a 64² layer alone; two 16² textures share the second layer side by
    // side: a solid green one, shown, and a solid red one beside it, never shown (emission
    // of factor 0). An occlusion texture of strength 0 changes no pixel either.
    let checker =
        png(64, 64, |x, y| if (x / 8 + y / 8) % 2 == 0 { [250, 200, 40, 255] } else { [20, 60, 200, 255] });
    let green = png(16, 16, |_, _| [30, 220, 60, 255]);
    let red = png(16, 16, |_, _| [255, 0, 0, 255]);
    let ambient = Lighting { lights: Vec::new(), ambient: Vec3::ONE, background: Vec3::ZERO, exposure: 1.0 };
    let render = |uvs: [[f32; 2]; 4], base: &[u8], packed: bool, name: &str| {
        let mut material =
            json!({ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 }, "metallicFactor": 0.0 } });
        let mut images = vec![base.to_vec()];
        if packed {
            material["occlusionTexture"] = json!({ "index": 1, "strength": 0.0 });
            material["emissiveTexture"] = json!({ "index": 2 });
            images.extend([checker.clone(), red.clone()]);
        }
        let quad = Quad { images, uvs, ..Quad::new(material) };
        let scene = quad.import(name);
        let camera = Camera::look_at(DVec3::new(0.0, 0.0, 1.0), DVec3::ZERO, 90.0);
        let (gpu, _guard) = gpu();
        let mut renderer = SceneRenderer::new(gpu, &scene, &camera, &ambient, settings(SIDE, SIDE)).unwrap();
        assert_eq!(renderer.needs().features.texture_pages, packed);
        (render(&mut renderer, "deferred-1x1"), renderer.texture_bytes())
    };
    let tiled = UPRIGHT.map(|[u, v]| [u * 8.0, v * 8.0]);
    let between = UPRIGHT.map(|[u, v]| [u * 12.0, v * 12.0]);
    let far = UPRIGHT.map(|[u, v]| [u * 64.0, v * 64.0]);
    let cases = [
        (UPRIGHT, "magnified 4×"),
        (tiled, "minified 2×, repeated"),
        // Between two levels, trilinear filtering reads the coarser one's larger texels too.
        (between, "minified 3×, repeated"),
        (far, "minified 16×, repeated"),
    ];
    for (uvs, what) in cases {
        let (alone, alone_bytes) = render(uvs, &green, false, &format!("green-alone-{what}"));
        let (packed, packed_bytes) = render(uvs, &green, true, &format!("green-packed-{what}"));
        // Not one texel of the red neighbour, nor of any level coarser than green's own last.
        assert!(max_step(&alone, &packed) <= 1, "{what}: {}", max_step(&alone, &packed));
        assert_eq!(
            (alone_bytes, packed_bytes),
            (16 * 16 * 4 * 341 / 256, 2 * 64 * 64 * 4 * 5461 / 4096),
            "{what}"
        );
    }
    // A checker packed beside others: its repeat seams clamp instead of blending across, which
    // shows only on pixels that straddle a seam.
    let checker_small =
        png(32, 32, |x, y| if (x / 4 + y / 4) % 2 == 0 { [250, 200, 40, 255] } else { [20, 60, 200, 255] });
    let (alone, _) = render(tiled, &checker_small, false, "checker-alone");
    let (packed, _) = render(tiled, &checker_small, true, "checker-packed");
    let differing =
        alone.display.rgba.iter().zip(&packed.display.rgba).filter(|(a, b)| a.abs_diff(**b) > 2).count();
    assert!(
        differing * 20 < alone.display.rgba.len(),
        "{differing} channel values differ by more than 2 codes"
    );
}

#[test]
fn more_texture_layers_than_the_device_holds_is_refused_by_name() {
    // 2 100 textures of one size: one layer each, past lavapipe's 2 048 array layers (as a
    // file whose materials use that many would import).
    let texel = png(4, 4, |_, _| [200, 100, 50, 255]);
    let mut quad = Quad::new(json!({ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } } }));
    quad.images = vec![texel];
    let mut scene = quad.import("many-textures");
    scene.textures = vec![scene.textures[0].clone(); 2100];
    let camera = Camera::look_at(DVec3::new(0.0, 0.0, 1.0), DVec3::ZERO, 90.0);
    let (gpu, _guard) = gpu();
    let error =
        SceneRenderer::new(gpu, &scene, &camera, &dark(), settings(SIDE, SIDE)).unwrap_err().to_string();
    assert!(
        error.contains("its 2100 textures need 2100 layers") && error.contains("max_texture_array_layers"),
        "{error}"
    );
}
