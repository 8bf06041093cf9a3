//! Images: from files, buffer views or data URIs, decoded (PNG, JPEG) and size-checked.

use std::path::Path;

use super::files::{ImageSource, decode_data_uri, image_source, percent_decode};
use super::primitives::view_bytes;
use crate::scene::{Encoding, Texture};

/// The largest texture side decoded (the largest 2D texture Vulkan devices commonly allow);
/// a larger image is refused from its header, before its pixels are read.
pub const MAX_TEXTURE_SIDE: u32 = 16384;

/// Decodes the images that materials use, in parallel: a Sponza-sized scene has
/// dozens of PNG/JPEG files and decoding dominates its load time.
pub(super) fn decode_textures(
    document: &gltf::Document,
    base: &Path,
    buffers: &[gltf::buffer::Data],
    wanted: &[(usize, Encoding)],
) -> Result<Vec<Texture>, String> {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let chunk = wanted.len().div_ceil(threads).max(1);
    std::thread::scope(|scope| {
        let workers: Vec<_> = wanted
            .chunks(chunk)
            .map(|part| {
                scope.spawn(move || {
                    part.iter()
                        .map(|&(image, encoding)| decode_image(document, image, encoding, base, buffers))
                        .collect::<Result<Vec<_>, _>>()
                })
            })
            .collect();
        let mut textures = Vec::with_capacity(wanted.len());
        for worker in workers {
            textures.extend(worker.join().expect("texture decoder panicked")?);
        }
        Ok(textures)
    })
}

/// One image to RGBA8. Errors name the image and where it comes from.
fn decode_image(
    document: &gltf::Document,
    index: usize,
    encoding: Encoding,
    base: &Path,
    buffers: &[gltf::buffer::Data],
) -> Result<Texture, String> {
    let (bytes, what) = match image_source(document, index)? {
        ImageSource::View(view) => {
            let what = format!("images[{index}] (bufferViews[{}])", view.index());
            let bytes = view_bytes(&view, buffers).map_err(|e| format!("{what}: {e}"))?;
            (std::borrow::Cow::Borrowed(bytes), what)
        }
        ImageSource::Uri(uri) if uri.starts_with("data:") => {
            // Decoded here rather than by the gltf crate, so an embedded image meets the same
            // size check and limits as one in a file.
            let what = format!("images[{index}] (data URI)");
            (std::borrow::Cow::Owned(decode_data_uri(uri).map_err(|e| format!("{what}: {e}"))?), what)
        }
        ImageSource::Uri(uri) => {
            let path = base.join(percent_decode(uri).map_err(|e| format!("images[{index}].uri: {e}"))?);
            let what = format!("images[{index}] (uri {})", super::files::shown(uri));
            let bytes = std::fs::read(&path).map_err(|e| format!("{what}: {}: {e}", path.display()))?;
            (std::borrow::Cow::Owned(bytes), what)
        }
    };
    if bytes.is_empty() {
        return Err(format!("{what}: the image is empty (0 bytes)"));
    }
    let reader = || {
        image::ImageReader::new(std::io::Cursor::new(&bytes[..]))
            .with_guessed_format()
            .map_err(|e| format!("{what}: {e}"))
    };
    let (width, height) = reader()?.into_dimensions().map_err(|e| format!("{what}: cannot decode: {e}"))?;
    if width > MAX_TEXTURE_SIDE || height > MAX_TEXTURE_SIDE {
        return Err(format!(
            "{what}: {width}×{height} is larger than the {MAX_TEXTURE_SIDE}×{MAX_TEXTURE_SIDE} textures aabench decodes"
        ));
    }
    let mut limits = image::Limits::default();
    // The largest accepted image at 16 bits × 4 channels; the crate's default (512 MiB) would
    // refuse images the renderer handles by scaling them down.
    limits.max_alloc = Some(u64::from(MAX_TEXTURE_SIDE).pow(2) * 8);
    let mut decoder = reader()?;
    decoder.limits(limits);
    let decoded = decoder.decode().map_err(|e| format!("{what}: cannot decode: {e}"))?;
    Ok(Texture { width, height, rgba: decoded.into_rgba8().into_raw(), encoding })
}
