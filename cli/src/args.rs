//! The command line's arguments (clap): the commands, their flags and value parsers.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};

use regolith::scene::Preset;

use crate::flags::{RecordArgs, VtkArgs};

#[derive(Parser)]
#[command(
    name = "regolith",
    version,
    about = "MPM simulation of projectile impact in dry granular media"
)]
pub(crate) struct Cli {
    #[command(subcommand)]
    pub(crate) command: Command,
}

#[derive(Subcommand)]
pub(crate) enum Command {
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
        #[command(flatten)]
        batch: BatchArgs,
    },
    /// Run an accuracy study: each knob moved alone from a baseline, errors against a named
    /// reference run (resumable), writing study.csv, study.md and pareto.png.
    ///
    /// --plan DIR and --collect DIR work as for `sweep`.
    Study {
        /// The RON study file (not with --collect).
        #[arg(required_unless_present = "collect")]
        study: Option<PathBuf>,
        #[command(flatten)]
        batch: BatchArgs,
    },
    /// Fit the Poncelet drag law m z'' = m g - f(z) - h(z) z'^2 across runs of one shape at
    /// three or more speeds (the paper's section 4.2), writing
    /// depth,f,h,runs,residual,f_error,h_error,condition as CSV. Runs whose scenes differ
    /// in more than the intruder's speed (two shapes of one sweep) are fitted as separate
    /// groups, one table each.
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
        /// t_k; it averages out oscillations shorter than the window.
        #[arg(long, value_name = "SECONDS", conflicts_with_all = ["cells", "spline"])]
        window: Option<f64>,
        /// Take z' and z'' from a least-squares parabola over the samples within N/2 cells
        /// of depth of each z_k [default: 3]: the grid's pulses, one per cell crossed, are
        /// averaged over N of them at every speed.
        #[arg(long, value_name = "N", conflicts_with = "spline")]
        cells: Option<f64>,
        /// Take z' and z'' from the interpolating spline, as the paper does (grid-crossing
        /// pulses then become noise in z'').
        #[arg(long)]
        spline: bool,
    },
    /// Fit Beverloo's law W = C rho_b sqrt(g) (D - k d)^beta to silo runs (each run's
    /// opening from its scene's Open floor segments, its rate from its Discharge output),
    /// one fit per grid, with beta = 3/2 and free; writes beverloo.md and beverloo.png.
    Beverloo {
        /// Run directories, or sweep output directories (all their runs); runs on several
        /// grids are fitted grid by grid.
        #[arg(required = true)]
        runs: Vec<PathBuf>,
        /// The grain diameter d (m), e.g. 0.005 for the PS-1 discs.
        #[arg(long, value_name = "METRES")]
        grain_diameter: f64,
        /// Where beverloo.md and beverloo.png go (default: the first directory given).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Run the coarse versions of the paper's experiments (reusing finished runs) and draw
    /// the paper's figures from them as PNG.
    Figures {
        /// Where the figures go [default: docs/figures; with --from DIR, DIR/figures, so a
        /// sweep's figures never overwrite the repository's].
        #[arg(long)]
        out: Option<PathBuf>,
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
        /// No progress bar.
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
/// How a sweep or a study runs here, or is planned or collected instead.
#[derive(Args)]
pub(crate) struct BatchArgs {
    /// Output directory (default: out/<name in the file>/).
    #[arg(long, conflicts_with_all = ["plan", "collect"])]
    pub(crate) out: Option<PathBuf>,
    /// Runs at once (default: the file's `jobs`, else the number of cores).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..), conflicts_with_all = ["plan", "collect"])]
    pub(crate) jobs: Option<u64>,
    #[command(flatten)]
    pub(crate) plan: PlanArgs,
}

#[derive(Args)]
pub(crate) struct PlanArgs {
    /// Write the runs into DIR as a plan (runs/, jobs.txt, slurm.sbatch) instead of
    /// running them.
    #[arg(long, value_name = "DIR", conflicts_with = "collect")]
    pub(crate) plan: Option<PathBuf>,
    /// Merge the finished runs of the plan in DIR into its table (DIR/sweep.csv, or a
    /// study's DIR/study.csv and study.md); fails while runs are missing or failed unless
    /// --partial.
    #[arg(long, value_name = "DIR")]
    pub(crate) collect: Option<PathBuf>,
    /// With --collect: succeed with whatever has finished.
    #[arg(long, requires = "collect")]
    pub(crate) partial: bool,
    #[command(flatten)]
    pub(crate) slurm: SlurmArgs,
}

/// The resources of a plan's `slurm.sbatch` (with `--plan`).
#[derive(Args)]
pub(crate) struct SlurmArgs {
    /// Time limit per array task, HH:MM:SS (default: the slowest run's estimate, tripled).
    #[arg(long, value_name = "HH:MM:SS", requires = "plan", value_parser = parse_slurm_time)]
    pub(crate) slurm_time: Option<String>,
    /// Partition to submit to.
    #[arg(long, value_name = "NAME", requires = "plan")]
    pub(crate) slurm_partition: Option<String>,
    /// CPUs (threads) per run (default 1).
    #[arg(long, value_name = "N", requires = "plan", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) slurm_cpus: u32,
    /// At most N array tasks at once (default: as many as Slurm allows).
    #[arg(long, value_name = "N", requires = "plan", value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) slurm_max_running: Option<u32>,
}

pub(crate) fn parse_slurm_time(t: &str) -> Result<String, String> {
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
pub(crate) struct SceneArgs {
    /// Override a scene value, e.g. --set time.end=0.1 --set 'bodies.intruder.velocity=(0,-3)'.
    #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
    pub(crate) sets: Vec<String>,
    /// Numerical preset: fast, accurate, fine or paper (docs/ACCURACY.md); --set wins over it.
    #[arg(long, value_parser = parse_preset)]
    pub(crate) preset: Option<Preset>,
    /// Run a fixed time step above the CFL limit anyway (sets time.allow_unstable).
    #[arg(long)]
    pub(crate) allow_unstable: bool,
}

impl SceneArgs {
    /// The flags as scene overrides.
    pub(crate) fn overrides(self) -> Vec<String> {
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

pub(crate) fn parse_preset(name: &str) -> Result<Preset, String> {
    Preset::parse(name)
        .ok_or_else(|| format!("unknown preset `{name}` (fast, accurate, fine or paper)"))
}

/// `START:STOP:COUNT` as COUNT evenly spaced depths.
pub(crate) fn parse_depths(spec: &str) -> Result<Vec<f64>, String> {
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
