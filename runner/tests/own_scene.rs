//! A user's own glTF file with a three-line manifest: no camera, no lights, no resolution.
//! The run frames the scene, lights it and renders it (real process, real files).
//!
//! Manifests read their assets from another folder and write only beside
//! themselves; automatic exposure renders a sun of 6830 lux like one of 6.83 lux, within 2
//! codes; the file's own point lights cast shadows when the manifest asks.

use aabench_renderer::scene::write::{GltfWriter, MaterialDesc, MeshData};
use serde_json::json;

use crate::support;

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

/// Three-line manifests for a cube modelled in metres and in millimetres (×500, off-centre)
/// both render `ok` at the quick tier's 256×192, with the cube covering 5–90% of the frame,
/// sky in the corner and lit faces (red above 120).
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
        let image = ws.display(mode(scene, "deferred-1x1")).to_rgb8();
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

#[test]
fn manifests_in_one_folder_read_assets_from_another_and_write_only_beside_themselves() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("assets-anywhere");
    std::fs::create_dir_all(ws.dir.join("assets/cube")).unwrap();
    let asset = ws.dir.join("assets/cube/cube.glb");
    cube_file(&asset, 1.0);
    let relative = json!({ "schema_version": 1, "name": "relative", "gltf": "../assets/cube/cube.glb" });
    let absolute = json!({ "schema_version": 1, "name": "absolute", "gltf": asset });
    std::fs::write(ws.dir.join("scenes/relative.json"), relative.to_string()).unwrap();
    std::fs::write(ws.dir.join("scenes/absolute.json"), absolute.to_string()).unwrap();
    let listed = |dir: &str| {
        let mut names: Vec<String> = std::fs::read_dir(ws.dir.join(dir))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    };
    let output = ws.run(&["run", "scenes", "--modes", "deferred-1x1,adaptive-2x2", "--repetitions", "1"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let record = ws.record();
    let scenes = record["scenes"].as_array().unwrap();
    assert_eq!(scenes.len(), 2, "the folder's two manifests");
    for scene in scenes {
        assert_eq!(scene["status"], "ok", "{scene}");
        assert!(scene["truth"]["image"].is_string(), "{scene}");
    }
    // The asset folder is read, never written: the truth cache lies beside the manifests.
    assert_eq!(listed("assets/cube"), ["cube.glb"]);
    assert!(ws.dir.join("scenes/cache/truth").is_dir());
}

#[test]
fn automatic_exposure_renders_a_sun_of_6830_lux_as_one_of_6_8() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("exposure");
    for (name, lux) in [("noon", 6830.0), ("dusk", 6.83)] {
        let mut writer = box_scene();
        writer.add_directional_light(glam::DVec3::new(-0.4, -1.0, -0.6), [1.0, 0.97, 0.9], lux);
        writer.write(&ws.dir.join(format!("scenes/{name}.glb"))).unwrap();
        // No ambient and a black sky: the sun is all the light, so the exposure alone differs.
        let manifest = json!({ "schema_version": 1, "name": name, "gltf": format!("{name}.glb"),
            "ambient": [0, 0, 0], "background": [0, 0, 0] });
        std::fs::write(ws.dir.join(format!("scenes/{name}.json")), manifest.to_string()).unwrap();
    }
    let output = ws.run(&["run", "--modes", "deferred-1x1", "--repetitions", "1"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let record = ws.record();
    let image = |name: &str| {
        let scene = scene(&record, name);
        assert_eq!(scene["exposure"]["metered"], true, "{scene}");
        (scene["exposure"]["value"].as_f64().unwrap(), ws.display(mode(scene, "deferred-1x1")).to_rgb8())
    };
    let ((noon_exposure, noon), (dusk_exposure, dusk)) = (image("noon"), image("dusk"));
    let ratio = dusk_exposure / noon_exposure;
    assert!((ratio / 1000.0 - 1.0).abs() < 0.01, "exposures {dusk_exposure} / {noon_exposure} = {ratio}");
    let steps: Vec<i32> = noon
        .pixels()
        .zip(dusk.pixels())
        .flat_map(|(a, b)| (0..3).map(move |c| i32::from(a[c]) - i32::from(b[c])))
        .collect();
    let worst = steps.iter().map(|d| d.abs()).max().unwrap();
    assert!(worst <= 2, "the two suns differ by up to {worst} steps");
    // Metered, the sunlit floor is a mid grey, neither blown out nor black.
    let mut floor: Vec<u8> =
        noon.pixels().filter(|p| p[0].abs_diff(p[2]) < 8 && p[1] > 0).map(|p| p[1]).collect();
    floor.sort_unstable();
    let lit = floor.len();
    assert!(lit > noon.pixels().len() / 20, "the floor covers {lit} pixels");
    let median = floor[lit / 2];
    assert!((80..=180).contains(&median), "the metered floor's median code is {median}");

    // The same noon at the old default exposure of 1 is what users saw: almost all white.
    let fixed = json!({ "schema_version": 1, "name": "fixed", "gltf": "noon.glb",
        "ambient": [0, 0, 0], "background": [0, 0, 0], "tonemap": { "exposure": 1.0 } });
    std::fs::write(ws.dir.join("scenes/fixed.json"), fixed.to_string()).unwrap();
    std::fs::remove_dir_all(ws.dir.join("reports")).unwrap();
    let output = ws.run(&["run", "scenes/fixed.json", "--modes", "deferred-1x1", "--repetitions", "1"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let record = ws.record();
    let scene = &record["scenes"][0];
    assert_eq!(scene["exposure"], json!({ "value": 1.0, "metered": false }));
    let white = ws
        .display(mode(scene, "deferred-1x1"))
        .to_rgb8()
        .pixels()
        .filter(|p| p.0.iter().all(|&c| c >= 250))
        .count();
    assert!(white > lit / 2, "exposure 1 under a 6830 lux sun should blow the lit scene out ({white} white)");
}

/// Automatic exposure meters what shows the scene: a dim sky behind a floor under a 2000 lux sun
/// (a real file's setting) does not drag the exposure up until the floor is white. A sun so
/// bright that the scene's radiance passes the HDR target's f16 limit fails the scene by name,
/// where it used to render one flat grey.
#[test]
fn automatic_exposure_meters_the_scene_not_its_sky_and_refuses_light_beyond_the_hdr_range() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("exposure-sky");
    // The blaze metered, and under exposures of its own: one that shows the lost light as grey
    // (refused like the metered one), one that displays the limit white (it hides nothing).
    // And a sky past the limit under an exposure that displays it grey, refused like the blaze.
    let (night, blazing) = ([0.0005, 0.0006, 0.001], [1e6, 1e6, 1e6]);
    let scenes = [
        ("sunlit", 2000.0, None, night),
        ("blaze", 1e9, None, night),
        ("dimmed", 1e9, Some(1e-9), night),
        ("white", 1e9, Some(1.0), night),
        ("sky", 2000.0, Some(1e-4), blazing),
    ];
    for (name, lux, exposure, background) in scenes {
        let mut writer = box_scene();
        writer.add_directional_light(glam::DVec3::new(-0.4, -1.0, -0.6), [1.0, 0.97, 0.9], lux);
        writer.write(&ws.dir.join(format!("scenes/{name}.glb"))).unwrap();
        let mut manifest = json!({ "schema_version": 1, "name": name, "gltf": format!("{name}.glb"),
            "ambient": [0, 0, 0], "background": background });
        if let Some(exposure) = exposure {
            manifest["tonemap"] = json!({ "exposure": exposure });
        }
        std::fs::write(ws.dir.join(format!("scenes/{name}.json")), manifest.to_string()).unwrap();
    }
    let output = ws.run(&["run", "--modes", "deferred-1x1", "--repetitions", "1"]);
    assert_eq!(output.status.code(), Some(3), "the blaze fails: {}", stderr(&output));
    let text = stderr(&output);
    assert!(text.contains("blaze.glb") && text.contains("65 504"), "{text}");
    let record = ws.record();
    let dimmed = scene(&record, "dimmed");
    assert_eq!(dimmed["status"], "failed", "{dimmed}");
    let error = dimmed["error"].as_str().unwrap();
    assert!(
        error.contains("dimmed.glb") && error.contains("which exposure 1e-9 displays below white"),
        "{error}"
    );
    let sky = scene(&record, "sky");
    assert_eq!(sky["status"], "failed", "{sky}");
    let error = sky["error"].as_str().unwrap();
    assert!(
        error.ends_with(
            "sky.json: background: [1000000, 1000000, 1000000] passes the HDR target's limit of 65 504, which \
             exposure 1e-4 displays below white: the sky would show as a flat grey; scale the background down \
             and the exposure up"
        ),
        "{error}"
    );
    assert_eq!(
        scene(&record, "white")["status"],
        "ok",
        "exposure 1 shows the limit white: nothing is hidden"
    );
    let sunlit = scene(&record, "sunlit");
    assert_eq!(sunlit["exposure"]["metered"], true, "{sunlit}");
    let image = ws.display(mode(sunlit, "deferred-1x1")).to_rgb8();
    // The sky is near black; what is not is the scene.
    let lit: Vec<&image::Rgb<u8>> = image.pixels().filter(|p| p[1] > 8).collect();
    assert!(lit.len() > image.pixels().len() / 10, "the scene covers {} pixels", lit.len());
    let white = lit.iter().filter(|p| p.0.iter().all(|&c| c >= 250)).count();
    assert!(white * 10 < lit.len(), "{white} of the scene's {} pixels are white", lit.len());
}

/// A floor with a box standing on it and `lights` point lights of the file's own above it.
fn lit_box_file(path: &std::path::Path, lights: usize) {
    let mut writer = box_scene();
    for i in 0..lights {
        writer.add_point_light([-3.0 + 0.01 * i as f64, 4.5, -2.0], [1.0; 3], 40.0 / lights as f32, 30.0);
    }
    writer.write(path).unwrap();
}

/// A floor 12 m on a side with a red 2 m box standing on it, no lights.
fn box_scene() -> GltfWriter {
    let mut floor = MeshData::default();
    for (x, z) in [(-1.0, -1.0), (-1.0, 1.0), (1.0, 1.0), (1.0, -1.0)] {
        floor.positions.push([x * 6.0, 0.0, z * 6.0]);
        floor.normals.push([0.0, 1.0, 0.0]);
        floor.uvs.push([0.0, 0.0]);
    }
    floor.indices = vec![0, 1, 2, 0, 2, 3];
    let mut writer = GltfWriter::new("a user's exporter");
    let grey = writer.add_material(&MaterialDesc::new("floor", [0.7, 0.7, 0.7], 0.8));
    writer.add_mesh("floor", &floor, grey);
    let mut block = MeshData::default();
    for (axis, sign) in (0..3).flat_map(|axis| [(axis, -1.0f32), (axis, 1.0)]) {
        let mut normal = [0.0; 3];
        normal[axis] = sign;
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let base = block.positions.len() as u32;
        for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            let mut p = [0.0, 1.0, 0.0];
            p[axis] += sign;
            p[u] += a;
            p[v] += b;
            block.positions.push(p);
            block.normals.push(normal);
            block.uvs.push([0.0, 0.0]);
        }
        block.indices.extend([base, base + 1, base + 2, base, base + 2, base + 3]);
    }
    let red = writer.add_material(&MaterialDesc::new("box", [0.8, 0.2, 0.2], 0.8));
    writer.add_mesh("box", &block, red);
    writer
}

#[test]
fn the_files_point_lights_cast_shadows_when_the_manifest_asks() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("file-shadows");
    lit_box_file(&ws.dir.join("scenes/box.glb"), 1);
    let camera = json!({ "position": [0, 12, 9], "target": [0, 0, 0], "fov_y_degrees": 50 });
    for (name, shadows) in [("plain", None), ("shadowed", Some(json!({ "resolution": 256 })))] {
        // One exposure for both: metered, the shadowed scene would take a brighter one.
        let mut manifest = json!({ "schema_version": 1, "name": name, "gltf": "box.glb", "camera": camera,
                                   "resolution": { "quick": [96, 72] }, "ambient": [0.02, 0.02, 0.02],
                                   "tonemap": { "exposure": 1.0 } });
        if let Some(shadows) = shadows {
            manifest["file_light_shadows"] = shadows;
        }
        std::fs::write(ws.dir.join(format!("scenes/{name}.json")), manifest.to_string()).unwrap();
    }
    let output = ws.run(&["run", "--modes", "deferred-1x1", "--repetitions", "1"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let record = ws.record();
    let image = |name: &str| ws.display(mode(scene(&record, name), "deferred-1x1")).to_rgb8();
    let (plain, shadowed) = (image("plain"), image("shadowed"));
    // The box's shadow falls on the floor behind it: floor pixels that darken by far.
    let darkened =
        plain.pixels().zip(shadowed.pixels()).filter(|(a, b)| a[1] > b[1].saturating_add(40)).count();
    let share = darkened as f64 / f64::from(plain.width() * plain.height());
    assert!(share > 0.02, "shadowed share {share:.4}");
    // Nothing gets brighter.
    assert!(plain.pixels().zip(shadowed.pixels()).all(|(a, b)| b[1] <= a[1].saturating_add(1)));

    // Nine shadowed point lights are more cubes than a scene holds: the scene fails saying so.
    let ws = Workspace::new("file-shadows-many");
    lit_box_file(&ws.dir.join("scenes/box.glb"), 9);
    let manifest =
        json!({ "schema_version": 1, "name": "many", "gltf": "box.glb", "file_light_shadows": {} });
    std::fs::write(ws.dir.join("scenes/many.json"), manifest.to_string()).unwrap();
    let output = ws.run(&["run", "--modes", "deferred-1x1", "--repetitions", "1"]);
    assert_eq!(output.status.code(), Some(3), "{}", stderr(&output));
    let message = stderr(&output);
    assert!(
        message.contains("many.json: file_light_shadows: 9 lights cast shadows, at most 8 may"),
        "{message}"
    );
}
