//! The command line: `regolith run` a scene, `check` it without running, `resume` a run
//! from its checkpoint, `sweep` a parameter cross product or `study` the numerical knobs
//! (here, or planned for GNU parallel and Slurm and collected), `fit` the drag law, or draw
//! the paper's `figures`.
//!
//! Every error ends the program with a non-zero status and one line on stderr that says what
//! and where; nothing a user types or writes in a scene may cause a panic. A plugin crate
//! gets the same command line with its own items by calling [`main_with`] from its binary.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Duration;

use clap::{Args, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};

use regolith::Regolith;
use regolith::error::{Error, SceneError};
use regolith::output::summary::Summary;
use regolith::registry::Registries;
use regolith::run::{CheckpointEvery, Provenance, memory_estimate, resume_run, run_scene};
use regolith::scene::{InitialStress, Preset, Scene, TimeStep};
use regolith::sim::{Clock, Simulation};
use regolith_lab::plan::{BatchFile, Layout, SlurmOptions, write_plan};
use regolith_lab::study::Study;
use regolith_lab::sweep::Sweep;
use regolith_lab::workers::run_local;

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
        #[command(flatten)]
        settings: SceneArgs,
        /// No progress bar.
        #[arg(long, short)]
        quiet: bool,
        /// Write checkpoint.bin every N steps (for `regolith resume`).
        #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
        checkpoint_every: Option<u64>,
        /// Claim the output directory first: skip the run if it completed or another live
        /// worker holds it (the lines of a plan's jobs.txt; see `sweep --plan`).
        #[arg(long)]
        claim: bool,
        #[command(flatten)]
        record: RecordArgs,
        #[command(flatten)]
        vtk: VtkArgs,
    },
    /// Run the cross product of a sweep file's parameter values (resumable), writing sweep.csv.
    ///
    /// With --plan DIR it runs nothing and writes the runs for GNU parallel or a Slurm array
    /// instead (DIR/jobs.txt, DIR/slurm.sbatch); --collect DIR merges a plan's finished runs
    /// into DIR/sweep.csv.
    Sweep {
        /// The RON sweep file (not with --collect).
        #[arg(required_unless_present = "collect")]
        sweep: Option<PathBuf>,
        /// Output directory (default: out/<sweep name>/).
        #[arg(long, conflicts_with_all = ["plan", "collect"])]
        out: Option<PathBuf>,
        /// Runs at once (default: the sweep's `jobs`, else the number of cores).
        #[arg(long, value_parser = clap::value_parser!(u64).range(1..), conflicts_with_all = ["plan", "collect"])]
        jobs: Option<u64>,
        #[command(flatten)]
        plan: PlanArgs,
    },
    /// Run an accuracy study: each knob moved alone from a baseline, errors against a named
    /// reference run (resumable), writing study.csv, study.md and pareto.png.
    ///
    /// --plan DIR and --collect DIR work as for `sweep`.
    Study {
        /// The RON study file (not with --collect).
        #[arg(required_unless_present = "collect")]
        study: Option<PathBuf>,
        /// Output directory (default: out/<study name>/).
        #[arg(long, conflicts_with_all = ["plan", "collect"])]
        out: Option<PathBuf>,
        /// Runs at once (default: the study's `jobs`, else the number of cores).
        #[arg(long, value_parser = clap::value_parser!(u64).range(1..), conflicts_with_all = ["plan", "collect"])]
        jobs: Option<u64>,
        #[command(flatten)]
        plan: PlanArgs,
    },
    /// Fit the Poncelet drag law m z'' = m g - f(z) - h(z) z'^2 across runs of one shape at
    /// three or more speeds (the paper's section 4.2), writing
    /// depth,f,h,runs,residual,f_error,h_error,condition as CSV.
    Fit {
        /// Run directories, or sweep output directories (all their runs).
        #[arg(required = true)]
        runs: Vec<PathBuf>,
        /// The intruder (a tracked body).
        #[arg(long, default_value = "intruder")]
        body: String,
        /// Depths to fit at, START:STOP:COUNT in metres (default: 20 depths from 5% to 90%
        /// of the shallowest depth the runs reach while descending).
        #[arg(long, value_name = "START:STOP:COUNT")]
        depths: Option<String>,
        /// Output CSV (default: poncelet.csv in the sweep directory when the first argument
        /// is one, else beside the first run directory).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Take z' and z'' from a least-squares parabola over this window (s) around each
        /// t_k instead of the interpolating spline (the paper's way); it averages out
        /// oscillations shorter than the window, such as grid-crossing pulses.
        #[arg(long, value_name = "SECONDS")]
        window: Option<f64>,
    },
    /// Run the coarse versions of the paper's experiments (reusing finished runs) and draw
    /// the paper's figures from them as PNG.
    Figures {
        /// Where the figures go.
        #[arg(long, default_value = "docs/figures")]
        out: PathBuf,
        /// Where the runs go (kept, and reused by the next call).
        #[arg(long, default_value = "out/figures")]
        runs: PathBuf,
        /// The directory holding the shipped scenes.
        #[arg(long, default_value = "scenes")]
        scenes: PathBuf,
        /// Runs at once in the sweeps (default: the number of cores).
        #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
        jobs: Option<u64>,
        /// Draw only the paper's Fig. 3 (depth_energy.png, stopping_time_energy.png), from
        /// the table of a sweep already run or collected in DIR (its sweep.csv), with one
        /// curve per tip slope; runs nothing.
        #[arg(long, value_name = "DIR", conflicts_with_all = ["runs", "scenes", "jobs"])]
        from: Option<PathBuf>,
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
        #[command(flatten)]
        record: RecordArgs,
    },
    /// Validate a scene and print the resolved setup without running it.
    Check {
        scene: PathBuf,
        #[command(flatten)]
        settings: SceneArgs,
    },
}

/// Planning and collecting instead of running (`sweep` and `study`).
#[derive(Args)]
struct PlanArgs {
    /// Write the runs into DIR as a plan (runs/, jobs.txt, slurm.sbatch) instead of
    /// running them.
    #[arg(long, value_name = "DIR", conflicts_with = "collect")]
    plan: Option<PathBuf>,
    /// Merge the finished runs of the plan in DIR into its table (DIR/sweep.csv, or a
    /// study's DIR/study.csv and study.md); fails while runs are missing or failed unless
    /// --partial.
    #[arg(long, value_name = "DIR")]
    collect: Option<PathBuf>,
    /// With --collect: succeed with whatever has finished.
    #[arg(long, requires = "collect")]
    partial: bool,
    #[command(flatten)]
    slurm: SlurmArgs,
}

/// The resources of a plan's `slurm.sbatch` (with `--plan`).
#[derive(Args)]
struct SlurmArgs {
    /// Time limit per array task, HH:MM:SS (default: the slowest run's estimate, tripled).
    #[arg(long, value_name = "HH:MM:SS", requires = "plan", value_parser = parse_slurm_time)]
    slurm_time: Option<String>,
    /// Partition to submit to.
    #[arg(long, value_name = "NAME", requires = "plan")]
    slurm_partition: Option<String>,
    /// CPUs (threads) per run (default 1).
    #[arg(long, value_name = "N", requires = "plan", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    slurm_cpus: u32,
    /// At most N array tasks at once (default: as many as Slurm allows).
    #[arg(long, value_name = "N", requires = "plan", value_parser = clap::value_parser!(u32).range(1..))]
    slurm_max_running: Option<u32>,
}

fn parse_slurm_time(t: &str) -> Result<String, String> {
    let parts: Vec<&str> = t.split(':').collect();
    let ok = (1..=3).contains(&parts.len())
        && parts
            .iter()
            .all(|p| !p.is_empty() && p.bytes().all(|b| b.is_ascii_digit()));
    if ok {
        Ok(t.to_string())
    } else {
        Err(format!(
            "expected HH:MM:SS (or MM:SS, or minutes), got `{t}`"
        ))
    }
}

/// How the command line changes a scene (run and check).
#[derive(Args)]
struct SceneArgs {
    /// Override a scene value, e.g. --set time.end=0.1 --set bodies.ball.velocity=(0,-3).
    #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
    sets: Vec<String>,
    /// Numerical preset: fast, accurate, fine or paper (docs/ACCURACY.md); --set wins over it.
    #[arg(long, value_parser = parse_preset)]
    preset: Option<Preset>,
    /// Run a fixed time step above the CFL limit anyway (sets time.allow_unstable).
    #[arg(long)]
    allow_unstable: bool,
}

impl SceneArgs {
    /// The flags as scene overrides.
    fn overrides(self) -> Vec<String> {
        let mut sets = self.sets;
        if self.allow_unstable {
            sets.push("time.allow_unstable=true".to_string());
        }
        if let Some(p) = self.preset {
            sets.push(format!("preset={p:?}"));
        }
        sets
    }
}

fn parse_preset(name: &str) -> Result<Preset, String> {
    Preset::parse(name)
        .ok_or_else(|| format!("unknown preset `{name}` (fast, accurate, fine or paper)"))
}

/// The name of the output the recording flags add (registered by the Rerun plugin crate).
pub const RECORDER: &str = "Rerun";

/// Recording for the Rerun viewer. The flags become a `Rerun(..)` scene output, so a
/// recording asked for on the command line and one listed in a scene are the same thing.
#[derive(clap::Args, Debug, Default)]
struct RecordArgs {
    /// Record the run for the Rerun viewer into FILE (.rrd).
    #[arg(long, value_name = "FILE")]
    rrd: Option<PathBuf>,
    /// Stream the recording to a Rerun viewer started from PATH (`rerun`).
    #[arg(long)]
    spawn: bool,
    /// Record every N steps (default: at the scene's output interval, time.output_every).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    record_every: Option<u64>,
    /// Colour the points by: pressure (default), plastic-strain-rate, inertial-number, phase,
    /// speed or body.
    #[arg(long, value_name = "FIELD")]
    color: Option<String>,
    /// Also record the grid: nodal velocities and masses.
    #[arg(long)]
    record_grid: bool,
}

impl RecordArgs {
    /// The `Rerun(..)` output these flags stand for, as scene text; `None` without `--rrd`
    /// or `--spawn`.
    fn output_text(&self) -> Result<Option<String>, String> {
        if self.rrd.is_none() && !self.spawn {
            if self.record_every.is_some() || self.color.is_some() || self.record_grid {
                return Err(
                    "--record-every, --color and --record-grid need --rrd FILE or --spawn".into(),
                );
            }
            return Ok(None);
        }
        let mut fields = Vec::new();
        if let Some(file) = &self.rrd {
            let file =
                std::path::absolute(file).map_err(|e| format!("--rrd {}: {e}", file.display()))?;
            fields.push(format!("file: {:?}", file.display().to_string()));
        }
        fields.push(format!("spawn: {}", self.spawn));
        if let Some(n) = self.record_every {
            fields.push(format!("every: {n}"));
        }
        if let Some(c) = &self.color {
            fields.push(format!("color: {}", camel_case(c)));
        }
        fields.push(format!("grid: {}", self.record_grid));
        Ok(Some(format!("{RECORDER}({})", fields.join(", "))))
    }

    /// Adds the recording to `scene`, or says why it cannot be made.
    fn apply(&self, scene: &mut Scene, registries: &Arc<Registries>) -> Result<(), Error> {
        let flags = |message: String| Error::Scene(SceneError::file("command line", message));
        let Some(text) = self.output_text().map_err(flags)? else {
            return Ok(());
        };
        if !registries
            .names::<dyn regolith::output::Output>()
            .contains(&RECORDER)
        {
            return Err(flags(
                "this program was built without the Rerun recorder; use the `regolith` \
                 command of the workspace (cli/), which includes it, or add \
                 `regolith_rerun::RerunPlugin` to yours"
                    .to_string(),
            ));
        }
        if scene.add_output(&text, "command line", registries)? {
            eprintln!(
                "note: the command line's recording replaces the scene's own {RECORDER}(..) output (one recording per run); only the command line's is written"
            );
        }
        Ok(())
    }
}

/// VTK files for ParaView. The flags become a `Vtk(..)` scene output, as the recording
/// flags become a `Rerun(..)` one.
#[derive(clap::Args, Debug, Default)]
struct VtkArgs {
    /// Write VTK files for ParaView every SECONDS of simulated time (open <out>/vtk/points.pvd).
    #[arg(long, value_name = "SECONDS")]
    vtk: Option<f64>,
    /// Also write each body's grid field (<out>/vtk/grid.pvd).
    #[arg(long, requires = "vtk")]
    vtk_grid: bool,
}

impl VtkArgs {
    /// Adds the `Vtk(..)` output to `scene`, replacing the scene's own.
    fn apply(&self, scene: &mut Scene, registries: &Arc<Registries>) -> Result<(), Error> {
        let Some(every) = self.vtk else {
            return Ok(());
        };
        let text = format!("Vtk(every: {every:?}, grid: {})", self.vtk_grid);
        if scene.add_output(&text, "command line --vtk", registries)? {
            eprintln!(
                "note: --vtk replaces the scene's own Vtk(..) output (one VTK series per run)"
            );
        }
        Ok(())
    }
}

/// `plastic-strain-rate` or `plastic_strain_rate` as the RON variant `PlasticStrainRate`.
fn camel_case(name: &str) -> String {
    name.split(['-', '_'])
        .map(|w| {
            let mut c = w.chars();
            c.next()
                .map(|f| f.to_uppercase().chain(c).collect::<String>())
                .unwrap_or_default()
        })
        .collect()
}

/// `--allow-unstable` as the override it stands for.
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
        Command::Sweep {
            sweep,
            out,
            jobs,
            plan,
        } => batch_command::<Sweep>(&registries, sweep, out, jobs, plan),
        Command::Study {
            study,
            out,
            jobs,
            plan,
        } => batch_command::<Study>(&registries, study, out, jobs, plan),
        Command::Fit {
            runs,
            body,
            depths,
            out,
            window,
        } => fit(&runs, &body, depths.as_deref(), out, window),
        Command::Figures {
            out,
            runs,
            scenes,
            jobs,
            from,
        } => match from {
            Some(dir) => regolith_lab::figures::depth_energy_from(&dir, &out),
            None => regolith_lab::figures::make_figures(
                &registries,
                &scenes,
                &runs,
                &out,
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
    println!(
        "  wall time per step set: {}",
        set_shares(&summary.timings_s)
    );
    if let Some(line) = impact_line(summary) {
        println!("  {line}");
    }
}

/// The impact result in one line, or why there is none (when the scene asked for one).
fn impact_line(summary: &Summary) -> Option<String> {
    if let Some(why) = &summary.impact_not_measured {
        return Some(format!("impact: not measured: {why}"));
    }
    let m = summary.impact.as_ref()?;
    let contact = format!(
        "first contact at {:.4} s, {:.3} m/s, {:.2} J/m",
        m.contact_time, m.contact_speed, m.impact_energy
    );
    Some(match (m.final_depth, m.stopping_time) {
        (Some(depth), Some(stop)) => format!(
            "impact: at rest; final depth {depth:.4} m, stopping time {stop:.4} s ({contact})"
        ),
        _ => format!(
            "impact: NOT at rest, no final depth or stopping time: {} (depth so far {:.4} m; {contact})",
            m.not_at_rest.as_deref().unwrap_or_default(),
            m.depth_at_end
        ),
    })
}

/// `name seconds (share)` for each step set, the largest first.
fn set_shares(timings: &std::collections::BTreeMap<String, f64>) -> String {
    let total: f64 = timings.values().sum();
    let mut sets: Vec<(&String, &f64)> = timings.iter().collect();
    sets.sort_by(|a, b| b.1.total_cmp(a.1));
    sets.iter()
        .map(|&(name, &s)| {
            let share = if total > 0.0 { 100.0 * s / total } else { 0.0 };
            format!("{name} {s:.3} s ({share:.0}%)")
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The flags of `regolith run` that do not change the scene.
struct RunFlags {
    quiet: bool,
    checkpoints: CheckpointEvery,
    /// Claim the output directory first (`regolith_lab::claim`).
    claim: bool,
}

fn run(
    registries: &Arc<Registries>,
    path: &Path,
    out: Option<PathBuf>,
    sets: &[String],
    flags: RunFlags,
    record: &RecordArgs,
    vtk: &VtkArgs,
) -> Result<(), Error> {
    let (mut scene, text) = Scene::load(path, sets, registries)?;
    record.apply(&mut scene, registries)?;
    vtk.apply(&mut scene, registries)?;
    for w in scene.warnings() {
        eprintln!("warning: {w}");
    }
    let out = out.unwrap_or_else(|| PathBuf::from("out").join(&scene.name));
    let mut claim = None;
    if flags.claim {
        use regolith_lab::claim::{Claimed, claim as take};
        // Done: completed from this very scene text (a changed scene is run again).
        let done = || {
            regolith_lab::sweep::read_summary(&out).is_some_and(|s| s["status"] == "completed")
                && std::fs::read_to_string(out.join("scene.ron")).is_ok_and(|t| t == text)
        };
        match take(&out, done)
            .map_err(|e| Error::io(format!("cannot claim {}", out.display()), e))?
        {
            Claimed::Mine(c) => claim = Some(c),
            Claimed::Completed => {
                println!("{}: already completed, skipped", out.display());
                return Ok(());
            }
            Claimed::Held { holder } => {
                println!("{}: claimed by {holder}, skipped", out.display());
                return Ok(());
            }
        }
    }
    let bar = progress_bar(flags.quiet);
    let mut last_draw = 0u64;
    let mut progress = |c: &Clock| {
        if let Some(claim) = claim.as_mut() {
            claim.heartbeat();
        }
        draw(&bar, &mut last_draw, c)
    };
    let from = Provenance {
        file: &path.display().to_string(),
        text: &text,
        overrides: sets,
    };
    let result = run_scene(&scene, &from, &out, flags.checkpoints, &mut progress);
    bar.finish_and_clear();
    report(&result?, &out);
    Ok(())
}

/// `regolith sweep` or `regolith study`: collect a plan, write one, or run the file here.
fn batch_command<B: BatchFile>(
    registries: &Arc<Registries>,
    file: Option<PathBuf>,
    out: Option<PathBuf>,
    jobs: Option<u64>,
    plan: PlanArgs,
) -> Result<(), Error> {
    let path = match (file, plan.collect) {
        (None, Some(dir)) => return collect_plan(&dir, plan.partial),
        (Some(_), Some(_)) => return Err(both_file_and_collect(B::KIND)),
        (Some(path), None) => path,
        (None, None) => unreachable!("clap requires the batch file without --collect"),
    };
    let batch = B::load(&path)?;
    if let Some(dir) = &plan.plan {
        return plan_batch(&path, &batch, dir, registries, plan.slurm);
    }
    let out = out.unwrap_or_else(|| PathBuf::from("out").join(batch.name()));
    let (name, runs) = (batch.name(), batch.runs().len());
    println!("{name}: {runs} runs into {}", out.display());
    let report = |line: &str| println!("{line}");
    let jobs = jobs.map(|j| j as usize);
    let failed = run_local(&path, &batch, &out, jobs, registries, report)?;
    println!(
        "{name}: done, {failed} failed; table in {}",
        out.join(B::TABLE).display()
    );
    if failed > 0 {
        return Err(Error::Scene(SceneError::file(
            &path.display().to_string(),
            format!("{failed} of {runs} runs failed (see {})", B::TABLE),
        )));
    }
    Ok(())
}

/// The error of a batch file given with `--collect`, which reads only the plan.
fn both_file_and_collect(kind: &str) -> Error {
    SceneError::file(
        "command line",
        format!("--collect DIR reads the plan in DIR; give it without the {kind} file"),
    )
    .into()
}

/// Writes the plan of `batch` (`sweep --plan` or `study --plan`) and says how to run it.
fn plan_batch(
    path: &Path,
    batch: &impl BatchFile,
    dir: &Path,
    registries: &Arc<Registries>,
    slurm: SlurmArgs,
) -> Result<(), Error> {
    let options = SlurmOptions {
        time: slurm.slurm_time,
        partition: slurm.slurm_partition,
        cpus: slurm.slurm_cpus,
        max_running: slurm.slurm_max_running,
    };
    let plan = write_plan(path, batch, dir, Layout::Plan, registries, &options)?;
    println!(
        "{}: {} runs planned in {}\n  run them: cd {} && parallel -j N < jobs.txt   (or: sbatch slurm.sbatch)\n  then: regolith {} --collect {}",
        batch.name(),
        plan.runs.len(),
        dir.display(),
        dir.display(),
        plan.kind,
        dir.display()
    );
    Ok(())
}

fn collect_plan(dir: &Path, partial: bool) -> Result<(), Error> {
    let found = regolith_lab::collect::collect(dir)?;
    println!(
        "{}: {} of {} runs completed; table in {}",
        dir.display(),
        found.completed,
        found.runs,
        dir.join(found.table).display()
    );
    if !found.missing.is_empty() {
        println!(
            "missing ({}): {}",
            found.missing.len(),
            found.missing.join(", ")
        );
    }
    for f in &found.failed {
        println!("failed: {f}");
    }
    let short = found.missing.len() + found.failed.len();
    if short > 0 && !partial {
        return Err(SceneError::file(
            &dir.display().to_string(),
            format!(
                "{short} of {} runs missing or failed (--partial accepts what has finished)",
                found.runs
            ),
        )
        .into());
    }
    Ok(())
}

fn resume(
    registries: &Arc<Registries>,
    dir: &Path,
    quiet: bool,
    checkpoints: CheckpointEvery,
    record: &RecordArgs,
) -> Result<(), Error> {
    let bar = progress_bar(quiet);
    let mut last_draw = 0u64;
    let mut progress = |c: &Clock| draw(&bar, &mut last_draw, c);
    let extend = |scene: &mut Scene| record.apply(scene, registries);
    let result = resume_run(registries, dir, checkpoints, extend, &mut progress);
    bar.finish_and_clear();
    report(&result?, dir);
    Ok(())
}

fn fit(
    dirs: &[PathBuf],
    body: &str,
    depths: Option<&str>,
    out: Option<PathBuf>,
    window: Option<f64>,
) -> Result<(), Error> {
    use regolith_lab::poncelet::{
        Derivatives, MIN_SPEEDS, default_depths, default_table, expand_dirs, fit, load_run,
        refuse_duplicates, to_csv,
    };
    let fail = |m: String| Error::Scene(SceneError::file("regolith fit", m));
    let how = match window {
        None => Derivatives::Spline,
        Some(w) if w.is_finite() && w > 0.0 => Derivatives::Window(w),
        Some(w) => return Err(fail(format!("--window must be a positive time, got {w}"))),
    };
    let table = out.unwrap_or_else(|| default_table(&dirs[0]));
    let dirs = expand_dirs(dirs).map_err(fail)?;
    let runs = dirs
        .iter()
        .map(|d| load_run(d, body))
        .collect::<Result<Vec<_>, _>>()
        .map_err(fail)?;
    refuse_duplicates(&dirs, &runs).map_err(fail)?;
    if runs.len() < MIN_SPEEDS {
        return Err(fail(format!(
            "the fit needs runs at {MIN_SPEEDS} or more speeds (two unknowns per depth; with two speeds the line fits exactly and nothing checks the law), got {} run(s)",
            runs.len()
        )));
    }
    let depths = match depths {
        Some(spec) => parse_depths(spec).map_err(|e| fail(format!("--depths {spec}: {e}")))?,
        None => default_depths(&runs),
    };
    let points = fit(&runs, &depths, how);
    if points.is_empty() {
        return Err(fail(format!(
            "none of the {} depths is reached while descending by runs at {MIN_SPEEDS} or more distinct speeds; nothing written",
            depths.len()
        )));
    }
    let out = table;
    regolith::output::write_atomic(&out, to_csv(&points).as_bytes())
        .map_err(|e| Error::io(format!("cannot write {}", out.display()), e))?;
    println!(
        "{} runs, {} of {} depths fitted; table in {}",
        runs.len(),
        points.len(),
        depths.len(),
        out.display()
    );
    Ok(())
}

/// `START:STOP:COUNT` as COUNT evenly spaced depths.
fn parse_depths(spec: &str) -> Result<Vec<f64>, String> {
    let parts: Vec<&str> = spec.split(':').collect();
    let [a, b, n] = parts[..] else {
        return Err("expected START:STOP:COUNT".into());
    };
    let num = |s: &str| {
        s.trim()
            .parse::<f64>()
            .map_err(|_| format!("`{s}` is not a number"))
    };
    let (a, b) = (num(a)?, num(b)?);
    let n: usize = n
        .trim()
        .parse()
        .map_err(|_| format!("`{n}` is not a count"))?;
    if !(a.is_finite() && b.is_finite() && a >= 0.0 && b > a && (1..=100_000).contains(&n)) {
        return Err("need 0 <= START < STOP and 1 <= COUNT <= 100000".into());
    }
    Ok((0..n)
        .map(|k| a + (b - a) * k as f64 / (n.max(2) - 1) as f64)
        .collect())
}

fn check(registries: &Arc<Registries>, path: &Path, sets: &[String]) -> Result<(), Error> {
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
    if let Some(p) = scene.preset {
        println!("preset: {p:?} (its settings are in the lines above; --set wins over it)");
    }
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
