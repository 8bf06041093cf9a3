//! Writing glTF 2.0 binary (GLB) files: the procedural generator's output format.

use std::io::Write;
use std::path::Path;

use glam::{DMat3, DQuat, DVec3};
use serde_json::{Value, json};

/// Triangle-list geometry with per-vertex normals and UVs.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MeshData {
    pub positions: Vec<[f32; 3]>,
    pub normals: Vec<[f32; 3]>,
    pub uvs: Vec<[f32; 2]>,
    pub indices: Vec<u32>,
}

impl MeshData {
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Winds every triangle counter-clockwise about its vertex normals, as glTF expects of
    /// front faces, so builders need not get each primitive's index order right by hand.
    pub fn orient_to_normals(&mut self) {
        let p = |i: u32| glam::Vec3::from(self.positions[i as usize]);
        let n = |i: u32| glam::Vec3::from(self.normals[i as usize]);
        for triangle in self.indices.chunks_exact_mut(3) {
            let [a, b, c] = [triangle[0], triangle[1], triangle[2]];
            let face = (p(b) - p(a)).cross(p(c) - p(a));
            if face.dot(n(a) + n(b) + n(c)) < 0.0 {
                triangle.swap(1, 2);
            }
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct MaterialDesc {
    pub name: String,
    pub base_color: [f32; 4],
    pub metallic: f32,
    pub roughness: f32,
    /// A texture index returned by [`GltfWriter::add_png`].
    pub texture: Option<usize>,
    /// A tangent-space normal map (a texture index); tangents are left to the reader.
    pub normal_texture: Option<usize>,
    /// Some(cutoff) makes the material alpha-MASKed.
    pub alpha_cutoff: Option<f32>,
    /// Seen from both sides (no back-face culling), e.g. cloth and foliage cards.
    pub double_sided: bool,
}

impl MaterialDesc {
    pub fn new(name: &str, base_color: [f32; 3], roughness: f32) -> MaterialDesc {
        MaterialDesc {
            name: name.to_string(),
            base_color: [base_color[0], base_color[1], base_color[2], 1.0],
            metallic: 0.0,
            roughness,
            texture: None,
            normal_texture: None,
            alpha_cutoff: None,
            double_sided: false,
        }
    }

    pub fn textured(self, texture: usize) -> MaterialDesc {
        MaterialDesc { texture: Some(texture), ..self }
    }

    pub fn normal_mapped(self, texture: usize) -> MaterialDesc {
        MaterialDesc { normal_texture: Some(texture), ..self }
    }

    pub fn metallic(self, metallic: f32) -> MaterialDesc {
        MaterialDesc { metallic, ..self }
    }

    pub fn masked(self, cutoff: f32) -> MaterialDesc {
        MaterialDesc { alpha_cutoff: Some(cutoff), ..self }
    }

    pub fn double_sided(self) -> MaterialDesc {
        MaterialDesc { double_sided: true, ..self }
    }
}

/// A skin for [`GltfWriter::add_skinned_mesh`]: its joints (nodes added before), their
/// inverse bind matrices (column-major), and each vertex's four joints (indices into `joints`)
/// with their weights.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SkinDesc {
    pub joints: Vec<usize>,
    pub inverse_binds: Vec<[f32; 16]>,
    pub vertex_joints: Vec<[u16; 4]>,
    pub vertex_weights: Vec<[f32; 4]>,
}

/// One channel of an animation: a node's `translation`, `rotation` (quaternions xyzw) or
/// `scale` at `times` (seconds), its values flattened.
#[derive(Debug, Clone, PartialEq)]
pub struct Channel {
    pub node: usize,
    pub path: &'static str,
    pub times: Vec<f32>,
    pub values: Vec<f32>,
}

/// Collects meshes, materials, PNG textures and a camera, and writes them as one GLB file.
#[derive(Debug, Clone)]
pub struct GltfWriter {
    generator: String,
    bin: Vec<u8>,
    buffer_views: Vec<Value>,
    accessors: Vec<Value>,
    images: Vec<Value>,
    textures: Vec<Value>,
    materials: Vec<Value>,
    meshes: Vec<Value>,
    nodes: Vec<Value>,
    cameras: Vec<Value>,
    /// `KHR_lights_punctual` lights.
    lights: Vec<Value>,
    animations: Vec<Value>,
    skins: Vec<Value>,
    /// A root node's uniform scale and translation over every node, if any.
    placement: Option<(f64, [f64; 3])>,
}

const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;
const UNSIGNED_SHORT: u32 = 5123;
const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;

impl GltfWriter {
    /// `generator` goes into `asset.generator`; the runner compares it to tell stale files.
    pub fn new(generator: &str) -> GltfWriter {
        GltfWriter {
            generator: generator.to_string(),
            bin: Vec::new(),
            buffer_views: Vec::new(),
            accessors: Vec::new(),
            images: Vec::new(),
            textures: Vec::new(),
            materials: Vec::new(),
            meshes: Vec::new(),
            nodes: Vec::new(),
            cameras: Vec::new(),
            lights: Vec::new(),
            animations: Vec::new(),
            skins: Vec::new(),
            placement: None,
        }
    }

    fn add_view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let mut view = json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()});
        if let Some(target) = target {
            view["target"] = json!(target);
        }
        self.bin.extend_from_slice(bytes);
        self.buffer_views.push(view);
        self.buffer_views.len() - 1
    }

    fn add_accessor(&mut self, bytes: &[u8], target: u32, accessor: Value) -> usize {
        let view = self.add_view(bytes, Some(target));
        let mut accessor = accessor;
        accessor["bufferView"] = json!(view);
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    /// Embeds a PNG image and returns its texture index.
    pub fn add_png(&mut self, name: &str, png: &[u8]) -> usize {
        let view = self.add_view(png, None);
        self.images.push(json!({"name": name, "bufferView": view, "mimeType": "image/png"}));
        self.textures.push(json!({"source": self.images.len() - 1, "sampler": 0}));
        self.textures.len() - 1
    }

    pub fn add_material(&mut self, material: &MaterialDesc) -> usize {
        let mut pbr = json!({
            "baseColorFactor": material.base_color,
            "metallicFactor": material.metallic,
            "roughnessFactor": material.roughness,
        });
        if let Some(texture) = material.texture {
            pbr["baseColorTexture"] = json!({"index": texture});
        }
        let mut value =
            json!({"name": material.name, "pbrMetallicRoughness": pbr, "doubleSided": material.double_sided});
        if let Some(texture) = material.normal_texture {
            value["normalTexture"] = json!({"index": texture});
        }
        if let Some(cutoff) = material.alpha_cutoff {
            value["alphaMode"] = json!("MASK");
            value["alphaCutoff"] = json!(cutoff);
        }
        self.materials.push(value);
        self.materials.len() - 1
    }

    /// Adds a mesh as a node of the scene, in world space, and returns the node. Empty meshes
    /// are skipped.
    pub fn add_mesh(&mut self, name: &str, mesh: &MeshData, material: usize) -> Option<usize> {
        if mesh.indices.is_empty() {
            return None;
        }
        let primitive = self.add_primitive(mesh, material);
        self.meshes.push(json!({"name": name, "primitives": [primitive]}));
        self.nodes.push(json!({"name": name, "mesh": self.meshes.len() - 1}));
        Some(self.nodes.len() - 1)
    }

    /// Adds a mesh that `skin` carries (its vertices in the skeleton's bind pose) as a node
    /// of the scene, and returns the node. Empty meshes are skipped.
    pub fn add_skinned_mesh(
        &mut self,
        name: &str,
        mesh: &MeshData,
        material: usize,
        skin: &SkinDesc,
    ) -> Option<usize> {
        if mesh.indices.is_empty() {
            return None;
        }
        let count = mesh.positions.len();
        let mut primitive = self.add_primitive(mesh, material);
        let joints = self.add_accessor(
            bytemuck::cast_slice(&skin.vertex_joints),
            ARRAY_BUFFER,
            json!({"componentType": UNSIGNED_SHORT, "count": count, "type": "VEC4"}),
        );
        let weights = self.add_accessor(
            bytemuck::cast_slice(&skin.vertex_weights),
            ARRAY_BUFFER,
            json!({"componentType": FLOAT, "count": count, "type": "VEC4"}),
        );
        primitive["attributes"]["JOINTS_0"] = json!(joints);
        primitive["attributes"]["WEIGHTS_0"] = json!(weights);
        let inverse_binds = self.add_data(
            bytemuck::cast_slice(&skin.inverse_binds),
            json!({"componentType": FLOAT, "count": skin.inverse_binds.len(), "type": "MAT4"}),
        );
        self.skins.push(json!({"joints": skin.joints, "inverseBindMatrices": inverse_binds}));
        self.meshes.push(json!({"name": name, "primitives": [primitive]}));
        self.nodes.push(json!({"name": name, "mesh": self.meshes.len() - 1, "skin": self.skins.len() - 1}));
        Some(self.nodes.len() - 1)
    }

    /// Adds a node at `translation` in its parent that holds `children` (nodes added before,
    /// which stop being roots): a joint of a skeleton. Returns it.
    pub fn add_joint(&mut self, name: &str, translation: [f32; 3], children: &[usize]) -> usize {
        self.nodes.push(json!({"name": name, "translation": translation, "children": children}));
        self.nodes.len() - 1
    }

    /// A mesh's triangle primitive (its accessors added, triangles wound to its normals).
    fn add_primitive(&mut self, mesh: &MeshData, material: usize) -> Value {
        let mut mesh = mesh.clone();
        mesh.orient_to_normals();
        let (min, max) =
            mesh.positions.iter().fold(([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]), |(lo, hi), p| {
                (std::array::from_fn(|i| lo[i].min(p[i])), std::array::from_fn(|i| hi[i].max(p[i])))
            });
        let count = mesh.positions.len();
        let position = self.add_accessor(
            bytemuck::cast_slice(&mesh.positions),
            ARRAY_BUFFER,
            json!({"componentType": FLOAT, "count": count, "type": "VEC3", "min": min, "max": max}),
        );
        let normal = self.add_accessor(
            bytemuck::cast_slice(&mesh.normals),
            ARRAY_BUFFER,
            json!({"componentType": FLOAT, "count": count, "type": "VEC3"}),
        );
        let uv = self.add_accessor(
            bytemuck::cast_slice(&mesh.uvs),
            ARRAY_BUFFER,
            json!({"componentType": FLOAT, "count": count, "type": "VEC2"}),
        );
        let indices = self.add_accessor(
            bytemuck::cast_slice(&mesh.indices),
            ELEMENT_ARRAY_BUFFER,
            json!({"componentType": UNSIGNED_INT, "count": mesh.indices.len(), "type": "SCALAR"}),
        );
        json!({
            "attributes": {"POSITION": position, "NORMAL": normal, "TEXCOORD_0": uv},
            "indices": indices,
            "material": material,
        })
    }

    /// Adds a node that holds `children` (nodes added before, which stop being roots) and returns
    /// it.
    pub fn add_group(&mut self, name: &str, children: &[usize]) -> usize {
        self.nodes.push(json!({"name": name, "children": children}));
        self.nodes.len() - 1
    }

    /// Adds an animation that moves `node` through `translations` at `times` (seconds),
    /// linearly.
    pub fn add_translation_animation(
        &mut self,
        name: &str,
        node: usize,
        times: &[f32],
        translations: &[[f32; 3]],
    ) {
        let values = translations.iter().flatten().copied().collect();
        self.add_animation(name, &[Channel { node, path: "translation", times: times.to_vec(), values }]);
    }

    /// Adds an animation of `channels`, each interpolated linearly (rotations spherically).
    pub fn add_animation(&mut self, name: &str, channels: &[Channel]) {
        let (mut targets, mut samplers) = (Vec::new(), Vec::new());
        for (sampler, channel) in channels.iter().enumerate() {
            let times = &channel.times;
            let (first, last) = (times.first().copied().unwrap_or(0.0), times.last().copied().unwrap_or(0.0));
            let input = self.add_data(
                bytemuck::cast_slice(times),
                json!({"componentType": FLOAT, "count": times.len(), "type": "SCALAR", "min": [first], "max": [last]}),
            );
            let (kind, width) = if channel.path == "rotation" { ("VEC4", 4) } else { ("VEC3", 3) };
            let output = self.add_data(
                bytemuck::cast_slice(&channel.values),
                json!({"componentType": FLOAT, "count": channel.values.len() / width, "type": kind}),
            );
            targets.push(json!({"sampler": sampler, "target": {"node": channel.node, "path": channel.path}}));
            samplers.push(json!({"input": input, "output": output, "interpolation": "LINEAR"}));
        }
        self.animations.push(json!({"name": name, "channels": targets, "samplers": samplers}));
    }

    /// An accessor of data that no vertex stage reads (its view has no target).
    fn add_data(&mut self, bytes: &[u8], accessor: Value) -> usize {
        let view = self.add_view(bytes, None);
        let mut accessor = accessor;
        accessor["bufferView"] = json!(view);
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    /// Adds a perspective camera at `position` looking at `target`, +Y up.
    pub fn add_camera(&mut self, position: DVec3, target: DVec3, fov_y_degrees: f64, near: f64, far: f64) {
        // A glTF camera looks down its local −Z with +Y up.
        let back = (position - target).normalize();
        let right = DVec3::Y.cross(back).normalize();
        let up = back.cross(right);
        let rotation = DQuat::from_mat3(&DMat3::from_cols(right, up, back));
        self.cameras.push(json!({
            "type": "perspective",
            "perspective": {"yfov": fov_y_degrees.to_radians(), "znear": near, "zfar": far},
        }));
        self.nodes.push(json!({
            "name": "camera",
            "camera": self.cameras.len() - 1,
            "translation": position.to_array(),
            "rotation": rotation.to_array(),
        }));
    }

    /// Adds a `KHR_lights_punctual` point light (intensity in candela) at `position`.
    pub fn add_point_light(&mut self, position: [f64; 3], color: [f32; 3], intensity: f32, range: f32) {
        self.lights.push(json!({"type": "point", "color": color, "intensity": intensity, "range": range}));
        self.nodes.push(json!({
            "name": "light",
            "translation": position,
            "extensions": {"KHR_lights_punctual": {"light": self.lights.len() - 1}},
        }));
    }

    /// Adds a `KHR_lights_punctual` directional light (intensity in lux) shining along
    /// `direction`, which the node's rotation turns the light's −Z onto.
    pub fn add_directional_light(&mut self, direction: DVec3, color: [f32; 3], intensity: f32) {
        self.lights.push(json!({"type": "directional", "color": color, "intensity": intensity}));
        let rotation = glam::DQuat::from_rotation_arc(DVec3::NEG_Z, direction.normalize());
        self.nodes.push(json!({
            "name": "sun",
            "rotation": rotation.to_array(),
            "extensions": {"KHR_lights_punctual": {"light": self.lights.len() - 1}},
        }));
    }

    /// Puts every node under one root node that scales by `scale` and then moves by
    /// `translation`; the geometry keeps its coordinates.
    pub fn place(&mut self, scale: f64, translation: [f64; 3]) {
        self.placement = Some((scale, translation));
    }

    fn document(&self) -> Value {
        let mut nodes = self.nodes.clone();
        // Every node that is nobody's child.
        let held: Vec<u64> = nodes
            .iter()
            .flat_map(|n| n["children"].as_array().cloned().unwrap_or_default())
            .filter_map(|c| c.as_u64())
            .collect();
        let tops: Vec<usize> = (0..nodes.len()).filter(|i| !held.contains(&(*i as u64))).collect();
        let roots: Vec<usize> = match self.placement {
            None => tops,
            Some((scale, translation)) => {
                let children = tops;
                nodes.push(json!({
                    "name": "placement",
                    "children": children,
                    "scale": [scale, scale, scale],
                    "translation": translation,
                }));
                vec![nodes.len() - 1]
            }
        };
        let mut document = json!({
            "asset": {"version": "2.0", "generator": self.generator},
            "scene": 0,
            "scenes": [{"nodes": roots}],
            "nodes": nodes,
            "meshes": self.meshes,
            "materials": self.materials,
            "accessors": self.accessors,
            "bufferViews": self.buffer_views,
            "buffers": [{"byteLength": self.bin.len()}],
        });
        if !self.textures.is_empty() {
            document["images"] = json!(self.images);
            document["textures"] = json!(self.textures);
            // Linear mag, trilinear min, repeat.
            document["samplers"] =
                json!([{"magFilter": 9729, "minFilter": 9987, "wrapS": 10497, "wrapT": 10497}]);
        }
        if !self.animations.is_empty() {
            document["animations"] = json!(self.animations);
        }
        if !self.skins.is_empty() {
            document["skins"] = json!(self.skins);
        }
        if !self.lights.is_empty() {
            document["extensionsUsed"] = json!(["KHR_lights_punctual"]);
            document["extensions"] = json!({"KHR_lights_punctual": {"lights": self.lights}});
        }
        if !self.cameras.is_empty() {
            let mut cameras = self.cameras.clone();
            // Clip planes are distances in the camera's space, which the root's scale does
            // not reach: scale them with the scene.
            if let Some((scale, _)) = self.placement {
                for camera in &mut cameras {
                    for plane in ["znear", "zfar"] {
                        let distance = camera["perspective"][plane].as_f64().unwrap_or(0.0);
                        camera["perspective"][plane] = json!(distance * scale);
                    }
                }
            }
            document["cameras"] = json!(cameras);
        }
        document
    }

    /// The scene as GLB.
    pub fn to_glb(&self) -> Vec<u8> {
        glb(&self.document(), &self.bin)
    }

    /// Writes the GLB atomically: a reader never sees half a file.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        write_atomic(path, &self.to_glb())
    }
}

/// The GLB container of a document and its binary buffer: a 12-byte header, the JSON chunk and
/// the binary chunk, each padded to four bytes (JSON with spaces, binary with zeros).
pub fn glb(document: &Value, bin: &[u8]) -> Vec<u8> {
    let mut json = serde_json::to_vec(document).expect("JSON of plain values");
    json.resize(json.len().next_multiple_of(4), b' ');
    let mut bin = bin.to_vec();
    bin.resize(bin.len().next_multiple_of(4), 0);
    let length = 12 + 8 + json.len() + 8 + bin.len();
    let mut glb = Vec::with_capacity(length);
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&(length as u32).to_le_bytes());
    for (kind, chunk) in [(b"JSON", &json), (b"BIN\0", &bin)] {
        glb.extend_from_slice(&(chunk.len() as u32).to_le_bytes());
        glb.extend_from_slice(kind);
        glb.extend_from_slice(chunk);
    }
    glb
}

/// Writes `bytes` to a temporary file beside `path`, then renames it into place.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent)?;
    }
    let mut temporary = path.as_os_str().to_owned();
    temporary.push(format!(".tmp-{}", std::process::id()));
    let temporary = std::path::PathBuf::from(temporary);
    let result = std::fs::File::create(&temporary).and_then(|mut file| {
        file.write_all(bytes)?;
        file.sync_all()
    });
    match result.and_then(|()| std::fs::rename(&temporary, path)) {
        Ok(()) => Ok(()),
        Err(error) => {
            let _ = std::fs::remove_file(&temporary);
            Err(error)
        }
    }
}
