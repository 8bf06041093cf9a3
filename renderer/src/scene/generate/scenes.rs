//! The generated scenes. Units are metres, +Y is up.

use glam::{Affine3A, Quat, Vec3};

use super::mesh::{self, Mesh};
use super::textures;
use super::{Builder, figure};
use crate::scene::write::MaterialDesc;

const TEXTURE_SIZE: u32 = 512;

fn at(x: f32, y: f32, z: f32) -> Affine3A {
    Affine3A::from_translation(Vec3::new(x, y, z))
}

fn turned(angle_y: f32, x: f32, y: f32, z: f32) -> Affine3A {
    Affine3A::from_rotation_translation(Quat::from_rotation_y(angle_y), Vec3::new(x, y, z))
}

/// A Sponza-like court, 30 m × 13 m, two storeys of colonnades along both long sides.
pub(super) fn atrium(b: &mut Builder) {
    let court = Atrium::materials(b);
    b.mesh(court.floor).append(
        &mesh::floor(2.0 * Atrium::HALF_LENGTH, 2.0 * Atrium::OUTER, 60, 26, 0.5),
        Affine3A::IDENTITY,
    );
    let height = 10.25;
    for side in [-1.0f32, 1.0] {
        let wall = mesh::cuboid(Vec3::new(2.0 * Atrium::HALF_LENGTH, height, 0.3), 0.25);
        b.mesh(court.brick).append(&wall, at(0.0, height / 2.0, side * (Atrium::OUTER + 0.15)));
        let end = mesh::cuboid(Vec3::new(0.3, height, 2.0 * Atrium::OUTER), 0.25);
        b.mesh(court.brick).append(&end, at(side * (Atrium::HALF_LENGTH + 0.15), height / 2.0, 0.0));
    }
    court.colonnades(b);
    court.balustrades(b);
    // Curtains hung in the upper arcade of one side.
    let drape = mesh::curtain(2.1, 2.9, 6.0, 0.08, 48, 64);
    for pair in court.columns.windows(2) {
        b.mesh(court.curtain).append(&drape, at((pair[0] + pair[1]) / 2.0, 8.6, -(Atrium::COURT + 0.35)));
    }
    court.planters(b);
    b.camera([-13.0, 1.8, 0.0], [10.0, 3.2, 0.0], 62.0, 80.0);
}

/// The atrium's materials and the places of its columns along the court.
struct Atrium {
    floor: usize,
    brick: usize,
    curtain: usize,
    foliage: usize,
    sandstone: usize,
    bronze: usize,
    columns: Vec<f32>,
}

impl Atrium {
    /// Half the court's length, the colonnades' distance from its axis, the outer walls'.
    const HALF_LENGTH: f32 = 15.0;
    const COURT: f32 = 4.0;
    const OUTER: f32 = 6.6;

    fn materials(b: &mut Builder) -> Atrium {
        let tiles = b.texture("floor-tiles", &textures::floor_tiles(TEXTURE_SIZE));
        let bricks = b.texture("bricks", &textures::bricks(TEXTURE_SIZE));
        let fabric = b.texture("fabric", &textures::fabric(TEXTURE_SIZE));
        let leaves = b.texture("leaves", &textures::leaves(TEXTURE_SIZE));
        let stone = b.texture("stone", &textures::stone(TEXTURE_SIZE));
        let bay = 2.5f32;
        Atrium {
            floor: b.material(MaterialDesc::new("floor", [1.0; 3], 0.35).textured(tiles)),
            brick: b.material(MaterialDesc::new("brick", [1.0; 3], 0.8).textured(bricks)),
            curtain: b.material(MaterialDesc::new("curtain", [1.0; 3], 0.7).textured(fabric).double_sided()),
            foliage: b.material(
                MaterialDesc::new("foliage", [1.0; 3], 0.6).textured(leaves).masked(0.5).double_sided(),
            ),
            sandstone: b.material(MaterialDesc::new("sandstone", [1.0; 3], 0.55).textured(stone)),
            bronze: b.material(MaterialDesc::new("bronze", [0.8, 0.5, 0.25], 0.3).metallic(1.0)),
            columns: (0..11).map(|i| -12.5 + bay * i as f32).collect(),
        }
    }

    /// Two storeys of fluted columns, arches, entablatures and the gallery floor.
    fn colonnades(&self, b: &mut Builder) {
        // Per storey: column foot, column height, radius, arch inner radius, arch outer radius.
        let storeys = [(0.0f32, 3.6f32, 0.3f32, 0.95f32, 1.25f32), (5.45, 3.0, 0.25, 1.0, 1.25)];
        for (storey, &(foot, shaft, radius, inner, outer_radius)) in storeys.iter().enumerate() {
            // Fluted shaft with a slight taper (entasis).
            let column = mesh::cylinder(shaft, 48, 36, |angle, t| {
                radius * (1.0 + 0.035 * (20.0 * angle).cos()) * (1.0 - 0.08 * t)
            });
            let base = mesh::cuboid(Vec3::new(2.6 * radius, 0.3, 2.6 * radius), 1.0);
            let capital = mesh::cuboid(Vec3::new(2.8 * radius, 0.3, 2.8 * radius), 1.0);
            let spring = foot + shaft + 0.3;
            let arch = mesh::arch(inner, outer_radius, 2.0 * radius, 48, 1.0);
            for side in [-1.0f32, 1.0] {
                let z = side * Atrium::COURT;
                for &x in &self.columns {
                    b.mesh(self.sandstone).append(&column, at(x, foot, z));
                    b.mesh(self.sandstone).append(&base, at(x, foot + 0.15, z));
                    b.mesh(self.sandstone).append(&capital, at(x, foot + shaft + 0.15, z));
                }
                for pair in self.columns.windows(2) {
                    b.mesh(self.sandstone).append(&arch, at((pair[0] + pair[1]) / 2.0, spring, z));
                }
                // The entablature over the arches, and the gallery floor behind it.
                let top = spring + outer_radius;
                let beam = mesh::cuboid(Vec3::new(2.0 * Atrium::HALF_LENGTH, 0.3, 0.7), 1.0);
                b.mesh(self.sandstone).append(&beam, at(0.0, top + 0.15, z));
                if storey == 0 {
                    let depth = Atrium::OUTER - Atrium::COURT;
                    let slab = mesh::cuboid(Vec3::new(2.0 * Atrium::HALF_LENGTH, 0.3, depth), 0.5);
                    let z = side * (Atrium::COURT + Atrium::OUTER) / 2.0;
                    b.mesh(self.floor).append(&slab, at(0.0, top + 0.15, z));
                }
            }
        }
    }

    /// Upper-storey balustrades: a rail over bulging balusters every 15 cm.
    fn balustrades(&self, b: &mut Builder) {
        let baluster = mesh::cylinder(0.9, 12, 8, |_, t| 0.025 + 0.02 * (t * std::f32::consts::PI).sin());
        let rail = mesh::cuboid(Vec3::new(2.0 * Atrium::HALF_LENGTH, 0.08, 0.14), 1.0);
        let gallery = 5.45;
        for side in [-1.0f32, 1.0] {
            let z = side * (Atrium::COURT - 0.3);
            b.mesh(self.sandstone).append(&rail, at(0.0, gallery + 0.94, z));
            for pair in self.columns.windows(2) {
                let mut x = pair[0] + 0.35;
                while x < pair[1] - 0.3 {
                    b.mesh(self.bronze).append(&baluster, at(x, gallery, z));
                    x += 0.15;
                }
            }
        }
    }

    /// Planters down the middle of the court, each with a bush of alpha-masked leaf cards.
    fn planters(&self, b: &mut Builder) {
        let planter = mesh::cuboid(Vec3::new(0.8, 0.6, 0.8), 1.0);
        let card = mesh::quad(0.6, 0.6);
        for x in [-10.0f32, -6.0, -2.0, 2.0, 6.0, 10.0] {
            b.mesh(self.sandstone).append(&planter, at(x, 0.3, 0.0));
            for _ in 0..90 {
                let offset = Vec3::new(b.rng.range(-0.5, 0.5), b.rng.range(0.7, 1.7), b.rng.range(-0.5, 0.5));
                let rotation = Quat::from_euler(
                    glam::EulerRot::YXZ,
                    b.rng.range(0.0, std::f32::consts::TAU),
                    b.rng.range(-0.6, 0.6),
                    b.rng.range(-0.6, 0.6),
                );
                let place = Affine3A::from_rotation_translation(rotation, Vec3::new(x, 0.0, 0.0) + offset);
                b.mesh(self.foliage).append(&card, place);
            }
        }
    }
}

/// Thin geometry and grazing planes: what a single sample per pixel cannot resolve.
pub(super) fn thin(b: &mut Builder) {
    let checks = b.texture("checker", &textures::checker(TEXTURE_SIZE, 8));
    let stripes = b.texture("stripes", &textures::stripes(TEXTURE_SIZE, 32));
    let ground = b.material(MaterialDesc::new("ground", [1.0; 3], 0.8).textured(checks));
    let facade = b.material(MaterialDesc::new("facade", [1.0; 3], 0.6).textured(stripes));
    let steel = b.material(MaterialDesc::new("steel", [0.75, 0.75, 0.78], 0.35).metallic(1.0));
    let wood = b.material(MaterialDesc::new("wood", [0.6, 0.45, 0.3], 0.7));
    let cable = b.material(MaterialDesc::new("cable", [0.05, 0.05, 0.05], 0.5));

    b.mesh(ground).append(&mesh::floor(400.0, 400.0, 40, 40, 0.5), Affine3A::IDENTITY);
    // A long striped wall running away from the camera: seen at a grazing angle.
    let wall = mesh::wall(120.0, 6.0, 60, 3, 0.25);
    b.mesh(facade).append(&wall, turned(std::f32::consts::FRAC_PI_2, -4.0, 3.0, -55.0));

    // A chain-link fence: wires 1.5 cm thick on a 12 cm diagonal grid, 20 m × 2 m.
    let (fence_width, fence_height, spacing) = (20.0f32, 2.0f32, 0.12f32);
    let diagonal = fence_height * std::f32::consts::SQRT_2;
    let strand = mesh::cuboid(Vec3::new(0.015, diagonal, 0.015), 1.0);
    let mut x = -fence_width / 2.0 - fence_height;
    while x < fence_width / 2.0 {
        for lean in [-1.0f32, 1.0] {
            let rotation = Quat::from_rotation_z(lean * std::f32::consts::FRAC_PI_4);
            let place =
                Affine3A::from_rotation_translation(rotation, Vec3::new(x + fence_height / 2.0, 1.0, -8.0));
            b.mesh(steel).append(&clip_x(&strand, place, fence_width / 2.0), Affine3A::IDENTITY);
        }
        x += spacing;
    }
    for post in 0..=5 {
        let px = -fence_width / 2.0 + post as f32 * fence_width / 5.0;
        b.mesh(steel).append(&mesh::rod(0.04, 2.1, 16), at(px, 0.0, -8.0));
    }

    // A picket fence receding along the view: slats 5 cm wide every 10 cm.
    let slat = mesh::cuboid(Vec3::new(0.02, 1.1, 0.05), 1.0);
    let mut z = 2.0f32;
    while z > -80.0 {
        b.mesh(wood).append(&slat, at(3.0, 0.55, z));
        z -= 0.1;
    }
    b.mesh(wood).append(&mesh::cuboid(Vec3::new(0.03, 0.06, 82.0), 1.0), at(3.0, 0.9, -39.0));

    // Power lines: sagging cables 1.6 cm thick between two poles 80 m apart.
    let poles = [-40.0f32, 40.0];
    for &px in &poles {
        b.mesh(wood).append(&mesh::rod(0.12, 9.0, 16), at(px, 0.0, -30.0));
    }
    for wire in 0..5 {
        let y = 8.6 - 0.45 * wire as f32;
        let z = -30.0 + (wire as f32 - 2.0) * 0.35;
        let segments = 64;
        for s in 0..segments {
            let (t0, t1) = (s as f32 / segments as f32, (s + 1) as f32 / segments as f32);
            let point = |t: f32| {
                let x = poles[0] + (poles[1] - poles[0]) * t;
                Vec3::new(x, y - 2.5 * 4.0 * t * (1.0 - t), z)
            };
            b.mesh(cable).append(&segment(point(t0), point(t1), 0.008, 6), Affine3A::IDENTITY);
        }
    }

    b.camera([0.0, 1.6, 6.0], [0.0, 1.9, -20.0], 60.0, 400.0);
}

/// A rod of `radius` from `a` to `b`.
fn segment(a: Vec3, b: Vec3, radius: f32, sides: u32) -> Mesh {
    let length = (b - a).length();
    let rotation = Quat::from_rotation_arc(Vec3::Y, (b - a) / length);
    let mut out = Mesh::default();
    out.append(&mesh::rod(radius, length, sides), Affine3A::from_rotation_translation(rotation, a));
    out
}

/// `part` moved by `place`, dropped if its centre lies beyond |x| = limit (keeps the diagonal
/// fence strands inside the fence's width).
fn clip_x(part: &Mesh, place: Affine3A, limit: f32) -> Mesh {
    let mut out = Mesh::default();
    if place.translation.x.abs() <= limit {
        out.append(part, place);
    }
    out
}

/// Glossy spheres and tori on a dark floor under five coloured point lights.
pub(super) fn specular(b: &mut Builder) {
    let floor = b.material(MaterialDesc::new("floor", [0.08, 0.08, 0.09], 0.45));
    b.mesh(floor).append(&mesh::floor(24.0, 24.0, 24, 24, 1.0), Affine3A::IDENTITY);
    let ball = mesh::sphere(0.45, 96, 48);
    let colours = [[0.9, 0.1, 0.1], [0.95, 0.8, 0.3], [0.2, 0.5, 0.95], [0.9, 0.9, 0.9], [0.2, 0.8, 0.3]];
    for row in 0..3 {
        for (column, colour) in colours.iter().enumerate() {
            let roughness = 0.04 + 0.08 * (row * 5 + column) as f32 / 14.0 * 4.0;
            let metallic = if (row + column) % 2 == 0 { 1.0 } else { 0.0 };
            let name = format!("sphere-{row}-{column}");
            let material = b.material(MaterialDesc::new(&name, *colour, roughness).metallic(metallic));
            let place = at(-2.6 + 1.3 * column as f32, 0.45, -1.3 * row as f32);
            b.mesh(material).append(&ball, place);
        }
    }
    let ring = mesh::torus(0.5, 0.14, 96, 32);
    let chrome = b.material(MaterialDesc::new("chrome", [0.95, 0.95, 0.95], 0.06).metallic(1.0));
    for (i, x) in [-3.2f32, -1.1, 1.1, 3.2].into_iter().enumerate() {
        let tilt = Quat::from_rotation_x(0.9 + 0.3 * i as f32) * Quat::from_rotation_z(0.4 * i as f32);
        b.mesh(chrome).append(&ring, Affine3A::from_rotation_translation(tilt, Vec3::new(x, 0.7, 1.4)));
    }
    b.camera([0.0, 1.7, 3.9], [0.0, 0.35, -0.9], 52.0, 60.0);
}

/// A closed room, 10 × 4 × 8 m, with boxes and a pillar around one point light.
pub(super) fn shadow_room(b: &mut Builder) {
    let tiles = b.texture("floor-tiles", &textures::floor_tiles(TEXTURE_SIZE));
    let plaster = b.texture("plaster", &textures::stone(TEXTURE_SIZE));
    let floor = b.material(MaterialDesc::new("floor", [1.0; 3], 0.4).textured(tiles));
    let walls = b.material(MaterialDesc::new("walls", [0.9, 0.88, 0.85], 0.9).textured(plaster));
    let crate_ = b.material(MaterialDesc::new("boxes", [0.55, 0.4, 0.25], 0.7));
    let (width, height, depth) = (10.0f32, 4.0f32, 8.0f32);
    b.mesh(floor).append(&mesh::floor(width, depth, 20, 16, 0.5), Affine3A::IDENTITY);
    // The ceiling: a floor turned upside down, facing into the room.
    let ceiling = Affine3A::from_rotation_translation(
        Quat::from_rotation_x(std::f32::consts::PI),
        Vec3::new(0.0, height, 0.0),
    );
    b.mesh(walls).append(&mesh::floor(width, depth, 10, 8, 0.5), ceiling);
    for (angle, distance, span) in [
        (0.0f32, depth / 2.0, width),
        (std::f32::consts::PI, depth / 2.0, width),
        (std::f32::consts::FRAC_PI_2, width / 2.0, depth),
        (-std::f32::consts::FRAC_PI_2, width / 2.0, depth),
    ] {
        let wall = mesh::wall(span, height, 10, 4, 0.5);
        let (sin, cos) = angle.sin_cos();
        b.mesh(walls).append(&wall, turned(angle, -sin * distance, height / 2.0, -cos * distance));
    }
    for _ in 0..14 {
        let size = Vec3::new(b.rng.range(0.4, 1.2), b.rng.range(0.4, 1.2), b.rng.range(0.4, 1.2));
        let (x, z) = (b.rng.range(-4.0, 4.0), b.rng.range(-3.2, 3.2));
        if x.abs() < 1.0 && z.abs() < 1.0 {
            continue; // Keep the light's surroundings clear.
        }
        let spin = b.rng.range(0.0, 1.5);
        b.mesh(crate_).append(&mesh::cuboid(size, 1.0), turned(spin, x, size.y / 2.0, z));
    }
    b.mesh(walls).append(&mesh::rod(0.3, height, 48), at(2.5, 0.0, 1.5));
    b.camera([-4.3, 2.3, 3.6], [1.0, 0.7, -1.0], 70.0, 40.0);
}

/// Texture aliasing alone: a checkered ground 300 m deep seen from 1.2 m up, so its cells are
/// magnified at the camera's feet, a few pixels wide some metres on and far below a pixel at
/// the horizon; a striped wall along the view at a grazing angle; and a finely checkered panel
/// facing the camera whose cells are about two pixels wide at the quick tier. All of it is flat
/// and rough: the only edges are the panel's and the horizon, so what aliases is the texture.
pub(super) fn texture(b: &mut Builder) {
    let fine = b.texture("checker-16", &textures::checker(TEXTURE_SIZE, 16));
    let finer = b.texture("checker-32", &textures::checker(TEXTURE_SIZE, 32));
    let stripes = b.texture("stripes-64", &textures::stripes(TEXTURE_SIZE, 64));
    let ground = b.material(MaterialDesc::new("ground", [1.0; 3], 0.9).textured(fine));
    let wall = b.material(MaterialDesc::new("wall", [1.0; 3], 0.9).textured(stripes));
    let panel = b.material(MaterialDesc::new("panel", [1.0; 3], 0.9).textured(finer));
    // One repeat of the 16-cell checker per metre: cells 6.25 cm wide.
    b.mesh(ground).append(&mesh::floor(300.0, 300.0, 30, 30, 1.0), Affine3A::IDENTITY);
    let long_wall = mesh::wall(150.0, 5.0, 75, 2, 0.5);
    b.mesh(wall).append(&long_wall, turned(-std::f32::consts::FRAC_PI_2, 3.5, 2.5, -70.0));
    // 2 m × 1.5 m, 32 cells across a 2 m repeat.
    b.mesh(panel).append(&mesh::wall(2.0, 1.5, 1, 1, 0.5), at(-1.4, 1.6, -5.0));
    b.camera([0.0, 1.2, 4.0], [0.0, 0.6, -20.0], 60.0, 400.0);
}

/// Five taut wires 4 mm thick, tilted a few degrees, and a fence of slats 1 cm wide every 6 cm,
/// 10 m from the camera before a plain light wall 30 m away: at 1024×768 a pixel there is 1.5 cm
/// wide, so a wire covers a quarter of a pixel's width and a slat two thirds of one pixel in
/// four. Under a slow pan they cross pixel centres at every phase: single samples catch them or
/// miss them from frame to frame.
pub(super) fn wire(b: &mut Builder) {
    let wall = b.material(MaterialDesc::new("wall", [0.8, 0.78, 0.72], 0.9));
    let cable = b.material(MaterialDesc::new("cable", [0.04, 0.04, 0.04], 0.5));
    let wood = b.material(MaterialDesc::new("wood", [0.35, 0.25, 0.15], 0.8));
    b.mesh(wall).append(&mesh::wall(80.0, 40.0, 1, 1, 1.0), at(0.0, 0.0, -30.0));
    b.mesh(wall).append(&mesh::floor(80.0, 40.0, 1, 1, 1.0), at(0.0, -3.0, -10.0));
    for wire in 0..5 {
        let y = 2.2 - 0.3 * wire as f32;
        let tilt = (1.5 + wire as f32) * std::f32::consts::PI / 180.0;
        let (dx, dy) = (8.0 * tilt.cos(), 8.0 * tilt.sin());
        let a = Vec3::new(-dx, y - dy, -10.0);
        b.mesh(cable).append(&segment(a, Vec3::new(dx, y + dy, -10.0), 0.002, 6), Affine3A::IDENTITY);
    }
    let slat = mesh::cuboid(Vec3::new(0.01, 1.6, 0.01), 1.0);
    for i in 0..60 {
        b.mesh(wood).append(&slat, at(-1.8 + 0.06 * i as f32, -1.5, -10.0));
    }
    b.camera([0.0, 0.0, 0.0], [0.0, 0.0, -10.0], 60.0, 100.0);
}

/// A crate 0.8 m wide, checkered in 5 cm cells, behind five bars 2 cm wide, sliding left to right
/// over a tiled floor 4 m from a still camera, before a brick wall 3 m further. Its speed,
/// 5.77 m/s, moves it 4 pixels a frame at 60 frames a second in the quick tier's 256×192 view
/// (a 60° vertical field: 166 pixels of focal length) and 16 at the nightly's 1024×768: its
/// trailing edge uncovers the wall's bricks, where a history that is not rejected ghosts.
pub(super) fn crossing(b: &mut Builder) {
    stage(b);
    let checks = b.texture("checker-16", &textures::checker(TEXTURE_SIZE, 16));
    let crate_ = b.material(MaterialDesc::new("crate", [1.0; 3], 0.6).textured(checks));
    let steel = b.material(MaterialDesc::new("bars", [0.1, 0.1, 0.12], 0.3).metallic(1.0));
    // One repeat of the 16-cell checker per 0.8 m: cells 5 cm wide.
    let body = mesh::cuboid(Vec3::new(0.8, 0.8, 0.4), 1.25);
    let mut bars = Mesh::default();
    for i in 0..5 {
        bars.append(&mesh::cuboid(Vec3::new(0.02, 0.8, 0.02), 1.0), at(-0.32 + 0.16 * i as f32, 0.0, 0.25));
    }
    let (speed, from, seconds) = (stage_speed(), -0.9f32, 2.0f32);
    b.moving(
        "crossing",
        &[(crate_, body), (steel, bars)],
        &[0.0, seconds],
        &[[from, -0.6, 0.0], [from + speed * seconds, -0.6, 0.0]],
    );
    stage_camera(b);
}

/// A striped figure, skinned on an eleven-joint skeleton, striding across a brick wall and a
/// tiled floor before a still camera: what a deforming object leaves behind.
pub(super) fn walker(b: &mut Builder) {
    stage(b);
    let stripes = b.texture("stripes-24", &textures::stripes(TEXTURE_SIZE, 24));
    let suit = b.material(MaterialDesc::new("suit", [1.0; 3], 0.6).textured(stripes));
    // The feet meet the floor where the legs stand straight; the figure strides as fast as the
    // crossing crate slides.
    let seconds = 2.0;
    figure::walker(b, "walk", suit, Vec3::new(-1.1, -0.055, 0.5), stage_speed() * seconds, seconds);
    stage_camera(b);
}

/// The stage of the moving-object scenes: a brick wall 3 m behind the origin over a tiled floor
/// 1 m below it.
fn stage(b: &mut Builder) {
    let bricks = b.texture("bricks", &textures::bricks(TEXTURE_SIZE));
    let tiles = b.texture("floor-tiles", &textures::floor_tiles(TEXTURE_SIZE));
    let wall = b.material(MaterialDesc::new("wall", [1.0; 3], 0.9).textured(bricks));
    let floor = b.material(MaterialDesc::new("floor", [1.0; 3], 0.5).textured(tiles));
    b.mesh(wall).append(&mesh::wall(12.0, 6.0, 6, 3, 0.25), at(0.0, 2.0, -3.0));
    b.mesh(floor).append(&mesh::floor(12.0, 10.0, 12, 10, 0.5), at(0.0, -1.0, 0.0));
}

/// How fast an object crosses the stage, in m/s: 4 px a frame at 4 m from [`stage_camera`] in
/// the quick tier (4 · 4 m / 166.28 px × 60 frames a second), 5.77 m/s.
fn stage_speed() -> f32 {
    4.0 * 4.0 * 60.0 * (30.0f32).to_radians().tan() / 96.0
}

/// The still camera 4 m before the stage, looking slightly down at it; added last, after the
/// scene's nodes.
fn stage_camera(b: &mut Builder) {
    b.camera([0.0, 0.6, 4.0], [0.0, -0.2, 0.0], 60.0, 40.0);
}

/// One untextured plane, 200 m wide, facing the camera 3 m away.
pub(super) fn plane(b: &mut Builder) {
    let grey = b.material(MaterialDesc::new("grey", [0.6, 0.6, 0.6], 0.8));
    b.mesh(grey).append(&mesh::wall(200.0, 200.0, 1, 1, 1.0), Affine3A::IDENTITY);
    b.camera([0.0, 0.0, 3.0], [0.0, 0.0, 0.0], 60.0, 50.0);
}

/// A light plane covering the left half of the view in front of a dark one; its right edge is
/// straight and tilted by 7° so it crosses pixels at every phase.
pub(super) fn edge(b: &mut Builder) {
    let dark = b.material(MaterialDesc::new("dark", [0.1, 0.1, 0.1], 0.9));
    let light = b.material(MaterialDesc::new("light", [0.8, 0.8, 0.8], 0.9));
    b.mesh(dark).append(&mesh::wall(100.0, 100.0, 1, 1, 1.0), at(0.0, 0.0, -2.0));
    let tilt = Affine3A::from_rotation_z(7f32.to_radians()) * at(-50.0, 0.0, 0.0);
    b.mesh(light).append(&mesh::wall(100.0, 100.0, 1, 1, 1.0), tilt);
    b.camera([0.0, 0.0, 4.0], [0.0, 0.0, 0.0], 60.0, 50.0);
}

/// The Cornell box, 0.55 m on a side: white floor, ceiling and back wall, a red and a green
/// side wall, a tall and a short block (34 triangles). Placed in millimetres or kilometres by
/// the manifest's `generate.scale`, it tests that sample maps do not depend on the unit.
pub(super) fn cornell(b: &mut Builder) {
    let white = b.material(MaterialDesc::new("white", [0.73, 0.73, 0.73], 0.9));
    let red = b.material(MaterialDesc::new("red", [0.65, 0.05, 0.05], 0.9));
    let green = b.material(MaterialDesc::new("green", [0.12, 0.45, 0.15], 0.9));
    let size = 0.55f32;
    let half = size / 2.0;
    let panel = mesh::wall(size, size, 1, 1, 1.0);
    let upside_down = Quat::from_rotation_x(std::f32::consts::PI);
    b.mesh(white).append(&mesh::floor(size, size, 1, 1, 1.0), at(0.0, 0.0, -half));
    b.mesh(white).append(
        &mesh::floor(size, size, 1, 1, 1.0),
        Affine3A::from_rotation_translation(upside_down, Vec3::new(0.0, size, -half)),
    );
    b.mesh(white).append(&panel, at(0.0, half, -size));
    b.mesh(red).append(&panel, turned(std::f32::consts::FRAC_PI_2, -half, half, -half));
    b.mesh(green).append(&panel, turned(-std::f32::consts::FRAC_PI_2, half, half, -half));
    let tall = mesh::cuboid(Vec3::new(0.165, 0.33, 0.165), 1.0);
    b.mesh(white).append(&tall, turned(0.3, -0.09, 0.165, -0.35));
    let short = mesh::cuboid(Vec3::new(0.165, 0.165, 0.165), 1.0);
    b.mesh(white).append(&short, turned(-0.3, 0.09, 0.0825, -0.17));
    b.camera([0.0, 0.275, 1.0], [0.0, 0.275, 0.0], 40.0, 5.0);
}

/// Geometry far below the sampling rate: a 40 × 40 grid of 2 mm triangles, needles 1 mm
/// thick, and a fence of 400 slats 4 mm wide seen at a grazing angle, over a floor.
pub(super) fn subpixel(b: &mut Builder) {
    let floor = b.material(MaterialDesc::new("floor", [0.5, 0.5, 0.5], 0.8));
    let bright = b.material(MaterialDesc::new("bright", [0.95, 0.9, 0.8], 0.5).double_sided());
    let dark = b.material(MaterialDesc::new("dark", [0.05, 0.05, 0.06], 0.4).double_sided());
    b.mesh(floor).append(&mesh::floor(40.0, 40.0, 4, 4, 1.0), Affine3A::IDENTITY);
    let mut dust = Mesh::default();
    for i in 0..40 {
        for j in 0..40 {
            let (x, y) = (i as f32 * 0.025, j as f32 * 0.025);
            let tiny = mesh::quad(0.002, 0.002);
            dust.append(&tiny, at(x, y, 0.0));
        }
    }
    b.mesh(bright).append(&dust, at(-2.0, 0.5, 0.0));
    let needle = mesh::rod(0.0005, 2.0, 6);
    for i in 0..24 {
        let tilt = Quat::from_rotation_z(-0.6 + 0.05 * i as f32);
        b.mesh(bright).append(
            &needle,
            Affine3A::from_rotation_translation(tilt, Vec3::new(0.2 * i as f32 - 1.0, 0.0, 0.5)),
        );
    }
    let slat = mesh::quad(0.004, 1.5);
    let mut fence = Mesh::default();
    for i in 0..400 {
        fence.append(&slat, at(i as f32 * 0.02, 0.75, 0.0));
    }
    // Nearly edge-on: the fence recedes from x = 1 m at 8° off the line of sight.
    b.mesh(dark).append(&fence, turned(-1.43, 1.0, 0.0, 1.0));
    b.camera([0.0, 1.6, 6.0], [0.0, 0.9, 0.0], 50.0, 60.0);
}

/// Input that is legal glTF but numerically hostile: zero-area triangles (collinear and
/// coincident corners), normals of length zero and five, coincident duplicate vertices, and a
/// textured quad whose UVs run to ±10⁶.
pub(super) fn degenerate(b: &mut Builder) {
    let checker = b.texture("checker", &textures::checker(64, 8));
    let floor = b.material(MaterialDesc::new("floor", [0.6, 0.6, 0.6], 0.7));
    let odd = b.material(MaterialDesc::new("odd", [0.8, 0.3, 0.2], 0.5).double_sided());
    let far_uv = b.material(MaterialDesc::new("far-uv", [1.0; 3], 0.6).textured(checker));
    b.mesh(floor).append(&mesh::floor(12.0, 12.0, 2, 2, 1.0), Affine3A::IDENTITY);

    let mut odd_mesh = Mesh::default();
    let corner = |m: &mut Mesh, p: [f32; 3], n: [f32; 3]| {
        m.positions.push(p);
        m.normals.push(n);
        m.uvs.push([0.0, 0.0]);
        (m.positions.len() - 1) as u32
    };
    // Collinear corners, then three coincident ones: no area at all.
    let line = [[-1.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]]
        .map(|p| corner(&mut odd_mesh, p, [0.0, 0.0, 1.0]));
    let point = [[0.0, 1.5, 0.0]; 3].map(|p| corner(&mut odd_mesh, p, [0.0, 0.0, 1.0]));
    odd_mesh.indices.extend(line);
    odd_mesh.indices.extend(point);
    // A quad with zero-length normals, one with normals five long, each with a duplicate of
    // one corner (same position, its own index).
    for (x, normal) in [(-1.5f32, [0.0, 0.0, 0.0]), (0.5, [0.0, 0.0, 5.0])] {
        let q = [[x, 0.2, 0.0], [x + 1.0, 0.2, 0.0], [x, 1.2, 0.0], [x + 1.0, 1.2, 0.0], [x + 1.0, 0.2, 0.0]]
            .map(|p| corner(&mut odd_mesh, p, normal));
        odd_mesh.indices.extend([q[0], q[1], q[2], q[2], q[4], q[3]]);
    }
    b.mesh(odd).append(&odd_mesh, Affine3A::IDENTITY);

    let mut far = mesh::quad(2.0, 2.0);
    for uv in &mut far.uvs {
        *uv = [uv[0] * 2e6 - 1e6, uv[1] * 2e6 - 1e6];
    }
    b.mesh(far_uv).append(&far, turned(0.4, 2.5, 1.2, -0.5));
    // A box for a light to sit inside (the manifest puts one there).
    b.mesh(floor).append(&mesh::cuboid(Vec3::splat(0.8), 1.0), at(-3.0, 0.4, -1.0));
    b.camera([0.0, 1.4, 5.0], [0.0, 0.8, 0.0], 55.0, 40.0);
}

/// A large file as a user might bring one: 99 spheres of 10 000 triangles in a 10 × 10 grid on
/// a floor, each with its own 256² texture (odd ones a colour texture, even ones a normal map
/// on a plain colour), the floor one 4096² texture. No camera and no lights: a three-line
/// manifest frames and lights it.
pub(super) fn gallery(b: &mut Builder) {
    let floor_texture = b.texture("floor", &textures::floor_tiles(4096));
    let floor = b.material(MaterialDesc::new("floor", [1.0; 3], 0.7).textured(floor_texture));
    b.mesh(floor).append(&mesh::floor(24.0, 24.0, 4, 4, 6.0), Affine3A::IDENTITY);
    let ball = mesh::sphere(0.8, 100, 51);
    for i in 0..99u32 {
        let material = if i % 2 == 1 {
            let texture = b.texture(&format!("colour-{i}"), &textures::checker(256, 2 + i % 13));
            MaterialDesc::new(&format!("ball-{i}"), [1.0; 3], 0.5).textured(texture)
        } else {
            let texture = b.texture(&format!("bumps-{i}"), &textures::bumps(256, 2 + i % 9));
            let tint = [0.3 + 0.6 * b.rng.range(0.0, 1.0), 0.5, 0.3 + 0.6 * b.rng.range(0.0, 1.0)];
            MaterialDesc::new(&format!("ball-{i}"), tint, 0.35).normal_mapped(texture)
        };
        let material = b.material(material);
        let (row, column) = ((i / 10) as f32, (i % 10) as f32);
        b.mesh(material)
            .append(&ball, Affine3A::from_translation(Vec3::new(column * 2.2 - 9.9, 0.8, row * 2.2 - 9.9)));
    }
}
