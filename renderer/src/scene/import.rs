//! glTF 2.0 import through the `gltf` crate: meshes with baked node transforms, base-colour
//! textures and factors, metallic/roughness factors, alpha MASK, UVs and normals (flat normals
//! generated where a primitive has none), and the first camera.

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use glam::{DMat3, DMat4, DVec3, Vec3};

use super::{AlphaMode, Camera, DrawClass, Material, Scene, Texture, Vertex};
use crate::RenderError;

/// Reads a `.gltf` or `.glb` file and everything it references.
pub fn load_gltf(path: &Path) -> Result<Scene, RenderError> {
    let fail = |message: String| RenderError::Scene { path: path.to_path_buf(), message };
    let gltf::Gltf { document, blob } =
        gltf::Gltf::open(path).map_err(|e| fail(format!("cannot read glTF: {e}")))?;
    let base = path.parent().unwrap_or(Path::new("."));
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
    let roots: Vec<gltf::Node> = match document.default_scene().or_else(|| document.scenes().next()) {
        Some(scene) => scene.nodes().collect(),
        None => document.nodes().collect(),
    };
    for node in roots {
        importer.visit(&node, DMat4::IDENTITY, &buffers).map_err(fail)?;
    }

    let mut scene = importer.finish();
    scene.textures = decode_textures(&document, base, &buffers, &image_of_texture)
        .map_err(|e| fail(format!("cannot decode texture: {e}")))?;
    for material in &mut scene.materials {
        material.texture = material.texture.map(|image| image_of_texture[&image]);
    }
    scene.generator = document.as_json().asset.generator.clone();
    Ok(scene)
}

/// The `asset.generator` string of a glTF file, if it can be read.
pub fn read_generator(path: &Path) -> Option<String> {
    let gltf = gltf::Gltf::open(path).ok()?;
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

#[derive(Default)]
struct Importer {
    scene: Scene,
    /// Triangles as vertex-index triples, by draw class.
    triangles: BTreeMap<DrawClass, Vec<[u32; 3]>>,
}

impl Importer {
    fn visit(
        &mut self,
        node: &gltf::Node,
        parent: DMat4,
        buffers: &[gltf::buffer::Data],
    ) -> Result<(), String> {
        let local = DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from)));
        let world = parent * local;
        if let Some(mesh) = node.mesh() {
            for primitive in mesh.primitives() {
                self.add_primitive(&mesh, &primitive, world, buffers)?;
            }
        }
        if let (Some(camera), None) = (node.camera(), &self.scene.camera) {
            self.scene.camera = camera_from_node(&camera, world);
        }
        for child in node.children() {
            self.visit(&child, world, buffers)?;
        }
        Ok(())
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
        let reader = primitive.reader(|buffer| buffers.get(buffer.index()).map(|d| &d.0[..]));
        let positions: Vec<[f32; 3]> = reader
            .read_positions()
            .ok_or_else(|| format!("{}: attributes.POSITION is missing", name()))?
            .collect();
        let uvs: Vec<[f32; 2]> = match reader.read_tex_coords(0) {
            Some(uvs) => uvs.into_f32().collect(),
            None => vec![[0.0; 2]; positions.len()],
        };
        let normals: Option<Vec<[f32; 3]>> = reader.read_normals().map(Iterator::collect);
        let indices: Vec<u32> = match reader.read_indices() {
            Some(indices) => indices.into_u32().collect(),
            None => (0..positions.len() as u32).collect(),
        };
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
        let to_world = |p: [f32; 3]| world.transform_point3(DVec3::from(p.map(f64::from))).as_vec3();
        let vertex = |position: Vec3, normal: Vec3, uv: [f32; 2]| Vertex {
            position: position.to_array(),
            normal: normal.to_array(),
            uv,
            material: material as u32,
        };
        let vertices = &mut self.scene.vertices;
        let triangles = self.triangles.entry(class).or_default();
        let wind = |t: &[u32]| if mirrored { [t[0], t[2], t[1]] } else { [t[0], t[1], t[2]] };

        match normals {
            Some(normals) => {
                let base = vertices.len() as u32;
                for ((p, n), uv) in positions.iter().zip(&normals).zip(&uvs) {
                    let n = (normal_matrix * DVec3::from(n.map(f64::from))).normalize_or_zero();
                    vertices.push(vertex(to_world(*p), n.as_vec3(), *uv));
                }
                let added: Vec<[u32; 3]> =
                    indices.chunks_exact(3).map(|t| wind(t).map(|i| base + i)).collect();
                repair_normals(&mut vertices[base as usize..], &added, base);
                triangles.extend(added);
            }
            None => {
                // Flat normals: every triangle gets its own three vertices.
                for t in indices.chunks_exact(3) {
                    let corners = wind(t).map(|i| (to_world(positions[i as usize]), uvs[i as usize]));
                    let normal =
                        (corners[1].0 - corners[0].0).cross(corners[2].0 - corners[0].0).normalize_or_zero();
                    let base = vertices.len() as u32;
                    for (position, uv) in corners {
                        vertices.push(vertex(position, normal, uv));
                    }
                    triangles.push([base, base + 1, base + 2]);
                }
            }
        }
        Ok(())
    }

    fn finish(mut self) -> Scene {
        for (class, triangles) in self.triangles {
            let start = self.scene.indices.len() as u32;
            self.scene.indices.extend(triangles.into_iter().flatten());
            self.scene.draws.push((class, start..self.scene.indices.len() as u32));
        }
        self.scene
    }
}

/// Replaces zero or non-finite vertex normals (which files do contain) with the area-weighted
/// normal of the primitive's triangles around the vertex, so shaders can normalize without NaN.
fn repair_normals(vertices: &mut [Vertex], triangles: &[[u32; 3]], base: u32) {
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
        let p = |i: usize| Vec3::from(vertices[i].position);
        // Unnormalized: the cross product's length weights by area.
        let face = (p(b) - p(a)).cross(p(c) - p(a));
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

fn camera_from_node(camera: &gltf::Camera, world: DMat4) -> Option<Camera> {
    let gltf::camera::Projection::Perspective(perspective) = camera.projection() else {
        return None;
    };
    Some(Camera {
        position: world.transform_point3(DVec3::ZERO),
        forward: world.transform_vector3(-DVec3::Z),
        up: world.transform_vector3(DVec3::Y),
        fov_y: f64::from(perspective.yfov()),
        near: f64::from(perspective.znear()),
        // An infinite far plane gets a finite one from the scene bounds later.
        far: perspective.zfar().map_or(f64::INFINITY, f64::from),
    })
}

/// Decodes the images used as base-colour textures, in parallel: a Sponza-sized scene has
/// dozens of PNG/JPEG files and decoding dominates its load time.
fn decode_textures(
    document: &gltf::Document,
    base: &Path,
    buffers: &[gltf::buffer::Data],
    image_of_texture: &HashMap<usize, usize>,
) -> Result<Vec<Texture>, gltf::Error> {
    let images: Vec<gltf::Image> = document.images().collect();
    let mut wanted: Vec<(usize, usize)> = image_of_texture.iter().map(|(&i, &t)| (i, t)).collect();
    wanted.sort_by_key(|&(_, texture)| texture);
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let chunk = wanted.len().div_ceil(threads).max(1);
    std::thread::scope(|scope| {
        let workers: Vec<_> = wanted
            .chunks(chunk)
            .map(|part| {
                let images = &images;
                scope.spawn(move || {
                    part.iter()
                        .map(|&(image, _)| {
                            gltf::image::Data::from_source(images[image].source(), Some(base), buffers)
                                .map(to_rgba8)
                        })
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

fn to_rgba8(data: gltf::image::Data) -> Texture {
    use gltf::image::Format;
    let (channels, bytes) = match data.format {
        Format::R8 => (1, 1),
        Format::R8G8 => (2, 1),
        Format::R8G8B8 => (3, 1),
        Format::R8G8B8A8 => (4, 1),
        Format::R16 => (1, 2),
        Format::R16G16 => (2, 2),
        Format::R16G16B16 => (3, 2),
        Format::R16G16B16A16 => (4, 2),
        Format::R32G32B32FLOAT => (3, 4),
        Format::R32G32B32A32FLOAT => (4, 4),
    };
    // 16-bit channels keep their high byte (little-endian), float channels are clamped.
    let byte = |texel: &[u8], c: usize| match bytes {
        1 => texel[c],
        2 => texel[2 * c + 1],
        _ => {
            let v = f32::from_le_bytes(texel[4 * c..4 * c + 4].try_into().expect("4 bytes"));
            (v.clamp(0.0, 1.0) * 255.0).round() as u8
        }
    };
    let rgba = data
        .pixels
        .chunks_exact(channels * bytes)
        .flat_map(|t| match channels {
            1 => [byte(t, 0), byte(t, 0), byte(t, 0), 255],
            2 => [byte(t, 0), byte(t, 0), byte(t, 0), byte(t, 1)],
            3 => [byte(t, 0), byte(t, 1), byte(t, 2), 255],
            _ => [byte(t, 0), byte(t, 1), byte(t, 2), byte(t, 3)],
        })
        .collect();
    Texture { width: data.width, height: data.height, rgba }
}
