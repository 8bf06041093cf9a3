//! glTF 2.0 import through the `gltf` crate: meshes with baked node transforms; base-colour,
//! metallic-roughness, normal, emissive and occlusion textures with `KHR_texture_transform`; factors (emission
//! with `KHR_materials_emissive_strength`), alpha MASK; UVs, normals (flat normals generated
//! where a primitive has none) and tangents (MikkTSpace where a normal-mapped primitive has
//! none); the first camera, and `KHR_lights_punctual` lights.

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

use glam::{DMat3, DMat4, DVec3, Vec3};

use super::{
    AlphaMode, Camera, DrawClass, Encoding, Light, LightKind, Material, Scene, Texture, TextureRef,
    UvTransform, Vertex,
};
use crate::error::RenderError;

/// Reads a `.gltf` or `.glb` file and everything it references. Every error names the part of
/// the file at fault (`nodes[3]`, `accessors[2]`, `images[0] (uri textures/a.png)`, …).
pub fn load_gltf(path: &Path) -> Result<Scene, RenderError> {
    let fail = |message: String| RenderError::Scene { path: path.to_path_buf(), message };
    regular_file(path).map_err(|e| fail(format!("cannot read glTF: {e}")))?;
    let (gltf::Gltf { document, blob }, lenient) =
        open(path).map_err(|e| fail(format!("cannot read glTF: {e}")))?;
    let base = path.parent().unwrap_or(Path::new("."));
    check_external_files(&document, base).map_err(fail)?;
    let buffers = gltf::import_buffers(&document, Some(base), blob)
        .map_err(|e| fail(format!("cannot read buffers: {e}")))?;

    let mut importer = Importer::default();
    let Materials { materials, textures, mut warnings } = import_materials(&document).map_err(fail)?;
    if materials.len() > super::MAX_MATERIALS {
        return Err(fail(format!(
            "materials: {} materials, the G-buffer holds at most {}",
            materials.len() - 1,
            super::MAX_MATERIALS - 1
        )));
    }
    importer.scene.materials = materials;
    importer.visit_scene(&document, &buffers).map_err(fail)?;

    let mut scene = importer.finish();
    scene.textures = decode_textures(&document, base, &buffers, &textures).map_err(fail)?;
    scene.generator = document.as_json().asset.generator.clone();
    warnings.extend(lenient);
    warnings.extend(ignored_extensions(&document));
    scene.warnings = warnings;
    Ok(scene)
}

/// Ok if `path` is a regular file (after symlinks); else why not, in words: a FIFO or a device
/// would block or never end, and a symlink loop is not "missing".
pub fn regular_file(path: &Path) -> Result<(), String> {
    match std::fs::metadata(path) {
        Ok(meta) if meta.is_file() => Ok(()),
        Ok(meta) if meta.is_dir() => Err(format!("{} is a folder, not a file", path.display())),
        Ok(_) => Err(format!("{} is not a regular file (a FIFO, socket or device)", path.display())),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            Err(format!("{} does not exist", path.display()))
        }
        Err(e) => Err(format!("{}: {e}", path.display())),
    }
}

/// Checks every buffer and image the file names by URI before anything reads them: the URI
/// is a relative reference (resolved against the file's folder, `..` included, as glTF says)
/// that names a regular file that exists.
fn check_external_files(document: &gltf::Document, base: &Path) -> Result<(), String> {
    let buffers = document.buffers().filter_map(|b| match b.source() {
        gltf::buffer::Source::Uri(uri) => Some((format!("buffers[{}]", b.index()), uri)),
        gltf::buffer::Source::Bin => None,
    });
    let mut images = Vec::new();
    for index in 0..document.images().len() {
        if let ImageSource::Uri(uri) = image_source(document, index)? {
            images.push((format!("images[{index}]"), uri));
        }
    }
    for (what, uri) in buffers.chain(images) {
        if uri.starts_with("data:") {
            continue;
        }
        // `file:`, `http:` …: the gltf crate would follow them out of the folder.
        if uri.split(['/', '?', '#']).next().is_some_and(|first| first.contains(':')) {
            return Err(format!(
                "{what}.uri: `{uri}` has a scheme; only relative paths and data: URIs are read"
            ));
        }
        let relative = PathBuf::from(percent_decode(uri).map_err(|e| format!("{what}.uri: {e}"))?);
        if relative.has_root() {
            return Err(format!(
                "{what}.uri: `{uri}` is an absolute path; glTF resources are named relative to the file"
            ));
        }
        regular_file(&base.join(&relative)).map_err(|e| format!("{what}.uri: {e}"))?;
    }
    Ok(())
}

/// `%XX` escapes of a URI decoded (glTF URIs are RFC 3986 references; a `%` not followed by
/// two hex digits is kept as it is). Escapes that decode to bytes which are not UTF-8 are an
/// error: the gltf crate would panic on them.
pub fn percent_decode(uri: &str) -> Result<String, String> {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        match (bytes[i], bytes.get(i + 1).copied().and_then(hex), bytes.get(i + 2).copied().and_then(hex)) {
            (b'%', Some(high), Some(low)) => {
                out.push((high * 16 + low) as u8);
                i += 3;
            }
            (byte, _, _) => {
                out.push(byte);
                i += 1;
            }
        }
    }
    String::from_utf8(out).map_err(|_| format!("`{uri}`: its %-escapes do not decode to UTF-8"))
}

/// Reads and validates a glTF or GLB file; the second value holds a warning for each departure
/// from the specification that it tolerates. The gltf crate's validation (gltf-json 1.4.1)
/// looks up each primitive's POSITION accessor before checking that it exists, and panics when
/// it does not; that one reference is checked here first.
fn open(path: &Path) -> Result<(gltf::Gltf, Vec<String>), String> {
    use gltf::json::mesh::Semantic;
    use gltf::json::validation::Checked;
    let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
    // The crate subtracts the 12-byte header from the stated length unchecked.
    if let Some(length) = bytes.strip_prefix(b"glTF").and_then(|rest| rest.get(4..8)) {
        let length = u32::from_le_bytes(length.try_into().expect("4 bytes"));
        if length < 12 {
            return Err(format!(
                "the GLB header states a length of {length} bytes, less than the header itself"
            ));
        }
    }
    let gltf::Gltf { document, blob } =
        gltf::Gltf::from_slice_without_validation(&bytes).map_err(|e| e.to_string())?;
    let mut json = document.into_json();
    // Before the crate's validation, which refuses required extensions it was not built with
    // in words that do not say what aabench reads.
    if let Some(unknown) = json.extensions_required.iter().find(|e| !EXTENSIONS.contains(&e.as_str())) {
        return Err(format!(
            "extensionsRequired: the file requires `{unknown}`, which aabench does not support (it reads {})",
            EXTENSIONS.join(", ")
        ));
    }
    let mut positions = Vec::new();
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let position = primitive.attributes.get(&Checked::Valid(Semantic::Positions));
            if let Some(accessor) = position.filter(|a| a.value() >= json.accessors.len()) {
                return Err(format!(
                    "meshes[{m}].primitives[{p}].attributes.POSITION: accessor {} does not exist (the file has {})",
                    accessor.value(),
                    json.accessors.len()
                ));
            }
            positions.extend(position.map(|a| a.value()));
        }
    }
    // glTF requires POSITION accessors to state their bounds, which the crate's validation
    // checks; some exporters omit them. The importer computes bounds itself, so it stands
    // in placeholders and says so.
    let mut warnings = Vec::new();
    positions.sort_unstable();
    positions.dedup();
    for index in positions {
        let accessor = &mut json.accessors[index];
        let valid = |bound: &Option<serde_json::Value>| {
            bound.as_ref().is_some_and(|b| serde_json::from_value::<[f32; 3]>(b.clone()).is_ok())
        };
        if !(valid(&accessor.min) && valid(&accessor.max)) {
            accessor.min = Some(serde_json::json!([0.0, 0.0, 0.0]));
            accessor.max = Some(serde_json::json!([0.0, 0.0, 0.0]));
            warnings.push(format!(
                "accessors[{index}]: a POSITION accessor without a valid min and max (glTF requires them); \
                 aabench computes bounds from the data"
            ));
        }
    }
    let document = gltf::Document::from_json(json).map_err(|e| e.to_string())?;
    Ok((gltf::Gltf { document, blob }, warnings))
}

/// The glTF extensions the importer reads. A file may require only these; others it merely
/// uses are ignored with a warning each.
pub const EXTENSIONS: [&str; 3] =
    ["KHR_lights_punctual", "KHR_texture_transform", "KHR_materials_emissive_strength"];

/// One line per extension the file uses that aabench ignores.
fn ignored_extensions(document: &gltf::Document) -> Vec<String> {
    let json = document.as_json();
    json.extensions_used
        .iter()
        .filter(|e| !EXTENSIONS.contains(&e.as_str()))
        .map(|e| format!("extension `{e}` is not supported and is ignored (the file marks it optional)"))
        .collect()
}

/// The `asset.generator` string of a glTF file, if it can be read.
pub fn read_generator(path: &Path) -> Option<String> {
    let (gltf, _) = open(path).ok()?;
    gltf.document.as_json().asset.generator.clone()
}

/// The textures that materials sample, in order of first use: each image once per encoding
/// it is read with (an image could be both a colour and a data texture).
#[derive(Default)]
struct TextureUses {
    keys: Vec<(usize, Encoding)>,
    index: HashMap<(usize, Encoding), usize>,
}

impl TextureUses {
    fn add(&mut self, image: usize, encoding: Encoding) -> usize {
        *self.index.entry((image, encoding)).or_insert_with(|| {
            self.keys.push((image, encoding));
            self.keys.len() - 1
        })
    }
}

/// One texture slot of a material as the JSON gives it: texture index, UV set, transform.
struct Slot<'a> {
    field: &'static str,
    texture: usize,
    tex_coord: u32,
    transform: Option<std::borrow::Cow<'a, gltf::json::extensions::texture::TextureTransform>>,
    encoding: Encoding,
}

/// The texture slots of a material that aabench reads: base colour, metallic-roughness,
/// normal, emissive and occlusion.
fn texture_slots(json: &gltf::json::Material) -> Result<Vec<Slot<'_>>, String> {
    use gltf::json::extensions::texture::TextureTransform;
    use std::borrow::Cow;
    fn info<'a>(field: &'static str, info: &'a gltf::json::texture::Info, encoding: Encoding) -> Slot<'a> {
        Slot {
            field,
            texture: info.index.value(),
            tex_coord: info.tex_coord,
            transform: info.extensions.as_ref().and_then(|e| e.texture_transform.as_ref()).map(Cow::Borrowed),
            encoding,
        }
    }
    // The crate keeps the extension of normal and occlusion textures as plain JSON.
    type Others = serde_json::Map<String, serde_json::Value>;
    let data = |field: &'static str, texture: usize, tex_coord: u32, others: Option<&Others>| {
        let transform = others
            .and_then(|o| o.get("KHR_texture_transform"))
            .map(|v| {
                serde_json::from_value::<TextureTransform>(v.clone())
                    .map(Cow::Owned)
                    .map_err(|e| format!("{field}.extensions.KHR_texture_transform: {e}"))
            })
            .transpose()?;
        Ok::<_, String>(Slot { field, texture, tex_coord, transform, encoding: Encoding::Linear })
    };
    let mut slots = Vec::new();
    if let Some(base) = &json.pbr_metallic_roughness.base_color_texture {
        slots.push(info("pbrMetallicRoughness.baseColorTexture", base, Encoding::Srgb));
    }
    if let Some(n) = &json.normal_texture {
        slots.push(data(
            "normalTexture",
            n.index.value(),
            n.tex_coord,
            n.extensions.as_ref().map(|e| &e.others),
        )?);
    }
    if let Some(metal_rough) = &json.pbr_metallic_roughness.metallic_roughness_texture {
        slots.push(info("pbrMetallicRoughness.metallicRoughnessTexture", metal_rough, Encoding::Linear));
    }
    if let Some(emissive) = &json.emissive_texture {
        slots.push(info("emissiveTexture", emissive, Encoding::Srgb));
    }
    if let Some(o) = &json.occlusion_texture {
        slots.push(data(
            "occlusionTexture",
            o.index.value(),
            o.tex_coord,
            o.extensions.as_ref().map(|e| &e.others),
        )?);
    }
    Ok(slots)
}

/// A slot's UV transform, checked: finite offset, rotation and scale.
fn uv_transform(
    transform: Option<&gltf::json::extensions::texture::TextureTransform>,
) -> Result<UvTransform, String> {
    let Some(t) = transform else {
        return Ok(UvTransform::IDENTITY);
    };
    let values = [t.offset.0[0], t.offset.0[1], t.rotation.0, t.scale.0[0], t.scale.0[1]];
    if !values.iter().all(|v| v.is_finite()) {
        return Err(format!(
            "extensions.KHR_texture_transform: offset {:?}, rotation {}, scale {:?} must be finite",
            t.offset.0, t.rotation.0, t.scale.0
        ));
    }
    Ok(UvTransform::new(t.offset.0, t.rotation.0, t.scale.0))
}

/// What [`import_materials`] reads: materials in file order plus one default at the end for
/// primitives without a material; the textures they use (image and encoding, indexed by
/// [`TextureRef::texture`]); and a warning for each texture that aabench cannot place (it
/// reads one UV set, `TEXCOORD_0`).
struct Materials {
    materials: Vec<Material>,
    textures: Vec<(usize, Encoding)>,
    warnings: Vec<String>,
}

fn import_materials(document: &gltf::Document) -> Result<Materials, String> {
    let mut uses = TextureUses::default();
    let mut warnings = Vec::new();
    let mut materials = Vec::new();
    for material in document.materials() {
        let index = material.index().unwrap_or(materials.len());
        let json = &document.as_json().materials[index];
        let mut refs: HashMap<&'static str, (TextureRef, Encoding)> = HashMap::new();
        for slot in texture_slots(json).map_err(|e| format!("materials[{index}].{e}"))? {
            let what = format!("materials[{index}].{}", slot.field);
            let transform = uv_transform(slot.transform.as_deref()).map_err(|e| format!("{what}.{e}"))?;
            let tex_coord = slot.transform.as_ref().and_then(|t| t.tex_coord).unwrap_or(slot.tex_coord);
            if tex_coord != 0 {
                warnings.push(format!(
                    "{what}: uses TEXCOORD_{tex_coord}; aabench reads only TEXCOORD_0, so the texture is ignored"
                ));
                continue;
            }
            let image = document
                .textures()
                .nth(slot.texture)
                .ok_or_else(|| format!("{what}.index: texture {} does not exist", slot.texture))?
                .source()
                .index();
            let texture = uses.add(image, slot.encoding);
            refs.insert(slot.field, (TextureRef { texture, transform }, slot.encoding));
        }
        let slot = |field: &str| refs.get(field).map(|(r, _)| *r);
        let pbr = material.pbr_metallic_roughness();
        let strength = material.emissive_strength().unwrap_or(1.0);
        let emissive = material.emissive_factor().map(|c| c * strength);
        if !emissive.iter().all(|c| c.is_finite() && *c >= 0.0) {
            return Err(format!(
                "materials[{index}]: emissiveFactor {:?} × KHR_materials_emissive_strength {strength} must be finite and ≥ 0",
                material.emissive_factor()
            ));
        }
        let normal_scale = material.normal_texture().map_or(1.0, |n| n.scale());
        if !normal_scale.is_finite() {
            return Err(format!("materials[{index}].normalTexture.scale: {normal_scale} must be finite"));
        }
        let occlusion_strength = material.occlusion_texture().map_or(1.0, |o| o.strength());
        if !(0.0..=1.0).contains(&occlusion_strength) {
            return Err(format!(
                "materials[{index}].occlusionTexture.strength: {occlusion_strength} must be in [0, 1]"
            ));
        }
        materials.push(Material {
            name: material.name().unwrap_or("").to_string(),
            base_color: pbr.base_color_factor(),
            metallic: pbr.metallic_factor(),
            roughness: pbr.roughness_factor(),
            texture: slot("pbrMetallicRoughness.baseColorTexture"),
            alpha: match material.alpha_mode() {
                gltf::material::AlphaMode::Mask => {
                    AlphaMode::Mask { cutoff: material.alpha_cutoff().unwrap_or(0.5) }
                }
                _ => AlphaMode::Opaque,
            },
            double_sided: material.double_sided(),
            normal_texture: slot("normalTexture"),
            normal_scale,
            emissive,
            emissive_texture: slot("emissiveTexture"),
            occlusion_texture: slot("occlusionTexture"),
            occlusion_strength,
            metallic_roughness_texture: slot("pbrMetallicRoughness.metallicRoughnessTexture"),
        });
    }
    materials.push(Material {
        name: "default".into(),
        base_color: [0.8, 0.8, 0.8, 1.0],
        metallic: 0.0,
        roughness: 0.6,
        ..Material::default()
    });
    Ok(Materials { materials, textures: uses.keys, warnings })
}

/// The scene's origin is a multiple of this many units (see `Importer::finish`).
pub const ORIGIN_GRID: f64 = 1024.0;

#[derive(Default)]
struct Importer {
    scene: Scene,
    /// Each vertex's world position, in f64.
    world: Vec<DVec3>,
    /// The file's lights with their world positions, in f64.
    lights: Vec<(Light, DVec3)>,
    /// Triangles as vertex-index triples, by draw class.
    triangles: BTreeMap<DrawClass, Vec<[u32; 3]>>,
    /// Normal-mapped primitives without tangents of their own, for MikkTSpace.
    untangented: Vec<Primitive>,
}

/// Where one primitive's vertices and triangles lie in the importer's lists.
struct Primitive {
    class: DrawClass,
    vertices: std::ops::Range<usize>,
    triangles: std::ops::Range<usize>,
}

impl Importer {
    /// Walks the default scene's node trees depth first (children in order), without recursion:
    /// a hierarchy thousands of nodes deep must not overflow the stack. A node reached twice
    /// is an error: glTF's nodes form disjoint trees, so it is a cycle or a second parent.
    fn visit_scene(
        &mut self,
        document: &gltf::Document,
        buffers: &[gltf::buffer::Data],
    ) -> Result<(), String> {
        let roots: Vec<gltf::Node> = match document.default_scene().or_else(|| document.scenes().next()) {
            Some(scene) => scene.nodes().collect(),
            None => {
                // No scene: every node that is nobody's child is a root.
                let mut is_child = vec![false; document.nodes().len()];
                for child in document.nodes().flat_map(|n| n.children()) {
                    is_child[child.index()] = true;
                }
                document.nodes().filter(|n| !is_child[n.index()]).collect()
            }
        };
        let mut reached = vec![false; document.nodes().len()];
        let mut stack: Vec<(gltf::Node, DMat4)> =
            roots.into_iter().rev().map(|n| (n, DMat4::IDENTITY)).collect();
        while let Some((node, parent)) = stack.pop() {
            if std::mem::replace(&mut reached[node.index()], true) {
                return Err(format!(
                    "nodes[{}]: reached twice: the node hierarchy has a cycle or a node with two parents \
                     (glTF nodes must form disjoint trees)",
                    node.index()
                ));
            }
            let world = self.visit(document, &node, parent, buffers)?;
            stack.extend(node.children().map(|child| (child, world)).collect::<Vec<_>>().into_iter().rev());
        }
        Ok(())
    }

    /// Adds one node's mesh and camera; returns its world transform.
    fn visit(
        &mut self,
        document: &gltf::Document,
        node: &gltf::Node,
        parent: DMat4,
        buffers: &[gltf::buffer::Data],
    ) -> Result<DMat4, String> {
        let local = DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from)));
        let world = parent * local;
        if !world.is_finite() {
            return Err(format!("nodes[{}]: the transform is not finite", node.index()));
        }
        if let Some(mesh) = node.mesh() {
            for primitive in mesh.primitives() {
                self.add_primitive(&mesh, &primitive, world, buffers)?;
            }
        }
        if let (Some(camera), None) = (node.camera(), &self.scene.camera) {
            self.scene.camera = camera_from_node(document, camera.index(), world)?;
        }
        if let Some(light) = node.light() {
            self.lights
                .push(light_from_node(&light, world).map_err(|e| format!("nodes[{}]: {e}", node.index()))?);
        }
        Ok(world)
    }

    fn add_primitive(
        &mut self,
        mesh: &gltf::Mesh,
        primitive: &gltf::Primitive,
        world: DMat4,
        buffers: &[gltf::buffer::Data],
    ) -> Result<(), String> {
        let name = || {
            format!(
                "meshes[{}] ({}) primitives[{}]",
                mesh.index(),
                mesh.name().unwrap_or("unnamed"),
                primitive.index()
            )
        };
        if primitive.mode() != gltf::mesh::Mode::Triangles {
            // Points and lines have no surface to shade; skipping them keeps the rest usable.
            return Ok(());
        }
        for (semantic, accessor) in primitive.attributes() {
            check_format(Some(&semantic), &accessor)
                .and_then(|()| check_accessor(&accessor, buffers))
                .map_err(|e| format!("{}: attributes.{}: {e}", name(), semantic.to_string()))?;
        }
        if let Some(accessor) = primitive.indices() {
            check_format(None, &accessor)
                .and_then(|()| check_accessor(&accessor, buffers))
                .map_err(|e| format!("{}: indices: {e}", name()))?;
        }
        let reader = primitive.reader(|buffer| buffers.get(buffer.index()).map(|d| &d.0[..]));
        let positions: Vec<[f32; 3]> = reader
            .read_positions()
            .ok_or_else(|| format!("{}: attributes.POSITION is missing", name()))?
            .collect();
        if let Some(i) = positions.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
            return Err(format!(
                "{}: attributes.POSITION: vertex {i} is {:?}, not finite",
                name(),
                positions[i]
            ));
        }
        let uvs: Vec<[f32; 2]> = match reader.read_tex_coords(0) {
            Some(uvs) => uvs.into_f32().collect(),
            None => vec![[0.0; 2]; positions.len()],
        };
        if let Some(i) = uvs.iter().position(|uv| !uv.iter().all(|c| c.is_finite())) {
            return Err(format!("{}: attributes.TEXCOORD_0: vertex {i} is {:?}, not finite", name(), uvs[i]));
        }
        let normals: Option<Vec<[f32; 3]>> = reader.read_normals().map(Iterator::collect);
        // Without normals the file's tangents must be ignored (glTF 2.0, 3.7.2.1).
        let file_tangents: Option<Vec<[f32; 4]>> =
            reader.read_tangents().filter(|_| normals.is_some()).map(Iterator::collect);
        let indices: Vec<u32> = match reader.read_indices() {
            Some(indices) => indices.into_u32().collect(),
            None => (0..positions.len() as u32).collect(),
        };
        if !indices.len().is_multiple_of(3) {
            return Err(format!(
                "{}: {} indices, not a multiple of 3: triangles need three each",
                name(),
                indices.len()
            ));
        }
        if let Some(&bad) = indices.iter().find(|&&i| i as usize >= positions.len()) {
            return Err(format!(
                "{}: indices: {bad} is out of range for {} vertices",
                name(),
                positions.len()
            ));
        }
        if uvs.len() != positions.len()
            || normals.as_ref().is_some_and(|n| n.len() != positions.len())
            || file_tangents.as_ref().is_some_and(|t| t.len() != positions.len())
        {
            return Err(format!("{}: attribute counts differ from POSITION", name()));
        }
        if let Some(i) =
            file_tangents.as_ref().and_then(|t| t.iter().position(|t| !t.iter().all(|c| c.is_finite())))
        {
            return Err(format!("{}: attributes.TANGENT: vertex {i} is not finite", name()));
        }

        let default_material = self.scene.materials.len() - 1;
        let material = primitive.material().index().unwrap_or(default_material);
        let class = self.scene.materials[material].draw_class();
        // A mirroring transform turns counter-clockwise front faces clockwise (glTF 2.0, 3.7.4).
        let mirrored = DMat3::from_mat4(world).determinant() < 0.0;
        let normal_matrix = DMat3::from_mat4(world).inverse().transpose();
        // World positions stay f64 until `finish` knows the scene's origin.
        let world_positions: Vec<DVec3> =
            positions.iter().map(|p| world.transform_point3(DVec3::from(p.map(f64::from)))).collect();
        // Finite scales can multiply up to positions no f32 (nor camera) can hold.
        let beyond = |p: &DVec3| !p.is_finite() || p.abs().max_element() > super::MAX_COORDINATE;
        if let Some(i) = world_positions.iter().position(beyond) {
            return Err(format!(
                "{}: vertex {i} lies at {} in world space, beyond ±{:e} (the node transforms multiply up)",
                name(),
                world_positions[i],
                super::MAX_COORDINATE
            ));
        }
        let vertex = |normal: Vec3, uv: [f32; 2]| Vertex {
            position: [0.0; 3],
            normal: normal.to_array(),
            uv,
            material: material as u32,
        };
        let first_vertex = self.scene.vertices.len();
        let first_triangle = self.triangles.get(&class).map_or(0, Vec::len);
        let vertices = &mut self.scene.vertices;
        let positions_world = &mut self.world;
        let triangles = self.triangles.entry(class).or_default();
        let wind = |t: &[u32]| if mirrored { [t[0], t[2], t[1]] } else { [t[0], t[1], t[2]] };

        match normals {
            Some(normals) => {
                let base = vertices.len() as u32;
                for ((p, n), uv) in world_positions.iter().zip(&normals).zip(&uvs) {
                    let n = (normal_matrix * DVec3::from(n.map(f64::from))).normalize_or_zero();
                    vertices.push(vertex(n.as_vec3(), *uv));
                    positions_world.push(*p);
                }
                let added: Vec<[u32; 3]> =
                    indices.chunks_exact(3).map(|t| wind(t).map(|i| base + i)).collect();
                let from = base as usize;
                repair_normals(&mut vertices[from..], &positions_world[from..], &added, base);
                triangles.extend(added);
            }
            None => {
                // Flat normals: every triangle gets its own three vertices.
                for t in indices.chunks_exact(3) {
                    let corners = wind(t).map(|i| (world_positions[i as usize], uvs[i as usize]));
                    let normal = (corners[1].0 - corners[0].0)
                        .cross(corners[2].0 - corners[0].0)
                        .normalize_or_zero()
                        .as_vec3();
                    let base = vertices.len() as u32;
                    for (position, uv) in corners {
                        vertices.push(vertex(normal, uv));
                        positions_world.push(position);
                    }
                    triangles.push([base, base + 1, base + 2]);
                }
            }
        }
        if self.scene.materials[material].normal_texture.is_some() {
            let file_tangents = file_tangents.map(|tangents| {
                // Tangents move with the surface; a mirroring transform flips the bitangent.
                let linear = DMat3::from_mat4(world);
                let handedness = if mirrored { -1.0 } else { 1.0 };
                tangents
                    .iter()
                    .map(|t| {
                        let xyz =
                            (linear * DVec3::new(t[0].into(), t[1].into(), t[2].into())).normalize_or_zero();
                        let w = if t[3] < 0.0 { -handedness } else { handedness };
                        [xyz.x as f32, xyz.y as f32, xyz.z as f32, w]
                    })
                    .collect()
            });
            self.add_tangents(class, first_vertex, first_triangle, file_tangents);
        }
        Ok(())
    }

    /// Gives the vertices from `first_vertex` on (one primitive's) tangents: the file's, or
    /// zero until [`Importer::generate_tangents`] gives them MikkTSpace's.
    fn add_tangents(
        &mut self,
        class: DrawClass,
        first_vertex: usize,
        first_triangle: usize,
        file: Option<Vec<[f32; 4]>>,
    ) {
        let tangents = &mut self.scene.tangents;
        tangents.resize(first_vertex, [0.0; 4]);
        match file {
            Some(file) => tangents.extend(file),
            None => {
                tangents.resize(self.scene.vertices.len(), [0.0; 4]);
                self.untangented.push(Primitive {
                    class,
                    vertices: first_vertex..self.scene.vertices.len(),
                    triangles: first_triangle..self.triangles[&class].len(),
                });
            }
        }
    }

    /// MikkTSpace tangents for the primitives that need them, primitives spread over the
    /// cores (it dominates the import of a large normal-mapped file). MikkTSpace gives one
    /// tangent per triangle corner; corners of one vertex that it gives different tangents (UV
    /// seams, mirrored UVs) split the vertex.
    fn generate_tangents(&mut self) {
        let primitives = std::mem::take(&mut self.untangented);
        if primitives.is_empty() {
            return;
        }
        // Split vertices go at the end: the table must reach it first.
        self.scene.tangents.resize(self.scene.vertices.len(), [0.0; 4]);
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
        let chunk = primitives.len().div_ceil(threads).max(1);
        let (vertices, world, triangles) = (&self.scene.vertices, &self.world, &self.triangles);
        let corners: Vec<Vec<[f32; 4]>> = std::thread::scope(|scope| {
            let workers: Vec<_> = primitives
                .chunks(chunk)
                .map(|part| {
                    scope.spawn(move || {
                        part.iter()
                            .map(|p| {
                                let triangles = &triangles[&p.class][p.triangles.clone()];
                                mikktspace_corners(vertices, world, triangles, p.vertices.start)
                            })
                            .collect::<Vec<_>>()
                    })
                })
                .collect();
            workers.into_iter().flat_map(|worker| worker.join().expect("MikkTSpace panicked")).collect()
        });
        for (primitive, corners) in primitives.iter().zip(corners) {
            self.weld_tangents(primitive, &corners);
        }
    }

    /// Gives each vertex of `primitive` the tangent of its corners, splitting vertices whose
    /// corners disagree.
    fn weld_tangents(&mut self, primitive: &Primitive, corners: &[[f32; 4]]) {
        let first = primitive.vertices.start;
        let mut assigned = vec![false; primitive.vertices.len()];
        let mut splits: HashMap<(u32, [u32; 4]), u32> = HashMap::new();
        let triangles = &mut self.triangles.get_mut(&primitive.class).expect("the primitive's class")
            [primitive.triangles.clone()];
        for (triangle, corner_tangents) in triangles.iter_mut().zip(corners.chunks_exact(3)) {
            for (index, &tangent) in triangle.iter_mut().zip(corner_tangents) {
                let v = *index as usize;
                if !std::mem::replace(&mut assigned[v - first], true) {
                    self.scene.tangents[v] = tangent;
                } else if self.scene.tangents[v] != tangent {
                    *index = *splits.entry((*index, tangent.map(f32::to_bits))).or_insert_with(|| {
                        self.scene.vertices.push(self.scene.vertices[v]);
                        self.world.push(self.world[v]);
                        self.scene.tangents.push(tangent);
                        (self.scene.vertices.len() - 1) as u32
                    });
                }
            }
        }
    }

    /// Sorts the triangles by draw class and makes positions relative to the scene's origin:
    /// the centre of its bounds, rounded to a multiple of [`ORIGIN_GRID`] units, so geometry
    /// far from the file's origin keeps f32 precision (and a scene near it keeps its bits).
    fn finish(mut self) -> Scene {
        self.generate_tangents();
        let (lo, hi) = self
            .world
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
        let origin = if self.world.is_empty() {
            DVec3::ZERO
        } else {
            ((lo + hi) * 0.5 / ORIGIN_GRID).round() * ORIGIN_GRID
        };
        for (vertex, world) in self.scene.vertices.iter_mut().zip(&self.world) {
            vertex.position = (*world - origin).as_vec3().to_array();
        }
        if !self.scene.tangents.is_empty() {
            self.scene.tangents.resize(self.scene.vertices.len(), [0.0; 4]);
        }
        self.scene.origin = origin;
        if let Some(camera) = &mut self.scene.camera {
            camera.position -= origin;
        }
        // A light without a range reaches everywhere (KHR_lights_punctual); the shader's
        // smooth window then sits far beyond the scene as seen from the light: ten times the
        // bounds' diagonal plus the light's distance from their centre.
        let (diagonal, centre) = if self.world.is_empty() {
            (1.0, DVec3::ZERO)
        } else {
            ((hi - lo).length().max(1e-6), (lo + hi) * 0.5)
        };
        self.scene.lights = self
            .lights
            .into_iter()
            .map(|(light, world)| Light {
                position: (world - origin).as_vec3(),
                range: if light.range.is_finite() {
                    light.range
                } else {
                    (10.0 * (diagonal + (world - centre).length())) as f32
                },
                ..light
            })
            .collect();
        for (class, triangles) in self.triangles {
            let start = self.scene.indices.len() as u32;
            self.scene.indices.extend(triangles.into_iter().flatten());
            self.scene.draws.push((class, start..self.scene.indices.len() as u32));
        }
        self.scene
    }
}

/// Checks that an accessor the importer reads has a format glTF allows for it (`None` for
/// indices): the gltf crate's readers assume it and panic otherwise. Sparse accessors are
/// refused rather than read: their indices and values are not bounds-checked by the crate.
fn check_format(semantic: Option<&gltf::Semantic>, accessor: &gltf::Accessor) -> Result<(), String> {
    use gltf::Semantic;
    use gltf::accessor::{DataType, Dimensions};
    let format = (accessor.data_type(), accessor.dimensions());
    let allowed = match semantic {
        None => matches!(format, (DataType::U8 | DataType::U16 | DataType::U32, Dimensions::Scalar)),
        Some(Semantic::Positions | Semantic::Normals) => format == (DataType::F32, Dimensions::Vec3),
        Some(Semantic::Tangents) => format == (DataType::F32, Dimensions::Vec4),
        Some(Semantic::TexCoords(_)) => {
            matches!(format, (DataType::F32 | DataType::U8 | DataType::U16, Dimensions::Vec2))
        }
        // Read by no one here.
        Some(_) => return Ok(()),
    };
    let index = accessor.index();
    if !allowed {
        let (data_type, dimensions) = format;
        return Err(format!(
            "accessors[{index}]: {dimensions:?} of {data_type:?} is not a format glTF allows here"
        ));
    }
    if accessor.sparse().is_some() {
        return Err(format!("accessors[{index}]: sparse accessors are not supported"));
    }
    Ok(())
}

/// Checks that an accessor's elements lie inside its buffer view and the view inside its
/// buffer, so that a short file is reported as short rather than as a missing attribute.
fn check_accessor(accessor: &gltf::Accessor, buffers: &[gltf::buffer::Data]) -> Result<(), String> {
    let index = accessor.index();
    // glTF requires count ≥ 1; the crate's readers compute count − 1.
    if accessor.count() == 0 {
        return Err(format!("accessors[{index}]: count is 0"));
    }
    let Some(view) = accessor.view() else {
        return Ok(());
    };
    let bytes = view_bytes(&view, buffers)?;
    let element = accessor.size();
    let stride = view.stride().unwrap_or(element);
    // The crate asserts that an element fits in its stride.
    if stride < element {
        return Err(format!(
            "bufferViews[{}].byteStride {stride} is shorter than the {element}-byte elements of accessors[{index}]",
            view.index()
        ));
    }
    // Counts come from the file: overflow means "too long" like any other excess.
    let needed = stride
        .checked_mul(accessor.count() - 1)
        .and_then(|n| n.checked_add(accessor.offset()))
        .and_then(|n| n.checked_add(element))
        .unwrap_or(usize::MAX);
    if needed > bytes.len() {
        return Err(format!(
            "accessors[{index}]: {} elements of {element} bytes from offset {} need {needed} bytes, \
             bufferViews[{}] holds {}",
            accessor.count(),
            accessor.offset(),
            view.index(),
            bytes.len()
        ));
    }
    Ok(())
}

/// The bytes of a buffer view, or why it does not fit in its buffer.
fn view_bytes<'a>(view: &gltf::buffer::View, buffers: &'a [gltf::buffer::Data]) -> Result<&'a [u8], String> {
    let buffer = view.buffer().index();
    let data = buffers.get(buffer).map_or(&[][..], |data| &data.0[..]);
    let end = view.offset().checked_add(view.length());
    end.and_then(|end| data.get(view.offset()..end)).ok_or_else(|| {
        format!(
            "bufferViews[{}] ends at byte {}, past the {} bytes of buffers[{buffer}]",
            view.index(),
            end.map_or("beyond 2⁶⁴".into(), |end| end.to_string()),
            data.len()
        )
    })
}

/// Replaces zero or non-finite vertex normals (which files do contain) with the area-weighted
/// normal of the primitive's triangles around the vertex, so shaders can normalize without NaN.
fn repair_normals(vertices: &mut [Vertex], world: &[DVec3], triangles: &[[u32; 3]], base: u32) {
    let broken = |v: &Vertex| {
        let n = Vec3::from(v.normal);
        !(n.is_finite() && n.length_squared() > 1e-12)
    };
    if !vertices.iter().any(broken) {
        return;
    }
    let mut sums = vec![Vec3::ZERO; vertices.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| (i - base) as usize);
        // Unnormalized: the cross product's length weights by area.
        let face = ((world[b] - world[a]).cross(world[c] - world[a])).as_vec3();
        for i in [a, b, c] {
            sums[i] += face;
        }
    }
    for (vertex, sum) in vertices.iter_mut().zip(sums) {
        if broken(vertex) {
            vertex.normal = sum.normalize_or(Vec3::Y).to_array();
        }
    }
}

/// MikkTSpace tangents of `triangles` (whose vertices start at `first_vertex`), one per
/// corner in triangle order. Positions are taken relative to the first vertex, so far-out
/// geometry keeps its precision; a corner MikkTSpace cannot give a finite tangent (a triangle
/// without UV area) gets zero, which the shaders read as "no normal map here".
fn mikktspace_corners(
    vertices: &[Vertex],
    world: &[DVec3],
    triangles: &[[u32; 3]],
    first_vertex: usize,
) -> Vec<[f32; 4]> {
    struct Corners<'a> {
        vertices: &'a [Vertex],
        world: &'a [DVec3],
        origin: DVec3,
        triangles: &'a [[u32; 3]],
        out: Vec<[f32; 4]>,
    }
    impl Corners<'_> {
        fn vertex(&self, face: usize, vert: usize) -> usize {
            self.triangles[face][vert] as usize
        }
    }
    impl mikktspace::Geometry for Corners<'_> {
        fn num_faces(&self) -> usize {
            self.triangles.len()
        }
        fn num_vertices_of_face(&self, _face: usize) -> usize {
            3
        }
        fn position(&self, face: usize, vert: usize) -> [f32; 3] {
            (self.world[self.vertex(face, vert)] - self.origin).as_vec3().to_array()
        }
        fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
            self.vertices[self.vertex(face, vert)].normal
        }
        /// glTF's V runs down the image, but its tangent space has +Y up the image (the
        /// bitangent `w · normal × tangent` points up): MikkTSpace is given 1 − V so that its
        /// bitangent, the direction of growing V, points up as well.
        fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
            let [u, v] = self.vertices[self.vertex(face, vert)].uv;
            [u, 1.0 - v]
        }
        fn set_tangent_encoded(&mut self, tangent: [f32; 4], face: usize, vert: usize) {
            self.out[face * 3 + vert] = tangent;
        }
    }
    let mut corners = Corners {
        vertices,
        world,
        origin: world.get(first_vertex).copied().unwrap_or_default(),
        triangles,
        out: vec![[0.0; 4]; triangles.len() * 3],
    };
    // MikkTSpace drops triangles with two equal corners and then underflows (an unchecked
    // usize loop bound; out-of-bounds reads in release) when none is left: a primitive that
    // is all slivers, or one under a node scaled to zero to hide it, gets zero tangents.
    let proper = |t: &[u32; 3]| {
        let p = t.map(|i| (world[i as usize] - corners.origin).as_vec3());
        p[0] != p[1] && p[0] != p[2] && p[1] != p[2]
    };
    if triangles.iter().any(proper) {
        mikktspace::generate_tangents(&mut corners);
    }
    corners.out.into_iter().map(|t| if t.iter().all(|c| c.is_finite()) { t } else { [0.0; 4] }).collect()
}

/// A `KHR_lights_punctual` light placed by its node: at the node's origin, shining along its
/// −Z. Every value is checked: a light the renderer cannot draw is an error, never dropped.
fn light_from_node(light: &gltf::khr_lights_punctual::Light, world: DMat4) -> Result<(Light, DVec3), String> {
    use gltf::khr_lights_punctual::Kind;
    let what = format!("KHR_lights_punctual light {}", light.index());
    // A directional light has no position (one far out would not even fit an f32).
    let position = match light.kind() {
        Kind::Directional => DVec3::ZERO,
        _ => world.transform_point3(DVec3::ZERO),
    };
    let direction = world.transform_vector3(-DVec3::Z).normalize_or_zero().as_vec3();
    if direction == glam::Vec3::ZERO && !matches!(light.kind(), Kind::Point) {
        return Err(format!("{what}: the node's transform collapses the light's direction"));
    }
    let kind = match light.kind() {
        Kind::Point => LightKind::Point,
        Kind::Directional => LightKind::Directional { direction },
        Kind::Spot { inner_cone_angle, outer_cone_angle } => {
            let quarter = std::f32::consts::FRAC_PI_2;
            let valid = (0.0..outer_cone_angle).contains(&inner_cone_angle)
                && (..=quarter).contains(&outer_cone_angle);
            if !valid {
                return Err(format!(
                    "{what}: cone angles {inner_cone_angle} and {outer_cone_angle} must satisfy 0 ≤ inner < outer ≤ π/2"
                ));
            }
            LightKind::Spot { direction, inner: inner_cone_angle, outer: outer_cone_angle }
        }
    };
    super::check_light(position, light.color(), light.intensity(), light.range())
        .map_err(|(field, why)| format!("{what}: {field}: {why}"))?;
    let (color, intensity) = (glam::Vec3::from(light.color()), light.intensity());
    let range = light.range().unwrap_or(f32::INFINITY);
    Ok((Light { kind, position: glam::Vec3::ZERO, color, intensity, range, shadow: None }, position))
}

/// The camera of a node, if perspective (orthographic cameras are skipped). Read from the
/// JSON: `gltf::Camera::projection` panics when the object its `type` names is missing.
fn camera_from_node(document: &gltf::Document, index: usize, world: DMat4) -> Result<Option<Camera>, String> {
    use gltf::json::camera::Type;
    use gltf::json::validation::Checked;
    let json = &document.as_json().cameras[index];
    if json.type_ != Checked::Valid(Type::Perspective) {
        return Ok(None);
    }
    let perspective = json
        .perspective
        .as_ref()
        .ok_or_else(|| format!("cameras[{index}]: type is perspective, but `perspective` is missing"))?;
    Ok(Some(Camera {
        position: world.transform_point3(DVec3::ZERO),
        forward: world.transform_vector3(-DVec3::Z),
        up: world.transform_vector3(DVec3::Y),
        fov_y: f64::from(perspective.yfov),
        near: f64::from(perspective.znear),
        // An infinite far plane gets a finite one from the scene bounds later.
        far: perspective.zfar.map_or(f64::INFINITY, f64::from),
    }))
}

/// The largest texture side decoded (the largest 2D texture Vulkan devices commonly allow);
/// a larger image is refused from its header, before its pixels are read.
pub const MAX_TEXTURE_SIDE: u32 = 16384;

/// Decodes the images that materials use, in parallel: a Sponza-sized scene has
/// dozens of PNG/JPEG files and decoding dominates its load time.
fn decode_textures(
    document: &gltf::Document,
    base: &Path,
    buffers: &[gltf::buffer::Data],
    wanted: &[(usize, Encoding)],
) -> Result<Vec<Texture>, String> {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let chunk = wanted.len().div_ceil(threads).max(1);
    std::thread::scope(|scope| {
        let workers: Vec<_> = wanted
            .chunks(chunk)
            .map(|part| {
                scope.spawn(move || {
                    part.iter()
                        .map(|&(image, encoding)| decode_image(document, image, encoding, base, buffers))
                        .collect::<Result<Vec<_>, _>>()
                })
            })
            .collect();
        let mut textures = Vec::with_capacity(wanted.len());
        for worker in workers {
            textures.extend(worker.join().expect("texture decoder panicked")?);
        }
        Ok(textures)
    })
}

/// Where an image's bytes are.
enum ImageSource<'a> {
    View(gltf::buffer::View<'a>),
    Uri(&'a str),
}

/// An image's source, read from its JSON: `gltf::Image::source` panics on an image with a
/// buffer view but no `mimeType`, or with neither a view nor a URI (gltf 1.4.1). The MIME type
/// is not needed: decoding guesses the format from the bytes.
fn image_source(document: &gltf::Document, index: usize) -> Result<ImageSource<'_>, String> {
    let json = &document.as_json().images[index];
    match (&json.buffer_view, &json.uri) {
        (Some(view), _) => document
            .views()
            .nth(view.value())
            .map(ImageSource::View)
            .ok_or_else(|| format!("images[{index}].bufferView: view {} does not exist", view.value())),
        (None, Some(uri)) => Ok(ImageSource::Uri(uri)),
        (None, None) => Err(format!("images[{index}]: has neither a bufferView nor a uri")),
    }
}

/// One image to RGBA8. Errors name the image and where it comes from.
fn decode_image(
    document: &gltf::Document,
    index: usize,
    encoding: Encoding,
    base: &Path,
    buffers: &[gltf::buffer::Data],
) -> Result<Texture, String> {
    let (bytes, what) = match image_source(document, index)? {
        ImageSource::View(view) => {
            let what = format!("images[{index}] (bufferViews[{}])", view.index());
            let bytes = view_bytes(&view, buffers).map_err(|e| format!("{what}: {e}"))?;
            (std::borrow::Cow::Borrowed(bytes), what)
        }
        ImageSource::Uri(uri) if uri.starts_with("data:") => {
            // Decoded here rather than by the gltf crate, so an embedded image meets the same
            // size check and limits as one in a file.
            let what = format!("images[{index}] (data URI)");
            (std::borrow::Cow::Owned(decode_data_uri(uri).map_err(|e| format!("{what}: {e}"))?), what)
        }
        ImageSource::Uri(uri) => {
            let path = base.join(percent_decode(uri).map_err(|e| format!("images[{index}].uri: {e}"))?);
            let what = format!("images[{index}] (uri {uri})");
            let bytes = std::fs::read(&path).map_err(|e| format!("{what}: {}: {e}", path.display()))?;
            (std::borrow::Cow::Owned(bytes), what)
        }
    };
    if bytes.is_empty() {
        return Err(format!("{what}: the image is empty (0 bytes)"));
    }
    let reader = || {
        image::ImageReader::new(std::io::Cursor::new(&bytes[..]))
            .with_guessed_format()
            .map_err(|e| format!("{what}: {e}"))
    };
    let (width, height) = reader()?.into_dimensions().map_err(|e| format!("{what}: cannot decode: {e}"))?;
    if width > MAX_TEXTURE_SIDE || height > MAX_TEXTURE_SIDE {
        return Err(format!(
            "{what}: {width}×{height} is larger than the {MAX_TEXTURE_SIDE}×{MAX_TEXTURE_SIDE} textures aabench decodes"
        ));
    }
    let mut limits = image::Limits::default();
    // The largest accepted image at 16 bits × 4 channels; the crate's default (512 MiB) would
    // refuse images the renderer handles by scaling them down.
    limits.max_alloc = Some(u64::from(MAX_TEXTURE_SIDE).pow(2) * 8);
    let mut decoder = reader()?;
    decoder.limits(limits);
    let decoded = decoder.decode().map_err(|e| format!("{what}: cannot decode: {e}"))?;
    Ok(Texture { width, height, rgba: decoded.into_rgba8().into_raw(), encoding })
}

/// The bytes of a base64 `data:` URI (`data:[<media type>];base64,<data>`).
fn decode_data_uri(uri: &str) -> Result<Vec<u8>, String> {
    let rest = uri.strip_prefix("data:").unwrap_or(uri);
    let (header, data) = rest.split_once(',').ok_or("no `,` between the media type and the data")?;
    if !header.ends_with(";base64") {
        return Err(format!("`data:{header},…` is not base64; only base64 data URIs are read"));
    }
    base64::decode(data).map_err(|e| format!("bad base64: {e}"))
}
