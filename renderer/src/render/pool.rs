//! Textures and buffers shared between the graphs of a scene's modes, which never run at the
//! same time, and created in the order a frame first writes them.

use std::collections::{BTreeMap, HashMap};

use crate::error::RenderError;
use crate::graph::{Output, Physical, Plan, Resolved, Usage};
use crate::mode::Mode;
use crate::passes::Allocated;

/// The retained outputs' textures.
pub(super) fn outputs(plan: &Plan, allocated: &[Allocated]) -> BTreeMap<Output, wgpu::Texture> {
    plan.resources
        .iter()
        .enumerate()
        .filter_map(|(index, resource)| {
            let output = resource.retained?;
            match &allocated[plan.allocation.assignment[index]] {
                Allocated::Texture(texture) => Some((output, texture.clone())),
                Allocated::Buffer(_) => None,
            }
        })
        .collect()
}

/// Textures and buffers keyed by descriptor, usage and ordinal: what graphs that never run
/// at the same time share. An allocation carried into the next frame (a history) is kept for
/// its mode alone: its key names the mode, so a scene holds one prepared instance of a
/// temporal mode at a time (two would share one history).
#[derive(Debug, Default)]
pub(super) struct Pool {
    entries: HashMap<PoolKey, Allocated>,
}

type PoolKey = (Resolved, Usage, usize, Option<Mode>);

fn pool_key(physical: &Physical, mode: Mode) -> PoolKey {
    (physical.desc, physical.usage, physical.ordinal, physical.carried.then_some(mode))
}

/// A target of a plan wider or taller than the device allows, named by its writing port.
#[derive(Debug)]
pub(super) struct Oversized {
    pub(super) port: String,
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) limit: u32,
}

impl Oversized {
    pub(super) fn find(plan: &Plan, limit: u32) -> Option<Oversized> {
        plan.allocation.physical.iter().find_map(|physical| match physical.desc {
            Resolved::Texture { width, height, .. } if width.max(height) > limit => {
                let writer = plan.resources[physical.resources[0]].writer;
                let port = format!("{}.{}", plan.names[writer.pass], writer.port);
                Some(Oversized { port, width, height, limit })
            }
            _ => None,
        })
    }
}

impl std::fmt::Display for Oversized {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let Oversized { port, width, height, limit } = self;
        write!(f, "{port}: a {width}×{height} target exceeds the device's limit of {limit} texels per side")
    }
}

impl Pool {
    /// An allocation for each of the plan's, created where the pool has none yet, in the
    /// order the frame first writes them: lavapipe's textures are plain memory, and where they
    /// land relative to each other decides how the loads of one texel from several targets
    /// share the CPU's caches.
    pub(super) fn acquire(
        &mut self,
        device: &wgpu::Device,
        plan: &Plan,
        mode: Mode,
    ) -> Result<Vec<Allocated>, RenderError> {
        if let Some(oversized) = Oversized::find(plan, device.limits().max_texture_dimension_2d) {
            return Err(RenderError::Limit(oversized.to_string()));
        }
        let physical = &plan.allocation.physical;
        let first_write = |p: usize| physical[p].resources.iter().map(|&r| plan.resources[r].first).min();
        let mut creation: Vec<usize> = (0..physical.len()).collect();
        creation.sort_by_key(|&p| (first_write(p), p));
        let mut allocated = vec![None; physical.len()];
        for p in creation {
            let physical = &physical[p];
            let key = pool_key(physical, mode);
            allocated[p] = Some(self.entries.entry(key).or_insert_with(|| create(device, physical)).clone());
        }
        Ok(allocated.into_iter().map(|a| a.expect("every allocation acquired")).collect())
    }

    pub(super) fn bytes(&self) -> u64 {
        self.entries.keys().map(|(desc, ..)| desc.bytes()).sum()
    }

    /// Bytes that acquiring `plan` for `mode` would newly allocate.
    pub(super) fn missing_bytes(&self, plan: &Plan, mode: Mode) -> u64 {
        plan.allocation
            .physical
            .iter()
            .filter(|p| !self.entries.contains_key(&pool_key(p, mode)))
            .map(|p| p.desc.bytes())
            .sum()
    }
}

fn create(device: &wgpu::Device, physical: &Physical) -> Allocated {
    let label = Some(physical.desc.to_string());
    match (physical.desc, physical.usage) {
        (Resolved::Texture { format, width, height, layers, samples }, Usage::Texture(usage)) => {
            Allocated::Texture(device.create_texture(&wgpu::TextureDescriptor {
                label: label.as_deref(),
                size: wgpu::Extent3d { width, height, depth_or_array_layers: layers },
                mip_level_count: 1,
                sample_count: samples,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            }))
        }
        (Resolved::Buffer { bytes }, Usage::Buffer(usage)) => {
            Allocated::Buffer(device.create_buffer(&wgpu::BufferDescriptor {
                label: label.as_deref(),
                size: bytes,
                usage,
                mapped_at_creation: false,
            }))
        }
        _ => unreachable!("a texture's usage is a texture usage"),
    }
}
