//! Camera paths: a manifest's `motion` section and the camera of each frame of its sequence.
//!
//! A preset path starts at the scene's camera (the manifest's, the file's or the framing one),
//! so `"motion": {}` animates any scene: the default is a slow orbit about the camera's target.
//! The target is the manifest camera's `target`; a camera from the file has only a direction,
//! so its target is the point of the view ray nearest the centre of the scene's bounds.
//! Presets move at a rate per second from the scene's camera at time 0 and frames are
//! `time_step_s` apart, so at a rate the quick tier's sequence is the first frames of the
//! nightly one. A preset's speed can instead be stated as the pixels a frame its image moves at
//! the tier's resolution (`pixels_per_frame`, one sequence per speed): users turn and walk 4 to
//! 20 pixels a frame, far faster than the default rate. A speed means the same motion on the
//! screen in either tier, so a tier of fewer pixels turns faster. A turn's speed is its
//! background's (what lies at the target barely moves in an orbit); a dolly's is its first
//! frame's (a dolly's image moves faster as it nears the target, and stops at 90 % of the way). Keyframes give positions and targets at times and
//! are interpolated linearly between them (held after the last).

mod pick;

use aabench_renderer::scene::{Camera, number};
use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};

pub use pick::{AnimationPick, MAX_ANIMATION_START_S, Picked};

/// A manifest's `motion` section.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MotionSpec {
    #[serde(default)]
    pub path: PathKind,
    /// The preset's speed: degrees per second for `orbit` and `pan`, the share of the distance
    /// to the target covered per second for `dolly`. Omitted: [`PathKind::default_rate`].
    pub rate: Option<f64>,
    /// The preset's speeds instead, in pixels a frame at the tier's resolution, per tier: one
    /// sequence each ([`MotionSpec::paces`]).
    pub pixels_per_frame: Option<Speeds>,
    /// For `path: "keyframes"`: at least two, in increasing time.
    #[serde(default)]
    pub keyframes: Vec<Keyframe>,
    #[serde(default)]
    pub frames: SequenceFrames,
    /// Seconds between frames.
    #[serde(default = "default_time_step")]
    pub time_step_s: f64,
    /// The file's animation that plays along the path, and from when.
    pub animation: Option<AnimationPick>,
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

/// A preset's speeds in pixels a frame, per tier.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Speeds {
    pub quick: Vec<f64>,
    pub nightly: Vec<f64>,
}

/// The most speeds a tier may list, and the fastest: a turn of 64 pixels a frame crosses a
/// 256-pixel-wide frame in four.
pub const MAX_SPEEDS: usize = 4;
pub const MAX_PIXELS_PER_FRAME: f64 = 64.0;

/// How one sequence of a path moves: the preset's rate (as `MotionSpec::rate`) and the pixels a
/// frame that gives at the tier's resolution (absent for keyframes and the static path).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pace {
    pub rate: f64,
    pub pixels_per_frame: Option<f64>,
}

impl Pace {
    /// `4 px a frame` (or `1.2 px a frame`), where it has a speed.
    pub fn label(&self) -> Option<String> {
        self.pixels_per_frame.map(|px| format!("{} px a frame", short(px)))
    }
}

/// A number to at most two decimals, without trailing zeros: `4`, `0.5`, `0.13`.
pub fn short(value: f64) -> String {
    let text = format!("{value:.2}");
    text.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// Frames of the sequence's measured window per tier. Both defaults span at least the 250 ms
/// that ColorVideoVDP's temporal filters take in ([`MIN_WINDOW_S`]) at 60 frames a second.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SequenceFrames {
    pub quick: u32,
    pub nightly: u32,
}

impl Default for SequenceFrames {
    fn default() -> Self {
        Self { quick: 16, nightly: 32 }
    }
}

impl SequenceFrames {
    /// The longer tier's.
    pub fn longest(&self) -> u32 {
        self.quick.max(self.nightly)
    }
}

/// The shortest measured window that ColorVideoVDP judges as a video, in seconds: its temporal
/// filters span 250 ms, and its authors ask for at least that much footage. A shorter window
/// is scored, with a warning.
pub const MIN_WINDOW_S: f64 = 0.25;

/// One frame of a sequence: its camera and, where an animation plays, the animation's time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathFrame {
    pub camera: Camera,
    pub time: Option<f64>,
}

/// When a sequence's frames are. The warm-up's `warmup` frames come first, then the measured
/// window's; frame f of the window (negative in the warm-up) shows the path at
/// `path_start_s + f · step_s` and the animation, where one plays, at
/// `animation_start_s + f · step_s`. The still is frame 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Timeline {
    pub step_s: f64,
    pub warmup: u32,
    /// The path's time at frame 0: 0 for a preset (its camera at 0 is the scene's camera), the
    /// lead for keyframes.
    pub path_start_s: f64,
    /// The animation's time at frame 0: the manifest's `start_s` plus the lead.
    pub animation_start_s: Option<f64>,
    /// The animation's first and last keyframe times: outside them it holds a pose.
    pub animation_keys_s: Option<[f64; 2]>,
    /// How much later than the manifest's start the window begins, so that the warm-up before
    /// it moves: 0 unless keyframes or an animation would hold still through part of it.
    pub lead_s: f64,
}

impl Timeline {
    /// The path's time at frame `frame` of the window (negative in the warm-up).
    pub fn path_time(&self, frame: i64) -> f64 {
        self.path_start_s + frame as f64 * self.step_s
    }

    /// The animation's time at frame `frame`, where one plays, kept within its keyframes (it
    /// holds its first and last pose outside them, so that two frames of one pose have one
    /// time).
    pub fn animation_time(&self, frame: i64) -> Option<f64> {
        let time = self.animation_start_s? + frame as f64 * self.step_s;
        Some(self.animation_keys_s.map_or(time, |[first, last]| time.clamp(first, last.max(first))))
    }

    /// The window's frames from the warm-up's first: `-warmup..frames`.
    pub fn frames(&self, frames: u32) -> std::ops::Range<i64> {
        -i64::from(self.warmup)..i64::from(frames)
    }

    /// How messages name frame `frame`: `frame 3`, or `warm-up frame 2 of 16`.
    pub fn frame_name(&self, frame: i64) -> String {
        match frame {
            0.. => format!("frame {frame}"),
            _ => format!("warm-up frame {} of {}", frame + i64::from(self.warmup) + 1, self.warmup),
        }
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
            return fail(
                "time_step_s",
                format!("{} must be within (0, 1] seconds", number(self.time_step_s)),
            );
        }
        self.check_speeds()?;
        self.check_animation()?;
        if let Some(rate) = self.rate {
            if matches!(self.path, PathKind::Static | PathKind::Keyframes) {
                return fail("rate", format!("the {} path has no rate", self.path.name()));
            }
            let limit = if self.path == PathKind::Dolly { 1.0 } else { 360.0 };
            if !(rate.is_finite() && rate.abs() <= limit) {
                return fail("rate", format!("{} must be finite and within ±{limit}", number(rate)));
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

    fn check_animation(&self) -> Result<(), (String, String)> {
        let Some(pick) = &self.animation else { return Ok(()) };
        pick.check().map_err(|(field, message)| (format!("animation.{field}"), message))
    }

    fn check_speeds(&self) -> Result<(), (String, String)> {
        let Some(speeds) = &self.pixels_per_frame else { return Ok(()) };
        let fail = |field: String, message: String| Err((field, message));
        if matches!(self.path, PathKind::Static | PathKind::Keyframes) {
            return fail("pixels_per_frame".into(), format!("the {} path has no speed", self.path.name()));
        }
        if self.rate.is_some() {
            return fail(
                "pixels_per_frame".into(),
                "give a rate or speeds in pixels a frame, not both".into(),
            );
        }
        for (tier, list) in [("quick", &speeds.quick), ("nightly", &speeds.nightly)] {
            if !(1..=MAX_SPEEDS).contains(&list.len()) {
                let message = format!("{} speeds: give 1 to {MAX_SPEEDS}", list.len());
                return fail(format!("pixels_per_frame.{tier}"), message);
            }
            for (i, &px) in list.iter().enumerate() {
                if !(px.is_finite() && px > 0.0 && px <= MAX_PIXELS_PER_FRAME) {
                    let message =
                        format!("{} must be within (0, {MAX_PIXELS_PER_FRAME}] pixels a frame", number(px));
                    return fail(format!("pixels_per_frame.{tier}[{i}]"), message);
                }
                if list[..i].contains(&px) {
                    return fail(format!("pixels_per_frame.{tier}[{i}]"), format!("{px} is listed twice"));
                }
            }
        }
        Ok(())
    }

    /// The sequences of the path in a tier whose `speeds` the section lists (or none), for
    /// frames `height` pixels tall through a camera of vertical field `fov_y` (radians): one per
    /// speed, or one at the rate.
    pub fn paces(&self, speeds: Option<&[f64]>, fov_y: f64, height: u32) -> Vec<Pace> {
        let focal = f64::from(height) / (2.0 * (fov_y / 2.0).tan());
        let step = self.time_step_s;
        match (self.path, speeds) {
            (PathKind::Static | PathKind::Keyframes, _) => vec![Pace { rate: 0.0, pixels_per_frame: None }],
            (PathKind::Dolly, Some(speeds)) => speeds
                .iter()
                // A point at the target's depth at the frame's top edge moves h/2 · s / (1 − s)
                // when the camera covers the share s of its distance.
                .map(|&px| Pace {
                    rate: px / (f64::from(height) / 2.0 + px) / step,
                    pixels_per_frame: Some(px),
                })
                .collect(),
            (_, Some(speeds)) => speeds
                .iter()
                // A turn of ω moves the middle of the frame by f · tan ω.
                .map(|&px| Pace { rate: (px / focal).atan().to_degrees() / step, pixels_per_frame: Some(px) })
                .collect(),
            (PathKind::Dolly, None) => {
                let share = (self.rate() * step).abs();
                let pixels = (share < 1.0).then(|| f64::from(height) / 2.0 * share / (1.0 - share));
                vec![Pace { rate: self.rate(), pixels_per_frame: pixels }]
            }
            (_, None) => {
                // Beyond half the vertical field a frame, tan ω says nothing of the image (at
                // 90° it is 10¹⁷ px, at 180° 0): no nominal speed; the measured one stands.
                let turn = (self.rate() * step).to_radians().abs();
                let pixels = (turn < fov_y / 2.0).then(|| focal * turn.tan());
                vec![Pace { rate: self.rate(), pixels_per_frame: pixels }]
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

    /// The sequence's clock (`Timeline`): when its measured window starts on the path's and
    /// the animation's clocks, with `warmup` frames before it. A preset path moves at its rate
    /// at any time, so its warm-up extends it backwards; keyframes and an animation hold their
    /// first key before it, so where the warm-up would begin earlier, the window moves later
    /// by what is missing (both by the same lead, so that a camera choreographed with the
    /// animation stays in step), but never so far that the longest tier's window would run past
    /// their last key: the measured frames move first. `keys_s` is the playing animation's
    /// first and last keyframe times.
    pub fn timeline(&self, warmup: u32, keys_s: Option<[f64; 2]>) -> Timeline {
        let step = self.time_step_s;
        let (warm, window) = (f64::from(warmup) * step, f64::from(self.frames.longest() - 1) * step);
        let path_keys = (self.path == PathKind::Keyframes)
            .then(|| [self.keyframes[0].time_s, self.keyframes[self.keyframes.len() - 1].time_s]);
        let start = self.animation.as_ref().map(|pick| pick.start_s);
        // Each absolute clock's keys, relative to where the window starts without a lead.
        let clocks =
            [path_keys, start.zip(keys_s).map(|(start, [first, last])| [first - start, last - start])];
        let clocks = clocks.into_iter().flatten();
        let needed = clocks.clone().map(|[first, _]| first + warm).fold(0.0, f64::max);
        let room = clocks.map(|[_, last]| last - window).fold(f64::INFINITY, f64::min).max(0.0);
        let lead_s = needed.min(room);
        Timeline {
            step_s: step,
            warmup,
            path_start_s: if path_keys.is_some() { lead_s } else { 0.0 },
            animation_start_s: start.map(|start| start + lead_s),
            animation_keys_s: start.and(keys_s),
            lead_s,
        }
    }

    /// The cameras of the window's frames `frames` (negative in the warm-up) on `timeline`,
    /// from the scene's camera `base` whose target lies `pivot` along its view (near and far
    /// planes, field of view and up axis kept along the path), each checked by the renderer's
    /// rules: `Err` names the frame's field (`motion.keyframes` or the preset's `motion.rate`).
    pub fn cameras(
        &self,
        base: &Camera,
        pivot: f64,
        timeline: &Timeline,
        frames: std::ops::Range<i64>,
        rate: f64,
    ) -> Result<Vec<Camera>, (String, String)> {
        frames
            .map(|frame| {
                let camera = self.camera_at(base, pivot, timeline.path_time(frame), rate);
                camera.validate().map(|()| camera).map_err(|e| {
                    let field = self.field().to_string();
                    (
                        field,
                        format!("{}: the camera's {}: {}", timeline.frame_name(frame), e.field, e.message),
                    )
                })
            })
            .collect()
    }

    /// The manifest field that decides where the path's cameras go: `motion.keyframes`,
    /// `motion.pixels_per_frame` or `motion.rate`.
    pub fn field(&self) -> &'static str {
        match self.path {
            PathKind::Keyframes => "motion.keyframes",
            _ if self.pixels_per_frame.is_some() => "motion.pixels_per_frame",
            _ => "motion.rate",
        }
    }

    /// The camera at `time` seconds along the path, a preset moving at `rate` (as
    /// [`MotionSpec::rate`]). A preset's is the scene's camera itself at time 0, so that its
    /// first frame is the still frame bit for bit.
    pub fn camera_at(&self, base: &Camera, pivot: f64, time: f64, rate: f64) -> Camera {
        let target = base.position + base.forward.normalize() * pivot;
        let up = base.up.normalize();
        let turn = |seconds: f64| DQuat::from_axis_angle(up, (rate * seconds).to_radians());
        match self.path {
            PathKind::Static => *base,
            _ if time == 0.0 && self.path != PathKind::Keyframes => *base,
            PathKind::Orbit => {
                let position = target + turn(time) * (base.position - target);
                Camera { position, forward: target - position, ..*base }
            }
            PathKind::Pan => Camera { forward: turn(time) * base.forward, ..*base },
            PathKind::Dolly => {
                let position = base.position + (target - base.position) * (rate * time).min(0.9);
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

    /// The cameras of the first `frames` frames of `motion`'s window, without a warm-up.
    fn window(motion: &MotionSpec, frames: u32, rate: f64) -> Result<Vec<Camera>, (String, String)> {
        let timeline = motion.timeline(0, None);
        motion.cameras(&base(), 10.0, &timeline, timeline.frames(frames), rate)
    }

    #[test]
    fn an_empty_section_orbits_the_target_slowly_and_starts_at_the_still() {
        let motion = spec("{}");
        let cameras = window(&motion, 8, motion.rate()).unwrap();
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
        assert_eq!(window(&motion, 32, motion.rate()).unwrap().len(), 32);
    }

    #[test]
    fn the_quick_sequence_is_the_start_of_the_nightly_one() {
        for path in ["orbit", "dolly", "pan"] {
            let motion = spec(&format!(r#"{{"path": "{path}"}}"#));
            let quick = window(&motion, 8, motion.rate()).unwrap();
            let nightly = window(&motion, 32, motion.rate()).unwrap();
            assert_eq!(quick[..], nightly[..quick.len()], "{path}");
            assert_ne!(quick[0], quick[1], "{path} moves");
        }
    }

    /// Where a world point lands through `camera` in a frame `height` pixels tall (4:3), in
    /// pixels from the top left.
    fn project(camera: &Camera, height: f64, point: DVec3) -> glam::DVec2 {
        let size = glam::DVec2::new(height * 4.0 / 3.0, height);
        let clip = camera.projection(size.x / size.y) * camera.view() * point.extend(1.0);
        let ndc = glam::DVec2::new(clip.x, clip.y) / clip.w;
        glam::DVec2::new((ndc.x + 1.0) / 2.0 * size.x, (1.0 - ndc.y) / 2.0 * size.y)
    }

    #[test]
    fn speeds_in_pixels_a_frame_move_the_image_by_that_much_at_the_tiers_resolution() {
        let height = 192;
        for path in ["pan", "orbit", "dolly"] {
            let motion = spec(&format!(
                r#"{{"path": "{path}", "pixels_per_frame": {{"quick": [4], "nightly": [0.5, 4, 16]}}}}"#
            ));
            let speeds = motion.pixels_per_frame.clone().unwrap();
            assert_eq!(motion.paces(Some(&speeds.quick), base().fov_y, height).len(), 1);
            for pace in motion.paces(Some(&speeds.nightly), base().fov_y, height) {
                let px = pace.pixels_per_frame.unwrap();
                let cameras = window(&motion, 2, pace.rate).unwrap();
                // The pan and the orbit move the middle of the frame's far background (a point
                // far along the view) and the dolly a point at the target's depth at the top edge.
                let point = match path {
                    "dolly" => {
                        let top = (base().fov_y / 2.0).tan() * 10.0;
                        DVec3::new(0.0, 2.0 + top, 0.0)
                    }
                    _ => base().position + base().forward.normalize() * 1e6,
                };
                let moved = project(&cameras[1], f64::from(height), point)
                    - project(&cameras[0], f64::from(height), point);
                assert!((moved.length() - px).abs() < 0.01 * px, "{path} at {px}: {moved}");
            }
        }
        // A rate states its speed too: the default orbit's at 192 pixels tall.
        let default = spec("{}").paces(None, base().fov_y, height);
        let px = default[0].pixels_per_frame.unwrap();
        assert!((px - 0.135).abs() < 0.01, "{px}");
        assert_eq!(Pace { rate: 1.0, pixels_per_frame: Some(0.5) }.label().unwrap(), "0.5 px a frame");
        // A pan of 90° or 180° a frame moves nothing tan ω can say (10¹⁷ px, or 0): no nominal
        // speed; one just under half the field still has its own.
        // (360° a second, frames 0.25 s and 0.5 s apart.)
        for step in [0.25, 0.5] {
            let fast = spec(&format!(r#"{{"path": "pan", "rate": 360, "time_step_s": {step}}}"#));
            assert_eq!(fast.paces(None, base().fov_y, height)[0].pixels_per_frame, None, "{step} s");
        }
        // 18° a frame, under the 45° field's half.
        let brisk = spec(r#"{"path": "pan", "rate": 360, "time_step_s": 0.05}"#);
        assert!(brisk.paces(None, base().fov_y, height)[0].pixels_per_frame.unwrap() > 50.0);
    }

    #[test]
    fn keyframes_interpolate_and_hold_after_the_last() {
        let motion = spec(
            r#"{"path": "keyframes", "time_step_s": 0.5, "frames": {"quick": 4, "nightly": 4},
                "keyframes": [{"time_s": 0, "position": [0, 0, 10], "target": [0, 0, 0]},
                              {"time_s": 1, "position": [2, 0, 10], "target": [2, 0, 0]}]}"#,
        );
        let cameras = window(&motion, 4, 0.0).unwrap();
        let xs: Vec<f64> = cameras.iter().map(|c| c.position.x).collect();
        assert_eq!(xs, [0.0, 1.0, 2.0, 2.0]);
        assert!(cameras.iter().all(|c| c.forward == DVec3::new(0.0, 0.0, -10.0)));
    }

    #[test]
    fn the_window_starts_late_enough_that_the_warm_up_moves_and_early_enough_that_it_moves_itself() {
        let step = 1.0 / 60.0;
        let warm = 16.0 * step;
        let near = |a: f64, b: f64| (a - b).abs() < 1e-12;
        // An animation keyed from 0 s to 2 s, started at 0: its warm-up would hold the first
        // key, so the window starts 16 frames later and the warm-up's first frame is the key's.
        let motion = spec(r#"{"path": "static", "animation": {"name": "walk"}}"#);
        let timeline = motion.timeline(16, Some([0.0, 2.0]));
        assert!(near(timeline.lead_s, warm) && timeline.path_start_s == 0.0, "{timeline:?}");
        assert!(near(timeline.animation_time(-16).unwrap(), 0.0));
        assert!(near(timeline.animation_time(0).unwrap(), warm));
        assert!(near(timeline.animation_time(5).unwrap(), warm + 5.0 * step));
        assert_eq!(timeline.frames(8), -16..8);
        assert_eq!(
            (timeline.frame_name(-16), timeline.frame_name(-1)),
            ("warm-up frame 1 of 16".into(), "warm-up frame 16 of 16".into())
        );
        assert_eq!(timeline.frame_name(3), "frame 3");
        // Started a second in, the warm-up moves already: no lead.
        let later = spec(r#"{"path": "static", "animation": {"name": "walk", "start_s": 1}}"#);
        let timeline = later.timeline(16, Some([0.0, 2.0]));
        assert_eq!((timeline.lead_s, timeline.animation_start_s), (0.0, Some(1.0)));
        // An animation too short for the warm-up and the nightly's 32 frames: the window keeps
        // what moves, and the warm-up holds its first pose, at one time.
        let short = motion.timeline(16, Some([0.0, 0.4]));
        assert_eq!(short.lead_s, 0.0);
        assert_eq!((short.animation_time(-16), short.animation_time(-1)), (Some(0.0), Some(0.0)));
        assert_eq!(short.animation_time(30), Some(0.4), "held at its last key");
        // Between the two: as late as the longest window allows.
        let timeline = motion.timeline(16, Some([0.0, 0.6]));
        assert!(near(timeline.lead_s, 0.6 - 31.0 * step), "{timeline:?}");
        // Keyframes hold their first key before it too, and share the lead with the animation;
        // a preset's camera extends backwards and keeps its start (the still camera).
        let keys = spec(
            r#"{"path": "keyframes", "animation": {"name": "walk"},
                "keyframes": [{"time_s": 0.1, "position": [0, 0, 10], "target": [0, 0, 0]},
                              {"time_s": 3, "position": [2, 0, 10], "target": [2, 0, 0]}]}"#,
        );
        let timeline = keys.timeline(16, Some([0.0, 2.0]));
        assert!(near(timeline.lead_s, 0.1 + warm) && near(timeline.path_start_s, timeline.lead_s));
        assert!(near(timeline.animation_time(0).unwrap(), timeline.lead_s));
        let orbit = spec(r#"{"animation": {"name": "walk"}}"#).timeline(16, Some([0.0, 2.0]));
        assert!(near(orbit.lead_s, warm) && orbit.path_start_s == 0.0, "{orbit:?}");
        assert_eq!(spec("{}").timeline(16, None).lead_s, 0.0, "a preset alone needs no lead");
    }

    #[test]
    fn a_static_path_repeats_the_still_camera() {
        let cameras = window(&spec(r#"{"path": "static"}"#), 32, 0.0).unwrap();
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
        let speeds = |quick: &str| {
            format!(r#"{{"path": "pan", "pixels_per_frame": {{"quick": {quick}, "nightly": [4]}}}}"#)
        };
        assert_eq!(field(&speeds("[]")), "pixels_per_frame.quick");
        assert_eq!(field(&speeds("[4, 0]")), "pixels_per_frame.quick[1]");
        assert_eq!(field(&speeds("[4, 4]")), "pixels_per_frame.quick[1]");
        assert_eq!(field(&speeds("[65]")), "pixels_per_frame.quick[0]");
        assert_eq!(
            field(r#"{"path": "pan", "rate": 2, "pixels_per_frame": {"quick": [4], "nightly": [4]}}"#),
            "pixels_per_frame"
        );
        assert_eq!(
            field(r#"{"path": "static", "pixels_per_frame": {"quick": [4], "nightly": [4]}}"#),
            "pixels_per_frame"
        );
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
        let (field, message) = window(&motion, 8, 0.0).unwrap_err();
        assert_eq!(field, "motion.keyframes");
        assert!(message.starts_with("frame 1: the camera's target"), "{message}");
    }
}
