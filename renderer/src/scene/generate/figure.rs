//! A skinned figure that strides along: a mannequin of capsules on an eleven-joint skeleton, one mesh
//! whose vertices blend between the joints on either side of a hip, knee, shoulder, elbow or
//! waist, and a running stride that swings its limbs while its hips carry it along x.

use std::f32::consts::{PI, TAU};

use glam::{Affine3A, Mat4, Quat, Vec3};

use super::Builder;
use super::mesh::{self, Mesh};
use crate::scene::write::{Channel, SkinDesc};

/// The skeleton's joints, parents before children: name, parent and place in the parent at
/// rest (metres; the hips at the origin, the figure facing +x).
const JOINTS: [(&str, Option<usize>, [f32; 3]); 11] = [
    ("hips", None, [0.0, 0.0, 0.0]),
    ("chest", Some(0), [0.0, 0.45, 0.0]),
    ("head", Some(1), [0.0, 0.17, 0.0]),
    ("thigh.l", Some(0), [0.0, -0.02, 0.1]),
    ("shin.l", Some(3), [0.0, -0.44, 0.0]),
    ("thigh.r", Some(0), [0.0, -0.02, -0.1]),
    ("shin.r", Some(5), [0.0, -0.44, 0.0]),
    ("arm.l", Some(1), [0.0, 0.05, 0.21]),
    ("forearm.l", Some(7), [0.0, -0.28, 0.0]),
    ("arm.r", Some(1), [0.0, 0.05, -0.21]),
    ("forearm.r", Some(9), [0.0, -0.28, 0.0]),
];

const HIPS: usize = 0;
const CHEST: usize = 1;
const HEAD: usize = 2;
/// The limbs: upper joint, lower joint, capsule radius and length from the upper joint down.
const LIMBS: [(usize, usize, f32, f32); 4] =
    [(3, 4, 0.065, 0.96), (5, 6, 0.065, 0.96), (7, 8, 0.045, 0.56), (9, 10, 0.045, 0.56)];
/// Over how many metres either side of a joint its two bones share the skin.
const BLEND: f32 = 0.08;

/// Where each joint lies at rest, relative to the hips.
fn rest_places() -> [Vec3; 11] {
    let mut places = [Vec3::ZERO; 11];
    for (i, (_, parent, offset)) in JOINTS.iter().enumerate() {
        places[i] = parent.map_or(Vec3::ZERO, |p| places[p]) + Vec3::from(*offset);
    }
    places
}

/// The figure's mesh in its bind pose (hips at the origin) with each vertex's joints and
/// weights: every part a capsule or sphere, each vertex shared by the two joints whose bones
/// meet nearest it.
fn body() -> (Mesh, Vec<[u16; 4]>, Vec<[f32; 4]>) {
    let places = rest_places();
    let mut body = Mesh::default();
    let (mut joints, mut weights) = (Vec::new(), Vec::new());
    let mut add = |part: Mesh, place: Affine3A, weigh: &dyn Fn(Vec3) -> ([u16; 4], [f32; 4])| {
        let first = body.positions.len();
        body.append(&part, place);
        for p in &body.positions[first..] {
            let (j, w) = weigh(Vec3::from(*p));
            joints.push(j);
            weights.push(w);
        }
    };
    // The torso, waist to shoulders: hips below the waist, chest above, shared between.
    let waist = places[HIPS].y + 0.22;
    add(mesh::capsule(0.15, 0.42, 24, 24), at(Vec3::new(0.0, 0.25, 0.0)), &|p| {
        between(HIPS, CHEST, p.y - waist)
    });
    add(mesh::sphere(0.11, 24, 16), at(places[HEAD] + Vec3::new(0.0, 0.10, 0.0)), &|_| only(HEAD));
    for (upper, lower, radius, length) in LIMBS {
        let top = places[upper];
        add(
            mesh::capsule(radius, length - 2.0 * radius, 16, 32),
            at(top - Vec3::new(0.0, length / 2.0 - radius, 0.0)),
            &|p| between(lower, upper, p.y - places[lower].y),
        );
    }
    // Feet, on the shins.
    for shin in [4, 6] {
        let foot = mesh::cuboid(Vec3::new(0.24, 0.07, 0.1), 4.0);
        add(foot, at(places[shin] + Vec3::new(0.06, -0.47, 0.0)), &|_| only(shin));
    }
    (body, joints, weights)
}

fn at(place: Vec3) -> Affine3A {
    Affine3A::from_translation(place)
}

/// One joint carries the vertex alone.
fn only(joint: usize) -> ([u16; 4], [f32; 4]) {
    ([joint as u16, 0, 0, 0], [1.0, 0.0, 0.0, 0.0])
}

/// A vertex `height` above the joint where bone `below` meets bone `above`: `below` alone
/// under the blend, `above` alone over it, smoothly shared within it.
fn between(below: usize, above: usize, height: f32) -> ([u16; 4], [f32; 4]) {
    let s = ((height / BLEND + 1.0) / 2.0).clamp(0.0, 1.0);
    let share = s * s * (3.0 - 2.0 * s);
    ([below as u16, above as u16, 0, 0], [1.0 - share, share, 0.0, 0.0])
}

/// The stride: each joint's rotation at `t` seconds, two strides a second, as fast a run as
/// the hips' pace needs (a foot on the ground then moves about as fast backwards as the hips
/// forwards). Legs and arms swing about z (the axis across the figure's path) in opposition,
/// knees bend on the swing, the chest turns against the hips about y.
fn rotation(joint: usize, t: f32) -> Quat {
    let phase = 2.0 * TAU * t;
    if joint == CHEST {
        return Quat::from_rotation_y(0.15 * phase.sin());
    }
    let angle = match joint {
        3 => 0.6 * phase.sin(),
        5 => -0.6 * phase.sin(),
        4 => -(phase + 1.2).sin().max(0.0) - 0.1,
        6 => -(phase + 1.2 + PI).sin().max(0.0) - 0.1,
        7 => -0.5 * phase.sin(),
        9 => 0.5 * phase.sin(),
        8 | 10 => 0.5,
        HEAD => 0.05 * (2.0 * phase).sin(),
        _ => 0.0,
    };
    Quat::from_rotation_z(angle)
}

/// Adds the figure (the mesh `figure`), striding `distance` metres along +x in `seconds` from
/// `start` (the hips at rest), as the animation `name`.
pub(super) fn walker(b: &mut Builder, name: &str, material: usize, start: Vec3, distance: f32, seconds: f32) {
    let places = rest_places();
    // Joints are added children first: a node names its children when it is added.
    let mut nodes = [usize::MAX; 11];
    for i in (0..JOINTS.len()).rev() {
        let children: Vec<usize> =
            (0..JOINTS.len()).filter(|&c| JOINTS[c].1 == Some(i)).map(|c| nodes[c]).collect();
        let offset = if i == HIPS { start.to_array() } else { JOINTS[i].2 };
        nodes[i] = b.writer.add_joint(JOINTS[i].0, offset, &children);
    }
    let (mesh, vertex_joints, vertex_weights) = body();
    let inverse_binds = places.iter().map(|p| Mat4::from_translation(-*p - start).to_cols_array()).collect();
    let skin = SkinDesc { joints: nodes.to_vec(), inverse_binds, vertex_joints, vertex_weights };
    let bound = mesh.positions.iter().map(|p| (Vec3::from(*p) + start).to_array()).collect();
    b.writer.add_skinned_mesh("figure", &Mesh { positions: bound, ..mesh }, material, &skin);
    // Keys every fortieth of a second: the swing's arcs stay round between them.
    let times: Vec<f32> = (0..=(seconds * 40.0) as u32).map(|k| k as f32 / 40.0).collect();
    let mut channels = vec![Channel {
        node: nodes[HIPS],
        path: "translation",
        times: times.clone(),
        values: (times.iter())
            .flat_map(|&t| {
                (start + Vec3::new(distance * t / seconds, 0.03 * (4.0 * TAU * t).cos(), 0.0)).to_array()
            })
            .collect(),
    }];
    for (joint, &node) in nodes.iter().enumerate().skip(1) {
        let values = times.iter().flat_map(|&t| rotation(joint, t).to_array()).collect();
        channels.push(Channel { node, path: "rotation", times: times.clone(), values });
    }
    b.writer.add_animation(name, &channels);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_vertex_weighs_one_and_the_knees_are_shared() {
        let (mesh, joints, weights) = body();
        assert_eq!((joints.len(), weights.len()), (mesh.positions.len(), mesh.positions.len()));
        assert!(weights.iter().all(|w| (w.iter().sum::<f32>() - 1.0).abs() < 1e-6));
        // Some vertices of each leg blend thigh and shin: the knee bends its skin.
        for (thigh, shin) in [(3u16, 4u16), (5, 6)] {
            let shared = joints
                .iter()
                .zip(&weights)
                .filter(|(j, w)| j[..2] == [shin, thigh] && w[0] > 0.1 && w[1] > 0.1);
            assert!(shared.count() > 16, "joints {thigh} and {shin}");
        }
    }
}
