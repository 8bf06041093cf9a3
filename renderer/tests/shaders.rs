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
    // A list entry packs a rank below M² ≤ 16 and the index of a pixel of up to 4096×4096.
    let naga::Literal::U32(rank_bits) = constant("adaptive.wgsl", "RANK_BITS") else { panic!("u32") };
    assert!(1u64 << rank_bits >= 16, "{rank_bits} bits cannot hold 16 ranks");
    assert!(32 - rank_bits >= 24, "{} bits cannot index 4096×4096 pixels", 32 - rank_bits);
}

#[test]
fn includes_are_spliced_once_and_bad_names_fail() {
    let text = shaders::compose("adaptive.wgsl").unwrap();
    assert_eq!(text.matches("struct Frame {").count(), 1);
    assert!(!text.contains("#include"));
    assert!(shaders::compose("missing.wgsl").is_err());
}
