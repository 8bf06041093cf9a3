//! The WGSL sources in `shaders/`, embedded at build time, and the one preprocessor feature they
//! use: a line `#include "lib/name.wgsl"` is replaced by that file (once per module).

use std::collections::HashSet;

use crate::RenderError;

macro_rules! sources {
    ($($name:literal),* $(,)?) => {
        /// Every file under `shaders/`, by its path relative to that folder.
        pub const SOURCES: &[(&str, &str)] = &[
            $(($name, include_str!(concat!("../../shaders/", $name)))),*
        ];
    };
}

sources!(
    "lib/common.wgsl",
    "lib/scene.wgsl",
    "lib/gbuffer.wgsl",
    "lib/shading.wgsl",
    "gbuffer.wgsl",
    "shade.wgsl",
    "resolve.wgsl",
    "display.wgsl",
    "adaptive.wgsl",
);

/// The pass shaders: every source that is not an include under `lib/`.
pub fn pass_files() -> impl Iterator<Item = &'static str> {
    SOURCES.iter().map(|(name, _)| *name).filter(|name| !name.starts_with("lib/"))
}

/// Set to a folder to read shaders from disk instead of the embedded copies: edit WGSL and
/// re-run without rebuilding, or A/B two shader trees in one process (each renderer reads the
/// variable when it first compiles a file).
pub const SHADER_DIR_VARIABLE: &str = "AABENCH_SHADER_DIR";

fn source(name: &str) -> Result<String, RenderError> {
    if let Some(dir) = std::env::var_os(SHADER_DIR_VARIABLE) {
        let path = std::path::Path::new(&dir).join(name);
        return std::fs::read_to_string(&path)
            .map_err(|e| RenderError::Shader(format!("{}: {e}", path.display())));
    }
    SOURCES
        .iter()
        .find(|(file, _)| *file == name)
        .map(|(_, text)| text.to_string())
        .ok_or_else(|| RenderError::Shader(format!("shaders/{name}: no such shader")))
}

/// The text of `name` with its includes spliced in, ready for naga.
pub fn compose(name: &str) -> Result<String, RenderError> {
    let mut out = String::new();
    let mut seen = HashSet::new();
    splice(name, &mut out, &mut seen)?;
    Ok(out)
}

fn splice(name: &str, out: &mut String, seen: &mut HashSet<String>) -> Result<(), RenderError> {
    if !seen.insert(name.to_string()) {
        return Ok(());
    }
    for (number, line) in source(name)?.lines().enumerate() {
        match line.trim().strip_prefix("#include") {
            Some(rest) => {
                let include = rest.trim().trim_matches('"');
                if include.is_empty() {
                    return Err(RenderError::Shader(format!(
                        "shaders/{name}:{}: #include needs a file name",
                        number + 1
                    )));
                }
                splice(include, out, seen)?;
            }
            None => {
                out.push_str(line);
                out.push('\n');
            }
        }
    }
    Ok(())
}

/// Compiles a pass shader into a module on `device`.
pub fn module(device: &wgpu::Device, name: &str) -> Result<wgpu::ShaderModule, RenderError> {
    let text = compose(name)?;
    Ok(device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(name),
        source: wgpu::ShaderSource::Wgsl(text.into()),
    }))
}
