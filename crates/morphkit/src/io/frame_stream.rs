//! Animations written frame by frame as they are made, so that a long animation is never held
//! in memory whole: a frame directory (`frame_0000.obj` …) or a PC2 point cache, the formats
//! whose layout allows it. glTF and USD need every frame before the file (a glTF buffer's
//! length, USD's time samples in one attribute), and are written from a [`ShapeSet`] by
//! [`super::write_frames_with`].
//!
//! A stream writes into a path it is given, normally a staged temporary
//! ([`super::Staging::stage`]), so that an unfinished stream never reaches its destination.
//!
//! [`ShapeSet`]: crate::mesh::ShapeSet

use super::atomic::check_fits_f32;
use super::{obj, IoError};
use crate::mesh::{Point, TriMesh};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Where the frames go.
#[derive(Debug)]
enum Sink {
    /// A frame directory: one OBJ per frame.
    Dir,
    /// A PC2 cache, its header written with the frame count.
    Pc2(std::io::BufWriter<std::fs::File>),
}

/// An animation being written frame by frame; see the module docs.
#[derive(Debug)]
pub struct FrameStream {
    sink: Sink,
    /// Where the frames are written (a directory, or the PC2 file).
    at: PathBuf,
    /// The destination, for messages.
    dest: PathBuf,
    base: TriMesh,
    frames: usize,
    written: usize,
    /// The artist's own OBJ that frames of a directory are written into.
    template: Option<super::ObjTemplate>,
}

impl FrameStream {
    /// Writes the frames of a frame directory into `template` (the input's own OBJ, every
    /// record kept: [`super::ObjTemplate`]) instead of plain `v`/`f` OBJ files.
    pub fn with_obj_template(mut self, template: Option<super::ObjTemplate>) -> Self {
        self.template = template;
        self
    }

    /// Whether an animation to `dest` can be streamed: a frame directory (`dir`) or `.pc2`.
    pub fn supports(dest: &Path, dir: bool) -> bool {
        dir || matches!(super::Format::from_path(dest), Some(super::Format::Pc2))
    }

    /// Starts writing `frames` frames of `base`'s connectivity at `at` (an existing directory
    /// when `dir`, else the PC2 file to create); errors name `dest`.
    pub fn create(
        at: &Path,
        dest: &Path,
        dir: bool,
        base: &TriMesh,
        frames: usize,
    ) -> Result<Self, IoError> {
        let sink = if dir {
            Sink::Dir
        } else {
            let too_big = |n: usize| i32::try_from(n).is_err();
            if too_big(base.num_vertices()) || too_big(frames) {
                return Err(IoError::content(
                    dest,
                    "too many points or samples for PC2's 32-bit counts",
                ));
            }
            let file = std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(at)
                .map_err(|e| IoError::os(dest, "create the output file", e))?;
            let mut w = std::io::BufWriter::with_capacity(1 << 20, file);
            super::pc2::write_header(&mut w, base.num_vertices(), 0.0, 1.0, frames)
                .map_err(|e| IoError::os(dest, "write the output file", e))?;
            Sink::Pc2(w)
        };
        Ok(Self {
            sink,
            at: at.to_path_buf(),
            dest: dest.to_path_buf(),
            base: base.clone(),
            frames,
            written: 0,
            template: None,
        })
    }

    /// Writes the next frame (`#V` positions).
    pub fn push(&mut self, positions: &[Point]) -> Result<(), IoError> {
        let k = self.written;
        if k == self.frames || positions.len() != self.base.num_vertices() {
            return Err(IoError::content(
                &self.dest,
                format!(
                    "frame {k}: {} positions for a mesh of {} vertices, {} frames announced",
                    positions.len(),
                    self.base.num_vertices(),
                    self.frames
                ),
            ));
        }
        match &mut self.sink {
            Sink::Dir => {
                let name = format!("frame_{k:04}.obj");
                match &self.template {
                    Some(t) => t.write(&self.at.join(&name), positions, false),
                    None => {
                        let mesh = self.base.with_positions(positions.to_vec());
                        obj::write_obj(&self.at.join(&name), &mesh, false)
                    }
                }
                .map_err(|e| e.at_path(&self.dest.join(&name)))?;
            }
            Sink::Pc2(w) => {
                check_fits_f32(&self.dest, &format!("frame {k}"), positions)?;
                let mut bytes = Vec::with_capacity(12 * positions.len());
                for p in positions {
                    for x in p {
                        bytes.extend_from_slice(&(*x as f32).to_le_bytes());
                    }
                }
                w.write_all(&bytes)
                    .map_err(|e| IoError::os(&self.dest, "write the output file", e))?;
            }
        }
        self.written += 1;
        Ok(())
    }

    /// Ends the stream: every announced frame must have been pushed; a PC2 file is flushed to
    /// disk.
    pub fn finish(self) -> Result<(), IoError> {
        if self.written != self.frames {
            return Err(IoError::content(
                &self.dest,
                format!(
                    "{} of {} announced frames were written",
                    self.written, self.frames
                ),
            ));
        }
        if let Sink::Pc2(w) = self.sink {
            let file = w
                .into_inner()
                .map_err(|e| IoError::os(&self.dest, "write the output file", e.into_error()))?;
            file.sync_all()
                .map_err(|e| IoError::os(&self.dest, "write the output file", e))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    #[test]
    fn streamed_frames_equal_the_whole_animation_written_at_once() {
        let d = std::env::temp_dir().join(format!("morphkit-stream-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(d.join("dir")).unwrap();
        let base = generate::grid(4, 3, 1.0, 1.0);
        let frames: Vec<Vec<Point>> = (0..5)
            .map(|k| {
                base.positions
                    .iter()
                    .map(|p| [p[0], p[1], p[2] + 0.1 * k as f64])
                    .collect()
            })
            .collect();
        let mut s =
            FrameStream::create(&d.join("a.pc2"), &d.join("a.pc2"), false, &base, 5).unwrap();
        let mut t = FrameStream::create(&d.join("dir"), &d.join("dir"), true, &base, 5).unwrap();
        for f in &frames {
            s.push(f).unwrap();
            t.push(f).unwrap();
        }
        s.finish().unwrap();
        t.finish().unwrap();
        super::super::pc2::write_pc2(
            &d.join("b.pc2"),
            &super::super::pc2::PointCache {
                start_frame: 0.0,
                sample_rate: 1.0,
                samples: frames.clone(),
            },
        )
        .unwrap();
        assert_eq!(
            std::fs::read(d.join("a.pc2")).unwrap(),
            std::fs::read(d.join("b.pc2")).unwrap()
        );
        let f3 = obj::read_obj(&d.join("dir/frame_0003.obj")).unwrap();
        assert_eq!(f3.positions, frames[3]);
        // Too few or too many frames are errors.
        let mut s =
            FrameStream::create(&d.join("c.pc2"), &d.join("c.pc2"), false, &base, 1).unwrap();
        s.push(&frames[0]).unwrap();
        assert!(s.push(&frames[1]).is_err());
        let s = FrameStream::create(&d.join("e.pc2"), &d.join("e.pc2"), false, &base, 2).unwrap();
        assert!(s.finish().unwrap_err().to_string().contains("0 of 2"));
        let _ = std::fs::remove_dir_all(&d);
    }
}
