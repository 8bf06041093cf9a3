//! The crates' layering: in neither crate does a top-level module use another that uses it back,
//! directly or through others (ARCHITECTURE.md lists the order). A module's uses are read from
//! its source files: every `crate::name` and every name in a `crate::{…}` group, outside
//! `#[cfg(test)]` modules, doc comments and comments.

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

/// The top-level modules a source text names through `crate::`.
fn uses(source: &str) -> BTreeSet<String> {
    // What follows a unit-test module is test code: it may reach anywhere.
    let code = source.split("#[cfg(test)]").next().unwrap_or_default();
    let mut names = BTreeSet::new();
    // Comments (from `//` to the end of the line, doc comments included) are not uses.
    for line in code.lines().map(|line| line.split("//").next().unwrap_or_default()) {
        for (at, _) in line.match_indices("crate::") {
            let rest = &line[at + "crate::".len()..];
            if let Some(group) = rest.strip_prefix('{') {
                let group = &group[..group.find('}').unwrap_or(group.len())];
                names.extend(group.split(',').map(|item| ident(item.trim()).to_string()));
            } else {
                names.insert(ident(rest).to_string());
            }
        }
    }
    names.retain(|name| !name.is_empty() && name != "self");
    names
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
    // Names that are not modules (re-exported items at the crate root) are not edges.
    let modules: BTreeSet<String> = graph.keys().cloned().collect();
    for used in graph.values_mut() {
        used.retain(|name| modules.contains(name));
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
    let used =
        uses("use crate::{fs, json::read, self};\nlet x = crate::plan::Tier::Quick; // crate::front\n");
    assert_eq!(used, BTreeSet::from(["fs".to_string(), "json".into(), "plan".into()]));
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
