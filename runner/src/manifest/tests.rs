//! The manifest's parsing and validation, field by field.

use super::*;
use aabench_renderer::AdaptiveSettings;

const VALID: &str = r#"{
    "schema_version": 1,
    "name": "edge",
    "gltf": "cache/edge.glb",
    "generate": { "generator": "edge", "seed": 3 },
    "resolution": { "quick": [64, 48], "nightly": [1024, 768] },
    "lights": [{ "position": [0, 1, 2], "intensity": 5, "range": 10 }]
}"#;

/// Parses `VALID` with `edit` applied to its JSON and expects an error naming the file,
/// `field` and something containing `reason`.
fn check(edit: impl Fn(&mut serde_json::Value), field: &str, reason: &str) {
    let mut json: serde_json::Value = serde_json::from_str(VALID).unwrap();
    edit(&mut json);
    let path = Path::new("scenes/edge.json");
    let error = Manifest::parse(path, &json.to_string()).expect_err("should be rejected");
    let text = error.to_string();
    assert_eq!(error.field, field, "{text}");
    assert!(text.starts_with("scenes/edge.json: "), "{text}");
    assert!(error.message.contains(reason), "{text}");
}

#[test]
fn a_file_of_ones_own_is_read_from_anywhere() {
    let own = |gltf: &str| {
        let mut json: serde_json::Value = serde_json::from_str(VALID).unwrap();
        json.as_object_mut().unwrap().remove("generate");
        json["gltf"] = serde_json::json!(gltf);
        Manifest::parse(Path::new("scenes/mine.json"), &json.to_string()).unwrap().gltf_path()
    };
    assert_eq!(own("../assets/Sponza/Sponza.gltf"), Path::new("scenes/../assets/Sponza/Sponza.gltf"));
    assert_eq!(own("/data/assets/box.glb"), Path::new("/data/assets/box.glb"));
}

#[test]
fn a_valid_manifest_parses_with_defaults() {
    let manifest = Manifest::parse(Path::new("scenes/edge.json"), VALID).unwrap();
    assert_eq!(manifest.gltf_path(), Path::new("scenes/cache/edge.glb"));
    assert_eq!(
        manifest.generator().map(|g| (g.generator.to_string(), g.seed, g.placement)),
        Some(("edge".into(), 3, Placement::IDENTITY))
    );
    assert_eq!(manifest.lights[0].color, [1.0; 3]);
    assert_eq!(manifest.stall_iterations, 256);
    assert_eq!(manifest.adaptive.settings(), AdaptiveSettings::default());
    assert!(manifest.camera.is_none());
    assert_eq!(manifest.gate, Tolerances::default());
    let mut json: serde_json::Value = serde_json::from_str(VALID).unwrap();
    json["gate"] = serde_json::json!({ "time_ratio": 0.2 });
    let custom = Manifest::parse(Path::new("scenes/edge.json"), &json.to_string()).unwrap();
    assert_eq!(custom.gate, Tolerances { time_ratio: 0.2, ..Tolerances::default() });
}

#[test]
fn malformed_manifests_name_the_file_and_the_field() {
    use serde_json::json;
    check(|j| j["colour"] = json!(1), "colour", "unknown field `colour`");
    check(|j| j["lights"][0]["colour"] = json!([1, 1, 1]), "lights[0].colour", "unknown field `colour`");
    check(|j| j["lights"][0]["range"] = json!("far"), "lights[0].range", "invalid type");
    check(|j| j["lights"][0]["range"] = json!(0), "lights[0].range", "must be finite and > 0");
    check(|j| j["lights"][0]["intensity"] = json!(-1), "lights[0].intensity", "≥ 0");
    check(|j| j["resolution"]["quick"] = json!([0, 48]), "resolution.quick", "between 1 and 4096");
    check(|j| j["resolution"]["nightly"] = json!([1024]), "resolution.nightly", "invalid length");
    check(
        |j| {
            j.as_object_mut().unwrap().remove("gltf");
        },
        "",
        "missing field `gltf`",
    );
    check(|j| j["schema_version"] = json!(2), "schema_version", "reads version 1");
    check(|j| j["name"] = json!("Edge Scene"), "name", "lowercase");
    check(
        |j| j["generate"]["generator"] = json!("sponza"),
        "generate.generator",
        "unknown generator `sponza`",
    );
    check(
        |j| j["camera"] = json!({"position": [0, 0, 1], "target": [0, 0, 0], "fov_y_degrees": 200}),
        "camera.fov_y_degrees",
        "within [0.01°, 179°]",
    );
    check(
        |j| j["camera"] = json!({"position": [0, 0, 1], "target": [0, 0, 1], "fov_y_degrees": 60}),
        "camera.target",
        "lies on the position",
    );
    check(
        |j| {
            j["camera"] = json!({"position": [0, 0, 1], "target": [0, 0, 0], "fov_y_degrees": 60, "near": 1, "far": 0.5})
        },
        "camera.far",
        "must be > near (1)",
    );
    check(
        |j| {
            j["camera"] =
                json!({"position": [0, 0, 1], "target": [0, 0, 0], "fov_y_degrees": 60, "near": 1e-50})
        },
        "camera.near",
        "within [1e-6, 1e9]",
    );
    check(|j| j["adaptive"] = json!({"t_edge": 2}), "adaptive.t_edge", "[0, 1]");
    check(|j| j["adaptive"] = json!({"stable_hold": 1.5}), "adaptive.stable_hold", "[0, 1]");
    check(|j| j["adaptive"] = json!({"stable_decay": -1}), "adaptive.stable_decay", "[0, 1]");
    check(|j| j["adaptive"] = json!({"c_depth": -1}), "adaptive.c_depth", "within [0, 1e12]");
    check(|j| j["adaptive"] = json!({"c_shadow": -0.5}), "adaptive.c_shadow", "within [0, 1e12]");
    check(
        |j| j["adaptive"] = json!({"c_normal": 1e13}),
        "adaptive.c_normal",
        "1e13 must be within [0, 1e12]",
    );
    // Huge numbers are quoted in scientific notation, not as hundreds of digits.
    check(|j| j["adaptive"] = json!({"c_depth": 3e38}), "adaptive.c_depth", "3e38 must be within");
    check(|j| j["motion"] = json!({"rate": 1e308}), "motion.rate", "1e308 must be finite");
    // A number past f32's range is quoted as written, not as the infinity it would round to.
    let past = "is past the largest number this setting holds (a 32-bit float: ±3.4e38)";
    check(|j| j["lights"][0]["intensity"] = json!(1e39), "lights[0].intensity", &format!("1e39 {past}"));
    check(|j| j["tonemap"] = json!({"exposure": 1e300}), "tonemap.exposure", &format!("1e300 {past}"));
    check(|j| j["ambient"] = json!([0, -4e38, 0]), "ambient", &format!("-4e38 {past}"));
    check(|j| j["adaptive"] = json!({"stable_decay": 1e39}), "adaptive.stable_decay", "1e39 is past");
    check(
        |j| j["motion"] = json!({"path": "static", "animation": {"name": "a", "start_s": 1e300}}),
        "motion.animation.start_s",
        "1e300 must be within",
    );
    // Several animations: a list of names or indices, or all of them; never two ways at once.
    let pick = |animation: serde_json::Value| {
        move |j: &mut serde_json::Value| {
            j["motion"] = json!({"path": "static", "animation": animation.clone()});
        }
    };
    check(
        pick(json!({"name": 3})),
        "motion.animation.name",
        "expected an animation's name, or a list of names",
    );
    check(
        pick(json!({"index": [0, -1]})),
        "motion.animation.index[1]",
        "integer `-1`, expected an animation's index",
    );
    check(pick(json!({"name": [["walk"]]})), "motion.animation.name[0]", "invalid type: sequence");
    check(pick(json!({"name": []})), "motion.animation.name", "the list is empty");
    check(
        pick(json!({"name": ["walk", "wave", "walk"]})),
        "motion.animation.name",
        "\"walk\" is listed twice",
    );
    check(pick(json!({"index": [2, 2]})), "motion.animation.index", "2 is listed twice");
    check(pick(json!({"all": false})), "motion.animation.all", "false picks nothing");
    check(pick(json!({"all": true, "index": 0})), "motion.animation.all", "not both");
    check(pick(json!({"start_s": 1})), "motion.animation.name", "or `\"all\": true`");
    check(|j| j["adaptive"] = json!({"depth_metric": "linear"}), "adaptive.depth_metric", "unknown variant");
    check(|j| j["stall_iterations"] = json!(1_000_001), "stall_iterations", "65 535 loop iterations");
    check(|j| j["gltf"] = json!("../elsewhere.glb"), "gltf", "generated files stay inside");
    check(|j| j["gltf"] = json!("/tmp/elsewhere.glb"), "gltf", "generated files stay inside");
    check(
        |j| j["camera"] = json!({"position": [1e300, 0, 1], "target": [0, 0, 0], "fov_y_degrees": 60}),
        "camera.position",
        "within ±1e12",
    );
    check(
        |j| {
            j["camera"] =
                json!({"position": [0, 0, 1], "target": [0, 0, 0], "up": [0, 0, 2], "fov_y_degrees": 60})
        },
        "camera.up",
        "parallel to the view direction",
    );
    check(|j| j["adaptive"] = json!({"c_dept": 1}), "adaptive.c_dept", "unknown field `c_dept`");
    check(|j| j["tonemap"] = json!({"exposure": 0}), "tonemap.exposure", "> 0");
    check(|j| j["tonemap"] = json!({"hdr_max": 0.1}), "tonemap.hdr_max", "greater than mid_in");
    check(|j| j["tonemap"] = json!({"contrast": 0}), "tonemap.contrast", "> 0");
    check(|j| j["tonemap"] = json!({"contrast": 9, "hdr_max": 6e4}), "tonemap.contrast", "f32");
    check(|j| j["tonemap"] = json!({"exposure": 1e30}), "tonemap.exposure", "at most");
    check(|j| j["tonemap"] = json!({"hdr_max": 1e6}), "tonemap.hdr_max", "[0, 65504]");
    check(|j| j["tonemap"] = json!({"crosstalk": 1000}), "tonemap.crosstalk", "[0.01, 100]");
    check(|j| j["tonemap"] = json!({"shoulder": -2}), "tonemap.shoulder", "> 0");
    check(|j| j["tonemap"] = json!({"shoulder": 1.5}), "tonemap.shoulder", "not increasing");
    check(|j| j["tonemap"] = json!({"mid_out": 1.2}), "tonemap.mid_out", "(0, 1)");
    check(|j| j["tonemap"] = json!({"mid_in": "x"}), "tonemap.mid_in", "invalid type");
    check(
        |j| {
            j["dynamic_range"] = json!("ldr");
            j["tonemap"] = json!({"contrast": 1.2});
        },
        "tonemap.contrast",
        "LDR scene",
    );
    check(|j| j["dynamic_range"] = json!("vdr"), "dynamic_range", "unknown variant");
    check(|j| j["display"] = json!({"bits": 12}), "display.bits", "8 or 10");
    check(|j| j["display"] = json!({"transfer": "pq", "peak_nits": 0}), "display.peak_nits", "> 0");
    check(|j| j["display"] = json!({"transfer": "pq", "peak_nits": 2e4}), "display.peak_nits", "10000");
    check(|j| j["display"] = json!({"peak_nits": 400}), "display.peak_nits", "only the pq");
    check(
        |j| j["display"] = json!({"jod_display": "crt"}),
        "display.jod_display",
        "unknown display model `crt`",
    );
    check(|j| j["display"] = json!({"jod_display": "standard_hdr_pq"}), "display.jod_display", "decodes PQ");
    check(
        |j| j["display"] = json!({"transfer": "pq", "jod_display": "standard_4k"}),
        "display.jod_display",
        "does not decode PQ",
    );
    check(|j| j["display"] = json!({"jod_display": "standard_hdr_hlg"}), "display.jod_display", "HLG");
    check(|j| j["display"] = json!({"transfer": "gamma2.4"}), "display.transfer", "unknown variant");
    check(|j| j["display"] = json!({"dither": "blue"}), "display.dither", "unknown variant");
    check(|j| j["gate"] = json!({"psnr_db": -0.1}), "gate.psnr_db", "≥ 0");
    check(|j| j["gate"] = json!({"time_ratio": 0}), "gate.time_ratio", "> 0");
    check(|j| j["gate"] = json!({"psnr": 1}), "gate.psnr", "unknown field `psnr`");
    check(|j| j["stall_iterations"] = json!(-5), "stall_iterations", "invalid value");
    check(|j| j["ambient"] = json!([0, -1, 0]), "ambient", "≥ 0");
    let light = json!({ "position": [0, 1, 2], "intensity": 5, "range": 10 });
    check(|j| j["lights"] = json!(vec![light.clone(); 65]), "lights", "at most 64");
    // Finite in f64, infinite as the f32 the shader gets (found by tests/fuzz.rs).
    check(|j| j["lights"][0]["position"] = json!([1e308, 0, 1]), "lights[0].position", "within ±1e12");
}

#[test]
fn shadow_settings_are_validated_per_light() {
    use serde_json::json;
    let shadowed = |shadow: serde_json::Value| {
        move |j: &mut serde_json::Value| {
            j["lights"][0]["casts_shadows"] = json!(true);
            j["lights"][0]["shadow"] = shadow.clone();
        }
    };
    check(shadowed(json!({"resolution": 8})), "lights[0].shadow.resolution", "[16, 4096]");
    check(shadowed(json!({"bias": -0.1})), "lights[0].shadow.bias", "≥ 0");
    check(shadowed(json!({"radius": -1})), "lights[0].shadow.radius", "≥ 0");
    check(shadowed(json!({"radious": 1})), "lights[0].shadow.radious", "unknown field `radious`");
    check(|j| j["lights"][0]["shadow"] = json!({"bias": 0.1}), "lights[0].shadow", "casts_shadows is false");
    let light = |resolution: u32| {
        json!({ "position": [0, 1, 2], "intensity": 5, "range": 10, "casts_shadows": true,
                "shadow": { "resolution": resolution } })
    };
    check(|j| j["lights"] = json!([light(512), light(256)]), "lights[1].shadow.resolution", "one resolution");
    check(|j| j["lights"] = json!(vec![light(64); 9]), "lights", "at most 8");
    check(|j| j["lights"] = json!(vec![light(4096); 2]), "lights", "768 MiB, more than 512 MiB");
    // The file's point lights: their settings here, their number once the file is read.
    check(
        |j| j["file_light_shadows"] = json!({"resolution": 8}),
        "file_light_shadows.resolution",
        "[16, 4096]",
    );
    check(
        |j| {
            j["file_light_shadows"] = json!({});
            j["file_lights"] = json!("replace");
        },
        "file_light_shadows",
        "file_lights is replace",
    );
    let mut json: serde_json::Value = serde_json::from_str(VALID).unwrap();
    json["lights"] = json!(vec![light(64); 8]);
    json["file_light_shadows"] = json!({"resolution": 512});
    Manifest::parse(Path::new("scenes/edge.json"), &json.to_string())
        .expect("eight shadow lights beside a file that may have no point light");
    // Defaults, and no shadow for a light that casts none.
    let mut json: serde_json::Value = serde_json::from_str(VALID).unwrap();
    shadowed(json!({"bias": 0.2}))(&mut json);
    let manifest = Manifest::parse(Path::new("scenes/edge.json"), &json.to_string()).unwrap();
    assert_eq!(manifest.lights[0].shadow(), Some(Shadow { bias: 0.2, ..Shadow::default() }));
    let plain = Manifest::parse(Path::new("scenes/edge.json"), VALID).unwrap();
    assert_eq!(plain.lights[0].shadow(), None);
}

#[test]
fn syntax_errors_give_the_line_and_column() {
    let error = Manifest::parse(Path::new("scenes/x.json"), "{\n  \"name\": \"x\",\n  oops\n}").unwrap_err();
    assert!(error.to_string().contains("line 3 column 3"), "{error}");
    let error = Manifest::load(Path::new("scenes/does-not-exist.json")).unwrap_err();
    assert!(error.to_string().starts_with("scenes/does-not-exist.json: cannot read"), "{error}");
}

#[test]
fn an_animation_is_picked_by_a_name_an_index_a_list_of_either_or_all() {
    use crate::manifest::motion::Picked;
    let picked = |animation: serde_json::Value| {
        let mut json: serde_json::Value = serde_json::from_str(VALID).unwrap();
        json["motion"] = serde_json::json!({"path": "static", "animation": animation});
        let manifest = Manifest::parse(Path::new("scenes/edge.json"), &json.to_string()).unwrap();
        manifest.motion.unwrap().animation.unwrap()
    };
    let name = picked(serde_json::json!({"name": "walk"}));
    assert_eq!(name.picked(), Picked::Names(&["walk".to_string()]));
    let names = picked(serde_json::json!({"name": ["walk", "wave"]}));
    assert_eq!(names.picked(), Picked::Names(&["walk".to_string(), "wave".to_string()]));
    assert_eq!(picked(serde_json::json!({"index": [0, 2]})).picked(), Picked::Indices(&[0, 2]));
    assert_eq!(picked(serde_json::json!({"index": 1})).picked(), Picked::Indices(&[1]));
    assert_eq!(picked(serde_json::json!({"all": true, "start_s": 0.5})).picked(), Picked::All);
}
