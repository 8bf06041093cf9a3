//! The renderer's integration tests, one module a file beside this one, in one binary: its
//! tests share one device (`support::gpu`) and render one at a time.
//!
//! One binary, not one a file: each binary links every dependency on its own, and cargo runs
//! the binaries one after the other. Building the workspace's crates and their tests took 229 s
//! with 37 binaries and 195 s with three, on 2 cores.

mod support;

mod adaptive;
mod animation;
mod color;
mod foundation;
mod graph;
mod import;
mod lights;
mod materials;
mod msaa;
mod properties;
mod shaders;
mod shadows;
mod skin;
mod smaa;
mod stable;
mod taa;
