//! Posing a scene whose animation plays: the vertices of the nodes it moves, carried from where
//! the importer baked them to where they lie at a time, with the normals and tangents turned
//! along. The G-buffer pass reads each vertex's position at the frame before beside its own, so
//! its motion vectors hold the objects' motion as well as the camera's.

use std::ops::Range;

use glam::{DMat3, DMat4, DVec3, Vec3};

use super::animation::{Rig, Track};
use super::{MAX_COORDINATE, Scene, Vertex};

/// What posing needs: the tracks, the rig, and the vertices as baked.
#[derive(Debug, Clone)]
pub struct Poser {
    tracks: Vec<Track>,
    rig: Rig,
    origin: DVec3,
    rest: Vec<Vertex>,
    rest_tangents: Vec<[f32; 4]>,
}

/// The vertices of one moved node at a time: where its range starts, and its vertices (with
/// their tangents, where the scene has them).
#[derive(Debug, Clone, PartialEq)]
pub struct Moved {
    pub first: usize,
    pub vertices: Vec<Vertex>,
    pub tangents: Vec<[f32; 4]>,
}

impl Poser {
    /// The poser of the scene's playing animation; none where no animation plays.
    pub fn of(scene: &Scene) -> Option<Poser> {
        Some(Poser {
            tracks: scene.playing_tracks()?.to_vec(),
            rig: scene.rig.clone(),
            origin: scene.origin,
            rest: scene.vertices.clone(),
            rest_tangents: scene.tangents.clone(),
        })
    }

    /// Each moved node's change at `time`, in the scene's coordinates (relative to its origin).
    fn changes(&self, time: f64) -> Vec<(Range<usize>, DMat4)> {
        let (to, from) = (DMat4::from_translation(-self.origin), DMat4::from_translation(self.origin));
        self.rig
            .moves(&self.tracks, time)
            .into_iter()
            .map(|(range, change)| (range, to * change * from))
            .collect()
    }

    /// The moved nodes' vertices at `time`.
    pub fn vertices_at(&self, time: f64) -> Vec<Moved> {
        self.changes(time)
            .into_iter()
            .map(|(range, change)| {
                let linear = DMat3::from_mat4(change);
                let normals = linear.inverse().transpose();
                let turn =
                    |m: DMat3, v: [f32; 3]| (m * Vec3::from(v).as_dvec3()).normalize_or_zero().as_vec3();
                let vertices = self.rest[range.clone()]
                    .iter()
                    .map(|v| Vertex {
                        position: moved(change, v.position),
                        normal: turn(normals, v.normal).to_array(),
                        ..*v
                    })
                    .collect();
                let tangents = self
                    .rest_tangents
                    .get(range.clone())
                    .unwrap_or_default()
                    .iter()
                    .map(|t| {
                        let xyz = turn(linear, [t[0], t[1], t[2]]);
                        [xyz.x, xyz.y, xyz.z, t[3]]
                    })
                    .collect();
                Moved { first: range.start, vertices, tangents }
            })
            .collect()
    }

    /// Checks every pose the animation takes against the bounds a rest pose keeps (finite and
    /// within ±[`MAX_COORDINATE`] in world space): at each channel's keyframes, and for a cubic
    /// spline between them ([`Track::checked_times`]). On failure, the first pose beyond them:
    /// the channel, the keyframe, the node it animates and the node whose vertices it carries.
    pub fn check(&self) -> Result<(), String> {
        // Each moved range's box once; each time once (channels often share their keyframe
        // times, and a pose that passed for one channel passes for the next).
        let boxes: std::collections::HashMap<Range<usize>, [DVec3; 2]> = (self.rig.nodes.iter())
            .flat_map(|rest| rest.vertices.iter().filter_map(|r| Some((r.clone(), self.bounds(r.clone())?))))
            .collect();
        let mut checked = std::collections::HashSet::new();
        for (channel, track) in self.tracks.iter().enumerate() {
            for (key, time) in track.checked_times().into_iter().filter(|(_, t)| checked.insert(t.to_bits()))
            {
                for (rest, change) in self.rig.node_changes(&self.tracks, time) {
                    let out = |r: &Range<usize>| beyond(boxes.get(r)?, change);
                    if let Some(place) = rest.vertices.iter().find_map(out) {
                        return Err(format!(
                            "channels[{channel}] ({} of nodes[{}]), {key} (t = {time} s), carries the vertices of \
                             nodes[{}] to {place}, beyond ±{MAX_COORDINATE:e} (the bounds of a scene at rest)",
                            track.property.name(),
                            track.node,
                            rest.node
                        ));
                    }
                }
            }
        }
        Ok(())
    }

    /// The world-space box of the baked vertices `range`; none for an empty range.
    fn bounds(&self, range: Range<usize>) -> Option<[DVec3; 2]> {
        let positions = self.rest.get(range)?.iter().map(|v| Vec3::from(v.position).as_dvec3() + self.origin);
        positions.fold(None, |bounds, p| match bounds {
            None => Some([p, p]),
            Some([lo, hi]) => Some([lo.min(p), hi.max(p)]),
        })
    }

    /// The moved nodes' positions at `time`: where their range starts, and the positions.
    pub fn positions_at(&self, time: f64) -> Vec<(usize, Vec<[f32; 3]>)> {
        self.changes(time)
            .into_iter()
            .map(|(range, change)| {
                let first = range.start;
                (first, self.rest[range].iter().map(|v| moved(change, v.position)).collect())
            })
            .collect()
    }
}

/// A corner of the box `[lo, hi]` that `change` carries out of bounds, in world space. The
/// box's image is a parallelepiped whose farthest points are corners.
fn beyond(&[lo, hi]: &[DVec3; 2], change: DMat4) -> Option<String> {
    (0..8).find_map(|corner: u32| {
        let pick = |bit: u32, a: f64, b: f64| if corner & bit == 0 { a } else { b };
        let at = DVec3::new(pick(1, lo.x, hi.x), pick(2, lo.y, hi.y), pick(4, lo.z, hi.z));
        let moved = change.transform_point3(at);
        (!moved.is_finite() || moved.abs().max_element() > MAX_COORDINATE).then(|| place(moved))
    })
}

/// A place in a message: `(1.000e30, -1.000, 0.200)`.
fn place(v: DVec3) -> String {
    let short = |x: f64| if x.is_finite() && x.abs() < 1e6 { format!("{x:.3}") } else { format!("{x:.3e}") };
    format!("({}, {}, {})", short(v.x), short(v.y), short(v.z))
}

fn moved(change: DMat4, position: [f32; 3]) -> [f32; 3] {
    change.transform_point3(Vec3::from(position).as_dvec3()).as_vec3().to_array()
}
