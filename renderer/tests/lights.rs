//! Spot and directional lights (KHR_lights_punctual's kinds) on lavapipe, judged on pixels: a
//! spot lights inside its cone and not outside, a directional light lights a plane evenly
//! where a point light at the same place falls off.
//!
//! Scenes with only point lights compile their shaders without the light-kind arithmetic (the
//! `LIGHT_KINDS` feature), and a point light shades to the same HDR bits with it as without.

use crate::support;

use aabench_renderer::scene::generate::Generator;
use aabench_renderer::scene::{Light, LightKind, Lighting};
use aabench_renderer::{FrameImages, SceneRenderer};
use glam::Vec3;
use support::*;

/// The plane scene (a large grey wall facing the camera 3 units away, 60° field of view)
/// under `lights` alone: no ambient, black background.
fn plane_under(lights: Vec<Light>) -> FrameImages {
    plane_and_needs(lights).0
}

/// The image, and whether the scene's shaders were composed with the light-kind arithmetic.
fn plane_and_needs(lights: Vec<Light>) -> (FrameImages, bool) {
    let (gpu, _guard) = gpu();
    let (scene, camera) = generated(Generator::Plane);
    let lighting = Lighting { lights, ambient: Vec3::ZERO, background: Vec3::ZERO, exposure: 1.0 };
    let mut renderer = SceneRenderer::new(gpu, &scene, &camera, &lighting, settings(64, 48)).unwrap();
    let kinds = renderer.needs().features.light_kinds;
    (render(&mut renderer, "deferred-1x1"), kinds)
}

/// The display image's green code at (x, y).
fn green(image: &FrameImages, x: u32, y: u32) -> u16 {
    image.display.rgba[((y * image.width + x) * 4 + 1) as usize]
}

fn light(kind: LightKind, position: Vec3, intensity: f32) -> Light {
    Light { kind, position, color: Vec3::ONE, intensity, range: 100.0, shadow: None }
}

/// A spot light at the camera lights the plane's centre and leaves six pixels well outside its
/// cone (corners and edge midpoints) at code 0, where a point light at the same place lights
/// a corner. At the centre, inside the inner cone, the spot's code equals the point light's.
#[test]
fn a_spot_light_lights_inside_its_cone_only() {
    let eye = Vec3::new(0.0, 0.0, 3.0);
    let spot = LightKind::Spot { direction: Vec3::NEG_Z, inner: 0.1, outer: 0.2 };
    let image = plane_under(vec![light(spot, eye, 20.0)]);
    // The cone meets the plane in a disc of radius 3·tan 0.2 = 0.61 around the centre; the
    // view's half-height there is 1.73.
    assert!(green(&image, 32, 24) > 100, "centre: {}", green(&image, 32, 24));
    for (x, y) in [(2, 2), (61, 2), (2, 45), (61, 45), (32, 2), (2, 24)] {
        assert_eq!(green(&image, x, y), 0, "({x}, {y}) lies outside the cone");
    }
    // The same light as a point light lights the corners too.
    let point = plane_under(vec![light(LightKind::Point, eye, 20.0)]);
    assert!(green(&point, 2, 2) > 30, "corner under a point light: {}", green(&point, 2, 2));
    // Inside the inner cone the spot is exactly the point light.
    assert_eq!(green(&image, 32, 24), green(&point, 32, 24));
}

/// A directional light lights the whole plane (every code above 80) within 3 codes, while a
/// point light at the camera falls off from the centre to the corner by more than 20 codes.
#[test]
fn a_directional_light_lights_a_plane_evenly() {
    let sun = LightKind::Directional { direction: Vec3::NEG_Z };
    let image = plane_under(vec![light(sun, Vec3::ZERO, 1.0)]);
    let greens: Vec<u16> = image.display.rgba.chunks_exact(4).map(|p| p[1]).collect();
    let (lo, hi) = (*greens.iter().min().unwrap(), *greens.iter().max().unwrap());
    assert!(lo > 80, "lit everywhere: darkest {lo}");
    // Only the rough specular term varies with the view direction.
    assert!(hi - lo <= 3, "even: {lo}..{hi}");
    // A point light where the camera is falls off towards the corners.
    let point = plane_under(vec![light(LightKind::Point, Vec3::new(0.0, 0.0, 3.0), 9.0)]);
    assert!(
        green(&point, 32, 24) > green(&point, 2, 2) + 20,
        "{} vs {}",
        green(&point, 32, 24),
        green(&point, 2, 2)
    );
}

/// Point lights alone compile without `LIGHT_KINDS`; a spot aimed away turns it on and adds
/// nothing, so the point light's HDR image is the same bit for bit. Measured once, interleaved
/// against the build from before light kinds existed: every output hash of the atrium and
/// specular scenes was equal, and frame times were within 1%.
#[test]
fn point_lights_shade_to_the_same_bits_with_or_without_the_light_kind_arithmetic() {
    let point = light(LightKind::Point, Vec3::new(0.5, 0.5, 2.0), 20.0);
    let (plain, plain_kinds) = plane_and_needs(vec![point.clone()]);
    assert!(!plain_kinds, "point lights alone compile without LIGHT_KINDS");
    // A spot aimed away from the plane adds nothing, but turns the arithmetic on.
    let away =
        light(LightKind::Spot { direction: Vec3::Z, inner: 0.1, outer: 0.2 }, Vec3::new(0.0, 0.0, 3.0), 20.0);
    let (mixed, mixed_kinds) = plane_and_needs(vec![point, away]);
    assert!(mixed_kinds);
    assert_eq!(plain.hdr, mixed.hdr, "the point light's radiance, bit for bit");
    assert!(plain.display.rgba.iter().any(|&v| v > 0), "something is lit");
}
