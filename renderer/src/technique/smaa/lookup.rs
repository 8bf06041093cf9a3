//! SMAA 1x's preset and lookup textures (their provenance and licence in `renderer/data/smaa/`).

use crate::pipelines::ConstantTexture;

/// The reference implementation's default quality preset (its `SMAA_PRESET_HIGH`), as the
/// shader's override constants.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SmaaPreset {
    /// Luma contrast, in code values / steps, that makes an edge.
    pub threshold: f64,
    /// An edge is dropped when a neighbouring edge has this many times its contrast.
    pub local_contrast_adaptation: f64,
    /// Steps of the horizontal and vertical line searches, each of two pixels.
    pub max_search_steps: f64,
    /// Steps of the diagonal line searches, each of one pixel.
    pub max_search_steps_diag: f64,
    /// How much sharp corners are rounded, in percent.
    pub corner_rounding: f64,
}

/// `SMAA_PRESET_HIGH`, which is also what the reference uses when no preset is named.
pub const PRESET_HIGH: SmaaPreset = SmaaPreset {
    threshold: 0.1,
    local_contrast_adaptation: 2.0,
    max_search_steps: 16.0,
    max_search_steps_diag: 8.0,
    corner_rounding: 25.0,
};

/// The area texture (distances along a line and crossing edges to the areas a pixel covers on
/// either side) and the search texture (the last search read to how far the line went).
pub const LOOKUP_TEXTURES: [ConstantTexture; 2] = [
    ConstantTexture {
        name: "smaa_area",
        width: 160,
        height: 560,
        format: wgpu::TextureFormat::Rg8Unorm,
        bytes: include_bytes!("../../../data/smaa/area.bin"),
    },
    ConstantTexture {
        name: "smaa_search",
        width: 64,
        height: 16,
        format: wgpu::TextureFormat::R8Unorm,
        bytes: include_bytes!("../../../data/smaa/search.bin"),
    },
];
