//! `KHR_lights_punctual` lights and the first perspective camera, placed by their nodes.

use glam::{DMat4, DVec3};

use crate::scene::{Camera, Light, LightKind};

/// A `KHR_lights_punctual` light placed by its node: at the node's origin, shining along its
/// −Z. Every value is checked: a light the renderer cannot draw is an error, never dropped.
pub(super) fn light_from_node(
    light: &gltf::khr_lights_punctual::Light,
    world: DMat4,
) -> Result<(Light, DVec3), String> {
    use gltf::khr_lights_punctual::Kind;
    let what = format!("KHR_lights_punctual light {}", light.index());
    // A directional light has no position (one far out would not even fit an f32).
    let position = match light.kind() {
        Kind::Directional => DVec3::ZERO,
        _ => world.transform_point3(DVec3::ZERO),
    };
    let direction = world.transform_vector3(-DVec3::Z).normalize_or_zero().as_vec3();
    if direction == glam::Vec3::ZERO && !matches!(light.kind(), Kind::Point) {
        return Err(format!("{what}: the node's transform collapses the light's direction"));
    }
    let kind = match light.kind() {
        Kind::Point => LightKind::Point,
        Kind::Directional => LightKind::Directional { direction },
        Kind::Spot { inner_cone_angle, outer_cone_angle } => {
            let quarter = std::f32::consts::FRAC_PI_2;
            let valid = (0.0..outer_cone_angle).contains(&inner_cone_angle)
                && (..=quarter).contains(&outer_cone_angle);
            if !valid {
                return Err(format!(
                    "{what}: cone angles {inner_cone_angle} and {outer_cone_angle} must satisfy 0 ≤ inner < outer ≤ π/2"
                ));
            }
            LightKind::Spot { direction, inner: inner_cone_angle, outer: outer_cone_angle }
        }
    };
    crate::scene::check_light(position, light.color(), light.intensity(), light.range())
        .map_err(|(field, why)| format!("{what}: {field}: {why}"))?;
    let (color, intensity) = (glam::Vec3::from(light.color()), light.intensity());
    let range = light.range().unwrap_or(f32::INFINITY);
    Ok((Light { kind, position: glam::Vec3::ZERO, color, intensity, range, shadow: None }, position))
}

/// The camera of a node, if perspective (orthographic cameras are skipped). Read from the
/// JSON: `gltf::Camera::projection` panics when the object its `type` names is missing.
pub(super) fn camera_from_node(
    document: &gltf::Document,
    index: usize,
    world: DMat4,
) -> Result<Option<Camera>, String> {
    use gltf::json::camera::Type;
    use gltf::json::validation::Checked;
    let json = &document.as_json().cameras[index];
    if json.type_ != Checked::Valid(Type::Perspective) {
        return Ok(None);
    }
    let perspective = json
        .perspective
        .as_ref()
        .ok_or_else(|| format!("cameras[{index}]: type is perspective, but `perspective` is missing"))?;
    Ok(Some(Camera {
        position: world.transform_point3(DVec3::ZERO),
        forward: world.transform_vector3(-DVec3::Z),
        up: world.transform_vector3(DVec3::Y),
        fov_y: f64::from(perspective.yfov),
        near: f64::from(perspective.znear),
        // An infinite far plane gets a finite one from the scene bounds later.
        far: perspective.zfar.map_or(f64::INFINITY, f64::from),
    }))
}
