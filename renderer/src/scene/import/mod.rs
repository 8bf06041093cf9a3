//! glTF 2.0 import through the `gltf` crate: meshes with baked node transforms; base-colour,
//! metallic-roughness, normal, emissive and occlusion textures with `KHR_texture_transform`;
//! factors (emission with `KHR_materials_emissive_strength`), alpha MASK; UVs, normals (flat
//! normals generated where a primitive has none) and tangents (MikkTSpace where a normal-mapped
//! primitive has none); skins; the first camera, and `KHR_lights_punctual` lights.
//!
//! This module walks the node trees and assembles the scene; its parts: `files` (the file and
//! the files it names), `materials`, `primitives` (accessors checked, vertices to world space),
//! `skins` (joints and influences), `tangents`, `lights` (and the camera) and `images`.

use std::collections::BTreeMap;
use std::path::Path;

use glam::{DMat4, DVec3};

use super::animation::{RestNode, Rig, Unseen};
use super::skin::Influence;
use super::{DrawClass, Light, Scene};
use crate::error::RenderError;

mod animations;
mod files;
mod images;
mod lights;
mod materials;
mod primitives;
mod skins;
mod tangents;

use animations::import_animations;
use files::{Opened, check_external_files, ignored_extensions, open};
pub use files::{is_data_uri, percent_decode, read_generator, regular_file, shown};
pub use images::MAX_TEXTURE_SIDE;
use images::decode_textures;
use lights::{camera_from_node, light_from_node};
use materials::{Materials, import_materials};
use primitives::Placement;

/// Reads a `.gltf` or `.glb` file and everything it references. Every error names the part of
/// the file at fault (`nodes[3]`, `accessors[2]`, `images[0] (uri textures/a.png)`, …).
pub fn load_gltf(path: &Path) -> Result<Scene, RenderError> {
    let fail = |message: String| RenderError::Scene { path: path.to_path_buf(), message };
    regular_file(path).map_err(|e| fail(format!("cannot read glTF: {e}")))?;
    let Opened { gltf: gltf::Gltf { document, blob }, warnings: lenient, broken_animations } =
        open(path).map_err(|e| fail(format!("cannot read glTF: {e}")))?;
    let base = path.parent().unwrap_or(Path::new("."));
    check_external_files(&document, base).map_err(fail)?;
    let buffers = gltf::import_buffers(&document, Some(base), blob)
        .map_err(|e| fail(format!("cannot read buffers: {e}")))?;

    let mut importer = Importer::default();
    let Materials { materials, textures, mut warnings } = import_materials(&document).map_err(fail)?;
    if materials.len() > super::MAX_MATERIALS {
        return Err(fail(format!(
            "materials: {} materials, the G-buffer holds at most {}",
            materials.len() - 1,
            super::MAX_MATERIALS - 1
        )));
    }
    importer.scene.materials = materials;
    importer.visit_scene(&document, &buffers).map_err(fail)?;
    warnings.extend(importer.add_skinned(&document, &buffers).map_err(fail)?);

    let animations = import_animations(&document, &buffers, &broken_animations, &importer.rig);
    let mut scene = importer.finish();
    for (index, animation) in animations.iter().enumerate() {
        if let Err(error) = &animation.tracks {
            warnings.push(format!("{}: cannot be played: {error}", animation.label(index)));
        }
    }
    scene.animations = animations;
    scene.textures = decode_textures(&document, base, &buffers, &textures).map_err(fail)?;
    scene.generator = document.as_json().asset.generator.clone();
    warnings.extend(lenient);
    warnings.extend(ignored_extensions(&document));
    scene.warnings = warnings;
    Ok(scene)
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
    /// Normal-mapped primitives without tangents of their own, for MikkTSpace.
    untangented: Vec<Primitive>,
    /// The node trees as walked, for the animations that move them.
    rig: Rig,
    /// Vertices that tangent generation split off at the end of the list: where the primitive
    /// they came from starts, and the range of its copies.
    split_off: Vec<(usize, std::ops::Range<usize>)>,
    /// The skinned nodes the walk met, whose meshes wait until every joint is placed.
    skinned: Vec<usize>,
    /// Each vertex's joints from the first skinned vertex on (empty without skins).
    influences: Vec<Influence>,
}

/// Where one primitive's vertices and triangles lie in the importer's lists.
struct Primitive {
    class: DrawClass,
    vertices: std::ops::Range<usize>,
    triangles: std::ops::Range<usize>,
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
        // Each node with its parent's world transform and place in the rig.
        let mut stack: Vec<(gltf::Node, DMat4, Option<usize>)> =
            roots.into_iter().rev().map(|n| (n, DMat4::IDENTITY, None)).collect();
        while let Some((node, parent, parent_place)) = stack.pop() {
            if std::mem::replace(&mut reached[node.index()], true) {
                return Err(format!(
                    "nodes[{}]: reached twice: the node hierarchy has a cycle or a node with two parents \
                     (glTF nodes must form disjoint trees)",
                    node.index()
                ));
            }
            let first_vertex = self.scene.vertices.len();
            let (local, world) = self.visit(document, &node, parent, buffers)?;
            let (translation, rotation, scale) = node.transform().decomposed();
            let own = first_vertex..self.scene.vertices.len();
            self.rig.nodes.push(RestNode {
                parent: parent_place,
                node: node.index(),
                matrix: local,
                translation: glam::Vec3::from(translation).as_dvec3(),
                rotation: glam::Quat::from_array(rotation).as_dquat(),
                scale: glam::Vec3::from(scale).as_dvec3(),
                vertices: vec![own],
                world,
            });
            let place = Some(self.rig.nodes.len() - 1);
            stack.extend(
                node.children().map(|child| (child, world, place)).collect::<Vec<_>>().into_iter().rev(),
            );
        }
        Ok(())
    }

    /// Adds one node's mesh and camera; returns its local and world transforms.
    fn visit(
        &mut self,
        document: &gltf::Document,
        node: &gltf::Node,
        parent: DMat4,
        buffers: &[gltf::buffer::Data],
    ) -> Result<(DMat4, DMat4), String> {
        let local = DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from)));
        let world = parent * local;
        if !world.is_finite() {
            return Err(format!("nodes[{}]: the transform is not finite", node.index()));
        }
        match (node.mesh(), node.skin()) {
            (Some(_), Some(_)) => {
                self.skinned.push(node.index());
                self.rig.unseen.push((node.index(), Unseen::SkinnedMesh));
            }
            (Some(mesh), None) => {
                for primitive in mesh.primitives() {
                    self.add_primitive(&mesh, &primitive, Placement::Node(world), buffers)?;
                }
            }
            (None, _) => {}
        }
        // The first perspective camera is the one aabench renders from; the others are noted,
        // so that an animation of them alone is refused for what it is.
        if let Some(camera) = node.camera() {
            // Read from the JSON: the gltf crate's `projection()` panics on a camera whose
            // projection object is missing, which `camera_from_node` refuses by name.
            use gltf::json::{camera::Type, validation::Checked};
            let json = &document.as_json().cameras[camera.index()];
            let perspective = json.type_ == Checked::Valid(Type::Perspective);
            let unseen = if !perspective {
                Some(Unseen::OrthographicCamera)
            } else if self.scene.camera.is_some() {
                Some(Unseen::LaterCamera)
            } else {
                self.scene.camera = camera_from_node(document, camera.index(), world)?;
                self.scene.camera_node = self.scene.camera.is_some().then_some(node.index());
                let aspect = json.perspective.as_ref().and_then(|p| p.aspect_ratio);
                self.scene.camera_aspect = aspect.map(|aspect| (camera.index(), f64::from(aspect)));
                None
            };
            self.rig.unseen.extend(unseen.map(|unseen| (node.index(), unseen)));
        }
        if let Some(light) = node.light() {
            self.lights
                .push(light_from_node(&light, world).map_err(|e| format!("nodes[{}]: {e}", node.index()))?);
        }
        Ok((local, world))
    }

    /// Sorts the triangles by draw class and makes positions relative to the scene's origin:
    /// the centre of its bounds, rounded to a multiple of [`ORIGIN_GRID`] units, so geometry
    /// far from the file's origin keeps f32 precision (and a scene near it keeps its bits).
    fn finish(mut self) -> Scene {
        self.generate_tangents();
        // A node or skin moves the copies of its vertices with them.
        for (first, copies) in std::mem::take(&mut self.split_off) {
            let holds = |ranges: &Vec<std::ops::Range<usize>>| ranges.iter().any(|r| r.contains(&first));
            let node = self.rig.nodes.iter_mut().map(|n| &mut n.vertices).find(|v| holds(v));
            let owner =
                node.or_else(|| self.rig.skins.iter_mut().map(|s| &mut s.vertices).find(|v| holds(v)));
            if let Some(owner) = owner {
                owner.push(copies);
            }
        }
        for skin in &mut self.rig.skins {
            skin.influences = skin.vertex_indices().map(|v| self.influences[v]).collect();
        }
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
        if !self.scene.tangents.is_empty() {
            self.scene.tangents.resize(self.scene.vertices.len(), [0.0; 4]);
        }
        self.scene.origin = origin;
        self.scene.rig = std::mem::take(&mut self.rig);
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
