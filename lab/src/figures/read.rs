//! Reading the runs' tables back for the figures: the sweep table (impact measures by
//! column name), the pressure space-time table, the flow-field and splash point clouds.

use std::path::{Path, PathBuf};

use regolith::error::Error;

use super::plot::{self, Series};
use super::{THICKNESS, fail};

/// One impact run's measures.
pub(super) struct Impact {
    pub(super) dir: PathBuf,
    pub(super) slope: f64,
    /// Impact energy over the experiment's thickness (J).
    pub(super) energy: f64,
    pub(super) depth: f64,
    pub(super) stopping: f64,
    pub(super) wall: f64,
}

/// The completed runs of a sweep's table (`sweep.csv` in `dir`, as `regolith sweep` and
/// `sweep --collect` write it) whose intruder came to rest, with the tip slope from the
/// table's `bodies.intruder.shape.slope` column (NaN when the sweep does not vary it), and
/// how many were left out: still moving at the end (their depth is not a result) or not
/// completed.
pub(super) fn read_impacts(dir: &Path) -> Result<(Vec<Impact>, usize), Error> {
    let path = dir.join("sweep.csv");
    let origin = path.display().to_string();
    let mut table = csv::Reader::from_path(&path).map_err(|e| fail(&origin, e))?;
    let header = table.headers().map_err(|e| fail(&origin, e))?.clone();
    let column = |name: &str| header.iter().position(|h| h == name);
    let required = |name: &str| {
        column(name).ok_or_else(|| fail(&origin, format!("no `{name}` column: not a sweep table")))
    };
    let [run, status, wall, energy, depth, stopping, at_rest] = [
        "run",
        "status",
        "wall_s",
        "impact_energy",
        "final_depth",
        "stopping_time",
        "at_rest",
    ]
    .map(required);
    let (run, status, wall, energy, depth, stopping, at_rest) =
        (run?, status?, wall?, energy?, depth?, stopping?, at_rest?);
    let slope = column("bodies.intruder.shape.slope");
    let mut kept = Vec::new();
    let mut left_out = 0;
    for (k, record) in table.records().enumerate() {
        let record = record.map_err(|e| fail(&format!("{origin}: row {}", k + 2), e))?;
        let num = |i: usize| {
            record
                .get(i)
                .and_then(|v| v.parse().ok())
                .unwrap_or(f64::NAN)
        };
        if record.get(status) != Some("completed") || record.get(at_rest) != Some("true") {
            left_out += 1;
            continue;
        }
        kept.push(Impact {
            dir: dir.join(record.get(run).unwrap_or_default()),
            slope: slope.map_or(f64::NAN, num),
            energy: num(energy) * THICKNESS,
            depth: num(depth),
            stopping: num(stopping),
            wall: num(wall),
        });
    }
    Ok((kept, left_out))
}

pub(super) fn read_csv(path: &Path) -> Result<(Vec<String>, Vec<Vec<f64>>), Error> {
    let text = std::fs::read_to_string(path).map_err(|e| fail(&path.display().to_string(), e))?;
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap_or("")
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .map(|l| {
            l.split(',')
                .map(|c| c.parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    Ok((header, rows))
}

/// A space-time diagram: a row of bin values per time.
pub(super) struct SpaceTime {
    pub(super) times: Vec<f64>,
    pub(super) radii: Vec<f64>,
    pub(super) values: Vec<Vec<f64>>,
}

/// A fitted term per depth (`(depth, value, standard error)`, per metre of thickness) as a
/// curve over the scene's thickness, with one standard error either side as its band.
pub(super) fn with_standard_error(label: &str, terms: &[(f64, f64, f64)]) -> [Series; 1] {
    let band = terms
        .iter()
        .map(|&(z, v, e)| (z, (v - e) * THICKNESS, (v + e) * THICKNESS))
        .collect();
    [Series {
        label: label.into(),
        points: terms.iter().map(|&(z, v, _)| (z, v * THICKNESS)).collect(),
        hollow: false,
        band: Some(("±1 standard error (fit residual)".into(), band)),
    }]
}

/// `pressure_front.csv`: times, bin radii (from the `rR` headers) and the rows.
pub(super) fn read_space_time(path: &Path) -> Result<SpaceTime, Error> {
    let (header, rows) = read_csv(path)?;
    Ok(SpaceTime {
        radii: header[1..]
            .iter()
            .map(|h| h.trim_start_matches('r').parse().unwrap_or(f64::NAN))
            .collect(),
        times: rows.iter().map(|r| r[0]).collect(),
        values: rows.iter().map(|r| r[1..].to_vec()).collect(),
    })
}

/// Length (in disc diameters) of the flow field's arrow for a point moving at the disc's speed.
pub(super) const FLOW_ARROW: f64 = 0.15;

/// `flow_field_K.csv`: offsets and normalised velocities of every point (arrows scaled to
/// [`FLOW_ARROW`] per unit of normalised velocity).
pub(super) fn read_flow(path: &Path) -> Result<(plot::Cloud, plot::Cloud), Error> {
    let (_, rows) = read_csv(path)?;
    let (mut o, mut v) = (Vec::new(), Vec::new());
    for r in &rows {
        if r.len() >= 7 && r[3].abs() < 1.5 && r[4] > -2.5 && r[4] < 0.5 {
            o.push((r[3], r[4]));
            v.push((FLOW_ARROW * r[5], FLOW_ARROW * r[6]));
        }
    }
    Ok((o, v))
}

/// A snapshot's points, one cloud per body (in order of appearance).
pub(super) fn read_cloud(path: &Path) -> Result<Vec<Vec<(f64, f64)>>, Error> {
    let text = std::fs::read_to_string(path).map_err(|e| fail(&path.display().to_string(), e))?;
    let mut names: Vec<String> = Vec::new();
    let mut clouds: Vec<Vec<(f64, f64)>> = Vec::new();
    for line in text.lines().skip(1) {
        let c: Vec<&str> = line.split(',').collect();
        if c.len() < 7 || c[6].parse::<f64>().unwrap_or(0.0) == 0.0 {
            continue;
        }
        let k = match names.iter().position(|n| n == c[1]) {
            Some(k) => k,
            None => {
                names.push(c[1].to_string());
                clouds.push(Vec::new());
                names.len() - 1
            }
        };
        if let (Ok(x), Ok(y)) = (c[2].parse(), c[3].parse()) {
            clouds[k].push((x, y));
        }
    }
    Ok(clouds)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run whose intruder is still moving has no final depth, and a run not completed
    /// has no result: the figures must leave both out (and say so), not plot them. The
    /// table is read by column name, with a quoted velocity as the sweep writes it.
    #[test]
    fn runs_not_at_rest_or_not_completed_are_left_out_and_counted() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("sweep.csv"),
            "run,bodies.intruder.shape.slope,bodies.intruder.velocity,status,wall_s,impact_energy,final_depth,stopping_time,at_rest\n\
             runs/run_0001,1.5,\"(0.0, -2.0)\",completed,2.0,100.0,0.3,0.25,true\n\
             runs/run_0002,1.5,\"(0.0, -3.0)\",completed,2.0,200.0,,,false\n\
             runs/run_0003,2.5,\"(0.0, -2.0)\",pending,,,,,\n",
        )
        .unwrap();
        let (kept, left_out) = read_impacts(dir.path()).unwrap();
        assert_eq!(left_out, 2);
        assert_eq!(kept.len(), 1);
        assert_eq!((kept[0].depth, kept[0].slope), (0.3, 1.5));
        assert_eq!(kept[0].energy, 100.0 * super::THICKNESS);
        assert_eq!(kept[0].dir, dir.path().join("runs/run_0001"));
    }

    /// A table without the impact columns is refused with the file named.
    #[test]
    fn a_table_that_is_not_a_sweep_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("sweep.csv"),
            "run,status\nrun_0001,completed\n",
        )
        .unwrap();
        let Err(e) = read_impacts(dir.path()) else {
            panic!("accepted")
        };
        assert!(
            e.to_string().contains("sweep.csv") && e.to_string().contains("wall_s"),
            "{e}"
        );
    }
}
