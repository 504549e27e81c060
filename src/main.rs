//! The `streakfit` command line. Each subcommand's arguments and logic live in the library;
//! this file only dispatches and maps results to exit codes (0 ok, 1 failed work, 2 bad usage).

use clap::{Parser, Subcommand};
use std::process::ExitCode;
use streakfit::cli::CliResult;

#[derive(Parser)]
#[command(
    name = "streakfit",
    version,
    about = "Long-exposure billiard-collision photographs to physics"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Theory: post-collision and post-transition angles for given coefficients.
    Predict(streakfit::predict::PredictArgs),
    /// Measure impact, post-collision and post-transition angles in folders of photographs.
    Extract(streakfit::extract::ExtractArgs),
    /// Synthetic long-exposure shot photographs with exact ground truth.
    Synth(streakfit::synth::SynthArgs),
    /// Run a pipeline (synth/extract/fit/report with caching), e.g. pipelines/demo.toml.
    Run(streakfit::pipeline::RunArgs),
    /// Figures and an HTML/Markdown report from angle tables and a fit.
    Report(streakfit::report::cli::ReportArgs),
    /// Fit material coefficients (e, mu, mu', mu0) with uncertainties and model selection.
    Fit(streakfit::fit::FitArgs),
    /// Benchmarks: `bench speed-error` sweeps each stage's cost knobs against ground truth;
    /// `bench psi-bound` gives psi's Cramér–Rao bound for synthetic photos.
    Bench(streakfit::bench::BenchArgs),
}

fn main() -> ExitCode {
    streakfit::tune_allocator();
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let _ = e.print();
            return if e.use_stderr() {
                ExitCode::from(2)
            } else {
                ExitCode::SUCCESS
            };
        }
    };
    let result: CliResult = match &cli.command {
        Command::Predict(a) => streakfit::predict::run(a),
        Command::Extract(a) => streakfit::extract::run(a),
        Command::Synth(a) => streakfit::synth::run(a),
        Command::Run(a) => streakfit::pipeline::run(a),
        Command::Report(a) => streakfit::report::cli::run(a),
        Command::Fit(a) => streakfit::fit::run(a),
        Command::Bench(a) => streakfit::bench::run(a),
    };
    match result {
        Ok(outcome) => outcome.exit_code(),
        Err(err) => {
            eprintln!("error: {err:#}");
            err.exit_code()
        }
    }
}
