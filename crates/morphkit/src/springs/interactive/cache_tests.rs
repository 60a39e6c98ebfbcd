//! Issue 55: the interactive cache's checksum (a single flipped bit anywhere is refused, and a
//! damaged cache file is rebuilt) and its refusal to replace a file that is not a cache.

use super::cache::checksum;
use crate::mesh::{generate, ShapeSet};
use crate::springs::{BlendError, BlendOptions, PhysicalBlend, Weights};
use std::path::PathBuf;

/// A small tube bent 90° by its one target.
fn blend() -> PhysicalBlend {
    let m = generate::tube(0.5, 4.0, 8, 12, false);
    let bent = generate::bend(&m.positions, 2.0, 2.0, 90f64.to_radians());
    let shapes = vec![
        ("base".to_string(), m.positions.clone()),
        ("bent".to_string(), bent),
    ];
    let set = ShapeSet::new(m, shapes).unwrap();
    PhysicalBlend::new(&set, &BlendOptions::default()).unwrap()
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("morphkit-h55-cache-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn checksum_sees_every_single_word_change() {
    let a: Vec<u8> = (0..1000u32).flat_map(|i| i.to_le_bytes()).collect();
    let h = checksum(&a);
    for bit in [0, 7, 63, 64 * 10 + 31, 8 * 999 + 7] {
        let mut b = a.clone();
        b[bit / 8] ^= 1 << (bit % 8);
        assert_ne!(checksum(&b), h, "bit {bit}");
    }
    // The same top bit flipped in two words does not cancel (a plain multiply would).
    let mut b = a.clone();
    b[7] ^= 0x80;
    b[15] ^= 0x80;
    assert_ne!(checksum(&b), h);
    assert_ne!(checksum(&a[..999]), checksum(&[&a[..999], &[0]].concat()));
}

#[test]
fn a_cache_with_any_bit_flipped_is_refused() {
    let mut a = blend();
    a.prepare_interactive(1);
    let bytes = a.interactive_bytes().unwrap();
    let mut fresh = blend();
    fresh.load_interactive(&bytes).unwrap();
    // One flipped bit in every 8-byte word, the bit moving along, the trailer included. A
    // refused load leaves the blend unprepared, so one blend takes them all.
    let mut other = blend();
    for (k, word) in (0..bytes.len() / 8).enumerate() {
        let bit = 64 * word + k % 64;
        let mut bad = bytes.clone();
        bad[bit / 8] ^= 1 << (bit % 8);
        let e = other.load_interactive(&bad).unwrap_err();
        assert!(matches!(e, BlendError::InteractiveCache { .. }), "{e}");
        assert!(other.interactive_space().is_none(), "bit {bit}");
        if word > 0 {
            assert!(e.to_string().contains("damaged"), "bit {bit}: {e}");
        }
    }
}

#[test]
fn a_damaged_cache_file_is_rebuilt_and_named() {
    let d = tmp("damaged");
    let path = d.join("rig.mkinteractive");
    let mut a = blend();
    assert!(!a.prepare_interactive_cached(1, &path).unwrap().loaded);
    let good = std::fs::read(&path).unwrap();
    // A weight's worth of damage in the middle of the fields.
    let mut bad = good.clone();
    let at = bad.len() / 2;
    bad[at] ^= 0x10;
    std::fs::write(&path, &bad).unwrap();
    let mut b = blend();
    let used = b.prepare_interactive_cached(1, &path).unwrap();
    let why = used.replaced.expect("the damaged file is replaced");
    assert!(!used.loaded);
    assert!(
        why.contains(&path.display().to_string()) && why.contains("damaged"),
        "{why}"
    );
    // Rebuilt, and read by the next run.
    let rebuilt = std::fs::read(&path).unwrap();
    assert_eq!(rebuilt.len(), good.len());
    let mut c = blend();
    assert!(c.prepare_interactive_cached(1, &path).unwrap().loaded);
    let w = Weights::Delta(vec![0.5]);
    assert_eq!(
        a.solve_interactive(&w, 0).unwrap().positions,
        c.solve_interactive(&w, 0).unwrap().positions
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_file_that_is_not_a_cache_is_never_replaced() {
    let d = tmp("notes");
    let notes = d.join("notes.txt");
    let text = b"my notes, not a cache\n";
    std::fs::write(&notes, text).unwrap();
    let mut b = blend();
    let e = b
        .prepare_interactive_cached(1, &notes)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(&notes.display().to_string()) && e.contains("not a morphkit interactive"),
        "{e}"
    );
    assert_eq!(std::fs::read(&notes).unwrap(), text);
    // Also once prepared: the file exists, so it is not written.
    b.prepare_interactive(1);
    b.prepare_interactive_cached(1, &notes).unwrap();
    assert_eq!(std::fs::read(&notes).unwrap(), text);
    // An empty file, or one of an older version, is replaced.
    let empty = d.join("empty.cache");
    std::fs::write(&empty, b"").unwrap();
    let mut c = blend();
    c.prepare_interactive_cached(1, &empty).unwrap();
    assert!(std::fs::read(&empty).unwrap().starts_with(b"MKINTER6"));
    let old = d.join("old.cache");
    std::fs::write(&old, b"MKINTER5 and whatever followed").unwrap();
    let mut c = blend();
    let used = c.prepare_interactive_cached(1, &old).unwrap();
    assert!(used.replaced.unwrap().contains("another version"));
    assert!(std::fs::read(&old).unwrap().starts_with(b"MKINTER6"));
    let _ = std::fs::remove_dir_all(&d);
}

/// A preparation stopped by its caller's hook (Ctrl-C in Python) ends at the next snapshot
/// solve, keeps nothing and writes no cache; a later preparation runs whole.
#[test]
fn a_stopped_preparation_ends_between_snapshots_and_writes_nothing() {
    use std::sync::atomic::{AtomicUsize, Ordering};
    let d = tmp("stopped");
    let path = d.join("rig.mkinter");
    for threads in [1, 2] {
        let mut b = blend();
        let asked = AtomicUsize::new(0);
        // Stop at the third question: after two snapshot solves.
        let stop = || asked.fetch_add(1, Ordering::Relaxed) + 1 >= 3;
        let e = b
            .prepare_interactive_cached_until(threads, &path, &stop)
            .unwrap_err();
        assert!(matches!(e, BlendError::Stopped { .. }), "{e}");
        assert!(
            e.to_string().contains("nothing of it was kept or written"),
            "{e}"
        );
        assert!(b.interactive_space().is_none());
        assert!(!path.exists(), "a stopped preparation wrote its cache");
        // One thread asks once per solve and stops at once; the second thread asks once more
        // at most before it sees the stop (of 7 snapshots and 8 checks in all).
        let asked = asked.load(Ordering::Relaxed);
        assert!(
            asked <= 2 + threads,
            "{threads} threads asked {asked} times"
        );
        let whole = b
            .prepare_interactive_until(threads, &|| false)
            .unwrap()
            .len();
        assert_eq!(whole, 7, "every eighth of the one target");
    }
    let mut b = blend();
    let used = b
        .prepare_interactive_cached_until(1, &path, &|| false)
        .unwrap();
    assert!(!used.loaded && path.exists());
    let _ = std::fs::remove_dir_all(&d);
}
