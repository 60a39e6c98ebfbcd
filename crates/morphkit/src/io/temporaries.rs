//! The temporary files and directories this process writes its outputs into, so that an
//! interrupted run leaves none behind.
//!
//! Every temporary that [`super::write_atomic`], [`super::Staging`] and the frame-directory
//! writer create is recorded here before it is created and forgotten once it is renamed into
//! place or removed. A program that handles SIGINT/SIGTERM (the `morphkit` CLI does) calls
//! [`remove_temporaries_then`] from its handler: the recorded temporaries are removed and, while
//! no new one can be recorded, the program exits.
//!
//! A run killed outright (SIGKILL, power loss) cannot clean up. Its temporaries are named after
//! their destination and the process id (`.stage-PID-N-NAME`, `.NAME.PID-N.tmp`,
//! `.NAME.PID-N.frames.tmp`, and those names nested); [`remove_stale_for`] removes the ones of
//! one destination whose process is gone, and [`super::Staging::stage`] calls it for each
//! output, so the next run of the same command cleans up after the killed one. Temporaries of
//! other destinations and of live processes are never touched.
//!
//! A file name holds at most 255 bytes on common file systems, so a long destination name
//! (a user may name an output with up to 255 bytes) stands in its temporaries' names as
//! `HASH.EXT` ([`name_in_temporary`]): a hash of the name, with its format's extension kept.
//! Staging allows [`STAGE_NAME_BUDGET`] bytes of the name and sibling temporaries
//! [`SIBLING_NAME_BUDGET`], more than a staged name can have, so that a temporary written next
//! to a staged one keeps the staged name as it is and stale ones are still recognised.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The live temporaries: (path, is a directory).
static LIVE: Mutex<Vec<(PathBuf, bool)>> = Mutex::new(Vec::new());

fn live() -> std::sync::MutexGuard<'static, Vec<(PathBuf, bool)>> {
    LIVE.lock().unwrap_or_else(|e| e.into_inner())
}

/// Records `path` (a directory when `dir`) as a temporary about to be created.
pub(crate) fn record(path: &Path, dir: bool) {
    live().push((path.to_path_buf(), dir));
}

/// Forgets `path`: it was moved into place or removed.
pub(crate) fn forget(path: &Path) {
    let mut l = live();
    if let Some(i) = l.iter().rposition(|(p, _)| p == path) {
        l.swap_remove(i);
    }
}

/// Removes every recorded temporary of this process, then runs `then` while no temporary can
/// be recorded (a writer that tries waits): call it from a signal handler's thread with
/// `|| std::process::exit(130)`. Returns what `then` returns when it does return.
pub fn remove_temporaries_then<R>(then: impl FnOnce() -> R) -> R {
    let mut l = live();
    remove_where(&mut l, |_| true);
    let r = then();
    drop(l);
    r
}

/// Removes (from disk and from `l`) the recorded temporaries whose path satisfies `pred`.
fn remove_where(l: &mut Vec<(PathBuf, bool)>, pred: impl Fn(&Path) -> bool) {
    let mut i = l.len();
    while i > 0 {
        i -= 1;
        if !pred(&l[i].0) {
            continue;
        }
        let (p, dir) = l.remove(i);
        if dir {
            // A writer may still add a file after the listing: try again.
            for _ in 0..3 {
                if std::fs::remove_dir_all(&p).is_ok() || !p.exists() {
                    break;
                }
            }
        } else {
            let _ = std::fs::remove_file(&p);
        }
    }
}

/// The most bytes of its destination's name that a staged temporary's name keeps
/// (`.stage-PID-N-NAME`, at most 40 bytes besides the name).
pub(crate) const STAGE_NAME_BUDGET: usize = 120;

/// The most bytes of its destination's name that a sibling temporary's name keeps
/// (`.NAME.PID-N.frames.tmp`, at most 44 bytes besides the name): more than a staged
/// temporary's name can have.
pub(crate) const SIBLING_NAME_BUDGET: usize = 200;

/// `name` as a temporary's name holds it: itself when it has at most `budget` bytes, else a
/// hash of it followed by its format's extension (`0123456789abcdef.glb`, `….obj.gz`), so
/// that the writers choose the same format from the temporary's name.
pub(crate) fn name_in_temporary(name: &str, budget: usize) -> std::borrow::Cow<'_, str> {
    if name.len() <= budget {
        return name.into();
    }
    hashed_name(name).into()
}

/// `HASH.EXT` for the destination name `name`: 16 hexadecimal digits of its 64-bit FNV-1a
/// hash (the same in every run and version) and its extension: the last one when it is a
/// short alphanumeric one, `obj.gz` for compressed OBJ.
fn hashed_name(name: &str) -> String {
    let hash = name.bytes().fold(0xcbf2_9ce4_8422_2325_u64, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    });
    let lower = name.to_ascii_lowercase();
    let ext = if lower.ends_with(".obj.gz") {
        Some(&name[name.len() - 6..])
    } else {
        name.rsplit_once('.').map(|(_, e)| e).filter(|e| {
            !e.is_empty() && e.len() <= 8 && e.bytes().all(|b| b.is_ascii_alphanumeric())
        })
    };
    match ext {
        Some(e) => format!("{hash:016x}.{e}"),
        None => format!("{hash:016x}"),
    }
}

/// Splits `.stage-PID-N-REST` into (PID, REST).
fn strip_stage(name: &str) -> Option<(u32, &str)> {
    let rest = name.strip_prefix(".stage-")?;
    let (pid, rest) = rest.split_once('-')?;
    let (n, rest) = rest.split_once('-')?;
    n.parse::<u64>().ok()?;
    Some((pid.parse().ok()?, rest))
}

/// Splits `.INNER.PID-N.tmp` / `.INNER.PID-N.frames.tmp` into (PID, INNER).
fn strip_sibling(name: &str) -> Option<(u32, &str)> {
    let body = name.strip_prefix('.')?;
    let body = body
        .strip_suffix(".frames.tmp")
        .or_else(|| body.strip_suffix(".tmp"))?;
    let (inner, tag) = body.rsplit_once('.')?;
    let (pid, n) = tag.split_once('-')?;
    n.parse::<u64>().ok()?;
    Some((pid.parse().ok()?, inner))
}

/// The process ids in `name` when it is a (possibly nested) temporary name of the destination
/// file name `dest`; `None` when it is not one.
pub(crate) fn temporary_of(name: &str, dest: &str) -> Option<Vec<u32>> {
    let mut pids = Vec::new();
    let mut cur = name;
    let hashed = hashed_name(dest);
    while cur != dest && cur != hashed {
        let (pid, inner) = strip_stage(cur).or_else(|| strip_sibling(cur))?;
        pids.push(pid);
        cur = inner;
    }
    (!pids.is_empty()).then_some(pids)
}

/// True when process `pid` exists (or may: unknown platforms say yes).
fn alive(pid: u32) -> bool {
    if pid == std::process::id() {
        return true;
    }
    #[cfg(unix)]
    {
        let Ok(p) = libc::pid_t::try_from(pid) else {
            return true;
        };
        // SAFETY: signal 0 only checks that the process exists and may be signalled.
        let r = unsafe { libc::kill(p, 0) };
        r == 0 || std::io::Error::last_os_error().raw_os_error() != Some(libc::ESRCH)
    }
    #[cfg(not(unix))]
    {
        true
    }
}

/// Removes the temporaries that a process which no longer runs left for the destination
/// `dest` (see the module docs); returns how many it removed.
pub fn remove_stale_for(dest: &Path) -> usize {
    let Some(name) = dest.file_name().map(|n| n.to_string_lossy().into_owned()) else {
        return 0;
    };
    let dir = match dest.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let Ok(listed) = std::fs::read_dir(&dir) else {
        return 0;
    };
    let mut removed = 0;
    for e in listed.filter_map(|e| e.ok()) {
        let n = e.file_name().to_string_lossy().into_owned();
        let Some(pids) = temporary_of(&n, &name) else {
            continue;
        };
        if pids.iter().any(|&p| alive(p)) {
            continue;
        }
        let p = e.path();
        let ok = match e.file_type() {
            Ok(t) if t.is_dir() => std::fs::remove_dir_all(&p).is_ok(),
            Ok(_) => std::fs::remove_file(&p).is_ok(),
            Err(_) => false,
        };
        removed += usize::from(ok);
    }
    removed
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_of_a_destination_and_only_those() {
        assert_eq!(
            temporary_of(".stage-12-0-out.glb", "out.glb"),
            Some(vec![12])
        );
        assert_eq!(temporary_of(".out.glb.7-3.tmp", "out.glb"), Some(vec![7]));
        assert_eq!(
            temporary_of("..stage-12-0-out.glb.12-4.tmp", "out.glb"),
            Some(vec![12, 12])
        );
        assert_eq!(
            temporary_of("..stage-9-1-frames.9-2.frames.tmp", "frames"),
            Some(vec![9, 9])
        );
        assert_eq!(temporary_of("out.glb", "out.glb"), None);
        assert_eq!(temporary_of(".stage-12-0-other.glb", "out.glb"), None);
        assert_eq!(temporary_of(".out.glb.x-3.tmp", "out.glb"), None);
        assert_eq!(temporary_of(".stage-12-0-out.glb.bak", "out.glb"), None);
        assert_eq!(temporary_of(".stage-12-0-xout.glb", "out.glb"), None);
    }

    #[test]
    fn long_names_stand_as_a_hash_with_their_extension() {
        let long = format!("{}.obj.gz", "a".repeat(243));
        assert_eq!(long.len(), 250);
        let short = name_in_temporary(&long, STAGE_NAME_BUDGET);
        assert_eq!(short.len(), 16 + 7, "{short}");
        assert!(short.ends_with(".obj.gz"), "{short}");
        assert_eq!(name_in_temporary("out.glb", STAGE_NAME_BUDGET), "out.glb");
        let other = format!("{}.obj.gz", "b".repeat(243));
        assert_ne!(name_in_temporary(&other, STAGE_NAME_BUDGET), short);
        let dir = "d".repeat(250);
        assert_eq!(name_in_temporary(&dir, SIBLING_NAME_BUDGET).len(), 16);
        let staged = format!(".stage-12-0-{short}");
        assert_eq!(temporary_of(&staged, &long), Some(vec![12]));
        assert_eq!(
            temporary_of(&format!(".{staged}.12-4.tmp"), &long),
            Some(vec![12, 12])
        );
        assert_eq!(
            temporary_of(&format!(".{short}.7-3.tmp"), &long),
            Some(vec![7])
        );
        assert_eq!(temporary_of(&staged, &other), None);
    }

    #[test]
    fn a_destination_of_250_bytes_is_staged_and_written() {
        let d = std::env::temp_dir().join(format!("morphkit-long-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        let dest = d.join(format!("{}.json", "n".repeat(245)));
        let mut staging = super::super::Staging::new();
        staging
            .write(&dest, false, |tmp| super::super::write_atomic(tmp, b"{}"))
            .unwrap();
        let frames = d.join("f".repeat(250));
        let tmp = staging.stage(&frames, true).unwrap();
        super::super::write_atomic(&tmp.join("frame_0000.obj"), b"v 0 0 0\n").unwrap();
        staging.commit().unwrap();
        assert_eq!(std::fs::read(&dest).unwrap(), b"{}");
        assert!(frames.join("frame_0000.obj").is_file());
        super::super::write_atomic(&dest, b"[]").unwrap();
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 2);
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn stale_temporaries_of_dead_processes_are_removed() {
        let d = std::env::temp_dir().join(format!("morphkit-stale-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        // A child that has exited is a process id that no longer runs.
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let dead = child.id();
        child.wait().unwrap();
        let me = std::process::id();
        let files = [
            format!(".stage-{dead}-0-out.glb"),
            format!("..stage-{dead}-0-out.glb.{dead}-1.tmp"),
            format!(".out.glb.{me}-5.tmp"),
            format!(".stage-{dead}-0-other.glb"),
            "out.glb".to_string(),
        ];
        for f in &files {
            std::fs::write(d.join(f), "x").unwrap();
        }
        std::fs::create_dir(d.join(format!("..stage-{dead}-2-out.glb.{dead}-3.frames.tmp")))
            .unwrap();
        assert_eq!(remove_stale_for(&d.join("out.glb")), 3);
        let mut left: Vec<String> = std::fs::read_dir(&d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        left.sort();
        let mut want = vec![
            format!(".out.glb.{me}-5.tmp"),
            format!(".stage-{dead}-0-other.glb"),
            "out.glb".to_string(),
        ];
        want.sort();
        assert_eq!(left, want);
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn recorded_temporaries_are_removed_on_request() {
        let d = std::env::temp_dir().join(format!("morphkit-live-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(d.join("t")).unwrap();
        std::fs::write(d.join("t/a"), "x").unwrap();
        std::fs::write(d.join("f"), "x").unwrap();
        record(&d.join("t"), true);
        record(&d.join("f"), false);
        // Only this test's own entries: other tests of this process write concurrently.
        remove_where(&mut live(), |p| p.starts_with(&d));
        assert!(!d.join("t").exists() && !d.join("f").exists());
        assert!(!live().iter().any(|(p, _)| p.starts_with(&d)));
        let _ = std::fs::remove_dir_all(&d);
    }
}
