//! Baselines as files a reviewer reads: a bless that moved nothing changes only its last two
//! sections, who blessed it when and the times; a moved value is one line; a baseline of the schema before
//! (whole run records) is compared as it was blessed, and `aabench upgrade` rewrites it into
//! exactly what a bless of the same runs writes. Real runs on lavapipe, real files and exits.

use crate::support;

use std::path::{Path, PathBuf};

use serde_json::{Value, json};
use support::*;

const MODES: &str = "deferred-1x1,reference-2x2,adaptive-2x2";

/// `aabench run` of 5 rounds into `<workspace>/<folder>`; its run folder.
fn run(ws: &Workspace, folder: &str) -> PathBuf {
    let output = ws.run(&["run", "--out", folder, "--modes", MODES, "--repetitions", "5"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    std::fs::read_dir(ws.dir.join(folder)).unwrap().next().unwrap().unwrap().path()
}

fn arg(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// The workspace's one baseline file.
fn baseline_file(ws: &Workspace) -> PathBuf {
    let key = std::fs::read_dir(ws.dir.join("baselines")).unwrap().find_map(|e| {
        let path = e.unwrap().path();
        path.is_dir().then_some(path)
    });
    key.unwrap().join("quick/edge.json")
}

fn bless(ws: &Workspace, runs: &[&Path]) -> String {
    let mut args = vec!["bless"];
    args.extend(runs.iter().map(|run| arg(run)));
    let output = ws.run(&args);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    std::fs::read_to_string(baseline_file(ws)).unwrap()
}

/// The lines of `new` that differ from `old`'s at the same place, each with the section it is
/// in (the top-level field it belongs to).
fn changed_lines<'a>(old: &str, new: &'a str) -> Vec<(String, &'a str)> {
    assert_eq!(old.lines().count(), new.lines().count(), "the same values, the same lines");
    let mut section = String::new();
    let mut changed = Vec::new();
    for (before, after) in old.lines().zip(new.lines()) {
        if let Some(field) = after.strip_prefix("  \"") {
            section = field.split('"').next().unwrap().to_string();
        }
        if before != after {
            changed.push((section.clone(), after.trim()));
        }
    }
    changed
}

#[test]
fn a_bless_that_moved_nothing_changes_only_who_blessed_it_when_and_the_times() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("baselines-review");
    ws.manifest("edge", "edge", |_| {});
    let (first, second) = (run(&ws, "first"), run(&ws, "second"));
    let old = bless(&ws, &[&first]);
    assert!(old.lines().count() < 200, "one value a line, no run record: {} lines", old.lines().count());
    assert!(old.contains("\n        \"psnr_vs_truth\": "), "a metric is a line of its own:\n{old}");
    let new = bless(&ws, &[&second]);
    let changed = changed_lines(&old, &new);
    for (section, line) in &changed {
        assert!(
            section == "blessed" || section == "times",
            "{section}: {line} moved, though no image or number did"
        );
    }
    assert!(changed.iter().any(|(section, _)| section == "times"), "two processes never time alike");

    // One value moved in one mode: one line outside the times, the value's own.
    let mut record = read_json(&second.join("run.json"));
    let modes = record["scenes"][0]["modes"].as_array_mut().unwrap();
    let reference = modes.iter_mut().find(|m| m["mode"] == "reference-2x2").unwrap();
    let psnr = &mut reference["vs_ground_truth"]["psnr_db"];
    *psnr = json!(psnr.as_f64().unwrap() - 0.5);
    record["run_id"] = json!("moved-quick");
    let moved = ws.dir.join("moved");
    std::fs::create_dir_all(&moved).unwrap();
    write_json(&moved.join("run.json"), &record);
    let after = bless(&ws, &[&moved]);
    let outside: Vec<_> = changed_lines(&new, &after)
        .into_iter()
        .filter(|(section, _)| section != "blessed" && section != "times")
        .collect();
    assert_eq!(outside.len(), 1, "{outside:?}");
    assert!(outside[0].1.starts_with("\"psnr_vs_truth\": "), "{outside:?}");
}

#[test]
fn a_baseline_of_the_schema_before_is_compared_as_blessed_and_upgraded_to_what_bless_writes() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("baselines-upgrade");
    ws.manifest("edge", "edge", |_| {});
    let (first, second) = (run(&ws, "first"), run(&ws, "second"));
    let blessed: Value = serde_json::from_str(&bless(&ws, &[&first, &second])).unwrap();
    let decide = |out: &str| -> Vec<Value> {
        let output = ws.run(&["compare", arg(&second), "--out", out]);
        assert_eq!(output.status.code(), Some(0), "{}", String::from_utf8_lossy(&output.stdout));
        let verdict = read_json(&ws.dir.join(out).join("verdict.json"));
        verdict["checks"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| json!([c["metric"], c["mode"], c["outcome"], c["detail"]]))
            .collect()
    };
    let today = decide("today");

    // The same two runs as schema 1 held them: every run's whole record of the scene.
    let records = [&first, &second].map(|run| read_json(&run.join("run.json")));
    let file = baseline_file(&ws);
    let whole = json!({
        "schema": "aabench.baseline/1",
        "aabench_version": records[0]["aabench_version"],
        "blessed_at": blessed["blessed"]["at"],
        "run_ids": [records[0]["run_id"], records[1]["run_id"]],
        "tier": "quick",
        "platform": records[0]["platform"],
        "settings": records[0]["settings"],
        "scenes": [records[0]["scenes"][0], records[1]["scenes"][0]],
    });
    write_json(&file, &whole);
    assert_eq!(decide("before"), today, "the same checks, outcomes and details");

    let upgraded = ws.run(&["upgrade"]);
    assert_eq!(upgraded.status.code(), Some(0), "{}", stderr(&upgraded));
    assert!(String::from_utf8_lossy(&upgraded.stdout).contains("upgraded"), "{upgraded:?}");
    assert_eq!(read_json(&file), blessed, "upgrade writes what bless wrote");
    let again = ws.run(&["upgrade"]);
    assert!(String::from_utf8_lossy(&again.stdout).contains("of today's schema"), "{again:?}");

    // A folder in the tier is no file upgrade can carry over: refused, naming upgrade.
    write_json(&file, &whole);
    let archive = file.parent().unwrap().join("archive");
    std::fs::create_dir(&archive).unwrap();
    let kept = ws.run(&["upgrade"]);
    assert_eq!(kept.status.code(), Some(2));
    let said = "archive: is no file: upgrade writes the tier's folder anew and could not keep it";
    assert!(stderr(&kept).contains(said) && stderr(&kept).contains("and upgrade again"), "{}", stderr(&kept));
    std::fs::remove_dir(&archive).unwrap();

    // A schema-1 file with fewer records than run ids is refused by name.
    let mut short = whole.clone();
    short["scenes"].as_array_mut().unwrap().pop();
    write_json(&file, &short);
    let refused = ws.run(&["upgrade"]);
    assert_eq!(refused.status.code(), Some(2));
    assert!(stderr(&refused).contains("edge.json: scenes: 1 records for 2 run ids"), "{}", stderr(&refused));
}
