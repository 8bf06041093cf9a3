//! The runner's integration tests, one module a file beside this one, in one binary.
//!
//! One binary, not one a file: each binary links every dependency on its own, and cargo runs
//! the binaries one after the other. Building the workspace's crates and their tests took 229 s
//! with 37 binaries and 195 s with three, on 2 cores.

mod source;
mod support;

mod baselines;
mod cli;
mod docs;
mod extreme;
mod flicker;
mod front;
mod fuzz;
mod gate;
mod gate_evidence;
mod layering;
mod moving;
mod own_scene;
mod perceptual;
mod robustness;
mod sequence;
mod size;
mod workflows;
