//! A user's own glTF file with a three-line manifest: no camera, no lights, no resolution.
//! The run frames the scene, lights it and renders it (real process, real files).

use aabench_renderer::scene::write::{GltfWriter, MaterialDesc, MeshData};
use serde_json::json;

mod support;

use support::*;

/// A unit cube as a file with no camera and no lights, `scale` units on a side, off-centre.
fn cube_file(path: &std::path::Path, scale: f64) {
    let mut mesh = MeshData::default();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut normal = [0.0; 3];
            normal[axis] = sign;
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let base = mesh.positions.len() as u32;
            for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                let mut p = [0.0; 3];
                p[axis] = sign * 0.5;
                p[u] = a * 0.5;
                p[v] = b * 0.5;
                mesh.positions.push(p);
                mesh.normals.push(normal);
                mesh.uvs.push([0.0, 0.0]);
            }
            mesh.indices.extend([base, base + 1, base + 2, base, base + 2, base + 3]);
        }
    }
    let mut writer = GltfWriter::new("a user's exporter");
    let material = writer.add_material(&MaterialDesc::new("paint", [0.8, 0.3, 0.2], 0.5));
    writer.add_mesh("cube", &mesh, material);
    writer.place(scale, [3.0 * scale, 0.0, -2.0 * scale]);
    writer.write(path).unwrap();
}

#[test]
fn a_three_line_manifest_frames_and_lights_a_file_in_any_unit() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("own-scene");
    // Metres (a 1-unit cube) and millimetres (a 500-unit one).
    for (name, scale) in [("metres", 1.0), ("millimetres", 500.0)] {
        cube_file(&ws.dir.join(format!("scenes/{name}.glb")), scale);
        let manifest = json!({ "schema_version": 1, "name": name, "gltf": format!("{name}.glb") });
        std::fs::write(ws.dir.join(format!("scenes/{name}.json")), manifest.to_string()).unwrap();
    }
    let output = ws.run(&["run", "--modes", "deferred-1x1", "--repetitions", "1"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let record = ws.record();
    for scene in record["scenes"].as_array().unwrap() {
        assert_eq!(scene["status"], "ok", "{scene}");
        assert_eq!(scene["resolution"], json!([256, 192]), "the quick tier's default");
        let png = ws.run_dir().join(mode(scene, "deferred-1x1")["images"]["display"].as_str().unwrap());
        let image = image::open(&png).unwrap().to_rgb8();
        // The default background is a sky blue; the cube is reddish and lit.
        let background = image.get_pixel(0, 0).0;
        let cube: Vec<[u8; 3]> = image.pixels().map(|p| p.0).filter(|p| p[0] > p[2] + 20).collect();
        let share = cube.len() as f64 / f64::from(image.width() * image.height());
        assert!((0.05..0.9).contains(&share), "{}: the cube covers {share:.3} of the frame", scene["name"]);
        assert!(background[2] > background[0], "{}: the corner is sky, not the cube", scene["name"]);
        // Lit: the cube's faces are brighter than ambient alone would make them.
        let brightest = cube.iter().map(|p| p[0]).max().unwrap();
        assert!(brightest > 120, "{}: brightest cube red {brightest}", scene["name"]);
    }
}
