//! Image files of a run: display PNGs, linear HDR EXRs, heatmaps (sample counts, absolute
//! differences) and animated PNGs of a sequence's region. Every write goes to a temporary file
//! first and is renamed into place.

use std::path::{Path, PathBuf};

use aabench_renderer::DisplayImage;
use anyhow::Context;

/// Writes RGBA8 pixels as PNG.
pub fn write_png(path: &Path, width: u32, height: u32, rgba: &[u8]) -> anyhow::Result<()> {
    encode_png(path, width, height, rgba, image::ExtendedColorType::Rgba8)
}

/// Encodes samples (16-bit ones in native byte order, as the image crate takes them) and
/// writes them atomically.
fn encode_png(
    path: &Path,
    width: u32,
    height: u32,
    samples: &[u8],
    color: image::ExtendedColorType,
) -> anyhow::Result<()> {
    let mut bytes = std::io::Cursor::new(Vec::new());
    image::write_buffer_with_format(&mut bytes, samples, width, height, color, image::ImageFormat::Png)
        .with_context(|| format!("{}: PNG encoding", path.display()))?;
    crate::files::write(path, bytes.get_ref()).map_err(anyhow::Error::msg)
}

/// Writes a display image as PNG: 8-bit, or 16-bit for 10-bit code values (each scaled to
/// the full 16-bit range by bit replication, so that the top 10 bits are the code value).
pub fn write_display_png(path: &Path, width: u32, height: u32, image: &DisplayImage) -> anyhow::Result<()> {
    if image.bits <= 8 {
        return write_png(path, width, height, &image.bytes());
    }
    let shift = 16 - image.bits;
    let samples: Vec<u8> =
        image.rgba.iter().flat_map(|&v| ((v << shift) | (v >> (image.bits - shift))).to_ne_bytes()).collect();
    encode_png(path, width, height, &samples, image::ExtendedColorType::Rgba16)
}

/// A display image as RGBA8: 10-bit code values rounded to 8 bits.
pub fn display_rgba8(image: &DisplayImage) -> Vec<u8> {
    if image.bits <= 8 {
        return image.bytes();
    }
    let max = u32::from(image.max_code());
    image.rgba.iter().map(|&v| ((u32::from(v) * 255 + max / 2) / max) as u8).collect()
}

/// Writes RGBA8 frames of one size as an animated PNG (APNG) that loops forever, each frame
/// shown for `delay_s` seconds (at least 20 ms: browsers slow shorter delays down to 100 ms).
/// A viewer without APNG shows the first frame. Frames are stored whole and losslessly, so
/// that a pixel that flickers in the animation flickered in the frames.
pub fn write_apng(
    path: &Path,
    width: u32,
    height: u32,
    frames: &[Vec<u8>],
    delay_s: f64,
) -> anyhow::Result<()> {
    anyhow::ensure!(!frames.is_empty(), "{}: an animation needs a frame", path.display());
    let mut bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut bytes, width, height);
        encoder.set_color(png::ColorType::Rgba);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_animated(frames.len() as u32, 0)?;
        // In 1/6000 s, which holds 1/60, 1/30 and 1/24 exactly.
        let ticks = (delay_s * 6000.0).round().clamp(120.0, f64::from(u16::MAX)) as u16;
        encoder.set_frame_delay(ticks, 6000)?;
        let mut writer =
            encoder.write_header().with_context(|| format!("{}: APNG header", path.display()))?;
        for frame in frames {
            writer.write_image_data(frame).with_context(|| format!("{}: APNG frame", path.display()))?;
        }
        writer.finish().with_context(|| format!("{}: APNG encoding", path.display()))?;
    }
    crate::files::write(path, &bytes).map_err(anyhow::Error::msg)
}

/// The frames of an animated PNG as RGBA8 images (a still PNG: its one image). A path that is
/// no regular file (a FIFO would block for ever) is an error naming it.
pub fn read_apng(path: &Path) -> anyhow::Result<Vec<image::RgbaImage>> {
    use image::AnimationDecoder;
    let bytes = crate::files::read_regular(path).with_context(|| format!("{}", path.display()))?;
    let file = std::io::Cursor::new(bytes);
    let decoder = image::codecs::png::PngDecoder::new(file).with_context(|| format!("{}", path.display()))?;
    let frames = if decoder.is_apng().with_context(|| format!("{}", path.display()))? {
        let frames = decoder.apng().with_context(|| format!("{}", path.display()))?.into_frames();
        frames.map(|frame| frame.map(image::Frame::into_buffer)).collect::<Result<Vec<_>, _>>()
    } else {
        image::DynamicImage::from_decoder(decoder).map(|image| vec![image.to_rgba8()])
    };
    frames.with_context(|| format!("{}: PNG decoding", path.display()))
}

/// Reads a display image that [`write_display_png`] wrote with `bits` per channel.
pub fn read_display_png(path: &Path, bits: u32) -> Option<(u32, u32, DisplayImage)> {
    let decoded = image::open(path).ok()?;
    let (width, height) = (decoded.width(), decoded.height());
    let image = match (bits, decoded) {
        (8, image::DynamicImage::ImageRgba8(rgba)) => DisplayImage::from_rgba8(rgba.as_raw()),
        (10, image::DynamicImage::ImageRgba16(rgba)) => {
            DisplayImage { bits, rgba: rgba.as_raw().iter().map(|&v| v >> 6).collect() }
        }
        _ => return None,
    };
    Some((width, height, image))
}

/// Writes the RGB of linear RGBA f32 pixels as a 32-bit float EXR (alpha holds the stall
/// checksum, not coverage, so it is left out).
pub fn write_exr(path: &Path, width: u32, height: u32, rgba: &[f32]) -> anyhow::Result<()> {
    let temporary = temporary_beside(path);
    let (w, h) = (width as usize, height as usize);
    let result = exr::prelude::write_rgb_file(&temporary, w, h, |x, y| {
        let p = &rgba[(y * w + x) * 4..];
        (p[0], p[1], p[2])
    });
    if let Err(error) = result {
        let _ = std::fs::remove_file(&temporary);
        return Err(anyhow::anyhow!("{}: EXR encoding: {error}", path.display()));
    }
    std::fs::rename(&temporary, path).with_context(|| format!("{}: write", path.display()))
}

fn temporary_beside(path: &Path) -> PathBuf {
    let mut name = path.as_os_str().to_owned();
    name.push(format!(".tmp-{}.exr", std::process::id()));
    PathBuf::from(name)
}

/// The top-left corner of the `side`×`side` window with the largest sum of `values`, a
/// `width` × `height` map row by row (a summed-area table makes every window O(1); the first
/// in reading order where several tie).
pub fn largest_window(values: &[f64], width: u32, height: u32, side: u32) -> (u32, u32) {
    let (w, h, side) = (width as usize, height as usize, side as usize);
    let mut sums = vec![0f64; (w + 1) * (h + 1)];
    for y in 0..h {
        for x in 0..w {
            sums[(y + 1) * (w + 1) + x + 1] =
                values[y * w + x] + sums[y * (w + 1) + x + 1] + sums[(y + 1) * (w + 1) + x]
                    - sums[y * (w + 1) + x];
        }
    }
    let window = |x: usize, y: usize| {
        let at = |x: usize, y: usize| sums[y * (w + 1) + x];
        at(x + side, y + side) - at(x, y + side) - at(x + side, y) + at(x, y)
    };
    let mut best = (0, 0, f64::NEG_INFINITY);
    for y in 0..=h - side {
        for x in 0..=w - side {
            let sum = window(x, y);
            if sum > best.2 {
                best = (x, y, sum);
            }
        }
    }
    (best.0 as u32, best.1 as u32)
}

/// A perceptually ordered colour map (Google's Turbo, polynomial fit) for t in [0, 1].
pub fn turbo(t: f64) -> [u8; 3] {
    let t = t.clamp(0.0, 1.0);
    let poly = |c: [f64; 6]| c[0] + t * (c[1] + t * (c[2] + t * (c[3] + t * (c[4] + t * c[5]))));
    let r = poly([0.13572138, 4.61539260, -42.66032258, 132.13108234, -152.94239396, 59.28637943]);
    let g = poly([0.09140261, 2.19418839, 4.84296658, -14.18503333, 4.27729857, 2.82956604]);
    let b = poly([0.10667330, 12.64194608, -60.58204836, 110.36276771, -89.90310912, 27.34824973]);
    [r, g, b].map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
}

/// Sample counts 1…M² as a heatmap: 1 sample near black, M² samples dark red.
pub fn sample_heatmap(counts: &[u8], m: u32) -> Vec<u8> {
    let max = f64::from(m * m - 1).max(1.0);
    counts
        .iter()
        .flat_map(|&n| {
            let [r, g, b] = turbo((f64::from(n) - 1.0) / max);
            [r, g, b, 255]
        })
        .collect()
}

/// Per-pixel absolute difference (largest over R, G, B) as a heatmap; `full_scale` 8-bit steps
/// (or as much at 10 bits) map to the top of the colour map.
pub fn difference_heatmap(image: &DisplayImage, reference: &DisplayImage, full_scale: f64) -> Vec<u8> {
    let full_scale = full_scale * f64::from(image.max_code()) / 255.0;
    image
        .rgba
        .chunks_exact(4)
        .zip(reference.rgba.chunks_exact(4))
        .flat_map(|(a, b)| {
            let d = (0..3).map(|c| a[c].abs_diff(b[c])).max().unwrap_or(0);
            let [r, g, b] = turbo(f64::from(d) / full_scale);
            [r, g, b, 255]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn turbo_runs_from_blue_to_red() {
        let [r0, _, b0] = turbo(0.15);
        let [r1, _, b1] = turbo(0.9);
        assert!(b0 > r0 && r1 > b1);
        assert!(turbo(0.0).iter().all(|&c| c < 64), "the low end is dark");
    }

    #[test]
    fn written_files_read_back() {
        let dir = std::env::temp_dir().join(format!("aabench-images-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let png = dir.join("a.png");
        write_png(&png, 2, 1, &[255, 0, 0, 255, 0, 255, 0, 255]).unwrap();
        let decoded = image::open(&png).unwrap().to_rgba8();
        assert_eq!(decoded.as_raw(), &vec![255, 0, 0, 255, 0, 255, 0, 255]);

        // 10-bit code values survive a 16-bit PNG, whose top 10 bits they are.
        let ten = DisplayImage { bits: 10, rgba: vec![0, 1, 512, 1023, 1023, 700, 3, 1023] };
        let png16 = dir.join("ten.png");
        write_display_png(&png16, 2, 1, &ten).unwrap();
        let sixteen = image::open(&png16).unwrap().to_rgba16();
        assert_eq!(sixteen.as_raw()[3], 65535, "1023 is full scale");
        assert_eq!(read_display_png(&png16, 10), Some((2, 1, ten.clone())));
        assert_eq!(read_display_png(&png16, 8), None, "a 16-bit file is no 8-bit image");

        // An animation reads back frame for frame, and 10-bit code values round to 8 bits.
        let apng = dir.join("moving.png");
        let frames = vec![vec![255, 0, 0, 255, 0, 0, 0, 255], vec![0, 255, 0, 255, 9, 9, 9, 255]];
        write_apng(&apng, 2, 1, &frames, 1.0 / 60.0).unwrap();
        let read: Vec<Vec<u8>> = read_apng(&apng).unwrap().into_iter().map(|f| f.into_raw()).collect();
        assert_eq!(read, frames);
        assert_eq!(display_rgba8(&ten), vec![0, 0, 128, 255, 255, 174, 1, 255]);

        // A FIFO where an animation should be (a report reads a sequence's) is an error naming
        // it, at once: opening it for reading would wait for a writer for ever.
        let fifo = dir.join("pipe.png");
        assert!(std::process::Command::new("mkfifo").arg(&fifo).status().unwrap().success());
        let (sender, receiver) = std::sync::mpsc::channel();
        let path = fifo.clone();
        std::thread::spawn(move || sender.send(read_apng(&path).map_err(|e| format!("{e:#}"))));
        let read = receiver.recv_timeout(std::time::Duration::from_secs(10)).expect("read_apng returns");
        let error = read.unwrap_err();
        assert!(error.contains("pipe.png") && error.contains("not a regular file"), "{error}");

        let exr_path = dir.join("a.exr");
        write_exr(&exr_path, 2, 1, &[1.5, 2.0, 3.0, 0.0, 0.25, 0.5, 100.0, 0.0]).unwrap();
        let read = exr::prelude::read_first_rgba_layer_from_file(
            &exr_path,
            |resolution, _| vec![[0f32; 3]; resolution.width() * resolution.height()],
            |pixels, position, (r, g, b, _a): (f32, f32, f32, f32)| {
                pixels[position.y() * 2 + position.x()] = [r, g, b]
            },
        )
        .unwrap();
        assert_eq!(read.layer_data.channel_data.pixels, vec![[1.5, 2.0, 3.0], [0.25, 0.5, 100.0]]);
        assert!(
            std::fs::read_dir(&dir).unwrap().all(|e| !e
                .unwrap()
                .file_name()
                .to_string_lossy()
                .contains(".tmp-"))
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
