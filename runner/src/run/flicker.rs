//! A sequence's worst-flickering region: the square of the frame where the modes' error changes
//! most from one frame to the next, kept as an animated PNG per mode for the report.
//!
//! Each pixel's flicker is its squared change of error along the truth's motion (`temporal.rs`)
//! summed over channels, frame pairs and modes: the per-pixel terms of every mode's `flicker`,
//! so the region is where the flicker comes from. Modes
//! flicker in the same places (edges, thin geometry, fine texture), and the sum is led by the
//! modes that flicker most, which is where a reader should look. The region is known only at the
//! last frame, so it is cut from the spooled frames (`spool.rs`).
//!
//! The animations play the path forwards and then backwards, at the path's own time step, so
//! that the loop has no jump back to the first frame that would read as flicker.

use std::collections::BTreeMap;
use std::path::Path;

use crate::files::images;
use crate::measure::{pixels, temporal};
use crate::record::FlickerRegion;
use crate::run::spool::{Spool, Square};

/// The side of the region, in pixels (smaller frames: their side).
pub const SIDE: u32 = 64;

/// How many consecutive frames the report's strips show: the ones within which the region
/// flickers most.
pub const STRIP_FRAMES: u32 = 8;

/// The name of the truth's stream, and so of its animation.
pub const TRUTH_STREAM: &str = "truth";

/// The worst-flickering square, and per animated stream (by its index in the spool) the share
/// of its error there that is coarse (`pixels::coarse_share`; `None` where it has no error).
#[derive(Debug)]
pub struct Cut {
    pub region: FlickerRegion,
    pub coarse_shares: Vec<(usize, Option<f64>)>,
}

/// Chooses the square with the most flicker in `map` (per pixel of the spool's frames) over the
/// first `frames` frames, and writes the animation of it of the truth's stream (the spool's
/// first) and of each of the `animated` streams that holds as many frames (a mode that failed on
/// the way holds fewer) to `<out_dir>/<stream>.png`, paths in the record relative to `run_dir`;
/// and takes each such stream's coarse share of its error over the square's frames.
pub fn region(
    spool: &Spool,
    map: &[f64],
    animated: &[usize],
    frames: usize,
    delay_s: f64,
    [run_dir, out_dir]: [&Path; 2],
) -> Result<Cut, String> {
    if frames < 2 {
        return Err("fewer than two frames: nothing flickers".into());
    }
    if spool.name(0) != TRUTH_STREAM || spool.frames(0) < frames {
        return Err("the truth's frames are missing from the spool".into());
    }
    let [width, height] = spool.size();
    let side = SIDE.min(width).min(height);
    let (x, y) = images::largest_window(map, width, height, side);
    let square = Square { x, y, side };
    let crops =
        |stream: usize| (0..frames).map(|f| spool.crop(stream, f, square)).collect::<Result<Vec<_>, _>>();
    let truth = crops(0)?;
    let mut modes = Vec::new();
    let mut coarse_shares = Vec::new();
    for &stream in animated.iter().filter(|&&s| spool.frames(s) >= frames) {
        let mode = crops(stream)?;
        coarse_shares.push((stream, pixels::coarse_share(&truth, &mode, side as usize)));
        modes.push((spool.name(stream), mode));
    }
    let strip_frames = STRIP_FRAMES.min(frames as u32);
    let strip_first = strip_start(&truth, modes.iter().map(|(_, crops)| crops.as_slice()), strip_frames);
    std::fs::create_dir_all(out_dir).map_err(|e| format!("{}: {e}", out_dir.display()))?;
    let mut animations = BTreeMap::new();
    for (name, crops) in std::iter::once((TRUTH_STREAM, &truth)).chain(modes.iter().map(|(n, c)| (*n, c))) {
        // Forwards, then backwards without repeating the ends: the loop has no jump.
        let played: Vec<Vec<u8>> = crops.iter().chain(crops[1..frames - 1].iter().rev()).cloned().collect();
        let path = out_dir.join(format!("{name}.png"));
        images::write_apng(&path, side, side, &played, delay_s).map_err(|e| format!("{e:#}"))?;
        let relative = path.strip_prefix(run_dir).unwrap_or(&path);
        animations.insert(name.to_string(), relative.to_string_lossy().replace('\\', "/"));
    }
    let region = FlickerRegion { x, y, side, strip_first, strip_frames, animations };
    Ok(Cut { region, coarse_shares })
}

/// The first of the `length` consecutive frames within which the modes' crops flicker most
/// against the truth's (the earliest where several tie).
fn strip_start<'a>(truth: &[Vec<u8>], modes: impl Iterator<Item = &'a [Vec<u8>]>, length: u32) -> u32 {
    // Per frame pair (f − 1, f), at index f: the crops' squared change of error.
    let mut pairs = vec![0u64; truth.len()];
    for crops in modes {
        for f in 1..truth.len() {
            pairs[f] += temporal::change_of_error(&crops[f], &crops[f - 1], &truth[f], &truth[f - 1]);
        }
    }
    let length = length as usize;
    let within = |first: usize| pairs[first + 1..first + length].iter().sum::<u64>();
    let mut best = 0;
    for first in 1..=truth.len() - length {
        if within(first) > within(best) {
            best = first;
        }
    }
    best as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 1-pixel RGBA8 frame of grey `v`.
    fn grey(v: u8) -> Vec<u8> {
        vec![v, v, v, 255]
    }

    #[test]
    fn the_strip_starts_where_the_modes_flicker_most() {
        // The truth is still; the mode's frame 6 alone differs: pairs (5, 6) and (6, 7) change.
        let truth: Vec<Vec<u8>> = (0..12).map(|_| grey(100)).collect();
        let mode: Vec<Vec<u8>> = (0..12).map(|f| grey(if f == 6 { 140 } else { 100 })).collect();
        let start = strip_start(&truth, std::iter::once(mode.as_slice()), 3);
        assert_eq!(start, 5, "frames 5–7 hold both changes");
        assert_eq!(
            strip_start(&truth, std::iter::once(truth.as_slice()), 4),
            0,
            "no flicker: the first frames"
        );
        assert_eq!(temporal::change_of_error(&grey(3), &grey(1), &grey(2), &grey(2)), 12, "alpha left out");
    }

    #[test]
    fn animations_cut_the_region_where_the_map_is_largest() {
        let dir = std::env::temp_dir().join(format!("aabench-flicker-{}", std::process::id()));
        let (width, height) = (80u32, 70u32);
        let frame = |f: u8| aabench_renderer::DisplayImage {
            bits: 8,
            rgba: (0..width * height).flat_map(|i| [(i % 256) as u16, u16::from(f), 0, 255]).collect(),
        };
        let names = [TRUTH_STREAM, "a", "b"].map(String::from).to_vec();
        let mut spool = Spool::create(dir.join("spool"), [width, height], 8, 0, names).unwrap();
        // The largest flicker sits at the bottom right corner.
        let mut map = vec![0.0; (width * height) as usize];
        map[(height * width - 1) as usize] = 5.0;
        for f in 0..3 {
            spool.append(0, &frame(f)).unwrap();
            spool.append(1, &frame(f + 10)).unwrap();
        }
        spool.append(2, &frame(0)).unwrap();
        let Cut { region, coarse_shares } =
            region(&spool, &map, &[1, 2], 3, 1.0 / 60.0, [&dir, &dir.join("path")]).unwrap();
        assert_eq!((region.x, region.y, region.side), (width - SIDE, height - SIDE, SIDE));
        assert_eq!((region.strip_first, region.strip_frames), (0, 3));
        assert_eq!(region.animations.keys().collect::<Vec<_>>(), ["a", "truth"], "b has one frame of three");
        assert_eq!(region.animations["a"], "path/a.png");
        let played = images::read_apng(&dir.join("path/a.png")).unwrap();
        let greens: Vec<u8> = played.iter().map(|f| f.get_pixel(0, 0)[1]).collect();
        assert_eq!(greens, [10, 11, 12, 11], "forwards, then backwards without the ends");
        let first_red = ((height - SIDE) * width + width - SIDE) % 256;
        assert_eq!(u32::from(played[0].get_pixel(0, 0)[0]), first_red, "the crop's corner");
        // a's error is a constant +10 of green: all of it coarse, as its animation reads.
        let [(stream, Some(share))] = coarse_shares[..] else { panic!("one share, of a: {coarse_shares:?}") };
        assert_eq!(stream, 1);
        assert!((share - 1.0).abs() < 1e-9, "{share}");
        let read = |path: &str| -> Vec<Vec<u8>> {
            let frames = images::read_apng(&dir.join(path)).unwrap().into_iter().take(3);
            frames.map(image::RgbaImage::into_raw).collect()
        };
        let from_animations =
            pixels::coarse_share(&read("path/truth.png"), &read("path/a.png"), SIDE as usize);
        assert_eq!(from_animations, Some(share), "the animations give the same share");
        drop(spool);
        assert!(!dir.join("spool").exists(), "the spool is removed");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
