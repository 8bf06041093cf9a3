//! glTF 2.0 import through the `gltf` crate: meshes with baked node transforms, base-colour
//! textures and factors, metallic/roughness factors, alpha MASK, UVs and normals (flat normals
//! generated where a primitive has none), the first camera, and `KHR_lights_punctual` lights.

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

use glam::{DMat3, DMat4, DVec3, Vec3};

use super::{AlphaMode, Camera, DrawClass, Light, LightKind, Material, Scene, Texture, Vertex};
use crate::RenderError;

/// Reads a `.gltf` or `.glb` file and everything it references. Every error names the part of
/// the file at fault (`nodes[3]`, `accessors[2]`, `images[0] (uri textures/a.png)`, …).
pub fn load_gltf(path: &Path) -> Result<Scene, RenderError> {
    let fail = |message: String| RenderError::Scene { path: path.to_path_buf(), message };
    regular_file(path).map_err(|e| fail(format!("cannot read glTF: {e}")))?;
    let gltf::Gltf { document, blob } = open(path).map_err(|e| fail(format!("cannot read glTF: {e}")))?;
    let base = path.parent().unwrap_or(Path::new("."));
    check_external_files(&document, base).map_err(fail)?;
    let buffers = gltf::import_buffers(&document, Some(base), blob)
        .map_err(|e| fail(format!("cannot read buffers: {e}")))?;

    let mut importer = Importer::default();
    let (materials, image_of_texture) = import_materials(&document);
    if materials.len() > crate::passes::gbuffer::MAX_MATERIALS {
        return Err(fail(format!(
            "materials: {} materials, the G-buffer holds at most {}",
            materials.len() - 1,
            crate::passes::gbuffer::MAX_MATERIALS - 1
        )));
    }
    importer.scene.materials = materials;
    importer.visit_scene(&document, &buffers).map_err(fail)?;

    let mut scene = importer.finish();
    scene.textures = decode_textures(&document, base, &buffers, &image_of_texture).map_err(fail)?;
    for material in &mut scene.materials {
        material.texture = material.texture.map(|image| image_of_texture[&image]);
    }
    scene.generator = document.as_json().asset.generator.clone();
    scene.warnings = ignored_extensions(&document);
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
/// stays inside the file's folder, and names a regular file that exists.
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
        if escapes(&relative) {
            return Err(format!("{what}.uri: `{uri}` leaves the glTF file's folder"));
        }
        regular_file(&base.join(&relative)).map_err(|e| format!("{what}.uri: {e}"))?;
    }
    Ok(())
}

/// Whether a relative path leaves the folder it is relative to: absolute, or more `..` than
/// folders before them (judged on the text, as a URI is).
pub fn escapes(path: &Path) -> bool {
    use std::path::Component;
    let mut depth = 0i64;
    for component in path.components() {
        match component {
            Component::Prefix(_) | Component::RootDir => return true,
            Component::ParentDir => depth -= 1,
            Component::Normal(_) => depth += 1,
            Component::CurDir => {}
        }
        if depth < 0 {
            return true;
        }
    }
    false
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

/// Reads and validates a glTF or GLB file. The gltf crate's validation (gltf-json 1.4.1) looks
/// up each primitive's POSITION accessor before checking that it exists, and panics when it
/// does not; that one reference is checked here first.
fn open(path: &Path) -> Result<gltf::Gltf, String> {
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
    let json = document.into_json();
    // Before the crate's validation, which refuses required extensions it was not built with
    // in words that do not say what aabench reads.
    if let Some(unknown) = json.extensions_required.iter().find(|e| !EXTENSIONS.contains(&e.as_str())) {
        return Err(format!(
            "extensionsRequired: the file requires `{unknown}`, which aabench does not support (it reads {})",
            EXTENSIONS.join(", ")
        ));
    }
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
        }
    }
    let document = gltf::Document::from_json(json).map_err(|e| e.to_string())?;
    Ok(gltf::Gltf { document, blob })
}

/// The glTF extensions the importer reads. A file may require only these; others it merely
/// uses are ignored with a warning each.
pub const EXTENSIONS: [&str; 1] = ["KHR_lights_punctual"];

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
    let gltf = open(path).ok()?;
    gltf.document.as_json().asset.generator.clone()
}

/// Materials in file order plus one default at the end for primitives without a material.
/// `Material::texture` holds the *image* index until the images are decoded; the returned map
/// sends each used image index to its place in `Scene::textures`.
fn import_materials(document: &gltf::Document) -> (Vec<Material>, HashMap<usize, usize>) {
    let mut image_of_texture = HashMap::new();
    let mut materials: Vec<Material> = document
        .materials()
        .map(|material| {
            let pbr = material.pbr_metallic_roughness();
            let image = pbr.base_color_texture().map(|info| info.texture().source().index());
            if let Some(image) = image {
                let next = image_of_texture.len();
                image_of_texture.entry(image).or_insert(next);
            }
            Material {
                name: material.name().unwrap_or("").to_string(),
                base_color: pbr.base_color_factor(),
                metallic: pbr.metallic_factor(),
                roughness: pbr.roughness_factor(),
                texture: image,
                alpha: match material.alpha_mode() {
                    gltf::material::AlphaMode::Mask => {
                        AlphaMode::Mask { cutoff: material.alpha_cutoff().unwrap_or(0.5) }
                    }
                    _ => AlphaMode::Opaque,
                },
                double_sided: material.double_sided(),
            }
        })
        .collect();
    materials.push(Material {
        name: "default".into(),
        base_color: [0.8, 0.8, 0.8, 1.0],
        metallic: 0.0,
        roughness: 0.6,
        texture: None,
        alpha: AlphaMode::Opaque,
        double_sided: false,
    });
    (materials, image_of_texture)
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
        if uvs.len() != positions.len() || normals.as_ref().is_some_and(|n| n.len() != positions.len()) {
            return Err(format!("{}: attribute counts differ from POSITION", name()));
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
        Ok(())
    }

    /// Sorts the triangles by draw class and makes positions relative to the scene's origin:
    /// the centre of its bounds, rounded to a multiple of [`ORIGIN_GRID`] units, so geometry
    /// far from the file's origin keeps f32 precision (and a scene near it keeps its bits).
    fn finish(mut self) -> Scene {
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

/// Decodes the images used as base-colour textures, in parallel: a Sponza-sized scene has
/// dozens of PNG/JPEG files and decoding dominates its load time.
fn decode_textures(
    document: &gltf::Document,
    base: &Path,
    buffers: &[gltf::buffer::Data],
    image_of_texture: &HashMap<usize, usize>,
) -> Result<Vec<Texture>, String> {
    let mut wanted: Vec<(usize, usize)> = image_of_texture.iter().map(|(&i, &t)| (i, t)).collect();
    wanted.sort_by_key(|&(_, texture)| texture);
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let chunk = wanted.len().div_ceil(threads).max(1);
    std::thread::scope(|scope| {
        let workers: Vec<_> = wanted
            .chunks(chunk)
            .map(|part| {
                scope.spawn(move || {
                    part.iter()
                        .map(|&(image, _)| decode_image(document, image, base, buffers))
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
    Ok(Texture { width, height, rgba: decoded.into_rgba8().into_raw() })
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
