//! Claims on a run directory, so that several workers can share one plan of runs.
//!
//! A sweep planned with `regolith sweep --plan` is run by whatever runs its `jobs.txt`: GNU
//! parallel on one or several hosts over a shared file system, a Slurm array that may be
//! resubmitted, or two `regolith` processes started by hand. Each line is a plain
//! `regolith run ... --claim`, and this module decides, per run directory, whether this
//! process runs it:
//!
//! * a directory whose `summary.json` says `completed` is done, and is left alone;
//! * otherwise the run is claimed by creating `claim` with `create_new`, which the file
//!   system grants to exactly one process (O_EXCL; NFS v3 and later honour it);
//! * a claim whose holder is gone can be taken over: on the same host when its process no
//!   longer exists, on any host when its heartbeat (the file's modification time, renewed
//!   every [`HEARTBEAT`] while the run steps) is older than [`LEASE`]. The takeover renames
//!   the stale claim away first, so of two workers that both find it stale only the one
//!   whose rename succeeds goes on to claim.
//!
//! A claim is removed when its run ends in any way this process sees (completed, failed,
//! interrupted); a worker killed outright (SIGKILL, a node lost) leaves its claim, which
//! the next worker takes over once the holder is known to be gone.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant, SystemTime};

use regolith::run::host;

/// How often a running claim renews its heartbeat.
pub const HEARTBEAT: Duration = Duration::from_secs(30);
/// How old a heartbeat may be before another host may take the claim over.
pub const LEASE: Duration = Duration::from_secs(300);

/// What a worker found when it asked for a run directory.
#[derive(Debug)]
pub enum Claimed {
    /// The run is this worker's; the claim is released when the value is dropped.
    Mine(Claim),
    /// The run completed earlier.
    Completed,
    /// Another worker holds the run: `holder` is its `host pid`.
    Held { holder: String },
}

/// A held claim on a run directory.
#[derive(Debug)]
pub struct Claim {
    path: PathBuf,
    beat: Instant,
}

/// The name of a claim file in a run directory.
const FILE: &str = "claim";

/// This process as a claim holder: `host pid`.
fn me() -> String {
    format!("{} {}", host(), std::process::id())
}

/// The holder (`host pid`) written in the claim at `path`; empty if it cannot be read or is
/// still being written.
fn holder(path: &Path) -> String {
    std::fs::read_to_string(path)
        .unwrap_or_default()
        .trim()
        .to_string()
}

/// Claims the run directory `dir` (created if missing) for this process, unless `done()`
/// says its run completed (checked before and after the claim is made) or a live worker
/// holds it.
pub fn claim(dir: &Path, done: impl Fn() -> bool) -> std::io::Result<Claimed> {
    std::fs::create_dir_all(dir)?;
    let path = dir.join(FILE);
    // Two rounds: the second after taking over a stale claim.
    for _ in 0..2 {
        if done() {
            return Ok(Claimed::Completed);
        }
        match std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&path)
        {
            Ok(mut f) => {
                writeln!(f, "{}", me())?;
                f.sync_all()?;
                // A worker may have completed the run between our look and our claim.
                if done() {
                    std::fs::remove_file(&path)?;
                    return Ok(Claimed::Completed);
                }
                return Ok(Claimed::Mine(Claim {
                    path,
                    beat: Instant::now(),
                }));
            }
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                let holder = holder(&path);
                if !stale(&path, &holder) {
                    return Ok(Claimed::Held { holder });
                }
                // Only one of several workers that found it stale renames it away.
                let aside = dir.join(format!("{FILE}.stale.{}", std::process::id()));
                if std::fs::rename(&path, &aside).is_ok() {
                    std::fs::remove_file(&aside)?;
                }
            }
            Err(e) => return Err(e),
        }
    }
    Ok(Claimed::Held {
        holder: holder(&path),
    })
}

/// Whether the claim at `path`, held by `holder` (`host pid`), belongs to a worker that is
/// gone: its process has ended on this host, or its heartbeat is older than the lease.
fn stale(path: &Path, holder: &str) -> bool {
    let host = host();
    let mut parts = holder.split_whitespace();
    if let (Some(h), Some(pid)) = (parts.next(), parts.next())
        && h == host
        && Path::new("/proc/self").exists()
        && !Path::new("/proc").join(pid).exists()
    {
        return true;
    }
    let age = std::fs::metadata(path)
        .and_then(|m| m.modified())
        .ok()
        .and_then(|t| SystemTime::now().duration_since(t).ok());
    age.is_some_and(|a| a > LEASE)
}

impl Claim {
    /// Renews the heartbeat if [`HEARTBEAT`] has passed since the last renewal (cheap to
    /// call every step).
    pub fn heartbeat(&mut self) {
        if self.beat.elapsed() < HEARTBEAT {
            return;
        }
        self.beat = Instant::now();
        if let Ok(f) = std::fs::File::options().write(true).open(&self.path) {
            let _ = f.set_modified(SystemTime::now());
        }
    }
}

impl Drop for Claim {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_claim_at_a_time_and_a_dead_holder_is_replaced() {
        let dir = tempfile::tempdir().unwrap();
        let run = dir.path().join("run_0001");
        let done = || crate::batch::read_summary(&run).is_some_and(|s| s["status"] == "completed");
        let claim = |run: &Path| claim(run, done);
        let first = claim(&run).unwrap();
        assert!(matches!(first, Claimed::Mine(_)), "{first:?}");
        let second = claim(&run).unwrap();
        assert!(
            matches!(&second, Claimed::Held { holder } if *holder == me()),
            "{second:?}"
        );
        drop(first);
        assert!(!run.join(FILE).exists(), "the claim is released");

        // A holder on this host whose process is gone (pid beyond pid_max).
        std::fs::write(run.join(FILE), format!("{} 4999999\n", host())).unwrap();
        assert!(matches!(claim(&run).unwrap(), Claimed::Mine(_)));

        // A live holder on another host keeps its claim while its heartbeat is fresh.
        std::fs::write(run.join(FILE), "elsewhere 1\n").unwrap();
        assert!(matches!(claim(&run).unwrap(), Claimed::Held { .. }));
        let old = SystemTime::now() - LEASE - Duration::from_secs(1);
        std::fs::File::options()
            .write(true)
            .open(run.join(FILE))
            .unwrap()
            .set_modified(old)
            .unwrap();
        assert!(matches!(claim(&run).unwrap(), Claimed::Mine(_)));

        std::fs::write(run.join("summary.json"), r#"{"status": "completed"}"#).unwrap();
        assert!(matches!(claim(&run).unwrap(), Claimed::Completed));
    }
}
