//! From a manifest to a scene ready to upload: generate the glTF file when it is missing or
//! stale, import it, and add the manifest's camera and lights.

use std::time::Instant;

use aabench_renderer::scene::{Camera, Lighting, PointLight, Scene, load_gltf, read_generator};
use anyhow::{Context, bail};
use glam::{DVec3, Vec3};

use crate::manifest::Manifest;

#[derive(Debug)]
pub struct LoadedScene {
    pub scene: Scene,
    pub camera: Camera,
    pub lighting: Lighting,
    /// Seconds spent generating (if it had to) and importing.
    pub seconds: f64,
}

/// Makes sure the manifest's glTF file exists and is current. Returns true if it generated.
pub fn ensure_generated(manifest: &Manifest, force: bool) -> anyhow::Result<bool> {
    let path = manifest.gltf_path();
    let Some((generator, seed)) = manifest.generator() else {
        if !path.exists() {
            bail!(
                "{}: gltf: {} does not exist, and the manifest has no `generate` section to make it",
                manifest.path.display(),
                path.display()
            );
        }
        return Ok(false);
    };
    let current = !force
        && path.exists()
        && read_generator(&path).as_deref() == Some(generator.signature(seed).as_str());
    if current {
        return Ok(false);
    }
    generator
        .write(seed, &path)
        .with_context(|| format!("{}: generate: cannot write {}", manifest.path.display(), path.display()))?;
    Ok(true)
}

/// Generates if needed, imports the glTF file and applies the manifest. Blocking.
pub fn load(manifest: &Manifest) -> anyhow::Result<LoadedScene> {
    let start = Instant::now();
    ensure_generated(manifest, false)?;
    let path = manifest.gltf_path();
    let scene = load_gltf(&path).with_context(|| format!("{}: gltf", manifest.path.display()))?;
    if scene.indices.is_empty() {
        bail!("{}: gltf: {} holds no triangles", manifest.path.display(), path.display());
    }
    let camera = camera(manifest, &scene)?;
    let lighting = Lighting {
        lights: manifest
            .lights
            .iter()
            .map(|l| PointLight {
                position: Vec3::from(l.position),
                color: Vec3::from(l.color),
                intensity: l.intensity,
                range: l.range,
                shadow: l.shadow(),
            })
            .collect(),
        ambient: Vec3::from(manifest.ambient),
        background: Vec3::from(manifest.background),
        exposure: manifest.tonemap.exposure,
    };
    Ok(LoadedScene { scene, camera, lighting, seconds: start.elapsed().as_secs_f64() })
}

/// The manifest's camera, else the file's. A missing far plane is set just beyond the farthest
/// corner of the scene's bounds.
fn camera(manifest: &Manifest, scene: &Scene) -> anyhow::Result<Camera> {
    let mut camera = match &manifest.camera {
        Some(spec) => Camera {
            position: DVec3::from(spec.position),
            forward: DVec3::from(spec.target) - DVec3::from(spec.position),
            up: DVec3::from(spec.up),
            fov_y: spec.fov_y_degrees.to_radians(),
            near: spec.near,
            far: spec.far.unwrap_or(f64::INFINITY),
        },
        None => scene.camera.with_context(|| {
            format!(
                "{}: camera: omitted, and {} has no camera node",
                manifest.path.display(),
                manifest.gltf_path().display()
            )
        })?,
    };
    if camera.forward.cross(camera.up).length_squared() < 1e-12 {
        bail!("{}: camera: the view direction is parallel to `up`", manifest.path.display());
    }
    if !camera.far.is_finite() {
        let (lo, hi) = scene.bounds();
        let farthest = (0..8)
            .map(|corner| {
                let pick = |bit: usize, a: f32, b: f32| f64::from(if corner & bit == 0 { a } else { b });
                let p = DVec3::new(pick(1, lo.x, hi.x), pick(2, lo.y, hi.y), pick(4, lo.z, hi.z));
                (p - camera.position).length()
            })
            .fold(0.0, f64::max);
        camera.far = (farthest * 1.05).max(camera.near * 2.0);
    }
    Ok(camera)
}
