//! Posing a scene whose animation plays: the vertices of the nodes it moves, carried from where
//! the importer baked them to where they lie at a time, with the normals and tangents turned
//! along, and the vertices of the skins whose joints it moves ([`super::skin`]). The G-buffer
//! pass reads each vertex's position at the frame before beside its own, so its motion vectors
//! hold the objects' motion as well as the camera's.

use std::ops::Range;

use glam::{DMat3, DMat4, DVec3, Vec3};

use super::animation::{Rig, Track};
use super::skin::BindPose;
use super::{Camera, MAX_COORDINATE, Scene, Vertex};

/// What posing needs: the tracks, the rig, the vertices as baked, and the moved skins' vertices
/// in their bind pose.
#[derive(Debug, Clone)]
pub struct Poser {
    tracks: Vec<Track>,
    /// How messages name each track (`channels[2]`).
    channel_names: Vec<String>,
    rig: Rig,
    origin: DVec3,
    rest: Vec<Vertex>,
    rest_tangents: Vec<[f32; 4]>,
    skins: Vec<BindPose>,
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
    /// The poser of the scene's playing animations; none where no animation plays.
    pub fn of(scene: &Scene) -> Option<Poser> {
        let playing = scene.playing.as_ref()?;
        let tracks = playing.tracks.clone();
        let rest_worlds = scene.rig.rest_worlds();
        let skins = (scene.rig.moved_skins(&tracks).into_iter())
            .map(|skin| BindPose::new(skin, &rest_worlds, scene.origin, &scene.vertices, &scene.tangents))
            .collect();
        Some(Poser {
            tracks,
            channel_names: playing.channel_names.clone(),
            rig: scene.rig.clone(),
            origin: scene.origin,
            rest: scene.vertices.clone(),
            rest_tangents: scene.tangents.clone(),
            skins,
        })
    }

    /// The rig's world transforms at `time`, where a skin needs them.
    fn worlds(&self, time: f64) -> Vec<DMat4> {
        if self.skins.is_empty() { Vec::new() } else { self.rig.worlds(&self.tracks, time) }
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

    /// The moved nodes' and skins' vertices at `time`.
    pub fn vertices_at(&self, time: f64) -> Vec<Moved> {
        let worlds = self.worlds(time);
        let skinned = self.skins.iter().flat_map(|skin| {
            let posed = skin.posed(&worlds, self.origin, &self.rest, &self.rest_tangents);
            posed.into_iter().map(|(first, vertices, tangents)| Moved { first, vertices, tangents })
        });
        let mut moved = self.node_vertices_at(time);
        moved.extend(skinned);
        moved
    }

    /// The moved nodes' vertices at `time`.
    fn node_vertices_at(&self, time: f64) -> Vec<Moved> {
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
    /// the channel, the keyframe, the node it animates and the node (or skin) whose vertices it
    /// carries. A skin whose joints flatten a vertex at rest fails too.
    pub fn check(&self) -> Result<(), String> {
        for skin in &self.skins {
            skin.check_rest()?;
        }
        // Each moved range's box once; each time once (channels often share their keyframe
        // times, and a pose that passed for one channel passes for the next).
        let boxes: std::collections::HashMap<Range<usize>, [DVec3; 2]> = (self.rig.nodes.iter())
            .flat_map(|rest| rest.vertices.iter().filter_map(|r| Some((r.clone(), self.bounds(r.clone())?))))
            .collect();
        let mut checked = std::collections::HashSet::new();
        for (channel, track) in self.tracks.iter().enumerate() {
            for (key, time) in track.checked_times().into_iter().filter(|(_, t)| checked.insert(t.to_bits()))
            {
                let Some(what) = self.beyond(&self.tracks, &boxes, time) else { continue };
                // The pose is every channel's: name the one that puts it out by itself, with its
                // own name for the time, where one does.
                let alone = |c: &usize| self.beyond(&self.tracks[*c..=*c], &boxes, time).is_some();
                let (channel, key) = match (0..self.tracks.len()).find(alone) {
                    Some(c) if c != channel => (c, self.tracks[c].name_of(time)),
                    _ => (channel, key),
                };
                let track = &self.tracks[channel];
                return Err(format!(
                    "{} ({} of nodes[{}]), {key} (t = {time} s), carries {what}, beyond \
                     ±{MAX_COORDINATE:e} (the bounds of a scene at rest)",
                    self.channel_names[channel],
                    track.property.name(),
                    track.node,
                ));
            }
        }
        Ok(())
    }

    /// What of the scene the pose of `tracks` at `time` carries beyond the bounds, if anything:
    /// a moved node's vertices, or a skin's vertex.
    fn beyond(
        &self,
        tracks: &[Track],
        boxes: &std::collections::HashMap<Range<usize>, [DVec3; 2]>,
        time: f64,
    ) -> Option<String> {
        self.node_beyond(tracks, boxes, time).or_else(|| self.skin_beyond(tracks, time))
    }

    /// The first moved node whose vertices (`boxes`: each range's box) lie beyond the bounds at
    /// `time`: `the vertices of nodes[2] to (…)`.
    fn node_beyond(
        &self,
        tracks: &[Track],
        boxes: &std::collections::HashMap<Range<usize>, [DVec3; 2]>,
        time: f64,
    ) -> Option<String> {
        self.rig.node_changes(tracks, time).into_iter().find_map(|(rest, change)| {
            let out = |r: &Range<usize>| beyond(boxes.get(r)?, change);
            let place = rest.vertices.iter().find_map(out)?;
            Some(format!("the vertices of nodes[{}] to {place}", rest.node))
        })
    }

    /// The first moved skin with a vertex beyond the bounds at `time`: `vertex 12 of skins[0]
    /// (of nodes[4]) to (…)`.
    fn skin_beyond(&self, tracks: &[Track], time: f64) -> Option<String> {
        if self.skins.is_empty() {
            return None;
        }
        let worlds = self.rig.worlds(tracks, time);
        self.skins.iter().find_map(|skin| {
            let positions = skin.positions(&worlds, self.origin);
            let mut placed = positions
                .iter()
                .flat_map(|(first, p)| p.iter().enumerate().map(move |(i, p)| (first + i, p)));
            let (vertex, at) = placed.find(|(_, p)| out_of_bounds(**p + self.origin))?;
            Some(format!("vertex {vertex} of {} to {}", skin.skin.label(), place(*at + self.origin)))
        })
    }

    /// The world-space box of the baked vertices `range`; none for an empty range.
    fn bounds(&self, range: Range<usize>) -> Option<[DVec3; 2]> {
        let positions = self.rest.get(range)?.iter().map(|v| Vec3::from(v.position).as_dvec3() + self.origin);
        positions.fold(None, |bounds, p| match bounds {
            None => Some([p, p]),
            Some([lo, hi]) => Some([lo.min(p), hi.max(p)]),
        })
    }

    /// The moved nodes' and skins' positions at `time`: where each range starts, and the
    /// positions.
    pub fn positions_at(&self, time: f64) -> Vec<(usize, Vec<[f32; 3]>)> {
        let nodes = self.changes(time).into_iter().map(|(range, change)| {
            let first = range.start;
            (first, self.rest[range].iter().map(|v| moved(change, v.position)).collect())
        });
        let worlds = self.worlds(time);
        let skins = self
            .skins
            .iter()
            .flat_map(|skin| skin.positions(&worlds, self.origin))
            .map(|(first, p)| (first, p.into_iter().map(|p| p.as_vec3().to_array()).collect()));
        nodes.chain(skins).collect()
    }

    /// Whether the animation moves anything a frame shows: a node's vertices, a skin's, or the
    /// camera aabench renders from. On failure, the nodes it moves and why none of them shows.
    pub fn check_moves_something(&self, camera: FileCamera) -> Result<(), String> {
        let shows = camera == FileCamera::Moved
            || !self.skins.is_empty()
            || !self.rig.node_changes(&self.tracks, 0.0).is_empty();
        if shows {
            return Ok(());
        }
        let mut nodes: Vec<usize> = self.tracks.iter().map(|t| t.node).collect();
        nodes.sort_unstable();
        nodes.dedup();
        let nodes: Vec<String> = nodes.iter().map(|n| format!("nodes[{n}]")).collect();
        let moved = self.rig.moved(&self.tracks);
        let moved_nodes: Vec<usize> = self
            .rig
            .nodes
            .iter()
            .zip(&moved)
            .filter(|(_, moved)| **moved)
            .map(|(rest, _)| rest.node)
            .collect();
        let mut why: Vec<String> = (self.rig.unseen.iter())
            .filter(|(node, _)| moved_nodes.contains(node))
            .map(|&(node, unseen)| unseen.why(node))
            .collect();
        if let FileCamera::Replaced(node) = camera {
            why.push(format!(
                "nodes[{node}] holds the file's camera, which the manifest's `camera` replaces"
            ));
        }
        if why.is_empty() {
            return Err(format!(
                "moves only {}, which hold no geometry and no camera, nor do the nodes below them: nothing \
                 in the frame would move",
                nodes.join(", ")
            ));
        }
        Err(format!("moves only {}: {}: nothing in the frame would move", nodes.join(", "), why.join("; ")))
    }
}

/// The file's camera as an animation's check sees it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FileCamera {
    /// The animation moves the camera that the frames are rendered from.
    Moved,
    /// The animation moves the file's camera, on `nodes[n]`, but the manifest's `camera`
    /// replaces it.
    Replaced(usize),
    /// The animation leaves it where it is, or the file has none.
    Still,
}

/// The file's camera as the playing animation moves it (the node that holds it, or one above).
#[derive(Debug, Clone)]
pub struct CameraPath {
    tracks: Vec<Track>,
    rig: Rig,
    place: usize,
    origin: DVec3,
}

impl CameraPath {
    /// The path of the scene's camera; none where no animation plays or it leaves the camera
    /// where it is.
    pub fn of(scene: &Scene) -> Option<CameraPath> {
        let tracks = scene.playing_tracks()?.to_vec();
        let node = scene.camera_node?;
        let place = scene.rig.nodes.iter().position(|n| n.node == node)?;
        let rig = Rig { nodes: scene.rig.nodes.clone(), ..Rig::default() };
        rig.moved(&tracks)[place].then_some(CameraPath { tracks, rig, place, origin: scene.origin })
    }

    /// The camera at `time`: `rest` (its lens and clip planes) placed where its node lies.
    pub fn camera(&self, rest: &Camera, time: f64) -> Camera {
        let world = self.rig.worlds(&self.tracks, time)[self.place];
        Camera {
            position: world.transform_point3(DVec3::ZERO) - self.origin,
            forward: world.transform_vector3(-DVec3::Z),
            up: world.transform_vector3(DVec3::Y),
            ..*rest
        }
    }
}

/// A corner of the box `[lo, hi]` that `change` carries out of bounds, in world space. The
/// box's image is a parallelepiped whose farthest points are corners.
fn beyond(&[lo, hi]: &[DVec3; 2], change: DMat4) -> Option<String> {
    (0..8).find_map(|corner: u32| {
        let pick = |bit: u32, a: f64, b: f64| if corner & bit == 0 { a } else { b };
        let at = DVec3::new(pick(1, lo.x, hi.x), pick(2, lo.y, hi.y), pick(4, lo.z, hi.z));
        let moved = change.transform_point3(at);
        out_of_bounds(moved).then(|| place(moved))
    })
}

/// Whether a world-space point lies beyond the bounds of a scene at rest.
fn out_of_bounds(p: DVec3) -> bool {
    !p.is_finite() || p.abs().max_element() > MAX_COORDINATE
}

/// A place in a message: `(1.000e30, -1.000, 0.200)`.
fn place(v: DVec3) -> String {
    let short = |x: f64| if x.is_finite() && x.abs() < 1e6 { format!("{x:.3}") } else { format!("{x:.3e}") };
    format!("({}, {}, {})", short(v.x), short(v.y), short(v.z))
}

fn moved(change: DMat4, position: [f32; 3]) -> [f32; 3] {
    change.transform_point3(Vec3::from(position).as_dvec3()).as_vec3().to_array()
}
