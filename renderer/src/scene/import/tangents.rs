//! Tangents for normal maps: the file's, or MikkTSpace's where a primitive has none.

use std::collections::HashMap;

use glam::DVec3;

use super::{Importer, Primitive};
use crate::scene::{DrawClass, Vertex};

impl Importer {
    /// Gives the vertices from `first_vertex` on (one primitive's) tangents: the file's, or
    /// zero until [`Importer::generate_tangents`] gives them MikkTSpace's.
    pub(super) fn add_tangents(
        &mut self,
        class: DrawClass,
        first_vertex: usize,
        first_triangle: usize,
        file: Option<Vec<[f32; 4]>>,
    ) {
        let tangents = &mut self.scene.tangents;
        tangents.resize(first_vertex, [0.0; 4]);
        match file {
            Some(file) => tangents.extend(file),
            None => {
                tangents.resize(self.scene.vertices.len(), [0.0; 4]);
                self.untangented.push(Primitive {
                    class,
                    vertices: first_vertex..self.scene.vertices.len(),
                    triangles: first_triangle..self.triangles[&class].len(),
                });
            }
        }
    }

    /// MikkTSpace tangents for the primitives that need them, primitives spread over the
    /// cores (it dominates the import of a large normal-mapped file). MikkTSpace gives one
    /// tangent per triangle corner; corners of one vertex that it gives different tangents (UV
    /// seams, mirrored UVs) split the vertex.
    pub(super) fn generate_tangents(&mut self) {
        let primitives = std::mem::take(&mut self.untangented);
        if primitives.is_empty() {
            return;
        }
        // Split vertices go at the end: the table must reach it first.
        self.scene.tangents.resize(self.scene.vertices.len(), [0.0; 4]);
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
        let chunk = primitives.len().div_ceil(threads).max(1);
        let (vertices, world, triangles) = (&self.scene.vertices, &self.world, &self.triangles);
        let corners: Vec<Vec<[f32; 4]>> = std::thread::scope(|scope| {
            let workers: Vec<_> = primitives
                .chunks(chunk)
                .map(|part| {
                    scope.spawn(move || {
                        part.iter()
                            .map(|p| {
                                let triangles = &triangles[&p.class][p.triangles.clone()];
                                mikktspace_corners(vertices, world, triangles, p.vertices.start)
                            })
                            .collect::<Vec<_>>()
                    })
                })
                .collect();
            workers.into_iter().flat_map(|worker| worker.join().expect("MikkTSpace panicked")).collect()
        });
        for (primitive, corners) in primitives.iter().zip(corners) {
            let before = self.scene.vertices.len();
            self.weld_tangents(primitive, &corners);
            let copies = before..self.scene.vertices.len();
            if !copies.is_empty() {
                self.split_off.push((primitive.vertices.start, copies));
            }
        }
    }

    /// Gives each vertex of `primitive` the tangent of its corners, splitting vertices whose
    /// corners disagree.
    fn weld_tangents(&mut self, primitive: &Primitive, corners: &[[f32; 4]]) {
        let first = primitive.vertices.start;
        let mut assigned = vec![false; primitive.vertices.len()];
        let mut splits: HashMap<(u32, [u32; 4]), u32> = HashMap::new();
        let triangles = &mut self.triangles.get_mut(&primitive.class).expect("the primitive's class")
            [primitive.triangles.clone()];
        for (triangle, corner_tangents) in triangles.iter_mut().zip(corners.chunks_exact(3)) {
            for (index, &tangent) in triangle.iter_mut().zip(corner_tangents) {
                let v = *index as usize;
                if !std::mem::replace(&mut assigned[v - first], true) {
                    self.scene.tangents[v] = tangent;
                } else if self.scene.tangents[v] != tangent {
                    *index = *splits.entry((*index, tangent.map(f32::to_bits))).or_insert_with(|| {
                        self.scene.vertices.push(self.scene.vertices[v]);
                        self.world.push(self.world[v]);
                        self.scene.tangents.push(tangent);
                        if !self.influences.is_empty() {
                            // A skinned vertex's copy follows its joints too.
                            let copied = self.influences.get(v).copied().unwrap_or_default();
                            self.influences.resize(self.scene.vertices.len() - 1, Default::default());
                            self.influences.push(copied);
                        }
                        (self.scene.vertices.len() - 1) as u32
                    });
                }
            }
        }
    }
}

/// MikkTSpace tangents of `triangles` (whose vertices start at `first_vertex`), one per
/// corner in triangle order. Positions are taken relative to the first vertex, so far-out
/// geometry keeps its precision; a corner MikkTSpace cannot give a finite tangent (a triangle
/// without UV area) gets zero, which the shaders read as "no normal map here".
fn mikktspace_corners(
    vertices: &[Vertex],
    world: &[DVec3],
    triangles: &[[u32; 3]],
    first_vertex: usize,
) -> Vec<[f32; 4]> {
    struct Corners<'a> {
        vertices: &'a [Vertex],
        world: &'a [DVec3],
        origin: DVec3,
        triangles: &'a [[u32; 3]],
        out: Vec<[f32; 4]>,
    }
    impl Corners<'_> {
        fn vertex(&self, face: usize, vert: usize) -> usize {
            self.triangles[face][vert] as usize
        }
    }
    impl mikktspace::Geometry for Corners<'_> {
        fn num_faces(&self) -> usize {
            self.triangles.len()
        }
        fn num_vertices_of_face(&self, _face: usize) -> usize {
            3
        }
        fn position(&self, face: usize, vert: usize) -> [f32; 3] {
            (self.world[self.vertex(face, vert)] - self.origin).as_vec3().to_array()
        }
        fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
            self.vertices[self.vertex(face, vert)].normal
        }
        /// glTF's V runs down the image, but its tangent space has +Y up the image (the
        /// bitangent `w · normal × tangent` points up): MikkTSpace is given 1 − V so that its
        /// bitangent, the direction of growing V, points up as well.
        fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
            let [u, v] = self.vertices[self.vertex(face, vert)].uv;
            [u, 1.0 - v]
        }
        fn set_tangent_encoded(&mut self, tangent: [f32; 4], face: usize, vert: usize) {
            self.out[face * 3 + vert] = tangent;
        }
    }
    let mut corners = Corners {
        vertices,
        world,
        origin: world.get(first_vertex).copied().unwrap_or_default(),
        triangles,
        out: vec![[0.0; 4]; triangles.len() * 3],
    };
    // MikkTSpace drops triangles with two equal corners and then underflows (an unchecked
    // usize loop bound; out-of-bounds reads in release) when none is left: a primitive that
    // is all slivers, or one under a node scaled to zero to hide it, gets zero tangents.
    let proper = |t: &[u32; 3]| {
        let p = t.map(|i| (world[i as usize] - corners.origin).as_vec3());
        p[0] != p[1] && p[0] != p[2] && p[1] != p[2]
    };
    if triangles.iter().any(proper) {
        mikktspace::generate_tangents(&mut corners);
    }
    corners.out.into_iter().map(|t| if t.iter().all(|c| c.is_finite()) { t } else { [0.0; 4] }).collect()
}
