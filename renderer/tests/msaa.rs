//! 4× MSAA: it shades per sample exactly the pixels that an edge crosses, once per pixel
//! elsewhere as deferred shading does, and brings geometric edges nearer their truth, the
//! edges that an alpha test cuts out of a texture included: its sample mask's bits are the
//! standard sample positions in order.

use crate::support;

use std::sync::Arc;

use aabench_renderer::scene::generate::Generator;
use aabench_renderer::scene::load_gltf;
use aabench_renderer::scene::write::{GltfWriter, MaterialDesc, MeshData};
use aabench_renderer::{DisplayImage, SceneRenderer};
use glam::{DVec2, DVec3};
use support::{Folder, ambient_only, generated, gpu, lit, project, render, renderer, settings};

/// The standard 4× sample positions within a pixel.
const SAMPLE_POSITIONS: [(f64, f64); 4] = [(0.375, 0.125), (0.875, 0.375), (0.125, 0.625), (0.625, 0.875)];

/// The edge scene (a light wall whose edge runs 7° from vertical through the image's centre,
/// over a dark wall parallel to it), seen head-on: an edge across flat surfaces.
fn edge_renderer(width: u32, height: u32) -> (SceneRenderer, std::sync::MutexGuard<'static, ()>) {
    let (gpu, guard) = gpu();
    let (scene, camera) = generated(Generator::Edge);
    let renderer =
        SceneRenderer::new(gpu, &scene, &camera, &lit(), settings(width, height)).expect("scene upload");
    (renderer, guard)
}

/// Which side of the edge a point of the image (in pixels) lies on, as a signed distance in
/// pixels: the camera looks straight at the walls, so the edge is a straight line through the
/// image's centre, tilted 7° clockwise from vertical.
fn edge_distance(x: f64, y: f64, width: u32, height: u32) -> f64 {
    let (sin, cos) = 7f64.to_radians().sin_cos();
    (x - f64::from(width) / 2.0) * cos - (y - f64::from(height) / 2.0) * sin
}

#[test]
fn msaa_shades_per_sample_exactly_the_pixels_an_edge_crosses() {
    let (width, height) = (96u32, 64u32);
    let (mut renderer, _gpu) = edge_renderer(width, height);
    let counts = render(&mut renderer, "msaa-4x").sample_counts.expect("msaa-4x records sample counts");
    let (mut crossed, mut on_the_line) = (0, 0);
    for y in 0..height {
        for x in 0..width {
            let sides: Vec<f64> = SAMPLE_POSITIONS
                .iter()
                .map(|(dx, dy)| edge_distance(f64::from(x) + dx, f64::from(y) + dy, width, height))
                .collect();
            // Vertices snap to 1/256 pixel: a sample this near the line may fall either way.
            if sides.iter().any(|d| d.abs() < 1.0 / 256.0) {
                on_the_line += 1;
                continue;
            }
            let split = sides.iter().any(|d| *d < 0.0) && sides.iter().any(|d| *d > 0.0);
            let count = counts[(y * width + x) as usize];
            assert_eq!(count, if split { 4 } else { 1 }, "pixel ({x}, {y}): samples at {sides:?}");
            crossed += usize::from(split);
        }
    }
    // A pixel's samples span 3/4 of its width: the edge splits them in most rows, not all.
    assert!(
        crossed >= height as usize / 2,
        "the edge split the samples of only {crossed} pixels in {height} rows"
    );
    // The line through the image's centre passes near samples of the pixels around it.
    assert!(on_the_line <= 8, "{on_the_line} pixels had a sample on the edge");
}

#[test]
fn msaa_shades_nothing_per_sample_where_nothing_is_seen() {
    let (gpu, _guard) = gpu();
    let (scene, mut camera) = generated(Generator::Edge);
    // Turned around: the walls lie behind the camera.
    camera.forward = -camera.forward;
    let mut renderer = SceneRenderer::new(gpu, &scene, &camera, &lit(), settings(64, 48)).unwrap();
    let images = render(&mut renderer, "msaa-4x");
    let counts = images.sample_counts.expect("sample counts");
    assert!(
        counts.iter().all(|&n| n == 1),
        "{} pixels shaded per sample",
        counts.iter().filter(|&&n| n != 1).count()
    );
    assert_eq!(images.display.rgba, render(&mut renderer, "deferred-1x1").display.rgba);
}

/// A pixel of one surface is shaded once at its centre, from the same attributes as deferred
/// shading's: on the lit flat walls every such pixel is within one code of deferred-1x1.
#[test]
fn msaa_interior_pixels_equal_deferred_shading() {
    let (width, height) = (96u32, 64u32);
    let (mut renderer, _gpu) = edge_renderer(width, height);
    let msaa = render(&mut renderer, "msaa-4x");
    let deferred = render(&mut renderer, "deferred-1x1");
    let counts = msaa.sample_counts.expect("sample counts");
    let mut interior = 0;
    for (pixel, &count) in counts.iter().enumerate() {
        if count != 1 {
            continue;
        }
        interior += 1;
        let (a, b) =
            (&msaa.display.rgba[4 * pixel..4 * pixel + 3], &deferred.display.rgba[4 * pixel..4 * pixel + 3]);
        let step = a.iter().zip(b).map(|(x, y)| x.abs_diff(*y)).max().unwrap();
        assert!(step <= 1, "pixel {pixel}: msaa-4x {a:?}, deferred-1x1 {b:?}");
    }
    assert!(interior > (width * height) as usize * 9 / 10, "only {interior} interior pixels");
}

/// Sum of squared differences of the colour channels.
fn squared_error(a: &DisplayImage, b: &DisplayImage) -> f64 {
    let pairs = a.rgba.iter().zip(&b.rgba).enumerate().filter(|(i, _)| i % 4 != 3);
    pairs.map(|(_, (x, y))| (f64::from(*x) - f64::from(*y)).powi(2)).sum()
}

/// Geometric aliasing, thin wires and silhouettes: MSAA's squared error against the 8×8 truth
/// is below deferred-1x1's on `thin` and on `atrium`, and below 0.5× deferred-1x1's on the edge.
#[test]
fn msaa_is_nearer_the_truth_than_deferred_shading() {
    for (generator, bound) in [(Generator::Thin, 1.0), (Generator::Atrium, 1.0), (Generator::Edge, 0.5)] {
        let (mut renderer, _gpu) = renderer(generator, &lit(), settings(128, 96));
        let truth = renderer.render_truth(8, 64 << 20).unwrap().images.display;
        let deferred = squared_error(&render(&mut renderer, "deferred-1x1").display, &truth);
        let msaa = squared_error(&render(&mut renderer, "msaa-4x").display, &truth);
        println!(
            "{generator}: msaa-4x {msaa:.0} against deferred-1x1 {deferred:.0} ({:.2}×)",
            msaa / deferred
        );
        assert!(
            msaa < bound * deferred,
            "{generator}: msaa-4x's error {msaa} against deferred-1x1's {deferred}"
        );
    }
}

/// Sum of squared differences of the colour channels over the pixels `within` holds.
fn squared_error_within(a: &DisplayImage, b: &DisplayImage, within: &[bool]) -> f64 {
    let pixels = a.rgba.chunks_exact(4).zip(b.rgba.chunks_exact(4)).zip(within);
    let inside = pixels.filter(|(_, inside)| **inside);
    inside.map(|((p, q), _)| (0..3).map(|c| (f64::from(p[c]) - f64::from(q[c])).powi(2)).sum::<f64>()).sum()
}

/// Cut-out edges: the atrium's leaf cards are alpha-masked, and their leaves' outlines lie
/// inside one triangle, where a single alpha test at the pixel's centre keeps or drops all four
/// samples together. Tested per sample, the outlines split pixels into two surfaces, which are
/// shaded per sample: at 128×96, 857 of the foliage's pixels (109 with one test per pixel, only
/// at the cards' own edges), and msaa-4x's error on the foliage and beside it falls to 0.77 of
/// deferred-1x1's (0.95 with one test per pixel). The texture inside a leaf is still sampled
/// once per pixel, as in deferred-1x1.
#[test]
fn msaa_tests_alpha_per_sample_so_cut_out_edges_are_shaded_per_sample() {
    let (mut renderer, _gpu) = renderer(Generator::Atrium, &lit(), settings(128, 96));
    let (scene, _) = generated(Generator::Atrium);
    let masked: Vec<bool> = scene
        .materials
        .iter()
        .map(|m| matches!(m.alpha, aabench_renderer::scene::AlphaMode::Mask { .. }))
        .collect();
    assert!(masked.iter().any(|&m| m), "the atrium has alpha-masked foliage");
    let truth = renderer.render_truth(8, 64 << 20).unwrap().images.display;
    let deferred = renderer.prepare("deferred-1x1".parse().unwrap()).unwrap();
    deferred.render().unwrap();
    let gbuffer = deferred.read_gbuffer().unwrap();
    let (width, height) = (128usize, 96usize);
    let foliage = |x: usize, y: usize| {
        let material = gbuffer.normal_material[y * width + x][3];
        material >= 0.0 && masked[material as usize]
    };
    // The foliage's pixels and their neighbours: a leaf's outline may fall on the pixels beside
    // the ones whose centre it covers.
    let near: Vec<bool> = (0..width * height)
        .map(|i| {
            let (x, y) = (i % width, i / width);
            (y.saturating_sub(1)..(y + 2).min(height))
                .any(|ny| (x.saturating_sub(1)..(x + 2).min(width)).any(|nx| foliage(nx, ny)))
        })
        .collect();
    assert!(near.iter().filter(|&&n| n).count() > 200, "the view holds foliage");
    let deferred = squared_error_within(&render(&mut renderer, "deferred-1x1").display, &truth, &near);
    let msaa = render(&mut renderer, "msaa-4x");
    let error = squared_error_within(&msaa.display, &truth, &near);
    let counts = msaa.sample_counts.expect("msaa-4x records sample counts");
    let split = (0..width * height).filter(|&i| foliage(i % width, i / width) && counts[i] == 4).count();
    println!(
        "foliage: deferred-1x1 {deferred:.0}, msaa-4x {error:.0}; {split} foliage pixels shaded per sample"
    );
    assert!(split >= 400, "{split} foliage pixels shaded per sample");
    assert!(error < 0.85 * deferred, "msaa-4x {error} against deferred-1x1 {deferred}");
}

/// A flat mesh of quads in the plane z = `z`, each given by its corners' (x, y), counter-
/// clockwise seen from +z; a quad's UVs map x ∈ [−2, 2] and y ∈ [2, −2] onto [0, 1]², so that
/// the card's edges lie well inside its texture and its filtering never wraps.
fn quads(z: f32, corners: &[[[f32; 2]; 4]]) -> MeshData {
    let mut mesh = MeshData::default();
    for quad in corners {
        let first = mesh.positions.len() as u32;
        for [x, y] in quad {
            mesh.positions.push([*x, *y, z]);
            mesh.normals.push([0.0, 0.0, 1.0]);
            mesh.uvs.push([(x + 2.0) / 4.0, (2.0 - y) / 4.0]);
        }
        mesh.indices.extend([first, first + 1, first + 2, first, first + 2, first + 3]);
    }
    mesh
}

/// Where the card's cut crosses y (world units, on the card's plane z = 0): a line 7° from
/// vertical through (0.1, 0). The card keeps what lies left of it.
fn cut_x(y: f32) -> f32 {
    0.1 + y * 7f32.to_radians().tan()
}

/// The alpha texture that cuts the card: a ramp of the signed distance to the cut, 0.5 on it and
/// rising by 1 every four texels leftwards. Bilinear filtering reproduces a linear function
/// exactly, so the alpha test at 0.5 finds the cut within the 8-bit rounding (under 0.01 texel).
fn cut_texture(size: u32) -> Vec<u8> {
    let image = image::RgbaImage::from_fn(size, size, |i, j| {
        // The texel's centre on the card.
        let texel = 4.0 / size as f32;
        let (x, y) = ((i as f32 + 0.5) * texel - 2.0, 2.0 - (j as f32 + 0.5) * texel);
        let distance = (x - cut_x(y)) * 7f32.to_radians().cos();
        let alpha = (0.5 - distance / (4.0 * texel)).clamp(0.0, 1.0);
        image::Rgba([255, 255, 255, (alpha * 255.0).round() as u8])
    });
    let mut png = std::io::Cursor::new(Vec::new());
    image.write_to(&mut png, image::ImageFormat::Png).unwrap();
    png.into_inner()
}

/// The height of the bars behind the card, in world units: at 128×96 under 0.9 px.
const BAR_HEIGHT: f32 = 0.03;

/// Where each bar begins along y: every 0.07, so that their edges, 2 px apart, fall at every
/// fraction of a pixel.
fn bar_bottoms() -> impl Iterator<Item = f32> {
    (-40..40).map(|k| k as f32 * 0.07)
}

/// A card before thin horizontal bars before a wall, seen head-on. With `alpha_cut`, the card is
/// the whole square x, y ∈ [−1, 1], alpha-masked by [`cut_texture`]; without, its geometric twin:
/// the part of that square left of the cut, opaque.
fn card_scene(folder: &Folder, alpha_cut: bool) -> aabench_renderer::scene::Scene {
    let mut writer = GltfWriter::new("msaa sample mask test");
    let wall = writer.add_material(&MaterialDesc::new("wall", [0.05; 3], 1.0));
    writer.add_mesh("wall", &quads(-1.0, &[[[-3.0, -3.0], [3.0, -3.0], [3.0, 3.0], [-3.0, 3.0]]]), wall);
    let bars: Vec<[[f32; 2]; 4]> =
        bar_bottoms().map(|y| [[-3.0, y], [3.0, y], [3.0, y + BAR_HEIGHT], [-3.0, y + BAR_HEIGHT]]).collect();
    let bar = writer.add_material(&MaterialDesc::new("bars", [0.35; 3], 1.0));
    writer.add_mesh("bars", &quads(-0.5, &bars), bar);
    let card = if alpha_cut {
        let texture = writer.add_png("cut", &cut_texture(32));
        let material = MaterialDesc::new("card", [0.8; 3], 1.0).textured(texture).masked(0.5);
        (writer.add_material(&material), [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
    } else {
        let corners = [[-1.0, -1.0], [cut_x(-1.0), -1.0], [cut_x(1.0), 1.0], [-1.0, 1.0]];
        (writer.add_material(&MaterialDesc::new("card", [0.8; 3], 1.0)), corners)
    };
    writer.add_mesh("card", &quads(0.0, &[card.1]), card.0);
    writer.add_camera(DVec3::new(0.0, 0.0, 4.0), DVec3::ZERO, 40.0, 0.1, 20.0);
    let path = folder.dir.join(format!("card-{alpha_cut}.glb"));
    writer.write(&path).unwrap();
    load_gltf(&path).unwrap()
}

/// The sample mask's bit i is the sample at the i-th of the standard positions. The card's
/// alpha cut and the bars' geometric edges cross inside some pixels; which of those pixels'
/// samples show the card, a bar or the wall then depends on which samples the mask names, so
/// the cut card must resolve as its geometric twin does: within one code in every pixel whose
/// samples lie further than 0.05 px from the cut. Listing the shader's sample offsets in
/// another order (reversed, or the middle two swapped) moves 9 or 6 of the 18 pixels where the
/// cut and a bar's edge cross, by 13 codes on average.
#[test]
fn msaa_sample_mask_bits_are_the_standard_sample_positions() {
    let folder = Folder::new("msaa-sample-mask");
    let (width, height) = (128u32, 96u32);
    let size = DVec2::new(f64::from(width), f64::from(height));
    let (gpu, _guard) = gpu();
    let images = [true, false].map(|alpha_cut| {
        let scene = card_scene(&folder, alpha_cut);
        let camera = scene.camera.expect("the file's camera");
        let mut renderer =
            SceneRenderer::new(Arc::clone(&gpu), &scene, &camera, &ambient_only(), settings(width, height))
                .expect("scene upload");
        (render(&mut renderer, "msaa-4x"), camera)
    });
    let [(cut, camera), (twin, _)] = images;
    // The cut and a bar's edge on screen: the planes face the camera, so lines stay lines.
    let on_screen =
        |x: f32, y: f32, z: f64| project(&camera, size, DVec3::new(f64::from(x), f64::from(y), z)).0;
    let (bottom, top) = (on_screen(cut_x(-1.0), -1.0, 0.0), on_screen(cut_x(1.0), 1.0, 0.0));
    let across = (top - bottom).perp().normalize();
    let cut_side = |p: DVec2| (p - bottom).dot(across);
    let bar_edges: Vec<f64> =
        bar_bottoms().flat_map(|y| [y, y + BAR_HEIGHT]).map(|y| on_screen(0.0, y, -0.5).y).collect();
    let (mut compared, mut crossed) = (0, 0);
    for y in 0..height {
        for x in 0..width {
            let samples: Vec<DVec2> = SAMPLE_POSITIONS
                .iter()
                .map(|(dx, dy)| DVec2::new(f64::from(x) + dx, f64::from(y) + dy))
                .collect();
            let sides: Vec<f64> = samples.iter().map(|&s| cut_side(s)).collect();
            if sides.iter().any(|d| d.abs() < 0.05) {
                continue;
            }
            compared += 1;
            let pixel = 4 * (y * width + x) as usize;
            let (a, b) = (&cut.display.rgba[pixel..pixel + 3], &twin.display.rgba[pixel..pixel + 3]);
            let step = a.iter().zip(b).map(|(p, q)| p.abs_diff(*q)).max().unwrap();
            assert!(
                step <= 1,
                "pixel ({x}, {y}): alpha cut {a:?}, geometric twin {b:?}, samples' sides {sides:?}"
            );
            let split = |d: &dyn Fn(&DVec2) -> f64| {
                samples.iter().any(|s| d(s) < 0.0) && samples.iter().any(|s| d(s) > 0.0)
            };
            let on_card = (top.y..bottom.y).contains(&(f64::from(y) + 0.5));
            if on_card && split(&|s| cut_side(*s)) && bar_edges.iter().any(|&e| split(&|s| s.y - e)) {
                crossed += 1;
            }
        }
    }
    println!("{compared} pixels compared, {crossed} crossed by the cut and a bar's edge");
    assert!(compared > (width * height) as usize * 9 / 10, "only {compared} pixels compared");
    assert!(crossed >= 10, "only {crossed} pixels where the cut and a bar's edge cross");
}
