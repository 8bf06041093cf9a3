//! Materials and the texture slots they use, with `KHR_texture_transform`.

use std::collections::HashMap;

use crate::scene::{AlphaMode, Encoding, Material, TextureRef, UvTransform};

/// The textures that materials sample, in order of first use: each image once per encoding
/// it is read with (an image could be both a colour and a data texture).
#[derive(Default)]
struct TextureUses {
    keys: Vec<(usize, Encoding)>,
    index: HashMap<(usize, Encoding), usize>,
}

impl TextureUses {
    fn add(&mut self, image: usize, encoding: Encoding) -> usize {
        *self.index.entry((image, encoding)).or_insert_with(|| {
            self.keys.push((image, encoding));
            self.keys.len() - 1
        })
    }
}

/// One texture slot of a material as the JSON gives it: texture index, UV set, transform.
struct Slot<'a> {
    field: &'static str,
    texture: usize,
    tex_coord: u32,
    transform: Option<std::borrow::Cow<'a, gltf::json::extensions::texture::TextureTransform>>,
    encoding: Encoding,
}

/// The texture slots of a material that aabench reads: base colour, metallic-roughness,
/// normal, emissive and occlusion.
fn texture_slots(json: &gltf::json::Material) -> Result<Vec<Slot<'_>>, String> {
    use gltf::json::extensions::texture::TextureTransform;
    use std::borrow::Cow;
    fn info<'a>(field: &'static str, info: &'a gltf::json::texture::Info, encoding: Encoding) -> Slot<'a> {
        Slot {
            field,
            texture: info.index.value(),
            tex_coord: info.tex_coord,
            transform: info.extensions.as_ref().and_then(|e| e.texture_transform.as_ref()).map(Cow::Borrowed),
            encoding,
        }
    }
    // The crate keeps the extension of normal and occlusion textures as plain JSON.
    type Others = serde_json::Map<String, serde_json::Value>;
    let data = |field: &'static str, texture: usize, tex_coord: u32, others: Option<&Others>| {
        let transform = others
            .and_then(|o| o.get("KHR_texture_transform"))
            .map(|v| {
                serde_json::from_value::<TextureTransform>(v.clone())
                    .map(Cow::Owned)
                    .map_err(|e| format!("{field}.extensions.KHR_texture_transform: {e}"))
            })
            .transpose()?;
        Ok::<_, String>(Slot { field, texture, tex_coord, transform, encoding: Encoding::Linear })
    };
    let mut slots = Vec::new();
    if let Some(base) = &json.pbr_metallic_roughness.base_color_texture {
        slots.push(info("pbrMetallicRoughness.baseColorTexture", base, Encoding::Srgb));
    }
    if let Some(n) = &json.normal_texture {
        slots.push(data(
            "normalTexture",
            n.index.value(),
            n.tex_coord,
            n.extensions.as_ref().map(|e| &e.others),
        )?);
    }
    if let Some(metal_rough) = &json.pbr_metallic_roughness.metallic_roughness_texture {
        slots.push(info("pbrMetallicRoughness.metallicRoughnessTexture", metal_rough, Encoding::Linear));
    }
    if let Some(emissive) = &json.emissive_texture {
        slots.push(info("emissiveTexture", emissive, Encoding::Srgb));
    }
    if let Some(o) = &json.occlusion_texture {
        slots.push(data(
            "occlusionTexture",
            o.index.value(),
            o.tex_coord,
            o.extensions.as_ref().map(|e| &e.others),
        )?);
    }
    Ok(slots)
}

/// A slot's UV transform, checked: finite offset, rotation and scale.
fn uv_transform(
    transform: Option<&gltf::json::extensions::texture::TextureTransform>,
) -> Result<UvTransform, String> {
    let Some(t) = transform else {
        return Ok(UvTransform::IDENTITY);
    };
    let values = [t.offset.0[0], t.offset.0[1], t.rotation.0, t.scale.0[0], t.scale.0[1]];
    if !values.iter().all(|v| v.is_finite()) {
        return Err(format!(
            "extensions.KHR_texture_transform: offset {:?}, rotation {}, scale {:?} must be finite",
            t.offset.0, t.rotation.0, t.scale.0
        ));
    }
    Ok(UvTransform::new(t.offset.0, t.rotation.0, t.scale.0))
}

/// What [`import_materials`] reads: materials in file order plus one default at the end for
/// primitives without a material; the textures they use (image and encoding, indexed by
/// [`TextureRef::texture`]); and a warning for each texture that aabench cannot place (it
/// reads one UV set, `TEXCOORD_0`).
pub(super) struct Materials {
    pub(super) materials: Vec<Material>,
    pub(super) textures: Vec<(usize, Encoding)>,
    pub(super) warnings: Vec<String>,
}

pub(super) fn import_materials(document: &gltf::Document) -> Result<Materials, String> {
    let mut uses = TextureUses::default();
    let mut warnings = Vec::new();
    let mut materials = Vec::new();
    for material in document.materials() {
        let index = material.index().unwrap_or(materials.len());
        let json = &document.as_json().materials[index];
        let mut refs: HashMap<&'static str, (TextureRef, Encoding)> = HashMap::new();
        for slot in texture_slots(json).map_err(|e| format!("materials[{index}].{e}"))? {
            let what = format!("materials[{index}].{}", slot.field);
            let transform = uv_transform(slot.transform.as_deref()).map_err(|e| format!("{what}.{e}"))?;
            let tex_coord = slot.transform.as_ref().and_then(|t| t.tex_coord).unwrap_or(slot.tex_coord);
            if tex_coord != 0 {
                warnings.push(format!(
                    "{what}: uses TEXCOORD_{tex_coord}; aabench reads only TEXCOORD_0, so the texture is ignored"
                ));
                continue;
            }
            let image = document
                .textures()
                .nth(slot.texture)
                .ok_or_else(|| format!("{what}.index: texture {} does not exist", slot.texture))?
                .source()
                .index();
            let texture = uses.add(image, slot.encoding);
            refs.insert(slot.field, (TextureRef { texture, transform }, slot.encoding));
        }
        let slot = |field: &str| refs.get(field).map(|(r, _)| *r);
        let pbr = material.pbr_metallic_roughness();
        let strength = material.emissive_strength().unwrap_or(1.0);
        let emissive = material.emissive_factor().map(|c| c * strength);
        if !emissive.iter().all(|c| c.is_finite() && *c >= 0.0) {
            return Err(format!(
                "materials[{index}]: emissiveFactor {:?} × KHR_materials_emissive_strength {strength} must be finite and ≥ 0",
                material.emissive_factor()
            ));
        }
        let normal_scale = material.normal_texture().map_or(1.0, |n| n.scale());
        if !normal_scale.is_finite() {
            return Err(format!("materials[{index}].normalTexture.scale: {normal_scale} must be finite"));
        }
        let occlusion_strength = material.occlusion_texture().map_or(1.0, |o| o.strength());
        if !(0.0..=1.0).contains(&occlusion_strength) {
            return Err(format!(
                "materials[{index}].occlusionTexture.strength: {occlusion_strength} must be in [0, 1]"
            ));
        }
        materials.push(Material {
            name: material.name().unwrap_or("").to_string(),
            base_color: pbr.base_color_factor(),
            metallic: pbr.metallic_factor(),
            roughness: pbr.roughness_factor(),
            texture: slot("pbrMetallicRoughness.baseColorTexture"),
            alpha: match material.alpha_mode() {
                gltf::material::AlphaMode::Mask => {
                    AlphaMode::Mask { cutoff: material.alpha_cutoff().unwrap_or(0.5) }
                }
                _ => AlphaMode::Opaque,
            },
            double_sided: material.double_sided(),
            normal_texture: slot("normalTexture"),
            normal_scale,
            emissive,
            emissive_texture: slot("emissiveTexture"),
            occlusion_texture: slot("occlusionTexture"),
            occlusion_strength,
            metallic_roughness_texture: slot("pbrMetallicRoughness.metallicRoughnessTexture"),
        });
    }
    materials.push(Material {
        name: "default".into(),
        base_color: [0.8, 0.8, 0.8, 1.0],
        metallic: 0.0,
        roughness: 0.6,
        ..Material::default()
    });
    Ok(Materials { materials, textures: uses.keys, warnings })
}
