//! What the gate refuses to call green: a compare that compared less than its baselines hold,
//! time decided on too little evidence, baselines blessed from runs that cannot carry them,
//! and time against the base build with the process as the unit. Real runs on lavapipe, real
//! files and exit codes; the doctored records are copies of a real run with one field changed.
//!
//! The machine probes, the confidence reached by four processes a side, and a stray process
//! are unit tests in `src/machine.rs` and `src/compare/ab.rs`.

use crate::support;

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

use serde_json::{Value, json};
use support::*;

const MODES: &str = "deferred-1x1,reference-2x2,adaptive-2x2,reference-2x2-stalled";

/// Runs `aabench run` into `<workspace>/<folder>` and returns the run folder.
fn run(ws: &Workspace, folder: &str, repetitions: &str) -> PathBuf {
    let output = ws.run(&["run", "--out", folder, "--modes", MODES, "--repetitions", repetitions]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let runs: Vec<PathBuf> =
        std::fs::read_dir(ws.dir.join(folder)).unwrap().map(|e| e.unwrap().path()).collect();
    assert_eq!(runs.len(), 1, "{runs:?}");
    runs[0].clone()
}

/// [`run`] of 5 repetitions into `<workspace>/reports`, blessed as the workspace's baselines.
fn blessed_run(ws: &Workspace) -> PathBuf {
    let measured = run(ws, "reports", "5");
    assert_eq!(ws.run(&["bless", arg(&measured)]).status.code(), Some(0));
    measured
}

fn arg(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// A copy of `record` under a new run id in `<workspace>/<folder>/run.json`.
fn doctored(ws: &Workspace, folder: &str, record: &Value, edit: impl Fn(&mut Value)) -> PathBuf {
    let mut copy = record.clone();
    copy["run_id"] = json!(format!("{folder}-quick"));
    edit(&mut copy);
    let dir = ws.dir.join(folder);
    std::fs::create_dir_all(&dir).unwrap();
    write_json(&dir.join("run.json"), &copy);
    dir
}

/// `aabench compare` with `args`, its outputs into `<workspace>/<out>`.
fn compare(ws: &Workspace, runs: &[&Path], out: &str, args: &[&str]) -> (Output, Value) {
    let mut all = vec!["compare"];
    all.extend(runs.iter().map(|run| arg(run)));
    all.extend(["--out", out]);
    all.extend_from_slice(args);
    let output = ws.run(&all);
    let verdict = ws.dir.join(out).join("verdict.json");
    let verdict = if verdict.is_file() { read_json(&verdict) } else { Value::Null };
    (output, verdict)
}

fn outcomes<'a>(verdict: &'a Value, metric: &str, against: &str) -> Vec<(&'a str, &'a str)> {
    verdict["checks"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["metric"] == metric && c["against"] == against)
        .map(|c| (c["mode"].as_str().unwrap(), c["outcome"].as_str().unwrap()))
        .collect()
}

/// Mode `id` of the record's first scene.
fn mode_mut<'a>(record: &'a mut Value, id: &str) -> &'a mut Value {
    record["scenes"][0]["modes"].as_array_mut().unwrap().iter_mut().find(|m| m["mode"] == id).unwrap()
}

/// Multiplies every frame time of mode `id` by `factor`, and every pass's: a process that lands
/// slow lands slow in every pass of its frames.
fn scale_mode(record: &mut Value, id: &str, factor: f64) {
    let mode = mode_mut(record, id);
    let scale = |samples: &mut Value| {
        for sample in samples.as_array_mut().unwrap() {
            *sample = json!(sample.as_f64().unwrap() * factor);
        }
    };
    scale(&mut mode["frame_ms"]["samples"]);
    for pass in mode["passes"].as_array_mut().unwrap() {
        scale(&mut pass["ms"]["samples"]);
    }
}

/// Sets every round of mode `id` (its frame and each pass) to the series' median, ±0.5 % in a
/// fixed pattern.
fn calm_mode(record: &mut Value, id: &str) {
    let mode = mode_mut(record, id);
    let calm = |series: &mut Value| {
        let median = series["median"].as_f64().unwrap();
        for (k, sample) in series["samples"].as_array_mut().unwrap().iter_mut().enumerate() {
            *sample = json!(median * (1.0 + 0.005 * ((k % 3) as f64 - 1.0)));
        }
    };
    calm(&mut mode["frame_ms"]);
    for pass in mode["passes"].as_array_mut().unwrap() {
        calm(&mut pass["ms"]);
    }
}

/// Multiplies pass `pass` of mode `id` by `factor` in every frame, the frame taking the
/// difference.
fn slow_pass(record: &mut Value, id: &str, pass: usize, factor: f64) {
    let mode = mode_mut(record, id);
    let samples: Vec<f64> = mode["passes"][pass]["ms"]["samples"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_f64().unwrap())
        .collect();
    for (k, ms) in samples.iter().enumerate() {
        mode["passes"][pass]["ms"]["samples"][k] = json!(ms * factor);
        let frame = mode["frame_ms"]["samples"][k].as_f64().unwrap();
        mode["frame_ms"]["samples"][k] = json!(frame + ms * (factor - 1.0));
    }
}

/// The pass of mode `id` with the largest share of its frame below `most`, and that share.
fn pass_below(record: &Value, id: &str, most: f64) -> (usize, f64) {
    let mode = record["scenes"][0]["modes"].as_array().unwrap().iter().find(|m| m["mode"] == id).unwrap();
    let frame = mode["frame_ms"]["median"].as_f64().unwrap();
    let shares =
        mode["passes"].as_array().unwrap().iter().map(|p| p["ms"]["median"].as_f64().unwrap() / frame);
    shares.enumerate().filter(|(_, share)| *share < most).max_by(|a, b| a.1.total_cmp(&b.1)).unwrap()
}

/// Against a base whose processes timed alone (`--quality off`), the run's process that
/// measured quality (the gate's first) gives no time: it did other work between its rounds.
/// Made 40 % slower, it moves no check; the checks count the processes that timed alone, and
/// the mode that it alone rendered (a stalled one, which the gate does not time) is named.
#[test]
fn the_process_that_measured_quality_gives_no_time_against_a_base_that_timed_alone() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("quality-process");
    ws.manifest("edge", "edge", |_| {});
    let measured = blessed_run(&ws);
    let timed_modes = "deferred-1x1,reference-2x2,adaptive-2x2";
    let args = ["run", "--out", "alone", "--modes", timed_modes, "--repetitions", "3", "--quality", "off"];
    let output = ws.run(&args);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let alone = std::fs::read_dir(ws.dir.join("alone")).unwrap().next().unwrap().unwrap().path();
    let record = read_json(&alone.join("run.json"));
    let copies = |side: &str| -> Vec<PathBuf> {
        (0..4).map(|i| doctored(&ws, &format!("{side}-{i}"), &record, |_| {})).collect()
    };
    let (head, base) = (copies("head"), copies("base"));
    let slow = doctored(&ws, "slow-measured", &read_json(&measured.join("run.json")), |r| {
        for id in MODES.split(',') {
            scale_mode(r, id, 1.4);
        }
    });
    let mut runs = vec![slow.as_path()];
    runs.extend(head.iter().map(PathBuf::as_path));
    let base_args: Vec<&str> = std::iter::once("--base-runs").chain(base.iter().map(|p| arg(p))).collect();
    let (output, verdict) = compare(&ws, &runs, "gate", &base_args);
    assert_eq!(output.status.code(), Some(0), "{}", String::from_utf8_lossy(&output.stdout));
    let frame = outcomes(&verdict, "frame_time", "base");
    assert_eq!(frame.len(), 3, "{frame:?}");
    assert!(frame.iter().all(|(_, outcome)| *outcome == "unchanged"), "{frame:?}");
    let details: Vec<&str> = verdict["checks"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["against"] == "base")
        .map(|c| c["detail"].as_str().unwrap())
        .collect();
    assert!(
        details.iter().all(|d| d.contains("over 4 processes of the base and 4 of the run")),
        "{details:?}"
    );
    let notes = verdict["notes"].to_string();
    assert!(notes.contains("slow-measured-quick measured quality too and gives no time"), "{notes}");
    assert!(
        notes.contains("not compared for these modes") && notes.contains("reference-2x2-stalled"),
        "{notes}"
    );
}

/// A missing, non-folder or empty baseline folder, another platform's baselines only, a
/// missing scene, a missing mode, a run without scenes, a shard and an unfinished run each fail
/// compare (exit 1) with the reason in summary.md, junit.xml and verdict.json, and pass with
/// `--lenient`, which still reports the reason.
#[test]
fn a_compare_that_compared_less_than_its_baselines_fails_and_lenient_reports_it() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("strict");
    ws.manifest("a-edge", "edge", |_| {});
    ws.manifest("b-plane", "plane", |_| {});
    let full = blessed_run(&ws);
    let (same, _) = compare(&ws, &[&full], "gate-same", &[]);
    assert_eq!(same.status.code(), Some(0), "{}", String::from_utf8_lossy(&same.stdout));

    let record = read_json(&full.join("run.json"));
    let key = record["platform"]["key"].as_str().unwrap().to_string();
    std::fs::create_dir_all(ws.dir.join("empty-baselines")).unwrap();
    std::fs::create_dir_all(ws.dir.join("other-baselines/another-platform")).unwrap();
    copy_dir(&ws.dir.join("baselines").join(&key), &ws.dir.join("other-baselines/another-platform"));
    let drop_scene = doctored(&ws, "no-plane", &record, |r| {
        r["scenes"].as_array_mut().unwrap().pop();
    });
    let drop_mode = doctored(&ws, "no-adaptive", &record, |r| {
        r["scenes"][0]["modes"].as_array_mut().unwrap().retain(|m| m["mode"] != "adaptive-2x2");
    });
    let no_scenes = doctored(&ws, "no-scenes", &record, |r| r["scenes"] = json!([]));
    // Baselines of another platform judge a run whose every image is theirs (another test):
    // this one's first image is of other bits.
    let other_bits = doctored(&ws, "other-bits", &record, |r| {
        r["scenes"][0]["modes"][0]["output_hash"] = json!("0000000000000000");
    });
    let shard = doctored(&ws, "shard", &record, |r| {
        r["shard"] = json!({ "index": 1, "count": 2 });
        r["scenes"].as_array_mut().unwrap().pop();
    });
    let unfinished = doctored(&ws, "unfinished", &record, |r| {
        r["status"] = json!("running");
        r["finished_at"] = Value::Null;
    });
    std::fs::write(ws.dir.join("a-edge-file"), "not a folder").unwrap();
    // A shard is compared with the baselines of its own scenes (a sharded gate's job);
    // `merge-verdicts` fails the baselines that no shard compared.
    let (alone, verdict) = compare(&ws, &[&shard], "gate-shard", &[]);
    assert_eq!(alone.status.code(), Some(0), "{}", String::from_utf8_lossy(&alone.stdout));
    assert_eq!(verdict["shard"]["index"], 1);
    let summary = std::fs::read_to_string(ws.dir.join("gate-shard/summary.md")).unwrap();
    assert!(summary.contains("Shard 1/2 of the suite"), "{summary}");
    let cases: [(&str, &Path, &str, &str); 8] = [
        ("missing folder", &full, "no-such-folder", "cannot be read"),
        ("a file", &full, "a-edge-file", "is not a folder"),
        ("empty folder", &full, "empty-baselines", "holds no baselines for the quick tier"),
        ("another platform", &other_bits, "other-baselines", "only of `another-platform`"),
        ("missing scene", &drop_scene, "baselines", "the scene is not in the run"),
        ("missing mode", &drop_mode, "baselines", "not in the run"),
        ("no scenes", &no_scenes, "baselines", "the run has no scenes"),
        ("unfinished", &unfinished, "baselines", "did not finish"),
    ];
    for (name, run, baselines, reason) in cases {
        let out = format!("gate-{}", name.replace(' ', "-"));
        let (output, verdict) = compare(&ws, &[run], &out, &["--baseline", baselines]);
        let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
        assert_eq!(output.status.code(), Some(1), "{name}: {stdout}{}", stderr(&output));
        assert_eq!(verdict["regressed"], true, "{name}");
        assert!(verdict.to_string().contains(reason), "{name}: {verdict}");
        let summary = std::fs::read_to_string(ws.dir.join(&out).join("summary.md")).unwrap();
        assert!(summary.contains("❌") && summary.contains(reason), "{name}: {summary}");
        let junit = std::fs::read_to_string(ws.dir.join(&out).join("junit.xml")).unwrap();
        assert!(junit.contains("<failure") && junit.contains(reason), "{name}: {junit}");

        let lenient_out = format!("{out}-lenient");
        let (lenient, verdict) = compare(&ws, &[run], &lenient_out, &["--baseline", baselines, "--lenient"]);
        assert_eq!(lenient.status.code(), Some(0), "{name}: {}", String::from_utf8_lossy(&lenient.stdout));
        assert_eq!(verdict["lenient"], true);
        assert!(verdict.to_string().contains(reason), "{name}: lenient still reports it: {verdict}");
    }
}

/// With one repetition a side, no time is compared (one note says why, instead of a row of
/// `insufficient` per mode and time metric), and bless warns that the modes have fewer than 5
/// timed frames.
#[test]
fn one_repetition_compares_no_time_and_bless_says_so() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("insufficient");
    ws.manifest("edge", "edge", |_| {});
    let first = run(&ws, "first", "1");
    let blessed = ws.run(&["bless", arg(&first)]);
    assert_eq!(blessed.status.code(), Some(0), "{}", stderr(&blessed));
    assert!(
        stderr(&blessed).contains("4 of 4 modes have fewer than the 5 timed frames"),
        "{}",
        stderr(&blessed)
    );
    let second = run(&ws, "second", "1");
    let (output, verdict) = compare(&ws, &[&second], "gate", &["--fail-on", "all"]);
    assert_eq!(output.status.code(), Some(0), "{}", String::from_utf8_lossy(&output.stdout));
    let times: Vec<&Value> = verdict["checks"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| {
            ["relative_time", "time_vs_reference", "frame_time"].contains(&c["metric"].as_str().unwrap())
        })
        .collect();
    assert!(times.is_empty(), "{times:?}");
    let summary = std::fs::read_to_string(ws.dir.join("gate/summary.md")).unwrap();
    assert!(
        summary.contains(
            "time not compared: the run timed 1 round of each mode, fewer than the 5 a time verdict needs"
        ),
        "{summary}"
    );
    assert!(summary.contains("no time check was made") && !summary.contains("### Insufficient"), "{summary}");

    // Five processes of one round each are five rounds: compared, and decided or insufficient.
    let runs: Vec<PathBuf> = (0..5).map(|i| run(&ws, &format!("process-{i}"), "1")).collect();
    let runs: Vec<&Path> = runs.iter().map(PathBuf::as_path).collect();
    let (_, verdict) = compare(&ws, &runs, "gate-five", &["--fail-on", "all"]);
    let timed = verdict["checks"].as_array().unwrap().iter().filter(|c| c["metric"] == "frame_time").count();
    assert!(timed >= 4, "{verdict}");
}

#[test]
fn bless_refuses_a_run_given_twice_and_a_run_that_did_not_finish() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("bless-refusals");
    ws.manifest("edge", "edge", |_| {});
    let first = run(&ws, "reports", "5");
    let twice = ws.run(&["bless", arg(&first), arg(&first)]);
    assert_eq!(twice.status.code(), Some(2));
    assert!(stderr(&twice).contains("is given twice"), "{}", stderr(&twice));
    assert!(!ws.dir.join("baselines").exists(), "a refused bless writes nothing");
    let record = read_json(&first.join("run.json"));
    let killed = doctored(&ws, "killed", &record, |r| {
        r["status"] = json!("running");
        r["finished_at"] = Value::Null;
    });
    let refused = ws.run(&["bless", arg(&first), arg(&killed)]);
    assert_eq!(refused.status.code(), Some(2));
    assert!(stderr(&refused).contains("did not finish (status `running`)"), "{}", stderr(&refused));
    assert!(!ws.dir.join("baselines").exists(), "a refused bless writes nothing");
    let compared_twice = ws.run(&["compare", arg(&first), "--base-runs", arg(&first), "--lenient"]);
    assert_eq!(compared_twice.status.code(), Some(2));
    assert!(stderr(&compared_twice).contains("is given twice"), "{}", stderr(&compared_twice));
}

/// A blessed run's record with adaptive-2x2's times scaled so that its pass of under a third of
/// the frame is checked on its own (at 64×48 a pass takes tenths of a millisecond, too short to
/// be), and that pass's index.
fn record_with_a_checked_pass(ws: &Workspace) -> (Value, usize) {
    let mut record = read_json(&blessed_run(ws).join("run.json"));
    let (pass, _) = pass_below(&record, "adaptive-2x2", 0.33);
    let pass_ms = mode_mut(&mut record, "adaptive-2x2")["passes"][pass]["ms"]["median"].as_f64().unwrap();
    scale_mode(&mut record, "adaptive-2x2", (2.0 / pass_ms).max(1.0));
    (record, pass)
}

/// Processes of one build differ a little, all modes together and each mode on its own: process
/// `i` by up to ±2% and ±1.5%, a fixed pattern.
fn process_pattern(record: &mut Value, i: usize) {
    let machine = 1.0 + 0.01 * ((i * 7 % 5) as f64 - 2.0);
    for (k, id) in MODES.split(',').enumerate() {
        scale_mode(record, id, machine * (1.0 + 0.005 * (((i + k) * 3 % 7) as f64 - 3.0)));
    }
}

/// Against six base processes, six head processes of the same build pass with every time
/// check unchanged, and a 25% slowdown of one stalled mode regresses that mode alone; the
/// regression stands when fresh processes find it again (or are too few to decide) and is
/// noisy when they do not. Three
/// processes a side are `insufficient`, never a verdict.
#[test]
fn time_is_gated_against_the_base_build_process_by_process() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("base-build");
    ws.manifest("edge", "edge", |_| {});
    let (record, _) = record_with_a_checked_pass(&ws);
    let process = |folder: String, i: usize, slow: f64| {
        doctored(&ws, &folder, &record, move |r| {
            process_pattern(r, i);
            scale_mode(r, "reference-2x2-stalled", slow);
        })
    };
    let side = |name: &str, count: usize, slow: f64, offset: usize| -> Vec<PathBuf> {
        (0..count).map(|i| process(format!("{name}-{i}"), i + offset, slow)).collect()
    };
    let base = side("base", 6, 1.0, 0);
    let base_args: Vec<&str> = std::iter::once("--base-runs").chain(base.iter().map(|p| arg(p))).collect();
    one_slow_pass_is_caught_where_the_frame_hides_it(&ws, &record, &base_args, &process);

    // A/A: the same build on both sides passes, every time check against the base unchanged.
    let same = side("same", 6, 1.0, 3);
    let same: Vec<&Path> = same.iter().map(PathBuf::as_path).collect();
    let (output, verdict) = compare(&ws, &same, "gate-same", &base_args);
    assert_eq!(output.status.code(), Some(0), "{}", String::from_utf8_lossy(&output.stdout));
    let against_base = outcomes(&verdict, "relative_time", "base");
    assert_eq!(against_base.len(), 4);
    assert!(against_base.iter().all(|(_, o)| *o == "unchanged"), "{against_base:?}");
    assert_eq!(verdict["base_run_ids"].as_array().map(Vec::len), Some(6));
    assert!(verdict["notes"].to_string().contains("base build's processes on this machine decide"));

    // 25% more time in one stalled mode: caught against the base, the others unchanged.
    let slow = side("slow", 6, 1.25, 3);
    let slow: Vec<&Path> = slow.iter().map(PathBuf::as_path).collect();
    let (output, verdict) = compare(&ws, &slow, "gate-slow", &base_args);
    assert_eq!(output.status.code(), Some(1), "{}", String::from_utf8_lossy(&output.stdout));
    for (mode, outcome) in outcomes(&verdict, "relative_time", "base") {
        let expected = if mode == "reference-2x2-stalled" { "regressed" } else { "unchanged" };
        assert_eq!(outcome, expected, "{mode}");
    }
    let frame = outcomes(&verdict, "frame_time", "base");
    assert!(frame.contains(&("reference-2x2-stalled", "regressed")), "{frame:?}");
    // The whole frame slower, every pass alike: no pass of it is called slower on its own
    // (an absolute pass time would call every one of them so).
    let passes: Vec<&Value> = verdict["checks"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["metric"].as_str().unwrap().starts_with("pass_time:"))
        .collect();
    assert!(!passes.is_empty() && passes.iter().all(|c| c["outcome"] != "regressed"), "{passes:?}");
    // Time against the committed baseline is reported, not gated, when the base decides.
    let gated_baseline_times = verdict["checks"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["against"] == "baseline" && c["metric"] == "relative_time" && c["gated"] == true)
        .count();
    assert_eq!(gated_baseline_times, 0);
    // The slower scene is named for measuring again, in verdict.json and in to-confirm.txt.
    let manifest = record["scenes"][0]["manifest"].as_str().unwrap();
    assert_eq!(verdict["to_confirm"], json!([manifest]));
    let list = ws.dir.join("gate-slow/to-confirm.txt");
    assert_eq!(std::fs::read_to_string(&list).unwrap(), format!("{manifest}\n"));

    // Fresh processes that find the slowdown again keep it a regression; fresh processes that
    // do not turn it noisy, and the gate passes. Either way nothing is left to confirm.
    let base_again = side("base-again", 6, 1.0, 5);
    let confirmed = |folder: &str, head: &[PathBuf]| {
        let mut args = base_args.clone();
        args.push("--confirm-runs");
        args.extend(head.iter().map(|p| arg(p)));
        args.push("--confirm-base-runs");
        args.extend(base_again.iter().map(|p| arg(p)));
        compare(&ws, &slow, folder, &args)
    };
    let stalled = |verdict: &Value| -> Value {
        let checks = verdict["checks"].as_array().unwrap();
        let found = checks.iter().find(|c| {
            c["mode"] == "reference-2x2-stalled" && c["metric"] == "relative_time" && c["against"] == "base"
        });
        found.unwrap().clone()
    };
    let (output, verdict) = confirmed("gate-slow", &side("slow-again", 6, 1.25, 7));
    assert_eq!(output.status.code(), Some(1), "{}", String::from_utf8_lossy(&output.stdout));
    let check = stalled(&verdict);
    assert_eq!(check["outcome"], "regressed");
    assert!(
        check["detail"]
            .as_str()
            .unwrap()
            .contains("; found again with fresh processes: first and fresh together "),
        "{check}"
    );
    assert_eq!(verdict["confirm_run_ids"].as_array().map(Vec::len), Some(6));
    assert!(verdict.get("to_confirm").is_none(), "{}", verdict["to_confirm"]);
    assert!(!list.exists(), "an earlier compare's list outlived it");
    let (output, verdict) = confirmed("gate-unconfirmed", &side("same-again", 6, 1.0, 7));
    assert_eq!(output.status.code(), Some(0), "{}", String::from_utf8_lossy(&output.stdout));
    let check = stalled(&verdict);
    assert_eq!(check["outcome"], "noisy");
    assert!(
        check["detail"]
            .as_str()
            .unwrap()
            .contains("; not found again with fresh processes: first and fresh together "),
        "{check}"
    );
    let others = outcomes(&verdict, "relative_time", "base");
    assert!(others.iter().filter(|(m, _)| *m != "reference-2x2-stalled").all(|(_, o)| *o == "unchanged"));
    // Too few fresh processes to decide leave the regression standing.
    let (output, verdict) = confirmed("gate-few-again", &side("few-again", 3, 1.0, 7));
    assert_eq!(output.status.code(), Some(1), "{}", String::from_utf8_lossy(&output.stdout));
    assert!(
        stalled(&verdict)["detail"]
            .as_str()
            .unwrap()
            .contains("; not decided again by the 3 fresh processes of the run and 6 of the base")
    );
    // A first process given again as a fresh one is refused: it is no new evidence.
    let (output, _) = confirmed("gate-reused", &[slow[0].to_path_buf()]);
    assert_eq!(output.status.code(), Some(2));
    assert!(stderr(&output).contains("is given twice"), "{}", stderr(&output));

    // Three processes a side cannot reach the confidence: insufficient, never a verdict.
    let (output, verdict) =
        compare(&ws, &slow[..3], "gate-few", &["--base-runs", arg(&base[0]), arg(&base[1]), arg(&base[2])]);
    assert_eq!(output.status.code(), Some(0), "{}", String::from_utf8_lossy(&output.stdout));
    let few = outcomes(&verdict, "relative_time", "base");
    assert!(few.iter().all(|(_, o)| *o == "insufficient"), "{few:?}");
    // And the headline says that no time was gated, not that time passed.
    let summary = std::fs::read_to_string(ws.dir.join("gate-few").join("summary.md")).unwrap();
    let headline = summary.lines().next().unwrap();
    assert!(headline.ends_with("— time not gated"), "no time check could decide: {headline}");
    assert!(summary.contains("but no time check had the evidence to decide"), "{summary}");
}

/// A pass a quarter slower in both scenes of a run: one check pooled over the scenes (scene `*`)
/// decides it, not each scene's (a pass that runs in two scenes or more is decided pooled); it
/// regresses, the summary gives its reach on a line of its own, and both scenes are named to be
/// measured again; fresh processes that find it again keep it regressed, with the processes
/// together and the fresh estimate in its detail.
#[test]
fn a_pass_slower_in_every_scene_is_also_decided_pooled_over_the_scenes() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("pooled");
    ws.manifest("edge", "edge", |_| {});
    let (mut record, pass) = record_with_a_checked_pass(&ws);
    let name = mode_mut(&mut record, "adaptive-2x2")["passes"][pass]["name"].as_str().unwrap().to_string();
    // Process `i` of a side: the one scene with a fixed pattern of machine and mode speeds, and
    // a second scene, the first's record under another name, with another pattern.
    let process = |folder: String, i: usize, slow: f64| {
        let pattern = |r: &mut Value, i: usize| {
            process_pattern(r, i);
            slow_pass(r, "adaptive-2x2", pass, slow);
        };
        doctored(&ws, &folder, &record, move |r| {
            let mut second = r.clone();
            pattern(r, i);
            pattern(&mut second, i + 2);
            let mut scene = second["scenes"][0].clone();
            scene["name"] = json!("edge-again");
            scene["manifest"] = json!("scenes/edge-again.json");
            r["scenes"].as_array_mut().unwrap().push(scene);
        })
    };
    let side = |name: &str, slow: f64, offset: usize| -> Vec<PathBuf> {
        (0..4).map(|i| process(format!("{name}-{i}"), i + offset, slow)).collect()
    };
    let base = side("base", 1.0, 0);
    let base_args: Vec<&str> = std::iter::once("--base-runs").chain(base.iter().map(|p| arg(p))).collect();
    let slow = side("slow", 1.25, 3);
    let slow: Vec<&Path> = slow.iter().map(PathBuf::as_path).collect();
    let (output, verdict) = compare(&ws, &slow, "gate-slow", &base_args);
    assert_eq!(output.status.code(), Some(1), "{}", String::from_utf8_lossy(&output.stdout));
    let metric = format!("pass_time:{name}");
    let pass_checks = |verdict: &Value| -> Vec<(String, String)> {
        let checks = verdict["checks"].as_array().unwrap().iter();
        let mine = checks
            .filter(|c| c["against"] == "base" && c["mode"] == "adaptive-2x2" && c["metric"] == *metric);
        mine.map(|c| (c["scene"].as_str().unwrap().into(), c["outcome"].as_str().unwrap().into())).collect()
    };
    let checks = pass_checks(&verdict);
    assert_eq!(checks, [("*".to_string(), "regressed".to_string())], "the pool alone decides");
    let pooled_of = |verdict: &Value| -> Value {
        let checks = verdict["checks"].as_array().unwrap();
        // Other modes have a pass of that name too (every mode has a gbuffer): the slowed mode's.
        let slowed = |c: &&Value| c["scene"] == "*" && c["mode"] == "adaptive-2x2" && c["metric"] == *metric;
        checks.iter().find(slowed).unwrap().clone()
    };
    let pooled = pooled_of(&verdict);
    assert!(pooled["detail"].as_str().unwrap().contains("geometric mean over 2 scenes"), "{pooled}");
    assert_eq!(verdict["to_confirm"], json!([record["scenes"][0]["manifest"], "scenes/edge-again.json"]));
    let summary = std::fs::read_to_string(ws.dir.join("gate-slow/summary.md")).unwrap();
    assert!(
        summary.contains(&format!("- pass {name} pooled over the scenes, against the base build: +")),
        "{summary}"
    );

    // Fresh processes of both builds: the pooled regression found again stands; not found
    // again, it is noisy and the gate passes.
    let confirmed = |folder: &str, slow_again: f64| {
        let head = side(&format!("{folder}-head"), slow_again, 5);
        let fresh_base = side(&format!("{folder}-base"), 1.0, 6);
        let mut args = base_args.clone();
        args.push("--confirm-runs");
        args.extend(head.iter().map(|p| arg(p)));
        args.push("--confirm-base-runs");
        args.extend(fresh_base.iter().map(|p| arg(p)));
        compare(&ws, &slow, folder, &args)
    };
    let (output, verdict) = confirmed("found", 1.25);
    assert_eq!(output.status.code(), Some(1), "{}", String::from_utf8_lossy(&output.stdout));
    let pooled = pooled_of(&verdict);
    assert_eq!(pooled["outcome"], "regressed", "{pooled}");
    let detail = pooled["detail"].as_str().unwrap();
    assert!(detail.contains("; found again with fresh processes: first and fresh together "), "{detail}");
    assert!(detail.contains("over 8 processes of the base and 8 of the run); the fresh alone +"), "{detail}");
    let (output, verdict) = confirmed("not-found", 1.0);
    assert_eq!(output.status.code(), Some(0), "{}", String::from_utf8_lossy(&output.stdout));
    assert_eq!(pooled_of(&verdict)["outcome"], "noisy");
    assert!(pass_checks(&verdict).iter().all(|(_, outcome)| outcome != "regressed"));
}

/// A quarter more time in one pass of adaptive-2x2 that is under a third of its frame moves the
/// frame by less than the frame's threshold: its frame and relative checks stay quiet, its pass
/// check regresses, and no other pass's check does.
fn one_slow_pass_is_caught_where_the_frame_hides_it(
    ws: &Workspace,
    record: &Value,
    base_args: &[&str],
    process: &dyn Fn(String, usize, f64) -> PathBuf,
) {
    let (pass, share) = pass_below(record, "adaptive-2x2", 0.33);
    assert!(share > 0.05, "a pass of {share:.2} of the frame");
    let name = record["scenes"][0]["modes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["mode"] == "adaptive-2x2")
        .unwrap()["passes"][pass]["name"]
        .as_str()
        .unwrap()
        .to_string();
    let slowed: Vec<PathBuf> = (0..6)
        .map(|i| {
            let dir = process(format!("pass-slow-{i}"), i + 3, 1.0);
            let mut run = read_json(&dir.join("run.json"));
            slow_pass(&mut run, "adaptive-2x2", pass, 1.25);
            write_json(&dir.join("run.json"), &run);
            dir
        })
        .collect();
    let slowed: Vec<&Path> = slowed.iter().map(PathBuf::as_path).collect();
    let (output, verdict) = compare(ws, &slowed, "gate-pass-slow", base_args);
    assert_eq!(output.status.code(), Some(1), "{}", String::from_utf8_lossy(&output.stdout));
    let of_mode = |metric: &str| -> Vec<String> {
        let checks = verdict["checks"].as_array().unwrap().iter();
        let mine =
            checks.filter(|c| c["against"] == "base" && c["mode"] == "adaptive-2x2" && c["metric"] == metric);
        mine.map(|c| c["outcome"].as_str().unwrap().to_string()).collect()
    };
    assert_eq!(
        of_mode("frame_time"),
        ["unchanged"],
        "a {:.0}% pass moves the frame {:.1}%",
        share * 100.0,
        share * 25.0
    );
    assert_eq!(of_mode(&format!("pass_time:{name}")), ["regressed"], "{name}");
    // Against the base, the pass alone (the baselines were blessed before the times were scaled:
    // against them time is reported, not gated).
    let regressed: Vec<&Value> = verdict["checks"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["outcome"] == "regressed" && c["against"] == "base")
        .collect();
    assert_eq!(regressed.len(), 1, "{regressed:?}");
}

/// A slowdown fails the gate on the machine that blessed the baseline; from a machine whose ALU
/// probe differs by 30% it is reported, not failed, while a quality drop there still fails.
#[test]
fn time_against_baselines_of_another_machine_is_informational() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("other-machine");
    ws.manifest("edge", "edge", |_| {});
    let measured = blessed_run(&ws);
    let record = read_json(&measured.join("run.json"));
    let machine = &record["platform"]["machine"];
    assert!(
        machine["alu_ns"].as_f64().unwrap() > 0.0 && machine["memory_ns"].as_f64().unwrap() > 0.0,
        "{machine}"
    );
    // The rule is the subject, not lavapipe's noise: five rounds of a 2 ms frame can hold one
    // twice the others, and then no interval tells a doubling. Every mode's rounds are calmed
    // to their medians (±0.5 %) and blessed so, and the doubling is of those.
    let calm = |r: &mut Value| MODES.split(',').for_each(|id| calm_mode(r, id));
    let record = read_json(&doctored(&ws, "calm", &record, calm).join("run.json"));
    assert_eq!(ws.run(&["bless", arg(&ws.dir.join("calm"))]).status.code(), Some(0));
    let slow = doctored(&ws, "slow", &record, |r| scale_mode(r, "reference-2x2-stalled", 2.0));
    // On the machine that blessed the baseline, the slowdown fails the gate.
    let (here, verdict) = compare(&ws, &[&slow], "gate-here", &[]);
    assert_eq!(here.status.code(), Some(1), "{}", String::from_utf8_lossy(&here.stdout));
    assert_eq!(verdict["same_machine"], true);
    // The same run from a machine whose ALU probe is 30% slower: reported, not failed.
    let elsewhere = doctored(&ws, "elsewhere", &record, |r| {
        scale_mode(r, "reference-2x2-stalled", 2.0);
        let alu = r["platform"]["machine"]["alu_ns"].as_f64().unwrap();
        r["platform"]["machine"]["alu_ns"] = json!(alu * 1.3);
    });
    let (there, verdict) = compare(&ws, &[&elsewhere], "gate-there", &[]);
    assert_eq!(there.status.code(), Some(0), "{}", String::from_utf8_lossy(&there.stdout));
    assert_eq!(verdict["same_machine"], false);
    let notes = verdict["notes"].to_string();
    assert!(notes.contains("informational") && notes.contains("ALU probe"), "{notes}");
    let summary = std::fs::read_to_string(ws.dir.join("gate-there/summary.md")).unwrap();
    let headline = summary.lines().next().unwrap();
    assert!(
        headline.starts_with("## aabench gate: ✅ no regression") && headline.ends_with("— time not gated"),
        "{summary}"
    );
    let here_summary = std::fs::read_to_string(ws.dir.join("gate-here/summary.md")).unwrap();
    assert!(!here_summary.contains("time not gated"), "{here_summary}");
    // A probe value no machine measures (an edited run.json) is no match, and says so.
    let edited = doctored(&ws, "edited", &record, |r| {
        scale_mode(r, "reference-2x2-stalled", 2.0);
        r["platform"]["machine"]["alu_ns"] = json!(0.0);
    });
    let (edited, verdict) = compare(&ws, &[&edited], "gate-edited", &[]);
    assert_eq!(edited.status.code(), Some(0), "{}", String::from_utf8_lossy(&edited.stdout));
    assert!(verdict["notes"].to_string().contains("is no measurement"), "{}", verdict["notes"]);
    let check = verdict["checks"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["mode"] == "reference-2x2-stalled" && c["metric"] == "relative_time")
        .unwrap();
    assert_eq!((check["outcome"].as_str(), check["gated"].as_bool()), (Some("regressed"), Some(false)));
    // Quality stays gated there: a doctored PSNR drop fails.
    let worse = doctored(&ws, "worse", &record, |r| {
        let psnr = &mut mode_mut(r, "adaptive-2x2")["vs_ground_truth"]["psnr_db"];
        *psnr = json!(psnr.as_f64().unwrap() - 0.5);
        let alu = r["platform"]["machine"]["alu_ns"].as_f64().unwrap();
        r["platform"]["machine"]["alu_ns"] = json!(alu * 1.3);
    });
    let (worse, _) = compare(&ws, &[&worse], "gate-worse", &[]);
    assert_eq!(worse.status.code(), Some(1), "{}", String::from_utf8_lossy(&worse.stdout));
}

#[test]
fn baselines_of_another_key_judge_a_run_only_where_every_image_is_theirs() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("other-key");
    ws.manifest("edge", "edge", |_| {});
    let measured = blessed_run(&ws);
    let record = read_json(&measured.join("run.json"));
    // The same baselines under another platform key (another Mesa, say).
    let root = ws.dir.join("baselines");
    let key = record["platform"]["key"].as_str().unwrap();
    std::fs::rename(root.join(key), root.join("llvmpipe-mesa-0.0.0-llvm-0.0.0-256-bits-fma-release"))
        .unwrap();
    let (same, verdict) = compare(&ws, &[&measured], "gate-same-bits", &[]);
    assert_eq!(same.status.code(), Some(0), "{}", String::from_utf8_lossy(&same.stdout));
    assert_eq!(verdict["same_platform"], false);
    let notes = verdict["notes"].to_string();
    assert!(notes.contains("every one of the 4 output hashes equals its baseline's"), "{notes}");
    // One image of other bits: the run fails, naming the first (scene, mode) that differs.
    let other = doctored(&ws, "other-bits", &record, |r| {
        mode_mut(r, "reference-2x2")["output_hash"] = json!("0000000000000000");
    });
    let (differs, verdict) = compare(&ws, &[&other], "gate-other-bits", &[]);
    assert_eq!(differs.status.code(), Some(1), "{}", String::from_utf8_lossy(&differs.stdout));
    let failed: Vec<&str> = verdict["checks"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["outcome"] == "failed")
        .filter_map(|c| c["detail"].as_str())
        .collect();
    assert!(
        failed.iter().any(|d| d.contains("no baselines of this run's platform")
            && d.contains("1 of 4 output hashes differ, the first: edge reference-2x2")),
        "{failed:?}"
    );
}

#[test]
fn bless_says_what_it_moved_and_calls_out_the_papers_bits() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("moved");
    ws.manifest("edge", "edge", |_| {});
    let measured = blessed_run(&ws);
    let record = read_json(&measured.join("run.json"));
    // Into the run's folder, for the commit message: nothing beside the baselines to churn.
    let written = measured.join("bless.md");
    assert!(std::fs::read_to_string(&written).unwrap().contains("- edge: a new scene (4 modes)"));
    let key = ws.dir.join("baselines").join(record["platform"]["key"].as_str().unwrap());
    let beside: Vec<_> = std::fs::read_dir(&key).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(beside, ["quick"], "only the tier's folder beside the baselines");
    // The same run blessed again moves nothing.
    let again = ws.run(&["bless", arg(&measured)]);
    assert_eq!(again.status.code(), Some(0), "{}", stderr(&again));
    let said = String::from_utf8_lossy(&again.stdout).into_owned();
    assert!(said.contains("Nothing moved: every one of the 4 output hashes"), "{said}");
    assert!(std::fs::read_to_string(&written).unwrap().contains("Nothing moved"));
    // The paper's bits and one PSNR moved: the bless needs a reason and lists exactly those.
    let moved = doctored(&ws, "moved", &record, |r| {
        let mode = mode_mut(r, "adaptive-2x2");
        mode["output_hash"] = json!("0123456789abcdef");
        let psnr = &mut mode["vs_ground_truth"]["psnr_db"];
        *psnr = json!(psnr.as_f64().unwrap() - 0.5);
    });
    let output = ws.run(&["bless", arg(&moved), "--why", "the test moves them"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let said = String::from_utf8_lossy(&output.stdout).into_owned();
    assert!(
        said.contains("Output hashes moved in 1 of 4 modes; the paper's mode: **edge adaptive-2x2**"),
        "{said}"
    );
    let rows: Vec<&str> = said.lines().filter(|line| line.starts_with("| edge |")).collect();
    assert_eq!(rows.len(), 2, "the hash and the PSNR, nothing else: {said}");
    assert!(
        rows[0].contains("**adaptive-2x2** (the paper's) | ") && rows[0].ends_with("→ 0123456789abcdef |")
    );
    assert!(rows[1].starts_with("| edge | adaptive-2x2 | psnr_vs_truth | "), "{}", rows[1]);
    let file = std::fs::read_to_string(moved.join("bless.md")).unwrap();
    assert!(file.starts_with("# What the bless moved") && said.contains(&file), "{file}");
}

#[test]
fn the_truth_note_speaks_only_when_the_truth_image_changed() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("truth-note");
    ws.manifest("edge", "edge", |_| {});
    let measured = blessed_run(&ws);
    let record = read_json(&measured.join("run.json"));
    assert_eq!(record["scenes"][0]["truth"]["image_hash"].as_str().map(str::len), Some(16));
    // A new key (any source edit does that), the same image: no note.
    let rekeyed =
        doctored(&ws, "rekeyed", &record, |r| r["scenes"][0]["truth"]["key"] = json!("0".repeat(64)));
    let (_, verdict) = compare(&ws, &[&rekeyed], "gate-rekeyed", &[]);
    assert!(!verdict["notes"].to_string().contains("ground truth"), "{}", verdict["notes"]);
    let moved =
        doctored(&ws, "moved", &record, |r| r["scenes"][0]["truth"]["image_hash"] = json!("0".repeat(16)));
    let (_, verdict) = compare(&ws, &[&moved], "gate-moved", &[]);
    assert!(verdict["notes"].to_string().contains("ground truth's image changed"), "{}", verdict["notes"]);
}

/// The `run_ids` of every baseline file in the tier folder, and whether any
/// temporary is inside it.
fn baseline_state(ws: &Workspace) -> (Vec<String>, bool) {
    let keys: Vec<PathBuf> = std::fs::read_dir(ws.dir.join("baselines"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| !p.to_string_lossy().contains(".tmp-"))
        .collect();
    let tier = keys[0].join("quick");
    let mut states = Vec::new();
    let mut temporary = false;
    for entry in std::fs::read_dir(&tier).unwrap() {
        let path = entry.unwrap().path();
        if path.to_string_lossy().contains(".tmp-") {
            temporary = true;
            continue;
        }
        states.push(read_json(&path)["blessed"]["run_ids"].to_string());
    }
    (states, temporary)
}

#[test]
fn a_killed_bless_leaves_all_old_or_all_new_baselines() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("bless-kill");
    for (name, generator) in [("a-edge", "edge"), ("b-plane", "plane"), ("c-thin", "thin")] {
        ws.manifest(name, generator, |_| {});
    }
    let old = run(&ws, "old", "5");
    let new = run(&ws, "new", "5");
    assert_eq!(ws.run(&["bless", arg(&old)]).status.code(), Some(0));
    let (blessed, _) = baseline_state(&ws);
    assert_eq!(blessed.len(), 3);
    // Kills at several points of a bless, from before it reads the runs to after it is done.
    for delay_ms in (0..40).step_by(3) {
        let mut child =
            ws.command(&["bless", arg(&new)]).stderr(Stdio::null()).stdout(Stdio::null()).spawn().unwrap();
        std::thread::sleep(std::time::Duration::from_millis(delay_ms));
        let _ = child.kill();
        let _ = child.wait();
        let (states, temporary) = baseline_state(&ws);
        assert!(!temporary, "a temporary inside the baselines after a kill at {delay_ms} ms");
        assert_eq!(states.len(), 3, "{states:?}");
        assert!(states.iter().all(|s| *s == states[0]), "a mix of old and new at {delay_ms} ms: {states:?}");
        // Back to the old baselines for the next kill.
        assert_eq!(ws.run(&["bless", arg(&old)]).status.code(), Some(0));
    }
    // A staging folder left by a killed bless goes with the next bless once its owner is gone.
    let key = std::fs::read_dir(ws.dir.join("baselines")).unwrap().next().unwrap().unwrap().path();
    let staging = key.join("quick.tmp-4294967294");
    std::fs::create_dir_all(&staging).unwrap();
    std::fs::write(staging.join("a-edge.json"), "{}").unwrap();
    let an_hour_ago = std::time::SystemTime::now() - std::time::Duration::from_secs(3600);
    std::fs::File::open(&staging).unwrap().set_modified(an_hour_ago).unwrap();
    let output = ws.run(&["bless", arg(&new)]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    assert!(stderr(&output).contains("removed 1 temporary"), "{}", stderr(&output));
    assert!(!staging.exists());
}

#[test]
fn fifos_in_place_of_runs_baselines_and_history_are_refused_at_once() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("fifos");
    ws.manifest("edge", "edge", |_| {});
    let measured = blessed_run(&ws);
    let fifo = |path: &Path| {
        let _ = std::fs::remove_file(path);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        assert!(Command::new("mkfifo").arg(path).status().unwrap().success());
    };
    let timed = |args: &[&str]| {
        let start = std::time::Instant::now();
        let output = ws.run(args);
        assert!(start.elapsed() < std::time::Duration::from_secs(1), "{args:?} took {:?}", start.elapsed());
        output
    };
    // A FIFO named run.json.
    fifo(&ws.dir.join("piped/run.json"));
    let output = timed(&["compare", "piped", "--out", "gate"]);
    assert_eq!(output.status.code(), Some(2));
    assert!(
        stderr(&output).contains("piped/run.json: cannot read: not a regular file"),
        "{}",
        stderr(&output)
    );
    // A FIFO as a baseline: compare and bless both refuse it by name.
    let key = std::fs::read_dir(ws.dir.join("baselines")).unwrap().next().unwrap().unwrap().path();
    let baseline = key.join("quick/edge.json");
    let blessed = std::fs::read(&baseline).unwrap();
    fifo(&baseline);
    let output = timed(&["compare", arg(&measured), "--out", "gate"]);
    assert_eq!(output.status.code(), Some(2));
    assert!(stderr(&output).contains("edge.json: cannot read: not a regular file"), "{}", stderr(&output));
    let output = timed(&["bless", arg(&measured)]);
    assert_eq!(output.status.code(), Some(2));
    assert!(stderr(&output).contains("not a regular file"), "{}", stderr(&output));
    std::fs::remove_file(&baseline).unwrap();
    std::fs::write(&baseline, blessed).unwrap();
    // A FIFO in the history folder: skipped with a warning, the report written.
    std::fs::create_dir_all(ws.dir.join("history")).unwrap();
    std::fs::copy(measured.join("run.json"), ws.dir.join("history/earlier.json")).unwrap();
    fifo(&ws.dir.join("history/stray.json"));
    let output = timed(&["report", arg(&measured), "--history", "history"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    assert!(stderr(&output).contains("stray.json: cannot read: not a regular file"), "{}", stderr(&output));
}
