//! The adaptive supersampling algorithm of Holländer, Boubekeur & Eisemann (2013), CPU side:
//! the ordered-dither sample order, the settings, and a CPU twin of the per-pixel sample-count
//! metric that the GPU's `evaluate` pass computes. The twin is the specification the shader is
//! tested against, in f64 where the shader works in f32.

/// The paper's Fig. 3 index matrices, row-major: the rank of each cell of the M×M window.
/// Samples are shaded in rank order, so any prefix of ranks is spread over the window.
pub const DITHER_2: [u32; 4] = [0, 2, 3, 1];
pub const DITHER_3: [u32; 9] = [2, 6, 3, 5, 0, 8, 1, 7, 4];
pub const DITHER_4: [u32; 16] = [1, 8, 2, 10, 12, 4, 14, 6, 3, 11, 0, 9, 15, 7, 13, 5];

/// The dither matrix for M, or `None` outside 2..=4.
pub fn dither_matrix(m: u32) -> Option<&'static [u32]> {
    match m {
        2 => Some(&DITHER_2),
        3 => Some(&DITHER_3),
        4 => Some(&DITHER_4),
        _ => None,
    }
}

/// Bits of a list entry per G-buffer texel coordinate (`shaders/adaptive.wgsl`: list_entry):
/// two coordinates and n − 1 < 16 fill 32 bits, so the G-buffer of a listed mode is at most
/// 2¹⁴ = 16 384 texels on a side (lavapipe's largest texture side).
pub const LIST_TEXEL_BITS: u32 = 14;
const _: () = assert!(2 * LIST_TEXEL_BITS + 4 <= 32, "two coordinates and n − 1 < 16 fill 32 bits");

/// Rank → window cell (row-major index `y·M + x`): the inverse permutation of the matrix. The
/// shaders get it as [`packed_sample_order`], so it is defined once, here.
pub fn sample_order(m: u32) -> Vec<u32> {
    let matrix = dither_matrix(m).unwrap_or(&[0]);
    let mut order = vec![0; matrix.len()];
    for (cell, &rank) in matrix.iter().enumerate() {
        order[rank as usize] = cell as u32;
    }
    order
}

/// [`sample_order`] as two words of eight 4-bit cells each, rank 0 in the lowest bits of the
/// first: the shaders' `ORDER_LOW` and `ORDER_HIGH` constants. Decoding them is a shift and a
/// mask, where a table in a storage buffer cost a load per sample of S and per list entry.
pub fn packed_sample_order(m: u32) -> [u32; 2] {
    pack_nibbles(&sample_order(m))
}

/// The dither matrix (window cell → rank) packed as [`packed_sample_order`] is: the shaders'
/// `RANK_LOW` and `RANK_HIGH`.
pub fn packed_dither_matrix(m: u32) -> [u32; 2] {
    pack_nibbles(dither_matrix(m).unwrap_or(&[0]))
}

/// Up to sixteen values below 16, eight to a word, the first in the lowest bits.
fn pack_nibbles(values: &[u32]) -> [u32; 2] {
    let mut words = [0u32; 2];
    for (i, &value) in values.iter().enumerate() {
        words[i / 8] |= value << (4 * (i % 8));
    }
    words
}

/// How a pixel's samples stand for it (a mode's `-area` or `-cells` suffix picks the variant).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Reconstruction {
    /// Every sample alike, as the paper does.
    Equal,
    /// Each sample by the area of the pixel nearer to it than to the pixel's other samples (its
    /// Voronoi cell within the pixel): a lopsided prefix such as 3×3's centre and lower-left
    /// corner no longer lets the corner stand for half the pixel. A pixel with one sample or all
    /// M² is averaged exactly as under `Equal`.
    Area,
    /// Each sample stands for its cell as a whole: weighted by the cell's area, shaded at the
    /// cell's centroid on the sample's tangent plane, its textures filtered over a square of the
    /// cell's area. One sample is then the pixel's centre with the pixel's footprint, as in
    /// deferred shading, at every M; a texture edge inside a pixel of n samples is filtered
    /// rather than point-sampled n times. The first sample of a pixel that takes more than one
    /// is shaded again for its own cell instead of reusing S, which stands for the whole pixel.
    /// Its shading metric also counts texture contrast below the pixel and bounds specular
    /// highlights from the lights (`shaders/adaptive.wgsl`: `texture_range`, `specular_range`).
    Cells,
    /// Beyond the paper's prefix: the M² samples of the G-buffer are grouped into the surfaces
    /// they lie on (material, normal, tangent plane: [`SURFACE_COS`], [`SURFACE_GAP`]); each
    /// surface is shaded once, at its sample nearest to its cells' centroid, and more samples
    /// are shaded where the shading metric asks (the first of the dither order). Every sample
    /// is stood for by the nearest shaded sample of its surface, which is shaded at the
    /// centroid of the samples it stands for and weighted by their share of the pixel: thin
    /// geometry counts by its coverage, as under per-sample edge shading (Lauritzen 2010) and
    /// surface-based anti-aliasing (Salvi & Vidimče 2012). Where a base-colour texture varies
    /// inside the pixel, a shaded sample's light is carried to the mean albedo of its samples,
    /// each read as the reference reads it (shading is affine in albedo): textures are filtered
    /// at the reference's rate while light is shaded at the surfaces' rate. A pixel on one
    /// surface with nothing more asked reuses S. Its shading metric bounds highlights from the
    /// lights as under `Cells`.
    Coverage,
}

/// Two samples of a window lie on one surface for `-coverage` when their normals' cosine is at
/// least this: 14°.
pub const SURFACE_COS: f32 = 0.97;

/// … and the second lies within this fraction of the first's depth from the first's tangent
/// plane.
pub const SURFACE_GAP: f32 = 0.01;

impl Reconstruction {
    /// Whether a pixel of `n` of `m`² samples reads [`sample_cells`] rather than averaging
    /// alike.
    pub fn weighted(self, m: u32, n: u32) -> bool {
        self != Reconstruction::Equal && n > 1 && n < m * m
    }

    /// Whether a pixel of `n` of `m`² samples shades its first sample again instead of
    /// reusing S: every full window does (to equal the reference), and under `Cells` and
    /// `Coverage` every pixel of more than one sample.
    pub fn reshades_first(self, m: u32, n: u32) -> bool {
        n == m * m || (matches!(self, Reconstruction::Cells | Reconstruction::Coverage) && n > 1)
    }
}

/// Where an adaptive mode's sample counts come from (a mode's `-stable` suffix picks `Stable`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Counts {
    /// From this frame's metric alone, as the paper does.
    PerFrame,
    /// The paper's future work (after Herzog et al. 2010): this frame's metric and the count
    /// the pixel's surface had in the frame before, reprojected along the camera's motion and
    /// carried between frames. See [`StableCounts`] for the rule. At a still camera the counts
    /// are the paper's, bit for bit.
    Stable,
}

/// How a `-stable` mode combines the count `now` that this frame's metric asks for with the
/// count `before` that the pixel's surface had in the frame before (both in samples, 1…M²): a
/// count rises at once to what the metric asks; it falls only where the metric asks for more
/// than [`Self::hold`] of the window fewer, and then to no less than 1 − [`Self::decay`] of
/// itself a frame. A metric that wavers by a few samples as detail slides through the window
/// leaves the count, and so the pixel's samples, as they were; a feature that leaves the pixel
/// hands its samples back over a few frames, 16 → 8 → 4 → 2 → 1 at 4×4, through prefixes of
/// the dither order that each spread evenly over the window. `shaders/adaptive.wgsl`
/// (evaluate_stable) computes this; [`Self::next`] is its CPU twin. `docs/adaptive.md`
/// measures the choices.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StableCounts {
    /// The share of the window's M² samples that the metric may ask for fewer than the count
    /// before without the count falling.
    pub hold: f32,
    /// The most a count falls in one frame, as a share of itself: 1 drops it to the metric's at
    /// once, 0 never lets it fall.
    pub decay: f32,
}

impl Default for StableCounts {
    fn default() -> Self {
        StableCounts { hold: STABLE_HOLD, decay: STABLE_DECAY }
    }
}

/// [`StableCounts::hold`] of the shipped `-stable` modes: 6 samples at 4×4.
pub const STABLE_HOLD: f32 = 0.375;
/// [`StableCounts::decay`] of the shipped `-stable` modes: a count halves at most, each frame.
pub const STABLE_DECAY: f32 = 0.5;

/// How much deeper, relative to it, than the deepest sample of the pixel whose count it takes a
/// `-stable` pixel's nearest point may have lain in the frame before: deeper, the point was
/// hidden there (a disocclusion), and the metric's count is taken alone.
pub const STABLE_DEPTH_TOLERANCE: f32 = 0.01;

impl StableCounts {
    /// The samples below the count before that the metric may ask for at `m`×`m` without the
    /// count falling.
    pub fn hold_samples(self, m: u32) -> f32 {
        self.hold * (m * m) as f32
    }

    /// The count a `-stable` pixel of an `m`×`m` window takes (rounded up to whole samples where
    /// the decay leaves it between two), from the metric's count `now` and the count its
    /// surface had in the frame before, where the history holds it.
    pub fn next(self, m: u32, now: f32, before: Option<f32>) -> f32 {
        match before {
            None => now,
            Some(before) if now >= before - self.hold_samples(m) => now.max(before),
            Some(before) => now.max(before * (1.0 - self.decay)),
        }
    }
}

/// One sample's cell in a prefix of the dither order: the part of the pixel nearer to it than
/// to the prefix's other samples.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SampleCell {
    /// The cell's share of the pixel.
    pub weight: f32,
    /// The cell's centroid less the sample's position, in G-buffer texels.
    pub centroid: [f32; 2],
    /// The side of a square of the cell's area, in G-buffer texels: M for a whole pixel, 1 for
    /// one texel's cell (the reference's footprint).
    pub footprint: f32,
}

/// The cells of every prefix of the M×M dither order: entry `(n − 1)·M² + rank` is the cell of
/// the sample of `rank` among the first n (all zero past n). Each row's weights sum to 1.
/// Cells are found exactly, by clipping the pixel with the bisector of each pair of samples
/// (points equally near two samples, a set of measure zero, count for both). M is 2, 3 or 4.
pub fn sample_cells(m: u32) -> Vec<SampleCell> {
    assert!(dither_matrix(m).is_some(), "no dither order for M = {m}");
    let cells = (m * m) as usize;
    let order = sample_order(m);
    let centre = |rank: usize| {
        let cell = order[rank];
        [(f64::from(cell % m) + 0.5) / f64::from(m), (f64::from(cell / m) + 0.5) / f64::from(m)]
    };
    let mut table = vec![SampleCell { weight: 0.0, centroid: [0.0; 2], footprint: 0.0 }; cells * cells];
    for n in 1..=cells {
        for rank in 0..n {
            let p = centre(rank);
            let mut cell = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
            for other in (0..n).filter(|&o| o != rank) {
                cell = clip_nearer(&cell, p, centre(other));
            }
            let (area, centroid) = area_and_centroid(&cell);
            let texels = f64::from(m);
            table[(n - 1) * cells + rank] = SampleCell {
                weight: area as f32,
                centroid: [((centroid[0] - p[0]) * texels) as f32, ((centroid[1] - p[1]) * texels) as f32],
                footprint: (area.sqrt() * texels) as f32,
            };
        }
    }
    table
}

/// The weights alone of [`sample_cells`]: the `-area` variant's.
pub fn area_weights(m: u32) -> Vec<f32> {
    sample_cells(m).iter().map(|cell| cell.weight).collect()
}

/// The part of convex polygon `polygon` nearer to `p` than to `q` (Sutherland–Hodgman against
/// their bisector).
fn clip_nearer(polygon: &[[f64; 2]], p: [f64; 2], q: [f64; 2]) -> Vec<[f64; 2]> {
    // side(x) = |x − q|² − |x − p|², affine in x: ≥ 0 where x is nearer p.
    let side = |x: [f64; 2]| {
        2.0 * (x[0] * (p[0] - q[0]) + x[1] * (p[1] - q[1])) + (q[0] * q[0] + q[1] * q[1])
            - (p[0] * p[0] + p[1] * p[1])
    };
    let mut out = Vec::with_capacity(polygon.len() + 1);
    for (i, &a) in polygon.iter().enumerate() {
        let b = polygon[(i + 1) % polygon.len()];
        let (sa, sb) = (side(a), side(b));
        if sa >= 0.0 {
            out.push(a);
        }
        if (sa >= 0.0) != (sb >= 0.0) {
            let t = sa / (sa - sb);
            out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
        }
    }
    out
}

/// The area and centroid of a simple polygon (the shoelace formula and its first moments).
fn area_and_centroid(polygon: &[[f64; 2]]) -> (f64, [f64; 2]) {
    let (mut twice, mut cx, mut cy) = (0.0, 0.0, 0.0);
    for (i, &a) in polygon.iter().enumerate() {
        let b = polygon[(i + 1) % polygon.len()];
        let cross = a[0] * b[1] - b[0] * a[1];
        twice += cross;
        cx += (a[0] + b[0]) * cross;
        cy += (a[1] + b[1]) * cross;
    }
    (twice.abs() / 2.0, [cx / (3.0 * twice), cy / (3.0 * twice)])
}

/// How the extra samples are shaded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExtraSamples {
    /// List every (pixel, rank) pair that needs shading with a prefix sum, then shade the list
    /// as one dense fragment per sample and gather per pixel. Costs scale with the samples
    /// shaded, without idle SIMD lanes. The default: fastest on lavapipe (see `docs/design-notes.md`).
    Compact,
    /// Shade a pixel's extra samples in a loop inside its gather invocation, as the paper's
    /// simplest variant does. Neighbours with different counts leave SIMD lanes idle.
    Loop,
}

/// The depth statistic of the geometry metric.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DepthMetric {
    /// The variance relative to the squared mean depth, Var(d) / E[d]²: free of the scene's
    /// unit, so a scene and its copy scaled ×1000 take the same samples. The default.
    Relative,
    /// The variance in view-space units², the paper's literal metric: the same geometry
    /// modelled in millimetres takes 10⁶ times the metric of its copy in metres.
    World,
}

impl DepthMetric {
    /// The default `c_depth` of each: tuned so that the generated metre-scale scenes take
    /// about the samples they took under the world-unit metric (`docs/design-notes.md`).
    pub fn default_c_depth(self) -> f32 {
        match self {
            DepthMetric::Relative => DEFAULT_C_DEPTH_RELATIVE,
            DepthMetric::World => 100.0,
        }
    }
}

/// The relative metric's `c_depth` default (see [`DepthMetric::default_c_depth`]).
pub const DEFAULT_C_DEPTH_RELATIVE: f32 = 10_000.0;

/// The largest metric constant accepted: with depths ≤ 1e12 (the far plane's bound) every
/// product the shader forms stays finite in f32.
pub const MAX_METRIC_CONSTANT: f32 = 1e12;

/// The metric constants (per scene, in the manifest) and test knobs.
///
/// The paper writes k = c · metric with one c per scene. Here the metric is also scaled by the
/// window's sample count: k = c · M² · metric. One set of constants then serves 2×2, 3×3 and
/// 4×4 alike (the paper's c is this c times M²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AdaptiveSettings {
    /// Which depth variance the geometry metric takes.
    pub depth_metric: DepthMetric,
    /// Scales the depth variance (relative, or in view-space units²).
    pub c_depth: f32,
    /// Scales the normal cone sqrt(1 − min |n̄·n|).
    pub c_normal: f32,
    /// Scales the luminance range r of the shade-first image.
    pub c_shading: f32,
    /// The range r counts only above max(t_min, l_max · t_edge) (FXAA's two thresholds).
    pub t_min: f32,
    pub t_edge: f32,
    /// Test knob: every pixel gets all M² samples, whatever the metrics say.
    pub force_all_samples: bool,
    pub extra_samples: ExtraSamples,
    /// How `-stable` modes carry counts from frame to frame.
    pub stable: StableCounts,
}

impl Default for AdaptiveSettings {
    fn default() -> Self {
        AdaptiveSettings {
            // Tuned on the generated scenes at 1024×768 (`docs/design-notes.md`).
            depth_metric: DepthMetric::Relative,
            c_depth: DepthMetric::Relative.default_c_depth(),
            c_normal: 1.0,
            c_shading: 2.0,
            t_min: 1.0 / 32.0,
            t_edge: 1.0 / 8.0,
            force_all_samples: false,
            extra_samples: ExtraSamples::Compact,
            stable: StableCounts::default(),
        }
    }
}

/// One G-buffer sample as the metric sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowSample {
    /// Linear view depth.
    pub depth: f64,
    /// World-space normal, not necessarily unit length (the G-buffer stores it in f16).
    pub normal: [f64; 3],
    /// False where no geometry covers the sample.
    pub covered: bool,
}

/// The luma cross of the shade-first image around a pixel: centre, left, right, up, down, each
/// from [`metric_luma`] (borders clamp to the edge pixel).
pub type LumaCross = [f64; 5];

/// The shading metric's perceptual luma of a linear HDR colour: the square root (a gamma-2
/// stand-in for sRGB, without `pow`) of the Rec. 709 luminance of the exposed colour clamped
/// to [0, 1]. The colour is sanitized first ([`crate::color::sanitize`]), as on the GPU.
pub fn metric_luma(rgb: [f64; 3], exposure: f64) -> f64 {
    let c = rgb.map(|v| (crate::color::sanitize(v) * exposure).clamp(0.0, 1.0));
    (0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]).sqrt()
}

/// The luma cross of pixel (x, y) of a `width`×`height` linear HDR image (the shade-first
/// image S), borders clamped.
pub fn luma_cross(image: &[[f32; 4]], width: u32, height: u32, x: u32, y: u32, exposure: f64) -> LumaCross {
    let luma = |dx: i64, dy: i64| {
        let px = (i64::from(x) + dx).clamp(0, i64::from(width) - 1) as usize;
        let py = (i64::from(y) + dy).clamp(0, i64::from(height) - 1) as usize;
        let p = image[py * width as usize + px];
        metric_luma([p[0], p[1], p[2]].map(f64::from), exposure)
    };
    [luma(0, 0), luma(-1, 0), luma(1, 0), luma(0, -1), luma(0, 1)]
}

/// A sample's texture footprint in G-buffer texels when n samples share an M×M window:
/// sqrt((1 + M²/n) / 2). Spread over the window in dither order, n samples filtered this wide
/// have together the same variance as the reference's M² samples of one texel each; it is 1 at
/// n = M² and sqrt((1 + M²)/2) for S (2.9 texels at M = 4, not the naive M/sqrt(n) = 4, which
/// blurs textures against the reference).
pub fn footprint(m: u32, n: u32) -> f64 {
    (0.5 + 0.5 * f64::from(m * m) / f64::from(n)).sqrt()
}

/// Which metrics take part: the paper's method uses both.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MetricSet {
    pub geometry: bool,
    pub shading: bool,
}

/// Samples to shade for one pixel, S included: 1 + round(k), clamped to [1, M²].
pub fn sample_count(
    window: &[WindowSample],
    luma: &LumaCross,
    m: u32,
    settings: &AdaptiveSettings,
    metrics: MetricSet,
) -> u32 {
    if settings.force_all_samples {
        return m * m;
    }
    clamp_count(metric_k(window, luma, m, settings, metrics), m * m)
}

/// k before rounding: the largest of the selected metrics, each scaled by its C and by M².
/// Infinite on silhouettes against the background, whatever the constants: every sample, as
/// the GPU's finite k = 1 also gives. Never NaN: every term is finite or +∞.
pub fn metric_k(
    window: &[WindowSample],
    luma: &LumaCross,
    m: u32,
    settings: &AdaptiveSettings,
    metrics: MetricSet,
) -> f64 {
    let scale = f64::from(m * m);
    let mut k: f64 = 0.0;
    if metrics.geometry {
        let (variance, cone) = geometry_metric(window, settings.depth_metric);
        if variance.is_infinite() {
            return f64::INFINITY;
        }
        k = k
            .max(f64::from(settings.c_depth) * scale * variance)
            .max(f64::from(settings.c_normal) * scale * cone);
    }
    if metrics.shading {
        k = k.max(f64::from(settings.c_shading) * scale * shading_metric(luma, settings));
    }
    k
}

/// 1 + round(k) in [1, total]. k is never NaN (see [`metric_k`]); if it were, this last guard
/// would take every sample: shading too much is slow, shading too little is wrong.
pub fn clamp_count(k: f64, total: u32) -> u32 {
    let max_extra = f64::from(total - 1);
    let extra = if k >= 0.0 {
        (k + 0.5).floor().min(max_extra)
    } else if k.is_nan() {
        max_extra
    } else {
        0.0
    };
    1 + extra as u32
}

/// Depth variance and normal cone of an M×M window.
///
/// - A window partly covered by geometry sits on a silhouette against the background: both
///   metrics are infinite there. A wholly uncovered window has nothing to anti-alias: zero.
/// - The variance is computed in two passes (mean, then mean squared deviation), which cannot
///   go negative or cancel the way E[d²] − E[d]² does at large depths. The shader uses the
///   equally stable shifted form, Σ(d − d₀)² − (Σ(d − d₀))²/n, in one pass.
/// - The mean normal of opposite normals is zero: the cone is then the widest possible (1).
/// - 1 − min |n̄·n| is clamped at zero before the square root.
/// - [`DepthMetric::Relative`] divides the variance by the squared mean depth (which is at
///   least the near plane, so never zero).
pub fn geometry_metric(window: &[WindowSample], depth_metric: DepthMetric) -> (f64, f64) {
    let covered = window.iter().filter(|s| s.covered).count();
    if covered == 0 {
        return (0.0, 0.0);
    }
    if covered < window.len() {
        return (f64::INFINITY, f64::INFINITY);
    }
    let n = window.len() as f64;
    let mean = window.iter().map(|s| s.depth).sum::<f64>() / n;
    let variance = window.iter().map(|s| (s.depth - mean).powi(2)).sum::<f64>() / n;
    let variance = match depth_metric {
        DepthMetric::Relative => variance / (mean * mean),
        DepthMetric::World => variance,
    };

    let unit = |v: [f64; 3]| {
        let length = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if length > 1e-6 { v.map(|c| c / length) } else { [0.0; 3] }
    };
    let normals: Vec<[f64; 3]> = window.iter().map(|s| unit(s.normal)).collect();
    let sum = normals.iter().fold([0.0; 3], |acc, v| [acc[0] + v[0], acc[1] + v[1], acc[2] + v[2]]);
    let sum_length = (sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]).sqrt();
    // The mean normal is only meaningful if the normals do not nearly cancel.
    if sum_length < 1e-3 * n {
        return (variance, 1.0);
    }
    let mean_normal = sum.map(|c| c / sum_length);
    let min_cos = normals
        .iter()
        .map(|v| (v[0] * mean_normal[0] + v[1] * mean_normal[1] + v[2] * mean_normal[2]).abs())
        .fold(1.0_f64, f64::min);
    (variance, (1.0 - min_cos).max(0.0).sqrt())
}

/// The luminance range r of the cross, or 0 below the thresholds. The centre pixel is included
/// (the paper names only the four neighbours): without it, a lone bright pixel among dark
/// neighbours would read as flat.
pub fn shading_metric(luma: &LumaCross, settings: &AdaptiveSettings) -> f64 {
    let l_max = luma.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let l_min = luma.iter().copied().fold(f64::INFINITY, f64::min);
    let range = l_max - l_min;
    let threshold = f64::from(settings.t_min).max(l_max * f64::from(settings.t_edge));
    if range < threshold { 0.0 } else { range }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flat(depth: f64, m: u32) -> Vec<WindowSample> {
        vec![WindowSample { depth, normal: [0.0, 0.0, 1.0], covered: true }; (m * m) as usize]
    }

    const BOTH: MetricSet = MetricSet { geometry: true, shading: true };

    #[test]
    fn sample_orders_are_permutations_starting_at_the_papers_first_cell() {
        for (m, first_cell) in [(2, 0), (3, 4), (4, 10)] {
            let order = sample_order(m);
            let mut sorted = order.clone();
            sorted.sort_unstable();
            assert_eq!(sorted, (0..m * m).collect::<Vec<_>>());
            assert_eq!(order[0], first_cell, "rank 0 of the {m}×{m} matrix");
            let [low, high] = packed_sample_order(m);
            let expected = match m {
                2 => [0x2130, 0],
                3 => [0x7138_2064, 5],
                _ => [0xD7F5_820A, 0xC6E4_93B1],
            };
            assert_eq!([low, high], expected, "{m}×{m}: the words the shaders decode");
            for (rank, &cell) in order.iter().enumerate() {
                let word = if rank < 8 { low } else { high };
                assert_eq!((word >> (4 * (rank % 8))) & 15, cell, "{m}×{m} rank {rank}");
            }
        }
    }

    #[test]
    fn area_weights_are_the_voronoi_shares_of_each_prefix() {
        for m in 2..=4u32 {
            let cells = (m * m) as usize;
            let table = area_weights(m);
            for n in 1..=cells {
                let row = &table[(n - 1) * cells..n * cells];
                let sum: f64 = row.iter().map(|&w| f64::from(w)).sum();
                assert!((sum - 1.0).abs() < 1e-6, "{m}×{m} n = {n}: the weights sum to {sum}");
                assert!(row[..n].iter().all(|&w| w > 0.0), "{m}×{m} n = {n}: {row:?}");
                assert!(row[n..].iter().all(|&w| w == 0.0), "{m}×{m} n = {n}: {row:?}");
            }
            assert_eq!(table[0], 1.0);
            let full = &table[(cells - 1) * cells..];
            assert!(full.iter().all(|&w| (w - 1.0 / cells as f32).abs() < 1e-6), "{m}×{m}: {full:?}");
        }
        // 3×3: the centre (1/2, 1/2) and the lower-left cell's (1/6, 5/6), y down, meet on the
        // line y = x + 1/3, which leaves the corner the triangle (0, 1/3), (0, 1), (2/3, 1): 2/9.
        let table = area_weights(3);
        assert!(
            (table[9] - 7.0 / 9.0).abs() < 1e-6 && (table[10] - 2.0 / 9.0).abs() < 1e-6,
            "{:?}",
            &table[9..11]
        );
        // 2×2: two diagonal samples halve the pixel; a third takes an eighth from each.
        let table = area_weights(2);
        assert_eq!(&table[4..6], &[0.5, 0.5]);
        assert!(table[8..11].iter().zip([0.375, 0.375, 0.25]).all(|(a, b)| (a - b).abs() < 1e-6));
    }

    #[test]
    fn the_cells_of_each_prefix_tile_the_pixel_around_its_centre() {
        for m in 2..=4u32 {
            let cells = (m * m) as usize;
            let table = sample_cells(m);
            let order = sample_order(m);
            let texels = f64::from(m);
            for n in 1..=cells {
                let row = &table[(n - 1) * cells..n * cells];
                // The cells' centroids, weighted by area, are the pixel's centre (M/2, M/2).
                let mut moment = [0.0f64; 2];
                for (rank, cell) in row[..n].iter().enumerate() {
                    let sample = [f64::from(order[rank] % m) + 0.5, f64::from(order[rank] / m) + 0.5];
                    for axis in 0..2 {
                        moment[axis] +=
                            f64::from(cell.weight) * (sample[axis] + f64::from(cell.centroid[axis]));
                    }
                    let side = f64::from(cell.weight).sqrt() * texels;
                    assert!((f64::from(cell.footprint) - side).abs() < 1e-5, "{m}×{m} n = {n}: {cell:?}");
                }
                for axis in 0..2 {
                    assert!((moment[axis] - texels / 2.0).abs() < 1e-5, "{m}×{m} n = {n}: {moment:?}");
                }
            }
            // One sample stands for the whole pixel: its centre, a pixel wide.
            let first = [f64::from(order[0] % m) + 0.5, f64::from(order[0] / m) + 0.5];
            let whole = table[0];
            assert!((f64::from(whole.footprint) - texels).abs() < 1e-6, "{m}×{m}: {whole:?}");
            for (position, offset) in first.iter().zip(whole.centroid) {
                assert!((position + f64::from(offset) - texels / 2.0).abs() < 1e-6, "{m}×{m}: {whole:?}");
            }
            // All M² samples: each its own texel, as the reference shades it.
            for cell in &table[(cells - 1) * cells..] {
                assert!((cell.footprint - 1.0).abs() < 1e-6 && cell.centroid.iter().all(|c| c.abs() < 1e-6));
            }
        }
        // 3×3's first sample is the centre: its whole-pixel cell needs no offset.
        assert_eq!(sample_cells(3)[0].centroid, [0.0, 0.0]);
    }

    #[test]
    fn a_flat_window_needs_one_sample() {
        let luma = [0.5; 5];
        for m in 2..=4 {
            assert_eq!(sample_count(&flat(3.0, m), &luma, m, &AdaptiveSettings::default(), BOTH), 1);
        }
    }

    #[test]
    fn variance_survives_large_depths() {
        // At depth 1e9, d² is 1e18 and f64 resolves it only to 128: E[d²] − E[d]² loses the
        // 0.25 of a ±0.5 split entirely, the two-pass variance keeps it exactly.
        let mut window = flat(1e9, 2);
        window[0].depth += 0.5;
        window[1].depth += 0.5;
        window[2].depth -= 0.5;
        window[3].depth -= 0.5;
        let (variance, _) = geometry_metric(&window, DepthMetric::World);
        assert_eq!(variance, 0.25);
        let naive = window.iter().map(|s| s.depth * s.depth).sum::<f64>() / 4.0
            - (window.iter().map(|s| s.depth).sum::<f64>() / 4.0).powi(2);
        assert!(
            (naive - 0.25).abs() > 0.1,
            "the naive formula should show the cancellation this guards against: {naive}"
        );
    }

    #[test]
    fn the_relative_depth_metric_ignores_the_scenes_unit() {
        let window = |scale: f64| -> Vec<WindowSample> {
            [4.0, 4.2, 5.0, 9.0]
                .map(|d| WindowSample { depth: d * scale, normal: [0.0, 0.0, 1.0], covered: true })
                .to_vec()
        };
        let metre = geometry_metric(&window(1.0), DepthMetric::Relative).0;
        for scale in [1e-3, 1e3, 1e6] {
            let scaled = geometry_metric(&window(scale), DepthMetric::Relative).0;
            assert!((scaled / metre - 1.0).abs() < 1e-12, "×{scale}: {scaled} vs {metre}");
            let world = geometry_metric(&window(scale), DepthMetric::World).0;
            let world_metre = geometry_metric(&window(1.0), DepthMetric::World).0;
            assert!((world / world_metre / (scale * scale) - 1.0).abs() < 1e-9);
        }
    }

    #[test]
    fn opposite_normals_give_the_widest_cone_not_nan() {
        let mut window = flat(1.0, 2);
        window[1].normal = [0.0, 0.0, -1.0];
        window[3].normal = [0.0, 0.0, -1.0];
        let (_, cone) = geometry_metric(&window, DepthMetric::World);
        assert_eq!(cone, 1.0);
    }

    #[test]
    fn degenerate_and_slightly_long_normals_stay_finite() {
        let mut window = flat(1.0, 2);
        window[0].normal = [0.0, 0.0, 0.0];
        window[1].normal = [0.0, 0.0, 1.0 + 1e-7];
        let (variance, cone) = geometry_metric(&window, DepthMetric::World);
        assert!(variance.is_finite() && cone.is_finite(), "{variance} {cone}");
        // A normal a hair longer than 1 must not push 1 − |n̄·n| below zero into sqrt.
        let mut window = flat(1.0, 2);
        window[2].normal = [0.0, 1e-9, 1.0 + 1e-6];
        assert!(geometry_metric(&window, DepthMetric::World).1 >= 0.0);
    }

    #[test]
    fn silhouettes_against_the_background_take_every_sample() {
        let mut window = flat(2.0, 3);
        window[4].covered = false;
        assert_eq!(sample_count(&window, &[0.0; 5], 3, &AdaptiveSettings::default(), BOTH), 9);
        let empty = vec![WindowSample { depth: 0.0, normal: [0.0; 3], covered: false }; 9];
        assert_eq!(sample_count(&empty, &[0.0; 5], 3, &AdaptiveSettings::default(), BOTH), 1);
    }

    #[test]
    fn shading_metric_respects_both_thresholds() {
        let settings = AdaptiveSettings::default();
        // Range 0.02 is below t_min = 1/32.
        assert_eq!(shading_metric(&[0.5, 0.52, 0.5, 0.5, 0.5], &settings), 0.0);
        // Range 0.1 is below l_max · t_edge = 0.9 · 1/8.
        assert_eq!(shading_metric(&[0.8, 0.9, 0.8, 0.8, 0.8], &settings), 0.0);
        // Range 0.5 counts.
        assert_eq!(shading_metric(&[0.0, 0.5, 0.0, 0.0, 0.0], &settings), 0.5);
        // A lone bright centre counts too.
        assert_eq!(shading_metric(&[1.0, 0.0, 0.0, 0.0, 0.0], &settings), 1.0);
    }

    #[test]
    fn footprint_matches_the_reference_at_full_sampling() {
        for m in 2..=4 {
            assert_eq!(footprint(m, m * m), 1.0);
            assert!(footprint(m, 1) < f64::from(m));
        }
        assert!((footprint(4, 1) - 8.5f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn luma_clamps_and_takes_the_square_root() {
        assert_eq!(metric_luma([1.0, 1.0, 1.0], 1.0), 1.0);
        assert_eq!(metric_luma([8.0, 8.0, 8.0], 1.0), 1.0);
        assert_eq!(metric_luma([0.25, 0.25, 0.25], 1.0), 0.5);
        assert_eq!(metric_luma([0.5, 0.5, 0.5], 0.5), 0.5);
        assert_eq!(metric_luma([-1.0, 0.0, 0.0], 1.0), 0.0);
    }

    #[test]
    fn counts_are_clamped_to_the_window() {
        assert_eq!(clamp_count(0.0, 16), 1);
        assert_eq!(clamp_count(0.49, 16), 1);
        assert_eq!(clamp_count(0.5, 16), 2);
        assert_eq!(clamp_count(1e30, 16), 16);
        assert_eq!(clamp_count(f64::INFINITY, 4), 4);
        assert_eq!(clamp_count(f64::NAN, 9), 9);
    }

    #[test]
    fn silhouettes_take_every_sample_even_with_zero_constants() {
        // 0 · ∞ is NaN, which a max() fold would silently drop; the GPU returns "all samples"
        // before applying any constant, and so must the twin.
        let mut window = flat(2.0, 2);
        window[1].covered = false;
        let settings = AdaptiveSettings { c_depth: 0.0, c_normal: 0.0, ..Default::default() };
        let geometry = MetricSet { geometry: true, shading: false };
        assert_eq!(metric_k(&window, &[0.0; 5], 2, &settings, geometry), f64::INFINITY);
        assert_eq!(sample_count(&window, &[0.0; 5], 2, &settings, BOTH), 4);
    }

    #[test]
    fn force_all_samples_overrides_the_metrics() {
        let settings = AdaptiveSettings { force_all_samples: true, ..Default::default() };
        assert_eq!(sample_count(&flat(1.0, 4), &[0.0; 5], 4, &settings, BOTH), 16);
    }

    #[test]
    fn ablations_use_one_metric_each() {
        let mut window = flat(1.0, 2);
        window[0].depth = 2.0;
        let luma = [0.5; 5];
        let settings = AdaptiveSettings::default();
        let geometry_only = MetricSet { geometry: true, shading: false };
        let shading_only = MetricSet { geometry: false, shading: true };
        assert!(sample_count(&window, &luma, 2, &settings, geometry_only) > 1);
        assert_eq!(sample_count(&window, &luma, 2, &settings, shading_only), 1);
    }
}
