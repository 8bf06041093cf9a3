//! Triangle primitives: their accessors checked, their vertices moved to world space, their
//! normals read, repaired or made flat.

use glam::{DMat3, DMat4, DVec3, Vec3};

use super::Importer;
use crate::scene::skin::Influence;
use crate::scene::{DrawClass, Vertex};

/// Where a primitive's vertices go from its mesh's space: all by its node's world transform,
/// or each by the blend of its joints at rest, with the influences the skin keeps.
#[derive(Clone, Copy)]
pub(super) enum Placement<'a> {
    Node(DMat4),
    Skinned { blends: &'a [DMat4], influences: &'a [Influence] },
}

impl Placement<'_> {
    /// The transform of the primitive's vertex `v`.
    fn matrix(&self, v: usize) -> DMat4 {
        match self {
            Placement::Node(world) => *world,
            Placement::Skinned { blends, .. } => blends[v],
        }
    }

    /// The influences of vertex `v`, where the primitive is skinned.
    fn influence(&self, v: usize) -> Option<Influence> {
        match self {
            Placement::Node(_) => None,
            Placement::Skinned { influences, .. } => Some(influences[v]),
        }
    }

    /// Whether the placement mirrors the primitive, reversing its winding: a skin does as its
    /// first vertex's blend does.
    fn mirrors(&self) -> bool {
        DMat3::from_mat4(self.matrix(0)).determinant() < 0.0
    }

    /// The transform that turns vertex `v`'s normal: the inverse transpose of its own.
    fn normal_matrix(&self, v: usize, node: &DMat3) -> DMat3 {
        match self {
            Placement::Node(_) => *node,
            Placement::Skinned { blends, .. } => DMat3::from_mat4(blends[v]).inverse().transpose(),
        }
    }
}

impl Importer {
    pub(super) fn add_primitive(
        &mut self,
        mesh: &gltf::Mesh,
        primitive: &gltf::Primitive,
        placement: Placement,
        buffers: &[gltf::buffer::Data],
    ) -> Result<(), String> {
        let name = || primitive_name(mesh, primitive);
        if primitive.mode() != gltf::mesh::Mode::Triangles {
            // Points and lines have no surface to shade; skipping them keeps the rest usable.
            return Ok(());
        }
        let Attributes { positions, uvs, normals, file_tangents, indices } =
            read_attributes(primitive, buffers).map_err(|e| format!("{}: {e}", name()))?;

        let default_material = self.scene.materials.len() - 1;
        let material = primitive.material().index().unwrap_or(default_material);
        let class = self.scene.materials[material].draw_class();
        let world_positions = to_world(&positions, placement).map_err(|(i, p)| {
            format!(
                "{}: vertex {i} lies at {} in world space, beyond ±{:e} (the node transforms multiply up)",
                name(),
                crate::scene::camera::vector(p),
                crate::scene::MAX_COORDINATE
            )
        })?;
        let first_vertex = self.scene.vertices.len();
        let first_triangle = self.triangles.get(&class).map_or(0, Vec::len);
        let geometry =
            Geometry { world: &world_positions, normals: normals.as_deref(), uvs: &uvs, indices: &indices };
        self.append(geometry, placement, material, class);
        if self.scene.materials[material].normal_texture.is_some() {
            let mirrored = placement.mirrors();
            let file_tangents = file_tangents.map(|tangents| world_tangents(&tangents, placement, mirrored));
            self.add_tangents(class, first_vertex, first_triangle, file_tangents);
        }
        Ok(())
    }

    /// Appends a primitive's vertices and triangles to the scene's, in world space: its normals
    /// turned as its vertices are, or flat normals (three vertices a triangle) where the file
    /// gives none; a mirroring transform reverses the winding.
    fn append(&mut self, geometry: Geometry, placement: Placement, material: usize, class: DrawClass) {
        let Geometry { world: world_positions, normals, uvs, indices } = geometry;
        let mirrored = placement.mirrors();
        let normal_matrix = DMat3::from_mat4(placement.matrix(0)).inverse().transpose();
        let vertex = |normal: Vec3, uv: [f32; 2]| Vertex {
            position: [0.0; 3],
            normal: normal.to_array(),
            uv,
            material: material as u32,
        };
        let first_vertex = self.scene.vertices.len();
        if placement.influence(0).is_some() {
            self.influences.resize(first_vertex, Influence::default());
        }
        let vertices = &mut self.scene.vertices;
        let positions_world = &mut self.world;
        let influences = &mut self.influences;
        let triangles = self.triangles.entry(class).or_default();

        match normals {
            Some(normals) => {
                let base = vertices.len() as u32;
                for (i, ((p, n), uv)) in world_positions.iter().zip(normals).zip(uvs).enumerate() {
                    let turn = placement.normal_matrix(i, &normal_matrix);
                    let n = (turn * DVec3::from(n.map(f64::from))).normalize_or_zero();
                    vertices.push(vertex(n.as_vec3(), *uv));
                    positions_world.push(*p);
                    influences.extend(placement.influence(i));
                }
                let added: Vec<[u32; 3]> =
                    indices.chunks_exact(3).map(|t| wound(t, mirrored).map(|i| base + i)).collect();
                let from = base as usize;
                repair_normals(&mut vertices[from..], &positions_world[from..], &added, base);
                triangles.extend(added);
            }
            None => {
                // Flat normals: every triangle gets its own three vertices.
                for (normal, corners) in flat_triangles(indices, world_positions, uvs, mirrored) {
                    let base = vertices.len() as u32;
                    for (position, uv, source) in corners {
                        vertices.push(vertex(normal, uv));
                        positions_world.push(position);
                        influences.extend(placement.influence(source as usize));
                    }
                    triangles.push([base, base + 1, base + 2]);
                }
            }
        }
    }
}

/// A primitive's geometry as the scene takes it: world positions, the file's normals if any,
/// texture coordinates, and three corners a triangle.
struct Geometry<'a> {
    world: &'a [DVec3],
    normals: Option<&'a [[f32; 3]]>,
    uvs: &'a [[f32; 2]],
    indices: &'a [u32],
}

/// `meshes[2] (wall) primitives[0]`, as messages name a primitive.
pub(super) fn primitive_name(mesh: &gltf::Mesh, primitive: &gltf::Primitive) -> String {
    format!(
        "meshes[{}] ({}) primitives[{}]",
        mesh.index(),
        mesh.name().unwrap_or("unnamed"),
        primitive.index()
    )
}

/// A triangle's indices in front-face order: a mirroring transform turns counter-clockwise front
/// faces clockwise (glTF 2.0, 3.7.4).
fn wound(t: &[u32], mirrored: bool) -> [u32; 3] {
    if mirrored { [t[0], t[2], t[1]] } else { [t[0], t[1], t[2]] }
}

/// A triangle's corner: its world position, UV and the primitive's vertex it came from.
type Corner = (DVec3, [f32; 2], u32);

/// Each triangle's corners (world position and UV, in front-face order) with the normal of its
/// plane: flat shading, where the file gives no normals.
fn flat_triangles(
    indices: &[u32],
    positions: &[DVec3],
    uvs: &[[f32; 2]],
    mirrored: bool,
) -> Vec<(Vec3, [Corner; 3])> {
    indices
        .chunks_exact(3)
        .map(|t| {
            let corners = wound(t, mirrored).map(|i| (positions[i as usize], uvs[i as usize], i));
            let normal = (corners[1].0 - corners[0].0)
                .cross(corners[2].0 - corners[0].0)
                .normalize_or_zero()
                .as_vec3();
            (normal, corners)
        })
        .collect()
}

/// The positions moved to world space, where they stay f64 until `finish` knows the scene's
/// origin; or the index and place of the first that lies beyond what an f32 (and a camera) can
/// hold: finite scales can multiply up to such places.
fn to_world(positions: &[[f32; 3]], placement: Placement) -> Result<Vec<DVec3>, (usize, DVec3)> {
    let world_positions: Vec<DVec3> = (positions.iter().enumerate())
        .map(|(i, p)| placement.matrix(i).transform_point3(DVec3::from(p.map(f64::from))))
        .collect();
    let beyond = |p: &DVec3| !p.is_finite() || p.abs().max_element() > crate::scene::MAX_COORDINATE;
    match world_positions.iter().position(beyond) {
        Some(i) => Err((i, world_positions[i])),
        None => Ok(world_positions),
    }
}

/// A triangle primitive's attributes as the file gives them, each checked: formats and
/// accessor bounds, finite positions, UVs and tangents, whole triangles, indices in range and
/// counts that agree. Errors name the attribute; the caller names the primitive.
struct Attributes {
    positions: Vec<[f32; 3]>,
    uvs: Vec<[f32; 2]>,
    normals: Option<Vec<[f32; 3]>>,
    /// The file's tangents, only where it gives normals too (glTF 2.0, 3.7.2.1).
    file_tangents: Option<Vec<[f32; 4]>>,
    indices: Vec<u32>,
}

fn read_attributes(
    primitive: &gltf::Primitive,
    buffers: &[gltf::buffer::Data],
) -> Result<Attributes, String> {
    for (semantic, accessor) in primitive.attributes() {
        check_format(Some(&semantic), &accessor)
            .and_then(|()| check_accessor(&accessor, buffers))
            .map_err(|e| format!("attributes.{}: {e}", semantic.to_string()))?;
    }
    if let Some(accessor) = primitive.indices() {
        check_format(None, &accessor)
            .and_then(|()| check_accessor(&accessor, buffers))
            .map_err(|e| format!("indices: {e}"))?;
    }
    let reader = primitive.reader(|buffer| buffers.get(buffer.index()).map(|d| &d.0[..]));
    let positions: Vec<[f32; 3]> =
        reader.read_positions().ok_or_else(|| "attributes.POSITION is missing".to_string())?.collect();
    if let Some(i) = positions.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
        return Err(format!("attributes.POSITION: vertex {i} is {:?}, not finite", positions[i]));
    }
    let uvs: Vec<[f32; 2]> = match reader.read_tex_coords(0) {
        Some(uvs) => uvs.into_f32().collect(),
        None => vec![[0.0; 2]; positions.len()],
    };
    if let Some(i) = uvs.iter().position(|uv| !uv.iter().all(|c| c.is_finite())) {
        return Err(format!("attributes.TEXCOORD_0: vertex {i} is {:?}, not finite", uvs[i]));
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
        return Err(format!("{} indices, not a multiple of 3: triangles need three each", indices.len()));
    }
    if let Some(&bad) = indices.iter().find(|&&i| i as usize >= positions.len()) {
        return Err(format!("indices: {bad} is out of range for {} vertices", positions.len()));
    }
    if uvs.len() != positions.len()
        || normals.as_ref().is_some_and(|n| n.len() != positions.len())
        || file_tangents.as_ref().is_some_and(|t| t.len() != positions.len())
    {
        return Err("attribute counts differ from POSITION".into());
    }
    if let Some(i) =
        file_tangents.as_ref().and_then(|t| t.iter().position(|t| !t.iter().all(|c| c.is_finite())))
    {
        return Err(format!("attributes.TANGENT: vertex {i} is not finite"));
    }
    Ok(Attributes { positions, uvs, normals, file_tangents, indices })
}

/// The file's tangents in world space: they move with the surface, and a mirroring transform
/// flips the bitangent's sign.
fn world_tangents(tangents: &[[f32; 4]], placement: Placement, mirrored: bool) -> Vec<[f32; 4]> {
    let handedness = if mirrored { -1.0 } else { 1.0 };
    (tangents.iter().enumerate())
        .map(|(i, t)| {
            let linear = DMat3::from_mat4(placement.matrix(i));
            let xyz = (linear * DVec3::new(t[0].into(), t[1].into(), t[2].into())).normalize_or_zero();
            let w = if t[3] < 0.0 { -handedness } else { handedness };
            [xyz.x as f32, xyz.y as f32, xyz.z as f32, w]
        })
        .collect()
}

/// Checks that an accessor the importer reads has a format glTF allows for it (`None` for
/// indices): the gltf crate's readers assume it and panic otherwise. Sparse accessors are
/// refused rather than read: their indices and values are not bounds-checked by the crate.
pub(super) fn check_format(
    semantic: Option<&gltf::Semantic>,
    accessor: &gltf::Accessor,
) -> Result<(), String> {
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
        Some(Semantic::Joints(_)) => matches!(format, (DataType::U8 | DataType::U16, Dimensions::Vec4)),
        Some(Semantic::Weights(_)) => {
            let integer = matches!(format.0, DataType::U8 | DataType::U16) && accessor.normalized();
            format.1 == Dimensions::Vec4 && (format.0 == DataType::F32 || integer)
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
pub(super) fn check_accessor(
    accessor: &gltf::Accessor,
    buffers: &[gltf::buffer::Data],
) -> Result<(), String> {
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
pub(super) fn view_bytes<'a>(
    view: &gltf::buffer::View,
    buffers: &'a [gltf::buffer::Data],
) -> Result<&'a [u8], String> {
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
