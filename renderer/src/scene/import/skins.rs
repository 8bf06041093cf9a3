//! Skinned meshes: their joints, inverse bind matrices and each vertex's influences read and
//! checked, and their vertices placed where the skeleton's rest pose carries them.

use std::collections::HashMap;

use glam::DMat4;

use super::Importer;
use super::primitives::{Placement, check_accessor, check_format, primitive_name};
use crate::scene::skin::{Influence, MAX_INFLUENCES, Skin};

impl Importer {
    /// Adds the meshes of the skinned nodes that the walk met, once it has placed every joint:
    /// each vertex where the blend of its joints at rest carries it. Returns what it warns of:
    /// vertices that named more joints than it keeps. The node that holds a
    /// skinned mesh does not place it (glTF 2.0, 3.7.3.3).
    pub(super) fn add_skinned(
        &mut self,
        document: &gltf::Document,
        buffers: &[gltf::buffer::Data],
    ) -> Result<Vec<String>, String> {
        let mut warnings = Vec::new();
        let places: HashMap<usize, usize> =
            self.rig.nodes.iter().enumerate().map(|(place, rest)| (rest.node, place)).collect();
        let rest_worlds = self.rig.rest_worlds();
        for index in std::mem::take(&mut self.skinned) {
            let node = document.nodes().nth(index).expect("a node of the document");
            let (Some(mesh), Some(skin)) = (node.mesh(), node.skin()) else {
                continue;
            };
            let joints = read_joints(&skin, buffers, &places)
                .map_err(|e| format!("nodes[{index}]: skins[{}]{e}", skin.index()))?;
            let matrices: Vec<DMat4> =
                joints.iter().map(|&(place, inverse_bind)| rest_worlds[place] * inverse_bind).collect();
            let first = self.scene.vertices.len();
            let triangles = mesh.primitives().filter(|p| p.mode() == gltf::mesh::Mode::Triangles);
            for primitive in triangles {
                let name = primitive_name(&mesh, &primitive);
                let (influences, dropped) =
                    read_influences(&primitive, buffers, joints.len()).map_err(|e| format!("{name}: {e}"))?;
                warnings.extend(dropped.map(|warning| format!("{name}: {warning}")));
                let blends: Vec<DMat4> = influences.iter().map(|i| i.blend(&matrices)).collect();
                let placement = Placement::Skinned { blends: &blends, influences: &influences };
                self.add_primitive(&mesh, &primitive, placement, buffers)?;
            }
            self.rig.skins.push(Skin {
                skin: skin.index(),
                node: index,
                joints,
                vertices: std::iter::once(first..self.scene.vertices.len()).collect(),
                // Filled once tangent generation has split off its copies.
                influences: Vec::new(),
            });
        }
        Ok(warnings)
    }
}

/// A skin's joints: each its place in the rig (`places`, by glTF node) and its inverse bind
/// matrix (the identity where the skin gives none). Errors start with the field at fault
/// (`.joints[3]: …`); the caller names the skin.
fn read_joints(
    skin: &gltf::Skin,
    buffers: &[gltf::buffer::Data],
    places: &HashMap<usize, usize>,
) -> Result<Vec<(usize, DMat4)>, String> {
    let joints: Vec<gltf::Node> = skin.joints().collect();
    let inverse_binds: Vec<DMat4> = match skin.inverse_bind_matrices() {
        None => vec![DMat4::IDENTITY; joints.len()],
        Some(accessor) => {
            let index = accessor.index();
            let format = (accessor.data_type(), accessor.dimensions());
            if format != (gltf::accessor::DataType::F32, gltf::accessor::Dimensions::Mat4)
                || accessor.sparse().is_some()
            {
                return Err(format!(
                    ".inverseBindMatrices: accessors[{index}] must hold float MAT4s, not sparse"
                ));
            }
            check_accessor(&accessor, buffers).map_err(|e| format!(".inverseBindMatrices: {e}"))?;
            if accessor.count() < joints.len() {
                return Err(format!(
                    ".inverseBindMatrices: accessors[{index}] holds {} matrices for {} joints",
                    accessor.count(),
                    joints.len()
                ));
            }
            let reader = skin.reader(|buffer| buffers.get(buffer.index()).map(|d| &d.0[..]));
            let matrices =
                reader.read_inverse_bind_matrices().ok_or(".inverseBindMatrices cannot be read")?;
            let matrices: Vec<DMat4> =
                matrices.map(|m| DMat4::from_cols_array_2d(&m.map(|c| c.map(f64::from)))).collect();
            if let Some(j) = matrices.iter().position(|m| !m.is_finite()) {
                return Err(format!(".inverseBindMatrices: matrix {j} is not finite"));
            }
            // An inverse bind matrix undoes its joint's bind pose: one without an inverse
            // flattens every vertex it carries, the still's rest pose included.
            if let Some(j) =
                matrices.iter().position(|m| !(m.determinant() != 0.0 && m.inverse().is_finite()))
            {
                return Err(format!(
                    ".inverseBindMatrices: matrix {j} has no inverse (its determinant is 0), so it cannot \
                     undo a bind pose: the vertices its joint carries would collapse"
                ));
            }
            matrices
        }
    };
    (joints.iter().zip(inverse_binds).enumerate())
        .map(|(j, (joint, inverse_bind))| {
            let place = places.get(&joint.index()).ok_or_else(|| {
                format!(".joints[{j}]: nodes[{}] is not in the scene, so nothing places it", joint.index())
            })?;
            Ok((*place, inverse_bind))
        })
        .collect()
}

/// One set of `JOINTS_n` and `WEIGHTS_n`: per vertex, four joints and their weights.
type InfluenceSet = (Vec<[u16; 4]>, Vec<[f32; 4]>);

/// Each vertex's influences, from every set of `JOINTS_n` and `WEIGHTS_n` the primitive has
/// (glTF allows any number; each must come in a pair), checked against the skin's `joints` and
/// normalised, and a warning where a vertex named more joints than [`MAX_INFLUENCES`] and lost
/// the lightest. Errors name the attribute and vertex.
fn read_influences(
    primitive: &gltf::Primitive,
    buffers: &[gltf::buffer::Data],
    joints: usize,
) -> Result<(Vec<Influence>, Option<String>), String> {
    use gltf::Semantic;
    let count = primitive.get(&Semantic::Positions).map_or(0, |a| a.count());
    let reader = primitive.reader(|buffer| buffers.get(buffer.index()).map(|d| &d.0[..]));
    let numbered = primitive.attributes().filter_map(|(semantic, _)| match semantic {
        Semantic::Joints(set) | Semantic::Weights(set) => Some(set),
        _ => None,
    });
    let last = numbered.max().unwrap_or(0);
    let mut sets: Vec<InfluenceSet> = Vec::new();
    for set in 0..=last {
        let pair = [Semantic::Joints(set), Semantic::Weights(set)].map(|s| primitive.get(&s).map(|a| (s, a)));
        let [Some(joints_accessor), Some(weights_accessor)] = pair else {
            return Err(format!(
                "a skinned mesh's primitive needs attributes.JOINTS_{set} and WEIGHTS_{set} together{}",
                if set > 0 { format!(", as it has a set numbered {last}") } else { String::new() }
            ));
        };
        for (semantic, accessor) in [joints_accessor, weights_accessor] {
            check_format(Some(&semantic), &accessor)
                .and_then(|()| check_accessor(&accessor, buffers))
                .map_err(|e| format!("attributes.{}: {e}", semantic.to_string()))?;
            if accessor.count() != count {
                return Err(format!(
                    "attributes.{}: {} elements for {count} vertices",
                    semantic.to_string(),
                    accessor.count()
                ));
            }
        }
        let read = (reader.read_joints(set), reader.read_weights(set));
        let (Some(joints), Some(weights)) = read else {
            return Err(format!("attributes.JOINTS_{set} or WEIGHTS_{set} cannot be read"));
        };
        sets.push((joints.into_u16().collect(), weights.into_f32().collect()));
    }
    let read: Vec<(Influence, f32)> = (0..count)
        .map(|v| {
            let per_vertex: Vec<([u16; 4], [f32; 4])> = sets.iter().map(|(j, w)| (j[v], w[v])).collect();
            Influence::from_sets(&per_vertex, joints)
                .map_err(|e| format!("attributes.JOINTS and WEIGHTS: vertex {v}: {e}"))
        })
        .collect::<Result<_, _>>()?;
    let dropped: Vec<f32> = read.iter().map(|(_, share)| *share).filter(|share| *share > 0.0).collect();
    let warning = (!dropped.is_empty()).then(|| {
        let most = dropped.iter().copied().fold(0.0f32, f32::max);
        format!(
            "attributes.JOINTS_0 to JOINTS_{last}: {} vertices name more than {MAX_INFLUENCES} joints; each \
             keeps its {MAX_INFLUENCES} heaviest, dropping at most {:.1} % of a vertex's weight",
            dropped.len(),
            most * 100.0
        )
    });
    Ok((read.into_iter().map(|(influence, _)| influence).collect(), warning))
}
