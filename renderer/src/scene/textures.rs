//! The scene's textures on the device: one mipmapped 2D array (lavapipe has no binding arrays),
//! sRGB, with a linear view for data textures. Each texture keeps its own power-of-two side:
//! when all share one side each fills a layer; otherwise the smaller ones are packed into
//! layers of the largest side ("pages"), so one large texture does not make every small one as
//! large (`docs/own-scene.md`, "Texture memory").

use super::{Encoding, Texture};

/// Textures larger than this are scaled down to it.
pub const MAX_TEXTURE_SIZE: u32 = 1024;

/// Where a texture lies in the array: its layer, its corner and its side, in texels of the
/// top level.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Place {
    pub layer: u32,
    pub x: u32,
    pub y: u32,
    pub side: u32,
}

/// How a scene's textures share the array.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Layout {
    /// The side of every layer: the largest texture's.
    pub side: u32,
    pub layers: u32,
    /// Per texture, in [`super::Scene::textures`] order.
    pub places: Vec<Place>,
}

impl Layout {
    /// Each texture at its power-of-two side (at most [`MAX_TEXTURE_SIZE`]). Packing puts them
    /// largest first in Morton order: every texture then starts at a multiple of its own side,
    /// so its mip levels stay texel-aligned and never share a texel with a neighbour, and no
    /// space is lost but the last layer's tail.
    pub fn of(textures: &[Texture]) -> Layout {
        let sides: Vec<u32> = textures.iter().map(texture_side).collect();
        let side = sides.iter().copied().max().unwrap_or(1);
        let mut order: Vec<usize> = (0..textures.len()).collect();
        order.sort_by_key(|&i| std::cmp::Reverse(sides[i]));
        let mut places = vec![Place { layer: 0, x: 0, y: 0, side }; textures.len()];
        let page = u64::from(side).pow(2);
        let (mut layer, mut used) = (0u32, 0u64);
        for i in order {
            let area = u64::from(sides[i]).pow(2);
            if used + area > page {
                (layer, used) = (layer + 1, 0);
            }
            let (x, y) = morton_decode(used / area);
            places[i] = Place { layer, x: x * sides[i], y: y * sides[i], side: sides[i] };
            used += area;
        }
        Layout { side, layers: if textures.is_empty() { 0 } else { layer + 1 }, places }
    }

    /// Whether textures share layers, so shaders must find them by their place
    /// (`TEXTURE_PAGES`); otherwise texture i is layer i.
    pub fn is_packed(&self) -> bool {
        self.places.iter().any(|p| p.side != self.side)
    }

    /// Bytes on the device: every layer with its full mip chain (RGBA8).
    pub fn bytes(&self) -> u64 {
        let levels = (0..=self.side.ilog2()).map(|level| u64::from(self.side >> level).pow(2));
        u64::from(self.layers) * 4 * levels.sum::<u64>()
    }

    /// The shaders' `texture_places` table: offset and side in units of the layer's side, and
    /// the layer.
    pub fn gpu_places(&self) -> Vec<[f32; 4]> {
        let side = self.side as f32;
        self.places
            .iter()
            .map(|p| [p.x as f32 / side, p.y as f32 / side, p.side as f32 / side, p.layer as f32])
            .collect()
    }
}

/// A texture's side in the array: its larger side rounded up to a power of two, at most
/// [`MAX_TEXTURE_SIZE`] (non-square textures are stretched to squares: UVs address them alike).
fn texture_side(texture: &Texture) -> u32 {
    texture.width.max(texture.height).next_power_of_two().min(MAX_TEXTURE_SIZE)
}

/// The cell of a Morton (Z-order) index: bits alternate x, y from the lowest.
fn morton_decode(index: u64) -> (u32, u32) {
    let (mut x, mut y) = (0u32, 0u32);
    for bit in 0..32 {
        x |= (((index >> (2 * bit)) & 1) as u32) << bit;
        y |= (((index >> (2 * bit + 1)) & 1) as u32) << bit;
    }
    (x, y)
}

/// Trilinear; the shaders add anisotropy with taps of their own (`sample_filtered`).
pub(super) fn sampler(device: &wgpu::Device) -> wgpu::Sampler {
    device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("scene textures"),
        address_mode_u: wgpu::AddressMode::Repeat,
        address_mode_v: wgpu::AddressMode::Repeat,
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        mipmap_filter: wgpu::MipmapFilterMode::Linear,
        ..Default::default()
    })
}

/// Uploads all textures (at least one) into one array laid out by `layout`: sRGB, with a linear
/// view for data textures (normal, occlusion, metallic-roughness); each texture's mipmaps average its values as its
/// encoding says. Levels of a layer below a packed texture's last are left zero: the shaders
/// never read them.
pub(super) fn upload(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    textures: &[Texture],
    layout: &Layout,
) -> wgpu::Texture {
    let array = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("scene textures"),
        size: wgpu::Extent3d {
            width: layout.side,
            height: layout.side,
            depth_or_array_layers: layout.layers,
        },
        mip_level_count: layout.side.ilog2() + 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8UnormSrgb,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[wgpu::TextureFormat::Rgba8Unorm],
    });
    for (chain, place) in mip_chains(textures, layout).iter().zip(&layout.places) {
        for (level, pixels) in chain.iter().enumerate() {
            let side = (place.side >> level).max(1);
            queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: &array,
                    mip_level: level as u32,
                    origin: wgpu::Origin3d { x: place.x >> level, y: place.y >> level, z: place.layer },
                    aspect: wgpu::TextureAspect::All,
                },
                pixels,
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(4 * side),
                    rows_per_image: Some(side),
                },
                wgpu::Extent3d { width: side, height: side, depth_or_array_layers: 1 },
            );
        }
    }
    array
}

/// Every texture scaled to its place's side with its full mip chain, spread over the cores.
fn mip_chains(textures: &[Texture], layout: &Layout) -> Vec<Vec<Vec<u8>>> {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let chunk = textures.len().div_ceil(threads).max(1);
    let work: Vec<(&Texture, u32)> = textures.iter().zip(&layout.places).map(|(t, p)| (t, p.side)).collect();
    std::thread::scope(|scope| {
        let workers: Vec<_> = work
            .chunks(chunk)
            .map(|part| {
                scope.spawn(move || part.iter().map(|&(t, side)| mip_chain(t, side)).collect::<Vec<_>>())
            })
            .collect();
        workers.into_iter().flat_map(|worker| worker.join().expect("mip generation panicked")).collect()
    })
}

fn mip_chain(texture: &Texture, size: u32) -> Vec<Vec<u8>> {
    let base = if texture.width == size && texture.height == size {
        texture.rgba.clone()
    } else {
        let image = image::RgbaImage::from_raw(texture.width, texture.height, texture.rgba.clone())
            .expect("texture size matches its pixels");
        image::imageops::resize(&image, size, size, image::imageops::FilterType::Triangle).into_raw()
    };
    let mut chain = vec![base];
    let mut side = size;
    while side > 1 {
        let next = downsample(chain.last().expect("level 0"), side, texture.encoding);
        side /= 2;
        chain.push(next);
    }
    chain
}

/// Halves a square RGBA8 image with a 2×2 box filter: sRGB colour in linear light (alpha is
/// linear), data as it is.
fn downsample(pixels: &[u8], side: u32, encoding: Encoding) -> Vec<u8> {
    let half = (side / 2) as usize;
    let side = side as usize;
    let linear = srgb_to_linear_table();
    let mut out = vec![0u8; half * half * 4];
    for y in 0..half {
        for x in 0..half {
            for c in 0..4 {
                let texel = |dx: usize, dy: usize| pixels[((2 * y + dy) * side + 2 * x + dx) * 4 + c];
                let quad = [texel(0, 0), texel(1, 0), texel(0, 1), texel(1, 1)];
                out[(y * half + x) * 4 + c] = if c == 3 || encoding == Encoding::Linear {
                    (quad.iter().map(|&v| u32::from(v)).sum::<u32>() as f32 / 4.0).round() as u8
                } else {
                    linear_to_srgb(quad.iter().map(|&v| linear[v as usize]).sum::<f32>() / 4.0)
                };
            }
        }
    }
    out
}

fn srgb_to_linear_table() -> [f32; 256] {
    std::array::from_fn(|i| {
        let v = i as f32 / 255.0;
        if v <= 0.04045 { v / 12.92 } else { ((v + 0.055) / 1.055).powf(2.4) }
    })
}

fn linear_to_srgb(v: f32) -> u8 {
    let encoded = if v <= 0.0031308 { v * 12.92 } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 };
    (encoded.clamp(0.0, 1.0) * 255.0).round() as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texture(side: u32) -> Texture {
        Texture {
            width: side,
            height: side,
            rgba: vec![128; (side * side * 4) as usize],
            encoding: Encoding::Srgb,
        }
    }

    #[test]
    fn downsampling_averages_colour_in_linear_light_and_data_as_it_is() {
        // Black and white average to linear 0.5, which sRGB encodes as 188, not 128.
        let pixels = [0, 0, 0, 255, 255, 255, 255, 255, 0, 0, 0, 255, 255, 255, 255, 255];
        assert_eq!(downsample(&pixels, 2, Encoding::Srgb), vec![188, 188, 188, 255]);
        // Data (a normal map's X, say) averages as it is.
        assert_eq!(downsample(&pixels, 2, Encoding::Linear), vec![128, 128, 128, 255]);
    }

    #[test]
    fn mip_chain_reaches_one_texel() {
        let texture = Texture { width: 8, height: 4, rgba: vec![128; 8 * 4 * 4], encoding: Encoding::Srgb };
        let chain = mip_chain(&texture, 8);
        let sides: Vec<usize> = chain.iter().map(|level| level.len() / 4).collect();
        assert_eq!(sides, vec![64, 16, 4, 1]);
        assert!(chain.iter().all(|level| level.iter().all(|&v| v == 128)));
    }

    #[test]
    fn textures_of_one_side_fill_a_layer_each() {
        let layout = Layout::of(&[texture(512), texture(300), texture(512)]);
        assert!(!layout.is_packed());
        assert_eq!((layout.side, layout.layers), (512, 3));
        let layers: Vec<u32> = layout.places.iter().map(|p| p.layer).collect();
        assert_eq!(layers, vec![0, 1, 2], "texture i is layer i");
    }

    #[test]
    fn small_textures_pack_into_pages_without_overlap_and_aligned() {
        // One large texture and 99 small ones, in a shuffled order, and a few of other sizes.
        let mut textures: Vec<Texture> = (0..99).map(|_| texture(256)).collect();
        textures.insert(37, texture(4096));
        textures.extend([texture(512), texture(128), texture(64), texture(1)]);
        let layout = Layout::of(&textures);
        assert!(layout.is_packed());
        assert_eq!(layout.side, MAX_TEXTURE_SIZE, "4096² is scaled down to the cap");
        // 1024² + 99·256² + 512² + 128² + 64² + 1 texels fill 8 layers of 1024², the last in part.
        assert_eq!(layout.layers, 8);
        for (i, a) in layout.places.iter().enumerate() {
            assert!(a.x.is_multiple_of(a.side) && a.y.is_multiple_of(a.side), "aligned: {a:?}");
            assert!(a.x + a.side <= layout.side && a.y + a.side <= layout.side, "inside: {a:?}");
            for b in &layout.places[i + 1..] {
                let apart = a.layer != b.layer
                    || a.x + a.side <= b.x
                    || b.x + b.side <= a.x
                    || a.y + a.side <= b.y
                    || b.y + b.side <= a.y;
                assert!(apart, "{a:?} overlaps {b:?}");
            }
        }
        // Every layer as large as the largest would take 104 layers: 13 times the memory.
        let unpacked = Layout { layers: textures.len() as u32, ..layout.clone() };
        assert_eq!(unpacked.bytes() / layout.bytes(), 13);
    }
}
