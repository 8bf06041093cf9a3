//! The Laplacian pyramid and its Weber contrast, as the reference's `lpyr_dec.py` builds them:
//! a 5-tap binomial-like kernel (a = 0.4), reduction with the reference's border terms,
//! expansion by zero interleaving, and each band divided by the expanded coarser level (the
//! local background luminance).

/// One channel of an image, row by row.
#[derive(Debug, Clone, PartialEq)]
pub struct Plane {
    pub width: usize,
    pub height: usize,
    pub data: Vec<f32>,
}

impl Plane {
    pub fn zeros(width: usize, height: usize) -> Self {
        Plane { width, height, data: vec![0.0; width * height] }
    }

    pub fn at(&self, x: usize, y: usize) -> f32 {
        self.data[y * self.width + x]
    }

    /// The plane with `f` applied to each value.
    pub fn map(&self, f: impl Fn(f32) -> f32) -> Plane {
        Plane { width: self.width, height: self.height, data: self.data.iter().map(|&v| f(v)).collect() }
    }

    /// The plane transposed, so that a filter along columns can run along rows.
    pub(crate) fn transposed(&self) -> Plane {
        let mut out = Plane::zeros(self.height, self.width);
        for y in 0..self.height {
            for x in 0..self.width {
                out.data[x * self.height + y] = self.data[y * self.width + x];
            }
        }
        out
    }
}

/// The pyramid's kernel for a = 0.4: [0.25 − a/2, 0.25, a, 0.25, 0.25 − a/2].
const KERNEL: [f32; 5] = [0.25 - 0.4 / 2.0, 0.25, 0.4, 0.25, 0.25 - 0.4 / 2.0];

/// The lowest band frequency kept, cycles per degree.
const MIN_FREQUENCY: f64 = 0.2;

/// The pyramid's shape for a `width` × `height` image seen at `ppd` pixels a degree: the
/// number of Laplacian levels (the bands but the baseband) and every band's peak frequency in
/// cycles per degree, the baseband last.
pub fn band_frequencies(width: usize, height: usize, ppd: f64) -> Vec<f64> {
    let max_levels = (width.min(height) as f64).log2().floor() as i64 - 1;
    let frequencies = |levels: i64| -> Vec<f64> {
        std::iter::once(1.0)
            .chain((0..levels).map(|f| 0.3228 * 2f64.powi(-f as i32)))
            .map(|b| b * ppd / 2.0)
            .collect()
    };
    let candidates = frequencies(14);
    let first_too_low = candidates.iter().position(|&f| f <= MIN_FREQUENCY);
    let max_band = first_too_low.map_or(max_levels, |i| i as i64);
    let levels = (max_band + 1).clamp(0, max_levels.max(0));
    frequencies(levels)
}

/// One step down the Gaussian pyramid: ⌈h/2⌉ × ⌈w/2⌉, with the reference's border terms.
pub fn reduce(x: &Plane) -> Plane {
    // The reference decides the last column's term by the parity of the rows, not of the
    // columns; this port keeps that, so that its numbers are the reference's.
    let odd_rows = x.height % 2 == 1;
    let vertical = reduce_rows(x, odd_rows);
    reduce_rows(&vertical.transposed(), odd_rows).transposed()
}

/// Filters and halves along columns (each output row from the input rows around twice its
/// index), with zero padding and then the terms the reference adds at the two ends.
fn reduce_rows(x: &Plane, odd_end: bool) -> Plane {
    let (w, h) = (x.width, x.height);
    let out_h = h.div_ceil(2);
    let mut out = Plane::zeros(w, out_h);
    let row = |y: usize| &x.data[y * w..(y + 1) * w];
    for i in 0..out_h {
        let target = &mut out.data[i * w..(i + 1) * w];
        for (k, &weight) in KERNEL.iter().enumerate() {
            let source = 2 * i + k;
            if source < 2 || source - 2 >= h {
                continue;
            }
            for (t, &v) in target.iter_mut().zip(row(source - 2)) {
                *t += v * weight;
            }
        }
    }
    let add = |out: &mut Plane, i: usize, y: usize, weight: f32| {
        for x_ in 0..w {
            out.data[i * w + x_] += x.data[y * w + x_] * weight;
        }
    };
    add(&mut out, 0, 0, KERNEL[1]);
    add(&mut out, 0, 1.min(h - 1), KERNEL[0]);
    let last = out_h - 1;
    if odd_end {
        add(&mut out, last, h - 1, KERNEL[3]);
        add(&mut out, last, h.saturating_sub(2), KERNEL[4]);
    } else {
        add(&mut out, last, h - 1, KERNEL[4]);
    }
    out
}

/// One step up the pyramid to `width` × `height`: zeros interleaved, the first and last
/// samples repeated at the ends, filtered by twice the kernel.
pub fn expand(x: &Plane, width: usize, height: usize) -> Plane {
    let vertical = expand_rows(x, height);
    expand_rows(&vertical.transposed(), width).transposed()
}

fn expand_rows(x: &Plane, out_h: usize) -> Plane {
    let w = x.width;
    // The padded column of out_h + 4 rows: row 2 + 2j holds input row j; row 0 the first
    // input row; row out_h + 2 (even out_h) or out_h + 3 (odd) the last.
    let mut padded: Vec<Option<usize>> = vec![None; out_h + 4];
    for (j, slot) in padded.iter_mut().skip(2).step_by(2).take(x.height).enumerate() {
        *slot = Some(j);
    }
    padded[0] = Some(0);
    padded[out_h + 2 + out_h % 2] = Some(x.height - 1);
    let mut out = Plane::zeros(w, out_h);
    for r in 0..out_h {
        let target = &mut out.data[r * w..(r + 1) * w];
        for (k, &weight) in KERNEL.iter().enumerate() {
            let Some(j) = padded[r + k] else { continue };
            let weight = weight * 2.0;
            for (t, &v) in target.iter_mut().zip(&x.data[j * w..(j + 1) * w]) {
                *t += v * weight;
            }
        }
    }
    out
}

/// A band of the Weber contrast pyramid for a test and a reference plane set (the planes in
/// the metric's channel order), with the local background luminance the contrast was taken
/// against, log10.
#[derive(Debug)]
pub struct ContrastBand {
    /// Contrast per channel: test, then reference.
    pub test: Vec<Plane>,
    pub reference: Vec<Plane>,
    /// log10 of the reference's background luminance: a plane, or one value for the baseband.
    pub log_background: Background,
}

/// The background luminance a band's contrast is relative to.
#[derive(Debug)]
pub enum Background {
    Local(Plane),
    /// The baseband's: the mean over the image.
    Mean(f32),
}

/// The largest contrast the reference keeps (there is no lower clamp).
const MAX_CONTRAST: f32 = 1000.0;
/// The least background luminance, cd/m².
const MIN_BACKGROUND: f32 = 0.01;

/// The Weber contrast pyramid of `test` and `reference` (the same channels, the achromatic
/// sustained channel first), `levels` Laplacian bands and the baseband. Bands between the
/// first and the baseband are doubled, as the reference's `get_band` does.
pub fn weber_contrast(test: &[Plane], reference: &[Plane], levels: usize) -> Vec<ContrastBand> {
    let gaussian = |planes: &[Plane]| -> Vec<Vec<Plane>> {
        planes
            .iter()
            .map(|plane| {
                let mut pyramid = vec![plane.clone()];
                for _ in 0..levels {
                    let next = reduce(pyramid.last().expect("the pyramid has its base"));
                    pyramid.push(next);
                }
                pyramid
            })
            .collect()
    };
    let (test_g, reference_g) = (gaussian(test), gaussian(reference));
    (0..=levels)
        .map(|level| {
            let gain = if level == 0 || level == levels { 1.0 } else { 2.0 };
            if level == levels {
                baseband(&test_g, &reference_g, level)
            } else {
                laplacian_band(&test_g, &reference_g, level, gain)
            }
        })
        .collect()
}

fn laplacian_band(
    test_g: &[Vec<Plane>],
    reference_g: &[Vec<Plane>],
    level: usize,
    gain: f32,
) -> ContrastBand {
    let band = |pyramids: &[Vec<Plane>]| -> (Vec<Plane>, Plane) {
        let mut background = None;
        let contrast = pyramids
            .iter()
            .map(|pyramid| {
                let fine = &pyramid[level];
                let coarse = expand(&pyramid[level + 1], fine.width, fine.height);
                let layer: Vec<f32> = fine.data.iter().zip(&coarse.data).map(|(f, c)| f - c).collect();
                let local = background.get_or_insert_with(|| coarse.map(|v| v.max(MIN_BACKGROUND)));
                let data =
                    layer.iter().zip(&local.data).map(|(l, b)| (l / b).min(MAX_CONTRAST) * gain).collect();
                Plane { width: fine.width, height: fine.height, data }
            })
            .collect();
        (contrast, background.expect("a band has channels"))
    };
    let (test, _) = band(test_g);
    let (reference, background) = band(reference_g);
    ContrastBand { test, reference, log_background: Background::Local(background.map(f32::log10)) }
}

fn baseband(test_g: &[Vec<Plane>], reference_g: &[Vec<Plane>], level: usize) -> ContrastBand {
    let band = |pyramids: &[Vec<Plane>]| -> (Vec<Plane>, f32) {
        let achromatic = &pyramids[0][level];
        let sum: f64 = achromatic.data.iter().map(|&v| f64::from(v.max(MIN_BACKGROUND))).sum();
        let mean = (sum / achromatic.data.len() as f64) as f32;
        let contrast =
            pyramids.iter().map(|pyramid| pyramid[level].map(|v| (v / mean).min(MAX_CONTRAST))).collect();
        (contrast, mean)
    };
    let (test, _) = band(test_g);
    let (reference, mean) = band(reference_g);
    ContrastBand { test, reference, log_background: Background::Mean(mean.log10()) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_standard_display_at_256_by_192_has_six_bands_and_a_baseband() {
        let frequencies = band_frequencies(256, 192, 37.842_503_853_602_885);
        assert_eq!(frequencies.len(), 7);
        assert!((frequencies[0] - 18.921_251_926_801_443).abs() < 1e-12);
        assert!((frequencies[1] - 6.107_780_121_971_505).abs() < 1e-12);
    }

    #[test]
    fn reduce_then_expand_keeps_a_constant_image_of_even_sides_constant() {
        let plane = Plane { width: 12, height: 10, data: vec![3.0; 120] };
        let reduced = reduce(&plane);
        assert_eq!((reduced.width, reduced.height), (6, 5));
        let expanded = expand(&reduced, 12, 10);
        for v in expanded.data {
            assert!((v - 3.0).abs() < 1e-5, "{v}");
        }
    }

    #[test]
    fn reduce_takes_the_last_columns_border_term_by_the_parity_of_the_rows_as_the_reference_does() {
        // 13 columns, 10 rows: the last column gets the even case's one term, so a constant
        // loses the kernel's fourth tap there (0.25).
        let reduced = reduce(&Plane { width: 13, height: 10, data: vec![1.0; 130] });
        assert_eq!((reduced.width, reduced.height), (7, 5));
        for y in 0..5 {
            assert!((reduced.at(0, y) - 1.0).abs() < 1e-6);
            assert!((reduced.at(6, y) - 0.75).abs() < 1e-6, "{}", reduced.at(6, y));
        }
    }
}
