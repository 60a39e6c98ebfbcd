//! One module per subcommand: its clap arguments and its `run`.

pub mod bake;
pub mod bench;
pub mod bench_continuity;
pub mod bench_machine;
pub mod bench_rig;
pub mod bench_scene;
pub mod bench_scrub;
pub mod bench_synth;
pub mod bench_transfer;
pub mod bench_volume;
pub mod blend;
pub mod blend_args;
pub mod blend_frames;
pub mod blend_inputs;
pub mod blend_interactive;
pub mod blend_outputs;
pub mod blend_rig;
pub mod blend_rig_out;
pub mod blend_solve;
pub mod convert;
pub mod corr_args;
pub mod correspond;
#[cfg(test)]
mod defaults_tests;
pub mod demo;
pub mod flex;
pub mod info;
pub mod rig;
pub mod scene;
pub mod synth;
pub mod transfer;
pub mod volume;
pub mod weld_util;
