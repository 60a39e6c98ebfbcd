//! Nested-dissection fill-reducing orderings from METIS (`METIS_NodeND`, vendored C library,
//! Apache-2.0), for the graph of a sparse symmetric matrix.

use super::SolveError;
use std::sync::Mutex;

/// METIS draws from one process-wide random generator (GKlib's `mt` state, reseeded with 4321
/// at the start of every call): two calls at once interleave their draws and give orderings
/// that depend on the timing of threads, hence factors that round differently. One call at a
/// time keeps every ordering a function of its graph alone.
static METIS_LOCK: Mutex<()> = Mutex::new(());

/// Nested-dissection ordering of an undirected graph given as adjacency lists (`adj[v]` the
/// neighbours of `v`; self-loops and duplicates are ignored). Returns `perm` with `perm[k]`
/// the vertex eliminated `k`-th, the convention of [`super::Ordering::Custom`].
pub fn nested_dissection(adj: &[Vec<usize>]) -> Result<Vec<usize>, SolveError> {
    let n = adj.len();
    if n == 0 {
        return Ok(Vec::new());
    }
    if n > i32::MAX as usize {
        return Err(SolveError::Backend("graph too large for METIS".into()));
    }
    // METIS wants a symmetric graph without self-loops: store every edge both ways.
    let mut sym: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (v, list) in adj.iter().enumerate() {
        for &w in list.iter().filter(|&&w| w != v && w < n) {
            sym[v].push(w);
            sym[w].push(v);
        }
    }
    let mut xadj: Vec<i32> = Vec::with_capacity(n + 1);
    let mut adjncy: Vec<i32> = Vec::new();
    xadj.push(0);
    for mut l in sym {
        l.sort_unstable();
        l.dedup();
        adjncy.extend(l.into_iter().map(|w| w as i32));
        if adjncy.len() > i32::MAX as usize {
            return Err(SolveError::Backend("graph too large for METIS".into()));
        }
        xadj.push(adjncy.len() as i32);
    }
    let mut nvtxs = n as i32;
    let mut options = [0i32; metis_sys::METIS_NOPTIONS as usize];
    let mut perm = vec![0i32; n];
    let mut iperm = vec![0i32; n];
    // SAFETY: every array has the length METIS documents for NodeND (xadj n+1, adjncy
    // xadj[n], options METIS_NOPTIONS, perm and iperm n); METIS reads the inputs and writes
    // only perm and iperm. No vertex weights are passed (null).
    let _one_at_a_time = METIS_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let status = unsafe {
        metis_sys::METIS_SetDefaultOptions(options.as_mut_ptr());
        metis_sys::METIS_NodeND(
            &mut nvtxs,
            xadj.as_mut_ptr(),
            adjncy.as_mut_ptr(),
            std::ptr::null_mut(),
            options.as_mut_ptr(),
            perm.as_mut_ptr(),
            iperm.as_mut_ptr(),
        )
    };
    if status != metis_sys::rstatus_et_METIS_OK {
        return Err(SolveError::Backend(format!(
            "METIS_NodeND failed with status {status}"
        )));
    }
    Ok(perm.into_iter().map(|p| p as usize).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sparse::cholesky::tests::random_spd;
    use crate::sparse::{Cholesky, Ordering, SymmetricPattern};

    #[test]
    fn ordering_is_a_permutation_and_solves_agree() {
        let n = 400;
        let t = random_spd(n, 21);
        let mut adj = vec![Vec::new(); n];
        for &(i, j, _) in &t {
            if i != j {
                adj[i].push(j);
                adj[j].push(i);
            }
        }
        let perm = nested_dissection(&adj).unwrap();
        let mut seen = vec![false; n];
        for &p in &perm {
            assert!(!seen[p]);
            seen[p] = true;
        }
        let (p, v) = SymmetricPattern::from_triplets(n, &t).unwrap();
        let b: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
        let mut a = Cholesky::analyze(p.clone(), Ordering::Amd).unwrap();
        let mut m = Cholesky::analyze(p, Ordering::Custom(perm)).unwrap();
        a.factorize(&v).unwrap();
        m.factorize(&v).unwrap();
        let (xa, xm) = (a.solve(&b).unwrap(), m.solve(&b).unwrap());
        let d = xa
            .iter()
            .zip(&xm)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        assert!(d < 1e-10);
    }

    /// Orderings computed on several threads at once equal the one computed alone (METIS's
    /// generator is process-wide; without the lock they differ from run to run).
    #[test]
    fn concurrent_orderings_equal_the_sequential_one() {
        let graphs: Vec<Vec<Vec<usize>>> = (0..3)
            .map(|g| {
                let n = 3000 + 500 * g;
                let mut adj = vec![Vec::new(); n];
                for &(i, j, _) in &random_spd(n, 40 + g as u64) {
                    if i != j {
                        adj[i].push(j);
                    }
                }
                adj
            })
            .collect();
        let alone: Vec<Vec<usize>> = graphs
            .iter()
            .map(|a| nested_dissection(a).unwrap())
            .collect();
        std::thread::scope(|s| {
            let handles: Vec<_> = (0..6)
                .map(|t| {
                    let (graphs, alone) = (&graphs, &alone);
                    s.spawn(move || {
                        for r in 0..4 {
                            let g = (t + r) % graphs.len();
                            assert_eq!(nested_dissection(&graphs[g]).unwrap(), alone[g]);
                        }
                    })
                })
                .collect();
            for h in handles {
                h.join().unwrap();
            }
        });
    }
}
