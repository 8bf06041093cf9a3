//! The paper's ordered-dither sample order (its Fig. 3) and the packed forms the shaders decode.

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

#[cfg(test)]
mod tests {
    use super::*;

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
}
