//! The Vulkan device (lavapipe on CI machines), the platform key recorded with every result,
//! timed submission and texture readback.

use std::any::Any;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crate::error::RenderError;

/// Everything about the machine that makes timings and images comparable. Two results with
/// the same [`PlatformInfo::key`] were rendered by the same driver, compiler and arithmetic, so
/// their images are the same bits; the CPU model and core count, which decide only their times,
/// are recorded beside it (and `runner::machine` tells one machine from another).
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct PlatformInfo {
    pub adapter: String,
    pub driver: String,
    pub driver_info: String,
    pub backend: String,
    pub device_type: String,
    /// `LP_NUM_THREADS` as set in the environment; `None` means lavapipe picks (one per core).
    pub lp_num_threads: Option<String>,
    pub cpu_model: String,
    pub cpu_cores: usize,
    /// Whether the CPU fuses multiply-add: llvmpipe's JIT emits `fmuladd`, which LLVM turns into
    /// one rounding where the CPU can and two where it cannot. `None` in records made before
    /// aabench recorded it.
    #[serde(default)]
    pub cpu_fma: Option<bool>,
    /// `release` or `debug`: CPU maths that feeds the GPU may differ by an ulp between them.
    pub build_profile: String,
}

impl PlatformInfo {
    /// A file-name-safe key of what decides a render's bits, e.g.
    /// `llvmpipe-mesa-22.3.6-llvm-15.0.6-256-bits-fma-release`: the driver and its version (Mesa
    /// and the LLVM that compiles the shaders), the vector width llvmpipe compiles for (its
    /// adapter name says it), whether the CPU fuses multiply-add, and the build profile. A GPU
    /// is named by its adapter. The CPU model, core count and `LP_NUM_THREADS` are not part of
    /// it: they change how fast lavapipe renders, not what (docs/gate.md says how that was
    /// measured).
    pub fn key(&self) -> String {
        let raw = if self.device_type == "cpu" {
            let width =
                vector_width(&self.adapter).map_or_else(|| self.adapter.clone(), |w| format!("{w} bits"));
            let fma = match self.cpu_fma {
                Some(true) => "fma",
                Some(false) => "no fma",
                None => "fma unknown",
            };
            format!("{} {} {width} {fma} {}", self.driver, self.driver_info, self.build_profile)
        } else {
            format!("{} {} {} {}", self.driver, self.driver_info, self.adapter, self.build_profile)
        };
        slug(&raw)
    }
}

/// The vector width in an llvmpipe adapter's name, `llvmpipe (LLVM 15.0.6, 256 bits)`.
fn vector_width(adapter: &str) -> Option<u32> {
    let words: Vec<&str> =
        adapter.split(|c: char| c.is_whitespace() || c == ',' || c == '(' || c == ')').collect();
    words.windows(2).find(|pair| pair[1] == "bits").and_then(|pair| pair[0].parse().ok())
}

/// Whether the CPU has fused multiply-add (`fma` among the first processor's flags in
/// `/proc/cpuinfo`); `None` where that cannot be read.
fn cpu_fma() -> Option<bool> {
    let info = std::fs::read_to_string("/proc/cpuinfo").ok()?;
    let flags = info.lines().find(|line| line.starts_with("flags"))?.split_once(':')?.1;
    Some(flags.split_whitespace().any(|flag| flag == "fma"))
}

/// Lowercases and keeps `[a-z0-9.]`, joining the other runs with single dashes.
fn slug(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars().flat_map(char::to_lowercase) {
        if c.is_ascii_alphanumeric() || c == '.' {
            out.push(c);
        } else if !out.is_empty() && !out.ends_with('-') {
            out.push('-');
        }
    }
    out.trim_end_matches('-').to_string()
}

fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|info| {
            info.lines()
                .find(|line| line.starts_with("model name"))
                .and_then(|line| line.split_once(':'))
                .map(|(_, name)| name.split_whitespace().collect::<Vec<_>>().join(" "))
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string())
}

/// The device and queue, with validation errors captured instead of panicking.
#[derive(Debug)]
pub struct Gpu {
    adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub platform: PlatformInfo,
    errors: Arc<Mutex<Vec<String>>>,
    /// What the renderer keeps on the device from one scene to the next (its pipelines, see
    /// `render::lend_pipelines`), of a type this layer does not know.
    kept: Mutex<Option<Box<dyn Any + Send>>>,
}

impl Gpu {
    /// Opens the first Vulkan adapter, or the first whose name contains `WGPU_ADAPTER_NAME`
    /// when that variable is set. Only Vulkan is asked for: the default backends also find a
    /// GL llvmpipe, which is a different driver with different timings.
    pub fn new() -> Result<Gpu, RenderError> {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = wgpu::Backends::VULKAN;
        let instance = wgpu::Instance::new(desc);
        let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::VULKAN));
        let wanted = std::env::var("WGPU_ADAPTER_NAME").ok();
        let adapter = adapters
            .into_iter()
            .find(|adapter| match &wanted {
                Some(name) => adapter.get_info().name.to_lowercase().contains(&name.to_lowercase()),
                None => true,
            })
            .ok_or(RenderError::NoAdapter)?;
        Self::open(&adapter)
    }

    fn open(adapter: &wgpu::Adapter) -> Result<Gpu, RenderError> {
        let info = adapter.get_info();
        // The adapter's own limits, not wgpu's conservative defaults: 4×4 G-buffers at
        // 1024×768 need 4096×3072 targets and more than the default buffer size.
        let limits = adapter.limits();
        // The 4× G-buffer's UV target (Rg32Float) multisamples on Vulkan devices, lavapipe
        // among them, but WebGPU does not guarantee it: only with this feature may it.
        let features = adapter.features() & wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("aabench"),
            required_features: features,
            required_limits: limits,
            ..Default::default()
        }))
        .map_err(|e| RenderError::Device(e.to_string()))?;

        let errors = Arc::new(Mutex::new(Vec::new()));
        let sink = Arc::clone(&errors);
        device.on_uncaptured_error(Arc::new(move |error: wgpu::Error| {
            sink.lock().expect("error sink").push(error.to_string());
        }));

        let platform = PlatformInfo {
            adapter: info.name.clone(),
            driver: info.driver.clone(),
            driver_info: info.driver_info.clone(),
            backend: format!("{:?}", info.backend).to_lowercase(),
            device_type: format!("{:?}", info.device_type).to_lowercase(),
            lp_num_threads: std::env::var("LP_NUM_THREADS").ok(),
            cpu_model: cpu_model(),
            cpu_cores: std::thread::available_parallelism().map_or(1, |n| n.get()),
            cpu_fma: cpu_fma(),
            build_profile: if cfg!(debug_assertions) { "debug" } else { "release" }.into(),
        };
        let kept = Mutex::new(None);
        Ok(Gpu { adapter: adapter.clone(), device, queue, platform, errors, kept })
    }

    /// Takes what a scene kept on the device for the next.
    pub(crate) fn take_kept(&self) -> Option<Box<dyn Any + Send>> {
        self.kept.lock().expect("kept").take()
    }

    /// Keeps `value` on the device for the next scene, in place of what was kept before.
    pub(crate) fn keep(&self, value: Box<dyn Any + Send>) {
        *self.kept.lock().expect("kept") = Some(value);
    }

    /// Whether this device renders `format` targets of `samples` samples per texel.
    pub fn multisamples(&self, format: wgpu::TextureFormat, samples: u32) -> bool {
        let adapter_specific =
            self.device.features().contains(wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES);
        let features = if adapter_specific {
            self.adapter.get_texture_format_features(format)
        } else {
            format.guaranteed_format_features(self.device.features())
        };
        features.flags.sample_count_supported(samples)
    }

    /// Returns the validation errors reported since the last call, as one error.
    pub fn check(&self) -> Result<(), RenderError> {
        let mut errors = self.errors.lock().expect("error sink");
        if errors.is_empty() {
            return Ok(());
        }
        let message = errors.join("; ");
        errors.clear();
        Err(RenderError::Validation(message))
    }

    /// Submits one command buffer and waits until the device has finished it. The returned
    /// duration runs from just before the submit to the end of the wait: on a CPU driver this
    /// wall clock is the dependable one (timestamps inside compute passes are not).
    pub fn submit_timed(&self, encoder: wgpu::CommandEncoder) -> Result<Duration, RenderError> {
        let commands = encoder.finish();
        let start = Instant::now();
        self.queue.submit([commands]);
        self.wait()?;
        let elapsed = start.elapsed();
        self.check()?;
        Ok(elapsed)
    }

    /// Blocks until all submitted work is done.
    pub fn wait(&self) -> Result<(), RenderError> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| RenderError::Device(e.to_string()))
    }

    pub fn encoder(&self, label: &str) -> wgpu::CommandEncoder {
        self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) })
    }

    /// Copies mip 0 of a 2D texture (colour, or the depth of a depth format) into memory, rows
    /// tightly packed.
    pub fn read_texture(&self, texture: &wgpu::Texture) -> Result<Vec<u8>, RenderError> {
        let aspect = if texture.format().is_depth_stencil_format() {
            wgpu::TextureAspect::DepthOnly
        } else {
            wgpu::TextureAspect::All
        };
        let texel =
            texture.format().block_copy_size(Some(aspect)).expect("a format with a readable aspect") as usize;
        let (width, height) = (texture.width() as usize, texture.height() as usize);
        // Every layer of an array, one after another.
        let rows = height * texture.depth_or_array_layers() as usize;
        let row = width * texel;
        let padded_row = row.next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT as usize);
        let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: (padded_row * rows) as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut encoder = self.encoder("readback");
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo { aspect, ..texture.as_image_copy() },
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded_row as u32),
                    rows_per_image: Some(height as u32),
                },
            },
            texture.size(),
        );
        self.queue.submit([encoder.finish()]);
        let bytes = self.map_read(&buffer)?;
        let mut packed = Vec::with_capacity(row * rows);
        for y in 0..rows {
            packed.extend_from_slice(&bytes[y * padded_row..y * padded_row + row]);
        }
        Ok(packed)
    }

    fn map_read(&self, buffer: &wgpu::Buffer) -> Result<Vec<u8>, RenderError> {
        let (sender, receiver) = std::sync::mpsc::channel();
        buffer.map_async(wgpu::MapMode::Read, .., move |result| {
            let _ = sender.send(result);
        });
        self.wait()?;
        receiver
            .recv()
            .map_err(|e| RenderError::Device(e.to_string()))?
            .map_err(|e| RenderError::Device(e.to_string()))?;
        let bytes = buffer.get_mapped_range(..).map_err(|e| RenderError::Device(e.to_string()))?.to_vec();
        buffer.unmap();
        self.check()?;
        Ok(bytes)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lavapipe() -> PlatformInfo {
        PlatformInfo {
            adapter: "llvmpipe (LLVM 15.0.6, 256 bits)".into(),
            driver: "llvmpipe".into(),
            driver_info: "Mesa 22.3.6 (LLVM 15.0.6)".into(),
            backend: "vulkan".into(),
            device_type: "cpu".into(),
            lp_num_threads: None,
            cpu_model: "AMD EPYC".into(),
            cpu_cores: 2,
            cpu_fma: Some(true),
            build_profile: "release".into(),
        }
    }

    #[test]
    fn slug_keeps_versions_and_joins_the_rest() {
        assert_eq!(
            slug("llvmpipe Mesa 22.3.6 (LLVM 15.0.6) 256 bits"),
            "llvmpipe-mesa-22.3.6-llvm-15.0.6-256-bits"
        );
    }

    #[test]
    fn the_key_names_what_decides_the_bits_and_not_the_cpu_that_ran_them() {
        let base = lavapipe();
        assert_eq!(base.key(), "llvmpipe-mesa-22.3.6-llvm-15.0.6-256-bits-fma-release");
        let other_cpu = PlatformInfo {
            cpu_model: "Intel(R) Xeon(R) Processor".into(),
            cpu_cores: 8,
            lp_num_threads: Some("1".into()),
            ..lavapipe()
        };
        assert_eq!(other_cpu.key(), base.key(), "the CPU model, cores and threads decide time, not bits");
        for (what, other) in [
            ("Mesa", PlatformInfo { driver_info: "Mesa 24.0.1 (LLVM 17.0.6)".into(), ..lavapipe() }),
            (
                "vector width",
                PlatformInfo { adapter: "llvmpipe (LLVM 15.0.6, 128 bits)".into(), ..lavapipe() },
            ),
            ("fused multiply-add", PlatformInfo { cpu_fma: Some(false), ..lavapipe() }),
            ("profile", PlatformInfo { build_profile: "debug".into(), ..lavapipe() }),
        ] {
            assert_ne!(other.key(), base.key(), "{what}");
        }
        let gpu = PlatformInfo {
            adapter: "NVIDIA H200".into(),
            driver: "NVIDIA".into(),
            driver_info: "560.35.03".into(),
            device_type: "discretegpu".into(),
            ..lavapipe()
        };
        assert_eq!(gpu.key(), "nvidia-560.35.03-nvidia-h200-release");
    }
}
