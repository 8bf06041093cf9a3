//! The deterministic procedural scene generator. It writes glTF files that the importer then
//! reads, so generated scenes and users' own files share one code path.

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
}

impl Generator {
    pub const ALL: [Generator; 6] = [
        Generator::Atrium,
        Generator::Thin,
        Generator::Specular,
        Generator::ShadowRoom,
        Generator::Plane,
        Generator::Edge,
    ];

    /// The `asset.generator` string of a current file made by this generator and seed.
    pub fn signature(self, seed: u64) -> String {
        format!("aabench-gen/{GENERATOR_VERSION} {self} seed={seed}")
    }

    /// Builds the scene in memory.
    pub fn build(self, seed: u64) -> GltfWriter {
        let mut builder = Builder::new(&self.signature(seed), seed);
        match self {
            Generator::Atrium => scenes::atrium(&mut builder),
            Generator::Thin => scenes::thin(&mut builder),
            Generator::Specular => scenes::specular(&mut builder),
            Generator::ShadowRoom => scenes::shadow_room(&mut builder),
            Generator::Plane => scenes::plane(&mut builder),
            Generator::Edge => scenes::edge(&mut builder),
        }
        builder.finish()
    }

    /// Builds the scene and writes it as GLB to `path`, atomically.
    pub fn write(self, seed: u64, path: &Path) -> std::io::Result<()> {
        self.build(seed).write(path)
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
