//! The ground truth: the brute-force reference at M×M samples per pixel (8×8 for the runner's),
//! unstalled and untimed, rendered tile by tile within a memory budget.

use super::SceneRenderer;
use super::images::{DisplayImage, FrameImages, half_texels, read_display};
use crate::error::RenderError;
use crate::graph::Output;
use crate::mode::Mode;
use crate::scene::Tile;
use crate::technique::Technique;

/// The ground truth of a scene: the brute-force reference at `m` × `m` samples per pixel,
/// unstalled, rendered tile by tile (see [`SceneRenderer::render_truth`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Truth {
    /// The display image and HDR image, as a mode's; no sample counts.
    pub images: FrameImages,
    pub m: u32,
    pub tiles: usize,
}

impl SceneRenderer {
    /// Renders the ground truth: the brute-force reference at `m` × `m` samples per pixel,
    /// unstalled and untimed, through reference-MxM's graph with its texture-footprint rule
    /// (UV derivatives per G-buffer sample), so a single tile at m = M gives reference-MxM's
    /// image bit for bit. Tiles keep each one's allocations within `tile_bytes`: at 8×8 a
    /// 1024×768 frame needs 1.8 GB of targets at once. The frame uniforms are restored
    /// afterwards.
    pub fn render_truth(&mut self, m: u32, tile_bytes: u64) -> Result<Truth, RenderError> {
        self.render_truth_until(m, tile_bytes, &|| false)
    }

    /// [`render_truth`](Self::render_truth), asking `stop` before each tile: a truth of many
    /// tiles (a 4096² frame takes 38 s) ends within one tile's time of a signal, with
    /// [`RenderError::Stopped`].
    pub fn render_truth_until(
        &mut self,
        m: u32,
        tile_bytes: u64,
        stop: &dyn Fn() -> bool,
    ) -> Result<Truth, RenderError> {
        let (width, height) = (self.settings.width, self.settings.height);
        let limit = self.gpu.device.limits().max_texture_dimension_2d;
        let tiles = truth_tiles(width, height, m, limit, tile_bytes)?;
        let pixels = width as usize * height as usize;
        let mut images = FrameImages {
            width,
            height,
            display: DisplayImage {
                bits: if self.settings.color.bits <= 8 { 8 } else { 10 },
                rgba: vec![0; 4 * pixels],
            },
            hdr: vec![0.0; 4 * pixels],
            sample_counts: None,
        };
        let result = tiles.iter().enumerate().try_for_each(|(done, tile)| {
            if stop() {
                return Err(RenderError::Stopped { done, of: tiles.len() });
            }
            self.render_truth_tile(m, *tile, &mut images)
        });
        self.write_frame_uniforms(Tile::whole(width, height));
        result?;
        Ok(Truth { images, m, tiles: tiles.len() })
    }

    /// Renders one tile of the truth into allocations of its own, freed afterwards, and copies
    /// its images into place in `out`.
    fn render_truth_tile(&mut self, m: u32, tile: Tile, out: &mut FrameImages) -> Result<(), RenderError> {
        let outputs = self.render_alone(Mode::new(Technique::Reference, m, false), tile, "truth")?;
        let tile_display = read_display(&self.gpu, &outputs[&Output::Display])?.rgba;
        let tile_hdr: Vec<f32> =
            half_texels(&self.gpu.read_texture(&outputs[&Output::Hdr])?).into_iter().flatten().collect();
        let row = 4 * tile.width as usize;
        for y in 0..tile.height as usize {
            let at = 4 * ((tile.y as usize + y) * out.width as usize + tile.x as usize);
            out.display.rgba[at..at + row].copy_from_slice(&tile_display[y * row..(y + 1) * row]);
            out.hdr[at..at + row].copy_from_slice(&tile_hdr[y * row..(y + 1) * row]);
        }
        Ok(())
    }
}

/// Target bytes per G-buffer sample of a truth tile: the G-buffer (UV 8, normal 8, UV
/// derivatives 8, depth 4) and the supersampled HDR image (8).
const TRUTH_BYTES_PER_SAMPLE: u64 = 36;

/// Whether the truth of a `width` × `height` frame at `m` × `m` samples is rendered in one
/// piece within `tile_bytes` (on a device whose texture sides allow it): if not, its tiles
/// differ from one piece where samples near an edge flip, so the tiling is part of its identity.
pub fn truth_in_one_piece(width: u32, height: u32, m: u32, tile_bytes: u64) -> bool {
    u64::from(m * m) * TRUTH_BYTES_PER_SAMPLE * u64::from(width) * u64::from(height) <= tile_bytes
}

/// Splits a `width` × `height` frame into tiles whose m·w × m·h targets fit `max_side` and
/// together take at most `budget` bytes (at least one row of pixels per tile): full-width
/// bands where the width fits, a grid otherwise, sizes as even as the division allows.
fn truth_tiles(
    width: u32,
    height: u32,
    m: u32,
    max_side: u32,
    budget: u64,
) -> Result<Vec<Tile>, RenderError> {
    let max_tile_side = max_side / m.max(1);
    if max_tile_side == 0 {
        return Err(RenderError::TooLarge { width: m, height: m, limit: max_side });
    }
    let tile_width = width.min(max_tile_side);
    let bytes_per_row = u64::from(m * m) * TRUTH_BYTES_PER_SAMPLE * u64::from(tile_width);
    let rows = (budget / bytes_per_row).clamp(1, u64::from(height.min(max_tile_side))) as u32;
    let (columns, bands) = (width.div_ceil(tile_width), height.div_ceil(rows));
    let (tile_width, rows) = (width.div_ceil(columns), height.div_ceil(bands));
    let mut tiles = Vec::new();
    for y in (0..height).step_by(rows as usize) {
        for x in (0..width).step_by(tile_width as usize) {
            tiles.push(Tile { x, y, width: tile_width.min(width - x), height: rows.min(height - y) });
        }
    }
    Ok(tiles)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every pixel in exactly one tile, every tile within the limits.
    fn check(width: u32, height: u32, m: u32, max_side: u32, budget: u64) -> Vec<Tile> {
        let tiles = truth_tiles(width, height, m, max_side, budget).unwrap();
        let mut covered = vec![0u8; (width * height) as usize];
        for tile in &tiles {
            assert!(tile.width > 0 && tile.height > 0, "{tile:?}");
            assert!(m * tile.width <= max_side && m * tile.height <= max_side, "{tile:?}");
            for y in tile.y..tile.y + tile.height {
                for x in tile.x..tile.x + tile.width {
                    covered[(y * width + x) as usize] += 1;
                }
            }
        }
        assert!(covered.iter().all(|&c| c == 1), "{width}×{height}: {tiles:?}");
        tiles
    }

    #[test]
    fn truth_tiles_cover_the_frame_once_within_the_limits() {
        // 1024×768 at 8×8 in 512 MiB: four full-width bands of 192 rows.
        let tiles = check(1024, 768, 8, 16384, 512 << 20);
        assert_eq!(tiles.len(), 4);
        assert!(tiles.iter().all(|t| t.width == 1024 && t.height == 192));
        // A budget of one row per tile, odd sizes, a width past the texture limit.
        assert_eq!(check(317, 211, 8, 16384, 1).len(), 211);
        let wide = check(4096, 8, 8, 16384, u64::MAX);
        assert_eq!(wide.len(), 2, "{wide:?}");
        assert_eq!(check(1, 1, 8, 16384, 512 << 20).len(), 1);
        assert!(truth_tiles(4, 4, 8, 4, u64::MAX).is_err(), "one pixel at 8×8 exceeds a 4-texel limit");
    }

    /// What the truth's cache key is told about tiling matches how it is tiled.
    #[test]
    fn one_piece_is_one_tile() {
        for (width, height, budget) in
            [(256, 192, 128 << 20), (1024, 768, 128 << 20), (1024, 768, u64::MAX), (160, 120, 1 << 20)]
        {
            let tiles = check(width, height, 8, 16384, budget).len();
            assert_eq!(truth_in_one_piece(width, height, 8, budget), tiles == 1, "{width}×{height}: {tiles}");
        }
    }
}
