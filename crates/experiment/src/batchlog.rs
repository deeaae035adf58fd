//! What a run tells while it runs: a progress bar on a terminal, plain
//! lines in a batch job.
//!
//! Under Slurm or `nohup` stderr is a file, where a bar draws nothing until
//! it ends. There the run writes one line per finished packing (its id,
//! φ_J, z, FIRE steps, seconds, and the run's elapsed time and ETA), and
//! for a packing still running after `every` (30 s by default) a line on
//! where it stands (minimisations so far, the last φ and `V/N`, whether it
//! is above jamming), read from the minimiser's [`Progress`] without
//! touching the computation. `--quiet` writes nothing; `--verbose` writes
//! the lines on a terminal too, and the in-progress ones every 10 s.

use crate::error::ExperimentError;
use crate::outcome::Outcome;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use jamkit_engine::Progress;
use std::collections::BTreeMap;
use std::io::Write;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// How a run reports while it runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Log {
    /// Nothing.
    Quiet,
    /// A progress bar on stderr (for a terminal).
    Bar,
    /// A line per finished packing, and one per running packing every
    /// `every` (for a batch job's log file).
    Lines {
        /// Interval of the in-progress lines.
        every: Duration,
    },
}

impl Log {
    /// The choice for stderr: a bar on a terminal, lines elsewhere (30 s);
    /// `quiet` wins; `verbose` asks for lines every 10 s even on a terminal.
    pub fn for_stderr(quiet: bool, verbose: bool) -> Self {
        use std::io::IsTerminal;
        if quiet {
            Log::Quiet
        } else if verbose {
            Log::Lines {
                every: Duration::from_secs(10),
            }
        } else if std::io::stderr().is_terminal() {
            Log::Bar
        } else {
            Log::Lines {
                every: Duration::from_secs(30),
            }
        }
    }
}

/// A packing under way.
struct Flight {
    start: Instant,
    last_line: Instant,
    progress: Arc<Progress>,
}

/// The log of one run.
pub(crate) struct BatchLog {
    log: Log,
    total: usize,
    start: Instant,
    done: AtomicUsize,
    /// Packings made in this run (not read back), for the ETA.
    made: AtomicUsize,
    flights: Mutex<BTreeMap<String, Flight>>,
    stop: AtomicBool,
    bar: ProgressBar,
}

impl BatchLog {
    pub fn new(log: Log, total: usize) -> Self {
        let bar = if log == Log::Bar {
            ProgressBar::with_draw_target(Some(total as u64), ProgressDrawTarget::stderr())
        } else {
            ProgressBar::hidden()
        };
        bar.set_style(
            ProgressStyle::with_template(
                "{bar:40} {pos}/{len} packings, {elapsed} elapsed, ~{eta} left",
            )
            .expect("valid template"),
        );
        Self {
            log,
            total,
            start: Instant::now(),
            done: AtomicUsize::new(0),
            made: AtomicUsize::new(0),
            flights: Mutex::new(BTreeMap::new()),
            stop: AtomicBool::new(false),
            bar,
        }
    }

    fn lines(&self) -> Option<Duration> {
        match self.log {
            Log::Lines { every } => Some(every),
            _ => None,
        }
    }

    /// A packing starts: the progress its minimiser should report to
    /// (`None` unless the log writes lines).
    pub fn begin(&self, id: &str) -> Option<Arc<Progress>> {
        self.lines()?;
        let progress = Arc::new(Progress::default());
        let now = Instant::now();
        self.flights
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .insert(
                id.to_string(),
                Flight {
                    start: now,
                    last_line: now,
                    progress: progress.clone(),
                },
            );
        Some(progress)
    }

    /// A job is over: made, read back, left to another process, or failed.
    pub fn finish(&self, id: &str, outcome: &Result<Outcome, ExperimentError>) {
        self.bar.inc(1);
        let done = self.done.fetch_add(1, Ordering::Relaxed) + 1;
        if matches!(outcome, Ok(Outcome::Done(_, false))) {
            self.made.fetch_add(1, Ordering::Relaxed);
        }
        self.flights
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .remove(id);
        if self.lines().is_none() {
            return;
        }
        let what = match outcome {
            Ok(Outcome::Done(_, true)) => "read back from an earlier run".to_string(),
            Ok(Outcome::Elsewhere(holder)) => format!("in flight elsewhere ({holder}), left to it"),
            Ok(Outcome::Stopped) => "stopped before it started".to_string(),
            Ok(Outcome::Done(f, false)) => {
                let m = &f.measures;
                let z = m.z_j.map_or("–".into(), |z| format!("{z:.4}"));
                let lbfgs = m
                    .lbfgs_evaluations
                    .map_or(String::new(), |n| format!(" + {n} L-BFGS evaluations"));
                format!(
                    "φ {:.6}, z {z}, {} FIRE steps{lbfgs}, {:.1} s",
                    f.phi, m.fire_steps, m.wall_s
                )
            }
            Err(e) => format!("FAILED: {e}"),
        };
        let elapsed = self.start.elapsed();
        let made = self.made.load(Ordering::Relaxed);
        let left = self.total - done;
        // Time per made packing so far times the packings left (read-back
        // ones cost nothing).
        let eta = if left == 0 {
            "done".to_string()
        } else if made == 0 {
            "?".to_string()
        } else {
            clock(elapsed.mul_f64(left as f64 / made as f64))
        };
        self.line(&format!(
            "[{done}/{}] {id}: {what}; {} elapsed, ETA {eta}",
            self.total,
            clock(elapsed)
        ));
    }

    /// Until [`BatchLog::close`]: every second, a line for each packing
    /// that has run `every` since its last line.
    pub fn watch(&self) {
        let Some(every) = self.lines() else {
            return;
        };
        while !self.stop.load(Ordering::Relaxed) {
            std::thread::park_timeout(Duration::from_millis(200));
            let now = Instant::now();
            let mut due = Vec::new();
            {
                let mut flights = self.flights.lock().unwrap_or_else(|e| e.into_inner());
                for (id, f) in flights.iter_mut() {
                    if now - f.last_line >= every {
                        f.last_line = now;
                        due.push((id.clone(), now - f.start, f.progress.snapshot()));
                    }
                }
            }
            for (id, running, p) in due {
                let stage = if p.minimizations == 0 {
                    "first minimisation".to_string()
                } else {
                    format!(
                        "{} minimisations, {} FIRE steps; last φ {:.9}, V/N {:.2e}",
                        p.minimizations, p.fire_steps, p.phi, p.energy_per_particle
                    )
                };
                self.line(&format!("  … {id}: running {}, {stage}", clock(running)));
            }
        }
    }

    /// End [`BatchLog::watch`] and clear the bar.
    pub fn close(&self) {
        self.stop.store(true, Ordering::Relaxed);
        self.bar.finish_and_clear();
    }

    fn line(&self, text: &str) {
        let mut err = std::io::stderr().lock();
        let _ = writeln!(err, "{text}");
    }
}

/// `1h02m`, `3m05s`, `12.3s`.
fn clock(d: Duration) -> String {
    let s = d.as_secs_f64();
    if s < 60.0 {
        format!("{s:.1}s")
    } else if s < 3600.0 {
        format!("{}m{:02}s", (s / 60.0) as u64, (s % 60.0) as u64)
    } else {
        format!(
            "{}h{:02}m",
            (s / 3600.0) as u64,
            ((s % 3600.0) / 60.0) as u64
        )
    }
}

#[cfg(test)]
mod tests {
    use super::clock;
    use std::time::Duration;

    #[test]
    fn clock_reads() {
        assert_eq!(clock(Duration::from_millis(12_340)), "12.3s");
        assert_eq!(clock(Duration::from_secs(185)), "3m05s");
        assert_eq!(clock(Duration::from_secs(3720)), "1h02m");
    }
}
