//! The `aabench` binary as users and CI run it: real processes, real exit codes, real files.
//!
//! A run writes its record and images, renders and caches the ground truth, and records every
//! frame's NaN, Inf and sample-count checks. A broken manifest fails alone with exit 3; no
//! Vulkan adapter exits 2 with one line naming `mesa-vulkan-drivers`; bad arguments exit 2
//! before any work; `gen-scenes` regenerates only stale files; Ctrl-C (a real SIGINT) keeps
//! what was measured (a signal while a path's FLIP and JOD are measured leaves its scene
//! `interrupted`, not `ok`) and `kill -9` leaves the scenes that finished. A frame too small for
//! JOD says so in the record and the gate.

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::{Value, json};

use crate::support;

use support::*;

#[test]
fn a_run_writes_its_record_and_images_and_exits_zero() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("ok");
    ws.manifest("edge", "edge", |_| {});
    let modes = "deferred-1x1,reference-2x2,reference-2x2-stalled,adaptive-2x2";
    let output = ws.run(&["run", "--modes", modes, "--repetitions", "2"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));

    let record = ws.record();
    assert_eq!(record["schema"], "aabench.run/2");
    assert_eq!(record["status"], "ok");
    assert_eq!(record["tier"], "quick");
    assert!(record["platform"]["key"].as_str().unwrap().contains("llvmpipe"), "{}", record["platform"]);
    let scene = &record["scenes"][0];
    assert_eq!(scene["status"], "ok");
    let truth = &scene["truth"];
    assert_eq!((truth["id"].as_str(), truth["samples_per_pixel"].as_u64()), (Some("truth-8x8"), Some(64)));
    assert_eq!((truth["cached"].as_bool(), truth["error"].is_null()), (Some(false), true), "{truth}");
    assert!(ws.run_dir().join(truth["image"].as_str().unwrap()).exists());
    let cached: Vec<_> = std::fs::read_dir(ws.dir.join("scenes/cache/truth")).unwrap().collect();
    assert_eq!(cached.len(), 1, "the truth is cached beside the manifest");
    assert_eq!(scene["resolution"], json!([64, 48]));
    for id in modes.split(',') {
        let m = mode(scene, id);
        assert_eq!(m["status"], "ok", "{id}: {}", m["error"]);
        assert_eq!(m["frame_ms"]["samples"].as_array().unwrap().len(), 2, "{id}");
        assert_eq!(m["stopped"], "count", "{id}");
        assert!(m["frame_ms"]["median"].as_f64().unwrap() > 0.0);
        assert_eq!(m["deterministic"], true, "{id}");
        // One warm-up and two timed frames, each checked for NaN, Inf and sample counts.
        assert_eq!(m["checks"], json!({"frames": 3, "nan": 0, "inf": 0, "counts_out_of_range": 0}), "{id}");
        assert_eq!(m["passes"][0]["name"], "gbuffer", "{id}");
        let png = ws.display(m);
        assert_eq!((png.width(), png.height()), (64, 48));
        let exr = ws.run_dir().join(m["images"]["hdr"].as_str().unwrap());
        exr::prelude::read_first_rgba_layer_from_file(&exr, |_, _| (), |_, _, _: (f32, f32, f32, f32)| ())
            .unwrap();
    }
    console_says_what_it_found(&stderr(&output));
    let hash = |id: &str| mode(scene, id)["output_hash"].as_str().map(str::to_owned);
    assert_eq!(hash("reference-2x2").map(|h| h.len()), Some(16), "a 64-bit hex fingerprint");
    assert_eq!(hash("reference-2x2"), hash("reference-2x2-stalled"), "the stall must not change the image");
    assert_ne!(hash("reference-2x2"), hash("deferred-1x1"));
    let deferred = mode(scene, "deferred-1x1");
    assert!(deferred["vs_ground_truth"]["psnr_db"].as_f64().unwrap() < 40.0, "the edge aliases at 1×1");
    assert_eq!(deferred["ratio_to_deferred"], 1.0);
    let reference = mode(scene, "reference-2x2")["vs_ground_truth"]["psnr_db"].as_f64().unwrap();
    assert!(
        reference > deferred["vs_ground_truth"]["psnr_db"].as_f64().unwrap(),
        "2×2 is nearer the 8×8 truth"
    );
    let adaptive = mode(scene, "adaptive-2x2");
    assert_eq!(adaptive["vs_reference"]["against"], "reference-2x2");
    let samples = &adaptive["samples"];
    assert!((25.0..60.0).contains(&samples["shaded_percent"].as_f64().unwrap()), "{samples}");
    assert_eq!(samples["histogram"].as_array().unwrap().len(), 4);
    assert!(adaptive["adaptive"]["speedup"].as_f64().unwrap() > 0.0);
    // The per-sample cost model: extra samples counted as the histogram says (n − 1 per pixel,
    // plus one for each full pixel that shades S again: none in a scene without textures, where
    // S is the reference's first sample), their cost and the reference's, the list's and
    // gather's shares of the frame.
    let cost = &adaptive["adaptive"]["samples"];
    let histogram: Vec<u64> =
        samples["histogram"].as_array().unwrap().iter().map(|n| n.as_u64().unwrap()).collect();
    assert_eq!(scene["textures"], 0);
    assert!(histogram[3] > 0 && samples["full_pixels"].as_u64() == Some(histogram[3]), "{samples}");
    assert_eq!(samples["reshaded"], 0, "{samples}");
    let extra: u64 = histogram.iter().enumerate().map(|(i, n)| n * i as u64).sum::<u64>();
    assert_eq!(cost["extra_samples"].as_u64(), Some(extra), "{cost}");
    let ratio = cost["extra_sample_ns"].as_f64().unwrap() / cost["reference_sample_ns"].as_f64().unwrap();
    assert!((ratio - cost["extra_sample_cost"].as_f64().unwrap()).abs() < 1e-9 && ratio > 0.0, "{cost}");
    for share in ["evaluate_share", "gather_share"] {
        assert!((0.0..1.0).contains(&cost[share].as_f64().unwrap()), "{share}: {cost}");
    }
    assert!(ws.run_dir().join(adaptive["images"]["samples"].as_str().unwrap()).exists());
    assert!(ws.run_dir().join(adaptive["images"]["difference"].as_str().unwrap()).exists());
    // Perceptual error against the truth, ranked as PSNR ranks the edge's aliasing, and
    // FLIP's error map beside the difference heatmap.
    let perceptual = |id: &str, metric: &str| mode(scene, id)["vs_ground_truth"][metric].as_f64().unwrap();
    assert!(perceptual("reference-2x2", "flip") < perceptual("deferred-1x1", "flip"));
    assert!(perceptual("reference-2x2", "ssim") > perceptual("deferred-1x1", "ssim"));
    assert!(perceptual("deferred-1x1", "flip") > 0.0 && perceptual("deferred-1x1", "ssim") < 1.0);
    assert!(ws.run_dir().join(adaptive["images"]["flip"].as_str().unwrap()).exists());
    assert!(adaptive["vs_reference"].get("flip").is_none(), "perceptual metrics are taken against the truth");
    // What the work after the timed rounds cost: its wall time, and the CPU time of comparing
    // with the truth within it.
    let seconds = |field: &str| scene[field].as_f64().unwrap_or_else(|| panic!("{field}: {scene}"));
    assert!(seconds("images_s") > 0.0 && seconds("perceptual_s") > 0.0);
    let graph = &adaptive["graph"];
    assert_eq!(
        graph["passes"],
        json!([
            "gbuffer",
            "shade_first",
            "evaluate",
            "compact",
            "shade_extra",
            "gather",
            "tonemap",
            "display"
        ])
    );
    assert_eq!(graph["allocated_bytes"], graph["lower_bound_bytes"], "{graph}");
    assert!(
        graph["allocations"].as_array().unwrap().iter().any(|a| a["holds"] == json!(["evaluate.counts"]))
    );
    assert_eq!(
        mode(scene, "deferred-1x1")["graph"]["passes"],
        json!(["gbuffer", "shade", "tonemap", "display"])
    );
}

/// The console of the run above: the scene's table names it, fits 120 columns and shows JOD
/// beside PSNR; the run closes with its summary, the scene's answer and the next commands.
fn console_says_what_it_found(log: &str) {
    let lines: Vec<&str> = log.lines().collect();
    let header =
        lines.iter().position(|l| l.starts_with("  mode ")).unwrap_or_else(|| panic!("no table: {log}"));
    assert!(lines[header - 2].starts_with("[edge] 64×48 · no camera path"), "{log}");
    assert!(lines[header].contains(" PSNR ") && lines[header].contains(" JOD "), "{}", lines[header]);
    for row in &lines[header..header + 6] {
        assert!(row.chars().count() <= 120, "{} columns: {row}", row.chars().count());
    }
    let summary = lines
        .iter()
        .position(|l| l.contains("1 scene(s) ok, 0 failed, 0 interrupted, 0 not run"))
        .unwrap_or_else(|| panic!("no summary: {log}"));
    let tail = &lines[summary..];
    let answer = tail.iter().find(|l| l.starts_with("  edge")).unwrap_or_else(|| panic!("{log}"));
    assert!(answer.contains("still") && answer.contains(" JOD, "), "{answer}");
    assert!(tail.iter().any(|l| l.contains("aabench report ")), "{log}");
    assert!(tail.last().is_some_and(|l| l.contains("aabench compare ")), "the last line: {log}");
}

#[test]
fn graph_prints_a_modes_passes_ports_and_allocations() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("graph");
    let shadowed = ws.manifest("room", "shadow-room", |m| {
        m["lights"][0]["casts_shadows"] = json!(true);
        m["lights"][0]["shadow"] = json!({ "resolution": 64 });
    });
    let path = shadowed.to_str().unwrap();
    let output = ws.run(&["graph", path, "--mode", "reference-2x2"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let text = String::from_utf8(output.stdout).unwrap();
    for needle in [
        "room reference-2x2 (quick tier, 64×48; textured, 1 shadow cube(s) of 64²)",
        " 1. shadow",
        " 2. gbuffer",
        "reads  shadow_cubes",
        "Depth32Float 64×64×6",
        "writes color              Attachment",
        "Rgba16Float 128×96",
        "[retained: Display]",
        "lower bound",
    ] {
        assert!(text.contains(needle), "{needle:?} missing in\n{text}");
    }
    let dot = ws.run(&["graph", path, "--mode", "adaptive-2x2", "--dot"]);
    let dot = String::from_utf8(dot.stdout).unwrap();
    assert!(
        dot.starts_with("digraph frame {") && dot.contains("shade_extra") && dot.trim_end().ends_with('}'),
        "{dot}"
    );
    // Without the shadow light there is no shadow pass.
    let plain = ws.manifest("plain", "shadow-room", |_| {});
    let output = ws.run(&["graph", plain.to_str().unwrap(), "--mode", "deferred-1x1"]);
    let text = String::from_utf8(output.stdout).unwrap();
    assert!(text.contains("no shadow-casting light") && !text.contains("shadow_cubes"), "{text}");
    let bad = ws.run(&["graph", path, "--mode", "fancy-2x2"]);
    assert_eq!(bad.status.code(), Some(2));
    assert!(stderr(&bad).contains("--mode"), "{}", stderr(&bad));
}

/// `aabench modes` lists the groups and says how the other adaptive ids are made, so that an
/// id no group holds is still one the listing explains; `graph` takes its example and names it
/// in full.
#[test]
fn modes_lists_the_groups_and_how_the_other_adaptive_ids_are_made() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("modes");
    let output = ws.run(&["modes"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let text = String::from_utf8(output.stdout).unwrap();
    assert!(text.contains("stable:\n  adaptive-2x2-stable\n"), "{text}");
    let example = text.rsplit("e.g. ").next().unwrap().trim();
    assert_eq!(example, "adaptive-2x2-shading-area-stable", "{text}");
    let plane = ws.manifest("plane", "plane", |_| {});
    let graph = ws.run(&["graph", plane.to_str().unwrap(), "--mode", example]);
    assert_eq!(graph.status.code(), Some(0), "{}", stderr(&graph));
    let heading = String::from_utf8(graph.stdout).unwrap();
    assert!(heading.starts_with(&format!("plane {example} (quick tier")), "{heading}");
    // With a tier: its modes, one id per line; the gate's timing processes time a subset.
    let lines = |args: &[&str]| -> Vec<String> {
        let output = ws.run(args);
        assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
        String::from_utf8(output.stdout).unwrap().lines().map(str::to_string).collect()
    };
    let quick = lines(&["modes", "--tier", "quick"]);
    let timed = lines(&["modes", "--tier", "quick", "--timed-by-gate"]);
    assert_eq!(quick.len(), 29, "{quick:?}");
    assert!(timed.iter().all(|id| quick.contains(id) && text.contains(&format!("  {id}\n"))), "{timed:?}");
    assert!(
        timed.contains(&"deferred-1x1-stalled".into()) && !timed.contains(&"adaptive-2x2-stalled".into())
    );
    // A variant is timed at its largest size alone.
    assert!(timed.contains(&"adaptive-4x4-area".into()) && !timed.contains(&"adaptive-3x3-area".into()));
    assert_eq!(ws.run(&["modes", "--timed-by-gate"]).status.code(), Some(2), "--timed-by-gate needs --tier");
}

#[test]
fn a_broken_manifest_fails_alone_and_the_run_exits_three() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("broken");
    ws.manifest("a-edge", "edge", |_| {});
    ws.manifest("b-broken", "plane", |m| m["lights"][0]["range"] = json!(-3));
    let output = ws.run(&["run", "--modes", "deferred-1x1"]);
    assert_eq!(output.status.code(), Some(3), "{}", stderr(&output));
    let summary = stderr(&output);
    assert!(summary.contains("1 scene(s) ok, 1 failed"), "{summary}");
    assert!(summary.contains("  b-broken  failed: "), "the failed scene's line: {summary}");

    let record = ws.record();
    assert_eq!(record["status"], "failed");
    assert_eq!(record["scenes"][0]["status"], "ok");
    let broken = &record["scenes"][1];
    assert_eq!(broken["status"], "failed");
    let error = broken["error"].as_str().unwrap();
    assert!(error.contains("b-broken.json: lights[0].range: -3 must be finite and > 0"), "{error}");
}

#[test]
fn no_vulkan_adapter_exits_two_with_one_line_on_how_to_install_one() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("noadapter");
    ws.manifest("edge", "edge", |_| {});
    let missing = ws.dir.join("no-such-icd.json");
    let output = ws
        .command(&["run"])
        .env("VK_ICD_FILENAMES", &missing)
        .env("VK_DRIVER_FILES", &missing)
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(2));
    let text = stderr(&output);
    let lines: Vec<&str> = text.lines().filter(|l| l.starts_with("aabench:")).collect();
    assert_eq!(lines.len(), 1, "{text}");
    assert!(
        lines[0].contains("no Vulkan adapter found") && lines[0].contains("mesa-vulkan-drivers"),
        "{text}"
    );
}

#[test]
fn a_ten_bit_pq_scene_writes_16_bit_pngs_and_reuses_its_cached_truth() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("ten-bit");
    ws.manifest("edge", "edge", |j| {
        j["display"] = json!({"transfer": "pq", "peak_nits": 600, "bits": 10, "dither": "asymmetric"});
    });
    let modes = "deferred-1x1,fxaa";
    for cached in [false, true] {
        // One run folder at a time; the truth cache stays beside the manifest.
        let _ = std::fs::remove_dir_all(ws.dir.join("reports"));
        let output = ws.run(&["run", "--modes", modes, "--repetitions", "2"]);
        assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
        let record = ws.record();
        let scene = &record["scenes"][0];
        assert_eq!(scene["truth"]["cached"], cached, "{}", scene["truth"]);
        let truth = image::open(ws.run_dir().join(scene["truth"]["image"].as_str().unwrap())).unwrap();
        assert_eq!(truth.color(), image::ColorType::Rgba16, "a 10-bit truth is a 16-bit PNG");
        for id in modes.split(',') {
            let m = mode(scene, id);
            assert_eq!(m["status"], "ok", "{id}: {}", m["error"]);
            let png = ws.display(m);
            let samples = png.to_rgba16().into_raw();
            assert_eq!(png.color(), image::ColorType::Rgba16, "{id}");
            // Each sample is a 10-bit code with its top bits repeated below it.
            assert!(samples.iter().all(|&v| v & 0x3f == v >> 10), "{id}: not 10-bit codes");
            // Some codes lie between those an 8-bit image has (code → 8 bits → back moves them).
            let eight_bit =
                |c: u16| ((f64::from(c) * 255.0 / 1023.0).round() * 1023.0 / 255.0).round() as u16;
            assert!(
                samples.iter().any(|&v| eight_bit(v >> 6) != v >> 6),
                "{id}: only codes that 8 bits have"
            );
        }
        let fxaa = mode(scene, "fxaa");
        assert_eq!(fxaa["vs_reference"]["against"], "deferred-1x1");
        assert_eq!(fxaa["passes"].as_array().unwrap().last().unwrap()["name"], "fxaa");
        assert!(fxaa["vs_ground_truth"]["psnr_db"].as_f64().unwrap() > 0.0);
    }
}

/// Each bad argument, `--warmup 4294967295` and negative numbers included, exits 2 with its
/// reason, and nothing is written.
#[test]
fn bad_arguments_exit_two_before_any_work() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("args");
    ws.manifest("edge", "edge", |_| {});
    for (args, reason) in [
        (vec!["run", "--modes", "reference-9x9"], "M must be in 1..=4"),
        (vec!["run", "--modes", "ssaa-2x2"], "technique must be"),
        (vec!["run", "--modes", "smaa-1x1"], "SMAA has no size"),
        (vec!["run", "--modes", "fxaa-1x1"], "FXAA has no size"),
        (vec!["run", "scenes/nope.json"], "no such file or folder"),
        (vec!["run", "--repetitions", "0"], "0 is not in 1..=10000"),
        (vec!["run", "--warmup", "4294967295"], "4294967295 is not in 0..=100"),
        (vec!["run", "--memory-limit", "0"], "positive number of GiB"),
        (vec!["run", "--frame-timeout", "0"], "positive number of seconds"),
        (vec!["run", "--shard", "3/2"], "--shard 3/2: expected I/N"),
        // Negative numbers reach aabench's own checks instead of clap's "unexpected argument".
        (vec!["run", "--memory-limit", "-1"], "--memory-limit -1 must be a positive number of GiB"),
        (vec!["run", "--frame-timeout", "-1"], "--frame-timeout -1 must be a positive number of seconds"),
        (vec!["run", "--shard", "-1/2"], "--shard -1/2: expected I/N"),
        (vec!["run", "--repetitions", "-1"], "-1 is not in 1..=10000"),
        (vec!["run", "--out", "/dev/full"], "--out /dev/full: exists and is not a folder"),
        (vec!["run", "--jod-display", "crt"], "--jod-display: unknown display model `crt`"),
        (vec!["run", "--keep-frames", "--sequences", "off"], "which --sequences off leaves out"),
        (vec!["run", "--keep-frames", "--quality", "off"], "which --quality off leaves out"),
    ] {
        let output = ws.run(&args);
        assert_eq!(output.status.code(), Some(2), "{args:?}");
        assert!(stderr(&output).contains(reason), "{args:?}: {}", stderr(&output));
    }
    assert!(!ws.dir.join("reports").exists(), "nothing should have been written");
}

/// A frame smaller than ColorVideoVDP scores (3×3) still runs, and says that JOD goes
/// unmeasured: on the console, in run.json's warnings, and in compare's notes, where the gate
/// has no JOD check of it.
#[test]
fn a_frame_too_small_for_jod_says_so_in_the_record_and_the_gate() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("tiny");
    ws.manifest("edge", "edge", |m| m["resolution"] = json!({ "quick": [3, 3], "nightly": [3, 3] }));
    let output = ws.run(&["run", "--modes", "deferred-1x1,reference-2x2", "--repetitions", "1"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let said = "resolution 3×3: JOD is not measured, since ColorVideoVDP needs at least 4×4 pixels";
    assert!(stderr(&output).contains(said), "{}", stderr(&output));
    let scene = &ws.record()["scenes"][0];
    assert!(
        scene["warnings"].as_array().unwrap().iter().any(|w| w.as_str().unwrap().starts_with(said)),
        "{scene}"
    );
    assert!(scene["modes"][0]["vs_ground_truth"]["jod"].is_null());
    let run = ws.run_dir().display().to_string();
    assert_eq!(ws.run(&["bless", &run]).status.code(), Some(0));
    let compared = ws.run(&["compare", &run]);
    let stdout = String::from_utf8_lossy(&compared.stdout).into_owned();
    assert_eq!(compared.status.code(), Some(0), "{stdout}");
    assert!(
        stdout.contains("edge: JOD not measured (its frame, 3×3, is smaller than ColorVideoVDP scores)"),
        "{stdout}"
    );
}

#[test]
fn gen_scenes_writes_once_then_reports_current_files() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("gen");
    ws.manifest("thin", "thin", |_| {});
    let first = ws.run(&["gen-scenes"]);
    assert!(String::from_utf8_lossy(&first.stdout).contains("thin: wrote"), "{first:?}");
    let glb = ws.dir.join("scenes/cache/thin.glb");
    let written = std::fs::metadata(&glb).unwrap().modified().unwrap();
    let second = ws.run(&["gen-scenes"]);
    assert!(String::from_utf8_lossy(&second.stdout).contains("is current"), "{second:?}");
    assert_eq!(std::fs::metadata(&glb).unwrap().modified().unwrap(), written);
    // A stale file (another generator version or seed) is replaced.
    ws.manifest("thin", "thin", |m| m["generate"]["seed"] = json!(2));
    let third = ws.run(&["gen-scenes"]);
    assert!(String::from_utf8_lossy(&third.stdout).contains("thin: wrote"), "{third:?}");
}

/// Waits until `record` holds for the run's run.json, or panics after `timeout`.
fn wait_for(ws: &Workspace, timeout: Duration, record: impl Fn(&Value) -> bool) {
    let start = Instant::now();
    while start.elapsed() < timeout {
        let ready = std::fs::read_dir(ws.dir.join("reports"))
            .ok()
            .and_then(|mut runs| runs.next())
            .and_then(|run| std::fs::read(run.ok()?.path().join("run.json")).ok())
            .and_then(|bytes| serde_json::from_slice::<Value>(&bytes).ok())
            .is_some_and(|r| record(&r));
        if ready {
            return;
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    panic!("run.json never reached the expected state");
}

#[test]
fn ctrl_c_stops_after_the_current_frame_and_keeps_what_was_measured() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("interrupt");
    ws.manifest("edge", "edge", |_| {});
    let mut child = ws
        .command(&["run", "--modes", "deferred-1x1,reference-2x2", "--repetitions", "10000"])
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Go on once timed frames are running.
    wait_for_line(&stderr_lines(&mut child), "rep 3/");
    let sent = Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    assert!(sent.success());
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130));

    let record = ws.record();
    assert_eq!(record["status"], "interrupted");
    let m = mode(&record["scenes"][0], "reference-2x2");
    let frames = m["frame_ms"]["samples"].as_array().unwrap().len();
    assert!((1..10000).contains(&frames), "{frames} frames");
    assert!(ws.run_dir().join(m["images"]["display"].as_str().unwrap()).exists(), "{m}");
}

#[test]
fn ctrl_c_while_the_path_is_measured_leaves_the_scene_interrupted_not_ok() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("interrupt-measures");
    ws.manifest("edge", "edge", |m| {
        m["resolution"]["quick"] = json!([384, 288]);
        m["motion"] = json!({"path": "pan", "rate": 3.0, "frames": {"quick": 16, "nightly": 16}});
    });
    let modes = "deferred-1x1,fxaa,smaa,reference-2x2";
    let mut child =
        ws.command(&["run", "--modes", modes, "--repetitions", "1"]).stderr(Stdio::piped()).spawn().unwrap();
    // The frames are rendered; FLIP and JOD along the path take seconds at this size.
    wait_for_line(&stderr_lines(&mut child), "sequence: FLIP, JOD");
    let sent = Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    assert!(sent.success());
    assert_eq!(child.wait().unwrap().code(), Some(130));

    let record = ws.record();
    assert_eq!(record["status"], "interrupted");
    let scene = &record["scenes"][0];
    assert_eq!(scene["status"], "interrupted", "a path without FLIP and JOD is no measurement: {scene}");
    let error = scene["error"].as_str().unwrap();
    assert!(error.starts_with("sequence (") && error.contains("interrupted: "), "{error}");
    assert!(!error.contains("stopped after"), "every frame was rendered: {error}");
    // What was measured is kept: the still's and the path's frames.
    assert_eq!(mode(scene, "reference-2x2")["status"], "ok");
    assert_eq!(scene["sequences"][0]["frames_done"], 16);
}

/// A signal while a large still's FLIP, SSIM and JOD are computed gives them up half a second later
/// (they cannot be stopped midway): the run exits with what it measured, each mode's timings,
/// while a cancelled CI job's SIGKILL is still seconds away, where it used to wait them out.
#[test]
fn a_signal_during_a_large_stills_metrics_gives_them_up_and_keeps_the_timings() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("interrupt-metrics");
    ws.manifest("edge", "edge", |m| m["resolution"]["quick"] = json!([2048, 1536]));
    let modes = "deferred-1x1,fxaa,smaa,reference-2x2";
    let mut child =
        ws.command(&["run", "--modes", modes, "--repetitions", "1"]).stderr(Stdio::piped()).spawn().unwrap();
    wait_for_line(&stderr_lines(&mut child), "writing images and metrics");
    let signalled = Instant::now();
    let sent = Command::new("kill").args(["-TERM", &child.id().to_string()]).status().unwrap();
    assert!(sent.success());
    assert_eq!(child.wait().unwrap().code(), Some(130));
    let waited = signalled.elapsed();

    let record = ws.record();
    assert_eq!(record["status"], "interrupted");
    let scene = &record["scenes"][0];
    assert_eq!(scene["status"], "interrupted", "{scene}");
    assert_eq!(scene["error"], "interrupted while its metrics and images were computed");
    let given_up: Vec<&Value> =
        scene["modes"].as_array().unwrap().iter().filter(|m| m["status"] == "interrupted").collect();
    assert!(
        !given_up.is_empty(),
        "the metrics of four modes at 2048×1536 take longer than half a second: {scene}"
    );
    for mode in given_up {
        assert!(mode["vs_ground_truth"].is_null(), "{mode}");
        assert_eq!(
            mode["frame_ms"]["samples"].as_array().map(Vec::len),
            Some(1),
            "its timing is kept: {mode}"
        );
    }
    // Without the grace the metrics take tens of seconds here; the bound leaves room for a
    // loaded machine.
    assert!(waited < Duration::from_secs(8), "exited {waited:?} after the signal");
}

#[test]
fn a_killed_run_leaves_the_scenes_that_finished() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("killed");
    ws.manifest("a-plane", "plane", |_| {});
    ws.manifest("b-edge", "edge", |m| m["resolution"]["quick"] = json!([256, 192]));
    let mut child = ws
        .command(&["run", "--modes", "deferred-1x1", "--repetitions", "10000"])
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // The first scene can never finish 10000 frames in time: kill while it runs.
    wait_for(&ws, Duration::from_secs(60), |r| r["status"] == "running");
    std::thread::sleep(Duration::from_secs(2));
    child.kill().unwrap();
    child.wait().unwrap();
    let record = ws.record();
    assert_eq!(record["status"], "running", "the record stays as last written");
    assert!(record["scenes"].as_array().unwrap().is_empty());

    // With a quick first scene and a slow second one, a kill during the second leaves the
    // first whole.
    let ws = Workspace::new("killed2");
    ws.manifest("a-plane", "plane", |_| {});
    ws.manifest("b-edge", "edge", |m| m["resolution"]["quick"] = json!([1024, 768]));
    let mut child = ws
        .command(&["run", "--modes", "deferred-1x1,reference-4x4", "--repetitions", "3"])
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    wait_for(&ws, Duration::from_secs(120), |r| r["scenes"].as_array().is_some_and(|s| s.len() == 1));
    child.kill().unwrap();
    child.wait().unwrap();
    let record = ws.record();
    assert_eq!(record["scenes"].as_array().unwrap().len(), 1, "killed before the slow scene finished");
    assert_eq!(record["scenes"][0]["name"], "a-plane");
    assert_eq!(record["scenes"][0]["status"], "ok");
    assert_eq!(
        mode(&record["scenes"][0], "reference-4x4")["frame_ms"]["samples"].as_array().unwrap().len(),
        3
    );
}

#[test]
fn run_help_states_each_tiers_most_rounds() {
    let ws = Workspace::new("help");
    let output = ws.run(&["run", "--help"]);
    assert!(output.status.success(), "{}", stderr(&output));
    let help = String::from_utf8_lossy(&output.stdout).split_whitespace().collect::<Vec<_>>().join(" ");
    for tier in [aabench::plan::Tier::Quick, aabench::plan::Tier::Nightly] {
        let said = format!("{}: ", tier.name());
        let line = help.split(&said).nth(1).unwrap_or_else(|| panic!("no `{said}` in: {help}"));
        let rounds = format!("up to {} rounds", tier.most_rounds());
        assert!(line.split(';').next().unwrap().contains(&rounds), "{said}… lacks `{rounds}`: {help}");
    }
}

/// Without `--repetitions` each mode takes its rounds by confidence, at least 5 and at most 15,
/// and says why it stopped, which its own frames bear out.
#[test]
fn a_run_takes_its_rounds_by_confidence_unless_given_a_count() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("confidence");
    ws.manifest("edge", "edge", |_| {});
    let modes = "deferred-1x1,reference-2x2,reference-4x4-stalled,adaptive-2x2";
    let output = ws.run(&["run", "--modes", modes]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let record = ws.record();
    let rule = &record["settings"]["confidence"];
    assert_eq!(rule, &json!({"floor": 9, "most": 15, "width": 0.1, "budget_s": 20.0}));
    assert_eq!(record["settings"]["repetitions"], 15);
    let scene = &record["scenes"][0];
    let spent_ms: f64 = scene["modes"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|m| m["frame_ms"]["samples"].as_array().unwrap())
        .map(|s| s.as_f64().unwrap())
        .sum();
    for id in modes.split(',') {
        let m = mode(scene, id);
        assert_eq!(m["status"], "ok", "{id}: {}", m["error"]);
        let frames = &m["frame_ms"];
        let taken = frames["samples"].as_array().unwrap().len();
        assert!((9..=15).contains(&taken), "{id}: {taken} rounds");
        let (low, high, median) = (
            frames["ci_low"].as_f64().unwrap(),
            frames["ci_high"].as_f64().unwrap(),
            frames["median"].as_f64().unwrap(),
        );
        match m["stopped"].as_str() {
            Some("interval") => assert!(high - low <= 0.1 * median, "{id}: {frames}"),
            Some("budget") => assert!(spent_ms >= 20_000.0, "{id}: the scene's frames took {spent_ms} ms"),
            Some("most") => assert_eq!(taken, 15, "{id}"),
            other => panic!("{id} stopped for {other:?}"),
        }
    }
}
