//! Moving objects: a glTF file's animations, sampled at a time, and the node tree they move.
//!
//! An animation moves nodes by translation, rotation and scale tracks, each sampled step-wise,
//! linearly (rotations by spherical interpolation) or along cubic Hermite splines (glTF 2.0,
//! appendix C), held at its first value before its first keyframe and at its last after. The
//! importer bakes node transforms into world-space vertices, so a node that moves carries the
//! ranges of vertices its meshes gave and the world transform they were baked with: a pose moves
//! them by the change of that transform ([`Rig::moves`]). A skinned mesh's vertices follow its
//! joints instead ([`super::skin`]).

use std::ops::Range;

use glam::{DMat4, DQuat, DVec3};

use super::skin::Skin;

/// One of a file's animations: how messages name it, and its tracks or why it cannot play.
#[derive(Debug, Clone, PartialEq)]
pub struct Animation {
    /// Its `name`, where the file gives one.
    pub name: Option<String>,
    pub tracks: Result<Vec<Track>, String>,
}

impl Animation {
    /// `animations[2] ("walk")`, as messages name it.
    pub fn label(&self, index: usize) -> String {
        match &self.name {
            Some(name) => format!("animations[{index}] ({name:?})"),
            None => format!("animations[{index}]"),
        }
    }
}

/// What a track moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Property {
    Translation,
    Rotation,
    Scale,
}

impl Property {
    /// Its glTF name: `translation`, `rotation` or `scale`.
    pub fn name(self) -> &'static str {
        match self {
            Property::Translation => "translation",
            Property::Rotation => "rotation",
            Property::Scale => "scale",
        }
    }
}

/// How a track's values run between keyframes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Interpolation {
    Step,
    Linear,
    CubicSpline,
}

/// One channel of an animation with its sampler: a node's property over time. Values are
/// xyz (translations and scales, w unused) or quaternions xyzw; a cubic spline's keyframe has
/// three (in-tangent, value, out-tangent).
#[derive(Debug, Clone, PartialEq)]
pub struct Track {
    pub node: usize,
    pub property: Property,
    pub interpolation: Interpolation,
    pub times: Vec<f32>,
    pub values: Vec<[f32; 4]>,
}

impl Track {
    /// Checks what the importer cannot leave to the crate: times finite and strictly
    /// increasing, as many values as the interpolation needs, every value finite, rotations
    /// not zero. On failure, why.
    pub fn check(&self) -> Result<(), String> {
        if self.times.is_empty() {
            return Err("no keyframes".into());
        }
        if let Some(i) = self.times.iter().position(|t| !t.is_finite()) {
            return Err(format!("keyframe time {i} is {}, not finite", self.times[i]));
        }
        if let Some(i) = self.times.windows(2).position(|w| w[1] <= w[0]) {
            return Err(format!(
                "keyframe times must increase: time {} is {} after {}",
                i + 1,
                self.times[i + 1],
                self.times[i]
            ));
        }
        let per_keyframe = if self.interpolation == Interpolation::CubicSpline { 3 } else { 1 };
        if self.values.len() != per_keyframe * self.times.len() {
            return Err(format!(
                "{} keyframe times need {} output values under {:?} interpolation, the sampler has {}",
                self.times.len(),
                per_keyframe * self.times.len(),
                self.interpolation,
                self.values.len()
            ));
        }
        if let Some(i) = self.values.iter().position(|v| !v.iter().all(|c| c.is_finite())) {
            return Err(format!("output value {i} is {:?}, not finite", self.values[i]));
        }
        if self.property == Property::Rotation {
            let zero = |v: &&[f32; 4]| v.iter().all(|&c| c == 0.0);
            if let Some(i) = self.keyframe_values().position(|v| zero(&v)) {
                return Err(format!("rotation {i} is the zero quaternion, which turns nothing"));
            }
        }
        Ok(())
    }

    /// The keyframe values without a cubic spline's tangents.
    fn keyframe_values(&self) -> impl Iterator<Item = &[f32; 4]> {
        let (skip, step) = if self.interpolation == Interpolation::CubicSpline { (1, 3) } else { (0, 1) };
        self.values.iter().skip(skip).step_by(step)
    }

    /// The times at which a pose of this track is checked, each with its name: every keyframe,
    /// and for a cubic spline the middle between two keys too, and every time between two keys
    /// where a coordinate of a translation or a scale turns (its tangents can carry it far past
    /// both keys, and with equal tangents it is back at them halfway).
    pub fn checked_times(&self) -> Vec<(String, f64)> {
        let keys = self.times.iter().enumerate().map(|(i, &t)| (format!("keyframe {i}"), f64::from(t)));
        let mut checked: Vec<(String, f64)> = keys.collect();
        if self.interpolation != Interpolation::CubicSpline {
            return checked;
        }
        for (i, pair) in self.times.windows(2).enumerate() {
            let (t0, t1) = (f64::from(pair[0]), f64::from(pair[1]));
            checked.push((format!("halfway between keyframes {i} and {}", i + 1), (t0 + t1) / 2.0));
            if self.property != Property::Rotation {
                let turns = self.turns_between(i);
                let name = format!("where the spline between keyframes {i} and {} turns", i + 1);
                checked.extend(turns.into_iter().map(|s| (name.clone(), t0 + s * (t1 - t0))));
            }
        }
        checked
    }

    /// What this track calls `time` among the times it is checked at (`keyframe 4`), or where
    /// it lies against its keyframes.
    pub fn name_of(&self, time: f64) -> String {
        if let Some((name, _)) = self.checked_times().into_iter().find(|(_, t)| *t == time) {
            return name;
        }
        let after = self.times.partition_point(|&t| f64::from(t) <= time);
        match after {
            0 => "before keyframe 0".into(),
            k if k == self.times.len() => format!("after keyframe {}", k - 1),
            k => format!("between keyframes {} and {k}", k - 1),
        }
    }

    /// The fractions `s` in (0, 1) of the cubic segment from keyframe `k` at which a coordinate
    /// of its value is at a maximum or a minimum: the roots of the derivative of the Hermite
    /// polynomial, `a s² + b s + c`.
    fn turns_between(&self, k: usize) -> Vec<f64> {
        let value = |i: usize| self.values[i].map(f64::from);
        let (p0, m0, m1, p1) =
            (value(3 * k + 1), value(3 * k + 2), value(3 * (k + 1)), value(3 * (k + 1) + 1));
        let span = f64::from(self.times[k + 1] - self.times[k]);
        let mut turns = Vec::new();
        for i in 0..3 {
            let (m0, m1) = (span * m0[i], span * m1[i]);
            let a = 6.0 * (p0[i] - p1[i]) + 3.0 * (m0 + m1);
            let b = 6.0 * (p1[i] - p0[i]) - 4.0 * m0 - 2.0 * m1;
            let c = m0;
            turns.extend(quadratic_roots(a, b, c).into_iter().filter(|s| *s > 0.0 && *s < 1.0));
        }
        turns
    }

    /// The track's value at `time` seconds: xyz, or a unit quaternion xyzw.
    pub fn sample(&self, time: f64) -> [f64; 4] {
        let times = &self.times;
        let value = |i: usize| self.values[i].map(f64::from);
        let key = |k: usize| match self.interpolation {
            Interpolation::CubicSpline => value(3 * k + 1),
            _ => value(k),
        };
        let last = times.len() - 1;
        let sampled = if time <= f64::from(times[0]) {
            key(0)
        } else if time >= f64::from(times[last]) {
            key(last)
        } else {
            // The keyframe at or before `time`, and the one after.
            let k = times.partition_point(|&t| f64::from(t) <= time) - 1;
            let (t0, t1) = (f64::from(times[k]), f64::from(times[k + 1]));
            let span = t1 - t0;
            let s = (time - t0) / span;
            match self.interpolation {
                Interpolation::Step => key(k),
                Interpolation::Linear if self.property == Property::Rotation => slerp(key(k), key(k + 1), s),
                Interpolation::Linear => lerp(key(k), key(k + 1), s),
                Interpolation::CubicSpline => {
                    hermite(key(k), value(3 * k + 2), key(k + 1), value(3 * (k + 1)), s, span)
                }
            }
        };
        if self.property == Property::Rotation { normalized(sampled) } else { sampled }
    }

    /// Whether some keyframe's scale turns the node inside out against its `rest` scale
    /// (x·y·z of the other sign) or flattens it (zero).
    pub fn turns_inside_out(&self, rest: DVec3) -> bool {
        let sign = rest.x * rest.y * rest.z;
        self.property == Property::Scale
            && self.keyframe_values().any(|v| f64::from(v[0] * v[1] * v[2]) * sign <= 0.0)
    }
}

fn lerp(a: [f64; 4], b: [f64; 4], s: f64) -> [f64; 4] {
    std::array::from_fn(|i| a[i] + (b[i] - a[i]) * s)
}

/// Spherical interpolation along the shorter arc.
fn slerp(a: [f64; 4], b: [f64; 4], s: f64) -> [f64; 4] {
    let (a, b) = (DQuat::from_array(normalized(a)), DQuat::from_array(normalized(b)));
    a.slerp(b, s).to_array()
}

/// glTF's cubic Hermite spline between values `p0` and `p1` with out-tangent `m0` and
/// in-tangent `m1` (per second; `span` seconds apart), at the share `s` of the way.
fn hermite(p0: [f64; 4], m0: [f64; 4], p1: [f64; 4], m1: [f64; 4], s: f64, span: f64) -> [f64; 4] {
    let (s2, s3) = (s * s, s * s * s);
    let (h00, h10, h01, h11) = (2.0 * s3 - 3.0 * s2 + 1.0, s3 - 2.0 * s2 + s, -2.0 * s3 + 3.0 * s2, s3 - s2);
    std::array::from_fn(|i| h00 * p0[i] + h10 * span * m0[i] + h01 * p1[i] + h11 * span * m1[i])
}

/// The real roots of `a x² + b x + c` (of `b x + c` where `a` is 0); none where every
/// coefficient is 0, since then no point is a turn.
fn quadratic_roots(a: f64, b: f64, c: f64) -> Vec<f64> {
    if a == 0.0 {
        return if b == 0.0 { Vec::new() } else { vec![-c / b] };
    }
    let discriminant = b * b - 4.0 * a * c;
    if discriminant < 0.0 {
        return Vec::new();
    }
    let root = discriminant.sqrt();
    vec![(-b - root) / (2.0 * a), (-b + root) / (2.0 * a)]
}

fn normalized(q: [f64; 4]) -> [f64; 4] {
    let length = q.iter().map(|c| c * c).sum::<f64>().sqrt();
    if length > 0.0 { q.map(|c| c / length) } else { [0.0, 0.0, 0.0, 1.0] }
}

/// A node's transform in its parent's space, as the file gives it when nothing animates it.
#[derive(Debug, Clone, PartialEq)]
pub struct RestNode {
    /// Its place in [`Rig::nodes`] of its parent: parents come first.
    pub parent: Option<usize>,
    /// The glTF node index.
    pub node: usize,
    pub matrix: DMat4,
    pub translation: DVec3,
    pub rotation: DQuat,
    pub scale: DVec3,
    /// The vertices its meshes gave (their own range, then the copies that tangent generation
    /// split off at the end of the list), and the world transform they were baked with.
    pub vertices: Vec<Range<usize>>,
    pub world: DMat4,
}

/// The default scene's node trees as the importer walked them: parents before children; and
/// the skinned meshes their joints carry.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Rig {
    pub nodes: Vec<RestNode>,
    pub skins: Vec<Skin>,
    /// The nodes (glTF indices) that hold something no move of their own shows in a frame.
    pub unseen: Vec<(usize, Unseen)>,
}

/// What a node holds that moving the node does not move in a frame: why an animation of such
/// nodes alone moves nothing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unseen {
    /// A skinned mesh: its joints place its vertices, and glTF ignores its own node's transform.
    SkinnedMesh,
    /// An orthographic camera: aabench renders from the file's first perspective camera.
    OrthographicCamera,
    /// A perspective camera after the first, which aabench renders from.
    LaterCamera,
}

impl Unseen {
    /// Why `nodes[node]`, which holds this, moves nothing in a frame.
    pub fn why(self, node: usize) -> String {
        match self {
            Unseen::SkinnedMesh => format!(
                "nodes[{node}] holds a skinned mesh, which its joints place (glTF ignores the transform of a \
                 skinned mesh's node), and the animation moves none of them"
            ),
            Unseen::OrthographicCamera => format!(
                "nodes[{node}] holds an orthographic camera, and aabench renders from the file's first \
                 perspective camera"
            ),
            Unseen::LaterCamera => format!(
                "nodes[{node}] holds a camera after the first, and aabench renders from the file's first \
                 perspective camera"
            ),
        }
    }
}

impl Rig {
    /// Each node that carries vertices and that `tracks` move at `time` (itself or a node above
    /// it): its vertex range and the change of its world transform since the vertices were
    /// baked, which maps a baked vertex to where it lies at `time`.
    pub fn moves(&self, tracks: &[Track], time: f64) -> Vec<(Range<usize>, DMat4)> {
        let mut moves = Vec::new();
        for (rest, change) in self.node_changes(tracks, time) {
            moves.extend(rest.vertices.iter().filter(|r| !r.is_empty()).map(|r| (r.clone(), change)));
        }
        moves
    }

    /// Each node with vertices that `tracks` move at `time`, with the change of its world
    /// transform since its vertices were baked.
    pub fn node_changes(&self, tracks: &[Track], time: f64) -> Vec<(&RestNode, DMat4)> {
        let (moved, world) = (self.moved(tracks), self.worlds(tracks, time));
        (self.nodes.iter().enumerate())
            .filter(|(i, rest)| moved[*i] && rest.vertices.iter().any(|r| !r.is_empty()))
            .map(|(i, rest)| (rest, world[i] * rest.world.inverse()))
            .collect()
    }

    /// Every node's world transform with `tracks` sampled at `time`, in [`Rig::nodes`] order.
    pub fn worlds(&self, tracks: &[Track], time: f64) -> Vec<DMat4> {
        let mut world: Vec<DMat4> = Vec::with_capacity(self.nodes.len());
        for rest in &self.nodes {
            let own: Vec<&Track> = tracks.iter().filter(|t| t.node == rest.node).collect();
            let local = if own.is_empty() { rest.matrix } else { animated(rest, &own, time) };
            let parent = rest.parent.map_or(DMat4::IDENTITY, |p| world[p]);
            world.push(parent * local);
        }
        world
    }

    /// Every node's world transform at rest, in [`Rig::nodes`] order.
    pub fn rest_worlds(&self) -> Vec<DMat4> {
        self.nodes.iter().map(|rest| rest.world).collect()
    }

    /// The skins whose joints `tracks` move.
    pub fn moved_skins(&self, tracks: &[Track]) -> Vec<&Skin> {
        let moved = self.moved(tracks);
        self.skins.iter().filter(|skin| skin.joints.iter().any(|&(place, _)| moved[place])).collect()
    }

    /// Which nodes `tracks` move, in [`Rig::nodes`] order: their own, and every node below one.
    pub fn moved(&self, tracks: &[Track]) -> Vec<bool> {
        let mut moved = vec![false; self.nodes.len()];
        for (i, rest) in self.nodes.iter().enumerate() {
            moved[i] = tracks.iter().any(|t| t.node == rest.node) || rest.parent.is_some_and(|p| moved[p]);
        }
        moved
    }

    /// The rest node of glTF node `node`, if the walk reached it.
    pub fn node(&self, node: usize) -> Option<&RestNode> {
        self.nodes.iter().find(|n| n.node == node)
    }

    /// A node with vertices that `tracks` move and whose rest world transform cannot be undone
    /// (a scale of zero at rest): its vertices cannot be carried from where they were baked.
    pub fn singular_mover(&self, tracks: &[Track]) -> Option<usize> {
        let carries = |rest: &RestNode| rest.vertices.iter().any(|r| !r.is_empty());
        self.nodes
            .iter()
            .zip(self.moved(tracks))
            .find(|(rest, moved)| *moved && carries(rest) && rest.world.determinant().abs() < 1e-300)
            .map(|(rest, _)| rest.node)
    }
}

/// A node's local transform with `tracks` (its own) sampled at `time`; what they leave alone
/// keeps its rest value.
fn animated(rest: &RestNode, tracks: &[&Track], time: f64) -> DMat4 {
    let (mut translation, mut rotation, mut scale) = (rest.translation, rest.rotation, rest.scale);
    for track in tracks {
        let [x, y, z, w] = track.sample(time);
        match track.property {
            Property::Translation => translation = DVec3::new(x, y, z),
            Property::Rotation => rotation = DQuat::from_xyzw(x, y, z, w),
            Property::Scale => scale = DVec3::new(x, y, z),
        }
    }
    DMat4::from_scale_rotation_translation(scale, rotation, translation)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn track(property: Property, interpolation: Interpolation, times: &[f32], values: &[[f32; 4]]) -> Track {
        Track { node: 0, property, interpolation, times: times.to_vec(), values: values.to_vec() }
    }

    #[test]
    fn each_interpolation_runs_between_its_keyframes_and_holds_outside_them() {
        let values = [[0.0, 0.0, 0.0, 0.0], [4.0, 2.0, 0.0, 0.0]];
        let linear = track(Property::Translation, Interpolation::Linear, &[1.0, 2.0], &values);
        assert_eq!(linear.sample(1.25)[..2], [1.0, 0.5]);
        assert_eq!(linear.sample(0.0)[0], 0.0, "held before the first keyframe");
        assert_eq!(linear.sample(9.0)[0], 4.0, "held after the last");
        let step = Track { interpolation: Interpolation::Step, ..linear.clone() };
        assert_eq!(step.sample(1.99)[0], 0.0);
        assert_eq!(step.sample(2.0)[0], 4.0);
        // A cubic spline with zero tangents eases in and out: a quarter of the way in time is
        // 15.625 % of the way in value (3s² − 2s³).
        let zero = [0.0; 4];
        let cubic = track(
            Property::Translation,
            Interpolation::CubicSpline,
            &[1.0, 2.0],
            &[zero, values[0], zero, zero, values[1], zero],
        );
        assert!((cubic.sample(1.25)[0] - 4.0 * 0.15625).abs() < 1e-12);
        // With tangents of the line's slope it is the line.
        let slope = [4.0, 2.0, 0.0, 0.0];
        let straight = track(
            Property::Translation,
            Interpolation::CubicSpline,
            &[1.0, 2.0],
            &[slope, values[0], slope, slope, values[1], slope],
        );
        assert!((straight.sample(1.25)[0] - 1.0).abs() < 1e-12);
    }

    #[test]
    fn cubic_tangents_are_per_second_whatever_the_spacing_of_the_keys() {
        // glTF's tangents are rates per second: the segment scales them by its own length. Keys
        // 0.5 s and then 3 s apart, on the line v = 2t with tangents of its slope, stay on it;
        // unscaled tangents would bend the long segment and overshoot the short one.
        let slope = [2.0, 0.0, 0.0, 0.0];
        let at = |t: f32| [2.0 * t, 0.0, 0.0, 0.0];
        let line = track(
            Property::Translation,
            Interpolation::CubicSpline,
            &[0.0, 0.5, 3.5],
            &[slope, at(0.0), slope, slope, at(0.5), slope, slope, at(3.5), slope],
        );
        for time in [0.1, 0.25, 0.4, 1.0, 2.0, 3.0, 3.4] {
            let x = line.sample(time)[0];
            assert!((x - 2.0 * time).abs() < 1e-9, "at {time} s: {x}");
        }
        // Flat tangents ease in and out alike on both: a quarter of each segment's time is
        // 15.625 % of its way in value.
        let zero = [0.0; 4];
        let eased =
            Track { values: vec![zero, at(0.0), zero, zero, at(0.5), zero, zero, at(3.5), zero], ..line };
        assert!((eased.sample(0.125)[0] - 1.0 * 0.15625).abs() < 1e-9);
        assert!((eased.sample(1.25)[0] - (1.0 + 6.0 * 0.15625)).abs() < 1e-9);
    }

    #[test]
    fn rotations_turn_along_the_shorter_arc_at_a_steady_rate() {
        let quarter = glam::Quat::from_rotation_y(std::f32::consts::FRAC_PI_2).to_array();
        // −q is the same turn as q: the interpolation must not go the long way round.
        let negated = quarter.map(|c| -c);
        let turn =
            track(Property::Rotation, Interpolation::Linear, &[0.0, 1.0], &[[0.0, 0.0, 0.0, 1.0], negated]);
        let halfway = DQuat::from_array(turn.sample(0.5));
        let expected = DQuat::from_rotation_y(std::f64::consts::FRAC_PI_4);
        assert!(halfway.angle_between(expected) < 1e-6, "{halfway:?}");
    }

    #[test]
    fn bad_keyframes_are_named() {
        let one = [[0.0; 4]];
        let check = |times: &[f32], values: &[[f32; 4]], interpolation| {
            track(Property::Translation, interpolation, times, values).check().unwrap_err()
        };
        assert!(check(&[1.0, 1.0], &[one[0]; 2], Interpolation::Linear).contains("must increase"));
        assert!(check(&[f32::NAN], &one, Interpolation::Linear).contains("not finite"));
        assert!(check(&[0.0, 1.0], &one, Interpolation::Linear).contains("need 2 output values"));
        assert!(check(&[0.0], &one, Interpolation::CubicSpline).contains("need 3 output values"));
        assert!(check(&[0.0], &[[f32::NAN; 4]], Interpolation::Step).contains("output value 0"));
        let zero = track(Property::Rotation, Interpolation::Linear, &[0.0], &one);
        assert!(zero.check().unwrap_err().contains("zero quaternion"));
    }

    #[test]
    fn a_moved_parent_moves_its_childrens_vertices_and_no_others() {
        let rest = |parent, node, vertices: Range<usize>, translation: DVec3| RestNode {
            parent,
            node,
            matrix: DMat4::from_translation(translation),
            translation,
            rotation: DQuat::IDENTITY,
            scale: DVec3::ONE,
            vertices: vec![vertices],
            world: DMat4::IDENTITY,
        };
        let mut rig = Rig {
            nodes: vec![
                rest(None, 0, 0..0, DVec3::X),
                rest(Some(0), 1, 0..3, DVec3::Y),
                rest(None, 2, 3..6, DVec3::Z),
            ],
            skins: vec![],
            unseen: vec![],
        };
        rig.nodes[1].world = DMat4::from_translation(DVec3::X + DVec3::Y);
        rig.nodes[2].world = DMat4::from_translation(DVec3::Z);
        let slide = track(
            Property::Translation,
            Interpolation::Linear,
            &[0.0, 1.0],
            &[[1.0, 0.0, 0.0, 0.0], [3.0, 0.0, 0.0, 0.0]],
        );
        let moves = rig.moves(&[slide], 0.5);
        assert_eq!(moves.len(), 1, "only the child of the moving node: {moves:?}");
        assert_eq!(moves[0].0, 0..3);
        let moved = moves[0].1.transform_point3(DVec3::X + DVec3::Y);
        assert!((moved - DVec3::new(2.0, 1.0, 0.0)).length() < 1e-12, "{moved}");
    }

    #[test]
    fn a_turned_parent_carries_its_child_in_its_own_frame() {
        // The parent turns a quarter about z at rest; its child sits one unit along the
        // parent's x, so at (0, 1, 0) in the world, where its vertex was baked. Moving the
        // parent to (5, 0, 0) carries the vertex to (5, 1, 0): the orders parent · local and
        // now · rest⁻¹ are the ones that do (translations alone would not tell).
        let turn = DQuat::from_rotation_z(std::f64::consts::FRAC_PI_2);
        let parent_matrix = DMat4::from_quat(turn);
        let child_matrix = DMat4::from_translation(DVec3::X);
        let first = 0..1;
        let rig = Rig {
            nodes: vec![
                RestNode {
                    parent: None,
                    node: 0,
                    matrix: parent_matrix,
                    translation: DVec3::ZERO,
                    rotation: turn,
                    scale: DVec3::ONE,
                    vertices: vec![],
                    world: parent_matrix,
                },
                RestNode {
                    parent: Some(0),
                    node: 1,
                    matrix: child_matrix,
                    translation: DVec3::X,
                    rotation: DQuat::IDENTITY,
                    scale: DVec3::ONE,
                    vertices: vec![first],
                    world: parent_matrix * child_matrix,
                },
            ],
            skins: vec![],
            unseen: vec![],
        };
        let slide = track(Property::Translation, Interpolation::Step, &[0.0], &[[5.0, 0.0, 0.0, 0.0]]);
        let moves = rig.moves(&[slide], 0.0);
        let moved = moves[0].1.transform_point3(DVec3::Y);
        assert!((moved - DVec3::new(5.0, 1.0, 0.0)).length() < 1e-12, "{moved}");
        // A cubic-spline rotation with flat (zero) tangents is valid; a zero value is not.
        let flat = [0.0; 4];
        let key = [0.0, 0.0, 0.0, 1.0];
        let spin = track(Property::Rotation, Interpolation::CubicSpline, &[0.0], &[flat, key, flat]);
        assert_eq!(spin.check(), Ok(()));
        let broken = track(Property::Rotation, Interpolation::CubicSpline, &[0.0], &[key, flat, key]);
        assert!(broken.check().unwrap_err().contains("zero quaternion"));
    }
}
