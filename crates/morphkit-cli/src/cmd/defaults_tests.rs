//! Issue 55, one answer per entry point: `transfer`, `correspond` and `rig` without flags use
//! the library's defaults, and their opt-out flags change only what they name.

use super::correspond::CorrespondArgs;
use super::rig::RigArgs;
use super::transfer::TransferArgs;
use clap::Parser;
use morphkit::transfer::{
    CorrespondenceOptions, GradientCombine, GradientFrame, RigOptions, TransferOptions,
    TriangleWeighting,
};

#[derive(Parser)]
struct Cli<A: clap::Args> {
    #[command(flatten)]
    args: A,
}

fn parse<A: clap::Args>(args: &[&str]) -> A {
    Cli::<A>::try_parse_from(std::iter::once("morphkit").chain(args.iter().copied()))
        .unwrap_or_else(|e| panic!("{args:?}: {e}"))
        .args
}

/// The options structs have no `PartialEq`; their `Debug` forms show every field.
fn same<T: std::fmt::Debug>(a: &T, b: &T) -> bool {
    format!("{a:?}") == format!("{b:?}")
}

const TRANSFER: [&str; 10] = [
    "--source-ref",
    "s.obj",
    "--source",
    "f.obj",
    "--target",
    "t.obj",
    "--markers",
    "m.json",
    "--out",
    "out/",
];

fn transfer(flags: &[&str]) -> TransferArgs {
    parse(&[&TRANSFER[..], flags].concat())
}

#[test]
fn transfer_without_flags_is_the_library_default() {
    let a = transfer(&[]);
    let o = super::transfer::options(&a).unwrap();
    assert!(same(&o, &TransferOptions::default()), "{o:?}");
    assert!(same(
        &a.corr.correspondence_options(),
        &CorrespondenceOptions::default()
    ));
    assert_eq!(a.corr.combine(), GradientCombine::default());
    // The flags that name the defaults change nothing.
    let named = transfer(&["--refine", "--local-stretch", "--area-weighted"]);
    assert!(same(
        &super::transfer::options(&named).unwrap(),
        &TransferOptions::default()
    ));
    assert!(same(
        &named.corr.correspondence_options(),
        &CorrespondenceOptions::default()
    ));
}

#[test]
fn transfer_opt_out_flags_change_only_what_they_name() {
    let a = transfer(&[
        "--no-refine",
        "--world-frame",
        "--uniform-weights",
        "--combine",
        "mean",
    ]);
    let want = TransferOptions {
        frame: GradientFrame::World,
        combine: GradientCombine::Mean,
        solver: morphkit::transfer::SolverOptions {
            weighting: TriangleWeighting::Uniform,
            ..TransferOptions::default().solver
        },
        ..TransferOptions::default()
    };
    assert!(same(&super::transfer::options(&a).unwrap(), &want));
    let want = CorrespondenceOptions {
        refine: None,
        ..CorrespondenceOptions::default()
    };
    assert!(same(&a.corr.correspondence_options(), &want));
    let a = transfer(&["--no-fold-guard"]);
    let o = super::transfer::options(&a).unwrap();
    assert!(o.fold_guard.is_none());
    assert!(same(
        &TransferOptions {
            fold_guard: TransferOptions::default().fold_guard,
            ..o
        },
        &TransferOptions::default()
    ));
}

#[test]
fn correspond_without_flags_is_the_library_default() {
    let a: CorrespondArgs = parse(&[
        "--source",
        "s.obj",
        "--target",
        "t.obj",
        "--markers",
        "m.json",
        "--out",
        "c.json",
    ]);
    let o = super::correspond::options(&a).unwrap();
    assert!(same(&o, &CorrespondenceOptions::default()), "{o:?}");
}

#[test]
fn rig_without_flags_is_the_library_rig_default() {
    let base = [
        "--source-neutral",
        "n.obj",
        "--source-shapes",
        "a.obj",
        "--target",
        "t.obj",
        "--markers",
        "m.json",
        "--out",
        "r.glb",
    ];
    let a: RigArgs = parse(&base);
    let (corr, opts) = super::rig::options(&a);
    assert!(same(&opts, &RigOptions::default()));
    assert!(same(
        &corr.correspondence_options(),
        &RigOptions::correspondence()
    ));
    let a: RigArgs = parse(&[&base[..], &["--refine"]].concat());
    let refined = super::rig::options(&a).0.correspondence_options();
    assert!(same(&refined, &CorrespondenceOptions::default()));
}
