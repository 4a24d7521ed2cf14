//! Timing for the evidence: the machine's description, the CPU time of the running thread, and
//! a batched median per call.

use std::hint::black_box;
use std::time::Duration;

/// The machine, for every benchmark header: cores, CPU model, OS and architecture.
pub fn machine_description() -> String {
    let nproc = std::thread::available_parallelism().map_or(0, |n| n.get());
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|text| {
            text.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".to_string());
    let load = std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|l| l.split_whitespace().next().map(str::to_string))
        .map_or_else(String::new, |l| format!(", load average {l} at the start"));
    format!(
        "{nproc} cores, {model}, {}-{}{load}",
        std::env::consts::OS,
        std::env::consts::ARCH
    )
}

/// CPU time of the calling thread, s (`CLOCK_THREAD_CPUTIME_ID`): what a computation costs,
/// which other load on a shared machine barely changes, unlike its wall time.
pub fn thread_cpu_time_s() -> f64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec for the duration of the call.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    assert_eq!(rc, 0, "clock_gettime(CLOCK_THREAD_CPUTIME_ID) failed");
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}

/// How a call is timed: CPU time of this thread ([`thread_cpu_time_s`]).
#[derive(Debug, Clone, Copy)]
pub struct Timing {
    /// At least this many timed batches…
    pub min_batches: usize,
    /// …totalling at least this long; each batch is sized from a warm-up call to last
    /// `batch_target`.
    pub min_total: Duration,
    pub batch_target: Duration,
}

impl Timing {
    /// One call after the warm-up: for quick runs.
    pub const SINGLE: Timing = Timing {
        min_batches: 1,
        min_total: Duration::ZERO,
        batch_target: Duration::ZERO,
    };
    pub const FULL: Timing = Timing {
        min_batches: 3,
        min_total: Duration::from_millis(200),
        batch_target: Duration::from_millis(50),
    };

    /// Median CPU time of one call of `f` over the batches, s.
    pub fn per_call<T>(&self, mut f: impl FnMut() -> T) -> f64 {
        let start = thread_cpu_time_s();
        black_box(f());
        let warm = thread_cpu_time_s() - start;
        let batch = ((self.batch_target.as_secs_f64() / warm.max(1e-9)).ceil() as usize).max(1);
        let mut per_call = Vec::new();
        let mut total = 0.0;
        while per_call.len() < self.min_batches || total < self.min_total.as_secs_f64() {
            let start = thread_cpu_time_s();
            for _ in 0..batch {
                black_box(f());
            }
            let elapsed = thread_cpu_time_s() - start;
            total += elapsed;
            per_call.push(elapsed / batch as f64);
        }
        per_call.sort_by(f64::total_cmp);
        let n = per_call.len();
        if n % 2 == 1 {
            per_call[n / 2]
        } else {
            0.5 * (per_call[n / 2 - 1] + per_call[n / 2])
        }
    }
}

/// A duration for tables: `12.3 µs`, `4.567 ms`, `1.234 s`.
pub fn fmt_time(s: f64) -> String {
    if !s.is_finite() {
        "–".to_string()
    } else if s >= 1.0 {
        format!("{s:.3} s")
    } else if s >= 1e-3 {
        format!("{:.3} ms", s * 1e3)
    } else {
        format!("{:.1} µs", s * 1e6)
    }
}
