//! Skinned meshes: vertices carried by a skeleton's joints, each by a weighted blend of its
//! joints' transforms (glTF 2.0, 3.7.3.3): the joint matrix of joint j is its node's world
//! transform times its inverse bind matrix, and a vertex lies where the blend of its joints'
//! matrices carries its position in the mesh. The node that holds the mesh does not place it.
//!
//! The importer bakes a skinned mesh in the pose its skeleton takes at rest, like every other
//! mesh; posing undoes each vertex's blend at rest once ([`BindPose`]) and applies its blend
//! at a time.

use std::ops::Range;

use glam::{DMat3, DMat4, DVec3, Vec3};

use super::Vertex;

/// At most this many joints carry one vertex: two sets of `JOINTS_n` and `WEIGHTS_n`. A vertex
/// that names more keeps its heaviest ([`Influence::from_sets`]).
pub const MAX_INFLUENCES: usize = 8;

/// The joints that carry one vertex: indices into its skin's joints, each with its weight.
/// Weights are normalised to sum to 1; unused slots weigh 0.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Influence {
    pub joints: [u16; MAX_INFLUENCES],
    pub weights: [f32; MAX_INFLUENCES],
}

impl Influence {
    /// The vertex's blend of `matrices` (its skin's joint matrices, [`Skin::matrices`]).
    pub fn blend(&self, matrices: &[DMat4]) -> DMat4 {
        let mut blend = DMat4::ZERO;
        for (&joint, &weight) in self.joints.iter().zip(&self.weights).filter(|(_, w)| **w != 0.0) {
            blend += matrices[usize::from(joint)] * f64::from(weight);
        }
        blend
    }

    /// Reads one vertex's influences from its `JOINTS_n` and `WEIGHTS_n` sets (four each, as
    /// many sets as the file gives), checked against the skin's `joints` count and normalised,
    /// and the share of its weight dropped: past [`MAX_INFLUENCES`] joints it keeps the
    /// heaviest (the first of equal ones). On failure, why (the caller names the vertex).
    pub fn from_sets(sets: &[([u16; 4], [f32; 4])], joints: usize) -> Result<(Influence, f32), String> {
        let mut pairs: Vec<(u16, f32)> =
            sets.iter().flat_map(|(j, w)| j.iter().copied().zip(w.iter().copied())).collect();
        for (slot, &(joint, weight)) in pairs.iter().enumerate() {
            if !(weight.is_finite() && weight >= 0.0) {
                return Err(format!("weight {slot} is {weight}; weights must be finite and ≥ 0"));
            }
            if weight > 0.0 && usize::from(joint) >= joints {
                return Err(format!("joint {joint} (weight {weight}) does not exist: the skin has {joints}"));
            }
        }
        let all: f32 = pairs.iter().map(|(_, w)| w).sum();
        if pairs.len() > MAX_INFLUENCES {
            pairs.sort_by(|a, b| b.1.total_cmp(&a.1));
        }
        let mut influence = Influence::default();
        for (slot, (joint, weight)) in pairs.into_iter().take(MAX_INFLUENCES).enumerate() {
            influence.joints[slot] = joint;
            influence.weights[slot] = weight;
        }
        let total: f32 = influence.weights.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            return Err(format!("its weights sum to {total}, so no joint carries it"));
        }
        influence.weights = influence.weights.map(|w| w / total);
        Ok((influence, 1.0 - total / all))
    }
}

/// One node's skinned mesh, as the importer baked it.
#[derive(Debug, Clone, PartialEq)]
pub struct Skin {
    /// The glTF skin, and the node whose mesh it carries: how messages name it.
    pub skin: usize,
    pub node: usize,
    /// Each joint: its place in the rig's list of nodes (parents first) and its inverse bind matrix.
    pub joints: Vec<(usize, DMat4)>,
    /// The vertices it carries: its primitives' own, then the copies tangent generation split
    /// off at the end of the list.
    pub vertices: Vec<Range<usize>>,
    /// One per vertex of `vertices`, in their order.
    pub influences: Vec<Influence>,
}

impl Skin {
    /// `skins[0] (of nodes[4])`, as messages name it.
    pub fn label(&self) -> String {
        format!("skins[{}] (of nodes[{}])", self.skin, self.node)
    }

    /// The joint matrices, given the world transform of every node of the rig (in its order).
    pub fn matrices(&self, worlds: &[DMat4]) -> Vec<DMat4> {
        self.joints.iter().map(|&(place, inverse_bind)| worlds[place] * inverse_bind).collect()
    }

    /// Its vertices' indices in the scene, in the order of `influences`.
    pub fn vertex_indices(&self) -> impl Iterator<Item = usize> + '_ {
        self.vertices.iter().flat_map(Clone::clone)
    }
}

/// A skinned vertex in its mesh's own space (the bind pose), found once from where it was
/// baked: what a blend of joint matrices carries to where it lies at a time.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Bound {
    position: DVec3,
    normal: DVec3,
    tangent: DVec3,
}

/// A skin whose joints an animation moves, with each vertex's bind-pose place.
#[derive(Debug, Clone)]
pub struct BindPose {
    pub skin: Skin,
    bound: Vec<Bound>,
}

impl BindPose {
    /// Undoes each vertex's blend at rest (`rest_worlds`: the rig's world transforms at rest):
    /// `rest` are the scene's baked vertices (relative to `origin`) and their tangents. A vertex
    /// whose joints flatten it at rest cannot be carried from where it was baked: its bind
    /// place is not finite, which [`BindPose::check_rest`] reports.
    pub fn new(
        skin: &Skin,
        rest_worlds: &[DMat4],
        origin: DVec3,
        rest: &[Vertex],
        tangents: &[[f32; 4]],
    ) -> BindPose {
        let matrices = skin.matrices(rest_worlds);
        let bound = skin
            .vertex_indices()
            .zip(&skin.influences)
            .map(|(v, influence)| {
                let blend = influence.blend(&matrices);
                let inverse = blend.inverse();
                let vector = |v: [f32; 3]| Vec3::from(v).as_dvec3();
                let tangent = tangents.get(v).map_or(DVec3::ZERO, |t| vector([t[0], t[1], t[2]]));
                Bound {
                    position: inverse.transform_point3(vector(rest[v].position) + origin),
                    // Normals turn by the inverse transpose; undoing it is the transpose.
                    normal: DMat3::from_mat4(blend).transpose() * vector(rest[v].normal),
                    tangent: DMat3::from_mat4(inverse) * tangent,
                }
            })
            .collect();
        BindPose { skin: skin.clone(), bound }
    }

    /// The first vertex that its joints flatten at rest, if one is.
    pub fn check_rest(&self) -> Result<(), String> {
        let flat = |b: &Bound| !(b.position.is_finite() && b.normal.is_finite() && b.tangent.is_finite());
        match self.bound.iter().position(flat) {
            Some(i) => Err(format!(
                "{}: vertex {} is flattened by its joints at rest (their blend cannot be undone), so it \
                 cannot be carried from where it was baked",
                self.skin.label(),
                self.skin.vertex_indices().nth(i).unwrap_or_default()
            )),
            None => Ok(()),
        }
    }

    /// Each of its vertex ranges posed by `worlds` (the rig's world transforms at a time):
    /// where the range starts, its vertices (`rest` gives what posing keeps: UVs, materials)
    /// and their tangents (none where the scene has none).
    pub fn posed(
        &self,
        worlds: &[DMat4],
        origin: DVec3,
        rest: &[Vertex],
        tangents: &[[f32; 4]],
    ) -> Vec<(usize, Vec<Vertex>, Vec<[f32; 4]>)> {
        let matrices = self.skin.matrices(worlds);
        let mut at = 0;
        let mut posed = Vec::with_capacity(self.skin.vertices.len());
        for range in &self.skin.vertices {
            let mut vertices = Vec::with_capacity(range.len());
            let mut turned = Vec::new();
            for v in range.clone() {
                let (blend, bound) = (self.skin.influences[at].blend(&matrices), &self.bound[at]);
                at += 1;
                let linear = DMat3::from_mat4(blend);
                vertices.push(Vertex {
                    position: (blend.transform_point3(bound.position) - origin).as_vec3().to_array(),
                    normal: unit(cofactor(linear) * bound.normal),
                    ..rest[v]
                });
                if let Some(t) = tangents.get(v) {
                    let xyz = unit(linear * bound.tangent);
                    turned.push([xyz[0], xyz[1], xyz[2], t[3]]);
                }
            }
            posed.push((range.start, vertices, turned));
        }
        posed
    }

    /// Its vertices' positions posed by `worlds`, relative to `origin` (f64, unrounded): where
    /// each range starts, and the positions.
    pub fn positions(&self, worlds: &[DMat4], origin: DVec3) -> Vec<(usize, Vec<DVec3>)> {
        let matrices = self.skin.matrices(worlds);
        let mut at = 0;
        (self.skin.vertices.iter())
            .map(|range| {
                let positions = range
                    .clone()
                    .map(|_| {
                        let (blend, bound) = (self.skin.influences[at].blend(&matrices), &self.bound[at]);
                        at += 1;
                        blend.transform_point3(bound.position) - origin
                    })
                    .collect();
                (range.start, positions)
            })
            .collect()
    }
}

/// The cofactor matrix of `m`: its inverse transpose times its determinant, which turns
/// normals as the inverse transpose does, without a division (and defined where `m` is
/// singular).
fn cofactor(m: DMat3) -> DMat3 {
    DMat3::from_cols(m.y_axis.cross(m.z_axis), m.z_axis.cross(m.x_axis), m.x_axis.cross(m.y_axis))
}

fn unit(v: DVec3) -> [f32; 3] {
    v.normalize_or_zero().as_vec3().to_array()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_are_normalised_and_joints_beyond_the_skin_refused() {
        let influence = Influence::from_sets(&[([0, 1, 0, 0], [1.0, 3.0, 0.0, 0.0])], 2).unwrap().0;
        assert_eq!(influence.weights[..2], [0.25, 0.75]);
        // A second set adds four more joints.
        let (eight, dropped) =
            Influence::from_sets(&[([0, 1, 2, 3], [1.0; 4]), ([4, 5, 6, 7], [1.0; 4])], 8).unwrap();
        assert_eq!((eight.weights, dropped), ([0.125; 8], 0.0));
        let beyond = Influence::from_sets(&[([0, 5, 0, 0], [0.5, 0.5, 0.0, 0.0])], 2).unwrap_err();
        assert!(beyond.contains("joint 5"), "{beyond}");
        // A joint index past the skin that weighs nothing is padding, as exporters write it.
        assert!(Influence::from_sets(&[([0, 9, 0, 0], [1.0, 0.0, 0.0, 0.0])], 1).is_ok());
        let none = Influence::from_sets(&[([0; 4], [0.0; 4])], 1).unwrap_err();
        assert!(none.contains("sum to 0"), "{none}");
        let negative = Influence::from_sets(&[([0; 4], [1.0, -0.5, 0.0, 0.0])], 1).unwrap_err();
        assert!(negative.contains("≥ 0"), "{negative}");
    }

    #[test]
    fn a_third_set_is_read_and_past_eight_joints_the_lightest_go() {
        // Half the weight on joint 0 in the first set, half on joint 1 in the third, the second
        // empty: both carry the vertex, half each.
        let sets =
            [([0, 0, 0, 0], [0.5, 0.0, 0.0, 0.0]), ([0; 4], [0.0; 4]), ([1, 0, 0, 0], [0.5, 0.0, 0.0, 0.0])];
        let (halves, dropped) = Influence::from_sets(&sets, 2).unwrap();
        assert_eq!(
            (halves.joints[..2].to_vec(), halves.weights[..2].to_vec(), dropped),
            (vec![0, 1], vec![0.5, 0.5], 0.0)
        );
        // Nine joints: the lightest (1 of 17) goes, and the rest are renormalised.
        let sets = [([0, 1, 2, 3], [2.0; 4]), ([4, 5, 6, 7], [2.0; 4]), ([8, 0, 0, 0], [1.0, 0.0, 0.0, 0.0])];
        let (kept, dropped) = Influence::from_sets(&sets, 9).unwrap();
        assert_eq!((kept.joints, kept.weights), ([0, 1, 2, 3, 4, 5, 6, 7], [0.125; 8]));
        assert!((dropped - 1.0 / 17.0).abs() < 1e-6, "{dropped}");
    }

    #[test]
    fn a_vertex_halfway_between_two_joints_follows_half_of_each() {
        // Joint 0 stays; joint 1 turns a quarter about z at the origin. A vertex at (1, 0, 0)
        // carried half by each lies halfway between (1, 0, 0) and (0, 1, 0); its normal, +x,
        // turns halfway too.
        let skin = Skin {
            skin: 0,
            node: 0,
            joints: vec![(0, DMat4::IDENTITY), (1, DMat4::IDENTITY)],
            vertices: std::iter::once(0..1).collect(),
            influences: vec![Influence::from_sets(&[([0, 1, 0, 0], [0.5, 0.5, 0.0, 0.0])], 2).unwrap().0],
        };
        let vertex =
            Vertex { position: [1.0, 0.0, 0.0], normal: [1.0, 0.0, 0.0], uv: [0.5, 0.5], material: 3 };
        let rest = [DMat4::IDENTITY, DMat4::IDENTITY];
        let pose = BindPose::new(&skin, &rest, DVec3::ZERO, &[vertex], &[]);
        pose.check_rest().unwrap();
        let turned = [DMat4::IDENTITY, DMat4::from_rotation_z(std::f64::consts::FRAC_PI_2)];
        let posed = pose.posed(&turned, DVec3::ZERO, &[vertex], &[]);
        let moved = posed[0].1[0];
        assert_eq!(moved.position, [0.5, 0.5, 0.0]);
        let half = std::f32::consts::FRAC_1_SQRT_2;
        assert!((Vec3::from(moved.normal) - Vec3::new(half, half, 0.0)).length() < 1e-6, "{moved:?}");
        assert_eq!((moved.uv, moved.material), ([0.5, 0.5], 3), "what posing keeps");
    }

    #[test]
    fn a_vertex_baked_away_from_its_bind_pose_comes_back_through_the_rest_blend() {
        // The skeleton's rest pose is not its bind pose: the joint lies 2 along x at rest and
        // its inverse bind matrix says it was bound at the origin. The vertex was baked where
        // the rest pose carries it; moving the joint to 5 along x carries it 3 further.
        let skin = Skin {
            skin: 0,
            node: 0,
            joints: vec![(0, DMat4::IDENTITY)],
            vertices: std::iter::once(0..1).collect(),
            influences: vec![Influence::from_sets(&[([0; 4], [1.0, 0.0, 0.0, 0.0])], 1).unwrap().0],
        };
        let baked = Vertex { position: [3.0, 1.0, 0.0], normal: [0.0, 1.0, 0.0], uv: [0.0; 2], material: 0 };
        let origin = DVec3::new(1024.0, 0.0, 0.0);
        let rest = [DMat4::from_translation(DVec3::new(2.0, 0.0, 0.0))];
        let pose = BindPose::new(&skin, &rest, origin, &[baked], &[]);
        let moved = pose.positions(&[DMat4::from_translation(DVec3::new(5.0, 0.0, 0.0))], origin);
        assert!((moved[0].1[0] - DVec3::new(6.0, 1.0, 0.0)).length() < 1e-12, "{moved:?}");
        // A joint scaled to nothing at rest flattens its vertices: they cannot be carried.
        let flat = BindPose::new(&skin, &[DMat4::from_scale(DVec3::ZERO)], origin, &[baked], &[]);
        assert!(flat.check_rest().unwrap_err().contains("vertex 0 is flattened"));
    }
}
