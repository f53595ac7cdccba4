//! Finding and reading the runs a fit takes: run directories, sweeps and collected plans.

use std::path::{Path, PathBuf};

use regolith::scene::overrides::set_in_text;

use super::PonceletRun;

/// Reads a run directory (`summary.json` and `trajectory.csv`) for the fit of `body`.
pub fn load_run(dir: &Path, body: &str) -> Result<PonceletRun, String> {
    let label = dir.display().to_string();
    let read = |name: &str| {
        std::fs::read_to_string(dir.join(name)).map_err(|e| format!("{label}/{name}: {e}"))
    };
    let summary: serde_json::Value = serde_json::from_str(&read("summary.json")?)
        .map_err(|e| format!("{label}/summary.json: {e}"))?;
    if summary["status"] != "completed" {
        return Err(format!("{label}: the run did not complete"));
    }
    let mass = summary["bodies"]
        .as_array()
        .and_then(|b| b.iter().find(|b| b["name"] == body))
        .and_then(|b| b["mass"].as_f64())
        .ok_or_else(|| format!("{label}/summary.json: no body named `{body}`"))?;
    let gravity = -summary["gravity"][1].as_f64().ok_or_else(|| {
        format!("{label}/summary.json: no gravity (written by an older regolith)")
    })?;
    let impact = &summary["impact"];
    if impact["at_rest"] == false {
        return Err(format!(
            "{label}: the intruder is not at rest ({}); a Poncelet fit needs runs that end at rest (rerun with a later time.end)",
            impact["not_at_rest"].as_str().unwrap_or_default()
        ));
    }
    let contact = impact["contact_time"].as_f64().unwrap_or(0.0);
    let csv = read("trajectory.csv")?;
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
    let column = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .ok_or_else(|| format!("{label}/trajectory.csv: no column {name}"))
    };
    let (ct, cy) = (column("t")?, column(&format!("{body}_y"))?);
    let (mut t, mut y) = (Vec::new(), Vec::new());
    for (n, line) in lines.enumerate() {
        let cells: Vec<&str> = line.split(',').collect();
        let num = |c: usize| {
            cells
                .get(c)
                .and_then(|s| s.parse::<f64>().ok())
                .ok_or_else(|| format!("{label}/trajectory.csv line {}: expected numbers", n + 2))
        };
        let (tn, yn) = (num(ct)?, num(cy)?);
        if tn >= contact {
            t.push(tn - contact);
            y.push(yn);
        }
    }
    let Some(&y0) = y.first() else {
        return Err(format!("{label}: no trajectory after first contact"));
    };
    // A run written before scene.ron was kept has no key: such runs group together.
    let scene_key = match std::fs::read_to_string(dir.join("scene.ron")) {
        Ok(text) => scene_key(&text, body).map_err(|e| format!("{label}/scene.ron: {e}"))?,
        Err(_) => String::new(),
    };
    Ok(PonceletRun {
        label,
        mass,
        gravity,
        t,
        z: y.iter().map(|y| y0 - y).collect(),
        state_hash: summary["state_hash"].as_str().map(str::to_string),
        cell_size: summary["cell_size"].as_f64(),
        scene_key,
    })
}

/// The scene a run ran (`scene.ron`, overrides applied) with what a Poncelet fit varies
/// taken out: the intruder's velocity set to zero and the end time to zero (a slow run may
/// be run longer), comments and layout dropped. Two runs of one shape, bed and numerics at
/// different speeds have equal keys; anything else that differs (the shape, the grid, the
/// material, the time step) makes the keys differ.
fn scene_key(text: &str, body: &str) -> Result<String, String> {
    let text = set_in_text(text, &format!("bodies.{body}.velocity=(0.0, 0.0)"))?;
    let text = set_in_text(&text, "time.end=0.0")?;
    Ok(bare(&text))
}

/// RON text without comments and without whitespace outside strings.
fn bare(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '"' => {
                out.push(c);
                while let Some(d) = chars.next() {
                    out.push(d);
                    match d {
                        '\\' => out.extend(chars.next()),
                        '"' => break,
                        _ => {}
                    }
                }
            }
            '/' if chars.peek() == Some(&'/') => while chars.next_if(|&d| d != '\n').is_some() {},
            '/' if chars.peek() == Some(&'*') => {
                chars.next();
                let mut last = ' ';
                for d in chars.by_ref() {
                    if last == '*' && d == '/' {
                        break;
                    }
                    last = d;
                }
            }
            c if c.is_whitespace() => {}
            c => out.push(c),
        }
    }
    out
}

/// Runs of one scene (equal [`PonceletRun::scene_key`]), in the order their first run was
/// given.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneGroup {
    /// Indices into the runs given.
    pub runs: Vec<usize>,
    /// When runs form several groups: the `field:value` at which this group's scene first
    /// differs from another group's (the first group's, or the second's for the first), as
    /// `slope:2.0`.
    pub differs: Option<String>,
}

/// Sorts runs into groups of one scene: a Poncelet fit is across speeds of one shape, and
/// runs of two shapes fitted together give a law of neither.
pub fn group_by_scene(runs: &[PonceletRun]) -> Vec<SceneGroup> {
    let mut groups: Vec<SceneGroup> = Vec::new();
    for (i, run) in runs.iter().enumerate() {
        match groups
            .iter_mut()
            .find(|g| runs[g.runs[0]].scene_key == run.scene_key)
        {
            Some(g) => g.runs.push(i),
            None => groups.push(SceneGroup {
                runs: vec![i],
                differs: None,
            }),
        }
    }
    if groups.len() > 1 {
        let key = |g: usize| &runs[groups[g].runs[0]].scene_key;
        let labels: Vec<String> = (0..groups.len())
            .map(|g| first_difference(key(g), key(usize::from(g == 0))).0)
            .collect();
        for (group, label) in groups.iter_mut().zip(labels) {
            group.differs = Some(label);
        }
    }
    groups
}

/// The `field:value` around the first place two bare scene texts differ, in each.
fn first_difference(a: &str, b: &str) -> (String, String) {
    let at = a
        .char_indices()
        .zip(b.chars())
        .find(|((_, x), y)| x != y)
        .map(|((i, _), _)| i)
        .unwrap_or(a.len().min(b.len()));
    // Back to the start of the field whose value differs: the last `name:` before it.
    let colon = a[..at].rfind(':');
    let start = colon
        .map(|c| {
            a[..c]
                .rfind(|ch: char| !(ch.is_alphanumeric() || ch == '_'))
                .map_or(0, |i| i + 1)
        })
        .unwrap_or(at);
    let excerpt = |s: &str| {
        let tail = &s[start.min(s.len())..];
        let end = tail
            .char_indices()
            .skip(at - start)
            .find(|&(_, c)| c == ',' || c == ')' || c == ']')
            .map_or(tail.len(), |(i, _)| i);
        let cut: String = tail[..end].chars().take(60).collect();
        if cut.is_empty() {
            "(nothing)".to_string()
        } else {
            cut
        }
    };
    (excerpt(a), excerpt(b))
}

/// Refuses a run given twice: the same directory twice, or two directories holding the same
/// run (equal `state_hash`). A duplicate would count as a second speed where there is one.
pub fn refuse_duplicates(dirs: &[PathBuf], runs: &[PonceletRun]) -> Result<(), String> {
    let canonical: Vec<PathBuf> = dirs
        .iter()
        .map(|d| d.canonicalize().unwrap_or_else(|_| d.clone()))
        .collect();
    for (b, run) in runs.iter().enumerate() {
        for a in 0..b {
            if canonical[a] == canonical[b] {
                return Err(format!("{} is given twice", run.label));
            }
            if let (Some(x), Some(y)) = (&runs[a].state_hash, &run.state_hash)
                && x == y
            {
                return Err(format!(
                    "{} and {} are the same run (state_hash {x}); give each run once",
                    runs[a].label, run.label
                ));
            }
        }
    }
    Ok(())
}

/// Where `regolith fit` writes by default: in the sweep directory when the first argument
/// is one, else beside the first run directory (never inside a run's own record).
pub fn default_table(first: &Path) -> PathBuf {
    if first.join("sweep.csv").is_file() {
        return first.join("poncelet.csv");
    }
    match first.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent.join("poncelet.csv"),
        _ => PathBuf::from("poncelet.csv"),
    }
}

/// Run directories named on the command line: a plan (`plan.json`: a sweep's output
/// directory, or a plan run elsewhere and collected) stands for its runs that have a
/// summary, as does a sweep directory written before plans (it has a `sweep.csv`).
pub fn expand_dirs(dirs: &[PathBuf]) -> Result<Vec<PathBuf>, String> {
    let mut out = Vec::new();
    for d in dirs {
        if d.join("plan.json").is_file() {
            // A sweep's output directory or a plan: the runs it lists that have a summary.
            let plan = crate::plan::read_plan(d).map_err(|e| e.to_string())?;
            out.extend(
                plan.runs
                    .iter()
                    .map(|r| d.join(&r.dir))
                    .filter(|p| p.join("summary.json").is_file()),
            );
        } else if d.join("sweep.csv").is_file() {
            // A sweep written before plans: its runs sit in its directory.
            let mut runs = Vec::new();
            for base in [d.clone(), d.join("runs")] {
                if !base.is_dir() {
                    continue;
                }
                runs.extend(
                    std::fs::read_dir(&base)
                        .map_err(|e| format!("{}: {e}", base.display()))?
                        .filter_map(|e| e.ok().map(|e| e.path()))
                        .filter(|p| p.join("summary.json").is_file()),
                );
            }
            runs.sort();
            out.extend(runs);
        } else {
            out.push(d.clone());
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scenes_that_differ_only_in_speed_and_end_share_a_key() {
        let scene = |v: &str, slope: &str, end: &str| {
            format!(
                "Scene( // a comment\n  time: (end: {end}, step: Cfl(0.5)),\n  bodies: [(name: \"bed\"), (name: \"intruder\", shape: Tip(slope: {slope}), velocity: {v})],\n)"
            )
        };
        let key = |v, s, e| scene_key(&scene(v, s, e), "intruder").unwrap();
        assert_eq!(
            key("(0.0, -2.0)", "1.0", "0.3"),
            key("(0, -5.25)", "1.0", "0.5")
        );
        let (one, two) = (
            key("(0.0, -2.0)", "1.0", "0.3"),
            key("(0.0, -2.0)", "2.0", "0.3"),
        );
        assert_ne!(one, two);
        assert_eq!(
            first_difference(&two, &one),
            ("slope:2.0".to_string(), "slope:1.0".to_string())
        );
        // Whitespace and comments are not differences; a string's spaces are.
        assert_eq!(bare("( a : \"x y\" /* c */ )"), "(a:\"x y\")");
    }

    #[test]
    fn a_sweep_directory_and_a_collected_plan_list_their_runs() {
        let dir = tempfile::tempdir().unwrap();
        let sweep = dir.path().join("sweep");
        let plan = dir.path().join("plan");
        for run in [sweep.join("run_0001"), plan.join("runs/run_0002")] {
            std::fs::create_dir_all(&run).unwrap();
            std::fs::write(run.join("summary.json"), "{}").unwrap();
        }
        std::fs::create_dir_all(sweep.join("run_0002")).unwrap(); // never ran
        // Not in the plan: left out even with a summary.
        std::fs::create_dir_all(plan.join("runs/stray")).unwrap();
        std::fs::write(plan.join("runs/stray/summary.json"), "{}").unwrap();
        std::fs::write(sweep.join("sweep.csv"), "run\n").unwrap();
        let run = |d: &str| {
            format!(r#"{{"dir": "{d}", "values": [], "scene_digest": "", "estimated_s": 1.0}}"#)
        };
        std::fs::write(
            plan.join("plan.json"),
            format!(
                r#"{{"kind": "sweep", "name": "p", "keys": [], "runs": [{}, {}]}}"#,
                run("runs/run_0001"),
                run("runs/run_0002")
            ),
        )
        .unwrap();
        let found = expand_dirs(&[sweep.clone(), plan.clone()]).unwrap();
        assert_eq!(found, [sweep.join("run_0001"), plan.join("runs/run_0002")]);
    }
}
