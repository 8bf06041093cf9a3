//! SMAA 1x: its lookup textures are the reference's, it changes only pixels beside an edge, and
//! it brings hard edges nearer their truth.

use crate::support;

use aabench_renderer::scene::generate::Generator;
use aabench_renderer::smaa::{LOOKUP_TEXTURES, PRESET_HIGH};
use aabench_renderer::{DisplayImage, SceneRenderer};
use glam::DQuat;
use sha2::{Digest, Sha256};
use support::{generated, gpu, lit, render, settings};

/// The checksums recorded in `renderer/data/smaa/README.md`: a changed byte fails here.
#[test]
fn the_lookup_textures_are_the_reference_implementations() {
    let expected = [
        ("smaa_area", 160 * 560 * 2, "35065cef2a02cabcad711d6bf430239ae64e27d71c4e4fa06f29cce2c992f0d2"),
        ("smaa_search", 64 * 16, "3694eae5e9d44b8ebb4415a13f8c7b94dc08a2fc86658434d771c4610fe5744d"),
    ];
    for (texture, (name, bytes, sha256)) in LOOKUP_TEXTURES.iter().zip(expected) {
        assert_eq!(texture.name, name);
        assert_eq!(texture.bytes.len(), bytes);
        let block = texture.format.block_copy_size(None).unwrap() as usize;
        assert_eq!(texture.bytes.len(), texture.width as usize * texture.height as usize * block);
        let digest: String = Sha256::digest(texture.bytes).iter().map(|b| format!("{b:02x}")).collect();
        assert_eq!(digest, sha256, "{name}");
    }
}

/// The edge scene (a light wall tilted 7° from vertical over a dark one) seen with the camera
/// rolled by `roll` degrees, at `width` × `height`.
fn edge_renderer(roll: f64, width: u32, height: u32) -> (SceneRenderer, std::sync::MutexGuard<'static, ()>) {
    let (gpu, guard) = gpu();
    let (scene, mut camera) = generated(Generator::Edge);
    camera.up = DQuat::from_axis_angle(camera.forward.normalize(), roll.to_radians()) * camera.up;
    let renderer =
        SceneRenderer::new(gpu, &scene, &camera, &lit(), settings(width, height)).expect("scene upload");
    (renderer, guard)
}

/// The reference's luma of an 8-bit pixel (Rec. 709 weights on code values).
fn luma(image: &DisplayImage, width: usize, x: usize, y: usize) -> f64 {
    let p = &image.rgba[4 * (y * width + x)..];
    aabench_renderer::color::luminance([p[0], p[1], p[2]].map(f64::from)) / 255.0
}

/// Sum of squared differences of the colour channels.
fn squared_error(a: &DisplayImage, b: &DisplayImage) -> f64 {
    let pairs = a.rgba.iter().zip(&b.rgba).enumerate().filter(|(i, _)| i % 4 != 3);
    pairs.map(|(_, (x, y))| (f64::from(*x) - f64::from(*y)).powi(2)).sum()
}

/// A pixel is blended only across a side where its luma and its neighbour's differ by the
/// threshold or more: every pixel SMAA changes has such a neighbour, and SMAA changes the
/// edge's pixels (more than one per row) and few others.
#[test]
fn smaa_changes_only_pixels_beside_an_edge() {
    let (width, height) = (96usize, 64usize);
    let (mut renderer, _gpu) = edge_renderer(0.0, width as u32, height as u32);
    let deferred = render(&mut renderer, "deferred-1x1").display;
    let smaa = render(&mut renderer, "smaa").display;
    let mut changed = 0;
    for y in 0..height {
        for x in 0..width {
            let p = 4 * (y * width + x);
            if deferred.rgba[p..p + 3] == smaa.rgba[p..p + 3] {
                continue;
            }
            changed += 1;
            let here = luma(&deferred, width, x, y);
            let contrast = [(-1, 0), (1, 0), (0, -1), (0, 1)]
                .iter()
                .map(|&(dx, dy): &(isize, isize)| {
                    let nx = (x as isize + dx).clamp(0, width as isize - 1) as usize;
                    let ny = (y as isize + dy).clamp(0, height as isize - 1) as usize;
                    (luma(&deferred, width, nx, ny) - here).abs()
                })
                .fold(0.0, f64::max);
            assert!(
                contrast >= PRESET_HIGH.threshold - 1e-6,
                "({x}, {y}) changed with neighbours within {contrast}"
            );
        }
    }
    assert!(changed > height, "SMAA smoothed only {changed} pixels of a {height}-row edge");
    assert!(changed < width * height / 10, "{changed} pixels changed");
}

/// The edge 7° from vertical, and rolled 38° into a diagonal: SMAA's squared error against the
/// 8×8 truth is below 0.3 × deferred-1x1's (measured: 0.06 and 0.19).
#[test]
fn smaa_brings_hard_edges_nearer_their_truth() {
    for roll in [0.0, 38.0] {
        let (mut renderer, _gpu) = edge_renderer(roll, 96, 64);
        let truth = renderer.render_truth(8, 64 << 20).unwrap().images.display;
        let deferred = squared_error(&render(&mut renderer, "deferred-1x1").display, &truth);
        let smaa = squared_error(&render(&mut renderer, "smaa").display, &truth);
        println!("roll {roll}°: SMAA {smaa:.0} against deferred-1x1 {deferred:.0} ({:.2}×)", smaa / deferred);
        assert!(smaa < 0.3 * deferred, "roll {roll}°: SMAA's error {smaa} against deferred-1x1's {deferred}");
    }
}
