//! Camera paths: a manifest's `motion` section and the camera of each frame of its sequence.
//!
//! A preset path starts at the scene's camera (the manifest's, the file's or the framing one),
//! so `"motion": {}` animates any scene: the default is a slow orbit about the camera's target.
//! The target is the manifest camera's `target`; a camera from the file has only a direction,
//! so its target is the point of the view ray nearest the centre of the scene's bounds.
//! Presets move at a rate per second from the scene's camera at time 0 and frames are
//! `time_step_s` apart, so the quick tier's sequence is the first frames of the nightly one. Keyframes give positions and targets at
//! times and are interpolated linearly between them (held after the last).

use aabench_renderer::scene::Camera;
use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};

/// A manifest's `motion` section.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MotionSpec {
    #[serde(default)]
    pub path: PathKind,
    /// The preset's speed: degrees per second for `orbit` and `pan`, the share of the distance
    /// to the target covered per second for `dolly`. Omitted: [`PathKind::default_rate`].
    pub rate: Option<f64>,
    /// For `path: "keyframes"`: at least two, in increasing time.
    #[serde(default)]
    pub keyframes: Vec<Keyframe>,
    #[serde(default)]
    pub frames: SequenceFrames,
    /// Seconds between frames.
    #[serde(default = "default_time_step")]
    pub time_step_s: f64,
}

/// How the camera moves.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PathKind {
    /// About the target, around the camera's up axis.
    #[default]
    Orbit,
    /// Towards the target.
    Dolly,
    /// The view turning about the up axis, the position fixed.
    Pan,
    /// Not at all: every frame is the still frame (a test of the sequence machinery).
    Static,
    /// Through the manifest's keyframes.
    Keyframes,
}

impl PathKind {
    /// The rate a preset takes when the manifest gives none: 2° per second for the turns, a
    /// thirtieth of a degree per frame at 60 frames a second (a pan moves the middle of a
    /// 1024-pixel-wide view with a 60° vertical field by half a pixel per frame, of a 256-pixel
    /// one by an eighth), and 3 % of the distance per second for the dolly.
    pub fn default_rate(self) -> f64 {
        match self {
            PathKind::Orbit | PathKind::Pan => 2.0,
            PathKind::Dolly => 0.03,
            PathKind::Static | PathKind::Keyframes => 0.0,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            PathKind::Orbit => "orbit",
            PathKind::Dolly => "dolly",
            PathKind::Pan => "pan",
            PathKind::Static => "static",
            PathKind::Keyframes => "keyframes",
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Keyframe {
    pub time_s: f64,
    pub position: [f64; 3],
    pub target: [f64; 3],
}

/// Frames of the sequence per tier.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SequenceFrames {
    pub quick: u32,
    pub nightly: u32,
}

impl Default for SequenceFrames {
    fn default() -> Self {
        Self { quick: 8, nightly: 32 }
    }
}

fn default_time_step() -> f64 {
    1.0 / 60.0
}

/// The most frames a sequence may have in either tier.
pub const MAX_FRAMES: u32 = 256;

impl MotionSpec {
    /// The preset's rate, the manifest's or the default.
    pub fn rate(&self) -> f64 {
        self.rate.unwrap_or(self.path.default_rate())
    }

    /// Checks the section on its own; the cameras it gives are checked against the scene's
    /// camera once that is known ([`MotionSpec::cameras`]). Fields are relative to `motion`.
    pub fn check(&self) -> Result<(), (String, String)> {
        let fail = |field: &str, message: String| Err((field.to_string(), message));
        for (field, frames) in [("frames.quick", self.frames.quick), ("frames.nightly", self.frames.nightly)]
        {
            if !(2..=MAX_FRAMES).contains(&frames) {
                return fail(
                    field,
                    format!("{frames} must be within 2..={MAX_FRAMES} (a sequence compares frames)"),
                );
            }
        }
        if !(self.time_step_s.is_finite() && self.time_step_s > 0.0 && self.time_step_s <= 1.0) {
            return fail("time_step_s", format!("{} must be within (0, 1] seconds", self.time_step_s));
        }
        if let Some(rate) = self.rate {
            if matches!(self.path, PathKind::Static | PathKind::Keyframes) {
                return fail("rate", format!("the {} path has no rate", self.path.name()));
            }
            let limit = if self.path == PathKind::Dolly { 1.0 } else { 360.0 };
            if !(rate.is_finite() && rate.abs() <= limit) {
                return fail("rate", format!("{rate} must be finite and within ±{limit}"));
            }
        }
        match (self.path, self.keyframes.len()) {
            (PathKind::Keyframes, n) if n < 2 => {
                fail("keyframes", format!("{n} given: the keyframes path needs at least two"))
            }
            (PathKind::Keyframes, _) => self.check_keyframes(),
            (_, 0) => Ok(()),
            (path, _) => {
                fail("keyframes", format!("only the keyframes path takes keyframes, not {}", path.name()))
            }
        }
    }

    fn check_keyframes(&self) -> Result<(), (String, String)> {
        for (i, key) in self.keyframes.iter().enumerate() {
            let field = |name: &str| format!("keyframes[{i}].{name}");
            let camera = Camera::look_at(DVec3::from(key.position), DVec3::from(key.target), 45.0);
            if let Err(e) = camera.validate() {
                let name = if e.field == "up" { "target" } else { e.field };
                return Err((field(name), e.message));
            }
            if !key.time_s.is_finite() || key.time_s < 0.0 {
                return Err((field("time_s"), format!("{} must be finite and at least 0", key.time_s)));
            }
            if i > 0 && key.time_s <= self.keyframes[i - 1].time_s {
                return Err((
                    field("time_s"),
                    format!("{} must be later than the keyframe before", key.time_s),
                ));
            }
        }
        Ok(())
    }

    /// The cameras of the first `frames` frames, from the scene's camera `base` whose target
    /// lies `pivot` along its view (near and far planes, field of view and up axis kept along
    /// the path), each checked by the renderer's rules: `Err` names the frame's field
    /// (`motion.keyframes` or the preset's `motion.rate`).
    pub fn cameras(&self, base: &Camera, pivot: f64, frames: u32) -> Result<Vec<Camera>, (String, String)> {
        (0..frames)
            .map(|frame| {
                let camera = self.camera_at(base, pivot, f64::from(frame) * self.time_step_s);
                camera.validate().map(|()| camera).map_err(|e| {
                    let field =
                        if self.path == PathKind::Keyframes { "motion.keyframes" } else { "motion.rate" };
                    (field.to_string(), format!("frame {frame}: the camera's {}: {}", e.field, e.message))
                })
            })
            .collect()
    }

    /// The camera at `time` seconds along the path. A preset's is the scene's camera itself at
    /// time 0, so that its first frame is the still frame bit for bit.
    pub fn camera_at(&self, base: &Camera, pivot: f64, time: f64) -> Camera {
        let target = base.position + base.forward.normalize() * pivot;
        let up = base.up.normalize();
        let turn = |seconds: f64| DQuat::from_axis_angle(up, (self.rate() * seconds).to_radians());
        match self.path {
            PathKind::Static => *base,
            _ if time == 0.0 && self.path != PathKind::Keyframes => *base,
            PathKind::Orbit => {
                let position = target + turn(time) * (base.position - target);
                Camera { position, forward: target - position, ..*base }
            }
            PathKind::Pan => Camera { forward: turn(time) * base.forward, ..*base },
            PathKind::Dolly => {
                let position = base.position + (target - base.position) * (self.rate() * time).min(0.9);
                Camera { position, forward: target - position, ..*base }
            }
            PathKind::Keyframes => {
                let (position, target) = self.keyframe_at(time);
                Camera { position, forward: target - position, ..*base }
            }
        }
    }

    /// Position and target at `time`, linear between the keyframes around it.
    fn keyframe_at(&self, time: f64) -> (DVec3, DVec3) {
        let keys = &self.keyframes;
        let at = |k: &Keyframe| (DVec3::from(k.position), DVec3::from(k.target));
        let Some(next) = keys.iter().position(|k| k.time_s > time) else {
            return at(keys.last().expect("checked: at least two keyframes"));
        };
        if next == 0 {
            return at(&keys[0]);
        }
        let (a, b) = (&keys[next - 1], &keys[next]);
        let t = (time - a.time_s) / (b.time_s - a.time_s);
        let ((pa, ta), (pb, tb)) = (at(a), at(b));
        (pa.lerp(pb, t), ta.lerp(tb, t))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn base() -> Camera {
        Camera::look_at(DVec3::new(0.0, 2.0, 10.0), DVec3::new(0.0, 2.0, 0.0), 45.0)
    }

    fn spec(json: &str) -> MotionSpec {
        let spec: MotionSpec = serde_json::from_str(json).unwrap();
        spec.check().unwrap();
        spec
    }

    #[test]
    fn an_empty_section_orbits_the_target_slowly_and_starts_at_the_still() {
        let motion = spec("{}");
        let cameras = motion.cameras(&base(), 10.0, 8).unwrap();
        assert_eq!(cameras.len(), 8);
        assert_eq!(cameras[0], base(), "frame 0 is the still frame");
        let target = DVec3::new(0.0, 2.0, 0.0);
        for (i, camera) in cameras.iter().enumerate() {
            // On the circle about the target, looking at it, a thirtieth of a degree a frame.
            assert!(((camera.position - target).length() - 10.0).abs() < 1e-9);
            assert!((camera.position + camera.forward - target).length() < 1e-9);
            let angle = (camera.position - target).angle_between(base().position - target).to_degrees();
            assert!((angle - i as f64 / 30.0).abs() < 1e-9, "frame {i}: {angle}°");
        }
        assert_eq!(motion.cameras(&base(), 10.0, 32).unwrap().len(), 32);
    }

    #[test]
    fn the_quick_sequence_is_the_start_of_the_nightly_one() {
        for path in ["orbit", "dolly", "pan"] {
            let motion = spec(&format!(r#"{{"path": "{path}"}}"#));
            let quick = motion.cameras(&base(), 10.0, 8).unwrap();
            let nightly = motion.cameras(&base(), 10.0, 32).unwrap();
            assert_eq!(quick[..], nightly[..quick.len()], "{path}");
            assert_ne!(quick[0], quick[1], "{path} moves");
        }
    }

    #[test]
    fn keyframes_interpolate_and_hold_after_the_last() {
        let motion = spec(
            r#"{"path": "keyframes", "time_step_s": 0.5, "frames": {"quick": 4, "nightly": 4},
                "keyframes": [{"time_s": 0, "position": [0, 0, 10], "target": [0, 0, 0]},
                              {"time_s": 1, "position": [2, 0, 10], "target": [2, 0, 0]}]}"#,
        );
        let cameras = motion.cameras(&base(), 10.0, 4).unwrap();
        let xs: Vec<f64> = cameras.iter().map(|c| c.position.x).collect();
        assert_eq!(xs, [0.0, 1.0, 2.0, 2.0]);
        assert!(cameras.iter().all(|c| c.forward == DVec3::new(0.0, 0.0, -10.0)));
    }

    #[test]
    fn a_static_path_repeats_the_still_camera() {
        let cameras = spec(r#"{"path": "static"}"#).cameras(&base(), 10.0, 32).unwrap();
        assert!(cameras.iter().all(|c| *c == base()));
    }

    #[test]
    fn bad_sections_name_their_field() {
        let field = |json: &str| serde_json::from_str::<MotionSpec>(json).unwrap().check().unwrap_err().0;
        assert_eq!(field(r#"{"frames": {"quick": 1, "nightly": 8}}"#), "frames.quick");
        assert_eq!(field(r#"{"time_step_s": 0}"#), "time_step_s");
        assert_eq!(field(r#"{"path": "static", "rate": 2}"#), "rate");
        assert_eq!(field(r#"{"path": "dolly", "rate": 3}"#), "rate");
        assert_eq!(field(r#"{"path": "keyframes"}"#), "keyframes");
        assert_eq!(
            field(r#"{"keyframes": [{"time_s": 0, "position": [0,0,1], "target": [0,0,0]}]}"#),
            "keyframes"
        );
        let backwards = r#"{"path": "keyframes", "keyframes": [
            {"time_s": 1, "position": [0,0,1], "target": [0,0,0]},
            {"time_s": 1, "position": [0,0,2], "target": [0,0,0]}]}"#;
        assert_eq!(field(backwards), "keyframes[1].time_s");
    }

    #[test]
    fn a_path_through_its_target_is_refused_with_its_frame() {
        let on_target = r#"{"path": "keyframes", "keyframes": [
            {"time_s": 0, "position": [0, 0, 1], "target": [0, 0, 0]},
            {"time_s": 1, "position": [0, 0, 0], "target": [0, 0, 0]}]}"#;
        let (field, _) = serde_json::from_str::<MotionSpec>(on_target).unwrap().check().unwrap_err();
        assert_eq!(field, "keyframes[1].target", "a keyframe on its own target");
        // Each keyframe is valid; the straight line between them passes through the target.
        let motion = spec(
            r#"{"path": "keyframes", "time_step_s": 0.5, "keyframes": [
                {"time_s": 0, "position": [0, 0, 1], "target": [0, 0, 0]},
                {"time_s": 1, "position": [0, 0, -1], "target": [0, 0, 0]}]}"#,
        );
        let (field, message) = motion.cameras(&base(), 10.0, 8).unwrap_err();
        assert_eq!(field, "motion.keyframes");
        assert!(message.starts_with("frame 1: the camera's target"), "{message}");
    }
}
