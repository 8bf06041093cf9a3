//! Procedural textures for the generated scenes, encoded as PNG. Several are deliberately high
//! frequency (grout lines, fine stripes, checkers): texture aliasing is what anisotropic
//! filtering at shading time has to handle.

use image::{Rgba, RgbaImage};

/// A 32-bit integer hash (lowbias32): deterministic noise without RNG state.
fn hash(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^ (x >> 16)
}

fn hash2(x: i32, y: i32, seed: u32) -> f32 {
    let h = hash((x as u32).wrapping_mul(0x9e37_79b9) ^ hash((y as u32) ^ seed.wrapping_mul(0x85eb_ca6b)));
    (h >> 8) as f32 / (1u32 << 24) as f32
}

/// Smooth value noise in [0, 1], periodic with `period` cells so textures tile.
fn value_noise(x: f32, y: f32, period: i32, seed: u32) -> f32 {
    let (xi, yi) = (x.floor() as i32, y.floor() as i32);
    let (fx, fy) = (x - x.floor(), y - y.floor());
    let smooth = |t: f32| t * t * (3.0 - 2.0 * t);
    let corner = |dx: i32, dy: i32| hash2((xi + dx).rem_euclid(period), (yi + dy).rem_euclid(period), seed);
    let top = corner(0, 0) + (corner(1, 0) - corner(0, 0)) * smooth(fx);
    let bottom = corner(0, 1) + (corner(1, 1) - corner(0, 1)) * smooth(fx);
    top + (bottom - top) * smooth(fy)
}

/// Fractal noise: four octaves of tiling value noise at `cells` cells across the texture.
fn fractal(u: f32, v: f32, cells: i32, seed: u32) -> f32 {
    let mut sum = 0.0;
    let mut weight = 0.5;
    let mut scale = cells;
    for octave in 0..4 {
        sum += weight * value_noise(u * scale as f32, v * scale as f32, scale, seed + octave);
        weight *= 0.5;
        scale *= 2;
    }
    sum / 0.9375
}

fn image(size: u32, texel: impl Fn(f32, f32, u32, u32) -> [f32; 4]) -> RgbaImage {
    RgbaImage::from_fn(size, size, |x, y| {
        let (u, v) = ((x as f32 + 0.5) / size as f32, (y as f32 + 0.5) / size as f32);
        let c = texel(u, v, x, y);
        Rgba(c.map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8))
    })
}

fn mix(a: [f32; 3], b: [f32; 3], t: f32) -> [f32; 3] {
    std::array::from_fn(|i| a[i] + (b[i] - a[i]) * t)
}

fn opaque(c: [f32; 3]) -> [f32; 4] {
    [c[0], c[1], c[2], 1.0]
}

/// Checkered marble tiles, 8 × 8 per texture, with dark grout lines.
pub fn floor_tiles(size: u32) -> RgbaImage {
    let tiles = 8.0;
    image(size, |u, v, _, _| {
        let (tu, tv) = (u * tiles, v * tiles);
        let (fu, fv) = (tu.fract(), tv.fract());
        let grout = 0.04;
        if fu < grout || fv < grout {
            return opaque([0.18, 0.16, 0.14]);
        }
        let dark = (tu.floor() as i32 + tv.floor() as i32) % 2 == 0;
        let vein = fractal(u, v, 4, 7);
        let vein = (1.0 - (vein * 12.0).sin().abs()).powf(8.0);
        let base = if dark { [0.35, 0.22, 0.16] } else { [0.85, 0.8, 0.72] };
        opaque(mix(base, [0.55, 0.5, 0.45], vein * 0.6))
    })
}

/// Running-bond bricks with mortar joints and per-brick colour variation.
pub fn bricks(size: u32) -> RgbaImage {
    let rows = 16.0;
    image(size, |u, v, _, _| {
        let row = (v * rows).floor();
        let shift = if row as i32 % 2 == 0 { 0.0 } else { 0.5 };
        let bricks_per_row = rows / 2.0;
        let column = (u * bricks_per_row + shift).floor();
        let (fu, fv) = ((u * bricks_per_row + shift).fract(), (v * rows).fract());
        if fu < 0.05 || fv < 0.1 {
            return opaque([0.62, 0.6, 0.55]);
        }
        let tint = hash2(column as i32, row as i32, 3);
        let grain = fractal(u, v, 16, 11) * 0.25;
        opaque(mix([0.55, 0.25, 0.16], [0.75, 0.45, 0.3], tint * 0.7 + grain))
    })
}

/// Fine woven stripes: a 6-texel period in one direction and a 2-texel weave across it.
pub fn fabric(size: u32) -> RgbaImage {
    image(size, |_, _, x, y| {
        let stripe = (x / 3) % 2 == 0;
        let weave = ((x + y) / 2) % 2 == 0;
        let base = if stripe { [0.7, 0.08, 0.1] } else { [0.85, 0.65, 0.2] };
        opaque(mix(base, [0.1, 0.05, 0.05], if weave { 0.25 } else { 0.0 }))
    })
}

/// Leaves on a transparent background, for alpha-masked foliage cards.
pub fn leaves(size: u32) -> RgbaImage {
    // Leaf ellipses placed on a jittered grid.
    let cells = 5;
    image(size, |u, v, _, _| {
        let mut best: Option<[f32; 4]> = None;
        for cy in 0..cells {
            for cx in 0..cells {
                let (jx, jy) = (hash2(cx, cy, 21), hash2(cx, cy, 22));
                let centre = (
                    (cx as f32 + 0.2 + 0.6 * jx) / cells as f32,
                    (cy as f32 + 0.2 + 0.6 * jy) / cells as f32,
                );
                let angle = hash2(cx, cy, 23) * std::f32::consts::PI;
                let (sin, cos) = angle.sin_cos();
                let (dx, dy) = (u - centre.0, v - centre.1);
                let (a, b) = ((dx * cos + dy * sin) / 0.09, (-dx * sin + dy * cos) / 0.035);
                if a * a + b * b < 1.0 {
                    let shade = 0.6 + 0.4 * hash2(cx, cy, 24);
                    let midrib = if b.abs() < 0.08 { 0.7 } else { 1.0 };
                    best = Some([0.12 * shade, 0.45 * shade * midrib, 0.1 * shade, 1.0]);
                }
            }
        }
        best.unwrap_or([0.1, 0.3, 0.1, 0.0])
    })
}

/// Sandstone: warm fractal noise.
pub fn stone(size: u32) -> RgbaImage {
    image(size, |u, v, _, _| opaque(mix([0.55, 0.48, 0.38], [0.78, 0.72, 0.6], fractal(u, v, 8, 5))))
}

/// A black and white checkerboard of `cells` × `cells` squares.
pub fn checker(size: u32, cells: u32) -> RgbaImage {
    image(size, |u, v, _, _| {
        let odd = ((u * cells as f32) as u32 + (v * cells as f32) as u32) % 2 == 1;
        opaque(if odd { [0.9; 3] } else { [0.05; 3] })
    })
}

/// Vertical stripes, `count` dark/light pairs across.
pub fn stripes(size: u32, count: u32) -> RgbaImage {
    image(size, |u, _, _, _| {
        let dark = (u * count as f32).fract() < 0.5;
        opaque(if dark { [0.1, 0.1, 0.12] } else { [0.85, 0.85, 0.8] })
    })
}

/// Encodes an image as PNG bytes.
pub fn png(image: &RgbaImage) -> Vec<u8> {
    let mut bytes = std::io::Cursor::new(Vec::new());
    image.write_to(&mut bytes, image::ImageFormat::Png).expect("PNG encoding to memory");
    bytes.into_inner()
}

/// A tangent-space normal map of `cells`² round bumps (glTF's encoding: +X right, +Y up the
/// image, +Z out of the surface).
pub fn bumps(size: u32, cells: u32) -> RgbaImage {
    image(size, |u, v, _, _| {
        // Each bump is a cosine dome; its slope gives the normal.
        let (cu, cv) = ((u * cells as f32).fract() - 0.5, (v * cells as f32).fract() - 0.5);
        let r = (cu * cu + cv * cv).sqrt();
        let slope = if r < 0.5 { (r * 2.0 * std::f32::consts::PI).sin() * 1.5 } else { 0.0 };
        let (dx, dy) = if r > 1e-6 { (cu / r * slope, -cv / r * slope) } else { (0.0, 0.0) };
        let n = glam::Vec3::new(dx, dy, 1.0).normalize();
        [n.x * 0.5 + 0.5, n.y * 0.5 + 0.5, n.z * 0.5 + 0.5, 1.0]
    })
}
