//! `morphkit`: physical blendshapes, animation transfer and synthesis from the command line.

mod cmd;
mod outputs;
mod outputs_flags;
mod util;
mod weights;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

/// Physically plausible blendshapes and example-driven animation transfer for triangle meshes.
#[derive(Parser, Debug)]
#[command(name = "morphkit", version, about, long_about = None, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    #[command(flatten)]
    output: outputs::OutputFlags,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Describe meshes: counts, size, boundary, components, shared connectivity.
    Info(cmd::info::InfoArgs),
    /// Convert between OBJ, PLY, OFF, glTF/GLB, PC2 and USD, single meshes or frame sequences.
    Convert(cmd::convert::ConvertArgs),
    /// Run the main job on a built-in example: physical vs. linear blend of a bent bar.
    Demo(cmd::demo::DemoArgs),
    /// Blend shapes by rest-length interpolation of a mass–spring system (Ma et al. 2012).
    Blend(Box<cmd::blend::BlendArgs>),
    /// Compute a triangle correspondence between two meshes from marker pairs.
    Correspond(cmd::correspond::CorrespondArgs),
    /// Transfer an animation from a source mesh onto a different target mesh.
    Transfer(cmd::transfer::TransferArgs),
    /// Move a blendshape rig (neutral + named expressions) onto another character as a GLB.
    Rig(cmd::rig::RigArgs),
    /// Bake a glTF rig's physical blend into in-between and combination shapes (any client).
    Bake(cmd::bake::BakeArgs),
    /// Show how flexible each triangle of an animation is (where markers are needed).
    Flex(cmd::flex::FlexArgs),
    /// Assemble a new animation from parts of several animations, by a TOML recipe.
    Synth(cmd::synth::SynthArgs),
    /// Measure solver speed on generated and real meshes.
    Bench(cmd::bench::BenchArgs),
}

/// On SIGINT, SIGTERM or SIGHUP: remove the temporary files of the outputs being written
/// (`morphkit::io::temporaries`), say so, and exit with 128 + the signal's number, as a shell
/// reports a process killed by it. Outputs already in place are complete ones.
#[cfg(unix)]
fn remove_temporaries_on_signals() {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) else {
        return;
    };
    std::thread::spawn(move || {
        if let Some(sig) = signals.forever().next() {
            morphkit::io::remove_temporaries_then(|| {
                let name = match sig {
                    SIGINT => "SIGINT",
                    SIGTERM => "SIGTERM",
                    _ => "SIGHUP",
                };
                eprintln!("\ninterrupted ({name}): nothing more was written, and the unfinished outputs were removed");
                std::process::exit(128 + sig)
            });
        }
    });
}

/// The command-line parser, where every option that takes a value accepts a negative number
/// as its value (`--alpha -0.5`, `--fps -1`): clap would otherwise take `-0.5` for a flag and
/// say "unexpected argument '-0' found". The value is then checked like any other (`--alpha
/// -0.5` extrapolates; `--fps -1` is refused naming the flag and the accepted range).
fn command() -> clap::Command {
    fn negatives(cmd: clap::Command) -> clap::Command {
        cmd.mut_args(|a| {
            if a.get_action().takes_values() {
                a.allow_negative_numbers(true)
            } else {
                a
            }
        })
        .mut_subcommands(negatives)
    }
    negatives(Cli::command())
}

fn main() {
    #[cfg(unix)]
    remove_temporaries_on_signals();
    let mut parser = command();
    let matches = parser.clone().get_matches();
    let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.format(&mut parser).exit());
    let name = match &cli.command {
        Command::Info(_) => "info",
        Command::Convert(_) => "convert",
        Command::Demo(_) => "demo",
        Command::Blend(_) => "blend",
        Command::Correspond(_) => "correspond",
        Command::Transfer(_) => "transfer",
        Command::Rig(_) => "rig",
        Command::Bake(_) => "bake",
        Command::Flex(_) => "flex",
        Command::Synth(_) => "synth",
        Command::Bench(_) => "bench",
    };
    outputs::set_context(cli.output.clone(), name);
    let result = match &cli.command {
        Command::Info(a) => cmd::info::run(a),
        Command::Convert(a) => cmd::convert::run(a),
        Command::Demo(a) => cmd::demo::run(a),
        Command::Blend(a) => cmd::blend::run(a),
        Command::Correspond(a) => cmd::correspond::run(a),
        Command::Transfer(a) => cmd::transfer::run(a),
        Command::Rig(a) => cmd::rig::run(a),
        Command::Bake(a) => cmd::bake::run(a),
        Command::Flex(a) => cmd::flex::run(a),
        Command::Synth(a) => cmd::synth::run(a),
        Command::Bench(a) => cmd::bench::run(a),
    };
    if let Err(e) = result {
        eprintln!("error: {e}");
        for cause in e.chain().skip(1) {
            eprintln!("  caused by: {cause}");
        }
        std::process::exit(1);
    }
}
