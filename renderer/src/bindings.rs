//! Bind groups from names: a shader's bindings are reflected with naga, and each is bound to
//! the resource of the same name (a scene resource, a port of the pass, or a constant the pass
//! owns). Layouts follow from the WGSL types and the resources together, so nothing pairs
//! resources with slots by position, and a resource whose kind, sample type or dimension does
//! not fit its WGSL declaration is an error naming the pass, the variable and both types.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use crate::error::RenderError;

/// A WGSL file compiled on the device, with the naga module it was reflected from.
#[derive(Debug)]
pub(crate) struct Shader {
    pub file: &'static str,
    pub module: wgpu::ShaderModule,
    naga: naga::Module,
    info: naga::valid::ModuleInfo,
}

/// What a WGSL global binding declares.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Kind {
    Uniform,
    Storage {
        writable: bool,
    },
    Texture {
        sample: Sample,
        dimension: wgpu::TextureViewDimension,
        /// `texture_multisampled_2d` or `texture_depth_multisampled_2d`: read sample by sample.
        multisampled: bool,
    },
    /// A non-comparison sampler.
    Sampler,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Sample {
    Float,
    Uint,
    Sint,
    Depth,
}

/// One binding an entry point uses.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Binding {
    pub group: u32,
    pub binding: u32,
    pub name: String,
    pub kind: Kind,
}

impl Shader {
    pub fn new(
        device: &wgpu::Device,
        dir: Option<&Path>,
        file: &'static str,
        text: &str,
    ) -> Result<Shader, RenderError> {
        // Errors name the file as read: the embedded copy, or the folder's.
        let shown = dir.map_or_else(|| format!("shaders/{file}"), |dir| dir.join(file).display().to_string());
        let naga = naga::front::wgsl::parse_str(text)
            .map_err(|e| RenderError::Shader(e.emit_to_string_with_path(text, &shown)))?;
        let info = naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::all(),
        )
        .validate(&naga)
        .map_err(|e| RenderError::Shader(format!("{shown}: {}", e.emit_to_string(text))))?;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(file),
            source: wgpu::ShaderSource::Wgsl(text.to_owned().into()),
        });
        Ok(Shader { file, module, naga, info })
    }

    /// The bindings that the entry points `entries` use, directly or through the functions
    /// they call, ordered by group and binding.
    pub fn bindings(&self, entries: &[&str]) -> Result<Vec<Binding>, RenderError> {
        let mut used = BTreeMap::new();
        for entry in entries {
            let index = self.naga.entry_points.iter().position(|e| e.name == *entry).ok_or_else(|| {
                RenderError::Shader(format!("shaders/{}: no entry point {entry}", self.file))
            })?;
            let function = self.info.get_entry_point(index);
            for (handle, global) in self.naga.global_variables.iter() {
                let Some(resource) = &global.binding else { continue };
                if function[handle].is_empty() {
                    continue;
                }
                let name = global.name.clone().unwrap_or_default();
                let kind = self.kind(global).ok_or_else(|| {
                    RenderError::Binding(format!(
                        "shaders/{}: {name} (group {}, binding {}) is of a kind aabench does not bind: \
                         storage textures, comparison samplers and binding arrays are not supported",
                        self.file, resource.group, resource.binding
                    ))
                })?;
                used.insert(
                    (resource.group, resource.binding),
                    Binding { group: resource.group, binding: resource.binding, name, kind },
                );
            }
        }
        Ok(used.into_values().collect())
    }

    /// What a binding declares; None for the kinds that nothing here binds.
    fn kind(&self, global: &naga::GlobalVariable) -> Option<Kind> {
        Some(match global.space {
            naga::AddressSpace::Uniform => Kind::Uniform,
            naga::AddressSpace::Storage { access } => {
                Kind::Storage { writable: access.contains(naga::StorageAccess::STORE) }
            }
            _ => match self.naga.types[global.ty].inner {
                naga::TypeInner::Sampler { comparison: false } => Kind::Sampler,
                naga::TypeInner::Image { dim, arrayed, class } => {
                    let (sample, multisampled) = match class {
                        naga::ImageClass::Depth { multi } => (Sample::Depth, multi),
                        naga::ImageClass::Sampled { kind: naga::ScalarKind::Uint, multi } => {
                            (Sample::Uint, multi)
                        }
                        naga::ImageClass::Sampled { kind: naga::ScalarKind::Sint, multi } => {
                            (Sample::Sint, multi)
                        }
                        naga::ImageClass::Sampled { kind: naga::ScalarKind::Float, multi } => {
                            (Sample::Float, multi)
                        }
                        _ => return None,
                    };
                    let dimension = match (dim, arrayed) {
                        (naga::ImageDimension::D1, _) => wgpu::TextureViewDimension::D1,
                        (naga::ImageDimension::D2, false) => wgpu::TextureViewDimension::D2,
                        (naga::ImageDimension::D2, true) => wgpu::TextureViewDimension::D2Array,
                        (naga::ImageDimension::D3, _) => wgpu::TextureViewDimension::D3,
                        (naga::ImageDimension::Cube, false) => wgpu::TextureViewDimension::Cube,
                        (naga::ImageDimension::Cube, true) => wgpu::TextureViewDimension::CubeArray,
                    };
                    Kind::Texture { sample, dimension, multisampled }
                }
                _ => return None,
            },
        })
    }
}

/// A resource offered for binding under a name.
#[derive(Debug, Clone)]
pub(crate) enum Bound {
    Buffer(wgpu::Buffer),
    /// A texture, whether shaders read it through a filtering sampler, and the format to view
    /// it in when not its own (the sRGB scene textures read as plain data).
    Texture {
        texture: wgpu::Texture,
        filterable: bool,
        view_format: Option<wgpu::TextureFormat>,
    },
    Sampler {
        sampler: wgpu::Sampler,
        filtering: bool,
    },
}

/// A binding matched with its resource: the layout entry and what the bind group holds.
#[derive(Debug)]
pub(crate) struct Resolved {
    pub group: u32,
    pub entry: wgpu::BindGroupLayoutEntry,
    pub resource: Held,
}

#[derive(Debug)]
pub(crate) enum Held {
    Buffer(wgpu::Buffer),
    View(wgpu::TextureView),
    Sampler(wgpu::Sampler),
}

impl Held {
    pub fn as_binding(&self) -> wgpu::BindingResource<'_> {
        match self {
            Held::Buffer(buffer) => buffer.as_entire_binding(),
            Held::View(view) => wgpu::BindingResource::TextureView(view),
            Held::Sampler(sampler) => wgpu::BindingResource::Sampler(sampler),
        }
    }
}

/// Which stages see a binding.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Stages {
    Render,
    Compute,
}

/// Matches every binding with the resource `lookup` finds under its name. `pass` names the
/// pass in errors; `bound` collects the names used, for the pass's check that every port it
/// declares is bound.
pub(crate) fn resolve(
    pass: &str,
    bindings: &[Binding],
    stages: Stages,
    lookup: &dyn Fn(&str) -> Option<Bound>,
    bound: &mut BTreeSet<String>,
) -> Result<Vec<Resolved>, RenderError> {
    bindings
        .iter()
        .map(|binding| {
            let resource = lookup(&binding.name).ok_or_else(|| {
                RenderError::Binding(format!(
                    "{pass}: the shader binds {} ({:?}) at group {}, binding {}, and nothing of that name is offered",
                    binding.name, binding.kind, binding.group, binding.binding
                ))
            })?;
            bound.insert(binding.name.clone());
            let (ty, held) = layout_type(pass, binding, resource)?;
            let visibility = match (stages, binding.kind) {
                (Stages::Compute, _) => wgpu::ShaderStages::COMPUTE,
                // Vertex shaders may not write storage buffers.
                (Stages::Render, Kind::Storage { writable: true }) => wgpu::ShaderStages::FRAGMENT,
                (Stages::Render, _) => wgpu::ShaderStages::VERTEX_FRAGMENT,
            };
            let entry = wgpu::BindGroupLayoutEntry { binding: binding.binding, visibility, ty, count: None };
            Ok(Resolved { group: binding.group, entry, resource: held })
        })
        .collect()
}

fn layout_type(
    pass: &str,
    binding: &Binding,
    resource: Bound,
) -> Result<(wgpu::BindingType, Held), RenderError> {
    let mismatch = |what: String| {
        RenderError::Binding(format!(
            "{pass}: {} is declared {:?} in WGSL (group {}, binding {}) but bound to {what}",
            binding.name, binding.kind, binding.group, binding.binding
        ))
    };
    let buffer = |ty| wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None };
    Ok(match (binding.kind, resource) {
        (Kind::Uniform, Bound::Buffer(b)) => (buffer(wgpu::BufferBindingType::Uniform), Held::Buffer(b)),
        (Kind::Storage { writable }, Bound::Buffer(b)) => {
            (buffer(wgpu::BufferBindingType::Storage { read_only: !writable }), Held::Buffer(b))
        }
        (
            Kind::Texture { sample, dimension, multisampled },
            Bound::Texture { texture, filterable, view_format },
        ) => {
            let format = view_format.unwrap_or(texture.format());
            let fits = match (sample, format.sample_type(None, None)) {
                (Sample::Float, Some(wgpu::TextureSampleType::Float { filterable: can })) => {
                    can || !filterable
                }
                (Sample::Uint, Some(wgpu::TextureSampleType::Uint)) => true,
                (Sample::Sint, Some(wgpu::TextureSampleType::Sint)) => true,
                (Sample::Depth, Some(wgpu::TextureSampleType::Depth)) => true,
                _ => false,
            };
            let layers = texture.depth_or_array_layers();
            let layers_fit = match dimension {
                wgpu::TextureViewDimension::D2 => layers == 1,
                wgpu::TextureViewDimension::Cube => layers == 6,
                wgpu::TextureViewDimension::CubeArray => layers % 6 == 0,
                _ => true,
            };
            // A multisampled texture is read sample by sample, never filtered.
            let samples = texture.sample_count();
            let samples_fit = multisampled == (samples > 1) && !(multisampled && filterable);
            if !fits || !layers_fit || !samples_fit {
                let how = if filterable { "filtered" } else { "loaded" };
                return Err(mismatch(format!(
                    "a {format:?} texture of {layers} layers and {samples} samples, {how}"
                )));
            }
            let sample_type = match sample {
                Sample::Float => wgpu::TextureSampleType::Float { filterable },
                Sample::Uint => wgpu::TextureSampleType::Uint,
                Sample::Sint => wgpu::TextureSampleType::Sint,
                Sample::Depth => wgpu::TextureSampleType::Depth,
            };
            let view = texture.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(dimension),
                format: view_format,
                ..Default::default()
            });
            (
                wgpu::BindingType::Texture { sample_type, view_dimension: dimension, multisampled },
                Held::View(view),
            )
        }
        (Kind::Sampler, Bound::Sampler { sampler, filtering }) => {
            let ty = if filtering {
                wgpu::SamplerBindingType::Filtering
            } else {
                wgpu::SamplerBindingType::NonFiltering
            };
            (wgpu::BindingType::Sampler(ty), Held::Sampler(sampler))
        }
        (_, Bound::Buffer(_)) => return Err(mismatch("a buffer".into())),
        (_, Bound::Texture { texture, .. }) => {
            return Err(mismatch(format!("a {:?} texture", texture.format())));
        }
        (_, Bound::Sampler { .. }) => return Err(mismatch("a sampler".into())),
    })
}

/// Layout entries per group index, groups in order; a group the shader does not use is empty.
pub(crate) fn group_entries(resolved: &[Resolved]) -> Vec<Vec<wgpu::BindGroupLayoutEntry>> {
    let groups = resolved.iter().map(|r| r.group + 1).max().unwrap_or(0) as usize;
    let mut entries = vec![Vec::new(); groups];
    for r in resolved {
        entries[r.group as usize].push(r.entry);
    }
    entries
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::Gpu;

    fn texture(gpu: &Gpu, format: wgpu::TextureFormat) -> wgpu::Texture {
        gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: None,
            size: wgpu::Extent3d { width: 4, height: 4, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        })
    }

    /// The gather pass's bindings are matched to resources by name. Swapping two textures'
    /// resources is refused naming the variable and the wrong format; a buffer where WGSL
    /// declares a texture, and a name nothing offers, are refused too.
    #[test]
    fn bindings_are_matched_by_name_and_a_swap_is_refused_naming_the_variable() {
        let gpu = Gpu::new().expect("lavapipe");
        let text = crate::shaders::compose("adaptive.wgsl", crate::shaders::Features::ALL).unwrap();
        let shader = Shader::new(&gpu.device, None, "adaptive.wgsl", &text).unwrap();
        let bindings = shader.bindings(&["fullscreen", "gather"]).unwrap();
        let names: Vec<&str> = bindings.iter().map(|b| b.name.as_str()).collect();
        assert_eq!(
            names,
            ["first", "counts", "list_offsets", "extra_samples", "sample_cells"],
            "{bindings:?}"
        );
        let first = texture(&gpu, wgpu::TextureFormat::Rgba16Float);
        let counts = texture(&gpu, wgpu::TextureFormat::R8Uint);
        let offsets = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: 16,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let offer = |swap: bool| {
            let (a, b) = if swap { (counts.clone(), first.clone()) } else { (first.clone(), counts.clone()) };
            let offsets = offsets.clone();
            move |name: &str| match name {
                "first" | "extra_samples" => {
                    Some(Bound::Texture { texture: a.clone(), filterable: false, view_format: None })
                }
                "counts" => Some(Bound::Texture { texture: b.clone(), filterable: false, view_format: None }),
                "list_offsets" | "sample_cells" => Some(Bound::Buffer(offsets.clone())),
                _ => None,
            }
        };
        let mut bound = BTreeSet::new();
        let resolved = resolve("gather", &bindings, Stages::Render, &offer(false), &mut bound).unwrap();
        assert_eq!(resolved.len(), 5);
        assert_eq!(bound.len(), 5);
        let error =
            resolve("gather", &bindings, Stages::Render, &offer(true), &mut bound).unwrap_err().to_string();
        assert!(error.contains("gather: first is declared") && error.contains("R8Uint"), "{error}");
        // A buffer where WGSL declares a texture, and a name nothing offers.
        let wrong = |name: &str| (name == "first").then(|| Bound::Buffer(offsets.clone()));
        let error = resolve("gather", &bindings, Stages::Render, &wrong, &mut bound).unwrap_err().to_string();
        assert!(error.contains("bound to a buffer"), "{error}");
        let error = resolve("gather", &bindings, Stages::Render, &|_: &str| None, &mut bound)
            .unwrap_err()
            .to_string();
        assert!(error.contains("nothing of that name is offered"), "{error}");
    }
}
