//! The blend's memory estimate follows the preconditioner actually used (issue 38, film
//! scale): the aggregation cycle never allocates the fine factor and is estimated smaller;
//! `Preconditioner::Auto` refuses a blend whose factor would not fit `max_memory_bytes`;
//! reference factors get only what the limit leaves, and are counted.

use morphkit::mesh::{generate, ShapeSet};
use morphkit::springs::{BlendError, BlendOptions, PhysicalBlend, Preconditioner};

/// A sheet bent by 60° along half its length, every vertex free.
fn bent_sheet(side: usize) -> ShapeSet {
    let g = generate::grid(side, side, 1.0, 1.0);
    let bent = generate::bend(&g.positions, 0.5, 0.5, 60f64.to_radians());
    ShapeSet::new(
        g.clone(),
        vec![("flat".into(), g.positions.clone()), ("bent".into(), bent)],
    )
    .unwrap()
}

fn options(preconditioner: Preconditioner, limit: u64) -> BlendOptions {
    BlendOptions {
        preconditioner,
        reference_factor_bytes: 0,
        max_memory_bytes: limit,
        ..Default::default()
    }
}

#[test]
fn the_estimate_follows_the_preconditioner_and_auto_refuses_over_the_limit() {
    let s = bent_sheet(90);
    let big = 8 << 30;
    let with_factor = PhysicalBlend::new(&s, &options(Preconditioner::Cholesky, big)).unwrap();
    let factor_bytes = with_factor.summary().predicted_bytes;
    assert_eq!(with_factor.summary().aggregates, 0);
    let forced = PhysicalBlend::new(&s, &options(Preconditioner::Aggregation, big)).unwrap();
    let cycle_bytes = forced.summary().predicted_bytes;
    assert!(forced.summary().aggregates > 0);
    assert!(
        cycle_bytes < factor_bytes,
        "cycle {cycle_bytes} vs factor {factor_bytes}"
    );
    // Auto keeps the factor on a sheet this small (its fill is cheap).
    let auto = PhysicalBlend::new(&s, &options(Preconditioner::Auto, big)).unwrap();
    assert_eq!(auto.summary().aggregates, 0);
    assert_eq!(auto.summary().predicted_bytes, factor_bytes);
    // Between the two estimates the forced cycle fits; Auto does not take the cycle for
    // memory alone (it does not converge on such sheets) and refuses with the factor's
    // estimate, which is what the blend would need.
    let limit = (cycle_bytes + factor_bytes) / 2;
    assert!(PhysicalBlend::new(&s, &options(Preconditioner::Aggregation, limit)).is_ok());
    let e = PhysicalBlend::new(&s, &options(Preconditioner::Auto, limit)).unwrap_err();
    assert!(
        matches!(e, BlendError::TooLarge { predicted_bytes, .. } if predicted_bytes == factor_bytes),
        "{e}"
    );
    // Forced, the factor is refused too (by the estimate before the scalar analysis).
    let e = PhysicalBlend::new(&s, &options(Preconditioner::Cholesky, limit)).unwrap_err();
    assert!(
        matches!(e, BlendError::TooLarge { predicted_bytes, .. } if predicted_bytes > limit),
        "{e}"
    );
}

#[test]
fn reference_factors_are_counted_and_get_only_what_the_limit_leaves() {
    let s = bent_sheet(40);
    let big = 8 << 30;
    let without = PhysicalBlend::new(&s, &options(Preconditioner::Cholesky, big)).unwrap();
    let base = without.summary().predicted_bytes;
    let with = PhysicalBlend::new(
        &s,
        &BlendOptions {
            reference_factor_bytes: 1 << 30,
            ..options(Preconditioner::Cholesky, big)
        },
    )
    .unwrap();
    let sum = with.summary();
    assert_eq!(sum.reference_targets, 1);
    // Five single-precision factors: the base's and the target's four.
    let factor = 4 * sum.factor_nnz as u64;
    assert_eq!(sum.predicted_bytes, base + 5 * factor);
    // A limit with room for the blend but not for its references: none, and not counted.
    let tight = PhysicalBlend::new(
        &s,
        &BlendOptions {
            reference_factor_bytes: 1 << 30,
            ..options(Preconditioner::Cholesky, base + 4 * factor)
        },
    )
    .unwrap();
    assert_eq!(tight.summary().reference_targets, 0);
    assert_eq!(tight.summary().predicted_bytes, base);
}
