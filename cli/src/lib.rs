//! The command line: `regolith run` a scene, `check` it without running, `resume` a run
//! from its checkpoint, `sweep` a parameter cross product or `study` the numerical knobs
//! (here, or planned for GNU parallel and Slurm and collected), `fit` the drag law, fit
//! Beverloo's law to silo runs (`beverloo`), or draw the paper's `figures`.
//!
//! Every error ends the program with a non-zero status and one line on stderr that says what
//! and where; nothing a user types or writes in a scene may cause a panic. A plugin crate
//! gets the same command line with its own items by calling [`main_with`] from its binary.

mod args;
mod commands;
mod flags;
mod progress;

use std::process::ExitCode;

use clap::Parser;

use regolith::Regolith;
use regolith::error::Error;
use regolith::run::CheckpointEvery;
use regolith_lab::study::Study;
use regolith_lab::sweep::Sweep;

use args::{Cli, Command};
use commands::{RunFlags, batch_command, beverloo, check, fit, resume, run};

/// Parses the process arguments and runs the command with the plugins of `app`.
pub fn main_with(app: Regolith) -> ExitCode {
    let cli = Cli::parse();
    // A first SIGINT / SIGTERM lets every run finish its step and save itself; a second
    // one stops at once. Without a handler (it could not be installed) a signal kills.
    let handler = ctrlc::set_handler(|| {
        if regolith::run::request_stop() {
            eprintln!("\nstopping now, without saving");
            std::process::exit(130);
        }
        eprintln!(
            "\ninterrupted: finishing the step, then saving checkpoint.bin and summary.json (interrupt again to stop at once)"
        );
    });
    if let Err(e) = handler {
        eprintln!("warning: no signal handler ({e}): an interrupted run will not save itself");
    }
    let registries = app.registries();
    let result = match cli.command {
        Command::Run {
            scene,
            out,
            settings,
            quiet,
            checkpoint_every,
            claim,
            record,
            vtk,
        } => run(
            &registries,
            &scene,
            out,
            &settings.overrides(),
            RunFlags {
                quiet,
                checkpoints: CheckpointEvery(checkpoint_every),
                claim,
            },
            &record,
            &vtk,
        ),
        Command::Resume {
            dir,
            quiet,
            checkpoint_every,
            record,
        } => resume(
            &registries,
            &dir,
            quiet,
            CheckpointEvery(checkpoint_every),
            &record,
        ),
        Command::Sweep { sweep, batch } => batch_command::<Sweep>(&registries, sweep, batch),
        Command::Study { study, batch } => batch_command::<Study>(&registries, study, batch),
        Command::Fit {
            runs,
            body,
            depths,
            out,
            window,
            cells,
            spline,
        } => fit(
            &runs,
            &body,
            depths.as_deref(),
            out,
            (window, cells, spline),
        ),
        Command::Beverloo {
            runs,
            grain_diameter,
            out,
        } => beverloo(&registries, &runs, grain_diameter, out),
        Command::Figures {
            out,
            runs,
            scenes,
            jobs,
            from,
        } => match from {
            Some(dir) => {
                let out = out.unwrap_or_else(|| dir.join("figures"));
                regolith_lab::figures::depth_energy_from(&dir, &out)
            }
            None => regolith_lab::figures::make_figures(
                &registries,
                &scenes,
                &runs,
                &out.unwrap_or_else(|| std::path::PathBuf::from("docs/figures")),
                jobs.map(|j| j as usize),
                &|line: &str| println!("{line}"),
            ),
        }
        .map(|files| {
            for f in files {
                println!("{}", f.display());
            }
        }),
        Command::Check { scene, settings } => check(&registries, &scene, &settings.overrides()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e @ Error::Interrupted { .. }) => {
            eprintln!("{e}");
            ExitCode::from(130)
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
