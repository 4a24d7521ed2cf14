//! A test hook that holds a run still at a named point, so that a test can interrupt, kill or
//! race it at that moment and at no other: no test waits on the clock.
//!
//! `SLIDESTACK_PAUSE_AT=POINT[:N]` makes the process stop the `N`-th time (default 1) any thread
//! passes `POINT`; it then creates the file `SLIDESTACK_PAUSE_FILE` (holding `POINT N PID`) and
//! waits until that file is removed (the test releases it) or the run is cancelled (Ctrl-C).
//! While one thread is held, every other thread that reaches the same point waits too, so what a
//! run has done when the file appears is fixed: with one thread, exactly `N` passes. Without
//! the variables a point costs one relaxed atomic load.
//!
//! The points, each named where it is passed:
//! - `session.locked`: the output directory is locked (a stage or `run` about to start);
//! - `motions.record`: a seed record about to be matched (or matched again);
//! - `sweep.unit`: one work unit's file written; `sweep.assemble`: every unit computed,
//!   `sweep.h5` not yet assembled;
//! - `tnew.zone`: one zone of `tnew.h5` computed;
//! - `ida.trace`: one IDA trace done;
//! - `stage.done`: a stage's output written and verified (before it returns).

use std::path::PathBuf;
use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Duration;

/// The environment variable naming the point (and the pass) to hold at.
pub const PAUSE_AT: &str = "SLIDESTACK_PAUSE_AT";
/// The environment variable naming the file that says the run is held; removing it releases it.
pub const PAUSE_FILE: &str = "SLIDESTACK_PAUSE_FILE";

/// How often a held thread looks for its release.
const POLL: Duration = Duration::from_millis(5);

struct Spec {
    point: String,
    pass: usize,
    file: PathBuf,
}

fn spec() -> Option<&'static Spec> {
    static SPEC: OnceLock<Option<Spec>> = OnceLock::new();
    SPEC.get_or_init(|| {
        let at = std::env::var(PAUSE_AT).ok()?;
        let file = PathBuf::from(std::env::var_os(PAUSE_FILE)?);
        let (point, pass) = match at.rsplit_once(':') {
            Some((p, n)) => (p.to_string(), n.parse().ok().filter(|&n| n > 0)?),
            None => (at, 1),
        };
        Some(Spec { point, pass, file })
    })
    .as_ref()
}

/// Passes made of the configured point.
static PASSES: AtomicUsize = AtomicUsize::new(0);
/// A thread is held at the point (set once, cleared on release).
static HELD: AtomicBool = AtomicBool::new(false);

/// Passes `point`; holds there as the module doc says when the environment asks for it.
/// `cancelled` is the run's cancellation (a held run stops holding when it is cancelled).
pub fn point(point: &str, cancelled: &dyn Fn() -> bool) {
    let Some(spec) = spec() else { return };
    if spec.point != point {
        return;
    }
    let pass = PASSES.fetch_add(1, Ordering::SeqCst) + 1;
    if pass == spec.pass {
        HELD.store(true, Ordering::SeqCst);
        let text = format!("{point} {pass} {}\n", std::process::id());
        if std::fs::write(&spec.file, text).is_err() {
            HELD.store(false, Ordering::SeqCst);
            return;
        }
    }
    while HELD.load(Ordering::SeqCst) {
        if cancelled() || !spec.file.exists() {
            HELD.store(false, Ordering::SeqCst);
            return;
        }
        std::thread::sleep(POLL);
    }
}
