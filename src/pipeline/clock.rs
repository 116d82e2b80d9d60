//! The process's CPU time, for the manifests' measured cost.

use std::time::Instant;

/// Clock ticks per second of `/proc/<pid>/stat`'s times (Linux's `USER_HZ`,
/// 100 on every architecture it exports to user space).
const TICKS_PER_SECOND: f64 = 100.0;

/// User plus system CPU time of this process, all threads, in seconds
/// (`utime + stime` of `/proc/self/stat`, 10 ms resolution); `None` where
/// `/proc` cannot be read (not Linux).
pub fn process_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command name, which may hold spaces and parentheses:
    // state is field 3, utime 14, stime 15.
    let after_name = &stat[stat.rfind(')')? + 1..];
    let fields: Vec<&str> = after_name.split_whitespace().collect();
    let ticks = |field: usize| fields.get(field - 3)?.parse::<u64>().ok();
    Some((ticks(14)? + ticks(15)?) as f64 / TICKS_PER_SECOND)
}

/// Wall and CPU time since it started.
#[derive(Clone, Copy, Debug)]
pub struct Stopwatch {
    wall: Instant,
    cpu: Option<f64>,
}

impl Stopwatch {
    /// Starts now.
    pub fn start() -> Stopwatch {
        Stopwatch {
            wall: Instant::now(),
            cpu: process_cpu_seconds(),
        }
    }

    /// Wall seconds since the start.
    pub fn wall_seconds(&self) -> f64 {
        self.wall.elapsed().as_secs_f64()
    }

    /// CPU seconds of the whole process since the start (every thread, so
    /// only the instance's own while the executor runs one at a time).
    pub fn cpu_seconds(&self) -> Option<f64> {
        Some(process_cpu_seconds()? - self.cpu?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn busy_work_advances_the_cpu_clock() {
        let watch = Stopwatch::start();
        let mut sum = 0.0_f64;
        // Spin until the clock has ticked five times (10 ms each), or give up.
        while watch.cpu_seconds().expect("Linux /proc") < 0.05 && watch.wall_seconds() < 30.0 {
            sum = std::hint::black_box(sum + 1.0);
        }
        assert!(sum > 0.0);
        assert!(watch.cpu_seconds().unwrap() >= 0.05, "{watch:?}");
    }
}
