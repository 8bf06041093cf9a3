//! The WGSL sources in `shaders/`, embedded at build time, and the two preprocessor features
//! they use: a line `#include "lib/name.wgsl"` is replaced by that file (once per module), and
//! lines between `#ifdef NAME` (or `#ifndef NAME`), an optional `#else` and `#endif` are kept
//! only when the [`Features`] of the module say so. Features remove bindings, which override
//! constants cannot: an untextured scene's shaders declare no texture array, a scene without
//! shadow-casting lights no shadow cubes.

use std::collections::HashSet;
use std::path::{Path, PathBuf};

use crate::error::RenderError;

/// Every file under `shaders/`, by its path relative to that folder (`lib/common.wgsl`), in
/// name order; `build.rs` finds them.
pub const SOURCES: &[(&str, &str)] = include!(concat!(env!("OUT_DIR"), "/shaders.rs"));

/// The pass shaders: every source that is not an include under `lib/`.
pub fn pass_files() -> impl Iterator<Item = &'static str> {
    SOURCES.iter().map(|(name, _)| *name).filter(|name| !name.starts_with("lib/"))
}

/// Set to a folder to read shaders from disk instead of the embedded copies: edit WGSL and
/// re-run without rebuilding. (`SceneRenderer::read_shaders_from` gives one renderer its own
/// folder, to A/B two shader trees in one process.)
pub const SHADER_DIR_VARIABLE: &str = "AABENCH_SHADER_DIR";

/// The text of shader file `name`: from `dir` when given, else from `AABENCH_SHADER_DIR` when
/// set, else the embedded copy.
fn source(dir: Option<&Path>, name: &str) -> Result<String, RenderError> {
    let dir = dir.map(Path::to_path_buf).or_else(|| std::env::var_os(SHADER_DIR_VARIABLE).map(PathBuf::from));
    if let Some(dir) = dir {
        let path = dir.join(name);
        return std::fs::read_to_string(&path)
            .map_err(|e| RenderError::Shader(format!("{}: {e}", path.display())));
    }
    SOURCES
        .iter()
        .find(|(file, _)| *file == name)
        .map(|(_, text)| text.to_string())
        .ok_or_else(|| RenderError::Shader(format!("shaders/{name}: no such shader")))
}

/// What a scene needs its shaders to declare.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct Features {
    /// `TEXTURED`: the scene texture array, its sampler and every lookup into them.
    pub textured: bool,
    /// `SHADOWS`: the shadow cube array, its sampler and the shadow test in shading.
    pub shadows: bool,
    /// `LIGHT_KINDS`: spot and directional lights in shading; without it, every light is a
    /// point light and shading skips the kind's arithmetic.
    pub light_kinds: bool,
    /// `NORMAL_MAPS`: tangents as a second vertex buffer and the normal map's lookup in the
    /// G-buffer pass. Needs `textured`.
    pub normal_maps: bool,
    /// `EMISSIVE`: emitted radiance (factor, and texture where textured) in shading.
    pub emissive: bool,
    /// `OCCLUSION`: occlusion textures on the ambient term. Needs `textured`.
    pub occlusion: bool,
    /// `TEXTURE_TRANSFORM`: `KHR_texture_transform` on every lookup. Needs `textured`.
    pub texture_transform: bool,
    /// `TEXTURE_PAGES`: textures of different sizes share layers; lookups find each by its
    /// place. Needs `textured`.
    pub texture_pages: bool,
    /// `METALLIC_ROUGHNESS`: metallic-roughness textures in shading. Needs `textured`.
    pub metallic_roughness: bool,
    /// `MOVING`: an animation plays. The G-buffer pass reads each vertex's position in the
    /// frame before (the last vertex buffer) and takes motion vectors from it; a `-stable`
    /// mode follows them.
    pub moving: bool,
}

impl Features {
    pub const ALL: Features = Features {
        textured: true,
        shadows: true,
        light_kinds: true,
        normal_maps: true,
        emissive: true,
        occlusion: true,
        texture_transform: true,
        texture_pages: true,
        metallic_roughness: true,
        moving: true,
    };

    /// Every consistent combination (the texture features need `textured`), for tests that
    /// validate each variant of a shader.
    pub fn combinations() -> impl Iterator<Item = Features> {
        (0..1024)
            .map(|bits: u32| Features {
                textured: bits & 1 != 0,
                shadows: bits & 2 != 0,
                light_kinds: bits & 4 != 0,
                normal_maps: bits & 8 != 0,
                emissive: bits & 16 != 0,
                occlusion: bits & 32 != 0,
                texture_transform: bits & 64 != 0,
                texture_pages: bits & 128 != 0,
                metallic_roughness: bits & 256 != 0,
                moving: bits & 512 != 0,
            })
            .filter(|f| f.is_consistent())
    }

    /// Whether the texture features come with `textured`, whose bindings and functions they
    /// use.
    pub fn is_consistent(self) -> bool {
        self.textured
            || !(self.normal_maps
                || self.occlusion
                || self.texture_transform
                || self.texture_pages
                || self.metallic_roughness)
    }

    fn defines(self, name: &str) -> Option<bool> {
        match name {
            "TEXTURED" => Some(self.textured),
            "SHADOWS" => Some(self.shadows),
            "LIGHT_KINDS" => Some(self.light_kinds),
            "NORMAL_MAPS" => Some(self.normal_maps),
            "EMISSIVE" => Some(self.emissive),
            "OCCLUSION" => Some(self.occlusion),
            "TEXTURE_TRANSFORM" => Some(self.texture_transform),
            "TEXTURE_PAGES" => Some(self.texture_pages),
            "METALLIC_ROUGHNESS" => Some(self.metallic_roughness),
            "MOVING" => Some(self.moving),
            _ => None,
        }
    }
}

/// The text of `name` with its includes spliced in and its conditional lines resolved for
/// `features`, ready for naga.
pub fn compose(name: &str, features: Features) -> Result<String, RenderError> {
    compose_from(None, name, features)
}

/// [`compose`], reading the files from `dir` when given.
pub fn compose_from(dir: Option<&Path>, name: &str, features: Features) -> Result<String, RenderError> {
    if !features.is_consistent() {
        return Err(RenderError::Shader(format!("{features:?}: texture features need `textured`")));
    }
    let mut out = String::new();
    let mut seen = HashSet::new();
    splice(dir, name, features, &mut out, &mut seen)?;
    Ok(out)
}

fn splice(
    dir: Option<&Path>,
    name: &str,
    features: Features,
    out: &mut String,
    seen: &mut HashSet<String>,
) -> Result<(), RenderError> {
    if !seen.insert(name.to_string()) {
        return Ok(());
    }
    let error = |number: usize, message: &str| {
        RenderError::Shader(format!("shaders/{name}:{}: {message}", number + 1))
    };
    // Whether each open conditional keeps its lines, innermost last.
    let mut open: Vec<bool> = Vec::new();
    for (number, line) in source(dir, name)?.lines().enumerate() {
        let directive = line.trim();
        let condition = |rest: &str| {
            features
                .defines(rest.trim())
                .ok_or_else(|| error(number, &format!("unknown feature {:?}", rest.trim())))
        };
        if let Some(rest) = directive.strip_prefix("#ifdef ") {
            open.push(condition(rest)?);
        } else if let Some(rest) = directive.strip_prefix("#ifndef ") {
            open.push(!condition(rest)?);
        } else if directive == "#else" {
            let keep = open.last_mut().ok_or_else(|| error(number, "#else without #ifdef"))?;
            *keep = !*keep;
        } else if directive == "#endif" {
            open.pop().ok_or_else(|| error(number, "#endif without #ifdef"))?;
        } else if !open.iter().all(|&keep| keep) {
            continue;
        } else if let Some(rest) = directive.strip_prefix("#include") {
            let include = rest.trim().trim_matches('"');
            if include.is_empty() {
                return Err(error(number, "#include needs a file name"));
            }
            splice(dir, include, features, out, seen)?;
        } else {
            out.push_str(line);
            out.push('\n');
        }
    }
    if !open.is_empty() {
        return Err(RenderError::Shader(format!("shaders/{name}: #ifdef without #endif")));
    }
    Ok(())
}
