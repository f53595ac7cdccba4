//! The commands: run, resume, sweep and study (local, planned, collected), fit, check.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use regolith::error::{Error, SceneError};
use regolith::registry::Registries;
use regolith::resources::Clock;
use regolith::run::{CheckpointEvery, Provenance, memory_estimate, resume_run, run_scene};
use regolith::scene::{InitialStress, Scene, TimeStep};
use regolith::sim::Simulation;
use regolith_lab::batch::BatchFile;
use regolith_lab::plan::{Layout, SlurmOptions, write_plan};
use regolith_lab::workers::run_local;

use crate::args::{BatchArgs, SlurmArgs, parse_depths};
use crate::flags::{RecordArgs, VtkArgs};
use crate::progress::{draw, progress_bar, report};

/// The flags of `regolith run` that do not change the scene.
pub(crate) struct RunFlags {
    pub(crate) quiet: bool,
    pub(crate) checkpoints: CheckpointEvery,
    /// Claim the output directory first (`regolith_lab::claim`).
    pub(crate) claim: bool,
}

pub(crate) fn run(
    registries: &Arc<Registries>,
    path: &Path,
    out: Option<PathBuf>,
    sets: &[String],
    flags: RunFlags,
    record: &RecordArgs,
    vtk: &VtkArgs,
) -> Result<(), Error> {
    let (mut scene, text) = Scene::load(path, sets, registries)?;
    record.apply(&mut scene)?;
    vtk.apply(&mut scene)?;
    for w in scene.warnings() {
        eprintln!("warning: {w}");
    }
    let out = out.unwrap_or_else(|| PathBuf::from("out").join(&scene.name));
    let mut claim = None;
    if flags.claim {
        use regolith_lab::claim::{Claimed, claim as take};
        // Done: completed from this very scene text (a changed scene is run again).
        let done = || {
            regolith_lab::batch::read_summary(&out).is_some_and(|s| s["status"] == "completed")
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
pub(crate) fn batch_command<B: BatchFile>(
    registries: &Arc<Registries>,
    file: Option<PathBuf>,
    batch_args: BatchArgs,
) -> Result<(), Error> {
    let BatchArgs { out, jobs, plan } = batch_args;
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
pub(crate) fn both_file_and_collect(kind: &str) -> Error {
    SceneError::file(
        "command line",
        format!("--collect DIR reads the plan in DIR; give it without the {kind} file"),
    )
    .into()
}

/// Writes the plan of `batch` (`sweep --plan` or `study --plan`) and says how to run it.
pub(crate) fn plan_batch(
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
        "{}: {} runs planned in {}\n  run them: cd {} && RAYON_NUM_THREADS=1 parallel -j N < jobs.txt   (or: sbatch slurm.sbatch)\n  then: regolith {} --collect {}",
        batch.name(),
        plan.runs.len(),
        dir.display(),
        dir.display(),
        plan.kind,
        dir.display()
    );
    Ok(())
}

pub(crate) fn collect_plan(dir: &Path, partial: bool) -> Result<(), Error> {
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

pub(crate) fn resume(
    registries: &Arc<Registries>,
    dir: &Path,
    quiet: bool,
    checkpoints: CheckpointEvery,
    record: &RecordArgs,
) -> Result<(), Error> {
    let bar = progress_bar(quiet);
    let mut last_draw = 0u64;
    let mut progress = |c: &Clock| draw(&bar, &mut last_draw, c);
    let extend = |scene: &mut Scene| record.apply(scene);
    let result = resume_run(registries, dir, checkpoints, extend, &mut progress);
    bar.finish_and_clear();
    report(&result?, dir);
    Ok(())
}

/// `regolith beverloo`: reads the runs, fits each grid, writes `beverloo.md` and
/// `beverloo.png` and prints the report.
pub(crate) fn beverloo(
    registries: &Arc<Registries>,
    dirs: &[PathBuf],
    grain_diameter: f64,
    out: Option<PathBuf>,
) -> Result<(), Error> {
    use regolith_lab::beverloo::{by_grid, figure, read_run, report};
    use regolith_lab::poncelet::expand_dirs;
    let fail = |m: String| Error::Scene(SceneError::file("regolith beverloo", m));
    if !(grain_diameter.is_finite() && grain_diameter > 0.0) {
        return Err(fail(format!(
            "--grain-diameter must be a positive length (m), got {grain_diameter}"
        )));
    }
    let out = out.unwrap_or_else(|| dirs[0].clone());
    let runs = expand_dirs(dirs)
        .map_err(fail)?
        .iter()
        .map(|d| read_run(d, registries))
        .collect::<Result<Vec<_>, _>>()
        .map_err(fail)?;
    let grids = by_grid(runs);
    let md = report(&grids, grain_diameter);
    std::fs::create_dir_all(&out).map_err(|e| fail(format!("{}: {e}", out.display())))?;
    let table = out.join("beverloo.md");
    std::fs::write(&table, &md).map_err(|e| fail(format!("{}: {e}", table.display())))?;
    let png = out.join("beverloo.png");
    figure(&grids, grain_diameter, &png).map_err(|e| fail(format!("{}: {e}", png.display())))?;
    print!("{md}");
    println!("wrote {} and {}", table.display(), png.display());
    Ok(())
}

/// `--window`, `--cells` and `--spline` of `regolith fit`.
type MethodFlags = (Option<f64>, Option<f64>, bool);

pub(crate) fn fit(
    dirs: &[PathBuf],
    body: &str,
    depths: Option<&str>,
    out: Option<PathBuf>,
    (window, cells, spline): MethodFlags,
) -> Result<(), Error> {
    use regolith_lab::poncelet::{
        DEFAULT_CELLS, Derivatives, MIN_SPEEDS, NOT_PHYSICAL, default_depths, default_table,
        expand_dirs, fit, group_by_scene, load_run, refuse_duplicates, to_csv,
    };
    let fail = |m: String| Error::Scene(SceneError::file("regolith fit", m));
    let positive = |flag: &str, w: f64| {
        if w.is_finite() && w > 0.0 {
            Ok(w)
        } else {
            Err(fail(format!("{flag} must be positive, got {w}")))
        }
    };
    let chosen = match (window, cells, spline) {
        (Some(w), _, _) => Some(Derivatives::Window(positive("--window", w)?)),
        (_, Some(n), _) => Some(Derivatives::Cells(positive("--cells", n)?)),
        (_, _, true) => Some(Derivatives::Spline),
        _ => None,
    };
    let how = chosen.unwrap_or(Derivatives::Cells(DEFAULT_CELLS));
    let table = out.unwrap_or_else(|| default_table(&dirs[0]));
    let dirs = expand_dirs(dirs).map_err(fail)?;
    let runs = dirs
        .iter()
        .map(|d| load_run(d, body))
        .collect::<Result<Vec<_>, _>>()
        .map_err(fail)?;
    refuse_duplicates(&dirs, &runs).map_err(fail)?;
    if let (Derivatives::Cells(_), Some(old)) = (how, runs.iter().find(|r| r.cell_size.is_none())) {
        return Err(fail(format!(
            "{}: its summary.json has no cell_size (written by an older regolith), which a window in cells needs; give --window SECONDS or --spline",
            old.label
        )));
    }
    let groups = group_by_scene(&runs);
    let several = groups.len() > 1;
    if several {
        println!(
            "{} runs of {} scenes (they differ in more than the intruder's speed): each is fitted alone",
            runs.len(),
            groups.len()
        );
    }
    let mut refused = Vec::new();
    for (k, group) in groups.iter().enumerate() {
        let members: Vec<_> = group.runs.iter().map(|&i| runs[i].clone()).collect();
        let name = match &group.differs {
            Some(differs) => format!(
                "group {} ({differs}: {}{})",
                k + 1,
                members[0].label,
                match members.len() {
                    1 => String::new(),
                    n => format!(" and {} more", n - 1),
                }
            ),
            None => "the runs".to_string(),
        };
        if members.len() < MIN_SPEEDS {
            refused.push(format!(
                "{name}: a fit needs runs at {MIN_SPEEDS} or more speeds (two unknowns per depth; with two speeds the line fits exactly and nothing checks the law), got {} run(s)",
                members.len()
            ));
            continue;
        }
        let depths = match depths {
            Some(spec) => parse_depths(spec).map_err(|e| fail(format!("--depths {spec}: {e}")))?,
            None => default_depths(&members),
        };
        let points = fit(&members, &depths, how);
        if points.is_empty() {
            refused.push(format!(
                "{name}: none of the {} depths is reached while descending by runs at {MIN_SPEEDS} or more distinct speeds; nothing written",
                depths.len()
            ));
            continue;
        }
        let unphysical = points.iter().filter(|p| !p.is_physical()).count();
        if unphysical > 0 && chosen.is_none() {
            let hint = regolith_lab::poncelet::physical_hint(&members, &depths, &points);
            refused.push(format!(
                "{name}: with {how}, {unphysical} of {} depths give {NOT_PHYSICAL} (not a drag law); {hint}; nothing written",
                points.len()
            ));
            continue;
        }
        let out = if several {
            numbered(&table, k + 1)
        } else {
            table.clone()
        };
        regolith::output::write_atomic(&out, to_csv(&points).as_bytes())
            .map_err(|e| Error::io(format!("cannot write {}", out.display()), e))?;
        let caution = if unphysical > 0 {
            format!(" (warning: {unphysical} of them give {NOT_PHYSICAL})")
        } else {
            String::new()
        };
        println!(
            "{}{} runs, {} of {} depths fitted with {how}{caution}; table in {}",
            if several {
                format!("{name}: ")
            } else {
                String::new()
            },
            members.len(),
            points.len(),
            depths.len(),
            out.display()
        );
    }
    match refused.len() {
        0 => Ok(()),
        _ => Err(fail(refused.join("\n"))),
    }
}

/// `poncelet.csv` -> `poncelet_2.csv`: the table of group `k` when runs form several.
fn numbered(table: &Path, k: usize) -> PathBuf {
    let stem = table.file_stem().unwrap_or_default().to_string_lossy();
    let name = match table.extension() {
        Some(ext) => format!("{stem}_{k}.{}", ext.to_string_lossy()),
        None => format!("{stem}_{k}"),
    };
    table.with_file_name(name)
}

pub(crate) fn check(
    registries: &Arc<Registries>,
    path: &Path,
    sets: &[String],
) -> Result<(), Error> {
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
    let w = &scene.walls;
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
    for seg in &w.segments {
        println!(
            "  segment: {:?} from {} to {} m: {:?}",
            seg.side, seg.from, seg.to, seg.wall
        );
    }
    for (k, o) in scene.obstacles.iter().enumerate() {
        let (lo, hi) = o.shape.bounds();
        let held = regolith::obstacle::Obstacles::nodes_inside(&*o.shape.0, &g).len();
        println!(
            "  obstacle {k}: {} from ({}, {}) to ({}, {}) m, {held} grid nodes held: {:?}",
            o.shape.name(),
            lo.x,
            lo.y,
            hi.x,
            hi.y,
            o.wall
        );
    }
    let contact = if scene.bodies.len() > 1 {
        format!("{:?}", scene.contact)
    } else {
        "none (one body)".to_string()
    };
    let blend = if scene.transfer.blends() {
        format!(" (FLIP fraction {})", scene.flip)
    } else {
        String::new()
    };
    println!(
        "integration: {:?}, transfer: {:?}{blend}, contact: {contact}",
        scene.integration, scene.transfer
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
    let memory = memory_estimate(&mut sim, &scene);
    let mib = |bytes: usize| bytes as f64 / (1024.0 * 1024.0);
    println!(
        "particles: {}; state memory about {:.1} MiB ({:.0} bytes per point, {:.1} MiB of grid)",
        sim.particle_count(),
        mib(memory.total()),
        memory.per_point(),
        mib(memory.grid_bytes)
    );
    let kernels = sim.world.resource::<regolith::kernels::Kernels>();
    println!(
        "kernels: {} (REGOLITH_KERNELS=scalar runs the reference path)",
        kernels.name()
    );
    Ok(())
}
