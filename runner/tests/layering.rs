//! The crates' layering: ARCHITECTURE.md lists each crate's top-level modules in layers, and
//! every module uses only modules of earlier layers (so no module uses another that uses it
//! back, directly or through others), and the list names every module there is. A module's uses
//! are read from its source files: every `crate::name` and every name in a `crate::{…}` group,
//! outside `#[cfg(test)]` modules, doc comments and comments.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap().to_path_buf()
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The identifier at the start of `text`.
fn ident(text: &str) -> &str {
    let end = text.find(|c: char| !(c.is_alphanumeric() || c == '_')).unwrap_or(text.len());
    &text[..end]
}

/// The source without comments (from `//` to the end of a line, doc comments included) and
/// without `#[cfg(test)]` items (the braced block that follows the attribute): test code may
/// reach anywhere.
fn production_code(source: &str) -> String {
    let lines: Vec<&str> = source.lines().map(|line| line.split("//").next().unwrap_or_default()).collect();
    let code = lines.join("\n");
    let mut out = String::new();
    let mut rest = code.as_str();
    while let Some(at) = rest.find("#[cfg(test)]") {
        out.push_str(&rest[..at]);
        let after = &rest[at..];
        let Some(open) = after.find('{') else { return out };
        let mut depth = 0usize;
        let mut end = after.len();
        for (i, c) in after[open..].char_indices() {
            match c {
                '{' => depth += 1,
                '}' => {
                    depth -= 1;
                    if depth == 0 {
                        end = open + i + 1;
                        break;
                    }
                }
                _ => {}
            }
        }
        rest = &after[end..];
    }
    out.push_str(rest);
    out
}

/// The first names of the items of a `{…}` group (nested groups and line breaks included),
/// given the text after its opening brace.
fn group_items(text: &str) -> Vec<String> {
    let (mut items, mut depth, mut start) = (Vec::new(), 0usize, 0usize);
    for (i, c) in text.char_indices() {
        match c {
            '{' => depth += 1,
            '}' if depth == 0 => {
                items.push(ident(text[start..i].trim()).to_string());
                return items;
            }
            '}' => depth -= 1,
            ',' if depth == 0 => {
                items.push(ident(text[start..i].trim()).to_string());
                start = i + 1;
            }
            _ => {}
        }
    }
    items
}

/// The names a source text uses through `crate::`: modules, or items the crate root re-exports.
fn uses(source: &str) -> BTreeSet<String> {
    let code = production_code(source);
    let mut names = BTreeSet::new();
    for (at, _) in code.match_indices("crate::") {
        let rest = &code[at + "crate::".len()..];
        match rest.strip_prefix('{') {
            Some(group) => names.extend(group_items(group)),
            None => {
                names.insert(ident(rest).to_string());
            }
        }
    }
    names.retain(|name| !name.is_empty() && name != "self");
    names
}

/// What the crate root re-exports, by name, and the module each comes from (`pub use m::{A, B}`).
fn root_exports(lib: &str) -> BTreeMap<String, String> {
    let code = production_code(lib);
    let mut exports = BTreeMap::new();
    for (at, _) in code.match_indices("pub use ") {
        let rest = &code[at + "pub use ".len()..];
        let module = ident(rest).to_string();
        let statement = &rest[..rest.find(';').unwrap_or(rest.len())];
        let items = match statement.find('{') {
            Some(open) => group_items(&statement[open + 1..]),
            None => vec![statement.rsplit("::").next().unwrap_or_default().trim().to_string()],
        };
        for item in items {
            exports.insert(item, module.clone());
        }
    }
    exports
}

/// Top-level module → the top-level modules it uses, for the crate whose sources are in `src`.
fn module_graph(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for file in files {
        let relative = file.strip_prefix(src).unwrap();
        let top = relative
            .components()
            .next()
            .unwrap()
            .as_os_str()
            .to_string_lossy()
            .trim_end_matches(".rs")
            .to_string();
        if top == "lib" || top == "main" {
            continue;
        }
        let mut used = uses(&std::fs::read_to_string(&file).unwrap());
        used.remove(&top);
        graph.entry(top).or_default().extend(used);
    }
    // An item the crate root re-exports is a use of the module it comes from; any other name
    // must be a module, or the reader has missed a path.
    let lib = ["lib.rs", "main.rs"].iter().find_map(|f| std::fs::read_to_string(src.join(f)).ok()).unwrap();
    let exports = root_exports(&lib);
    let modules: BTreeSet<String> = graph.keys().cloned().collect();
    // Modules written inline in the crate root (`pub mod exit { … }`) are leaves, not edges.
    let inline: BTreeSet<String> =
        lib.match_indices("mod ").map(|(at, _)| ident(&lib[at + 4..]).to_string()).collect();
    for (module, used) in graph.iter_mut() {
        let resolved: BTreeSet<String> = used
            .iter()
            .map(|name| exports.get(name).cloned().unwrap_or_else(|| name.clone()))
            .filter(|name| name != module)
            .collect();
        for name in &resolved {
            assert!(
                modules.contains(name) || inline.contains(name),
                "{module}: `crate::{name}` is neither a module nor a root re-export"
            );
        }
        *used = resolved.into_iter().filter(|name| modules.contains(name)).collect();
    }
    graph
}

/// A cycle of the graph, if it has one.
fn cycle(graph: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        node: &str,
        graph: &BTreeMap<String, BTreeSet<String>>,
        path: &mut Vec<String>,
        done: &mut BTreeSet<String>,
    ) -> Option<Vec<String>> {
        if let Some(start) = path.iter().position(|n| n == node) {
            let mut found = path[start..].to_vec();
            found.push(node.to_string());
            return Some(found);
        }
        if done.contains(node) {
            return None;
        }
        path.push(node.to_string());
        for next in graph.get(node).into_iter().flatten() {
            if let Some(found) = visit(next, graph, path, done) {
                return Some(found);
            }
        }
        path.pop();
        done.insert(node.to_string());
        None
    }
    let mut done = BTreeSet::new();
    graph.keys().find_map(|node| visit(node, graph, &mut Vec::new(), &mut done))
}

#[test]
fn the_reader_sees_plain_and_grouped_uses_and_finds_a_cycle() {
    let source = "use crate::{\n    fs,\n    json::{read, write},\n    self,\n};\nlet x = crate::plan::Tier::Quick; // crate::front\n\
                  #[cfg(test)]\nmod tests {\n    use crate::report;\n}\nfn after() { crate::stats::median(); }\n";
    assert_eq!(
        uses(source),
        BTreeSet::from(["fs".to_string(), "json".into(), "plan".into(), "stats".into()])
    );
    let exports = root_exports(
        "pub use error::RenderError;\npub use render::{\n    DisplayImage, SceneRenderer,\n};\n",
    );
    assert_eq!(exports.get("SceneRenderer").map(String::as_str), Some("render"));
    assert_eq!(exports.get("RenderError").map(String::as_str), Some("error"));
    let graph: BTreeMap<String, BTreeSet<String>> = [
        ("a".to_string(), BTreeSet::from(["b".to_string()])),
        ("b".into(), BTreeSet::from(["c".to_string()])),
        ("c".into(), BTreeSet::from(["a".to_string()])),
    ]
    .into();
    assert_eq!(cycle(&graph), Some(vec!["a".to_string(), "b".into(), "c".into(), "a".into()]));
}

#[test]
fn neither_crate_has_an_import_cycle_between_its_modules() {
    for crate_src in ["renderer/src", "runner/src"] {
        let graph = module_graph(&workspace().join(crate_src));
        assert!(graph.len() > 10, "{crate_src}: only {} modules found", graph.len());
        assert_eq!(cycle(&graph), None, "{crate_src}: modules use each other in a cycle");
    }
}

/// The layers of a crate as ARCHITECTURE.md lists them: the line `- <crate>: `a`, `b` → `c` …`,
/// each layer the modules between arrows.
fn documented_layers(crate_name: &str) -> Vec<Vec<String>> {
    let map = std::fs::read_to_string(workspace().join("ARCHITECTURE.md")).unwrap();
    let prefix = format!("- {crate_name}: ");
    let line = map
        .lines()
        .find_map(|line| line.strip_prefix(&prefix))
        .unwrap_or_else(|| panic!("ARCHITECTURE.md has no line `{prefix}…` listing the layers"));
    line.split('→')
        .map(|layer| {
            layer
                .split(',')
                .map(|m| m.trim().trim_matches('`').to_string())
                .filter(|m| !m.is_empty())
                .collect()
        })
        .collect()
}

/// Every edge that goes against the layers: a module that uses one of its own layer or a later
/// one.
fn against_the_layers(graph: &BTreeMap<String, BTreeSet<String>>, layers: &[Vec<String>]) -> Vec<String> {
    let layer = |module: &str| layers.iter().position(|l| l.iter().any(|m| m == module));
    let mut wrong = Vec::new();
    for (module, used) in graph {
        for other in used {
            if let (Some(a), Some(b)) = (layer(module), layer(other))
                && b >= a
            {
                wrong.push(format!("{module} (layer {}) uses {other} (layer {})", a + 1, b + 1));
            }
        }
    }
    wrong
}

#[test]
fn the_layers_reject_a_use_upwards_or_within_a_layer() {
    let layers: Vec<Vec<String>> = vec![vec!["a".into(), "b".into()], vec!["c".into()]];
    let graph: BTreeMap<String, BTreeSet<String>> = [
        ("c".to_string(), BTreeSet::from(["a".to_string()])),
        ("a".into(), BTreeSet::from(["b".to_string(), "c".to_string()])),
    ]
    .into();
    assert_eq!(
        against_the_layers(&graph, &layers),
        ["a (layer 1) uses b (layer 1)", "a (layer 1) uses c (layer 2)"]
    );
}

#[test]
fn every_module_is_on_the_map_and_uses_only_earlier_layers() {
    for (crate_name, src) in [("renderer", "renderer/src"), ("runner", "runner/src")] {
        let graph = module_graph(&workspace().join(src));
        let layers = documented_layers(crate_name);
        let listed: BTreeSet<String> = layers.iter().flatten().cloned().collect();
        let modules: BTreeSet<String> = graph.keys().cloned().collect();
        let missing: Vec<&String> = modules.difference(&listed).collect();
        let stale: Vec<&String> = listed.difference(&modules).collect();
        assert!(
            missing.is_empty() && stale.is_empty(),
            "{crate_name}: not on the map {missing:?}, on the map but gone {stale:?}"
        );
        let wrong = against_the_layers(&graph, &layers);
        assert!(wrong.is_empty(), "{crate_name}: {wrong:#?}\nthe graph: {graph:#?}");
    }
}

/// The files of a folder, recursively, relative to it with `/` between folders.
fn files_under(root: &Path, extension: &str) -> Vec<String> {
    let mut files = Vec::new();
    let mut folders = vec![root.to_path_buf()];
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                folders.push(path);
            } else if path.extension().is_some_and(|e| e == extension) {
                files.push(path.strip_prefix(root).unwrap().to_string_lossy().replace('\\', "/"));
            }
        }
    }
    files.sort();
    files
}

#[test]
fn every_source_file_is_in_the_code_map_and_every_test_it_names_exists() {
    let map = std::fs::read_to_string(workspace().join("ARCHITECTURE.md")).unwrap();
    let named: BTreeSet<&str> = map.split('`').skip(1).step_by(2).collect();
    let mut missing = Vec::new();
    for (folder, extension) in [("renderer/src", "rs"), ("runner/src", "rs"), ("shaders", "wgsl")] {
        for file in files_under(&workspace().join(folder), extension) {
            if !named.contains(file.as_str()) {
                missing.push(format!("{folder}/{file}"));
            }
        }
    }
    assert!(missing.is_empty(), "ARCHITECTURE.md's code map lacks {missing:?}");
    // `path/to/file.rs::test_name` (or `…::tests::name`) names a function of that file.
    for reference in named.iter().filter(|r| r.contains(".rs::")) {
        let (file, path) = reference.split_once("::").unwrap();
        let function = path.rsplit("::").next().unwrap();
        let source = std::fs::read_to_string(workspace().join(file))
            .unwrap_or_else(|e| panic!("ARCHITECTURE.md names {reference}: {file}: {e}"));
        assert!(
            source.contains(&format!("fn {function}(")),
            "ARCHITECTURE.md names {reference}, which {file} lacks"
        );
    }
}
