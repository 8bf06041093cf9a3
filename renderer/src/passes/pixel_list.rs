//! Pixels marked as bits and the list of the marked pixels (`shaders/lib/pixel_list.wgsl`):
//! SMAA's edge pixels and MSAA's pixels shaded per sample.

use super::{BuildContext, ComputeStep, Io};
use crate::error::RenderError;
use crate::graph::Resource;
use crate::pipelines::Constants;

/// Pixels per word of marks: two bits each.
pub(crate) const SLOTS: u32 = 16;

/// All the words of one set of marks over a `width` × `height` image, its rows one after the
/// other.
pub(crate) fn mark_words(width: u32, height: u32) -> u32 {
    height * width.div_ceil(SLOTS)
}

/// The list buffer: its length, row starts, word starts and an entry for every pixel.
pub(crate) fn list(width: u32, height: u32) -> Resource {
    let (w, h) = (u64::from(width), u64::from(height));
    Resource::Buffer { bytes: 4 * (4 + h + u64::from(mark_words(width, height)) + w * h) }
}

/// A compact target (`shaders/lib/compact.wgsl`) of 4×4 blocks, `width` rounded up to them
/// wide, with room for `entries`.
pub(crate) fn compact_size(width: u32, entries: u64) -> (u32, u32) {
    let width = width.next_multiple_of(4);
    let height = u32::try_from(entries.div_ceil(u64::from(width))).unwrap_or(u32::MAX).next_multiple_of(4);
    (width, height)
}

/// The steps that list the marked pixels once `edge_words` holds the marks: each row's count,
/// the rows' starts, the entries. `constants` set `WIDTH` and `HEIGHT`.
pub(crate) fn list_steps(
    ctx: &mut BuildContext,
    io: &mut Io,
    shader: &'static str,
    constants: &Constants,
    width: u32,
    height: u32,
) -> Result<Vec<ComputeStep>, RenderError> {
    [
        ("list_count_rows", height),
        // One invocation: the rows are few and the scan is serial.
        ("list_scan_rows", 1),
        ("list_emit", mark_words(width, height)),
    ]
    .into_iter()
    // Workgroups of 64 (`list_scan_rows`: of 1).
    .map(|(entry, invocations)| {
        ctx.compute_step(io, shader, entry, constants.clone(), [invocations.div_ceil(64), 1, 1])
    })
    .collect()
}
