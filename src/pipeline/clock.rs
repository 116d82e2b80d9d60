//! The process's CPU time, for the manifests' measured cost.

use std::collections::BTreeMap;
use std::sync::Mutex;
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

/// The process's CPU time shared out among the instances computed at once.
/// Between two changes of who runs, each of the `n` running accounts is
/// credited `1/n` of the CPU time the process spent: run one at a time, an
/// account holds exactly the process's CPU time while it was open.
#[derive(Debug, Default)]
pub struct CpuLedger {
    shares: Mutex<Shares>,
}

/// The ledger's books: the process's CPU time when they were last settled,
/// and each open account's credit (seconds) by its number.
#[derive(Debug, Default)]
struct Shares {
    settled_at: Option<f64>,
    credit: BTreeMap<u64, f64>,
    opened: u64,
}

impl Shares {
    /// Credits the CPU time spent since the last settlement to the open
    /// accounts in equal parts.
    fn settle(&mut self) {
        let now = process_cpu_seconds();
        if let (Some(now), Some(then)) = (now, self.settled_at)
            && !self.credit.is_empty()
        {
            let each = (now - then) / self.credit.len() as f64;
            self.credit.values_mut().for_each(|credit| *credit += each);
        }
        self.settled_at = now;
    }
}

impl CpuLedger {
    /// Opens an account for one instance, credited from now until it is dropped.
    pub fn open(&self) -> CpuAccount<'_> {
        let mut shares = self.books();
        shares.settle();
        let number = shares.opened;
        shares.opened += 1;
        shares.credit.insert(number, 0.0);
        CpuAccount {
            ledger: self,
            number,
        }
    }

    /// The books (a thread that panicked while holding them left them whole:
    /// every update is a single assignment).
    fn books(&self) -> std::sync::MutexGuard<'_, Shares> {
        self.shares
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }
}

/// One instance's share of the process's CPU time (see [`CpuLedger`]).
#[derive(Debug)]
pub struct CpuAccount<'a> {
    ledger: &'a CpuLedger,
    number: u64,
}

impl CpuAccount<'_> {
    /// CPU seconds credited so far; `None` where `/proc` cannot be read.
    pub fn seconds(&self) -> Option<f64> {
        let mut shares = self.ledger.books();
        shares.settle();
        shares.settled_at?;
        shares.credit.get(&self.number).copied()
    }
}

impl Drop for CpuAccount<'_> {
    fn drop(&mut self) {
        let mut shares = self.ledger.books();
        shares.settle();
        shares.credit.remove(&self.number);
    }
}

/// Wall time and an account's CPU time since it started.
#[derive(Clone, Copy, Debug)]
pub struct Stopwatch<'a> {
    wall: Instant,
    account: &'a CpuAccount<'a>,
    cpu: Option<f64>,
}

impl<'a> Stopwatch<'a> {
    /// Starts now, on `account`'s CPU time.
    pub fn start(account: &'a CpuAccount<'a>) -> Stopwatch<'a> {
        Stopwatch {
            wall: Instant::now(),
            account,
            cpu: account.seconds(),
        }
    }

    /// Wall seconds since the start.
    pub fn wall_seconds(&self) -> f64 {
        self.wall.elapsed().as_secs_f64()
    }

    /// CPU seconds credited to the account since the start: the whole
    /// process's while its instance runs alone, a share while others run.
    pub fn cpu_seconds(&self) -> Option<f64> {
        Some(self.account.seconds()? - self.cpu?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn busy_work_advances_the_cpu_clock() {
        let ledger = CpuLedger::default();
        let account = ledger.open();
        let watch = Stopwatch::start(&account);
        let mut sum = 0.0_f64;
        // Spin until the clock has ticked five times (10 ms each), or give up.
        while watch.cpu_seconds().expect("Linux /proc") < 0.05 && watch.wall_seconds() < 30.0 {
            sum = std::hint::black_box(sum + 1.0);
        }
        assert!(sum > 0.0);
        assert!(watch.cpu_seconds().unwrap() >= 0.05, "{watch:?}");
    }

    #[test]
    fn accounts_open_together_share_the_cpu_time_equally() {
        let ledger = CpuLedger::default();
        let first = ledger.open();
        let second = ledger.open();
        let start = process_cpu_seconds().expect("Linux /proc");
        let mut sum = 0.0_f64;
        while process_cpu_seconds().unwrap() < start + 0.1 {
            sum = std::hint::black_box(sum + 1.0);
        }
        assert!(sum > 0.0);
        // Each holds half of the 0.1 s spent since both were open; the
        // first also holds what it was credited alone.
        let (b, a) = (second.seconds().unwrap(), first.seconds().unwrap());
        assert!(b >= 0.05 - 1e-12 && a >= b, "{a} {b}");
        drop(second);
        let later = ledger.open();
        assert_eq!(later.seconds(), Some(0.0));
    }
}
