//! Mesh primitives for the generated scenes. Every builder returns geometry around the origin;
//! [`Mesh::append`] places it in the world.

use std::f32::consts::{PI, TAU};

use glam::{Affine3A, Vec2, Vec3};

use crate::scene::write::MeshData;

pub type Mesh = MeshData;

impl MeshData {
    fn push(&mut self, position: Vec3, normal: Vec3, uv: Vec2) -> u32 {
        self.positions.push(position.to_array());
        self.normals.push(normal.to_array());
        self.uvs.push(uv.to_array());
        (self.positions.len() - 1) as u32
    }

    /// Appends `other` moved by `transform` (normals follow the rotation; transforms here
    /// are rigid or uniformly scaled).
    pub fn append(&mut self, other: &Mesh, transform: Affine3A) {
        let base = self.positions.len() as u32;
        for ((p, n), uv) in other.positions.iter().zip(&other.normals).zip(&other.uvs) {
            self.positions.push(transform.transform_point3(Vec3::from(*p)).to_array());
            self.normals.push(transform.transform_vector3(Vec3::from(*n)).normalize_or_zero().to_array());
            self.uvs.push(*uv);
        }
        self.indices.extend(other.indices.iter().map(|i| base + i));
    }

    /// A grid of `columns` × `rows` quads over the parametric square [0, 1]²; `at` gives the
    /// position, normal and UV of each grid point.
    pub fn surface(columns: u32, rows: u32, at: impl Fn(f32, f32) -> (Vec3, Vec3, Vec2)) -> Mesh {
        let mut mesh = Mesh::default();
        for j in 0..=rows {
            for i in 0..=columns {
                let (p, n, uv) = at(i as f32 / columns as f32, j as f32 / rows as f32);
                mesh.push(p, n, uv);
            }
        }
        let stride = columns + 1;
        for j in 0..rows {
            for i in 0..columns {
                let a = j * stride + i;
                let (b, c, d) = (a + 1, a + stride, a + stride + 1);
                mesh.indices.extend([a, c, b, b, c, d]);
            }
        }
        mesh
    }
}

/// An axis-aligned box centred on the origin. UVs are world units times `uv_scale`, so a
/// texture keeps its scale on boxes of any size.
pub fn cuboid(size: Vec3, uv_scale: f32) -> Mesh {
    let half = size * 0.5;
    let mut mesh = Mesh::default();
    // Each face: its normal and two in-plane axes.
    let faces = [
        (Vec3::X, Vec3::Z, Vec3::Y),
        (Vec3::NEG_X, Vec3::Z, Vec3::Y),
        (Vec3::Y, Vec3::X, Vec3::Z),
        (Vec3::NEG_Y, Vec3::X, Vec3::Z),
        (Vec3::Z, Vec3::X, Vec3::Y),
        (Vec3::NEG_Z, Vec3::X, Vec3::Y),
    ];
    for (normal, u, v) in faces {
        let centre = normal * half;
        let (extent_u, extent_v) = ((u * half).length(), (v * half).length());
        let base = mesh.positions.len() as u32;
        for (su, sv) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
            let p = centre + u * (su * extent_u) + v * (sv * extent_v);
            let uv = Vec2::new(p.dot(u), p.dot(v)) * uv_scale;
            mesh.push(p, normal, uv);
        }
        mesh.indices.extend([base, base + 1, base + 2, base + 2, base + 1, base + 3]);
    }
    mesh
}

/// A horizontal rectangle in the XZ plane facing +Y, centred on the origin, in
/// `columns` × `rows` quads.
pub fn floor(width: f32, depth: f32, columns: u32, rows: u32, uv_scale: f32) -> Mesh {
    Mesh::surface(columns, rows, |s, t| {
        let p = Vec3::new((s - 0.5) * width, 0.0, (t - 0.5) * depth);
        (p, Vec3::Y, Vec2::new(p.x, p.z) * uv_scale)
    })
}

/// A vertical rectangle in the XY plane facing +Z, centred on the origin.
pub fn wall(width: f32, height: f32, columns: u32, rows: u32, uv_scale: f32) -> Mesh {
    Mesh::surface(columns, rows, |s, t| {
        let p = Vec3::new((s - 0.5) * width, (0.5 - t) * height, 0.0);
        (p, Vec3::Z, Vec2::new(p.x, -p.y) * uv_scale)
    })
}

/// A vertical cylinder from y = 0 to `height` (no caps) whose radius at angle θ and height
/// fraction t is `radius(θ, t)`.
pub fn cylinder(height: f32, segments: u32, rings: u32, radius: impl Fn(f32, f32) -> f32) -> Mesh {
    Mesh::surface(segments, rings, |s, t| {
        let angle = s * TAU;
        let (sin, cos) = angle.sin_cos();
        let r = radius(angle, t);
        // The normal of a radially modulated cylinder: the radial direction tilted by dr/dθ.
        let step = 1e-3;
        let slope = (radius(angle + step, t) - radius(angle - step, t)) / (2.0 * step);
        let radial = Vec3::new(cos, 0.0, sin);
        let tangent = Vec3::new(-sin, 0.0, cos);
        let normal = (radial * r - tangent * slope).normalize();
        (Vec3::new(cos * r, t * height, sin * r), normal, Vec2::new(s * 2.0, t * height))
    })
}

/// A plain cylinder of constant radius.
pub fn rod(radius: f32, height: f32, segments: u32) -> Mesh {
    cylinder(height, segments, 1, |_, _| radius)
}

/// A capsule along y centred on the origin: a cylinder `length` long between two hemispheres
/// of `radius`. The first and last quarter of the rings round its ends; the middle half runs
/// straight, so that a skin can bend it there.
pub fn capsule(radius: f32, length: f32, segments: u32, rings: u32) -> Mesh {
    let half = length / 2.0;
    Mesh::surface(segments, rings, |s, t| {
        let (phi, y) = if t < 0.25 {
            (t * TAU, half)
        } else if t > 0.75 {
            ((t - 0.5) * TAU, -half)
        } else {
            (PI / 2.0, half - (t - 0.25) * 2.0 * length)
        };
        let theta = s * TAU;
        let n = Vec3::new(phi.sin() * theta.cos(), phi.cos(), phi.sin() * theta.sin());
        (n * radius + Vec3::Y * y, n, Vec2::new(s, t * 2.0))
    })
}

pub fn sphere(radius: f32, segments: u32, rings: u32) -> Mesh {
    Mesh::surface(segments, rings, |s, t| {
        let (theta, phi) = (s * TAU, t * PI);
        let n = Vec3::new(phi.sin() * theta.cos(), phi.cos(), phi.sin() * theta.sin());
        (n * radius, n, Vec2::new(s * 4.0, t * 2.0))
    })
}

/// A torus around the Y axis.
pub fn torus(major: f32, minor: f32, segments: u32, sides: u32) -> Mesh {
    Mesh::surface(segments, sides, |s, t| {
        let (theta, phi) = (s * TAU, t * TAU);
        let centre = Vec3::new(theta.cos(), 0.0, theta.sin()) * major;
        let n = Vec3::new(phi.cos() * theta.cos(), phi.sin(), phi.cos() * theta.sin());
        (centre + n * minor, n, Vec2::new(s * 8.0, t * 2.0))
    })
}

/// A semicircular arch band in the XY plane (springing at y = 0), `depth` thick along Z:
/// front and back faces, the intrados (inner curve) and extrados (outer curve).
pub fn arch(inner: f32, outer: f32, depth: f32, segments: u32, uv_scale: f32) -> Mesh {
    let mut mesh = Mesh::default();
    let point = |r: f32, s: f32, z: f32| {
        let angle = PI * s;
        Vec3::new(angle.cos() * r, angle.sin() * r, z)
    };
    for side in [1.0f32, -1.0] {
        let z = side * depth * 0.5;
        mesh.append(
            &Mesh::surface(segments, 1, |s, t| {
                let p = point(inner + (outer - inner) * t, s, z);
                (p, Vec3::Z * side, Vec2::new(p.x, p.y) * uv_scale)
            }),
            Affine3A::IDENTITY,
        );
    }
    for (r, inward) in [(inner, -1.0f32), (outer, 1.0)] {
        mesh.append(
            &Mesh::surface(segments, 1, |s, t| {
                let p = point(r, s, (t - 0.5) * depth);
                let n = Vec3::new(p.x, p.y, 0.0).normalize() * inward;
                (p, n, Vec2::new(s * PI * r, p.z) * uv_scale)
            }),
            Affine3A::IDENTITY,
        );
    }
    mesh
}

/// A hanging curtain in the XY plane: `width` × `height` from y = 0 down, with `folds`
/// sinusoidal folds of amplitude `depth` along X.
pub fn curtain(width: f32, height: f32, folds: f32, depth: f32, columns: u32, rows: u32) -> Mesh {
    Mesh::surface(columns, rows, |s, t| {
        let phase = s * folds * TAU;
        // Folds open up towards the hem.
        let amplitude = depth * (0.6 + 0.4 * t);
        let z = phase.sin() * amplitude;
        let dz_dx = phase.cos() * amplitude * folds * TAU / width;
        let normal = Vec3::new(-dz_dx, 0.0, 1.0).normalize();
        let p = Vec3::new((s - 0.5) * width, -t * height, z);
        (p, normal, Vec2::new(s * width, t * height))
    })
}

/// A single quad in the XY plane facing +Z, centred on the origin, UVs over [0, 1]².
pub fn quad(width: f32, height: f32) -> Mesh {
    Mesh::surface(1, 1, |s, t| {
        (Vec3::new((s - 0.5) * width, (0.5 - t) * height, 0.0), Vec3::Z, Vec2::new(s, t))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn surface_counts_match_the_grid() {
        let mesh = floor(2.0, 2.0, 3, 4, 1.0);
        assert_eq!(mesh.positions.len(), 4 * 5);
        assert_eq!(mesh.triangle_count(), 3 * 4 * 2);
        assert!(mesh.indices.iter().all(|&i| (i as usize) < mesh.positions.len()));
    }

    #[test]
    fn cuboid_faces_point_outwards() {
        let mesh = cuboid(Vec3::new(1.0, 2.0, 3.0), 1.0);
        for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
            assert!(Vec3::from(*p).dot(Vec3::from(*n)) > 0.0);
        }
    }

    #[test]
    fn sphere_normals_are_unit_and_radial() {
        let mesh = sphere(2.0, 16, 8);
        for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
            assert!((Vec3::from(*n).length() - 1.0).abs() < 1e-5);
            assert!((Vec3::from(*p) - Vec3::from(*n) * 2.0).length() < 1e-5);
        }
    }
}
