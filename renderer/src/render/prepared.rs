//! A mode ready to render: its passes in order, the textures holding its results, and for a
//! mode that carries a history, the frame uniforms and history it keeps between frames.

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex, MutexGuard};

use glam::DVec2;

use super::View;
use super::images::{
    DisplayImage, FrameImages, FrameTiming, GBufferImages, PassTime, ShadowDepths, half_texels, read_display,
};
use crate::error::RenderError;
use crate::frame::GraphSummary;
use crate::gpu::Gpu;
use crate::graph::Output;
use crate::mode::Mode;
use crate::passes::Pass;
use crate::scene::{Camera, FrameUniforms};
use crate::technique::taa;

/// What a mode that carries a history keeps between frames: frame uniforms of its own (with
/// the previous frame's camera, and jittered under TAA), the scene's view they are made from,
/// and where its history stands.
#[derive(Debug)]
pub(super) struct Temporal {
    pub(super) frame: wgpu::Buffer,
    pub(super) view: Arc<Mutex<View>>,
    pub(super) size: [u32; 2],
    /// Whether the frames are jittered (TAA); a `-stable` mode's are not.
    pub(super) jittered: bool,
    /// Whether the history is taken from where each point was in the frame before: only a
    /// test turns it off ([`PreparedMode::without_reprojection`]).
    pub(super) reprojected: bool,
    pub(super) history: Mutex<History>,
}

/// Frames rendered since the history was last reset, and the camera of the last one.
#[derive(Debug, Default)]
pub(super) struct History {
    frames: u32,
    camera: Option<Camera>,
}

impl Temporal {
    /// Writes the uniforms of the next frame: jittered by the frame's Halton point (TAA), with
    /// the camera of the frame before as the history's (this frame's own after a reset).
    fn next_frame(&self, queue: &wgpu::Queue) {
        let view = lock(&self.view);
        let mut history = lock(&self.history);
        let previous = history.camera.filter(|_| self.reprojected).unwrap_or(view.camera);
        let [x, y] = self.jitter(history.frames).unwrap_or_default();
        let uniforms = FrameUniforms::temporal(
            &view.camera,
            &previous,
            &view.lighting,
            self.size,
            DVec2::new(x, y),
            history.frames > 0,
        );
        queue.write_buffer(&self.frame, 0, bytemuck::bytes_of(&uniforms));
        history.frames += 1;
        history.camera = Some(view.camera);
    }

    /// The jitter of frame `index` after a reset, where the frames are jittered.
    fn jitter(&self, index: u32) -> Option<[f64; 2]> {
        self.jittered.then(|| taa::jitter(index))
    }
}

/// A lock that a panic elsewhere does not poison: what it guards is plain data, whole at every
/// step.
pub(super) fn lock<T>(mutex: &Mutex<T>) -> MutexGuard<'_, T> {
    mutex.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// A mode ready to render: its passes in order and the textures holding its results.
#[derive(Debug)]
pub struct PreparedMode {
    pub(super) gpu: Arc<Gpu>,
    pub mode: Mode,
    pub(super) passes: Vec<Box<dyn Pass>>,
    /// Where the colour end begins in `passes`: the first pass that encodes colour.
    pub(super) color_end: usize,
    pub(super) outputs: BTreeMap<Output, wgpu::Texture>,
    pub(super) graph: GraphSummary,
    pub(super) clip: (f64, f64),
    pub(super) temporal: Option<Temporal>,
}

impl PreparedMode {
    /// Renders one frame, one submit per pass, each timed from submit to completion. The frame
    /// of a mode that carries a history is the next of it: TAA's jittered and blended with the
    /// frames before, a `-stable` mode's counts following the frame before's.
    pub fn render(&self) -> Result<FrameTiming, RenderError> {
        if let Some(temporal) = &self.temporal {
            temporal.next_frame(&self.gpu.queue);
        }
        let mut timing = FrameTiming { passes: Vec::with_capacity(self.passes.len()) };
        for pass in &self.passes {
            let mut encoder = self.gpu.encoder(pass.name());
            pass.encode(&mut encoder);
            let elapsed = self.gpu.submit_timed(encoder)?;
            timing.passes.push(PassTime { name: pass.name(), seconds: elapsed.as_secs_f64() });
        }
        Ok(timing)
    }

    /// The jitter of the last frame in pixels, where the mode jitters: its sample of pixel
    /// (x, y) lay at (x + ½ + jitter.x, y + ½ + jitter.y).
    pub fn last_jitter(&self) -> Option<[f64; 2]> {
        let temporal = self.temporal.as_ref()?;
        let frames = lock(&temporal.history).frames;
        temporal.jitter(frames.checked_sub(1)?)
    }

    /// The mode with a history that does not follow motion: each frame takes it from the
    /// pixel's own place, as if nothing had moved. A deliberately broken TAA, for the tests that
    /// show a temporal measure tells it from the real one.
    pub fn without_reprojection(mut self) -> PreparedMode {
        if let Some(temporal) = &mut self.temporal {
            temporal.reprojected = false;
        }
        self
    }

    /// Forgets the history: the next frame starts it again, unjittered by earlier frames.
    pub fn reset_history(&self) {
        if let Some(temporal) = &self.temporal {
            *lock(&temporal.history) = History::default();
        }
    }

    /// The mode's frame at the current camera as a still: for a jittered mode, the last of
    /// [`taa::WARMUP_FRAMES`] frames rendered from a reset; for any other, one frame, from a
    /// reset where the mode carries a history. Returns the last frame's timing.
    pub fn render_still(&self) -> Result<FrameTiming, RenderError> {
        let jittered = self.temporal.as_ref().is_some_and(|temporal| temporal.jittered);
        let frames = if jittered { taa::WARMUP_FRAMES } else { 1 };
        self.reset_history();
        for _ in 1..frames {
            self.render()?;
        }
        self.render()
    }

    /// Encodes a given linear HDR image (RGBA, stored as f16 like every HDR image) through this
    /// mode's colour passes (tonemap, display, FXAA) and reads back the display image: how
    /// tests feed the display end values that no scene shades, NaN and infinities included.
    /// The HDR image of the last frame is overwritten.
    pub fn display_from_hdr(&self, hdr: &[[f32; 4]]) -> Result<DisplayImage, RenderError> {
        let target = self.output(Output::Hdr);
        let (width, height) = (target.width(), target.height());
        if hdr.len() != (width * height) as usize {
            return Err(RenderError::Limit(format!(
                "{} texels given for a {width}×{height} image",
                hdr.len()
            )));
        }
        let texels: Vec<u8> =
            hdr.iter().flatten().flat_map(|&v| half::f16::from_f32(v).to_le_bytes()).collect();
        self.gpu.queue.write_texture(
            target.as_image_copy(),
            &texels,
            wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(8 * width), rows_per_image: None },
            target.size(),
        );
        let mut encoder = self.gpu.encoder("display_from_hdr");
        for pass in &self.passes[self.color_end..] {
            pass.encode(&mut encoder);
        }
        self.gpu.submit_timed(encoder)?;
        self.read_display()
    }

    /// The compiled graph: passes in order, allocations and their bytes.
    pub fn graph(&self) -> &GraphSummary {
        &self.graph
    }

    fn output(&self, output: Output) -> &wgpu::Texture {
        &self.outputs[&output]
    }

    /// Reads back the display image of the last frame, for determinism checks.
    pub fn read_display(&self) -> Result<DisplayImage, RenderError> {
        read_display(&self.gpu, self.output(Output::Display))
    }

    /// Reads back the HDR image of the last frame: linear RGBA, alpha the stall's result.
    pub fn read_hdr(&self) -> Result<Vec<[f32; 4]>, RenderError> {
        Ok(half_texels(&self.gpu.read_texture(self.output(Output::Hdr))?))
    }

    /// Reads back the sample counts of the last frame (adaptive modes).
    pub fn read_sample_counts(&self) -> Result<Option<Vec<u8>>, RenderError> {
        self.outputs.get(&Output::SampleCounts).map(|t| self.gpu.read_texture(t)).transpose()
    }

    /// Reads back the single-sampled G-buffer of the last frame (every mode but MSAA's, whose
    /// multisampled G-buffer is not kept).
    pub fn read_gbuffer(&self) -> Result<GBufferImages, RenderError> {
        let kept = |output| {
            self.outputs.get(&output).ok_or_else(|| {
                RenderError::Binding("the multisampled G-buffer of msaa-4x is not read back".into())
            })
        };
        let normal = kept(Output::GBufferNormal)?;
        let normal_material = half_texels(&self.gpu.read_texture(normal)?);
        let (near, far) = self.clip;
        let depth = self
            .gpu
            .read_texture(kept(Output::GBufferDepth)?)?
            .chunks_exact(4)
            .map(|b| {
                let d = f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]]));
                near * far / (d * (far - near) + near)
            })
            .collect();
        Ok(GBufferImages { width: normal.width(), height: normal.height(), normal_material, depth })
    }

    /// Reads back the motion of the last frame (temporal modes): per pixel, the pixels its
    /// point moved since the frame before (x right, y down) and its linear view depth then.
    pub fn read_motion(&self) -> Result<Option<Vec<[f32; 4]>>, RenderError> {
        self.outputs.get(&Output::Motion).map(|t| Ok(half_texels(&self.gpu.read_texture(t)?))).transpose()
    }

    /// Reads back S, the shade-first image of an adaptive mode (linear RGBA).
    pub fn read_first(&self) -> Result<Option<Vec<[f32; 4]>>, RenderError> {
        self.outputs.get(&Output::First).map(|t| Ok(half_texels(&self.gpu.read_texture(t)?))).transpose()
    }

    /// Reads back the shadow cubes of the last frame, where the scene has shadow lights:
    /// reversed depth per texel, layer after layer (6 per light: +X, −X, +Y, −Y, +Z, −Z), each
    /// `resolution`² from the top row.
    pub fn read_shadow_cubes(&self) -> Result<Option<ShadowDepths>, RenderError> {
        let Some(cubes) = self.outputs.get(&Output::ShadowCubes) else { return Ok(None) };
        let depth = self
            .gpu
            .read_texture(cubes)?
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        Ok(Some(ShadowDepths { resolution: cubes.width(), layers: cubes.depth_or_array_layers(), depth }))
    }

    /// Reads back the images of the last frame. Call it before another mode of the same scene
    /// renders: modes share their allocations.
    pub fn read_images(&self) -> Result<FrameImages, RenderError> {
        let display = self.output(Output::Display);
        let hdr = self.read_hdr()?.into_iter().flatten().collect();
        Ok(FrameImages {
            width: display.width(),
            height: display.height(),
            display: read_display(&self.gpu, display)?,
            hdr,
            sample_counts: self.read_sample_counts()?,
        })
    }
}
