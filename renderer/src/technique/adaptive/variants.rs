//! How a pixel's samples stand for it (the `-area`, `-cells` and `-coverage` variants) and where its
//! count comes from (the paper's per frame, or `-stable`'s carried between frames).

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
    /// Whether a pixel of `n` of `m`² samples reads [`sample_cells`](super::cells::sample_cells) rather than averaging
    /// alike.
    pub fn weighted(self, m: u32, n: u32) -> bool {
        self != Reconstruction::Equal && n > 1 && n < m * m
    }

    /// Whether a pixel of `n` of `m`² samples shades its first sample again instead of
    /// reusing S: under `Cells` and `Coverage` every pixel of more than one sample, and a full
    /// window in a `textured` scene, to equal the reference (S filters textures over the whole
    /// pixel). Without textures S is the reference's first sample, and a full window reuses it.
    pub fn reshades_first(self, m: u32, n: u32, textured: bool) -> bool {
        (textured && n == m * m)
            || (matches!(self, Reconstruction::Cells | Reconstruction::Coverage) && n > 1)
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
