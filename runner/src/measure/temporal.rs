//! Temporal error along the truth's motion: each pixel of a frame followed back to where its
//! surface point lay in the frame before, and the mode's error compared there.
//!
//! **Flicker** is the mean, over the pixels seen in both frames of each consecutive pair, their
//! colour channels and the pairs, of (E_f(x) − E_{f−1}(x − v(x)))², where E = A − T is the
//! mode's error image (display code values scaled to [0, 1]), v(x) the motion of the point that
//! pixel x sees in the truth's geometry (camera and objects), and E_{f−1} is fetched bilinearly
//! between pixel centres. An error that travels with the surface — blur, a frozen texture
//! filter, a steady edge — cancels out; aliasing that crawls or shimmers, and an image that
//! stays put while the scene moves under it (lag, a frozen frame), do not.
//!
//! What lag costs is measured apart: the mode's squared error on the pixels whose point the
//! frame before could not see (off screen, or hidden behind another surface: disoccluded), on
//! the pixels at or beside a silhouette that moved (where ghosting trails), and elsewhere.
//!
//! The geometry is the renderer's probe (`SceneRenderer::prepare_geometry`): per pixel, one
//! unjittered sample's linear view depth and motion. Pixels without geometry see the background,
//! which lies at infinity: they follow the direction they look in from one camera to the other,
//! and were hidden where the frame before had geometry all around that place.
//!
//! The frame-to-frame arithmetic that every temporal measure shares lives here too: the change
//! of the error image in place (`change_of_error`, what the uncompensated instability and the
//! flicker square sum), the squared change of an image, and the means.

use aabench_renderer::scene::Camera;
use aabench_renderer::{DisplayImage, GBufferImages};
use glam::{DMat4, DVec2, DVec3, DVec4};

/// How much deeper than every surface seen around its place in the frame before a point must
/// have been, relatively, to count as hidden then.
pub const HIDDEN_DEPTH: f64 = 0.01;

/// How far apart in relative depth two neighbouring pixels must be for a silhouette to lie
/// between them.
const SILHOUETTE_DEPTH: f64 = 0.05;

/// How many pixels a silhouette must move between two frames for its pixels to count as a
/// moving edge: TAA's threshold between a still pixel and a moving one.
const MOVING: f32 = 0.01;

/// Motion is kept to this fraction of a pixel: the probe's motion is f16, whose rounding leaves
/// a still camera's motion a hair off 0 (its step is 1/1024 pixel below a pixel, 1/256 at 4 to 8
/// pixels, 1/64 at 16 to 32), and a 1/256 pixel is far finer than any error an interpolation
/// between pixel centres could show.
const MOTION_STEP: f32 = 1.0 / 256.0;

/// One frame's geometry, from the probe: per pixel, the pixels its point moved since the frame
/// before (x right, y down) and its linear view depth then, and its depth now; both depths
/// infinite where no geometry covers the pixel.
#[derive(Debug, Clone)]
pub struct Geometry {
    pub width: usize,
    pub motion: Vec<[f32; 2]>,
    pub depth_then: Vec<f64>,
    pub depth: Vec<f64>,
}

/// How fast the truth's content moves: over every frame pair, the motion from the frame before
/// of the covered pixels (those with geometry) whose point moved at all (by at least
/// `SPEED_BIN`), in pixels, and what share of the frame they are. A path's nominal speed is
/// its background's or the frame centre's; an orbit's content at the pivot moves slower, and an
/// object crossing a still view is what moves, however little of the frame it covers.
#[derive(Debug, Clone, Default)]
pub struct Speeds {
    /// Moving pixels per bin of [`SPEED_BIN`] px, the last holding everything beyond (bin 0,
    /// what stood still, stays empty).
    counts: Vec<u64>,
    max: f64,
    /// All the pixels of the frames added.
    pixels: u64,
}

/// The speed histogram's resolution, px, and its last bin's start. A pixel moves when its point
/// moved at least one bin: the probe's f16 motion leaves a still camera's a hair off 0.
const SPEED_BIN: f64 = 1.0 / 64.0;
const SPEED_BINS: usize = 64 * 512;

/// A sequence's measured speed over its moving pixels and frame pairs, px a frame.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MeasuredSpeed {
    pub median: f64,
    pub p90: f64,
    pub max: f64,
    /// The share of the frame's pixels that moved, over the frame pairs (absent in runs from
    /// before, whose median and p90 were over every covered pixel, still or not).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub moving: Option<f64>,
}

impl Speeds {
    /// Adds a frame's geometry (its motion from the frame before).
    pub fn add(&mut self, geometry: &Geometry) {
        if self.counts.is_empty() {
            self.counts = vec![0; SPEED_BINS];
        }
        self.pixels += geometry.motion.len() as u64;
        for (_, [dx, dy]) in geometry.motion.iter().enumerate().filter(|&(i, _)| geometry.covered(i)) {
            let speed = f64::from(dx.hypot(*dy));
            self.max = self.max.max(speed);
            let bin = (speed / SPEED_BIN) as usize;
            if bin > 0 {
                self.counts[bin.min(SPEED_BINS - 1)] += 1;
            }
        }
    }

    /// The median and 90th percentile of the moving pixels' speeds (each to a 64th of a pixel,
    /// the bin's middle), the fastest, and the share of the frame that moved; `None` where no
    /// pixel moved.
    pub fn measured(&self) -> Option<MeasuredSpeed> {
        let total: u64 = self.counts.iter().sum();
        let quantile = |q: f64| -> f64 {
            let rank = (q * total as f64).ceil().max(1.0) as u64;
            let mut seen = 0;
            let bin = self.counts.iter().position(|&c| {
                seen += c;
                seen >= rank
            });
            ((bin.unwrap_or(0) as f64 + 0.5) * SPEED_BIN).min(self.max)
        };
        let moving = Some(total as f64 / self.pixels.max(1) as f64);
        (total > 0).then(|| MeasuredSpeed {
            median: quantile(0.5),
            p90: quantile(0.9),
            max: self.max,
            moving,
        })
    }
}

/// Why the frame before did not see a pixel's point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Unseen {
    /// It lay outside that frame, or behind its camera.
    Entered,
    /// Another surface hid it.
    Hidden,
}

/// Where a pixel's point lay in the frame before: the pixel centres around it, left and above,
/// and its offsets from them, in pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Source {
    x: u32,
    y: u32,
    fx: f32,
    fy: f32,
}

/// How each pixel of a frame follows back into the frame before, by the truth's geometry.
#[derive(Debug, Clone)]
pub struct Flow {
    width: usize,
    height: usize,
    /// Per pixel, where its point lay, or `None` where the frame before did not see it.
    from: Vec<Option<Source>>,
    /// Per pixel, whether its point lay off the frame before (outside it, or behind its
    /// camera): content that enters, which no history can hold.
    entered: Vec<bool>,
    /// Per pixel, whether it lies at or beside a silhouette that moved.
    edge: Vec<bool>,
    /// The shares of pixels whose point entered from off screen, and that the frame before
    /// had hidden behind another surface (disoccluded).
    entered_share: f64,
    disoccluded: f64,
}

/// One mode's error over one frame pair, in sums of squared display values and their counts.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PairError {
    /// Σ (E_f(x) − E_{f−1}(x − v))² over the followed pixels' colour channels, and their number.
    pub flicker: (f64, u64),
    /// Σ (A − T)² of frame f over the colour channels of the pixels that entered from off
    /// screen, of the disoccluded ones, of the pixels at moving edges (followed ones), and of
    /// the other followed pixels; each with its count.
    pub entered: (f64, u64),
    pub disoccluded: (f64, u64),
    pub edges: (f64, u64),
    pub elsewhere: (f64, u64),
}

impl PairError {
    /// Adds another pair's sums.
    pub fn add(&mut self, other: &PairError) {
        for (sum, more) in [
            (&mut self.flicker, other.flicker),
            (&mut self.entered, other.entered),
            (&mut self.disoccluded, other.disoccluded),
            (&mut self.edges, other.edges),
            (&mut self.elsewhere, other.elsewhere),
        ] {
            *sum = (sum.0 + more.0, sum.1 + more.1);
        }
    }
}

/// A sum over a count, where there is a count.
pub fn mean((sum, count): (f64, u64)) -> Option<f64> {
    (count > 0).then(|| sum / count as f64)
}

/// The mean of `values`, where there are any.
pub fn mean_of(values: &[f64]) -> Option<f64> {
    (!values.is_empty()).then(|| values.iter().sum::<f64>() / values.len() as f64)
}

/// Σ over pixels and colour channels (alpha left out) of ((a − b) − (t − u))² of four RGBA
/// images of one size (code values of any width), in squared code steps: how much the error
/// image a − t changed from the frame (b, u) before, pixel by pixel in place.
pub fn change_of_error<T: Copy + Into<i64>>(a: &[T], b: &[T], t: &[T], u: &[T]) -> u64 {
    pixel_changes_of_error(a, b, t, u).sum()
}

/// [`change_of_error`] pixel by pixel.
pub fn pixel_changes_of_error<'x, T: Copy + Into<i64>>(
    a: &'x [T],
    b: &'x [T],
    t: &'x [T],
    u: &'x [T],
) -> impl Iterator<Item = u64> + 'x {
    assert!([b, t, u].iter().all(|i| i.len() == a.len()), "images of different sizes");
    let step = |x: T, y: T| x.into() - y.into();
    let pixels = a.chunks_exact(4).zip(b.chunks_exact(4)).zip(t.chunks_exact(4).zip(u.chunks_exact(4)));
    pixels.map(move |((p, q), (r, s))| {
        (0..3).map(|i| (step(p[i], q[i]) - step(r[i], s[i])).pow(2) as u64).sum()
    })
}

/// Σ over pixels and colour channels (alpha left out) of (a − b)² of two display images of
/// one size, in squared code steps (exact in integers).
pub fn squared_difference(a: &DisplayImage, b: &DisplayImage) -> u64 {
    assert_eq!(a.rgba.len(), b.rgba.len(), "images of different sizes");
    let pixel = |p: &[u16], q: &[u16]| (0..3).map(|c| u64::from(p[c].abs_diff(q[c])).pow(2)).sum::<u64>();
    a.rgba.chunks_exact(4).zip(b.rgba.chunks_exact(4)).map(|(p, q)| pixel(p, q)).sum()
}

/// A sum of squared code steps over `frames` images like `image`, as a mean over values in
/// [0, 1].
pub fn per_value(sum: u64, image: &DisplayImage, frames: usize) -> f64 {
    let scale = f64::from(image.max_code());
    let values = (image.rgba.len() / 4 * 3 * frames).max(1) as f64;
    sum as f64 / (scale * scale) / values
}

impl Geometry {
    /// From the probe's G-buffer and motion (`read_gbuffer`, `read_motion`) of the frame seen
    /// through `now`, whose frame before was seen through `then`.
    pub fn from_probe(gbuffer: &GBufferImages, motion: &[[f32; 4]], [now, then]: [&Camera; 2]) -> Geometry {
        let width = gbuffer.width as usize;
        let size = DVec2::new(f64::from(gbuffer.width), f64::from(gbuffer.height));
        let turn = Turn::new(now, then, size);
        let mut geometry = Geometry { width, motion: Vec::new(), depth_then: Vec::new(), depth: Vec::new() };
        for (i, (sample, &[dx, dy, depth_then, _])) in gbuffer.normal_material.iter().zip(motion).enumerate()
        {
            // The background's material index is negative (`BACKGROUND_MATERIAL`).
            let (motion, depth_then, depth) = if sample[3] < 0.0 {
                let pixel = DVec2::new((i % width) as f64 + 0.5, (i / width) as f64 + 0.5);
                let moved = pixel - turn.then(pixel);
                ([moved.x as f32, moved.y as f32], f64::INFINITY, f64::INFINITY)
            } else {
                ([dx, dy], f64::from(depth_then), gbuffer.depth[i])
            };
            let motion = motion.map(|v| (v / MOTION_STEP).round() * MOTION_STEP);
            geometry.motion.push(motion);
            geometry.depth_then.push(depth_then);
            geometry.depth.push(depth);
        }
        geometry
    }

    fn height(&self) -> usize {
        self.motion.len() / self.width.max(1)
    }

    fn covered(&self, i: usize) -> bool {
        self.depth[i].is_finite()
    }

    /// Where pixel `i`'s point lay in the frame `then`, where `then` saw it: inside the frame
    /// and no deeper than the surfaces around that place by more than [`HIDDEN_DEPTH`]; else
    /// why it did not see it.
    fn source(&self, i: usize, then: &Geometry) -> Result<Source, Unseen> {
        let (width, height) = (self.width as f64, self.height() as f64);
        let [dx, dy] = self.motion[i];
        let x = (i % self.width) as f64 + 0.5 - f64::from(dx);
        let y = (i / self.width) as f64 + 0.5 - f64::from(dy);
        if !(0.0..width).contains(&x) || !(0.0..height).contains(&y) {
            return Err(Unseen::Entered);
        }
        // The pixel centres around the point, clamped to the frame.
        let (cx, cy) = ((x - 0.5).clamp(0.0, width - 1.0), (y - 0.5).clamp(0.0, height - 1.0));
        let (x0, y0) = (cx.floor().min(width - 2.0).max(0.0), cy.floor().min(height - 2.0).max(0.0));
        let source = Source { x: x0 as u32, y: y0 as u32, fx: (cx - x0) as f32, fy: (cy - y0) as f32 };
        // Corners of no weight are left out: a point on a pixel's centre is that pixel's. The
        // background (infinitely deep) was hidden where geometry covered every corner.
        let depth_then = self.depth_then[i];
        if depth_then <= 0.0 {
            // The point lay behind the camera of the frame before.
            return Err(Unseen::Entered);
        }
        let corners = source.corners(self.width, self.height());
        let mut around = corners.iter().filter(|&&(_, weight)| weight > 0.0);
        let hidden =
            around.all(|&(j, _)| then.covered(j) && depth_then > then.depth[j] * (1.0 + HIDDEN_DEPTH));
        if hidden { Err(Unseen::Hidden) } else { Ok(source) }
    }

    /// Whether a silhouette lies between pixels `i` and `j`: one has no geometry and the other
    /// has, or their depths differ by more than [`SILHOUETTE_DEPTH`] relatively.
    fn apart(&self, i: usize, j: usize) -> bool {
        match (self.covered(i), self.covered(j)) {
            (true, true) => {
                (self.depth[i] - self.depth[j]).abs() > SILHOUETTE_DEPTH * self.depth[i].min(self.depth[j])
            }
            (covered_i, covered_j) => covered_i != covered_j,
        }
    }

    /// Per pixel, whether it lies at or beside (within one pixel of) a silhouette that moved:
    /// one between two neighbouring pixels, either of which moved by at least [`MOVING`]
    /// pixels (an object that slides over a still background moves on one side only, the
    /// leading or the trailing).
    fn moving_edges(&self) -> Vec<bool> {
        let (width, height) = (self.width, self.height());
        let moved = |i: usize| {
            let [dx, dy] = self.motion[i];
            dx.hypot(dy) >= MOVING
        };
        let moving_pair = |i: usize, j: usize| self.apart(i, j) && (moved(i) || moved(j));
        let silhouette: Vec<bool> = (0..width * height)
            .map(|i| {
                let (x, y) = (i % width, i / width);
                (x + 1 < width && moving_pair(i, i + 1)) || (y + 1 < height && moving_pair(i, i + width))
            })
            .collect();
        (0..width * height)
            .map(|i| {
                let (x, y) = (i % width, i / width);
                let rows = y.saturating_sub(1)..(y + 2).min(height);
                rows.flat_map(|ny| (x.saturating_sub(1)..(x + 2).min(width)).map(move |nx| ny * width + nx))
                    .any(|j| silhouette[j])
            })
            .collect()
    }
}

/// Where the direction seen at `pixel` through `now` (in a frame of `size` pixels) lay in the
/// frame seen through `then`: the motion of the background, which lies at infinity.
/// Where a direction seen through one camera shows through another, in a frame of `size`
/// pixels: how the background, which lies at infinity, moved. Its matrices are made once a frame.
struct Turn {
    size: DVec2,
    tan_y: f64,
    world_from_now: DMat4,
    clip_then: DMat4,
}

impl Turn {
    fn new(now: &Camera, then: &Camera, size: DVec2) -> Turn {
        Turn {
            size,
            tan_y: (now.fov_y * 0.5).tan(),
            world_from_now: now.view().inverse(),
            clip_then: then.projection(size.x / size.y) * then.view(),
        }
    }

    /// Where the direction seen at `pixel` now lay in the frame before, in pixels.
    fn then(&self, pixel: DVec2) -> DVec2 {
        let (size, tan_y) = (self.size, self.tan_y);
        let ndc = DVec2::new(pixel.x / size.x * 2.0 - 1.0, 1.0 - pixel.y / size.y * 2.0);
        let ray = DVec3::new(ndc.x * tan_y * size.x / size.y, ndc.y * tan_y, -1.0);
        let clip = self.clip_then * (self.world_from_now * DVec4::from((ray, 0.0)));
        let ndc = DVec2::new(clip.x, clip.y) / clip.w;
        DVec2::new((ndc.x + 1.0) / 2.0 * size.x, (1.0 - ndc.y) / 2.0 * size.y)
    }
}

/// An image's display values, per pixel and channel, scaled to [0, 1].
fn values(image: &DisplayImage) -> impl Fn(usize, usize) -> f32 + '_ {
    let scale = 1.0 / f32::from(image.max_code().max(1));
    move |j, c| f32::from(image.rgba[4 * j + c]) * scale
}

impl Source {
    /// The four pixels around the point and their bilinear weights.
    fn corners(self, width: usize, height: usize) -> [(usize, f32); 4] {
        let (x0, y0) = (self.x as usize, self.y as usize);
        let (x1, y1) = ((x0 + 1).min(width - 1), (y0 + 1).min(height - 1));
        let (fx, fy) = (self.fx, self.fy);
        [
            (y0 * width + x0, (1.0 - fx) * (1.0 - fy)),
            (y0 * width + x1, fx * (1.0 - fy)),
            (y1 * width + x0, (1.0 - fx) * fy),
            (y1 * width + x1, fx * fy),
        ]
    }
}

impl Flow {
    /// How the frame of geometry `now` follows back into the frame of geometry `then`.
    pub fn between(now: &Geometry, then: &Geometry) -> Flow {
        assert_eq!(now.motion.len(), then.motion.len(), "geometries of different sizes");
        let sources: Vec<Result<Source, Unseen>> =
            (0..now.motion.len()).map(|i| now.source(i, then)).collect();
        let share = |unseen: Unseen| {
            sources.iter().filter(|s| s.err() == Some(unseen)).count() as f64 / sources.len().max(1) as f64
        };
        let (entered_share, disoccluded) = (share(Unseen::Entered), share(Unseen::Hidden));
        let entered = sources.iter().map(|s| s.err() == Some(Unseen::Entered)).collect();
        let from = sources.into_iter().map(Result::ok).collect();
        let (width, height, edge) = (now.width, now.height(), now.moving_edges());
        Flow { width, height, from, entered, edge, entered_share, disoccluded }
    }

    /// The share of pixels whose point the frame before had hidden behind another surface.
    pub fn disoccluded_share(&self) -> f64 {
        self.disoccluded
    }

    /// The share of pixels whose point lay off the frame before.
    pub fn entered_share(&self) -> f64 {
        self.entered_share
    }

    /// A mode's error over the frame pair: its image and the truth's now (`a`, `t`) and in the
    /// frame before (`a_then`, `t_then`). Each followed pixel's squared change of error is also
    /// added to `per_pixel`.
    pub fn error(
        &self,
        [a, t]: [&DisplayImage; 2],
        [a_then, t_then]: [&DisplayImage; 2],
        per_pixel: &mut [f64],
    ) -> PairError {
        let (mode, truth) = (values(a), values(t));
        let (mode_then, truth_then) = (values(a_then), values(t_then));
        let error = |j: usize, c: usize| mode(j, c) - truth(j, c);
        let error_then = |j: usize, c: usize| mode_then(j, c) - truth_then(j, c);
        self.follow(error, error_then, Some(per_pixel))
    }

    /// The truth's own change along the motion, from `t_then` to `t`: the flicker of a blank
    /// image (its error is the truth's negative), and so the scale of the modes' flicker where
    /// the truth's fine detail aliases into moiré that no interpolation predicts.
    pub fn own_change(&self, t: &DisplayImage, t_then: &DisplayImage) -> (f64, u64) {
        self.follow(values(t), values(t_then), None).flicker
    }

    /// Follows an error image from the frame before (`then`, per pixel and channel) into this
    /// one (`now`).
    fn follow(
        &self,
        now: impl Fn(usize, usize) -> f32,
        then: impl Fn(usize, usize) -> f32,
        mut per_pixel: Option<&mut [f64]>,
    ) -> PairError {
        let mut sums = PairError::default();
        for (i, from) in self.from.iter().enumerate() {
            let error = [0, 1, 2].map(|c| now(i, c));
            let squared = error.iter().map(|e| f64::from(e * e)).sum::<f64>();
            let Some(from) = from else {
                let sum = if self.entered[i] { &mut sums.entered } else { &mut sums.disoccluded };
                *sum = (sum.0 + squared, sum.1 + 3);
                continue;
            };
            let corners = from.corners(self.width, self.height);
            let change: f64 = (0..3)
                .map(|c| {
                    let before: f32 = corners.iter().map(|&(j, w)| w * then(j, c)).sum();
                    f64::from(error[c] - before).powi(2)
                })
                .sum();
            if let Some(map) = per_pixel.as_deref_mut() {
                map[i] += change;
            }
            sums.flicker = (sums.flicker.0 + change, sums.flicker.1 + 3);
            let place = if self.edge[i] { &mut sums.edges } else { &mut sums.elsewhere };
            *place = (place.0 + squared, place.1 + 3);
        }
        sums
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A geometry of `width` × `height` pixels at depth `depth` (infinite: none), every point moved by
    /// `motion` pixels and as deep before.
    fn flat(width: usize, height: usize, depth: f64, motion: [f32; 2]) -> Geometry {
        let pixels = width * height;
        Geometry {
            width,
            motion: vec![motion; pixels],
            depth_then: vec![depth; pixels],
            depth: vec![depth; pixels],
        }
    }

    /// A grey image whose pixel (x, y) is `value(x, y)`.
    fn image(width: usize, height: usize, value: impl Fn(usize, usize) -> u16) -> DisplayImage {
        let rgba = (0..width * height)
            .flat_map(|i| {
                let v = value(i % width, i / width);
                [v, v, v, 255]
            })
            .collect();
        DisplayImage { bits: 8, rgba }
    }

    #[test]
    fn the_measured_speed_is_the_moving_covered_pixels_and_an_empty_frame_has_none() {
        let (w, h) = (10, 10);
        // Half the frame: an object moving 3 px right and 4 down (5 px); the other half: the
        // background, without geometry, turning 40 px a frame. Only the object counts.
        let mut geometry = flat(w, h, 5.0, [3.0, 4.0]);
        for i in 0..w * h / 2 {
            (geometry.depth[i], geometry.motion[i]) = (f64::INFINITY, [40.0, 0.0]);
        }
        // A slower object in one row of the covered half: 1 px.
        for i in w * h / 2..w * h / 2 + w {
            geometry.motion[i] = [1.0, 0.0];
        }
        let mut speeds = Speeds::default();
        speeds.add(&geometry);
        let measured = speeds.measured().unwrap();
        assert!((measured.median - 5.0).abs() <= 1.0 / 64.0, "{measured:?}");
        assert!((measured.p90 - 5.0).abs() <= 1.0 / 64.0 && measured.max == 5.0, "{measured:?}");
        assert_eq!(measured.moving, Some(0.5), "the covered half moved");
        let still = flat(w, h, 5.0, [0.0, 0.0]);
        assert_eq!(Speeds::default().measured(), None, "nothing added");
        let mut empty = Speeds::default();
        empty.add(&Geometry { depth: vec![f64::INFINITY; w * h], ..still.clone() });
        assert_eq!(empty.measured(), None, "an empty frame has no covered pixel");
        let mut standing = Speeds::default();
        standing.add(&flat(w, h, 5.0, [0.5 / 1024.0, 0.0]));
        assert_eq!(standing.measured(), None, "f16's hair off 0 is no motion");
        // A still frame beside it: the object is still what moves, at its own speed, over a
        // quarter of the two frames' pixels (where the speed of every covered pixel would
        // have put the median at 0).
        speeds.add(&still);
        let measured = speeds.measured().unwrap();
        assert!((measured.median - 5.0).abs() <= 1.0 / 64.0, "{measured:?}");
        assert_eq!(measured.moving, Some(0.25));
    }

    #[test]
    fn an_error_that_moves_with_the_surface_does_not_flicker_and_one_that_stays_does() {
        let (w, h) = (12, 6);
        // The scene moves 2 pixels right; the truth is a ramp that moves with it.
        let geometry = flat(w, h, 5.0, [2.0, 0.0]);
        let flow = Flow::between(&geometry, &geometry);
        let truth = |shift: usize| image(w, h, move |x, _| (10 * (x + 10 - shift)) as u16);
        let (t_then, t_now) = (truth(0), truth(2));
        // A mode whose error (+8 where x + 10 − shift is even) travels with the ramp.
        let moving = |shift: usize| {
            image(w, h, move |x, _| (10 * (x + 10 - shift) + 8 * ((x + 10 - shift) % 2)) as u16)
        };
        let mut map = vec![0.0; w * h];
        let travelling = flow.error([&moving(2), &t_now], [&moving(0), &t_then], &mut map);
        // Its frame before, kept: the frozen frame.
        let frozen = flow.error([&moving(0), &t_now], [&moving(0), &t_then], &mut map);
        // Pixels 0 and 1 of each row came from outside the frame: entered, not disoccluded.
        assert_eq!(travelling.entered.1, 2 * h as u64 * 3);
        assert_eq!(travelling.disoccluded.1, 0);
        assert_eq!(travelling.flicker.1, (w - 2) as u64 * h as u64 * 3);
        assert_eq!(mean(travelling.flicker), Some(0.0), "the error went with the surface");
        let frozen_flicker = mean(frozen.flicker).unwrap();
        assert!(frozen_flicker > 0.005, "a frozen frame's error changes along the motion: {frozen_flicker}");
        assert!(map.iter().any(|&v| v > 0.0));
    }

    #[test]
    fn the_background_follows_the_cameras_turn_and_is_hidden_where_geometry_covered_it() {
        use glam::{DQuat, DVec3};
        let (w, h) = (64usize, 48usize);
        let then = Camera::look_at(DVec3::ZERO, DVec3::new(0.0, 0.0, -1.0), 60.0);
        // The view turns left by a twelfth of its vertical field: the background moves right.
        let turn = DQuat::from_rotation_y(5f64.to_radians());
        let now = Camera { forward: turn * then.forward, ..then };
        let sky = GBufferImages {
            width: w as u32,
            height: h as u32,
            normal_material: vec![[0.0, 0.0, 0.0, -1.0]; w * h],
            depth: vec![1.0; w * h],
        };
        let geometry = Geometry::from_probe(&sky, &vec![[0.0; 4]; w * h], [&now, &then]);
        let [dx, dy] = geometry.motion[h / 2 * w + w / 2];
        // tan(5°) / tan(30°) of half the height, to the motion's step.
        let expected = (5f64.to_radians().tan() / 30f64.to_radians().tan() * h as f64 / 2.0) as f32;
        assert!((dx - expected).abs() < 0.01 && dy.abs() < 0.01, "({dx}, {dy}) against {expected}");
        assert!(geometry.depth.iter().all(|d| d.is_infinite()));
        // Where the frame before had geometry all around, the background was hidden.
        let covered = flat(w, h, 3.0, [0.0, 0.0]);
        let flow = Flow::between(&geometry, &covered);
        assert_eq!(flow.disoccluded_share() + flow.entered_share(), 1.0);
        assert!(flow.disoccluded_share() > 0.8, "hidden, but for what entered at the edges");
        // Against itself, only what came in at the left edge was unseen (off screen), and at
        // the top and bottom rows, where the turn also moves the view's corners vertically.
        let flow = Flow::between(&geometry, &geometry);
        let unseen: Vec<usize> = (0..w * h).filter(|&i| flow.from[i].is_none()).collect();
        let at_an_edge = |i: &usize| i % w < 6 || i / w == 0 || i / w == h - 1;
        assert!(unseen.len() >= 2 * h && unseen.iter().all(at_an_edge), "{unseen:?}");
    }

    #[test]
    fn a_point_behind_a_nearer_surface_then_is_disoccluded_and_silhouettes_that_move_are_edges() {
        let (w, h) = (8, 4);
        // Now: every pixel at depth 10, moved one pixel right since the frame before.
        let now = flat(w, h, 10.0, [1.0, 0.0]);
        // Then: a nearer surface covered columns 2–4.
        let mut then = flat(w, h, 10.0, [0.0, 0.0]);
        for y in 0..h {
            for x in 2..5 {
                then.depth[y * w + x] = 4.0;
            }
        }
        let flow = Flow::between(&now, &then);
        let hidden: Vec<usize> = (0..w).filter(|&x| flow.from[x].is_none()).collect();
        // Column 0 came from off screen; columns 3–5 from the centres of columns 2–4, behind
        // the nearer surface.
        assert_eq!(hidden, [0, 3, 4, 5], "{:?}", flow.from[..w].to_vec());
        assert_eq!((flow.entered_share(), flow.disoccluded_share()), (1.0 / 8.0, 3.0 / 8.0));
        // A point that lay behind the camera then (its depth then negative) was not seen.
        let mut behind = now.clone();
        behind.depth_then[7] = -3.0;
        assert!(Flow::between(&behind, &then).from[7].is_none());
        // A silhouette between columns 3 and 4 that moved, marked on column 3: columns 2–4 lie
        // at or beside it.
        let mut edge = flat(w, h, 10.0, [1.0, 0.0]);
        for y in 0..h {
            for x in 0..4 {
                edge.depth[y * w + x] = 4.0;
            }
        }
        let edges: Vec<usize> = (0..w).filter(|&x| edge.moving_edges()[x]).collect();
        assert_eq!(edges, [2, 3, 4]);
        let still = Geometry { motion: vec![[0.0; 2]; w * h], ..edge.clone() };
        assert!(still.moving_edges().iter().all(|&e| !e), "a silhouette that did not move");
        // An object in columns 4–7 slides right over a still background: the silhouette's
        // left (background) side did not move, its right side did. It is a moving edge all the
        // same: the trailing edge, where the background reappears.
        let mut trailing = still.clone();
        for y in 0..h {
            for x in 4..w {
                trailing.motion[y * w + x] = [1.0, 0.0];
            }
        }
        let edges: Vec<usize> = (0..w).filter(|&x| trailing.moving_edges()[x]).collect();
        assert_eq!(edges, [2, 3, 4], "the trailing silhouette between columns 3 and 4");
    }
}
