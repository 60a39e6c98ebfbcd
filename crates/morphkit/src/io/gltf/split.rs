//! Cutting a morph-weight animation into windows that each need at most `max` morph targets
//! (the long-animation layout of the [module documentation](super)).
//!
//! Greedy over the keys: a window grows while the union of the targets with a nonzero weight in
//! its keys stays within `max`; the next window starts at the previous one's last key, so the
//! interpolation between any two neighbouring keys happens inside one window.

/// One mesh of a split rig.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Window {
    /// Indices of the rig's targets this mesh holds, ascending.
    pub targets: Vec<usize>,
    /// First and last key (inclusive) this mesh plays.
    pub keys: (usize, usize),
}

fn active(w: &[f64]) -> impl Iterator<Item = usize> + '_ {
    w.iter()
        .enumerate()
        .filter(|(_, &x)| x != 0.0)
        .map(|(i, _)| i)
}

/// The windows of `keys` (each a weight row over `num_targets`) with at most `max` targets
/// each; `None` when one window cannot do (a key pair needs more than `max` targets, or some
/// target is never used and would be lost). One window holding everything when no split is
/// needed (`max == 0`, few targets, or no keys).
pub(super) fn windows(keys: &[Vec<f64>], num_targets: usize, max: usize) -> Option<Vec<Window>> {
    let all = || Window {
        targets: (0..num_targets).collect(),
        keys: (0, keys.len().saturating_sub(1)),
    };
    if max == 0 || num_targets <= max || keys.is_empty() {
        return Some(vec![all()]);
    }
    let mut used = vec![false; num_targets];
    let mut out = Vec::new();
    let mut start = 0;
    let mut set = std::collections::BTreeSet::new();
    set.extend(active(&keys[0]));
    if set.len() > max {
        return None;
    }
    for k in 1..keys.len() {
        let before = set.clone();
        set.extend(active(&keys[k]));
        if set.len() <= max {
            continue;
        }
        if k - 1 == start {
            return None;
        }
        for &t in &before {
            used[t] = true;
        }
        out.push(Window {
            targets: before.into_iter().collect(),
            keys: (start, k - 1),
        });
        start = k - 1;
        set.clear();
        set.extend(active(&keys[k - 1]));
        set.extend(active(&keys[k]));
        if set.len() > max {
            return None;
        }
    }
    for &t in &set {
        used[t] = true;
    }
    out.push(Window {
        targets: set.into_iter().collect(),
        keys: (start, keys.len() - 1),
    });
    used.iter().all(|&u| u).then_some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one_hot(n: usize) -> Vec<Vec<f64>> {
        // Key 0 is the base (all zero), key k > 0 selects target k − 1.
        (0..=n)
            .map(|k| {
                (0..n)
                    .map(|t| if k > 0 && t == k - 1 { 1.0 } else { 0.0 })
                    .collect()
            })
            .collect()
    }

    #[test]
    fn frame_sequences_split_into_overlapping_windows() {
        let keys = one_hot(10);
        let w = windows(&keys, 10, 4).unwrap();
        assert_eq!(
            w[0],
            Window {
                targets: vec![0, 1, 2, 3],
                keys: (0, 4)
            }
        );
        assert_eq!(
            w[1],
            Window {
                targets: vec![3, 4, 5, 6],
                keys: (4, 7)
            }
        );
        assert_eq!(w.last().unwrap().keys.1, 10);
        for win in &w {
            assert!(win.targets.len() <= 4);
        }
        for pair in w.windows(2) {
            assert_eq!(
                pair[0].keys.1, pair[1].keys.0,
                "windows share their boundary key"
            );
        }
        assert_eq!(windows(&keys, 10, 0).unwrap().len(), 1);
        assert_eq!(windows(&keys, 10, 10).unwrap().len(), 1);
    }

    #[test]
    fn dense_keys_cannot_split() {
        let keys = vec![vec![1.0; 5], vec![0.5; 5]];
        assert!(windows(&keys, 5, 3).is_none());
    }
}
