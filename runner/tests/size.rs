//! The size rule of ARCHITECTURE.md: no production function longer than 80 lines (from its `fn`
//! line to its closing brace) and no source file longer than 700, in the renderer's and the
//! runner's sources, their build scripts and the WGSL under `shaders/`. Test code is not held to
//! it: `#[cfg(test)]` items, `tests.rs` files, and the `tests/`, `benches/` and `examples/`
//! folders (which are not walked). The exceptions are the ones ARCHITECTURE.md lists with their
//! reasons, and each must still be over the rule, so the list cannot outlive its cause.
//!
//! Braces are counted in the code only: comments, strings and character literals are blanked
//! first (lines kept, `source::blank_non_code`), so a `'{'` or a `"}"` never opens or closes a
//! body.

use crate::source;

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use source::{blank_non_code, item_end, test_ranges};

const MAX_FUNCTION_LINES: usize = 80;
const MAX_FILE_LINES: usize = 700;
/// The start of ARCHITECTURE.md's paragraph that the list of exceptions follows.
const HEADING: &str = "**Exceptions to the size rule.**";

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap().to_path_buf()
}

/// The files of a folder with one of `extensions`, recursively, relative to the workspace with
/// `/` between folders; `tests.rs` files are test code and left out.
fn sources(folder: &str, extensions: &[&str]) -> Vec<String> {
    let root = workspace();
    let mut files = Vec::new();
    let mut folders = vec![root.join(folder)];
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                folders.push(path);
            } else if path.extension().is_some_and(|e| extensions.iter().any(|x| e == *x))
                && path.file_name().is_some_and(|name| name != "tests.rs")
            {
                files.push(path.strip_prefix(&root).unwrap().to_string_lossy().replace('\\', "/"));
            }
        }
    }
    files.sort();
    files
}

/// One function of a source: its name, the line of its `fn` (1-based) and its length in lines.
#[derive(Debug, PartialEq)]
struct Function {
    name: String,
    line: usize,
    lines: usize,
}

/// Every function with a body outside `skip`, in the code `blank_non_code` left.
fn functions(code: &str, skip: &[(usize, usize)]) -> Vec<Function> {
    let line_of = |at: usize| code[..at].matches('\n').count() + 1;
    let mut found = Vec::new();
    for (at, _) in code.match_indices("fn") {
        let before = code[..at].chars().next_back();
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_')
            || skip.iter().any(|&(a, b)| a <= at && at < b)
        {
            continue;
        }
        let rest = &code[at + 2..];
        let name_start = rest.len() - rest.trim_start().len();
        if name_start == 0 {
            continue; // `fn(` is a pointer type; `fnord` is another word
        }
        let rest = &rest[name_start..];
        let name_len = rest.find(|c: char| !(c.is_alphanumeric() || c == '_')).unwrap_or(rest.len());
        if name_len == 0 || rest[..name_len].starts_with(|c: char| c.is_ascii_digit()) {
            continue;
        }
        let Some((end, true)) = item_end(code, at) else { continue };
        let (first, last) = (line_of(at), line_of(end - 1));
        found.push(Function { name: rest[..name_len].to_string(), line: first, lines: last - first + 1 });
    }
    found
}

/// What breaks the rule in one source: `path` for the file, `path::name` for a function, each
/// with its count of lines.
fn over_the_rule(path: &str, source: &str) -> Vec<(String, usize)> {
    let code = blank_non_code(source);
    let tests = if path.ends_with(".rs") { test_ranges(&code) } else { Vec::new() };
    let test_lines: usize = tests.iter().map(|&(a, b)| code[a..b].lines().count()).sum();
    let mut over = Vec::new();
    let file_lines = source.lines().count() - test_lines;
    if file_lines > MAX_FILE_LINES {
        over.push((path.to_string(), file_lines));
    }
    for function in functions(&code, &tests) {
        if function.lines > MAX_FUNCTION_LINES {
            over.push((format!("{path}::{}", function.name), function.lines));
        }
    }
    over
}

/// The exceptions that `map` (ARCHITECTURE.md) lists after its paragraph `HEADING`: list items
/// `- \`path\` — reason` or `- \`path::function\` — reason` after the paragraph's blank line,
/// up to the first line that is neither an item nor its continuation.
fn exceptions_in(map: &str) -> BTreeSet<String> {
    let mut lines = map.lines().skip_while(|line| !line.starts_with(HEADING));
    assert!(lines.next().is_some(), "ARCHITECTURE.md has no paragraph {HEADING}");
    let mut exceptions = BTreeSet::new();
    let list = lines.skip_while(|line| !line.trim().is_empty()).skip_while(|line| line.trim().is_empty());
    for line in list.take_while(|line| line.starts_with("- ") || line.starts_with("  ")) {
        let Some(item) = line.strip_prefix("- ") else { continue };
        let (name, reason) = item.split_once(" — ").unwrap_or_else(|| {
            panic!("ARCHITECTURE.md's size exception {item:?} gives no reason (`- `path` — reason`)")
        });
        assert!(!reason.trim().is_empty(), "ARCHITECTURE.md's size exception {name} gives no reason");
        exceptions.insert(name.trim().trim_matches('`').to_string());
    }
    exceptions
}

#[test]
fn the_reader_counts_code_braces_only_and_leaves_out_test_code() {
    let source = "fn a() {\n    let s = \"}\";\n    let c = '{';\n    // }\n    /* { /* } */ */\n    \
                  let r = r#\"}\"#;\n}\nfn b<'x>(v: &'x [u8; 2]) -> u8 { v[0] }\nfn decl(x: fn(u8) -> u8);\n\
                  #[cfg(test)]\nmod tests {\n    fn t() {\n    }\n}\nfn after() {\n}\n";
    let code = blank_non_code(source);
    assert_eq!(code.lines().count(), source.lines().count());
    let found = functions(&code, &test_ranges(&code));
    assert_eq!(
        found,
        [
            Function { name: "a".into(), line: 1, lines: 7 },
            Function { name: "b".into(), line: 8, lines: 1 },
            Function { name: "after".into(), line: 15, lines: 2 },
        ]
    );
    let long = format!("fn long() {{\n{}}}\n", "    x();\n".repeat(MAX_FUNCTION_LINES - 2));
    assert!(over_the_rule("a.rs", &long).is_empty());
    let longer = format!("fn long() {{\n{}}}\n", "    x();\n".repeat(MAX_FUNCTION_LINES - 1));
    assert_eq!(over_the_rule("a.wgsl", &longer), [("a.wgsl::long".to_string(), MAX_FUNCTION_LINES + 1)]);
    let map = format!(
        "{HEADING} Listed below.\nStill the paragraph.\n\n- `a.rs` — generated\n- `b.wgsl::f` — one \
         table,\n  whole\n\n- `c.rs` — after the list\n"
    );
    assert_eq!(exceptions_in(&map), BTreeSet::from(["a.rs".to_string(), "b.wgsl::f".to_string()]));
}

#[test]
fn no_source_file_or_function_is_over_the_size_rule_unless_the_map_names_it() {
    let mut files = sources("renderer/src", &["rs"]);
    files.extend(sources("runner/src", &["rs"]));
    files.extend(sources("cvvdp/src", &["rs"]));
    files.extend(sources("shaders", &["wgsl"]));
    files.extend(["renderer/build.rs".to_string(), "runner/build.rs".to_string()]);
    let exceptions = exceptions_in(&std::fs::read_to_string(workspace().join("ARCHITECTURE.md")).unwrap());
    let mut over = Vec::new();
    let mut excused = BTreeSet::new();
    for path in &files {
        let source = std::fs::read_to_string(workspace().join(path)).unwrap();
        for (name, lines) in over_the_rule(path, &source) {
            if exceptions.contains(&name) {
                excused.insert(name);
            } else {
                over.push(format!("{name}: {lines} lines"));
            }
        }
    }
    let stale: Vec<&String> = exceptions.difference(&excused).collect();
    assert!(
        over.is_empty() && stale.is_empty(),
        "over the size rule ({MAX_FUNCTION_LINES} lines a function, {MAX_FILE_LINES} a file) and not \
         among ARCHITECTURE.md's exceptions: {over:#?}\nexceptions no longer over it: {stale:?}"
    );
}
