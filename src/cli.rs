//! The command line: `regolith run` a scene, `check` it without running, `resume` a run
//! from its checkpoint, or `sweep` a parameter cross product.
//!
//! Every error ends the program with a non-zero status and one line on stderr that says what
//! and where; nothing a user types or writes in a scene may cause a panic. A plugin crate
//! gets the same command line with its own items by calling [`main_with`] from its binary.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::rc::Rc;
use std::time::Duration;

use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};

use crate::Regolith;
use crate::error::Error;
use crate::output::summary::Summary;
use crate::registry::Registries;
use crate::run::{CheckpointEvery, Provenance, memory_estimate, resume_run, run_scene};
use crate::scene::{InitialStress, Scene, TimeStep};
use crate::sim::{Clock, Simulation};
use crate::sweep::{Sweep, run_sweep};

#[derive(Parser)]
#[command(
    name = "regolith",
    version,
    about = "MPM simulation of projectile impact in dry granular media"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene and write summary.json and trajectory.csv.
    Run {
        /// The RON scene file.
        scene: PathBuf,
        /// Output directory (default: out/<scene name>/).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Override a scene value, e.g. --set time.end=0.1 --set bodies.ball.velocity=(0,-3).
        #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
        sets: Vec<String>,
        /// No progress bar.
        #[arg(long, short)]
        quiet: bool,
        /// Write checkpoint.bin every N steps (for `regolith resume`).
        #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
        checkpoint_every: Option<u64>,
        /// Run a fixed time step above the CFL limit anyway (sets time.allow_unstable).
        #[arg(long)]
        allow_unstable: bool,
    },
    /// Run the cross product of a sweep file's parameter values (resumable), writing sweep.csv.
    Sweep {
        /// The RON sweep file.
        sweep: PathBuf,
        /// Output directory (default: out/<sweep name>/).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Runs at once (default: the sweep's `jobs`, else the number of cores).
        #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
        jobs: Option<u64>,
    },
    /// Continue a run from the checkpoint.bin in its output directory.
    Resume {
        /// The run's output directory.
        dir: PathBuf,
        #[arg(long, short)]
        quiet: bool,
        /// Keep writing checkpoint.bin every N steps.
        #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
        checkpoint_every: Option<u64>,
    },
    /// Validate a scene and print the resolved setup without running it.
    Check {
        scene: PathBuf,
        #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
        sets: Vec<String>,
        /// Accept a fixed time step above the CFL limit (sets time.allow_unstable).
        #[arg(long)]
        allow_unstable: bool,
    },
}

/// `--allow-unstable` as the override it stands for.
fn with_flags(sets: Vec<String>, allow_unstable: bool) -> Vec<String> {
    let mut sets = sets;
    if allow_unstable {
        sets.push("time.allow_unstable=true".to_string());
    }
    sets
}

/// Parses the process arguments and runs the command with the plugins of `app`.
pub fn main_with(app: Regolith) -> ExitCode {
    let cli = Cli::parse();
    let registries = app.registries();
    let result = match cli.command {
        Command::Run {
            scene,
            out,
            sets,
            quiet,
            checkpoint_every,
            allow_unstable,
        } => run(
            &registries,
            &scene,
            out,
            &with_flags(sets, allow_unstable),
            quiet,
            CheckpointEvery(checkpoint_every),
        ),
        Command::Resume {
            dir,
            quiet,
            checkpoint_every,
        } => resume(&registries, &dir, quiet, CheckpointEvery(checkpoint_every)),
        Command::Sweep { sweep, out, jobs } => {
            run_sweep_command(&registries, &sweep, out, jobs.map(|j| j as usize))
        }
        Command::Check {
            scene,
            sets,
            allow_unstable,
        } => check(&registries, &scene, &with_flags(sets, allow_unstable)),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// A progress bar on stderr (hidden with `--quiet`), redrawn every 50 steps.
fn progress_bar(quiet: bool) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(1000);
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:30} {percent:>3}% ETA {eta} {msg}",
        )
        .expect("a fixed template is valid"),
    );
    bar.enable_steady_tick(Duration::from_millis(250));
    bar
}

fn draw(bar: &ProgressBar, last_draw: &mut u64, c: &Clock) {
    if c.step - *last_draw >= 50 || c.time >= c.end {
        *last_draw = c.step;
        bar.set_position((1000.0 * c.time / c.end) as u64);
        bar.set_message(format!(
            "step {} t = {:.4e} s dt = {:.2e} s",
            c.step, c.time, c.dt
        ));
    }
}

fn report(summary: &Summary, out: &Path) {
    println!(
        "{}: {} steps to t = {} s, {} points, {:.1} s wall, {:.3e} particle-steps/s, max CFL {:.3}; outputs in {}",
        summary.scene,
        summary.steps,
        summary.time,
        summary.particles,
        summary.wall_s,
        summary.particle_steps_per_s,
        summary.cfl,
        out.display()
    );
}

fn run(
    registries: &Rc<Registries>,
    path: &Path,
    out: Option<PathBuf>,
    sets: &[String],
    quiet: bool,
    checkpoints: CheckpointEvery,
) -> Result<(), Error> {
    let (scene, text) = Scene::load(path, sets, registries)?;
    for w in scene.warnings() {
        eprintln!("warning: {w}");
    }
    let out = out.unwrap_or_else(|| PathBuf::from("out").join(&scene.name));
    let bar = progress_bar(quiet);
    let mut last_draw = 0u64;
    let mut progress = |c: &Clock| draw(&bar, &mut last_draw, c);
    let from = Provenance {
        file: &path.display().to_string(),
        text: &text,
        overrides: sets,
    };
    let result = run_scene(&scene, &from, &out, checkpoints, &mut progress);
    bar.finish_and_clear();
    report(&result?, &out);
    Ok(())
}

fn run_sweep_command(
    registries: &Rc<Registries>,
    path: &Path,
    out: Option<PathBuf>,
    jobs: Option<usize>,
) -> Result<(), Error> {
    let sweep = Sweep::load(path)?;
    let out = out.unwrap_or_else(|| PathBuf::from("out").join(&sweep.name));
    let shared: Registries = (**registries).clone();
    let runs = sweep.plan().len();
    println!("{}: {runs} runs into {}", sweep.name, out.display());
    let failed = run_sweep(
        path,
        &sweep,
        &out,
        jobs,
        || Rc::new(shared.clone()),
        |line: &str| println!("{line}"),
    )?;
    println!(
        "{}: done, {failed} failed; table in {}",
        sweep.name,
        out.join("sweep.csv").display()
    );
    if failed > 0 {
        return Err(Error::Scene(crate::error::SceneError::file(
            &path.display().to_string(),
            format!("{failed} of {runs} runs failed (see sweep.csv)"),
        )));
    }
    Ok(())
}

fn resume(
    registries: &Rc<Registries>,
    dir: &Path,
    quiet: bool,
    checkpoints: CheckpointEvery,
) -> Result<(), Error> {
    let bar = progress_bar(quiet);
    let mut last_draw = 0u64;
    let mut progress = |c: &Clock| draw(&bar, &mut last_draw, c);
    let result = resume_run(registries, dir, checkpoints, &mut progress);
    bar.finish_and_clear();
    report(&result?, dir);
    Ok(())
}

fn check(registries: &Rc<Registries>, path: &Path, sets: &[String]) -> Result<(), Error> {
    let (scene, _) = Scene::load(path, sets, registries)?;
    for w in scene.warnings() {
        println!("warning: {w}");
    }
    let mut sim = Simulation::new(&scene);
    let g = sim.grid().clone();
    println!("scene: {} ({})", scene.name, path.display());
    if !scene.description.is_empty() {
        println!("  {}", scene.description);
    }
    let w = scene.walls;
    println!(
        "domain: {} x {} m from ({}, {}), {} x {} cells of {} m, {} nodes per body field",
        scene.domain.size.x,
        scene.domain.size.y,
        g.origin.x,
        g.origin.y,
        g.cells[0],
        g.cells[1],
        g.cell_size,
        g.node_count()
    );
    println!(
        "walls: left {:?}, right {:?}, bottom {:?}, top {:?}; gravity ({}, {}) m/s^2",
        w.left, w.right, w.bottom, w.top, scene.gravity.x, scene.gravity.y
    );
    let contact = if scene.bodies.len() > 1 {
        format!("{:?}", scene.contact)
    } else {
        "none (one body)".to_string()
    };
    println!(
        "integration: {:?}, FLIP fraction {}, contact: {contact}",
        scene.integration, scene.flip
    );
    let (dt, cfl) = sim.next_time_step();
    let rule = match scene.time.step {
        TimeStep::Fixed(dt) => format!("fixed dt = {dt:e} s"),
        TimeStep::Cfl(c) => format!("CFL {c}"),
    };
    println!(
        "time: end {} s, {rule}: first dt = {dt:.3e} s at CFL {cfl:.3}, about {:.0} steps; output every {} s",
        scene.time.end,
        (scene.time.end / dt).ceil(),
        scene.time.output_every
    );
    println!("bodies:");
    for ((body, state, n), spec) in sim.bodies().into_iter().zip(&scene.bodies) {
        println!(
            "  {}: {} {}, {} points ({}x{} per cell), mass {:.4} kg/m, p-wave speed {:.1} m/s, initial stress {}{}",
            body.name,
            spec.shape.name(),
            body.material,
            n,
            spec.points_per_cell,
            spec.points_per_cell,
            state.mass,
            body.wave_speed,
            match spec.initial_stress {
                InitialStress::None => "none",
                InitialStress::Lithostatic => "lithostatic",
            },
            if body.tracked { ", tracked" } else { "" }
        );
    }
    let bytes = memory_estimate(&mut sim, &scene);
    println!(
        "particles: {}; state memory about {:.1} MiB",
        sim.particle_count(),
        bytes as f64 / (1024.0 * 1024.0)
    );
    Ok(())
}
