//! Writing several outputs as one unit: all of them, or none.
//!
//! A command with several outputs (a blend and its report, a correspondence and its warped
//! meshes) writes each one to a temporary sibling of its destination ([`Staging::stage`]),
//! and only when every write has succeeded moves them all into place ([`Staging::commit`]).
//! A failure before the commit (or dropping the [`Staging`]) removes the temporaries, so no
//! destination is touched. The temporaries live in their destination's directory, so the
//! final moves are renames on one file system, which do not fail for lack of space.
//!
//! A frame-directory destination is staged as a temporary directory; committing it renames it
//! into place when the destination does not exist, or else moves its frames in and removes
//! the destination's other `frame_*.obj` files (those of an earlier, longer sequence).

use super::temporaries::{name_in_temporary, STAGE_NAME_BUDGET};
use super::IoError;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

static COUNTER: AtomicU64 = AtomicU64::new(0);

/// One staged output.
#[derive(Debug)]
struct Entry {
    tmp: PathBuf,
    dest: PathBuf,
    dir: bool,
}

/// Outputs written to temporaries and moved into place together; see the module docs.
#[derive(Debug, Default)]
pub struct Staging {
    entries: Vec<Entry>,
    /// Files an earlier run may have left that this run owns but did not write.
    obsolete: Vec<PathBuf>,
}

/// True for the names frame directories hold: `frame_*.obj`.
pub fn is_frame_file_name(name: &str) -> bool {
    name.starts_with("frame_") && name.ends_with(".obj")
}

/// `frame_*.obj` files directly in `dir`, sorted by name (empty when `dir` does not exist).
pub fn frame_files(dir: &Path) -> Vec<PathBuf> {
    let Ok(listed) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut v: Vec<PathBuf> = listed
        .filter_map(|e| e.ok())
        .filter(|e| is_frame_file_name(&e.file_name().to_string_lossy()) && e.path().is_file())
        .map(|e| e.path())
        .collect();
    v.sort();
    v
}

impl Staging {
    /// An empty staging area.
    pub fn new() -> Self {
        Self::default()
    }

    /// A temporary path to write `dest`'s content to, in `dest`'s directory. Its name ends in
    /// `dest`'s file name (`.stage-PID-N-NAME`), so the format chosen by extension is the same;
    /// a long name stands there as a hash with the extension (see [`super::temporaries`]), so
    /// that a destination name of up to 255 bytes has a temporary that the file system allows.
    /// With `dir`, `dest` is a frame directory: the temporary directory is created (and the
    /// missing parents of `dest` with it).
    pub fn stage(&mut self, dest: &Path, dir: bool) -> Result<PathBuf, IoError> {
        let name = dest
            .file_name()
            .map_or_else(|| "out".into(), |n| n.to_string_lossy().into_owned());
        let parent = match dest.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        // What a killed earlier run left for this destination goes first.
        super::temporaries::remove_stale_for(dest);
        let tmp = parent.join(format!(
            ".stage-{}-{}-{}",
            std::process::id(),
            COUNTER.fetch_add(1, Ordering::Relaxed),
            name_in_temporary(&name, STAGE_NAME_BUDGET)
        ));
        super::temporaries::record(&tmp, dir);
        if dir {
            let made = std::fs::create_dir_all(&parent)
                .map_err(|e| IoError::os(dest, "create the parent directory", e))
                .and_then(|_| {
                    std::fs::create_dir(&tmp).map_err(|e| {
                        IoError::os(dest, "create a temporary directory next to it", e)
                    })
                });
            if let Err(e) = made {
                super::temporaries::forget(&tmp);
                return Err(e);
            }
        }
        self.entries.push(Entry {
            tmp: tmp.clone(),
            dest: dest.to_path_buf(),
            dir,
        });
        Ok(tmp)
    }

    /// Runs `write` on a staged temporary for `dest` (see [`Staging::stage`]); an error names
    /// `dest`, not the temporary.
    pub fn write(
        &mut self,
        dest: &Path,
        dir: bool,
        write: impl FnOnce(&Path) -> Result<(), IoError>,
    ) -> Result<(), IoError> {
        let tmp = self.stage(dest, dir)?;
        write(&tmp).map_err(|e| e.at_path(dest))
    }

    /// Makes [`Staging::commit`] remove the file `dest` unless this staging wrote it: an
    /// output a command writes only sometimes (a region of unconverged vertices), so that a
    /// file from an earlier run never sits beside new outputs that contradict it.
    pub fn remove_unless_written(&mut self, dest: &Path) {
        self.obsolete.push(dest.to_path_buf());
    }

    /// Moves every staged output into place, in staging order, then removes the files given to
    /// [`Staging::remove_unless_written`] that were not written. A rename that fails leaves the
    /// outputs before it in place and removes the remaining temporaries.
    pub fn commit(mut self) -> Result<(), IoError> {
        let entries = std::mem::take(&mut self.entries);
        let mut written = Vec::with_capacity(entries.len());
        let mut it = entries.into_iter();
        while let Some(e) = it.next() {
            let r = if e.dir {
                commit_dir(&e.tmp, &e.dest)
            } else {
                std::fs::rename(&e.tmp, &e.dest)
                    .map_err(|err| IoError::os(&e.dest, "move the finished file into place", err))
            };
            if r.is_ok() {
                super::temporaries::forget(&e.tmp);
            }
            if let Err(err) = r {
                remove(&e);
                it.for_each(|e| remove(&e));
                return Err(err);
            }
            written.push(e.dest);
        }
        for p in std::mem::take(&mut self.obsolete) {
            if !written.contains(&p) && p.is_file() {
                std::fs::remove_file(&p)
                    .map_err(|e| IoError::os(&p, "remove the output of an earlier run", e))?;
            }
        }
        Ok(())
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        for e in &self.entries {
            remove(e);
        }
    }
}

fn remove(e: &Entry) {
    if e.dir {
        let _ = std::fs::remove_dir_all(&e.tmp);
    } else {
        let _ = std::fs::remove_file(&e.tmp);
    }
    super::temporaries::forget(&e.tmp);
}

/// Moves the frames of the finished directory `tmp` into `dest` (see the module docs).
pub(crate) fn commit_dir(tmp: &Path, dest: &Path) -> Result<(), IoError> {
    if !dest.exists() {
        return std::fs::rename(tmp, dest).map_err(|e| {
            let _ = std::fs::remove_dir_all(tmp);
            IoError::os(dest, "move the finished frames into place", e)
        });
    }
    let names: Vec<std::ffi::OsString> = std::fs::read_dir(tmp)
        .map_err(|e| IoError::os(tmp, "list the directory", e))?
        .filter_map(|e| e.ok())
        .map(|e| e.file_name())
        .collect();
    // Stale frames of an earlier, longer sequence: listed before anything is moved.
    let stale: Vec<PathBuf> = frame_files(dest)
        .into_iter()
        .filter(|p| p.file_name().is_none_or(|n| !names.iter().any(|m| m == n)))
        .collect();
    for name in &names {
        if let Err(e) = std::fs::rename(tmp.join(name), dest.join(name)) {
            let _ = std::fs::remove_dir_all(tmp);
            return Err(IoError::os(
                &dest.join(name),
                "move the finished frame into place",
                e,
            ));
        }
    }
    let _ = std::fs::remove_dir(tmp);
    for p in stale {
        std::fs::remove_file(&p).map_err(|e| IoError::os(&p, "remove a stale frame", e))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmp_dir(name: &str) -> PathBuf {
        let d =
            std::env::temp_dir().join(format!("morphkit-staging-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn names(d: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn a_failed_write_leaves_no_output_and_no_temporary() {
        let d = tmp_dir("fail");
        let mut s = Staging::new();
        s.write(&d.join("a.txt"), false, |p| {
            super::super::write_atomic(p, b"a")
        })
        .unwrap();
        let e = s
            .write(&d.join("b.txt"), false, |p| {
                Err(IoError::content(p, "disk on fire"))
            })
            .unwrap_err();
        assert!(
            e.to_string()
                .starts_with(&d.join("b.txt").display().to_string()),
            "{e}"
        );
        drop(s);
        assert!(names(&d).is_empty(), "{:?}", names(&d));
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn outputs_not_written_this_time_are_removed_at_commit() {
        let d = tmp_dir("obsolete");
        std::fs::write(d.join("out-unconverged.ply"), "old").unwrap();
        std::fs::write(d.join("out-jumps.ply"), "old").unwrap();
        let mut s = Staging::new();
        s.remove_unless_written(&d.join("out-unconverged.ply"));
        s.remove_unless_written(&d.join("out-jumps.ply"));
        s.write(&d.join("out-jumps.ply"), false, |p| {
            super::super::write_atomic(p, b"new")
        })
        .unwrap();
        // An uncommitted staging removes nothing.
        drop(s);
        assert_eq!(names(&d), ["out-jumps.ply", "out-unconverged.ply"]);
        let mut s = Staging::new();
        s.remove_unless_written(&d.join("out-unconverged.ply"));
        s.remove_unless_written(&d.join("out-jumps.ply"));
        s.write(&d.join("out-jumps.ply"), false, |p| {
            super::super::write_atomic(p, b"new")
        })
        .unwrap();
        s.commit().unwrap();
        assert_eq!(names(&d), ["out-jumps.ply"]);
        assert_eq!(
            std::fs::read_to_string(d.join("out-jumps.ply")).unwrap(),
            "new"
        );
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn commit_moves_files_and_frame_directories_into_place() {
        let d = tmp_dir("commit");
        let out = d.join("frames");
        std::fs::create_dir(&out).unwrap();
        std::fs::write(out.join("frame_0009.obj"), "old").unwrap();
        std::fs::write(out.join("notes.txt"), "keep").unwrap();
        let mut s = Staging::new();
        s.write(&out, true, |p| {
            super::super::write_atomic(&p.join("frame_0000.obj"), b"new")
        })
        .unwrap();
        s.write(&d.join("r.json"), false, |p| {
            super::super::write_atomic(p, b"{}")
        })
        .unwrap();
        s.commit().unwrap();
        assert_eq!(names(&out), ["frame_0000.obj", "notes.txt"]);
        assert_eq!(names(&d), ["frames", "r.json"]);
        let _ = std::fs::remove_dir_all(&d);
    }
}
