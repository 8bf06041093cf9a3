//! Each sample's cell in a prefix of the dither order: what the `-area` and `-cells` variants
//! weight and shade by.

use super::order::{dither_matrix, sample_order};

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

#[cfg(test)]
mod tests {
    use super::*;

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
}
