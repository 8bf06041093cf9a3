//! A sequence's frames on disk: every frame of the truth and of each mode, as the RGBA8 display
//! image (`images::display_rgba8`), appended to one file per stream as it is rendered, the
//! warm-up's first. The warm-up's frames are there for ColorVideoVDP, whose temporal filters
//! read the frames before each measured one ([`Spool::seen_frame`]); everything else reads the
//! measured window's ([`Spool::frame`], 0 its first).
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

use crate::images;

/// One file of RGBA8 frames per stream, named, with how many frames each holds, of which the
/// first `warmup` are the warm-up's.
#[derive(Debug)]
pub struct Spool {
    dir: PathBuf,
    size: [u32; 2],
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
    /// An empty spool of `size` frames for the named streams, each to take `warmup` frames
    /// before its measured window's, in `dir` (created).
    pub fn create(dir: PathBuf, size: [u32; 2], warmup: usize, names: Vec<String>) -> Result<Self, String> {
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
        Ok(Self { dir, size, warmup, streams })
    }

    /// Appends a frame to stream `stream`.
    pub fn append(&mut self, stream: usize, image: &DisplayImage) -> Result<(), String> {
        let (_, file, frames) = &mut self.streams[stream];
        let error = |e: std::io::Error| format!("{}: spool: {e}", self.dir.display());
        file.write_all(&images::display_rgba8(image)).map_err(error)?;
        *frames += 1;
        Ok(())
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
        let bytes = u64::from(self.size[0]) * u64::from(self.size[1]) * 4;
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

    /// Frame `frame` of stream `stream`'s measured window, whole.
    pub fn frame(&self, stream: usize, frame: usize) -> Result<Vec<u8>, String> {
        self.seen_frame(stream, self.warmup + frame)
    }

    /// Frame `index` of stream `stream` counted from the warm-up's first, whole.
    pub fn seen_frame(&self, stream: usize, index: usize) -> Result<Vec<u8>, String> {
        let [width, height] = self.size;
        let bytes = width as usize * height as usize * 4;
        let mut out = vec![0; bytes];
        self.read(stream, (index * bytes) as u64, &mut out)?;
        Ok(out)
    }

    /// Writes each stream's warm-up and the first `frames` frames of its window as PNGs,
    /// `<dir>/<stream name>/<NNN>.png` (000 the warm-up's first), each atomically; a stream
    /// that holds fewer frames (a mode that failed, or one that took its twin's frames) is left
    /// out.
    pub fn write_pngs(&self, dir: &Path, frames: usize) -> Result<(), String> {
        let [width, height] = self.size;
        for stream in (0..self.streams()).filter(|&s| self.frames(s) >= frames) {
            let folder = dir.join(self.name(stream));
            std::fs::create_dir_all(&folder).map_err(|e| format!("{}: {e}", folder.display()))?;
            for index in 0..self.warmup + frames {
                let path = folder.join(format!("{index:03}.png"));
                images::write_png(&path, width, height, &self.seen_frame(stream, index)?)
                    .map_err(|e| format!("{}: {e}", path.display()))?;
            }
        }
        Ok(())
    }

    /// The `square` of frame `frame` of stream `stream`'s measured window.
    pub fn crop(&self, stream: usize, frame: usize, square: Square) -> Result<Vec<u8>, String> {
        let [width, height] = self.size.map(u64::from);
        let row = width * 4;
        let index = (self.warmup + frame) as u64;
        let mut out = vec![0; square.side as usize * square.side as usize * 4];
        for (y, line) in (u64::from(square.y)..).zip(out.chunks_exact_mut(square.side as usize * 4)) {
            self.read(stream, index * row * height + y * row + u64::from(square.x) * 4, line)?;
        }
        Ok(out)
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
            Spool::create(spool_dir.clone(), [2, 2], 0, vec!["truth".into(), "taa".into()]).unwrap();
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
}
