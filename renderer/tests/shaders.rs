//! Every WGSL file is valid, embedded, and agrees with the Rust side on shared constants.
//!
//! Every pass shader parses and validates with naga under every consistent feature set
//! (textured, shadows, light kinds, normal maps, emission, occlusion, metallic-roughness,
//! texture transforms, texture pages), and the features remove the bindings a scene does not
//! need. Every file in `shaders/` is embedded and every include is included by some file. The
//! light table size, the light kinds, the material texture slots, the shadow face table, the
//! background marker and the list-entry bits have the same values in WGSL as in Rust. None of
//! these tests needs a device.

use aabench_renderer::shaders::{self, Features, SOURCES};

fn parse_with(name: &str, features: Features) -> naga::Module {
    let text = shaders::compose(name, features).unwrap_or_else(|e| panic!("{name}: {e}"));
    naga::front::wgsl::parse_str(&text)
        .unwrap_or_else(|e| panic!("{features:?}: {}", e.emit_to_string_with_path(&text, name)))
}

fn parse(name: &str) -> naga::Module {
    parse_with(name, Features::ALL)
}

#[test]
fn every_pass_shader_parses_and_validates_with_naga_under_every_feature_set() {
    let mut validated = 0;
    for name in shaders::pass_files() {
        for features in Features::combinations() {
            let module = parse_with(name, features);
            // Cube arrays are a downlevel capability that lavapipe has.
            naga::valid::Validator::new(
                naga::valid::ValidationFlags::all(),
                naga::valid::Capabilities::CUBE_ARRAY_TEXTURES,
            )
            .validate(&module)
            .unwrap_or_else(|e| panic!("shaders/{name} with {features:?}: {e:?}"));
            assert!(!module.entry_points.is_empty(), "shaders/{name} has no entry point");
            validated += 1;
        }
    }
    assert!(validated >= 20, "only {validated} pass shader variants found");
}

#[test]
fn features_remove_the_bindings_a_scene_does_not_need() {
    let names = |features| {
        let module = parse_with("shade.wgsl", features);
        module.global_variables.iter().filter_map(|(_, g)| g.name.clone()).collect::<Vec<_>>()
    };
    let plain = names(Features::default());
    let optional = [
        "scene_textures",
        "scene_data_textures",
        "scene_sampler",
        "texture_places",
        "shadow_cubes",
        "shadow_sampler",
    ];
    for absent in optional {
        assert!(!plain.contains(&absent.to_string()), "{absent} in {plain:?}");
    }
    let all = names(Features::ALL);
    for present in optional {
        assert!(all.contains(&present.to_string()), "{present} missing in {all:?}");
    }
}

#[test]
fn every_file_in_the_shaders_folder_is_embedded_and_used() {
    let root = std::path::PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../shaders"));
    let mut on_disk = Vec::new();
    let mut folders = vec![root.clone()];
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder).expect("shaders folder") {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                folders.push(path);
            } else if path.extension().is_some_and(|e| e == "wgsl") {
                let relative = path.strip_prefix(&root).unwrap().to_string_lossy().replace('\\', "/");
                on_disk.push(relative);
            }
        }
    }
    on_disk.sort();
    let mut embedded: Vec<String> = SOURCES.iter().map(|(name, _)| name.to_string()).collect();
    embedded.sort();
    assert_eq!(on_disk, embedded, "shaders/ and shaders::SOURCES differ");
    // Every include is included by some other file.
    for (name, _) in SOURCES.iter().filter(|(n, _)| n.starts_with("lib/")) {
        let directive = format!("#include \"{name}\"");
        let used = SOURCES.iter().any(|(other, text)| other != name && text.contains(&directive));
        assert!(used, "shaders/{name} is included by no file");
    }
}

/// The value of a WGSL `const` of a composed pass shader.
fn constant(file: &str, name: &str) -> naga::Literal {
    let module = parse(file);
    let (_, constant) = module
        .constants
        .iter()
        .find(|(_, c)| c.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("{name} in {file}"));
    match module.global_expressions[constant.init] {
        naga::Expression::Literal(literal) => literal,
        ref other => panic!("{name} is not a literal: {other:?}"),
    }
}

#[test]
fn constants_shared_with_rust_agree() {
    assert_eq!(
        constant("shade.wgsl", "MAX_LIGHTS"),
        naga::Literal::U32(aabench_renderer::scene::MAX_LIGHTS as u32)
    );
    assert_eq!(
        constant("shade.wgsl", "BACKGROUND"),
        naga::Literal::I32(aabench_renderer::BACKGROUND_MATERIAL)
    );
    assert_eq!(
        constant("shadow.wgsl", "MAX_SHADOW_FACES"),
        naga::Literal::U32(6 * aabench_renderer::scene::MAX_SHADOW_LIGHTS as u32)
    );
    use aabench_renderer::scene::{LIGHT_DIRECTIONAL, LIGHT_POINT, LIGHT_SPOT};
    for (name, value) in
        [("LIGHT_POINT", LIGHT_POINT), ("LIGHT_SPOT", LIGHT_SPOT), ("LIGHT_DIRECTIONAL", LIGHT_DIRECTIONAL)]
    {
        assert_eq!(constant("shade.wgsl", name), naga::Literal::U32(value), "{name}");
    }
    use aabench_renderer::scene::{
        SLOT_BASE, SLOT_EMISSIVE, SLOT_METALLIC_ROUGHNESS, SLOT_NORMAL, SLOT_OCCLUSION,
    };
    for (name, value) in [
        ("SLOT_BASE", SLOT_BASE),
        ("SLOT_NORMAL", SLOT_NORMAL),
        ("SLOT_EMISSIVE", SLOT_EMISSIVE),
        ("SLOT_OCCLUSION", SLOT_OCCLUSION),
        ("SLOT_METALLIC_ROUGHNESS", SLOT_METALLIC_ROUGHNESS),
    ] {
        assert_eq!(constant("shade.wgsl", name), naga::Literal::U32(value as u32), "{name}");
    }
    // A list entry packs two texel coordinates and n − 1 < 16 into 32 bits (adaptive.rs checks
    // that they fit).
    let texel_bits = aabench_renderer::adaptive::LIST_TEXEL_BITS;
    assert_eq!(constant("adaptive.wgsl", "TEXEL_BITS"), naga::Literal::U32(texel_bits));
}

#[test]
fn includes_are_spliced_once_and_bad_names_fail() {
    let text = shaders::compose("adaptive.wgsl", Features::ALL).unwrap();
    assert_eq!(text.matches("struct Frame {").count(), 1);
    assert!(!text.contains('#'), "a directive survived composition");
    assert!(shaders::compose("missing.wgsl", Features::ALL).is_err());
}

#[test]
fn a_shader_folder_replaces_the_embedded_files_includes_and_all() {
    let dir = std::env::temp_dir().join(format!("aabench-shader-folder-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("lib")).unwrap();
    std::fs::write(dir.join("pass.wgsl"), "#include \"lib/common.wgsl\"\nfn pass_body() {}\n").unwrap();
    std::fs::write(dir.join("lib/common.wgsl"), "fn folder_only() {}\n").unwrap();
    let text = shaders::compose_from(Some(&dir), "pass.wgsl", Features::ALL).unwrap();
    assert_eq!(text, "fn folder_only() {}\nfn pass_body() {}\n");
    // The folder's files stand alone: the embedded pass shaders are not there.
    let error = shaders::compose_from(Some(&dir), "shade.wgsl", Features::ALL).unwrap_err().to_string();
    assert!(error.contains(&dir.join("shade.wgsl").display().to_string()), "{error}");
    std::fs::remove_dir_all(&dir).unwrap();
}
