//! Every WGSL file is valid, embedded, and agrees with the Rust side on shared constants.

use aabench_renderer::shaders::{self, SOURCES};

fn parse(name: &str) -> naga::Module {
    let text = shaders::compose(name).unwrap_or_else(|e| panic!("{name}: {e}"));
    naga::front::wgsl::parse_str(&text)
        .unwrap_or_else(|e| panic!("{}", e.emit_to_string_with_path(&text, name)))
}

#[test]
fn every_pass_shader_parses_and_validates_with_naga() {
    let mut validated = 0;
    for name in shaders::pass_files() {
        let module = parse(name);
        naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::default(),
        )
        .validate(&module)
        .unwrap_or_else(|e| panic!("shaders/{name}: {e:?}"));
        assert!(!module.entry_points.is_empty(), "shaders/{name} has no entry point");
        validated += 1;
    }
    assert!(validated >= 5, "only {validated} pass shaders found");
}

#[test]
fn every_file_in_the_shaders_folder_is_embedded_and_used() {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../shaders");
    let mut on_disk = Vec::new();
    for dir in ["", "lib/"] {
        for entry in std::fs::read_dir(format!("{root}/{dir}")).expect("shaders folder") {
            let path = entry.expect("entry").path();
            if path.extension().is_some_and(|e| e == "wgsl") {
                on_disk.push(format!("{dir}{}", path.file_name().unwrap().to_string_lossy()));
            }
        }
    }
    on_disk.sort();
    let mut embedded: Vec<String> = SOURCES.iter().map(|(name, _)| name.to_string()).collect();
    embedded.sort();
    assert_eq!(on_disk, embedded, "shaders/ and shaders::SOURCES differ");
    // Every include is included by some pass.
    for (name, _) in SOURCES.iter().filter(|(n, _)| n.starts_with("lib/")) {
        let used = shaders::pass_files()
            .any(|pass| SOURCES.iter().any(|(n, text)| *n == pass && text.contains(name)));
        assert!(used, "shaders/{name} is included by no pass");
    }
}

#[test]
fn the_light_table_size_matches_the_rust_side() {
    let module = parse("shade.wgsl");
    let (_, constant) = module
        .constants
        .iter()
        .find(|(_, c)| c.name.as_deref() == Some("MAX_LIGHTS"))
        .expect("MAX_LIGHTS in lib/scene.wgsl");
    match module.global_expressions[constant.init] {
        naga::Expression::Literal(naga::Literal::U32(value)) => {
            assert_eq!(value as usize, aabench_renderer::scene::MAX_LIGHTS)
        }
        ref other => panic!("MAX_LIGHTS is not a u32 literal: {other:?}"),
    }
}

#[test]
fn includes_are_spliced_once_and_bad_names_fail() {
    let text = shaders::compose("adaptive.wgsl").unwrap();
    assert_eq!(text.matches("struct Frame {").count(), 1);
    assert!(!text.contains("#include"));
    assert!(shaders::compose("missing.wgsl").is_err());
}
