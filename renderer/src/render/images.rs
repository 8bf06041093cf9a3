//! What a frame gives back: its timing, pass by pass, and its images read from the device.

use crate::error::RenderError;
use crate::gpu::Gpu;

/// Wall-clock time of one pass of one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct PassTime {
    pub name: &'static str,
    pub seconds: f64,
}

/// The passes of one frame, in submission order.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameTiming {
    pub passes: Vec<PassTime>,
}

impl FrameTiming {
    /// The frame's time: the sum of its passes, each measured from submit to completion.
    pub fn seconds(&self) -> f64 {
        self.passes.iter().map(|p| p.seconds).sum()
    }
}

/// The images of a frame, read back after it was timed.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameImages {
    pub width: u32,
    pub height: u32,
    /// The display image's code values.
    pub display: DisplayImage,
    /// Linear HDR RGBA as f32 (stored on the GPU as f16). Alpha carries the stall result.
    pub hdr: Vec<f32>,
    /// Samples shaded per pixel (1…M²), for adaptive modes.
    pub sample_counts: Option<Vec<u8>>,
}

/// A display image: code values per channel, RGBA, row-major from the top.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DisplayImage {
    /// Bits per channel of the target: 8, or 10 (alpha then has 2 bits, scaled to 0…1023).
    pub bits: u32,
    pub rgba: Vec<u16>,
}

impl DisplayImage {
    /// From an 8-bit image's bytes.
    pub fn from_rgba8(bytes: &[u8]) -> DisplayImage {
        DisplayImage { bits: 8, rgba: bytes.iter().map(|&b| u16::from(b)).collect() }
    }

    /// From a texture's bytes as read back: Rgba8Unorm or Rgb10a2Unorm.
    pub(super) fn from_texels(format: wgpu::TextureFormat, bytes: &[u8]) -> DisplayImage {
        match format {
            wgpu::TextureFormat::Rgb10a2Unorm => DisplayImage {
                bits: 10,
                rgba: bytes
                    .chunks_exact(4)
                    .flat_map(|t| {
                        let v = u32::from_le_bytes([t[0], t[1], t[2], t[3]]);
                        let channel = |shift: u32| (v >> shift & 0x3ff) as u16;
                        [channel(0), channel(10), channel(20), (v >> 30) as u16 * 341]
                    })
                    .collect(),
            },
            _ => DisplayImage::from_rgba8(bytes),
        }
    }

    /// The largest code value: 255 or 1023.
    pub fn max_code(&self) -> u16 {
        ((1u32 << self.bits) - 1) as u16
    }

    /// The code values as little-endian bytes, one per channel at 8 bits, two at 10: what
    /// run fingerprints hash.
    pub fn bytes(&self) -> Vec<u8> {
        if self.bits <= 8 {
            self.rgba.iter().map(|&v| v as u8).collect()
        } else {
            self.rgba.iter().flat_map(|v| v.to_le_bytes()).collect()
        }
    }
}

/// A G-buffer read back for checks: what the adaptive metric sees.
#[derive(Debug, Clone, PartialEq)]
pub struct GBufferImages {
    pub width: u32,
    pub height: u32,
    /// World-space normal and material index ([`crate::passes::gbuffer::BACKGROUND_MATERIAL`]: no geometry),
    /// per sample.
    pub normal_material: Vec<[f32; 4]>,
    /// Linear view depth per sample, recovered from the depth buffer in f64.
    pub depth: Vec<f64>,
}

impl GBufferImages {
    /// The indices of pixel (x, y)'s M×M samples, row by row.
    pub fn window_indices(&self, m: u32, x: u32, y: u32) -> impl Iterator<Item = usize> + use<> {
        let width = self.width;
        (0..m * m).map(move |i| ((y * m + i / m) * width + x * m + i % m) as usize)
    }

    /// The M×M window of samples of pixel (x, y), row by row, as the adaptive metric sees it.
    pub fn window(&self, m: u32, x: u32, y: u32) -> Vec<crate::technique::adaptive::WindowSample> {
        self.window_indices(m, x, y)
            .map(|s| {
                let [nx, ny, nz, material] = self.normal_material[s];
                crate::technique::adaptive::WindowSample {
                    depth: self.depth[s],
                    normal: [nx, ny, nz].map(f64::from),
                    covered: material >= 0.0,
                }
            })
            .collect()
    }
}

pub(super) fn read_display(gpu: &Gpu, texture: &wgpu::Texture) -> Result<DisplayImage, RenderError> {
    Ok(DisplayImage::from_texels(texture.format(), &gpu.read_texture(texture)?))
}

/// The shadow cubes of a frame, read back.
#[derive(Debug, Clone, PartialEq)]
pub struct ShadowDepths {
    pub resolution: u32,
    pub layers: u32,
    /// Reversed depth (1 at the near plane, 0 at the light's range), layer by layer.
    pub depth: Vec<f32>,
}

/// RGBA f16 texels as f32.
pub(super) fn half_texels(bytes: &[u8]) -> Vec<[f32; 4]> {
    bytes
        .chunks_exact(8)
        .map(|t| std::array::from_fn(|c| half::f16::from_le_bytes([t[2 * c], t[2 * c + 1]]).to_f32()))
        .collect()
}
