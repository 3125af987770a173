//! An animated GIF of a run, written a frame at a time with the `gif` crate (each frame
//! quantised to its own palette by NeuQuant, looping forever).
//!
//! The frames' encoded blocks are appended to a hidden part file as they come; at
//! [`GifWriter::finish`] the file is written atomically as the header, the part file's blocks and
//! the trailer. A block is cut out of what the `gif` encoder writes for a one-frame file (the same
//! header and trailer around it), so the writer can stop at a checkpoint and go on in another
//! process ([`GifWriter::resume`]) to the same bytes.

use crate::atomic::write_atomic_with;
use crate::cache::CacheError;
use crate::preview::Image;
use std::fs::{File, OpenOptions};
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// Writes an animated GIF a frame at a time.
#[derive(Debug)]
pub struct GifWriter {
    path: PathBuf,
    part: PathBuf,
    out: BufWriter<File>,
    width: u16,
    height: u16,
    /// Each frame's delay (1/100 s).
    delay: u16,
    state: GifState,
}

/// What a [`GifWriter`] had written at a checkpoint.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GifState {
    /// Bytes of frame blocks in the part file, and the frames.
    pub written: u64,
    pub frames: u32,
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> CacheError + '_ {
    move |source| CacheError::Io {
        path: path.to_path_buf(),
        source,
    }
}

fn encode_error(path: &Path) -> impl Fn(gif::EncodingError) -> CacheError + '_ {
    move |e| CacheError::Invalid {
        path: path.to_path_buf(),
        what: format!("cannot encode the GIF: {e}"),
    }
}

impl GifWriter {
    /// A GIF of `width` x `height` pixels at `path`, each frame shown `delay` hundredths of a
    /// second.
    pub fn create(path: &Path, width: u32, height: u32, delay: u16) -> Result<Self, CacheError> {
        let part = part_path(path);
        let out = BufWriter::new(File::create(&part).map_err(io(&part))?);
        Self::with(path, part, out, (width, height, delay), GifState::default())
    }

    fn with(
        path: &Path,
        part: PathBuf,
        out: BufWriter<File>,
        (width, height, delay): (u32, u32, u16),
        state: GifState,
    ) -> Result<Self, CacheError> {
        let (Ok(width), Ok(height)) = (u16::try_from(width), u16::try_from(height)) else {
            return Err(CacheError::Invalid {
                path: path.to_path_buf(),
                what: format!("{width} x {height} pixels: a GIF is at most 65535 a side"),
            });
        };
        Ok(GifWriter {
            path: path.to_path_buf(),
            part,
            out,
            width: width.max(1),
            height: height.max(1),
            delay,
            state,
        })
    }

    /// The GIF's width and height (pixels).
    pub fn width(&self) -> u32 {
        self.width as u32
    }
    pub fn height(&self) -> u32 {
        self.height as u32
    }

    /// Appends `image` (of the GIF's size) as the next frame.
    pub fn frame(&mut self, image: &Image) -> Result<(), CacheError> {
        let (w, h) = (self.width, self.height);
        if image.width != w as u32 || image.height != h as u32 {
            return Err(CacheError::Invalid {
                path: self.path.clone(),
                what: format!("a {}x{} frame in a {w}x{h} GIF", image.width, image.height),
            });
        }
        let mut frame = gif::Frame::from_rgb_speed(w, h, &image.rgb, 10);
        frame.delay = self.delay;
        let bare = self.encoded(None, false)?;
        let one = self.encoded(Some(&frame), false)?;
        let block = &one[bare.len() - 1..one.len() - 1];
        self.out.write_all(block).map_err(io(&self.part))?;
        self.state.written += block.len() as u64;
        self.state.frames += 1;
        Ok(())
    }

    /// What the `gif` encoder writes for a file of at most one frame (header, the frame, the
    /// trailer), looping or not.
    fn encoded(&self, frame: Option<&gif::Frame>, looping: bool) -> Result<Vec<u8>, CacheError> {
        let mut buf = Vec::new();
        {
            let err = encode_error(&self.path);
            let mut e = gif::Encoder::new(&mut buf, self.width, self.height, &[]).map_err(&err)?;
            if looping {
                e.set_repeat(gif::Repeat::Infinite).map_err(&err)?;
            }
            if let Some(f) = frame {
                e.write_frame(f).map_err(&err)?;
            }
        }
        Ok(buf)
    }

    /// Flushes what is written and says how far it got.
    pub fn checkpoint(&mut self) -> Result<GifState, CacheError> {
        self.out.flush().map_err(io(&self.part))?;
        Ok(self.state)
    }

    /// A writer of the GIF at `path` (made with the same size and delay) going on from `state`.
    pub fn resume(
        path: &Path,
        (width, height, delay): (u32, u32, u16),
        state: GifState,
    ) -> Result<Self, CacheError> {
        let part = part_path(path);
        let mut f = OpenOptions::new()
            .write(true)
            .open(&part)
            .map_err(io(&part))?;
        if f.metadata().map_err(io(&part))?.len() < state.written {
            return Err(CacheError::Invalid {
                path: part,
                what: "shorter than at the checkpoint".into(),
            });
        }
        f.set_len(state.written).map_err(io(&part))?;
        f.seek(SeekFrom::End(0)).map_err(io(&part))?;
        Self::with(path, part, BufWriter::new(f), (width, height, delay), state)
    }

    /// Writes the GIF (header, frames, trailer) atomically and removes the part file.
    pub fn finish(mut self) -> Result<(), CacheError> {
        self.out.flush().map_err(io(&self.part))?;
        let head = self.encoded(None, true)?;
        let head = &head[..head.len() - 1];
        let mut blocks = File::open(&self.part).map_err(io(&self.part))?;
        let written = write_atomic_with(&self.path, |w| {
            w.write_all(head)?;
            std::io::copy(&mut blocks, w)?;
            w.write_all(&[0x3b])
        });
        let _ = std::fs::remove_file(&self.part);
        written.map_err(io(&self.path))
    }
}

fn part_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .and_then(|n| n.to_str())
        .unwrap_or("run.gif");
    path.with_file_name(format!(".{name}.part"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn picture(k: u8) -> Image {
        let (w, h) = (24u32, 16u32);
        let rgb = (0..w * h)
            .flat_map(|i| [k.wrapping_mul(40), (i % w) as u8 * 10, (i / w) as u8 * 15])
            .collect();
        Image {
            width: w,
            height: h,
            rgb,
        }
    }

    #[test]
    fn a_gif_decodes_with_its_frames_and_resumes_to_the_same_bytes() {
        let dir = std::env::temp_dir().join(format!("tryon-gif-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (a, b) = (dir.join("a.gif"), dir.join("b.gif"));
        let mut w = GifWriter::create(&a, 24, 16, 7).unwrap();
        (0..5).for_each(|k| w.frame(&picture(k)).unwrap());
        assert!(
            w.frame(&Image {
                width: 2,
                height: 2,
                rgb: vec![0; 12]
            })
            .is_err()
        );
        w.finish().unwrap();
        let mut w = GifWriter::create(&b, 24, 16, 7).unwrap();
        (0..2).for_each(|k| w.frame(&picture(k)).unwrap());
        let state = w.checkpoint().unwrap();
        w.frame(&picture(2)).unwrap();
        w.checkpoint().unwrap();
        drop(w);
        let mut w = GifWriter::resume(&b, (24, 16, 7), state).unwrap();
        (2..5).for_each(|k| w.frame(&picture(k)).unwrap());
        w.finish().unwrap();
        let bytes = std::fs::read(&a).unwrap();
        assert_eq!(bytes, std::fs::read(&b).unwrap());
        // Read back by the gif crate's decoder: five frames of the size, with the delay.
        let mut opts = gif::DecodeOptions::new();
        opts.set_color_output(gif::ColorOutput::RGBA);
        let mut d = opts.read_info(bytes.as_slice()).unwrap();
        assert_eq!((d.width(), d.height()), (24, 16));
        let mut frames = 0;
        while let Some(f) = d.read_next_frame().unwrap() {
            assert_eq!((f.width, f.height, f.delay), (24, 16, 7));
            frames += 1;
        }
        assert_eq!(frames, 5);
        assert!(!dir.join(".a.gif.part").exists());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
