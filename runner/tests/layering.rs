//! The crates' layering: ARCHITECTURE.md lists each crate's top-level modules in layers, and
//! every module uses only modules of earlier layers (so no module uses another that uses it
//! back, directly or through others), and the list names every module there is. A module's uses
//! are read from its source files: every `crate::name` and every name in a `crate::{…}` group,
//! outside `#[cfg(test)]` modules, doc comments and comments. Inside each folder module, its
//! children use each other in no cycle either, read from `crate::`, `super::` and `self::` paths.

use crate::source;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use source::production_code;

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
        let src = workspace().join(crate_src);
        let graph = module_graph(&src);
        // The reader saw every top-level module: each folder and file beside the crate root.
        let entries: BTreeSet<String> = std::fs::read_dir(&src)
            .unwrap()
            .map(|entry| entry.unwrap().file_name().to_string_lossy().trim_end_matches(".rs").to_string())
            .filter(|name| name != "lib" && name != "main")
            .collect();
        assert_eq!(graph.keys().cloned().collect::<BTreeSet<_>>(), entries, "{crate_src}: modules missed");
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
    for (crate_name, src) in [("cvvdp", "cvvdp/src"), ("renderer", "renderer/src"), ("runner", "runner/src")]
    {
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
    for (folder, extension) in
        [("cvvdp/src", "rs"), ("renderer/src", "rs"), ("runner/src", "rs"), ("shaders", "wgsl")]
    {
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

// Inside a folder module the same rule holds among its children: `run/scene.rs` may use
// `run/rounds.rs` or be used by it, not both. A folder's `mod.rs` is the children's parent, not
// one of them: a child that uses an item `mod.rs` defines uses its parent; one that uses an item
// `mod.rs` only imports (`use rounds::ModeRun;`, `pub use verdict::Check;`) uses that child.

/// Module → the modules it uses.
type Graph = BTreeMap<String, BTreeSet<String>>;

/// Module path → the names its `use` declarations bring in → the paths they stand for.
type Imports = BTreeMap<Vec<String>, BTreeMap<String, Vec<String>>>;

/// A module's path from the crate root: `scene/import/files.rs` → `scene::import::files`,
/// `scene/import/mod.rs` → `scene::import`, `lib.rs` → the root.
fn module_path(relative: &str) -> Vec<String> {
    let mut path: Vec<String> = relative.trim_end_matches(".rs").split('/').map(String::from).collect();
    if path == ["lib"] || path.last().is_some_and(|last| last == "mod") {
        path.pop();
    }
    path
}

/// The paths of a path tree, given the text at its start and the module path its first segment
/// is relative to: `super::{a::B, c as d}` from `m::n` gives `m::a::B` (named `B`) and `m::c`
/// (named `d`). `super` goes up, `self` stays, `crate` starts at the root; a glob names the
/// module. Returns the paths with the name each brings in, and the length of text read.
fn path_tree(text: &str, prefix: Vec<String>, out: &mut Vec<(Vec<String>, String)>) -> usize {
    let trimmed = text.trim_start();
    if let Some(mut rest) = trimmed.strip_prefix('{') {
        loop {
            rest = rest.trim_start();
            if let Some(after) = rest.strip_prefix('}') {
                return text.len() - after.len();
            }
            let used = path_tree(rest, prefix.clone(), out);
            rest = rest[used..].trim_start();
            match rest.strip_prefix(',') {
                Some(after) => rest = after,
                None if rest.starts_with('}') => {}
                // Nothing this reader understands: leave the group.
                None => return text.len() - rest.len(),
            }
        }
    }
    if let Some(after) = trimmed.strip_prefix('*') {
        out.push((prefix, "*".to_string()));
        return text.len() - after.len();
    }
    let name = ident(trimmed);
    if name.is_empty() {
        return 0;
    }
    let mut path = prefix;
    match name {
        "super" => {
            path.pop();
        }
        "crate" => path.clear(),
        "self" => {}
        _ => path.push(name.to_string()),
    }
    let mut rest = &trimmed[name.len()..];
    if let Some(next) = rest.strip_prefix("::")
        && (next.starts_with(['{', '*']) || !ident(next).is_empty())
    {
        return text.len() - next.len() + path_tree(next, path, out);
    }
    // A leaf, renamed or not.
    let mut alias = path.last().cloned().unwrap_or_default();
    if let Some(renamed) = rest.trim_start().strip_prefix("as ") {
        let renamed = renamed.trim_start();
        alias = ident(renamed).to_string();
        rest = &renamed[alias.len()..];
    }
    out.push((path, alias));
    text.len() - rest.len()
}

/// Whether `text[at..]` starts a token: nothing of a name or a path right before it.
fn token_start(text: &str, at: usize) -> bool {
    !text[..at].ends_with(|c: char| c.is_alphanumeric() || c == '_' || c == ':')
}

/// The production source files of a crate, relative to its `src` with `/` between folders,
/// and their text: the crate root and every module it declares, outside `#[cfg(test)]`.
fn crate_sources(src: &Path) -> BTreeMap<String, String> {
    files_under(src, "rs")
        .into_iter()
        .filter(|f| f != "main.rs")
        .map(|f| {
            let text = std::fs::read_to_string(src.join(&f)).unwrap();
            (f, text)
        })
        .collect()
}

/// Every module of a crate, and for each, the names its `use` declarations bring in with the
/// paths they stand for (those of the crate; other crates' are left out). `sources` maps each
/// file, relative to `src`, to its text; only modules declared outside `#[cfg(test)]` count.
fn modules_and_imports(sources: &BTreeMap<String, String>) -> (BTreeSet<Vec<String>>, Imports) {
    let code: BTreeMap<Vec<String>, String> =
        sources.iter().map(|(file, text)| (module_path(file), production_code(text))).collect();
    let mut modules = BTreeSet::from([Vec::new()]);
    let mut queue = vec![Vec::<String>::new()];
    while let Some(module) = queue.pop() {
        let Some(text) = code.get(&module) else { continue };
        for (at, _) in text.match_indices("mod ") {
            let name = ident(&text[at + 4..]);
            let after = text[at + 4 + name.len()..].trim_start();
            if token_start(text, at) && !name.is_empty() && after.starts_with([';', '{']) {
                let mut child = module.clone();
                child.push(name.to_string());
                if modules.insert(child.clone()) {
                    queue.push(child);
                }
            }
        }
    }
    let mut imports = Imports::new();
    for (module, text) in &code {
        if !modules.contains(module) {
            continue;
        }
        for (at, _) in text.match_indices("use ") {
            if !token_start(text, at) {
                continue;
            }
            let tree = &text[at + 4..];
            let first = ident(tree.trim_start());
            let mut child = module.clone();
            child.push(first.to_string());
            if !(matches!(first, "crate" | "super" | "self") || modules.contains(&child)) {
                continue;
            }
            let mut paths = Vec::new();
            path_tree(tree, module.clone(), &mut paths);
            for (path, name) in paths {
                imports.entry(module.clone()).or_default().insert(name, path);
            }
        }
    }
    (modules, imports)
}

/// The module a path lands in: the longest run of modules it names from the root, after the
/// names that modules only import are followed to where they come from.
fn landing_module(path: &[String], modules: &BTreeSet<Vec<String>>, imports: &Imports) -> Vec<String> {
    let mut path = path.to_vec();
    let mut depth = 0;
    for _ in 0..64 {
        while depth < path.len() && modules.contains(&path[..=depth]) {
            depth += 1;
        }
        let imported = path.get(depth).and_then(|name| imports.get(&path[..depth])?.get(name));
        match imported {
            Some(target) if target.as_slice() != &path[..=depth] => {
                path = target.iter().chain(&path[depth + 1..]).cloned().collect();
                depth = 0;
            }
            _ => break,
        }
    }
    path.truncate(depth);
    path
}

/// For each folder module (the root left out: the layers above order it), its children and
/// the children each uses: read from every `crate::…`, `super::…` and `self::…` path (groups
/// included) outside `#[cfg(test)]` modules and comments, each resolved to the module it lands
/// in. A file inside a child (`scene/import/files.rs` for `scene`) speaks for that child.
fn folder_graphs(sources: &BTreeMap<String, String>) -> BTreeMap<Vec<String>, Graph> {
    let (modules, imports) = modules_and_imports(sources);
    let mut graphs: BTreeMap<Vec<String>, Graph> = BTreeMap::new();
    for module in &modules {
        if let Some((child, folder)) = module.split_last()
            && !folder.is_empty()
        {
            graphs.entry(folder.to_vec()).or_default().entry(child.clone()).or_default();
        }
    }
    for (file, text) in sources {
        let module = module_path(file);
        if !modules.contains(&module) {
            continue;
        }
        let code = production_code(text);
        let mut read_to = 0;
        for (at, _) in code.match_indices(['c', 's']) {
            let rest = &code[at..];
            if at < read_to
                || !token_start(&code, at)
                || !["crate::", "super::", "self::"].iter().any(|k| rest.starts_with(k))
            {
                continue;
            }
            let mut paths = Vec::new();
            read_to = at + path_tree(rest, module.clone(), &mut paths);
            for (path, _) in paths {
                let target = landing_module(&path, &modules, &imports);
                let shared = module.iter().zip(&target).take_while(|(a, b)| a == b).count();
                if shared == 0 || shared == module.len() || shared == target.len() {
                    // The root's children, the file's own folder or below it, or an ancestor.
                    continue;
                }
                let graph = graphs.entry(module[..shared].to_vec()).or_default();
                graph.entry(module[shared].clone()).or_default().insert(target[shared].clone());
            }
        }
    }
    graphs
}

/// Every cycle of a graph that passes no node twice, each from its first node by name: all of
/// them, so that a failure names every one to break.
fn cycles(graph: &Graph) -> Vec<Vec<String>> {
    fn extend(graph: &Graph, path: &mut Vec<String>, found: &mut Vec<Vec<String>>) {
        let start = path[0].clone();
        for next in graph.get(path.last().unwrap()).into_iter().flatten() {
            if *next == start {
                found.push(path.iter().chain([next]).cloned().collect());
            } else if *next > start && !path.contains(next) {
                path.push(next.clone());
                extend(graph, path, found);
                path.pop();
            }
        }
    }
    let mut found = Vec::new();
    for node in graph.keys() {
        extend(graph, &mut vec![node.clone()], &mut found);
    }
    found
}

/// Each cycle among the children of a folder module, as `folder: a → b → a`.
fn folder_cycles(sources: &BTreeMap<String, String>) -> Vec<String> {
    let mut found = Vec::new();
    for (folder, graph) in folder_graphs(sources) {
        for circle in cycles(&graph) {
            found.push(format!("{}: {}", folder.join("/"), circle.join(" → ")));
        }
    }
    found
}

#[test]
fn the_folder_reader_sees_uses_between_siblings_and_finds_their_cycles() {
    let sources: BTreeMap<String, String> = [
        ("lib.rs", "mod error;\npub mod run;\npub use run::Record;\n"),
        ("error.rs", "pub struct Error;\n"),
        (
            "run/mod.rs",
            "mod scene;\nmod rounds;\nmod results;\nmod memory;\n#[cfg(test)]\nmod tests;\n\
             pub use results::Record;\nuse scene::Scene;\npub struct Plan;\nfn go() { rounds::go(); }\n",
        ),
        // Through a group, past a comment and a test module.
        (
            "run/scene.rs",
            "use super::{\n    rounds::{self, Round},\n    Plan,\n};\nuse crate::error::Error; // super::memory\n\
             #[cfg(test)]\nmod tests {\n    use super::super::memory;\n}\n",
        ),
        // Through a name `mod.rs` imports, and through `crate::` to the re-export of a re-export.
        ("run/rounds.rs", "pub fn go() { let _: super::Scene; let _: Option<crate::Record>; }\n"),
        // A circle of its own: results ↔ memory, through `crate::run::` and `super::super::`.
        ("run/results.rs", "pub struct Record;\nfn f() { crate::run::memory::free(); }\n"),
        ("run/memory.rs", "pub fn free() { let _ = super::super::run::results::Record; }\n"),
        ("run/tests.rs", "use super::scene::Scene;\nuse super::rounds;\n"),
    ]
    .into_iter()
    .map(|(file, text)| (file.to_string(), text.to_string()))
    .collect();
    let graphs = folder_graphs(&sources);
    let run = &graphs[&vec!["run".to_string()]];
    let set = |names: &[&str]| names.iter().map(|n| n.to_string()).collect::<BTreeSet<String>>();
    assert_eq!(run["scene"], set(&["rounds"]), "the graph: {run:#?}");
    assert_eq!(run["rounds"], set(&["results", "scene"]), "the graph: {run:#?}");
    assert_eq!(run["results"], set(&["memory"]));
    assert_eq!(run["memory"], set(&["results"]));
    assert!(!run.contains_key("tests"), "test modules are left out: {run:#?}");
    assert_eq!(folder_cycles(&sources), ["run: memory → results → memory", "run: rounds → scene → rounds"]);
    let graph: Graph = [
        ("a".to_string(), set(&["b"])),
        ("b".into(), set(&["a", "c"])),
        ("c".into(), set(&["a"])),
        ("d".into(), set(&["a"])),
    ]
    .into();
    assert_eq!(cycles(&graph), [vec!["a", "b", "a"], vec!["a", "b", "c", "a"]]);
}

#[test]
fn no_folder_module_has_an_import_cycle_between_its_children() {
    let mut found = Vec::new();
    for crate_src in ["renderer/src", "runner/src"] {
        let sources = crate_sources(&workspace().join(crate_src));
        let graphs = folder_graphs(&sources);
        assert!(graphs.len() >= 4, "{crate_src}: only {} folder modules found", graphs.len());
        found.extend(folder_cycles(&sources).into_iter().map(|c| format!("{crate_src}/{c}")));
    }
    assert!(found.is_empty(), "modules of one folder use each other in a cycle:\n{}", found.join("\n"));
}
