//! Posing a scene whose animation plays: the vertices of the nodes it moves, carried from where
//! the importer baked them to where they lie at a time, with the normals and tangents turned
//! along. The G-buffer pass reads each vertex's position at the frame before beside its own, so
//! its motion vectors hold the objects' motion as well as the camera's.

use std::ops::Range;

use glam::{DMat3, DMat4, DVec3, Vec3};

use super::animation::{Rig, Track};
use super::{Scene, Vertex};

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

fn moved(change: DMat4, position: [f32; 3]) -> [f32; 3] {
    change.transform_point3(Vec3::from(position).as_dvec3()).as_vec3().to_array()
}
