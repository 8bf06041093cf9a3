//! Sequences along a manifest's camera path, through the `aabench` binary: a static path gives
//! every mode its still frame bit for bit and no instability; a thin wire under a slow pan
//! flickers in deferred-1x1 far more than in reference-4x4, and the metric ranks them so; TAA
//! flickers less than deferred-1x1 on the moving `thin` scene, every mode reports what lag
//! costs, its stalled twin takes its frames, and the report shows every mode along the path, where it flickers most and which
//! technique to choose along it; stable counts flicker less than the paper's there, for the
//! samples they add; shards merged keep every path image and kept frame.

use std::path::{Path, PathBuf};

use serde_json::{Value, json};

use crate::support;

use support::*;

/// Every mode of the sequence's scene: status ok, a sequence of `frames` frames.
fn sequence<'a>(scene: &'a Value, id: &str, frames: usize) -> &'a Value {
    let m = mode(scene, id);
    assert_eq!(m["status"], "ok", "{id}: {}", m["error"]);
    let sequence = &m["sequences"][0];
    assert_eq!(sequence["mse"].as_array().map(Vec::len), Some(frames), "{id}: {sequence}");
    sequence
}

#[test]
fn a_static_path_repeats_the_still_frame_in_every_mode_without_instability() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("static-path");
    ws.manifest("edge", "edge", |m| {
        m["motion"] = json!({"path": "static", "frames": {"quick": 3, "nightly": 3}});
    });
    let modes =
        "deferred-1x1,fxaa,smaa,msaa-4x,reference-2x2,adaptive-2x2,adaptive-2x2-cells,adaptive-2x2-stable";
    let output = ws.run(&["run", "--modes", modes, "--repetitions", "1"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let scene = &ws.record()["scenes"][0];
    let record = &scene["sequences"][0];
    assert_eq!(
        (record["path"].as_str(), record["frames_done"].as_u64()),
        (Some("static"), Some(3)),
        "{record}"
    );
    assert!(record["error"].is_null(), "{record}");
    assert_eq!(record["truth_change"].as_f64(), Some(0.0));
    for id in modes.split(',') {
        let own = sequence(scene, id, 3);
        let still = &mode(scene, id)["output_hash"];
        assert!(own["hashes"].as_array().unwrap().iter().all(|h| h == still), "{id}: {own}");
        assert_eq!(own["instability"].as_f64(), Some(0.0), "{id}");
        assert_eq!(own["flicker"].as_f64(), Some(0.0), "{id}");
        assert!(own["change_ratio"].is_null(), "{id}: the truth does not change");
        let still_mse = mode(scene, id)["vs_ground_truth"]["mse"].as_f64().unwrap();
        assert!(own["mse"].as_array().unwrap().iter().all(|e| e.as_f64() == Some(still_mse)), "{id}");
        // FLIP's reference code can differ in the last bit of its mean between calls on the
        // same images; the images themselves are equal bit for bit (the hashes above).
        let still_flip = mode(scene, id)["vs_ground_truth"]["flip"].as_f64().unwrap();
        let near = |e: &Value| (e.as_f64().unwrap() - still_flip).abs() <= 1e-12 * still_flip;
        assert!(own["flip"].as_array().unwrap().iter().all(near), "{id}: {} vs {still_flip}", own["flip"]);
        assert!(near(&own["mean_flip"]), "{id}");
        // One warm-up, one timed frame and three sequence frames, each checked.
        assert_eq!(mode(scene, id)["checks"]["frames"], 5, "{id}");
    }
    for id in ["adaptive-2x2", "adaptive-2x2-stable"] {
        assert_eq!(sequence(scene, id, 3)["count_changes"].as_f64(), Some(0.0), "{id}");
    }
    // A stable mode's still is the paper's.
    assert_eq!(mode(scene, "adaptive-2x2-stable")["output_hash"], mode(scene, "adaptive-2x2")["output_hash"]);
    // Nothing flickers: the region is the first square, and the strip the first frames.
    let region = &record["region"];
    assert_eq!(
        (region["x"].as_u64(), region["y"].as_u64(), region["strip_first"].as_u64()),
        (Some(0), Some(0), Some(0))
    );
    // Every frame's camera is the still's, the warm-up's too: its truth is the still truth,
    // rendered once.
    assert_eq!(record["truth_rendered"], 0);
    let cached = std::fs::read_dir(ws.dir.join("scenes/cache/truth")).unwrap().count();
    assert_eq!(cached, 1);
}

#[test]
fn a_wire_under_a_slow_pan_flickers_at_one_sample_and_far_less_at_sixteen() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("wire-pan");
    ws.manifest("wire", "wire", |m| {
        m["resolution"] = json!({"quick": [128, 96], "nightly": [128, 96]});
        m["lights"] = json!([{ "position": [5.0, 10.0, 5.0], "intensity": 900.0, "range": 80.0 }]);
        m["motion"] = json!({"path": "pan", "rate": 3.0, "frames": {"quick": 6, "nightly": 6}});
    });
    let modes = "deferred-1x1,reference-4x4";
    let output = ws.run(&["run", "--modes", modes, "--repetitions", "1"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let scene = &ws.record()["scenes"][0];
    let truth_change = scene["sequences"][0]["truth_change"].as_f64().unwrap();
    assert!(truth_change > 0.0, "the view moves");
    // Frame 0 is the still truth; the warm-up's 16 and the window's other five are rendered
    // and cached beside it under keys of their own.
    assert_eq!(scene["sequences"][0]["truth_rendered"], 16 + 5);
    let cached = std::fs::read_dir(ws.dir.join("scenes/cache/truth")).unwrap().count();
    assert_eq!(cached, 1 + 16 + 5);
    let measure = |id: &str, key: &str| sequence(scene, id, 6)[key].as_f64().unwrap();
    let (deferred, reference) = (measure("deferred-1x1", "flicker"), measure("reference-4x4", "flicker"));
    // A single sample catches the wires and slats or misses them from frame to frame; sixteen
    // average them out.
    assert!(deferred > 3.0 * reference, "deferred-1x1 {deferred:e}, reference-4x4 {reference:e}");
    // Without motion compensation too.
    let instability = |id: &str| measure(id, "instability");
    let (deferred, reference) = (instability("deferred-1x1"), instability("reference-4x4"));
    assert!(deferred > 4.0 * reference, "deferred-1x1 {deferred:e}, reference-4x4 {reference:e}");
    // Its image changes from frame to frame more than the truth's, and more than sixteen
    // samples' does.
    let change = |id: &str| sequence(scene, id, 6)["change_ratio"].as_f64().unwrap();
    assert!(change("deferred-1x1") > 1.0 && change("deferred-1x1") > change("reference-4x4"));
    // And the frames move: no two of deferred-1x1's are alike.
    let hashes = sequence(scene, "deferred-1x1", 6)["hashes"].as_array().unwrap().clone();
    assert!(hashes.windows(2).all(|w| w[0] != w[1]), "{hashes:?}");
    // FLIP, frame by frame, ranks them as the MSE does.
    let flip = |id: &str| sequence(scene, id, 6)["mean_flip"].as_f64().unwrap();
    assert!(flip("deferred-1x1") > flip("reference-4x4") && flip("reference-4x4") > 0.0);
    assert_eq!(sequence(scene, "deferred-1x1", 6)["flip"].as_array().map(Vec::len), Some(6));

    // The worst-flickering region, animated: the truth's first frame is the still truth's crop
    // there, and deferred-1x1 flickers in it more than across the frame and more than
    // reference-4x4 does.
    let region = &scene["sequences"][0]["region"];
    let (x, y, side) = (region["x"].as_u64().unwrap() as u32, region["y"].as_u64().unwrap() as u32, 64);
    assert_eq!(region["side"], side);
    let animation = |id: &str| {
        let file =
            ws.run_dir().join(region["animations"][id].as_str().unwrap_or_else(|| panic!("{id}: {region}")));
        let frames = aabench::files::images::read_apng(&file).unwrap();
        // Forwards, then back without the ends.
        assert_eq!(frames.len(), 10, "{id}");
        assert!(frames.iter().all(|f| f.dimensions() == (side, side)), "{id}");
        frames
    };
    let truth = animation("truth");
    let still = image::open(ws.run_dir().join(scene["truth"]["image"].as_str().unwrap())).unwrap().to_rgba8();
    assert_eq!(truth[0], image::imageops::crop_imm(&still, x, y, side, side).to_image());
    let back: Vec<image::RgbaImage> = truth[1..5].iter().rev().cloned().collect();
    assert_eq!(truth[6..], back[..], "frames 4 to 1 after 5");
    let flicker = |id: &str| {
        let frames = animation(id);
        let mut sum = 0.0;
        for f in 1..6 {
            for (((a, b), t), u) in
                frames[f].iter().zip(frames[f - 1].iter()).zip(truth[f].iter()).zip(truth[f - 1].iter())
            {
                sum += ((f64::from(*a) - f64::from(*b) - f64::from(*t) + f64::from(*u)) / 255.0).powi(2);
            }
        }
        // Per colour value and frame pair, as `instability` (alpha never changes).
        sum / (f64::from(side * side) * 3.0 * 5.0)
    };
    eprintln!(
        "region flicker {:e} {:e}, frame {deferred:e} {reference:e}",
        flicker("deferred-1x1"),
        flicker("reference-4x4")
    );
    assert!(flicker("deferred-1x1") > 2.0 * deferred, "{} vs {deferred:e}", flicker("deferred-1x1"));
    assert!(flicker("deferred-1x1") > 4.0 * flicker("reference-4x4"));
}

/// Keyframes from the edge scene's camera (head-on before its two walls, which face it) to
/// `position`, looking at `target`, over frames half a second apart.
fn edge_path(name: &str, position: [f64; 3], target: [f64; 3]) -> Workspace {
    let ws = Workspace::new(name);
    ws.manifest("edge", "edge", |m| {
        m["motion"] = json!({"path": "keyframes", "time_step_s": 0.5, "frames": {"quick": 3, "nightly": 3},
            "keyframes": [{"time_s": 0, "position": [0, 0, 4], "target": [0, 0, 0]},
                          {"time_s": 1, "position": position, "target": target}]});
    });
    ws
}

#[test]
fn a_path_frame_that_shows_nothing_fails_naming_the_frame() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    // Turning away from the walls: from frame 1 on, no triangle is in view. The scene fails
    // when it loads, before anything renders.
    let ws = edge_path("path-away", [0.0, 0.0, 4.0], [0.0, 0.0, 10.0]);
    let output = ws.run(&["run", "--modes", "deferred-1x1", "--repetitions", "1"]);
    assert_eq!(output.status.code(), Some(3), "{}", stderr(&output));
    let error = ws.record()["scenes"][0]["error"].as_str().unwrap().to_string();
    assert!(
        error.contains("motion.keyframes: frame 1 of the path at 64×48 has none of the scene's"),
        "{error}"
    );
    // Declared empty, it renders, and its frames show nothing.
    let declared = edge_path("path-away-empty", [0.0, 0.0, 4.0], [0.0, 0.0, 10.0]);
    declared.manifest("edge", "edge", |m| {
        m["empty"] = json!(true);
        m["motion"] = json!({"path": "keyframes", "time_step_s": 0.5, "frames": {"quick": 3, "nightly": 3},
            "keyframes": [{"time_s": 0, "position": [0, 0, 4], "target": [0, 0, 0]},
                          {"time_s": 1, "position": [0, 0, 4], "target": [0, 0, 10]}]});
    });
    let output = declared.run(&["run", "--modes", "deferred-1x1", "--repetitions", "1"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));

    // Behind the walls, looking back at them: their triangles are in view, but only their back
    // faces, which are culled. Frame 1 shows nothing: every mode fails, naming it, and no mean
    // along the path counts its empty frames as perfect.
    let ws = edge_path("path-behind", [0.0, 0.0, -6.0], [0.0, 0.0, 0.0]);
    let output = ws.run(&["run", "--modes", "deferred-1x1,fxaa", "--repetitions", "1"]);
    assert_eq!(output.status.code(), Some(3), "{}", stderr(&output));
    let scene = &ws.record()["scenes"][0];
    for id in ["deferred-1x1", "fxaa"] {
        let m = mode(scene, id);
        assert_eq!(m["status"], "failed", "{id}: {m}");
        let error = m["error"].as_str().unwrap();
        assert!(error.contains("frame 1: blank frame"), "{id}: {error}");
        assert!(m["sequences"][0].is_null(), "{id}: no record along the path");
    }
}

/// A 10-bit display's path is scored from its 10-bit frames: the kept frames are 16-bit PNGs of
/// 10-bit codes, and ColorVideoVDP of exactly those codes (not of their 8-bit roundings), seen at
/// the display's own pixels a degree, is the path's JOD.
#[test]
fn a_ten_bit_path_is_scored_from_its_ten_bit_frames() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("path-ten-bit");
    ws.manifest("edge", "edge", |m| {
        m["display"] = json!({"transfer": "pq", "peak_nits": 600, "bits": 10});
        m["motion"] = json!({"path": "keyframes", "time_step_s": 0.5, "frames": {"quick": 3, "nightly": 3},
            "keyframes": [{"time_s": 0, "position": [0, 0, 4], "target": [0, 0, 0]},
                          {"time_s": 1, "position": [1.0, 0.5, 3.5], "target": [0, 0, 0]}]});
    });
    let output = ws.run(&["run", "--modes", "deferred-1x1", "--repetitions", "1", "--keep-frames"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let scene = &ws.record()["scenes"][0];
    let jod = sequence(scene, "deferred-1x1", 3)["jod"].as_f64().unwrap();
    let dir = ws.run_dir().join("edge/frames/1");
    let kept: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("sequence.json")).unwrap()).unwrap();
    assert_eq!(
        (kept["bits"].as_u64(), kept["first_measured_frame"].as_u64()),
        (Some(10), Some(16)),
        "{kept}"
    );
    let frames = kept["frames"].as_u64().unwrap() as usize;
    // Each stream's frames as code values in [0, 1], at 10 bits and rounded to 8.
    let clip = |stream: &str, bits: u32| -> Vec<Vec<f32>> {
        (0..frames)
            .map(|index| {
                let png = image::open(dir.join(format!("{stream}/{index:03}.png"))).unwrap();
                assert_eq!(png.color(), image::ColorType::Rgba16, "{stream} {index}");
                let codes = png.to_rgba16().into_raw();
                let rgb = codes.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]);
                rgb.map(|v| match bits {
                    10 => f32::from(v >> 6) / 1023.0,
                    _ => (f32::from(v >> 6) * 255.0 / 1023.0).round() / 255.0,
                })
                .collect()
            })
            .collect()
    };
    // Seen at the display's own pixels a degree, though the quick frame is half the nightly's
    // width: a pixel is as large to the eye in every tier.
    let display = aabench_cvvdp::Display::named(kept["display"].as_str().unwrap()).unwrap();
    assert_eq!(kept["pixels_per_degree"].as_f64(), Some(display.pixels_per_degree), "{kept}");
    assert_eq!(scene["pixels_per_degree"].as_f64(), Some(display.pixels_per_degree));
    let metric = aabench_cvvdp::Cvvdp::new(display);
    let score = |bits: u32| {
        let (test, truth) = (clip("deferred-1x1", bits), clip("truth", bits));
        let mut video = metric.video(64, 48, kept["fps"].as_f64().unwrap()).unwrap().measured_from(16);
        for (t, r) in test.iter().zip(&truth) {
            let frame = |rgb| aabench_cvvdp::Frame { width: 64, height: 48, rgb };
            video.push(frame(t), frame(r)).unwrap();
        }
        video.finish().unwrap().jod
    };
    assert!((score(10) - jod).abs() < 1e-9, "the run's {jod} is the 10-bit frames' {}", score(10));
    assert_ne!(score(8), jod, "8-bit roundings of the frames score otherwise");
}

/// A workspace with the `thin` scene at `size`, lit by the suite's sun, on the suite's default
/// path (an orbit of 2° a second) over eight frames.
fn moving_thin(name: &str, size: [u32; 2]) -> Workspace {
    let ws = Workspace::new(name);
    ws.manifest("thin", "thin", |m| {
        m["resolution"] = json!({"quick": size, "nightly": size});
        m["lights"] = json!([{ "position": [30.0, 50.0, 20.0], "intensity": 4500.0, "range": 250.0 }]);
        m["ambient"] = json!([0.12, 0.13, 0.15]);
        m["background"] = json!([0.55, 0.7, 0.95]);
        m["motion"] = json!({"frames": {"quick": 8, "nightly": 8}});
    });
    ws
}

/// Every file below a folder, by its path inside it, with its bytes.
fn files_below(root: &Path) -> std::collections::BTreeMap<PathBuf, Vec<u8>> {
    let mut files = std::collections::BTreeMap::new();
    let mut folders = vec![root.to_path_buf()];
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder).unwrap().map(Result::unwrap) {
            let path = entry.path();
            if path.is_dir() {
                folders.push(path);
            } else {
                files.insert(path.strip_prefix(root).unwrap().to_path_buf(), std::fs::read(&path).unwrap());
            }
        }
    }
    files
}

/// Two shards of a suite with a camera path, run with `--keep-frames`, merge into a run that
/// holds every file each shard wrote for its scenes, byte for byte (the path's animations and
/// distortion maps, the kept frames), and that `report` reads without a file missing.
#[test]
fn merged_shards_keep_every_path_image_and_kept_frame() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = moving_thin("merge-path", [64, 48]);
    ws.manifest("plane", "plane", |_| {});
    let args = ["run", "--modes", "deferred-1x1,taa", "--repetitions", "1", "--keep-frames"];
    for (shard, folder) in [("1/2", "shard1"), ("2/2", "shard2")] {
        let output = ws.run(&[&args[..], &["--shard", shard, "--out", folder]].concat());
        assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    }
    let shard_runs: Vec<PathBuf> = ["shard1", "shard2"]
        .iter()
        .map(|folder| std::fs::read_dir(ws.dir.join(folder)).unwrap().next().unwrap().unwrap().path())
        .collect();
    let mut arguments = vec!["merge".to_string()];
    arguments.extend(shard_runs.iter().map(|run| run.display().to_string()));
    arguments.extend(["--out".into(), "merged".into()]);
    let output = ws.run(&arguments.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let merged = ws.dir.join("merged");

    let mut scenes = 0;
    for run in &shard_runs {
        for scene in std::fs::read_dir(run).unwrap().map(|e| e.unwrap().path()).filter(|p| p.is_dir()) {
            scenes += 1;
            let name = scene.file_name().unwrap();
            let (theirs, ours) = (files_below(&scene), files_below(&merged.join(name)));
            assert_eq!(theirs.keys().collect::<Vec<_>>(), ours.keys().collect::<Vec<_>>(), "{name:?}");
            assert!(theirs == ours, "{name:?}: a merged file's bytes differ from the shard's");
        }
    }
    assert_eq!(scenes, 2);
    let thin = files_below(&merged.join("thin"));
    let below = |folder: &str| thin.keys().filter(|path| path.starts_with(folder)).count();
    assert!(below("path") >= 2, "the path's images: {:?}", thin.keys().collect::<Vec<_>>());
    assert_eq!(
        below("frames"),
        3 * (16 + 8) + 1,
        "the kept frames of the truth and two modes, and sequence.json"
    );

    let report = ws.run(&["report", "merged"]);
    assert_eq!(report.status.code(), Some(0), "{}", stderr(&report));
    assert!(!stderr(&report).contains("missing"), "{}", stderr(&report));

    // A link in a shard's scene folder is no file aabench wrote: the merge is refused, by name,
    // and writes nothing.
    let scene =
        std::fs::read_dir(&shard_runs[0]).unwrap().map(|e| e.unwrap().path()).find(|p| p.is_dir()).unwrap();
    std::os::unix::fs::symlink("/etc/hostname", scene.join("link.png")).unwrap();
    arguments.last_mut().unwrap().replace_range(.., "linked");
    let refused = ws.run(&arguments.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(refused.status.code(), Some(2), "{}", stderr(&refused));
    assert!(stderr(&refused).contains("link.png: neither a file nor a folder"), "{}", stderr(&refused));
    assert!(!ws.dir.join("linked").exists());
}

#[test]
fn taa_flickers_less_than_deferred_on_a_moving_thin_scene_and_reports_what_lag_costs() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = moving_thin("taa-thin", [128, 96]);
    let output = ws.run(&["run", "--modes", "deferred-1x1,taa,taa-stalled", "--repetitions", "2"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let scene = &ws.record()["scenes"][0];
    let (deferred, taa) = (sequence(scene, "deferred-1x1", 8), sequence(scene, "taa", 8));
    // The stalled twin's still is taa's to the bit: it takes taa's frames instead of rendering
    // the path again, and says so; it has no time of its own along the path.
    let mut stalled = sequence(scene, "taa-stalled", 8).clone();
    assert_eq!(stalled["frames_of"], "taa", "{stalled}");
    assert!(stalled.get("frame_ms").is_none() && taa["frame_ms"]["samples"].as_array().unwrap().len() == 8);
    let object = stalled.as_object_mut().unwrap();
    object.remove("frames_of");
    object.insert("frame_ms".into(), taa["frame_ms"].clone());
    assert_eq!(&stalled, taa);
    let flicker = |s: &Value| s["flicker"].as_f64().unwrap();
    assert!(flicker(taa) < flicker(deferred), "taa {:e}, deferred-1x1 {:e}", flicker(taa), flicker(deferred));
    // Its path does not start from its still (16 frames at the first camera, converged): its
    // history warmed up along the 16 frames of the path before the first, as in a game. The
    // orbit moves there already: no lead, no still warm-up frame.
    assert_eq!(scene["sequences"][0]["warmup_frames"], 16);
    assert!(
        scene["sequences"][0].get("lead_s").is_none()
            && scene["sequences"][0].get("warmup_still_frames").is_none()
    );
    assert_ne!(taa["hashes"][0], mode(scene, "taa")["output_hash"]);
    // The still is rendered twice from a reset, and both agree.
    assert_eq!(mode(scene, "taa")["deterministic"], true);
    // What lag costs: the error where the orbit uncovers what the frame before hid, at the
    // silhouettes that moved, and elsewhere; the pixels are the truth's, the same for each mode.
    let ghosting = &taa["ghosting"];
    let disoccluded = ghosting["disoccluded"].as_f64().unwrap();
    assert!(disoccluded > 0.0 && disoccluded < 0.1, "{ghosting}");
    for key in ["mse", "mse_edges", "mse_elsewhere"] {
        assert!(ghosting[key].as_f64().unwrap() > 0.0, "{key}: {ghosting}");
    }
    assert_eq!(deferred["ghosting"]["disoccluded"], ghosting["disoccluded"], "{deferred}");
    assert!(scene["sequences"][0]["blank_flicker"].as_f64().unwrap() > 0.0);
    // How coarse each mode's error is at the square where the modes flicker most is taken by
    // the run, not by the report (the stalled twin's, equal to taa's above, is taa's).
    for along in [taa, deferred] {
        let share = along["coarse_share"].as_f64().expect("a coarse share");
        assert!(share > 0.0 && share < 1.0, "{share}");
    }

    // The report shows the path: a table of every mode along it, and flicker against time.
    let run_dir = ws.run_dir();
    let run_dir = run_dir.to_str().unwrap();
    let output = ws.run(&["report", "--markdown", run_dir, "--figures", "figures"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let markdown = String::from_utf8(output.stdout).unwrap();
    // Labelled by the speed the content moved (an orbit's content near its pivot moves slower
    // than the background's nominal speed), the nominal beside it.
    let speed = scene["sequences"][0]["measured_speed"]["median"].as_f64().unwrap();
    assert!(speed > 0.0 && speed < 0.05, "{}", scene["sequences"][0]);
    let label = format!("{} px a frame (median; 0.05 nominal)", aabench::manifest::motion::short(speed));
    assert!(
        markdown.contains(&format!("Along the camera path: orbit path at {label}, 8 of 8 frames")),
        "{markdown}"
    );
    // A mode's row of the path's table: as many cells as its columns, the lag's among them.
    let columns = aabench::report::sequence_columns();
    let path_row = |mode: &str| {
        let cells = |line: &str| line.trim().trim_matches('|').split(" | ").count();
        let row =
            markdown.lines().find(|l| l.starts_with(&format!("| {mode} | ")) && cells(l) == columns.len());
        row.unwrap_or_else(|| panic!("{mode}'s row along the path: {markdown}"))
    };
    let row = path_row("taa");
    assert!(row.contains(&format!("{:.3}", flicker(taa) * 1e4)), "{row}");
    let disoccluded = columns.iter().position(|c| c == "disoccluded %").expect("a column of the lag's rows");
    let share = ghosting["disoccluded"].as_f64().unwrap() * 100.0;
    assert_eq!(
        row.trim().trim_matches('|').split(" | ").nth(disoccluded),
        Some(format!("{share:.2}").as_str())
    );
    let row = path_row("taa-stalled");
    assert!(row.starts_with("| taa-stalled | taa's frames | "), "{row}");
    let plot = std::fs::read_to_string(ws.dir.join("figures/thin-front-flicker.svg")).unwrap();
    assert!(plot.contains("flicker against run time") && plot.contains("taa"), "{plot}");
    // Which technique: along the path, and the still without TAA, seen as the caption says:
    // on the JOD display, at its distance, a frame of this width so many degrees across.
    let seen = "as seen on standard_fhd at 37.8 pixels a degree (a 128-pixel-wide frame 3.4° across)";
    assert!(markdown.contains(seen), "{markdown}");
    let along = markdown
        .lines()
        .find(|l| l.starts_with(&format!("| thin | along the path: {label} | ")))
        .expect("the path's row");
    assert!(along.contains("flicker"), "{along}");
    let still = markdown.lines().find(|l| l.starts_with("| thin | still | ")).expect("the still's row");
    assert!(!still.contains("taa"), "TAA is not ranked by its still: {still}");
    // The truth, deferred-1x1 and taa side by side at ×2, every frame forwards and back.
    let animation = aabench::files::images::read_apng(&ws.dir.join("figures/thin-flicker.png")).unwrap();
    assert_eq!(animation.len(), 14);
    assert_eq!(animation[0].dimensions(), (3 * 128 + 2 * 6, 128));
    assert_eq!(ws.run(&["report", run_dir]).status.code(), Some(0));
    let page = std::fs::read_to_string(std::path::Path::new(run_dir).join("index.html")).unwrap();
    assert!(
        page.contains(&format!("<h3>Along the camera path: {label}</h3>"))
            && page.contains("flicker against run time")
    );
    // Where it flickers most: the modes' animations and a strip of eight frames each.
    assert!(page.contains("<h3>Where it flickers most</h3>") && page.contains("thin/path/taa.png"), "{page}");
    for id in ["truth-8x8", "deferred-1x1", "taa"] {
        let strip =
            image::open(std::path::Path::new(run_dir).join(format!("report/thin/strip-{id}.png"))).unwrap();
        assert_eq!((strip.width(), strip.height()), (8 * 65 - 1, 64), "{id}");
    }
}

#[test]
fn stable_counts_flicker_less_than_the_papers_on_a_moving_thin_scene_for_the_samples_they_add() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    // At the quick tier's size: at 128×96 most of thin's detail is finer than a pixel wherever
    // it lies, and the counts have less to keep.
    let ws = moving_thin("stable-thin", [256, 192]);
    let output = ws.run(&[
        "run",
        "--modes",
        "adaptive-4x4,adaptive-4x4-stable",
        "--repetitions",
        "1",
        "--keep-frames",
    ]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let scene = &ws.record()["scenes"][0];
    let (paper, stable) = (sequence(scene, "adaptive-4x4", 8), sequence(scene, "adaptive-4x4-stable", 8));
    // --keep-frames: every frame the metric saw of each stream, the 16 of the warm-up first,
    // display-encoded, as the metrics read them, in the scene's folder, and beside them what a
    // reference implementation needs to score them as the run did.
    let frames = ws.run_dir().join("thin/frames/1");
    for stream in ["truth", "adaptive-4x4", "adaptive-4x4-stable"] {
        let kept: Vec<_> =
            std::fs::read_dir(frames.join(stream)).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(kept.len(), 16 + 8, "{stream}: {kept:?}");
        let last = image::open(frames.join(stream).join("023.png")).unwrap();
        assert_eq!((last.width(), last.height()), (256, 192), "{stream}");
    }
    let kept: Value = serde_json::from_slice(&std::fs::read(frames.join("sequence.json")).unwrap()).unwrap();
    assert_eq!(
        (kept["first_measured_frame"].as_u64(), kept["frames"].as_u64()),
        (Some(16), Some(24)),
        "{kept}"
    );
    assert_eq!(
        (kept["fps"].as_f64(), kept["display"].as_str()),
        (Some(60.0), Some("standard_fhd")),
        "{kept}"
    );
    let last = image::open(frames.join("adaptive-4x4-stable/023.png")).unwrap().to_rgba8();
    let shown = image::open(frames.join("adaptive-4x4/023.png")).unwrap().to_rgba8();
    assert_ne!(last.as_raw(), shown.as_raw(), "the two modes' last frames differ, as their hashes do");
    let number = |s: &Value, key: &str| s[key].as_f64().unwrap_or_else(|| panic!("{key}: {s}"));
    // The still is the paper's; along the path the counts follow the frames before, from the
    // first measured frame on (the warm-up frames before it moved already).
    assert_eq!(mode(scene, "adaptive-4x4-stable")["output_hash"], mode(scene, "adaptive-4x4")["output_hash"]);
    assert_ne!(stable["hashes"][0], paper["hashes"][0]);
    assert_ne!(stable["hashes"][7], paper["hashes"][7]);
    let (steadier, fewer) = (number(stable, "flicker"), number(stable, "count_changes"));
    assert!(
        steadier < 0.9 * number(paper, "flicker"),
        "flicker: stable {steadier:e}, paper {:e}",
        number(paper, "flicker")
    );
    assert!(fewer < number(paper, "count_changes"), "count changes: stable {fewer}, paper {paper}");
    // What that costs: a count never falls below the metric's, so it shades at least as many
    // samples along the path; every measured frame is timed.
    assert!(number(stable, "shaded_percent") >= number(paper, "shaded_percent"), "{stable}\n{paper}");
    for s in [paper, stable] {
        assert_eq!(s["frame_ms"]["samples"].as_array().map(Vec::len), Some(8), "{s}");
        assert!(number(&s["frame_ms"], "median") > 0.0);
    }
}

/// The gate compares a sequence: against its own baseline nothing moves; a baseline doctored
/// 20 % steadier and a point cheaper in one mode makes that mode's instability and samples
/// along the path regress; a run rendered with
/// `--sequences off` compared less than the baseline holds, which fails unless `--lenient`.
#[test]
fn the_gate_compares_sequences_and_a_run_without_them_compared_less() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let ws = Workspace::new("sequence-gate");
    ws.manifest("wire", "wire", |m| {
        m["lights"] = json!([{ "position": [5.0, 10.0, 5.0], "intensity": 900.0, "range": 80.0 }]);
        m["motion"] = json!({"path": "pan", "rate": 3.0, "frames": {"quick": 4, "nightly": 4}});
    });
    let run = |folder: &str, extra: &[&str]| {
        let mut args =
            vec!["run", "--out", folder, "--modes", "deferred-1x1,adaptive-2x2", "--repetitions", "2"];
        args.extend_from_slice(extra);
        let output = ws.run(&args);
        assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
        let runs: Vec<_> =
            std::fs::read_dir(ws.dir.join(folder)).unwrap().map(|e| e.unwrap().path()).collect();
        runs[0].to_str().unwrap().to_string()
    };
    let first = run("reports", &[]);
    let blessed = ws.run(&["bless", &first]);
    assert_eq!(blessed.status.code(), Some(0), "{}", stderr(&blessed));
    let out = ws.dir.join("gate");
    let out = out.to_str().unwrap();
    let compare = |run: &str, extra: &[&str]| {
        let mut args = vec!["compare", run, "--baseline", "baselines", "--out", out];
        args.extend_from_slice(extra);
        let code = ws.run(&args).status.code();
        (code, read_json(&ws.dir.join("gate/verdict.json")))
    };
    let outcome = |verdict: &Value, mode: &str, metric: &str| {
        let checks = verdict["checks"].as_array().unwrap();
        let check = checks.iter().find(|c| c["mode"] == mode && c["metric"] == metric);
        check.unwrap_or_else(|| panic!("no {metric} check of {mode}")).clone()
    };
    let (code, verdict) = compare(&first, &[]);
    assert_eq!(code, Some(0), "{verdict}");
    for mode in ["deferred-1x1", "adaptive-2x2"] {
        assert_eq!(outcome(&verdict, mode, "instability")["outcome"], "unchanged");
        assert_eq!(outcome(&verdict, mode, "sequence_psnr_vs_truth")["outcome"], "unchanged");
        assert_eq!(outcome(&verdict, mode, "sequence_flip_vs_truth")["outcome"], "unchanged");
    }
    assert_eq!(outcome(&verdict, "adaptive-2x2", "sequence_shaded_percent")["outcome"], "unchanged");

    let file = std::fs::read_dir(ws.dir.join("baselines")).unwrap().next().unwrap().unwrap().path();
    let file = file.join("quick/wire.json");
    let mut doctored = read_json(&file);
    let mut edit = |mode: &str, metric: &str, change: fn(f64) -> f64| {
        let value = &mut doctored["modes"][mode]["metrics"][metric];
        *value = json!(change(value.as_f64().unwrap()));
    };
    edit("adaptive-2x2", "instability", |v| v * 0.8);
    edit("adaptive-2x2", "sequence_shaded_percent", |v| v - 1.0);
    edit("deferred-1x1", "sequence_flip_vs_truth", |v| v * 0.9);
    let original = std::fs::read(&file).unwrap();
    write_json(&file, &doctored);
    let (code, verdict) = compare(&first, &[]);
    assert_eq!(code, Some(1), "{verdict}");
    assert_eq!(outcome(&verdict, "adaptive-2x2", "instability")["outcome"], "regressed");
    assert_eq!(outcome(&verdict, "adaptive-2x2", "sequence_shaded_percent")["outcome"], "regressed");
    assert_eq!(outcome(&verdict, "deferred-1x1", "instability")["outcome"], "unchanged");
    assert_eq!(outcome(&verdict, "deferred-1x1", "sequence_flip_vs_truth")["outcome"], "regressed");
    std::fs::write(&file, &original).unwrap();

    let stills = run("stills", &["--sequences", "off"]);
    let (code, verdict) = compare(&stills, &[]);
    assert_eq!(code, Some(1), "{verdict}");
    assert_eq!(outcome(&verdict, "*", "status")["outcome"], "missing");
    assert_eq!(compare(&stills, &["--lenient"]).0, Some(0));

    // A baseline whose sequence has another length is no comparison of this run's means.
    let mut longer = read_json(&file);
    longer["sequences"][0]["frames"] = json!(8);
    longer["sequences"][0]["frames_done"] = json!(8);
    write_json(&file, &longer);
    let (code, verdict) = compare(&first, &[]);
    assert_eq!(code, Some(1), "{verdict}");
    let status = outcome(&verdict, "*", "status");
    assert_eq!(status["outcome"], "failed");
    assert!(
        status["detail"].as_str().unwrap().contains("4 of 4 frames rendered, the baseline's 8 of 8"),
        "{status}"
    );
    std::fs::write(&file, original).unwrap();
}
