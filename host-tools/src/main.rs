//! `posecoach`: the host command-line tool.
//!
//! Every command returns its output as text (a readable summary, or one JSON object with
//! `--json`) and `main` prints it; a failure is printed and its exit status given as
//! [`posecoach_cli::failure`] says.

use posecoach_cli::failure::{self, Kind};
#[cfg(feature = "learn")]
use posecoach_cli::learn;
use posecoach_cli::{
    bench, bridge, demo, device_sim, inspect, reference, replay, retarget, score, synth, tpose,
};

use clap::{Parser, Subcommand};
use std::io::Write;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "posecoach",
    version,
    about = "Virtual golf coach: retarget a coach's swing onto a student and score it"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Score a bundled recorded session against the bundled coaches: report.html, report.json.
    Demo(demo::Args),
    /// Retarget a coach's motion onto a student's skeleton, given by a T-pose.
    Retarget(retarget::Args),
    /// Score a student's swing against the coach's swing retargeted onto the student.
    Score(score::Args),
    /// Describe a motion file: format, joints, frames, rate, height, segments, missing data.
    Inspect(inspect::Args),
    /// Store a coach's swing as the device stores it: a coach reference blob (.pcr).
    Reference(reference::Args),
    /// Write a keypoint format's standard T-pose scaled to a height, for use as a student.
    Tpose(tpose::Args),
    /// Measure the speed of the core's hot paths.
    Bench(bench::Args),
    /// Run a recorded session (.pclog) through the device's pipeline and report every swing.
    Replay(replay::Args),
    /// Make a realistic recorded session (.pclog and its expected swings) from swing files.
    SynthLog(synth::Args),
    /// Relay between a device's serial port and phone apps over TCP, one JSON message per line.
    Bridge(bridge::Args),
    /// Run the device's pipeline on the host, speaking the wire protocol over a serial port.
    DeviceSim(device_sim::Args),
    /// Train the learned retargeter (the teacher network) on motion data, unsupervised.
    #[cfg(feature = "learn")]
    Train(learn::TrainArgs),
    /// Distill a trained teacher into a smaller network (for the device) on the teacher's outputs.
    #[cfg(feature = "learn")]
    Distill(learn::DistillArgs),
    /// Quantize a distilled network to int8 and write the device's weights blob (.pcw).
    #[cfg(feature = "learn")]
    Export(learn::ExportArgs),
    /// Fine-tune a trained teacher to one student's body.
    #[cfg(feature = "learn")]
    Finetune(learn::FinetuneArgs),
    /// Evaluate retargeters on held-out characters and motions against the ground truth.
    #[cfg(feature = "learn")]
    Eval(learn::EvalArgs),
}

// glibc's malloc makes training steps several times slower (page faults on every large
// tensor); mimalloc keeps freed pages. Scoring does not need it.
#[cfg(feature = "learn")]
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> ExitCode {
    let json = std::env::args_os().skip(1).any(|a| a == "--json");
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        // Help and version, and a usage error as a person reads it, as clap prints them.
        Err(e) if !json || !e.use_stderr() => e.exit(),
        Err(e) => {
            let rendered = e.render().to_string();
            let message = rendered.lines().next().unwrap_or_default();
            let message = message.strip_prefix("error: ").unwrap_or(message);
            println!("{}", failure::to_json(Kind::Usage, message));
            eprint!("{rendered}");
            return ExitCode::from(Kind::Usage.status());
        }
    };
    let result = match cli.command {
        Command::Demo(args) => demo::run(&args),
        Command::Retarget(args) => retarget::run(&args),
        Command::Score(args) => score::run(&args),
        Command::Inspect(args) => inspect::run(&args),
        Command::Reference(args) => reference::run(&args),
        Command::Tpose(args) => tpose::run(&args),
        Command::Bench(args) => bench::run(&args),
        Command::Replay(args) => replay::run(&args),
        Command::SynthLog(args) => synth::run(&args),
        Command::Bridge(args) => bridge::run(&args),
        Command::DeviceSim(args) => device_sim::run(&args),
        #[cfg(feature = "learn")]
        Command::Train(args) => learn::train(&args),
        #[cfg(feature = "learn")]
        Command::Distill(args) => learn::distill(&args),
        #[cfg(feature = "learn")]
        Command::Export(args) => learn::export(&args),
        #[cfg(feature = "learn")]
        Command::Finetune(args) => learn::finetune(&args),
        #[cfg(feature = "learn")]
        Command::Eval(args) => learn::eval(&args),
    };
    let (output, status) = match result {
        Ok(output) => (output, ExitCode::SUCCESS),
        Err(e) => {
            let kind = Kind::of(&e);
            eprintln!("error: {e:#}");
            // A command that found nothing may still have its usual output; else, under
            // `--json`, the error as an object.
            let output = match (failure::output(&e), json) {
                (Some(output), _) => output.to_string(),
                (None, true) => format!("{}\n", failure::to_json(kind, &format!("{e:#}"))),
                (None, false) => String::new(),
            };
            (output, ExitCode::from(kind.status()))
        }
    };
    // A reader that stops early (`| head`) is not an error.
    let mut stdout = std::io::stdout().lock();
    match stdout
        .write_all(output.as_bytes())
        .and_then(|()| stdout.flush())
    {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            eprintln!("error: writing the output: {e}");
            ExitCode::from(Kind::BadInput.status())
        }
        _ => status,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    /// clap's own checks of every command's flags (names, groups, conflicts), which otherwise
    /// run only when a debug build parses that command.
    #[test]
    fn every_command_is_well_formed() {
        Cli::command().debug_assert();
    }
}
