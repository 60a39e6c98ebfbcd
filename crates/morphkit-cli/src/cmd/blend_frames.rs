//! The plain mode of `morphkit blend`: surface frames (physical, `--linear` or
//! `--interactive`) of a base and targets, or of `--rig` when `--out` is not the asset, written
//! as frames. The pipeline is [`run`]: inputs (an [`Input`]) → the surface solve
//! ([`super::blend_solve`]) → one of three outputs, each its own function:
//!
//! - a frame directory or .pc2 is streamed as frames are solved ([`io::FrameStream`]);
//! - a .glb/.gltf or .usda animation receives every frame at once ([`write_animation`]);
//! - a single .obj/.ply/.off holds the one frame, in the base's own file format where it has
//!   one ([`write_mesh`]).
//!
//! A mode at the top of `blend`'s one-way stack (see [`super::blend`]): only the dispatcher
//! calls it, and `--rig`'s asset output is a mode of its own ([`super::blend_rig_out`]).

use super::blend_args::BlendArgs;
use super::blend_inputs::Input;
use super::blend_outputs::weights_json;
use super::blend_solve::{finish, Surface};
use crate::outputs::{is_frame_dir, Outputs};
use morphkit::io::{self, FramesOptions};
use morphkit::mesh::{Point, ShapeSet};
use serde_json::json;
use std::time::Instant;

/// Where the frames of [`run`] go while they are solved.
enum Frames {
    /// A frame directory or .pc2, written chunk by chunk; the seconds its writes took.
    Streamed(Box<io::FrameStream>, f64),
    /// Every frame, named `frame_KKKK`, for an output written at the end.
    Held(Vec<(String, Vec<Point>)>),
}

/// Runs the plain mode: solves `input`'s frames and writes them to `--out`.
pub(super) fn run(a: &BlendArgs, input: Input, mut outputs: Outputs) -> anyhow::Result<()> {
    let mut surface = Surface::setup(a, &input)?;
    let mut frames = Frames::open(a, &input, &mut outputs)?;
    let solved = surface.solve(a, &input, |k, positions| frames.push(k, positions))?;
    let regions = solved.warn(&mut outputs, a, &input)?;
    let write_seconds = frames.write(&mut outputs, a, &input)?;
    // How a .glb/.gltf animation was laid out (a compact clip or a target per frame).
    let clip = outputs.clips().last().cloned();
    surface.report(
        &mut outputs,
        a,
        &input,
        (&solved, &regions),
        (write_seconds, clip),
    )?;
    finish(outputs, a, &input)
}

impl Frames {
    /// A stream where `--out` takes one (a frame directory or .pc2), else an empty hold.
    fn open(a: &BlendArgs, input: &Input, outputs: &mut Outputs) -> anyhow::Result<Frames> {
        let dir_out = is_frame_dir(&a.out);
        Ok(
            if !input.single_mesh && io::FrameStream::supports(&a.out, dir_out) {
                let stream = outputs.stream(
                    &a.out,
                    dir_out,
                    input.shapes.base(),
                    input.weights.len(),
                    input.template.clone(),
                )?;
                Frames::Streamed(Box::new(stream), 0.0)
            } else {
                Frames::Held(Vec::new())
            },
        )
    }

    /// Takes frame `k` (the input's layout): written now when streamed, else kept.
    fn push(&mut self, k: usize, positions: Vec<Point>) -> anyhow::Result<()> {
        match self {
            Frames::Streamed(stream, seconds) => {
                let t = Instant::now();
                stream.push(&positions)?;
                *seconds += t.elapsed().as_secs_f64();
            }
            Frames::Held(frames) => frames.push((format!("frame_{k:04}"), positions)),
        }
        Ok(())
    }

    /// Finishes the stream or writes the held frames; returns the seconds all writes took.
    fn write(self, outputs: &mut Outputs, a: &BlendArgs, input: &Input) -> anyhow::Result<f64> {
        let t_write = Instant::now();
        let mut write_seconds = 0.0;
        match self {
            Frames::Streamed(stream, seconds) => {
                write_seconds = seconds;
                stream.finish()?;
            }
            Frames::Held(frames) if input.single_mesh => write_mesh(outputs, a, input, frames)?,
            Frames::Held(frames) => write_animation(outputs, a, input, frames)?,
        }
        Ok(write_seconds + t_write.elapsed().as_secs_f64())
    }
}

/// Stages the one frame of a single .obj/.ply/.off `--out`, as the base's own file (texture
/// coordinates, normals, materials kept; `io::MeshTemplate`) where it has one.
fn write_mesh(
    outputs: &mut Outputs,
    a: &BlendArgs,
    input: &Input,
    frames: Vec<(String, Vec<Point>)>,
) -> anyhow::Result<()> {
    let out_set = ShapeSet::new(input.shapes.base().clone(), frames)?;
    outputs.mesh_like(&a.out, &out_set.mesh(0), input.template.as_ref())
}

/// Stages every frame as an animation (.glb/.gltf: frame `k` at `k / fps` seconds, the weights
/// in the asset's extras; .usda: time-sampled points).
fn write_animation(
    outputs: &mut Outputs,
    a: &BlendArgs,
    input: &Input,
    frames: Vec<(String, Vec<Point>)>,
) -> anyhow::Result<()> {
    let out_set = ShapeSet::new(input.shapes.base().clone(), frames)?;
    let mut opts = FramesOptions {
        fps: a.fps,
        inputs: input.inputs.clone(),
        ..FramesOptions::default()
    };
    let weights: Vec<_> = input.weights.iter().map(weights_json).collect();
    opts.gltf.extras = Some(json!({ "weights": weights }));
    outputs.frames(&a.out, &out_set, &opts, |_| {})
}
