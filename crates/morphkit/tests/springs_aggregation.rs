//! The two-level aggregation preconditioner (`Preconditioner::Aggregation`) in the physical
//! blend with internal springs: it reaches the equilibria the Cholesky factor reaches, keeps
//! the endpoints exact and the volume of the factor's solve, gives the same bytes whatever the
//! thread count or frame order, and `Auto` leaves small systems with the factor.

mod common;

use common::max_dist;
use morphkit::mesh::enclosed_volume as volume;
use morphkit::mesh::{bbox_diagonal, ShapeSet};
use morphkit::springs::{
    AnchorOptions, AnchorPlacement, BlendOptions, InteriorMode, InteriorOptions, PhysicalBlend,
    Preconditioner, VolumetricBlend, Weights,
};

/// A closed tube bent by 120°, about 1.5k vertices with its lattice interior.
fn bent_tube() -> ShapeSet {
    common::bent_tube(20, 48, 120.0)
}

fn blend(s: &ShapeSet, preconditioner: Preconditioner, anchor: bool) -> VolumetricBlend {
    let options = BlendOptions {
        preconditioner,
        ..Default::default()
    };
    let interior = InteriorOptions {
        mode: InteriorMode::Lattice,
        ..Default::default()
    };
    let anchor = AnchorOptions {
        placement: if anchor {
            AnchorPlacement::Auto
        } else {
            AnchorPlacement::None
        },
        ..Default::default()
    };
    VolumetricBlend::new(s, &options, &interior, &anchor).unwrap()
}

#[test]
fn aggregation_reaches_the_factors_equilibria_with_exact_endpoints() {
    let s = bent_tube();
    let d = bbox_diagonal(s.positions(0));
    let tris = s.triangles();
    for anchor in [false, true] {
        let mut agg = blend(&s, Preconditioner::Aggregation, anchor);
        let mut chol = blend(&s, Preconditioner::Cholesky, anchor);
        let sa = agg.physical().summary().clone();
        assert!(
            sa.aggregates > 0 && sa.aggregates * 4 < sa.vertices,
            "{} aggregates of {} vertices",
            sa.aggregates,
            sa.vertices
        );
        assert_eq!(chol.physical().summary().aggregates, 0);
        for (alpha, shape) in [(0.0, 0), (1.0, 1)] {
            let r = agg.solve(&Weights::Alpha(alpha)).unwrap();
            assert!(
                max_dist(&r.positions, s.positions(shape)) <= 1e-6 * d,
                "anchor {anchor}, α = {alpha}"
            );
        }
        let (mut cg_agg, mut cg_chol) = (0, 0);
        for alpha in [0.25, 0.5, 0.8] {
            let a = agg.solve(&Weights::Alpha(alpha)).unwrap();
            let c = chol.solve(&Weights::Alpha(alpha)).unwrap();
            assert!(a.stats.converged && c.stats.converged, "{:?}", a.stats);
            cg_agg += a.stats.cg_iterations;
            cg_chol += c.stats.cg_iterations;
            // Both are the equilibrium to the gradient tolerance: the same shape.
            let gap = max_dist(&a.positions, &c.positions);
            assert!(
                gap <= 1e-5 * d,
                "anchor {anchor}, α = {alpha}: {gap:e} of {d}"
            );
            let (va, vc) = (volume(&a.positions, tris), volume(&c.positions, tris));
            assert!((va - vc).abs() <= 1e-6 * vc.abs(), "{va} vs {vc}");
        }
        // The cycle is a weaker preconditioner than the factor: more inner iterations, so the
        // two runs did not take the same path.
        assert!(cg_agg > cg_chol, "{cg_agg} vs {cg_chol}");
    }
}

#[test]
fn aggregation_frames_are_the_same_bytes_in_any_order_and_thread_count() {
    let s = bent_tube();
    let mut v = blend(&s, Preconditioner::Aggregation, false);
    let w: Vec<Weights> = (0..6).map(|k| Weights::Alpha(k as f64 / 5.0)).collect();
    let one: Vec<_> = v
        .solve_many(&w, 1)
        .into_iter()
        .map(|r| r.unwrap())
        .collect();
    let order = [4usize, 1, 5, 0, 3, 2];
    let shuffled: Vec<Weights> = order.iter().map(|&k| w[k].clone()).collect();
    for (r, &k) in v.solve_many(&shuffled, 2).iter().zip(&order) {
        let r = r.as_ref().unwrap();
        assert!(r.stats.converged, "frame {k}: {:?}", r.stats);
        common::assert_same_frame(&r.positions, &one[k].positions, &format!("frame {k}"));
    }
}

#[test]
fn auto_keeps_the_factor_where_it_fills_little() {
    // A surface tube and a small volumetric one: both far below the fill threshold.
    let s = bent_tube();
    let surface = PhysicalBlend::new(&s, &BlendOptions::default()).unwrap();
    assert_eq!(surface.summary().aggregates, 0);
    let v = blend(&s, Preconditioner::Auto, false);
    let sm = v.physical().summary();
    assert!(
        sm.factor_flops
            <= morphkit::springs::AGGREGATION_FLOPS_PER_ENTRY * sm.hessian_entries as f64
    );
    assert_eq!(sm.aggregates, 0);
}
