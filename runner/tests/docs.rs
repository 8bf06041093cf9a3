//! The documentation as a reader meets it: every link and image in README.md, ARCHITECTURE.md
//! and `docs/` resolves to a file that exists and, where it names a heading, to a heading that
//! exists (GitHub's anchor rules); every chapter is in `docs/SUMMARY.md` and linked from the
//! README or the book's introduction (which the README links); the README stays a front door
//! (at most 200 lines and 20 KB); the generated results chapters name the run they came from. No
//! device: these read files only.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap().to_path_buf()
}

/// README.md, ARCHITECTURE.md and every Markdown file under `docs/`.
fn documents() -> Vec<PathBuf> {
    let root = workspace();
    let mut files = vec![root.join("README.md"), root.join("ARCHITECTURE.md")];
    let mut chapters: Vec<PathBuf> = std::fs::read_dir(root.join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    chapters.sort();
    files.extend(chapters);
    files
}

/// The text outside fenced code blocks and inline code spans, line by line: links there are
/// text, not links. A code span may wrap onto the next line of its paragraph.
fn prose(markdown: &str) -> Vec<String> {
    let mut lines = Vec::new();
    let mut paragraph: Vec<&str> = Vec::new();
    let flush = |paragraph: &mut Vec<&str>, lines: &mut Vec<String>| {
        // Every other piece between backticks is code.
        let text: String = paragraph.join("\n").split('`').step_by(2).collect();
        lines.extend(text.lines().map(str::to_owned));
        paragraph.clear();
    };
    let mut fenced = false;
    for line in markdown.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            flush(&mut paragraph, &mut lines);
        } else if !fenced && line.trim().is_empty() {
            flush(&mut paragraph, &mut lines);
        } else if !fenced {
            paragraph.push(line);
        }
    }
    flush(&mut paragraph, &mut lines);
    lines
}

/// The headings outside fenced code blocks, their code spans kept as text.
fn headings(markdown: &str) -> Vec<String> {
    let mut fenced = false;
    let mut found = Vec::new();
    for line in markdown.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        let hashes = line.chars().take_while(|&c| c == '#').count();
        if !fenced && (1..=6).contains(&hashes) && line[hashes..].starts_with(' ') {
            found.push(line[hashes..].replace(['`', '*'], ""));
        }
    }
    found
}

/// The targets of inline links and images, `[text](target)` and `![alt](target)`.
fn link_targets(markdown: &str) -> Vec<String> {
    let mut targets = Vec::new();
    for line in prose(markdown) {
        let mut rest = line.as_str();
        while let Some(at) = rest.find("](") {
            let after = &rest[at + 2..];
            let Some(end) = after.find(')') else { break };
            targets.push(after[..end].trim().to_string());
            rest = &after[end..];
        }
    }
    targets
}

/// GitHub's anchor for a heading: lowercase, letters, digits, `-` and `_` kept, spaces to
/// hyphens, everything else dropped.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

/// The anchors of a document's headings (a repeated heading gets `-1`, `-2`, … as on GitHub).
fn anchors(markdown: &str) -> BTreeSet<String> {
    let mut seen = BTreeSet::new();
    for heading in headings(markdown) {
        let base = slug(&heading);
        let mut anchor = base.clone();
        let mut n = 0;
        while seen.contains(&anchor) {
            n += 1;
            anchor = format!("{base}-{n}");
        }
        seen.insert(anchor);
    }
    seen
}

#[test]
fn slugs_follow_github() {
    assert_eq!(slug("Colour: from HDR to code values"), "colour-from-hdr-to-code-values");
    assert_eq!(slug("Beyond the paper: area weights"), "beyond-the-paper-area-weights");
    assert_eq!(slug("The suite's scenes"), "the-suites-scenes");
    assert_eq!(slug("Adaptive and its variants"), "adaptive-and-its-variants");
    assert_eq!(link_targets("see [a](b.md#c) and ![d](e.png), not `[f](g)`"), ["b.md#c", "e.png"]);
    // A code span that wraps onto the next line hides its code, not the prose after it.
    assert_eq!(link_targets("a `span that\nwraps` then [h](i.md)"), ["i.md"]);
    assert!(anchors("### `renderer/src`\n").contains("renderersrc"));
}

#[test]
fn every_link_and_image_in_the_documentation_resolves() {
    let mut broken = Vec::new();
    let mut checked = 0;
    for file in documents() {
        let text = std::fs::read_to_string(&file).unwrap();
        for target in link_targets(&text) {
            if target.starts_with("http://")
                || target.starts_with("https://")
                || target.starts_with("mailto:")
            {
                continue;
            }
            checked += 1;
            let (path, anchor) =
                target.split_once('#').map_or((target.as_str(), None), |(p, a)| (p, Some(a)));
            let linked = if path.is_empty() { file.clone() } else { file.parent().unwrap().join(path) };
            if !linked.exists() {
                broken.push(format!("{}: {target}: no such file", file.display()));
                continue;
            }
            if let Some(anchor) = anchor {
                let heads = anchors(&std::fs::read_to_string(&linked).unwrap_or_default());
                if !heads.contains(anchor) {
                    broken.push(format!(
                        "{}: {target}: no heading `{anchor}` in {}",
                        file.display(),
                        linked.display()
                    ));
                }
            }
        }
    }
    assert!(broken.is_empty(), "{} broken link(s):\n{}", broken.len(), broken.join("\n"));
    assert!(checked > 50, "only {checked} links found: the parser is missing them");
}

#[test]
fn every_chapter_is_in_the_book_and_reached_from_the_front_door_which_stays_short() {
    let root = workspace();
    let summary = std::fs::read_to_string(root.join("docs/SUMMARY.md")).unwrap();
    let listed: BTreeSet<String> = link_targets(&summary).into_iter().collect();
    for file in documents().iter().filter(|f| f.starts_with(root.join("docs"))) {
        let name = file.file_name().unwrap().to_string_lossy().to_string();
        assert!(name == "SUMMARY.md" || listed.contains(&name), "docs/{name} is not in docs/SUMMARY.md");
    }
    // And a reader finds it from the front door: linked from the README or from the book's
    // introduction, which the README links.
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let introduction = std::fs::read_to_string(root.join("docs/introduction.md")).unwrap();
    let file_of = |target: &str| target.split('#').next().unwrap_or_default().to_string();
    let from_readme: BTreeSet<String> = link_targets(&readme).iter().map(|t| file_of(t)).collect();
    let from_introduction: BTreeSet<String> =
        link_targets(&introduction).iter().map(|t| format!("docs/{}", file_of(t))).collect();
    assert!(from_readme.contains("docs/introduction.md"), "README.md does not link docs/introduction.md");
    for file in documents().iter().filter(|f| f.starts_with(root.join("docs"))) {
        let name = format!("docs/{}", file.file_name().unwrap().to_string_lossy());
        assert!(
            name == "docs/SUMMARY.md" || from_readme.contains(&name) || from_introduction.contains(&name),
            "{name} is linked from neither README.md nor docs/introduction.md"
        );
    }
    assert!(readme.len() <= 20_000, "README.md is {} bytes; depth belongs in docs/", readme.len());
    assert!(
        readme.lines().count() <= 200,
        "README.md is {} lines; depth belongs in docs/",
        readme.lines().count()
    );
    // The two commands that set up a fresh machine are the first code the reader sees.
    let first_block = readme.split("```").nth(1).expect("the README shows its commands");
    for command in ["ci/suite.sh", "ci/test.sh"] {
        assert!(
            first_block.contains(command),
            "the README's first code block lacks {command}: {first_block}"
        );
    }
}

#[test]
fn generated_results_name_their_run() {
    for chapter in ["docs/results.md", "docs/results-nightly.md", "docs/results-nightly-stills.md"] {
        let text = std::fs::read_to_string(workspace().join(chapter)).unwrap();
        let first = text.lines().next().unwrap_or_default();
        assert!(
            first.starts_with("<!-- Generated by `aabench report --markdown` from run ")
                && text.contains("\nRun `"),
            "{chapter} was not written by `aabench report --markdown` (first line: {first})"
        );
    }
}
