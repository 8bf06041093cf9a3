//! A sequence's frames on disk: every frame of the truth and of each mode, as the display
//! image's code values (a byte each on an 8-bit display, two on a 10-bit one), appended to one
//! file per stream as it is rendered, the warm-up's first. The warm-up's frames are there for
//! ColorVideoVDP, whose temporal filters read the frames before each measured one, at the
//! display's depth ([`Spool::seen_image`]); everything else reads the measured window's as
//! RGBA8 ([`Spool::frame`], 0 its first).
//!
//! What needs every frame at once waits for the last: FLIP along the path, computed once the
//! renders are done so that it neither slows nor disturbs them (`run/sequence.rs`), and the
//! worst-flickering square, known only at the end (`flicker.rs`). A 256×192 frame takes 192 KB,
//! a 1024×768 one 3 MB, so a nightly scene's spool runs to a few GB, mostly read back from the
//! page cache. The folder is removed when the spool is dropped; it is named as a temporary of
//! its process (`.spool.tmp-<pid>`), so that what a killed run left is removed by the next run,
//! report or compare of that folder (`plan::remove_stale_temporaries`). Before anything reads it
//! back, every stream's length is checked against the frames appended to it.

use std::fs::File;
use std::io::Write;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

use aabench_renderer::DisplayImage;

use crate::files::images;

/// One file of frames per stream, named, with how many frames each holds, of which the first
/// `warmup` are the warm-up's.
#[derive(Debug)]
pub struct Spool {
    dir: PathBuf,
    size: [u32; 2],
    /// The display's bits per code value: 8, or 10 (stored as two bytes, little-endian).
    bits: u32,
    warmup: usize,
    streams: Vec<(String, File, usize)>,
}

/// A square of a frame: its top-left corner and side, in pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Square {
    pub x: u32,
    pub y: u32,
    pub side: u32,
}

/// The folder a sequence spools to under `dir` (its `path` folder): named as this process's
/// temporary.
pub fn folder(dir: &Path) -> PathBuf {
    dir.join(format!(".spool.tmp-{}", std::process::id()))
}

impl Spool {
    /// An empty spool of `size` frames of `bits`-bit code values for the named streams, each to
    /// take `warmup` frames before its measured window's, in `dir` (created).
    pub fn create(
        dir: PathBuf,
        size: [u32; 2],
        bits: u32,
        warmup: usize,
        names: Vec<String>,
    ) -> Result<Self, String> {
        // The folder is this process's own: anything in it is a leftover.
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        let mut streams = Vec::with_capacity(names.len());
        for (index, name) in names.into_iter().enumerate() {
            let path = dir.join(format!("{index}.rgba"));
            // Appending, so that a file cut from outside stays short (rather than growing a hole
            // of zeros at the cut) and its length tells.
            let file = File::options()
                .create(true)
                .read(true)
                .append(true)
                .open(&path)
                .map_err(|e| format!("{}: {e}", path.display()))?;
            streams.push((name, file, 0));
        }
        Ok(Self { dir, size, bits, warmup, streams })
    }

    /// Appends a frame, of the spool's size and bits, to stream `stream`.
    pub fn append(&mut self, stream: usize, image: &DisplayImage) -> Result<(), String> {
        let [width, height] = self.size;
        if image.bits != self.bits || image.rgba.len() != width as usize * height as usize * 4 {
            return Err(format!(
                "{}: spool: a {}-bit frame of {} values where the spool takes {}-bit {width}×{height} frames",
                self.dir.display(),
                image.bits,
                image.rgba.len(),
                self.bits
            ));
        }
        let bytes = match self.bytes_per_value() {
            1 => image.bytes(),
            _ => image.rgba.iter().flat_map(|v| v.to_le_bytes()).collect(),
        };
        let (_, file, frames) = &mut self.streams[stream];
        let error = |e: std::io::Error| format!("{}: spool: {e}", self.dir.display());
        file.write_all(&bytes).map_err(error)?;
        *frames += 1;
        Ok(())
    }

    /// Bytes a code value takes.
    fn bytes_per_value(&self) -> usize {
        if self.bits <= 8 { 1 } else { 2 }
    }

    /// Code values read back: a byte each, or two little-endian bytes each.
    fn image_of(&self, raw: &[u8]) -> DisplayImage {
        let rgba = match self.bytes_per_value() {
            1 => raw.iter().map(|&v| u16::from(v)).collect(),
            _ => raw.chunks_exact(2).map(|b| u16::from_le_bytes([b[0], b[1]])).collect(),
        };
        DisplayImage { bits: self.bits, rgba }
    }

    pub fn size(&self) -> [u32; 2] {
        self.size
    }

    pub fn streams(&self) -> usize {
        self.streams.len()
    }

    pub fn name(&self, stream: usize) -> &str {
        &self.streams[stream].0
    }

    /// The display's bits per code value.
    pub fn bits(&self) -> u32 {
        self.bits
    }

    /// The frames before the measured window's first.
    pub fn warmup(&self) -> usize {
        self.warmup
    }

    /// How many frames of the measured window stream `stream` holds.
    pub fn frames(&self, stream: usize) -> usize {
        self.streams[stream].2.saturating_sub(self.warmup)
    }

    /// Checks that every stream's file holds exactly the frames appended to it. A file cut short
    /// or written from outside would read back zeros or another's frames, which FLIP would
    /// score without a word; this is an error naming the stream instead.
    pub fn check(&self) -> Result<(), String> {
        let bytes = u64::from(self.size[0]) * u64::from(self.size[1]) * 4 * self.bytes_per_value() as u64;
        for (index, (name, file, frames)) in self.streams.iter().enumerate() {
            let length = file.metadata().map_err(|e| format!("{}: spool: {e}", self.dir.display()))?.len();
            let expected = *frames as u64 * bytes;
            if length != expected {
                return Err(format!(
                    "{}: spool: {index}.rgba ({name}) holds {length} bytes where its {frames} frame(s) \
                     take {expected}: it was cut or written from outside, so its frames are not compared",
                    self.dir.display()
                ));
            }
        }
        Ok(())
    }

    /// Frame `frame` of stream `stream`'s measured window, whole, as RGBA8 (10-bit code values
    /// rounded to 8 bits).
    pub fn frame(&self, stream: usize, frame: usize) -> Result<Vec<u8>, String> {
        Ok(images::display_rgba8(&self.seen_image(stream, self.warmup + frame)?))
    }

    /// Frame `index` of stream `stream` counted from the warm-up's first, whole, at the
    /// display's depth.
    pub fn seen_image(&self, stream: usize, index: usize) -> Result<DisplayImage, String> {
        let [width, height] = self.size;
        let bytes = width as usize * height as usize * 4 * self.bytes_per_value();
        let mut raw = vec![0; bytes];
        self.read(stream, (index * bytes) as u64, &mut raw)?;
        Ok(self.image_of(&raw))
    }

    /// Writes each stream's warm-up and the first `frames` frames of its window as PNGs,
    /// `<dir>/<stream name>/<NNN>.png` (000 the warm-up's first; 16-bit for 10-bit code values,
    /// as the stills are written), each atomically; a stream
    /// that holds fewer frames (a mode that failed, or one that took its twin's frames) is left
    /// out.
    pub fn write_pngs(&self, dir: &Path, frames: usize) -> Result<(), String> {
        let [width, height] = self.size;
        for stream in (0..self.streams()).filter(|&s| self.frames(s) >= frames) {
            let folder = dir.join(self.name(stream));
            std::fs::create_dir_all(&folder).map_err(|e| format!("{}: {e}", folder.display()))?;
            for index in 0..self.warmup + frames {
                let path = folder.join(format!("{index:03}.png"));
                // The write's error names the file already.
                images::write_display_png(&path, width, height, &self.seen_image(stream, index)?)
                    .map_err(|e| format!("{e:#}"))?;
            }
        }
        Ok(())
    }

    /// The `square` of frame `frame` of stream `stream`'s measured window, as RGBA8.
    pub fn crop(&self, stream: usize, frame: usize, square: Square) -> Result<Vec<u8>, String> {
        let [width, height] = self.size.map(u64::from);
        let pixel = 4 * self.bytes_per_value() as u64;
        let row = width * pixel;
        let index = (self.warmup + frame) as u64;
        let line_bytes = square.side as usize * pixel as usize;
        let mut raw = vec![0; square.side as usize * line_bytes];
        for (y, line) in (u64::from(square.y)..).zip(raw.chunks_exact_mut(line_bytes)) {
            self.read(stream, index * row * height + y * row + u64::from(square.x) * pixel, line)?;
        }
        Ok(images::display_rgba8(&self.image_of(&raw)))
    }

    fn read(&self, stream: usize, offset: u64, out: &mut [u8]) -> Result<(), String> {
        self.streams[stream]
            .1
            .read_exact_at(out, offset)
            .map_err(|e| format!("{}: spool: {e}", self.dir.display()))
    }
}

impl Drop for Spool {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stream_cut_from_outside_is_an_error_naming_it() {
        let dir = std::env::temp_dir().join(format!("aabench-spool-test-{}", std::process::id()));
        let spool_dir = folder(&dir);
        assert!(spool_dir.to_string_lossy().ends_with(&format!(".spool.tmp-{}", std::process::id())));
        let mut spool =
            Spool::create(spool_dir.clone(), [2, 2], 8, 0, vec!["truth".into(), "taa".into()]).unwrap();
        let frame = DisplayImage::from_rgba8(&[7; 16]);
        for stream in [0, 1] {
            spool.append(stream, &frame).unwrap();
            spool.append(stream, &frame).unwrap();
        }
        assert_eq!(spool.check(), Ok(()));
        assert_eq!(spool.frame(1, 1).unwrap(), vec![7; 16]);
        // Cut in the middle of the run and written on: its frames would read back shifted or
        // as zeros.
        spool.streams[1].1.set_len(16).unwrap();
        spool.append(1, &frame).unwrap();
        let error = spool.check().unwrap_err();
        assert!(error.contains("1.rgba (taa) holds 32 bytes") && error.contains("take 48"), "{error}");
        drop(spool);
        assert!(!spool_dir.exists(), "the folder goes with the spool");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_kept_frame_that_cannot_be_written_names_its_path_once() {
        let dir = std::env::temp_dir().join(format!("aabench-spool-keep-{}", std::process::id()));
        let mut spool = Spool::create(folder(&dir), [2, 2], 8, 0, vec!["truth".into()]).unwrap();
        spool.append(0, &DisplayImage::from_rgba8(&[7; 16])).unwrap();
        // A folder where the frame's file goes: the rename onto it fails, as a full disk's
        // write would.
        let kept = dir.join("frames");
        let blocked = kept.join("truth/000.png");
        std::fs::create_dir_all(blocked.join("inside")).unwrap();
        let error = spool.write_pngs(&kept, 1).unwrap_err();
        let named = blocked.display().to_string();
        assert_eq!(error.matches(&named).count(), 1, "{error}");
        assert!(error.starts_with(&format!("{named}: write: ")), "{error}");
        drop(spool);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn ten_bit_frames_come_back_at_ten_bits_and_as_rgba8_rounded() {
        let dir = std::env::temp_dir().join(format!("aabench-spool-ten-{}", std::process::id()));
        let mut spool = Spool::create(folder(&dir), [2, 1], 10, 1, vec!["truth".into()]).unwrap();
        let codes = vec![0, 1, 2, 1023, 511, 512, 513, 1022];
        let frame = DisplayImage { bits: 10, rgba: codes.clone() };
        spool.append(0, &frame).unwrap();
        spool.append(0, &frame).unwrap();
        assert_eq!(spool.check(), Ok(()));
        assert_eq!(spool.seen_image(0, 1).unwrap().rgba, codes, "every code value kept");
        // Codes between two 8-bit ones are what an 8-bit spool loses.
        assert_eq!(spool.frame(0, 0).unwrap(), images::display_rgba8(&frame));
        let square = spool.crop(0, 0, Square { x: 1, y: 0, side: 1 }).unwrap();
        assert_eq!(square, images::display_rgba8(&frame)[4..]);
        let error = spool.append(0, &DisplayImage::from_rgba8(&[7; 8])).unwrap_err();
        assert!(error.contains("8-bit frame") && error.contains("10-bit 2×1"), "{error}");
        drop(spool);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
