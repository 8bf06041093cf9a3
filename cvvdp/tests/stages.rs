//! Each stage of the port against the reference's own values for it (`fixtures.json`'s
//! `stages`, written by `fixtures/make_fixtures.py` from cvvdp 0.5.7): the display model, the
//! colour transform, the temporal filters, castleCSF, the pyramid's reduce and expand with
//! their border terms, the phase-uncertainty blur, and the per-pixel distortion map
//! (`heatmaps.json`, by `fixtures/make_heatmaps.py`). A stage that breaks fails here by name,
//! before the scores of `reference.rs` say only that something moved.

use crate::common;

use aabench_cvvdp::csf::{CastleCsf, Channel};
use aabench_cvvdp::masking::PhaseBlur;
use aabench_cvvdp::parameters::Parameters;
use aabench_cvvdp::pyramid::{self, Plane};
use aabench_cvvdp::temporal::Filters;
use aabench_cvvdp::{Display, colour};
use serde_json::Value;
use std::path::Path;

fn stages() -> Value {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/fixtures.json");
    let fixtures: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    fixtures["stages"].clone()
}

fn floats(value: &Value) -> Vec<f32> {
    value.as_array().unwrap().iter().map(|v| v.as_f64().unwrap() as f32).collect()
}

fn plane(rows: &Value) -> Plane {
    let rows: Vec<Vec<f32>> = rows.as_array().unwrap().iter().map(floats).collect();
    Plane { width: rows[0].len(), height: rows.len(), data: rows.concat() }
}

/// Whether `got` is `want` within `relative` of its size (and 10⁻⁶ absolute).
fn close(got: f32, want: f32, relative: f32) -> bool {
    (got - want).abs() <= 1e-6 + relative * want.abs()
}

#[test]
fn the_display_model_gives_the_references_luminance_and_colour_matrix() {
    let display = Display::standard_fhd();
    let stage = &stages()["display"];
    for (code, want) in floats(&stage["code_values"]).into_iter().zip(floats(&stage["luminance"])) {
        assert!(
            close(display.luminance(code), want, 1e-6),
            "code {code}: {} against {want}",
            display.luminance(code)
        );
    }
    let matrix = colour::rgb_to_dkl(&display);
    for (row, want) in matrix.iter().zip(stage["rgb_to_dkld65"].as_array().unwrap()) {
        for (&got, want) in row.iter().zip(floats(want)) {
            assert!(close(got, want, 1e-6), "RGB → DKL: {got} against {want}");
        }
    }
}

#[test]
fn the_temporal_filters_are_the_references_at_60_and_30_frames_a_second() {
    let parameters = Parameters::embedded();
    for stage in stages()["temporal_filters"].as_array().unwrap() {
        let fps = stage["fps"].as_f64().unwrap();
        let filters = Filters::new(&parameters, fps);
        for (channel, want) in stage["filters"].as_array().unwrap().iter().enumerate() {
            let want = floats(want);
            assert_eq!(filters.taps[channel].len(), want.len(), "{fps} fps, channel {channel}");
            for (&got, &w) in filters.taps[channel].iter().zip(&want) {
                assert!((got - w).abs() < 1e-6, "{fps} fps, channel {channel}: {got} against {w}");
            }
        }
    }
}

#[test]
fn castle_csf_gives_the_references_sensitivity_over_frequency_luminance_and_channel() {
    let csf = CastleCsf::embedded();
    let stage = stages()["csf"].clone();
    let values = stage["values"].as_array().unwrap();
    assert!(values.len() >= 100, "the stage samples the table widely");
    for value in values {
        let channel = match (value["cc"].as_u64().unwrap(), value["omega"].as_u64().unwrap()) {
            (0, 0) => Channel::AchromaticSustained,
            (1, 0) => Channel::RedGreen,
            (2, 0) => Channel::YellowViolet,
            (0, _) => Channel::AchromaticTransient,
            other => panic!("no channel {other:?}"),
        };
        let rho = value["rho"].as_f64().unwrap();
        let log_l = value["log10_L"].as_f64().unwrap() as f32;
        let got = csf.at_frequency(channel, rho).sensitivity(log_l);
        let want = value["S"].as_f64().unwrap() as f32;
        assert!(close(got, want, 1e-5), "{channel:?} at {rho} cpd, log L {log_l}: {got} against {want}");
    }
}

#[test]
fn the_pyramids_reduce_and_expand_are_the_references_borders_included() {
    for stage in stages()["pyramid"].as_array().unwrap() {
        let input = plane(&stage["input"]);
        let reduced = pyramid::reduce(&input);
        let want = plane(&stage["reduced"]);
        assert_eq!((reduced.width, reduced.height), (want.width, want.height));
        for (got, want) in reduced.data.iter().zip(&want.data) {
            assert!(
                close(*got, *want, 1e-6),
                "{}×{} reduced: {got} against {want}",
                input.width,
                input.height
            );
        }
        let expanded = pyramid::expand(&reduced, input.width, input.height);
        for (got, want) in expanded.data.iter().zip(&plane(&stage["expanded"]).data) {
            assert!(
                close(*got, *want, 1e-6),
                "{}×{} expanded: {got} against {want}",
                input.width,
                input.height
            );
        }
    }
}

#[test]
fn the_phase_uncertainty_blur_is_torchvisions_kernel() {
    let stage = &stages()["masking_blur"];
    let blur = PhaseBlur::new(stage["sigma"].as_f64().unwrap() as f32);
    let want = floats(&stage["kernel"]);
    assert_eq!(blur.taps().len(), want.len());
    for (got, want) in blur.taps().iter().zip(&want) {
        assert!(close(*got, *want, 1e-6), "{got} against {want}");
    }
}

/// A map of the reference's, from its little-endian float16 bytes in base64.
fn reference_map(encoded: &Value) -> Vec<f32> {
    let bytes = base64::decode(encoded.as_str().unwrap()).unwrap();
    bytes.chunks_exact(2).map(|b| half::f16::from_le_bytes([b[0], b[1]]).to_f32()).collect()
}

#[test]
fn the_distortion_maps_are_the_references_for_a_still_and_a_videos_worst_frame() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/heatmaps.json");
    let heatmaps: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let fixtures = common::fixtures();
    let metric = aabench_cvvdp::Cvvdp::new(Display::standard_fhd());
    for entry in heatmaps["maps"].as_array().unwrap() {
        let name = entry["name"].as_str().unwrap();
        let fixture = fixtures["fixtures"].as_array().unwrap().iter().find(|f| f["name"] == name).unwrap();
        let dims = |key: &str| fixture[key].as_u64().unwrap() as usize;
        let (width, height, count) = (dims("width"), dims("height"), dims("frames"));
        let test = common::frames(name, "test", width, height, count);
        let reference = common::frames(name, "reference", width, height, count);
        let frame = |rgb| common::frame(width, height, rgb);
        let (index, map) = if count == 1 {
            (0, metric.image_with_map(frame(&test[0]), frame(&reference[0])).unwrap().1)
        } else {
            let mut video =
                metric.video(width, height, fixture["fps"].as_f64().unwrap()).unwrap().with_worst_map();
            for (t, r) in test.iter().zip(&reference) {
                video.push(frame(t), frame(r)).unwrap();
            }
            let worst = video.finish().unwrap().worst.unwrap();
            (worst.frame, worst.map)
        };
        let want = reference_map(&entry["float16_base64"][index]);
        assert_eq!((map.width, map.height, map.data.len()), (width, height, want.len()), "{name}");
        // float16 keeps 11 significant bits: a relative step of 1/1024.
        let off = map.data.iter().zip(&want).filter(|(g, w)| (*g - *w).abs() > 1e-4 + 2e-3 * w.abs()).count();
        assert_eq!(off, 0, "{name}, frame {index}: {off} of {} pixels off the reference's map", want.len());
    }
}
