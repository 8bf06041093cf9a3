//! Omnidirectional shadows on lavapipe: cube faces hold what lies along their axes, occluded
//! points are dark and visible ones lit, and PCF's penumbra widens with its radius.

use crate::support;

use aabench_renderer::scene::shadow::face_and_coordinates;
use aabench_renderer::scene::{
    Camera, DrawClass, Light, LightKind, Lighting, Material, Scene, Shadow, Vertex,
};
use aabench_renderer::{FrameImages, Mode, RenderSettings, SceneRenderer, Technique};
use glam::{DVec3, Vec3};
use support::*;

/// A scene of quads, each given by its centre, two half-extent vectors and its normal.
fn quads(quads: &[(Vec3, Vec3, Vec3)], double_sided: bool) -> Scene {
    let mut scene = Scene::default();
    for &(centre, u, v) in quads {
        let normal = u.cross(v).normalize();
        let base = scene.vertices.len() as u32;
        for (su, sv) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            let position = centre + u * su + v * sv;
            scene.vertices.push(Vertex {
                position: position.to_array(),
                normal: normal.to_array(),
                uv: [0.0, 0.0],
                material: 0,
            });
        }
        scene.indices.extend([base, base + 1, base + 2, base, base + 2, base + 3]);
    }
    let class = DrawClass { masked: false, double_sided };
    scene.draws = vec![(class, 0..scene.indices.len() as u32)];
    scene.materials = vec![Material {
        name: "grey".into(),
        base_color: [0.5, 0.5, 0.5, 1.0],
        metallic: 0.0,
        roughness: 0.9,
        double_sided,
        ..Material::default()
    }];
    scene
}

fn light(position: Vec3, shadow: Option<Shadow>) -> Lighting {
    Lighting {
        lights: vec![Light {
            kind: LightKind::Point,
            position,
            color: Vec3::ONE,
            intensity: 10.0,
            range: 10.0,
            shadow,
        }],
        ambient: Vec3::splat(0.02),
        background: Vec3::ZERO,
        exposure: 1.0,
    }
}

fn deferred() -> Mode {
    Mode::new(Technique::Deferred, 1, false)
}

/// A marker 2 units from the light along each of ±X, ±Y and ±Z lands in its own cube face:
/// the CPU twin of the cube lookup picks that face, the centroid of the face's covered texels
/// lies within 0.03 of where the lookup reads the marker's centre, and the stored value is the
/// expected reversed depth within 10⁻⁶.
#[test]
fn a_marker_along_each_axis_lands_in_its_face_where_the_lookup_reads() {
    // A small square 2 units from the light along each axis, off-centre towards a neighbouring
    // axis, so a face that is mirrored or turned puts it in the wrong place.
    let axes = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
    let markers: Vec<(Vec3, Vec3, Vec3)> = axes
        .iter()
        .enumerate()
        .map(|(i, &axis)| {
            let side = axes[(i + 2) % 6];
            let other = axis.cross(side);
            (axis * 2.0 + side * 0.8 + other * 0.3, side * 0.15, other * 0.15)
        })
        .collect();
    let resolution = 64;
    let scene = quads(&markers, true);
    let lighting = light(Vec3::ZERO, Some(Shadow { resolution, ..Shadow::default() }));
    let (gpu, _guard) = gpu();
    let camera = Camera::look_at(DVec3::new(0.5, 0.5, 5.0), DVec3::ZERO, 60.0);
    let mut renderer = SceneRenderer::new(gpu, &scene, &camera, &lighting, settings(32, 24)).unwrap();
    let prepared = renderer.prepare(deferred()).unwrap();
    prepared.render().unwrap();
    let cubes = prepared.read_shadow_cubes().unwrap().expect("a shadow light's cube");
    assert_eq!((cubes.resolution, cubes.layers), (resolution, 6));
    let side = resolution as usize;
    let layer = |face: usize| &cubes.depth[face * side * side..(face + 1) * side * side];
    for (marker, &(centre, _, _)) in markers.iter().enumerate() {
        let (face, s, t) = face_and_coordinates(centre);
        assert_eq!(face, marker, "the CPU lookup puts marker {marker} on face {face}");
        // Each face sees exactly its own marker: the centroid of its covered texels is where
        // the lookup reads the marker's centre.
        let covered: Vec<(f64, f64)> = layer(face)
            .iter()
            .enumerate()
            .filter(|(_, d)| **d > 0.0)
            .map(|(i, _)| (((i % side) as f64 + 0.5) / side as f64, ((i / side) as f64 + 0.5) / side as f64))
            .collect();
        assert!(!covered.is_empty(), "face {face} saw nothing");
        let n = covered.len() as f64;
        let (cs, ct) = covered.iter().fold((0.0, 0.0), |(a, b), (s, t)| (a + s / n, b + t / n));
        assert!(
            (cs - s).abs() < 0.03 && (ct - t).abs() < 0.03,
            "face {face}: marker at ({cs}, {ct}), lookup reads ({s}, {t})"
        );
        // The depth is reversed depth along the face's axis: n·(f − ma) / (ma·(f − n)).
        let (near, far) = (10.0 * 1e-4, 10.0);
        let ma = 2.0f64;
        let expected = near * (far - ma) / (ma * (far - near));
        let texel = (t * side as f64) as usize * side + (s * side as f64) as usize;
        let stored = f64::from(layer(face)[texel]);
        assert!((stored - expected).abs() < 1e-6, "face {face}: depth {stored}, expected {expected}");
    }
}

/// A floor at y = 0 lit from (0, 2, 0), and a square occluder at y = 1 over the origin that
/// faces down: the camera above sees its back, which the G-buffer culls, so the shadow it
/// casts is in plain view.
fn occluder_scene() -> (Scene, Camera) {
    let floor = (Vec3::ZERO, Vec3::X * 4.0, -Vec3::Z * 4.0);
    // X × Z = −Y: the occluder faces the floor.
    let occluder = (Vec3::Y, Vec3::X * 0.25, Vec3::Z * 0.25);
    let scene = quads(&[floor, occluder], false);
    let camera = Camera {
        position: DVec3::new(0.0, 6.0, 0.0),
        forward: DVec3::NEG_Y,
        up: DVec3::NEG_Z,
        fov_y: 60f64.to_radians(),
        near: 0.05,
        far: 50.0,
    };
    (scene, camera)
}

fn render_floor(shadow: Option<Shadow>) -> FrameImages {
    render_floor_in(shadow, &deferred().to_string(), settings(96, 96))
}

/// The occluder scene's frame in `mode`, lit from (0, 2, 0).
fn render_floor_in(shadow: Option<Shadow>, mode: &str, settings: RenderSettings) -> FrameImages {
    let (scene, camera) = occluder_scene();
    let (gpu, _guard) = gpu();
    let lighting = light(Vec3::new(0.0, 2.0, 0.0), shadow);
    let mut renderer = SceneRenderer::new(gpu, &scene, &camera, &lighting, settings).unwrap();
    render(&mut renderer, mode)
}

/// Per pixel of the middle row: the fraction of the light that reaches it, from the shadowed
/// and unshadowed renders (ambient removed).
fn visibility_row(shadow: Shadow) -> Vec<f32> {
    let shadowed = render_floor(Some(shadow));
    let open = render_floor(None);
    let ambient = 0.02 * 0.5;
    let width = shadowed.width as usize;
    let row = shadowed.height as usize / 2;
    (0..width)
        .map(|x| {
            let at = 4 * (row * width + x);
            (shadowed.hdr[at] - ambient) / (open.hdr[at] - ambient)
        })
        .collect()
}

/// A point of the floor under the occluder receives less than 1% of the light; a point in the
/// open receives all of it, within 1%.
#[test]
fn an_occluded_point_is_shadowed_and_a_visible_one_lit() {
    let visibility = visibility_row(Shadow { resolution: 256, bias: 0.05, radius: 0.01 });
    let width = visibility.len();
    // The occluder's shadow spans |x| < 0.5 on the floor (twice its half-size at half the
    // light's height); the frame spans |x| < 6·tan 30° ≈ 3.46.
    let centre = visibility[width / 2];
    let outside = visibility[width / 8];
    assert!(centre < 0.01, "under the occluder: {centre}");
    assert!((outside - 1.0).abs() < 0.01, "in the open: {outside}");
}

/// PCF's penumbra along the middle row widens with the radius: the test asserts at least 2
/// partly lit pixels at radius 0.03 and at least 4 more at 0.12 (measured: 4 and 12), and
/// every visibility finite and within [0, 1].
#[test]
fn pcf_gives_a_soft_edge_that_widens_with_the_radius() {
    let penumbra = |radius: f32| {
        let visibility = visibility_row(Shadow { resolution: 256, bias: 0.05, radius });
        let partial = visibility.iter().filter(|&&v| v > 0.02 && v < 0.98).count();
        assert!(visibility.iter().all(|v| v.is_finite() && (-0.01..=1.01).contains(v)), "{visibility:?}");
        // The open floor is fully lit right up to the penumbra: a wide disk does not shadow
        // the surface it sits on.
        let lit = visibility.iter().filter(|&&v| v >= 0.98).count();
        assert_eq!(lit + partial + visibility.iter().filter(|&&v| v <= 0.02).count(), visibility.len());
        partial
    };
    let (narrow, wide) = (penumbra(0.03), penumbra(0.12));
    assert!(narrow >= 2, "a soft edge on both sides: {narrow} partly lit pixels");
    assert!(wide >= narrow + 4, "radius 0.12 gives {wide} partly lit pixels, 0.03 gives {narrow}");
}

/// Inside a penumbra, PCF's visibility steps by a twentieth of the light wherever an occluder's
/// edge crosses a tap's ray, so one sample misses the steps inside its pixel while its
/// neighbours look alike to the luma cross. `-coverage`'s shadow term asks for samples there:
/// on the floor under a wide penumbra every partly lit pixel takes more than one sample (the
/// metric without the term leaves some at one), the fully lit and fully shadowed floor keep
/// the counts they take without it, and the penumbra's squared error against reference-4x4
/// falls by more than half.
#[test]
fn the_shadow_term_samples_the_penumbrae_that_the_luma_cross_misses() {
    let shadow = Some(Shadow { resolution: 256, bias: 0.05, radius: 0.12 });
    let mode = "adaptive-4x4-coverage";
    let with = render_floor_in(shadow, mode, settings(96, 96));
    let mut off = settings(96, 96);
    off.adaptive.c_shadow = 0.0;
    let without = render_floor_in(shadow, mode, off);
    let reference = render_floor_in(shadow, "reference-4x4", settings(96, 96));
    let (shadowed, open) = (render_floor(shadow), render_floor(None));
    // Each pixel's share of the light from deferred shading, whose sample is S's.
    let ambient = 0.02 * 0.5;
    let visibility = |p: usize| (shadowed.hdr[4 * p] - ambient) / (open.hdr[4 * p] - ambient);
    let pixels = (with.width * with.height) as usize;
    let is_partial: Vec<bool> = (0..pixels).map(|p| (0.02..0.98).contains(&visibility(p))).collect();
    let partial: Vec<usize> = (0..pixels).filter(|&p| is_partial[p]).collect();
    let counts = |image: &FrameImages| image.sample_counts.clone().expect("sample counts");
    let (counts_with, counts_without) = (counts(&with), counts(&without));
    assert!(partial.len() >= 100, "only {} partly lit pixels", partial.len());
    let single = |counts: &[u8]| partial.iter().filter(|&&p| counts[p] == 1).count();
    assert!(single(&counts_without) > 0, "the luma cross sampled the whole penumbra: the test shows nothing");
    assert_eq!(single(&counts_with), 0, "partly lit pixels left at one sample");
    assert!(
        (0..pixels).filter(|&p| !is_partial[p]).all(|p| counts_with[p] == counts_without[p]),
        "counts moved outside the penumbra"
    );
    let error = |image: &FrameImages| -> f64 {
        let channel = |p: usize, c: usize| {
            f64::from(image.display.rgba[4 * p + c]) - f64::from(reference.display.rgba[4 * p + c])
        };
        partial.iter().map(|&p| (0..3).map(|c| channel(p, c).powi(2)).sum::<f64>()).sum()
    };
    let (error_with, error_without) = (error(&with), error(&without));
    assert!(
        error_with < 0.5 * error_without,
        "squared error in the penumbra {error_with} with the term, {error_without} without"
    );
}
