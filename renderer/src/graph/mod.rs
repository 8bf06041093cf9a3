//! A frame as a graph of passes with typed ports, compiled without a device.
//!
//! Each pass declares the ports it reads and writes: a texture (format, extent relative to the
//! output or to the M×M G-buffer, layers) or a storage buffer, and how the pass accesses it.
//! A [`Graph`] connects output ports to input ports, the way the seed paper "Shader Pipeline
//! and Effect Encapsulation" (§5) assembles its pipelines, and [`Graph::compile`] turns it into
//! a [`Plan`]: every read checked against its write, constraints checked across each
//! connection, passes ordered (dependencies first, ties in insertion order, so the submission
//! order that a benchmark measures is the one the recipe wrote), usage flags derived from the
//! accesses, lifetimes computed, and resources with equal descriptors and disjoint lifetimes
//! sharing one allocation (§6; see `allocate`). Retained outputs, which are read back after
//! the frame, live to its end and never share. A *carried* connection reads in the next frame
//! what a pass wrote in this one (a temporal mode's history): its resource spans every frame and
//! never shares, and its writer runs after its reader. Nothing is culled: a pass whose outputs nobody
//! reads still runs, since a benchmark must not drop timed work.

mod allocate;
mod describe;

use std::collections::HashMap;
use std::fmt;

pub use allocate::{Allocation, Physical};

/// Index of a pass in its graph, in insertion order.
pub type PassId = usize;

/// A texture's size, relative to what the frame is rendered at.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Extent {
    /// The output resolution, w × h.
    Output,
    /// The enlarged G-buffer of an M×M mode, M·w × M·h.
    GBuffer,
    Fixed {
        width: u32,
        height: u32,
    },
}

/// What a port carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Resource {
    /// A 2D texture of `layers` layers; `samples` > 1 makes it multisampled (one layer only).
    Texture {
        format: wgpu::TextureFormat,
        extent: Extent,
        layers: u32,
        samples: u32,
    },
    Buffer {
        bytes: u64,
    },
}

impl Resource {
    /// A single-layer, single-sampled 2D texture.
    pub fn texture(format: wgpu::TextureFormat, extent: Extent) -> Resource {
        Resource::Texture { format, extent, layers: 1, samples: 1 }
    }

    /// A single-layer 2D texture of `samples` samples per texel.
    pub fn multisampled(format: wgpu::TextureFormat, extent: Extent, samples: u32) -> Resource {
        Resource::Texture { format, extent, layers: 1, samples }
    }
}

/// How a pass touches a port's resource.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Access {
    /// Read through a filtering sampler.
    Sampled,
    /// Read texel by texel (`textureLoad`), or through a non-filtering sampler.
    Loaded,
    /// A storage buffer the pass only reads.
    StorageRead,
    /// A storage buffer the pass writes (and may read).
    StorageWrite,
    /// A colour attachment the pass renders into.
    Attachment,
    /// A depth attachment the pass renders into.
    Depth,
    /// The source of a copy, which no shader binds.
    CopySource,
    /// The destination of a copy: the pass writes it without a shader.
    CopyDestination,
}

impl Access {
    pub fn writes(self) -> bool {
        matches!(self, Access::StorageWrite | Access::Attachment | Access::Depth | Access::CopyDestination)
    }

    /// Whether the resource is bound to the shader (the rest are attachments and copies).
    pub fn is_binding(self) -> bool {
        !matches!(self, Access::Attachment | Access::Depth | Access::CopySource | Access::CopyDestination)
    }
}

/// One named input or output of a pass. Ports that shaders bind carry the name of the WGSL
/// variable they are bound to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Port {
    pub name: &'static str,
    pub resource: Resource,
    pub access: Access,
}

impl Port {
    pub fn new(name: &'static str, resource: Resource, access: Access) -> Port {
        Port { name, resource, access }
    }
}

/// What a pass is called and which ports it has.
#[derive(Debug, Clone, PartialEq)]
pub struct PassDecl {
    pub name: &'static str,
    pub ports: Vec<Port>,
}

impl PassDecl {
    pub fn port(&self, name: &str) -> Option<&Port> {
        self.ports.iter().find(|p| p.name == name)
    }
}

/// Results read back after a frame: kept alive to its end and never shared.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Output {
    /// The display-encoded 8-bit image.
    Display,
    /// The linear HDR image.
    Hdr,
    /// Samples shaded per pixel (adaptive modes).
    SampleCounts,
    /// S, the shade-first image of adaptive modes.
    First,
    /// The G-buffer's normal/material and depth targets, for the metric's checks.
    GBufferNormal,
    GBufferDepth,
    /// The depth cubes of shadow-casting lights.
    ShadowCubes,
    /// Per-pixel motion in pixels since the previous frame (temporal modes).
    Motion,
}

/// A port of a pass in a graph.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct PortRef {
    pub pass: PassId,
    pub port: &'static str,
}

/// Passes, each with a payload `T` (what builds it on a device; `()` in tests), connected
/// output → input, and the outputs retained for reading back.
#[derive(Debug)]
pub struct Graph<T> {
    passes: Vec<(PassDecl, T)>,
    edges: Vec<(PortRef, PortRef)>,
    /// Connections into the next frame: output → input.
    carried: Vec<(PortRef, PortRef)>,
    retained: Vec<(PortRef, Output)>,
}

impl<T> Default for Graph<T> {
    fn default() -> Self {
        Graph { passes: Vec::new(), edges: Vec::new(), carried: Vec::new(), retained: Vec::new() }
    }
}

/// What relative extents resolve against.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Dims {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel along each axis of the G-buffer.
    pub m: u32,
}

impl Dims {
    pub fn resolve(self, resource: Resource) -> Resolved {
        match resource {
            Resource::Buffer { bytes } => Resolved::Buffer { bytes },
            Resource::Texture { format, extent, layers, samples } => {
                let (width, height) = match extent {
                    Extent::Output => (self.width, self.height),
                    Extent::GBuffer => (self.m * self.width, self.m * self.height),
                    Extent::Fixed { width, height } => (width, height),
                };
                Resolved::Texture { format, width, height, layers, samples }
            }
        }
    }
}

/// A resource's descriptor with its size in texels or bytes: what an allocation is keyed by.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Resolved {
    Texture { format: wgpu::TextureFormat, width: u32, height: u32, layers: u32, samples: u32 },
    Buffer { bytes: u64 },
}

impl Resolved {
    pub fn bytes(&self) -> u64 {
        match *self {
            Resolved::Buffer { bytes } => bytes,
            Resolved::Texture { format, width, height, layers, samples } => {
                let texel = format.block_copy_size(None).unwrap_or(4);
                u64::from(width) * u64::from(height) * u64::from(layers * samples) * u64::from(texel)
            }
        }
    }
}

impl fmt::Display for Resolved {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Resolved::Buffer { bytes } => write!(f, "buffer {bytes} B"),
            Resolved::Texture { format, width, height, layers, samples } => {
                write!(f, "{format:?} {width}×{height}")?;
                if *layers > 1 {
                    write!(f, "×{layers}")?;
                }
                if *samples > 1 {
                    write!(f, " ({samples} samples)")?;
                }
                Ok(())
            }
        }
    }
}

/// Usage flags a resource needs, derived from every access to it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Usage {
    Texture(wgpu::TextureUsages),
    Buffer(wgpu::BufferUsages),
}

impl Usage {
    fn of(resource: Resolved, access: Access) -> Usage {
        match resource {
            // Storage access to a texture is refused when shaders are bound (bindings.rs).
            Resolved::Texture { .. } => Usage::Texture(match access {
                Access::Sampled | Access::Loaded => wgpu::TextureUsages::TEXTURE_BINDING,
                Access::StorageRead | Access::StorageWrite => wgpu::TextureUsages::STORAGE_BINDING,
                Access::Attachment | Access::Depth => wgpu::TextureUsages::RENDER_ATTACHMENT,
                Access::CopySource => wgpu::TextureUsages::COPY_SRC,
                Access::CopyDestination => wgpu::TextureUsages::COPY_DST,
            }),
            Resolved::Buffer { .. } => Usage::Buffer(match access {
                Access::CopySource => wgpu::BufferUsages::COPY_SRC,
                Access::CopyDestination => wgpu::BufferUsages::COPY_DST,
                _ => wgpu::BufferUsages::STORAGE,
            }),
        }
    }

    /// What reading back after the frame adds; a retained texture may also be written from
    /// the CPU (tests feed the colour passes HDR images that no scene shades).
    fn read_back(self) -> Usage {
        match self {
            Usage::Texture(u) => {
                Usage::Texture(u | wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::COPY_DST)
            }
            Usage::Buffer(u) => Usage::Buffer(u | wgpu::BufferUsages::COPY_SRC),
        }
    }

    fn union(self, other: Usage) -> Usage {
        match (self, other) {
            (Usage::Texture(a), Usage::Texture(b)) => Usage::Texture(a | b),
            (Usage::Buffer(a), Usage::Buffer(b)) => Usage::Buffer(a | b),
            _ => unreachable!("connections join textures with textures and buffers with buffers"),
        }
    }
}

/// One written port and everything that reads it: a resource of the frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Virtual {
    pub writer: PortRef,
    pub readers: Vec<PortRef>,
    pub desc: Resolved,
    pub usage: Usage,
    /// Positions in [`Plan::order`] of the first write and the last read; retained outputs
    /// and carried resources last until `order.len()`, after the frame.
    pub first: usize,
    pub last: usize,
    pub retained: Option<Output>,
    /// Read in the next frame: it spans every frame.
    pub carried: bool,
}

/// A compiled graph: the order to run passes in, the frame's resources and their allocation.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    pub dims: Dims,
    /// Pass ids in submission order.
    pub order: Vec<PassId>,
    pub names: Vec<&'static str>,
    pub resources: Vec<Virtual>,
    pub allocation: Allocation,
    ports: HashMap<PortRef, usize>,
}

impl Plan {
    /// The resource a port reads or writes.
    pub fn resource_of(&self, port: PortRef) -> Option<usize> {
        self.ports.get(&port).copied()
    }

    /// The allocation behind a port.
    pub fn physical_of(&self, port: PortRef) -> Option<usize> {
        self.resource_of(port).map(|r| self.allocation.assignment[r])
    }

    /// The allocation that holds a retained output.
    pub fn output(&self, output: Output) -> Option<usize> {
        let resource = self.resources.iter().position(|r| r.retained == Some(output))?;
        Some(self.allocation.assignment[resource])
    }

    pub fn pass_names(&self) -> Vec<&'static str> {
        self.order.iter().map(|&p| self.names[p]).collect()
    }

    /// Bytes of every allocation the plan makes.
    pub fn allocated_bytes(&self) -> u64 {
        self.allocation.bytes()
    }

    /// Bytes one allocation per written port would take.
    pub fn one_per_output_bytes(&self) -> u64 {
        allocate::one_per_resource_bytes(&self.resources)
    }

    /// Per descriptor, the most resources alive at once, in bytes.
    pub fn lower_bound_bytes(&self) -> u64 {
        allocate::lower_bound_bytes(&self.resources)
    }
}

/// Why a graph does not compile. Messages name the passes and ports involved.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum GraphError {
    #[error("two passes are named {0}")]
    DuplicatePass(&'static str),
    #[error("{pass} has two ports named {port}")]
    DuplicatePort { pass: &'static str, port: &'static str },
    #[error("a connection or retained output names pass {0}, but the graph has {1} passes")]
    UnknownPass(PassId, usize),
    #[error("{pass} has no port {port}")]
    UnknownPort { pass: &'static str, port: &'static str },
    #[error("{pass}.{port} is connected from, but it is read, not written")]
    NotAnOutput { pass: &'static str, port: &'static str },
    #[error("{pass}.{port} is connected to, but it is written, not read")]
    NotAnInput { pass: &'static str, port: &'static str },
    #[error("{pass}.{port} reads nothing: no pass writes it before")]
    Unwritten { pass: &'static str, port: &'static str },
    #[error("{pass}.{port} is connected to more than one output")]
    TwoWriters { pass: &'static str, port: &'static str },
    #[error("{from} ({from_desc}) is connected to {to}, which needs {to_desc}")]
    Mismatch { from: String, from_desc: String, to: String, to_desc: String },
    #[error("{port} is retained twice, or two ports are retained as {output:?}")]
    Retained { port: String, output: Output },
    #[error("the passes {} wait on each other in a cycle", .0.join(", "))]
    Cycle(Vec<&'static str>),
    #[error("{0} reads in the next frame what it writes: a pass cannot read and write one allocation")]
    CarriedIntoItself(&'static str),
}

impl<T> Graph<T> {
    pub fn new() -> Graph<T> {
        Graph::default()
    }

    pub fn add(&mut self, decl: PassDecl, node: T) -> PassId {
        self.passes.push((decl, node));
        self.passes.len() - 1
    }

    /// Connects an output port to an input port.
    pub fn connect(&mut self, from: PassId, from_port: &'static str, to: PassId, to_port: &'static str) {
        self.edges.push((PortRef { pass: from, port: from_port }, PortRef { pass: to, port: to_port }));
    }

    /// Connects same-named ports: what the G-buffer writes to what shading reads, for example.
    pub fn connect_all(&mut self, from: PassId, to: PassId, ports: &[&'static str]) {
        for port in ports {
            self.connect(from, port, to, port);
        }
    }

    /// Connects an output port to an input port of the next frame: `to` reads what `from`
    /// wrote in the frame before (a history). `from` runs after `to` within a frame.
    pub fn carry(&mut self, from: PassId, from_port: &'static str, to: PassId, to_port: &'static str) {
        self.carried.push((PortRef { pass: from, port: from_port }, PortRef { pass: to, port: to_port }));
    }

    /// Marks an output port as read back after the frame.
    pub fn retain(&mut self, pass: PassId, port: &'static str, output: Output) {
        self.retained.push((PortRef { pass, port }, output));
    }

    pub fn decl(&self, pass: PassId) -> &PassDecl {
        &self.passes[pass].0
    }

    pub fn node(&self, pass: PassId) -> &T {
        &self.passes[pass].1
    }

    pub fn len(&self) -> usize {
        self.passes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.passes.is_empty()
    }

    fn port(&self, r: PortRef) -> Result<&Port, GraphError> {
        let decl = &self.passes[r.pass].0;
        decl.port(r.port).ok_or(GraphError::UnknownPort { pass: decl.name, port: r.port })
    }

    fn label(&self, r: PortRef) -> String {
        format!("{}.{}", self.passes[r.pass].0.name, r.port)
    }

    /// Checks, orders and allocates the graph for frames of `dims`.
    pub fn compile(&self, dims: Dims) -> Result<Plan, GraphError> {
        let names: Vec<&'static str> = self.passes.iter().map(|(d, _)| d.name).collect();
        for (i, name) in names.iter().enumerate() {
            if names[..i].contains(name) {
                return Err(GraphError::DuplicatePass(name));
            }
            let ports = &self.passes[i].0.ports;
            if let Some(port) =
                ports.iter().enumerate().find(|(j, p)| ports[..*j].iter().any(|q| q.name == p.name))
            {
                return Err(GraphError::DuplicatePort { pass: name, port: port.1.name });
            }
        }
        let refs = self
            .edges
            .iter()
            .chain(&self.carried)
            .flat_map(|(a, b)| [a, b])
            .chain(self.retained.iter().map(|(p, _)| p));
        if let Some(bad) = refs.map(|r| r.pass).find(|&pass| pass >= self.passes.len()) {
            return Err(GraphError::UnknownPass(bad, self.passes.len()));
        }
        let writer_of = self.check_edges(dims)?;
        let order = self.order()?;
        let position: HashMap<PassId, usize> = order.iter().enumerate().map(|(i, &p)| (p, i)).collect();

        // One resource per written port, in submission order.
        let mut resources = Vec::new();
        let mut ports = HashMap::new();
        for &pass in &order {
            for port in self.passes[pass].0.ports.iter().filter(|p| p.access.writes()) {
                let writer = PortRef { pass, port: port.name };
                let desc = dims.resolve(port.resource);
                ports.insert(writer, resources.len());
                resources.push(Virtual {
                    writer,
                    readers: Vec::new(),
                    desc,
                    usage: Usage::of(desc, port.access),
                    first: position[&pass],
                    last: position[&pass],
                    retained: None,
                    carried: false,
                });
            }
        }
        for (reader, writer, carried) in &writer_of {
            let index = ports[writer];
            let resource = &mut resources[index];
            resource.readers.push(*reader);
            resource.usage = resource.usage.union(Usage::of(resource.desc, self.port(*reader)?.access));
            resource.last = resource.last.max(if *carried { order.len() } else { position[&reader.pass] });
            resource.carried |= carried;
            ports.insert(*reader, index);
        }
        for resource in &mut resources {
            resource.readers.sort_by_key(|r| (position[&r.pass], r.port));
        }
        for (port, output) in &self.retained {
            let index = match self.port(*port)?.access.writes() {
                true => ports[port],
                false => return Err(GraphError::NotAnOutput { pass: names[port.pass], port: port.port }),
            };
            let taken = self.retained.iter().filter(|(p, o)| p == port || o == output).count() > 1;
            if taken {
                return Err(GraphError::Retained { port: self.label(*port), output: *output });
            }
            let resource = &mut resources[index];
            resource.retained = Some(*output);
            resource.last = order.len();
            resource.usage = resource.usage.read_back();
        }
        let allocation = allocate::allocate(&resources);
        Ok(Plan { dims, order, names, resources, allocation, ports })
    }

    /// Checks every connection and every input; returns each input's writer and whether it
    /// reads the writer's previous frame.
    fn check_edges(&self, dims: Dims) -> Result<Vec<(PortRef, PortRef, bool)>, GraphError> {
        let mut writer_of: Vec<(PortRef, PortRef, bool)> = Vec::new();
        let edges = self.edges.iter().map(|&e| (e, false));
        for ((from, to), carried) in edges.chain(self.carried.iter().map(|&e| (e, true))) {
            if carried && from.pass == to.pass {
                return Err(GraphError::CarriedIntoItself(self.passes[from.pass].0.name));
            }
            let (out, input) = (self.port(from)?, self.port(to)?);
            if !out.access.writes() {
                return Err(GraphError::NotAnOutput { pass: self.passes[from.pass].0.name, port: from.port });
            }
            if input.access.writes() {
                return Err(GraphError::NotAnInput { pass: self.passes[to.pass].0.name, port: to.port });
            }
            let (from_desc, to_desc) = (dims.resolve(out.resource), dims.resolve(input.resource));
            if from_desc != to_desc {
                return Err(GraphError::Mismatch {
                    from: self.label(from),
                    from_desc: from_desc.to_string(),
                    to: self.label(to),
                    to_desc: to_desc.to_string(),
                });
            }
            if writer_of.iter().any(|(reader, _, _)| *reader == to) {
                return Err(GraphError::TwoWriters { pass: self.passes[to.pass].0.name, port: to.port });
            }
            writer_of.push((to, from, carried));
        }
        for (pass, (decl, _)) in self.passes.iter().enumerate() {
            for port in decl.ports.iter().filter(|p| !p.access.writes()) {
                if !writer_of.iter().any(|(reader, _, _)| *reader == PortRef { pass, port: port.name }) {
                    return Err(GraphError::Unwritten { pass: decl.name, port: port.name });
                }
            }
        }
        Ok(writer_of)
    }

    /// Kahn's algorithm, always taking the earliest-inserted pass that is ready.
    fn order(&self) -> Result<Vec<PassId>, GraphError> {
        let n = self.passes.len();
        let mut waiting = vec![0usize; n];
        let mut dependents = vec![Vec::new(); n];
        // A carried resource's writer waits for its reader: the reader must see the frame
        // before's, not this frame's.
        let carried = self.carried.iter().map(|&(from, to)| (to, from));
        for (from, to) in self.edges.iter().copied().chain(carried) {
            if from.pass != to.pass {
                waiting[to.pass] += 1;
                dependents[from.pass].push(to.pass);
            }
        }
        if let Some(&(from, _)) = self.edges.iter().find(|(from, to)| from.pass == to.pass) {
            return Err(GraphError::Cycle(vec![self.passes[from.pass].0.name]));
        }
        let mut order = Vec::with_capacity(n);
        let mut done = vec![false; n];
        while order.len() < n {
            let Some(next) = (0..n).find(|&p| !done[p] && waiting[p] == 0) else {
                return Err(GraphError::Cycle(self.cycle(&done, &dependents)));
            };
            done[next] = true;
            order.push(next);
            for &dependent in &dependents[next] {
                waiting[dependent] -= 1;
            }
        }
        Ok(order)
    }

    /// The passes left over when ordering stops that lie on a cycle: passes downstream of a
    /// cycle wait too, so those without a waiting dependent are dropped until none is left.
    fn cycle(&self, done: &[bool], dependents: &[Vec<PassId>]) -> Vec<&'static str> {
        let mut stuck: Vec<bool> = done.iter().map(|d| !d).collect();
        while let Some(sink) =
            (0..stuck.len()).find(|&p| stuck[p] && !dependents[p].iter().any(|&d| stuck[d]))
        {
            stuck[sink] = false;
        }
        (0..stuck.len()).filter(|&p| stuck[p]).map(|p| self.passes[p].0.name).collect()
    }
}

#[cfg(test)]
mod tests;
