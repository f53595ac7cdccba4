//! What a run shows while it goes and after: the progress bar and the closing report.

use std::path::Path;
use std::time::Duration;

use indicatif::{ProgressBar, ProgressStyle};

use regolith::output::summary::Summary;
use regolith::resources::Clock;

/// A progress bar on stderr (hidden with `--quiet`), redrawn every 50 steps.
pub(crate) fn progress_bar(quiet: bool) -> ProgressBar {
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

pub(crate) fn draw(bar: &ProgressBar, last_draw: &mut u64, c: &Clock) {
    if c.step - *last_draw >= 50 || c.time >= c.end {
        *last_draw = c.step;
        bar.set_position((1000.0 * c.time / c.end) as u64);
        bar.set_message(format!(
            "step {} t = {:.4e} s dt = {:.2e} s",
            c.step, c.time, c.dt
        ));
    }
}

pub(crate) fn report(summary: &Summary, out: &Path) {
    println!(
        "{}: {} steps to t = {} s, {} points, {:.1} s wall, {:.3e} particle-steps/s, max CFL {:.3}; outputs in {}",
        summary.scene,
        summary.steps,
        regolith::format::Seconds(summary.time),
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
    for line in &summary.headlines {
        println!("  {line}");
    }
}

/// `name seconds (share)` for each step set, the largest first.
pub(crate) fn set_shares(timings: &std::collections::BTreeMap<String, f64>) -> String {
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
