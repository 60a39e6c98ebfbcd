use super::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// `f` frames of `v` vertices: `rank` random shapes at random coefficients, plus noise of
/// amplitude `noise` per coordinate.
fn frames(f: usize, v: usize, rank: usize, noise: f64, seed: u64) -> Vec<Vec<Point>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let shapes: Vec<Vec<Point>> = (0..rank)
        .map(|_| {
            (0..v)
                .map(|_| std::array::from_fn(|_| rng.random_range(-1.0..1.0)))
                .collect()
        })
        .collect();
    (0..f)
        .map(|_| {
            let c: Vec<f64> = (0..rank).map(|_| rng.random_range(-2.0..2.0)).collect();
            (0..v)
                .map(|i| {
                    std::array::from_fn(|a| {
                        let s: f64 = (0..rank).map(|k| c[k] * shapes[k][i][a]).sum();
                        s + noise * rng.random_range(-1.0..1.0)
                    })
                })
                .collect()
        })
        .collect()
}

/// The largest vertex distance between the frames and the basis's reconstruction.
fn worst(frames: &[Vec<Point>], b: &ClipBasis) -> f64 {
    let mut w: f64 = 0.0;
    for (f, fr) in frames.iter().enumerate() {
        for (p, q) in fr.iter().zip(b.frame(f)) {
            let d = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
            w = w.max(d);
        }
    }
    w
}

#[test]
fn a_low_rank_clip_needs_its_rank_and_no_more() {
    // F > 3V (the 3V × 3V Gram) and F < 3V (the F × F Gram).
    for (f, v) in [(60, 8), (12, 40)] {
        let fr = frames(f, v, 3, 0.0, 7);
        let b = residual_basis(&fr, 1e-6, 50).unwrap();
        assert_eq!(b.shapes.len(), 3, "{f} frames of {v} vertices");
        assert!(b.max_error <= 1e-6, "{}", b.max_error);
        // The reported error is the true error of the stored numbers.
        let w = worst(&fr, &b);
        assert!((w - b.max_error).abs() <= 1e-12, "{w} vs {}", b.max_error);
    }
}

#[test]
fn every_frame_is_within_the_tolerance_and_a_looser_one_needs_fewer_shapes() {
    let fr = frames(40, 30, 6, 0.02, 11);
    let mut last = usize::MAX;
    for tol in [1e-3, 0.03, 0.1, 1.0] {
        let b = residual_basis(&fr, tol, 200).unwrap();
        let w = worst(&fr, &b);
        assert!(w <= tol, "tolerance {tol}: worst {w}");
        assert!(
            b.shapes.len() <= last,
            "tolerance {tol}: {} shapes",
            b.shapes.len()
        );
        last = b.shapes.len();
    }
    // The noise (0.02 per coordinate, up to 0.035 per vertex) needs more than the six shapes
    // at 1e-3, the six alone are enough at 0.1.
    assert!(residual_basis(&fr, 1e-3, 200).unwrap().shapes.len() > 6);
    assert!(residual_basis(&fr, 0.1, 200).unwrap().shapes.len() <= 6);
}

#[test]
fn stored_numbers_are_f32_and_each_shape_peaks_at_one() {
    let fr = frames(25, 10, 4, 0.0, 3);
    let b = residual_basis(&fr, 1e-5, 50).unwrap();
    for s in &b.shapes {
        assert!(s.iter().flatten().all(|&x| x as f32 as f64 == x));
    }
    for k in 0..b.shapes.len() {
        let col: Vec<f64> = b.coefficients.iter().map(|c| c[k]).collect();
        assert!(col.iter().all(|&x| x as f32 as f64 == x));
        let peak = col
            .iter()
            .copied()
            .max_by(|a, b| a.abs().total_cmp(&b.abs()));
        assert!((peak.unwrap() - 1.0).abs() < 1e-5, "shape {k}: {peak:?}");
    }
}

#[test]
fn zero_frames_need_no_shape_and_the_same_frames_give_the_same_bits() {
    let zero = vec![vec![[0.0; 3]; 5]; 4];
    let b = residual_basis(&zero, 1e-9, 10).unwrap();
    assert!(b.shapes.is_empty());
    assert_eq!(b.max_error, 0.0);
    let fr = frames(30, 20, 5, 0.01, 5);
    let a = residual_basis(&fr, 1e-3, 100).unwrap();
    let c = residual_basis(&fr, 1e-3, 100).unwrap();
    let bits = |b: &ClipBasis| -> Vec<u64> {
        b.shapes
            .iter()
            .flatten()
            .flatten()
            .chain(b.coefficients.iter().flatten())
            .map(|x| x.to_bits())
            .collect()
    };
    assert_eq!(bits(&a), bits(&c));
}

#[test]
fn bad_input_is_refused_with_its_place() {
    assert_eq!(residual_basis(&[], 1e-3, 5).unwrap_err(), ClipError::Empty);
    let mut fr = frames(4, 3, 2, 0.0, 1);
    assert_eq!(
        residual_basis(&fr, 0.0, 5).unwrap_err(),
        ClipError::Tolerance(0.0)
    );
    assert!(matches!(
        residual_basis(&fr, f64::NAN, 5),
        Err(ClipError::Tolerance(_))
    ));
    fr[2][1][0] = f64::NAN;
    assert_eq!(
        residual_basis(&fr, 1e-3, 5).unwrap_err(),
        ClipError::NotFinite {
            frame: 2,
            vertex: 1
        }
    );
    fr[2].pop();
    assert!(matches!(
        residual_basis(&fr, 1e-3, 5),
        Err(ClipError::VertexCount { frame: 2, .. })
    ));
    // Full rank noise cannot be reached with one shape.
    let fr = frames(10, 6, 0, 0.5, 2);
    match residual_basis(&fr, 1e-4, 1) {
        Err(ClipError::TooManyShapes {
            max_shapes, error, ..
        }) => {
            assert_eq!(max_shapes, 1);
            assert!(error > 1e-4);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn shapes_on_an_integer_grid_report_the_error_of_the_stored_numbers() {
    let fr = frames(40, 30, 4, 0.001, 5);
    let tol = 0.02;
    // (grid, the least scale, the range of its integers in the shape's units).
    for (grid, least, range) in [
        (Grid::I16Normalized, 0.5, 1.0),
        (Grid::I16, tol / 16.0, 32767.0),
    ] {
        let mut scales = Vec::new();
        let b = residual_basis_on(&fr, tol, 100, |shape| {
            assert_eq!(shape.len(), 30);
            let s = f64::max(least, peak_of(shape) / range);
            scales.push(s);
            (s, grid)
        })
        .unwrap();
        assert_eq!(scales.len(), b.shapes.len());
        assert!(b.grids.iter().all(|g| *g == grid));
        // Every coordinate is on the grid, and the error is that of these numbers.
        for x in b.shapes.iter().flatten().flatten() {
            assert_eq!(grid.round(*x), *x);
        }
        let w = worst(&fr, &b);
        assert!(
            w <= tol && (w - b.max_error).abs() <= 1e-12,
            "{w} vs {}",
            b.max_error
        );
        // The largest coefficient of each shape is the scale asked for, but for rounding.
        for (k, want) in scales.iter().enumerate() {
            let c = b
                .coefficients
                .iter()
                .map(|r| r[k].abs())
                .fold(0.0, f64::max);
            assert!(
                (c / want - 1.0).abs() < 1e-2,
                "{grid:?} shape {k}: {c} vs {want}"
            );
        }
    }
}

/// The largest absolute coordinate of `p`.
fn peak_of(p: &[Point]) -> f64 {
    p.iter().flatten().fold(0.0, |m, x| m.max(x.abs()))
}

#[test]
fn blocks_from_the_range_finder_need_about_as_many_shapes_as_the_exact_directions() {
    // Rank 30 (two blocks and more) with decaying coefficients and a little noise, on both
    // sides of the Gram matrix's shape (F < 3V and F > 3V).
    for (f, v, seed) in [(150, 200, 3), (400, 60, 5)] {
        let mut fr = frames(f, v, 30, 0.0, seed);
        let decay = frames(f, v, 30, 2e-4, seed + 1);
        for (a, b) in fr.iter_mut().zip(&decay) {
            for (p, q) in a.iter_mut().zip(b) {
                for k in 0..3 {
                    p[k] = 0.05 * p[k] + q[k] * 0.001;
                }
            }
        }
        let tolerance = 0.02;
        let exact = basis_by_route(&fr, tolerance, 200, |_| (1.0, Grid::F32), false).unwrap();
        let blocks = basis_by_route(&fr, tolerance, 200, |_| (1.0, Grid::F32), true).unwrap();
        for b in [&exact, &blocks] {
            assert!(b.max_error <= tolerance, "{}", b.max_error);
            let w = worst(&fr, b);
            assert!((w - b.max_error).abs() <= 1e-12, "{w} vs {}", b.max_error);
        }
        let (ne, nb) = (exact.shapes.len(), blocks.shapes.len());
        assert!(
            nb > YIELD_FOR_TESTS,
            "{nb}: one block would do, the test tests too little"
        );
        assert!(
            nb <= ne + ne / 5 + 2,
            "{f}×{v}: {nb} shapes in blocks, {ne} exact"
        );
        // The same frames, the same bits.
        let again = basis_by_route(&fr, tolerance, 200, |_| (1.0, Grid::F32), true).unwrap();
        assert_eq!(again.shapes, blocks.shapes);
        assert_eq!(again.coefficients, blocks.coefficients);
        eprintln!("{f}×{v}: {ne} exact, {nb} in blocks");
    }
}

const YIELD_FOR_TESTS: usize = randomized::YIELD;

#[test]
fn the_block_route_is_taken_only_where_the_gram_matrix_is_expensive() {
    // 2 100 frames of the 420-vertex tube: the exact route (as before); 1 800 frames of the
    // 26 719-vertex ICT head: blocks, about 5× fewer operations for 64 shapes.
    assert!(exact_flops(2100, 3 * 420) < EXACT_FLOPS);
    assert!(exact_flops(335, 3 * 26719) < EXACT_FLOPS);
    assert!(exact_flops(1800, 3 * 26719) > EXACT_FLOPS);
    assert!(block_flops(1800, 3 * 26719, 64) * 4.0 < exact_flops(1800, 3 * 26719));
}
