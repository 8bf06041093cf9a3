//! The deterministic procedural scene generator. It writes glTF files that the importer then
//! reads, so generated scenes and users' own files share one code path.

mod figure;
mod mesh;
mod scenes;
mod textures;

use std::collections::BTreeMap;
use std::fmt;
use std::path::Path;
use std::str::FromStr;

pub use mesh::Mesh;

use super::write::{GltfWriter, MaterialDesc};

/// Bumped whenever any generator's output changes, so cached files are regenerated.
pub const GENERATOR_VERSION: u32 = 3;

/// How every generated file's `asset.generator` starts: what marks a file aabench may replace.
pub const GENERATOR_STAMP: &str = "aabench-gen/";

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Generator {
    /// A Sponza-like court: two storeys of fluted columns and arches, balustrades, curtains,
    /// alpha-masked foliage, tiled floor; over 250k triangles.
    Atrium,
    /// Wires, a chain-link fence, a picket fence and grazing-angle planes: geometric aliasing.
    Thin,
    /// Glossy spheres and tori under coloured point lights: shading aliasing.
    Specular,
    /// A closed room with boxes around one shadow-casting point light.
    ShadowRoom,
    /// One large untextured plane facing the camera.
    Plane,
    /// A light plane in front of a dark one, split by one straight, slightly tilted edge.
    Edge,
    /// A Cornell box, 0.55 m (34 triangles): the scale test, placed in mm, m or km.
    Cornell,
    /// Triangles far smaller than a sample, needles, and a dense fence at a grazing angle.
    Subpixel,
    /// Zero-area triangles, zero-length and non-unit normals, coincident vertices, UVs far
    /// outside [0, 1].
    Degenerate,
    /// A stand-in for a large real-world file: 99 spheres on a floor, a million triangles, 100
    /// textures (one 4096², 99 of 256², half of them normal maps without tangents), no camera
    /// and no lights.
    Gallery,
    /// A checkered ground at a grazing angle, a striped wall along the view and a finely
    /// checkered panel: texture aliasing on flat, rough surfaces.
    Texture,
    /// Wires far thinner than a pixel and a fence of thin slats before a plain wall: what
    /// flickers when the camera moves.
    Wire,
    /// A finely checkered crate behind thin bars, sliding across a brick wall and a tiled floor
    /// before a still camera: what a moving object leaves behind.
    Crossing,
    /// A striped figure, skinned on an eleven-joint skeleton, striding across a brick wall and a
    /// tiled floor before a still camera: what a deforming object leaves behind.
    Walker,
}

impl Generator {
    pub const ALL: [Generator; 14] = [
        Generator::Atrium,
        Generator::Thin,
        Generator::Specular,
        Generator::ShadowRoom,
        Generator::Plane,
        Generator::Edge,
        Generator::Cornell,
        Generator::Subpixel,
        Generator::Degenerate,
        Generator::Gallery,
        Generator::Texture,
        Generator::Wire,
        Generator::Crossing,
        Generator::Walker,
    ];

    /// The `asset.generator` string of a current file made by this generator and seed.
    pub fn signature(self, seed: u64) -> String {
        Generated::new(self, seed).signature()
    }

    /// Builds the scene in memory.
    pub fn build(self, seed: u64) -> GltfWriter {
        Generated::new(self, seed).build()
    }

    /// Builds the scene and writes it as GLB to `path`, atomically.
    pub fn write(self, seed: u64, path: &Path) -> std::io::Result<()> {
        Generated::new(self, seed).write(path)
    }
}

/// Where a generated scene sits in its file: uniformly scaled about the origin, then moved.
/// The geometry keeps its own coordinates; a root node carries the transform, so a scene a
/// long way from the origin loses no precision in the file (glTF positions are f32).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    pub scale: f64,
    pub offset: [f64; 3],
}

impl Placement {
    pub const IDENTITY: Placement = Placement { scale: 1.0, offset: [0.0; 3] };
}

impl Default for Placement {
    fn default() -> Self {
        Placement::IDENTITY
    }
}

/// A generator, its seed and the scene's placement: everything that decides a generated file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Generated {
    pub generator: Generator,
    pub seed: u64,
    pub placement: Placement,
}

impl Generated {
    pub fn new(generator: Generator, seed: u64) -> Generated {
        Generated { generator, seed, placement: Placement::IDENTITY }
    }

    /// The `asset.generator` string of a current file: generator, version, seed and (when not
    /// the identity) placement.
    pub fn signature(&self) -> String {
        let Generated { generator, seed, placement } = *self;
        let mut signature = format!("{GENERATOR_STAMP}{GENERATOR_VERSION} {generator} seed={seed}");
        if placement != Placement::IDENTITY {
            let [x, y, z] = placement.offset;
            signature += &format!(" scale={} offset={x},{y},{z}", placement.scale);
        }
        signature
    }

    /// Builds the scene in memory.
    pub fn build(&self) -> GltfWriter {
        let mut builder = Builder::new(&self.signature(), self.seed);
        match self.generator {
            Generator::Atrium => scenes::atrium(&mut builder),
            Generator::Thin => scenes::thin(&mut builder),
            Generator::Specular => scenes::specular(&mut builder),
            Generator::ShadowRoom => scenes::shadow_room(&mut builder),
            Generator::Plane => scenes::plane(&mut builder),
            Generator::Edge => scenes::edge(&mut builder),
            Generator::Cornell => scenes::cornell(&mut builder),
            Generator::Subpixel => scenes::subpixel(&mut builder),
            Generator::Degenerate => scenes::degenerate(&mut builder),
            Generator::Gallery => scenes::gallery(&mut builder),
            Generator::Texture => scenes::texture(&mut builder),
            Generator::Wire => scenes::wire(&mut builder),
            Generator::Crossing => scenes::crossing(&mut builder),
            Generator::Walker => scenes::walker(&mut builder),
        }
        let mut writer = builder.finish();
        if self.placement != Placement::IDENTITY {
            writer.place(self.placement.scale, self.placement.offset);
        }
        writer
    }

    /// Builds the scene and writes it as GLB to `path`, atomically.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        self.build().write(path)
    }
}

impl fmt::Display for Generator {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(match self {
            Generator::Atrium => "atrium",
            Generator::Thin => "thin",
            Generator::Specular => "specular",
            Generator::ShadowRoom => "shadow-room",
            Generator::Plane => "plane",
            Generator::Edge => "edge",
            Generator::Cornell => "cornell",
            Generator::Subpixel => "subpixel",
            Generator::Degenerate => "degenerate",
            Generator::Gallery => "gallery",
            Generator::Texture => "texture",
            Generator::Wire => "wire",
            Generator::Crossing => "crossing",
            Generator::Walker => "walker",
        })
    }
}

impl FromStr for Generator {
    type Err = String;

    fn from_str(name: &str) -> Result<Generator, String> {
        Generator::ALL.into_iter().find(|g| g.to_string() == name).ok_or_else(|| {
            let known: Vec<String> = Generator::ALL.iter().map(ToString::to_string).collect();
            format!("unknown generator `{name}` (known: {})", known.join(", "))
        })
    }
}

/// SplitMix64: a small, fast, seedable generator; the same seed gives the same scene.
#[derive(Debug, Clone)]
pub(crate) struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        let unit = (self.next() >> 40) as f32 / (1u64 << 24) as f32;
        lo + (hi - lo) * unit
    }
}

/// Accumulates geometry per material, so a scene becomes one glTF mesh per material.
#[derive(Debug)]
pub(crate) struct Builder {
    writer: GltfWriter,
    parts: BTreeMap<usize, (String, Mesh)>,
    pub rng: Rng,
}

impl Builder {
    fn new(signature: &str, seed: u64) -> Builder {
        Builder { writer: GltfWriter::new(signature), parts: BTreeMap::new(), rng: Rng(seed) }
    }

    pub fn texture(&mut self, name: &str, image: &image::RgbaImage) -> usize {
        self.writer.add_png(name, &textures::png(image))
    }

    pub fn material(&mut self, material: MaterialDesc) -> usize {
        let name = material.name.clone();
        let index = self.writer.add_material(&material);
        self.parts.insert(index, (name, Mesh::default()));
        index
    }

    /// The mesh that collects all geometry of `material`.
    pub fn mesh(&mut self, material: usize) -> &mut Mesh {
        &mut self.parts.get_mut(&material).expect("material made by this builder").1
    }

    /// Adds an object of `parts` (each a material's mesh) that the animation `name` slides
    /// linearly through `translations` at `times` (seconds): one node moved, its parts its
    /// children.
    pub fn moving(&mut self, name: &str, parts: &[(usize, Mesh)], times: &[f32], translations: &[[f32; 3]]) {
        let children: Vec<usize> =
            parts.iter().filter_map(|(material, mesh)| self.writer.add_mesh(name, mesh, *material)).collect();
        let node = self.writer.add_group(name, &children);
        self.writer.add_translation_animation(name, node, times, translations);
    }

    pub fn camera(&mut self, position: [f64; 3], target: [f64; 3], fov_y_degrees: f64, far: f64) {
        self.writer.add_camera(position.into(), target.into(), fov_y_degrees, 0.05, far);
    }

    fn finish(mut self) -> GltfWriter {
        for (material, (name, mesh)) in std::mem::take(&mut self.parts) {
            self.writer.add_mesh(&name, &mesh, material);
        }
        self.writer
    }
}
