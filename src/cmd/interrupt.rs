//! Ctrl-C on the command line. A command whose library work checks for cancellation (the
//! study's stages between work units, `simulate` every few samples) is asked to stop at its next
//! check: it keeps what it stored, says so and the process exits 130. A second Ctrl-C, or the first during a command that does not check, ends
//! the process at once with 130, as the shell's default would (every file is written under a
//! temporary name and renamed, so nothing half-written is ever taken as a result).

use std::sync::atomic::{AtomicBool, Ordering};

/// The exit code of an interrupted command (128 + SIGINT, the shell's convention).
pub const EXIT_CODE: u8 = 130;

static INTERRUPTED: AtomicBool = AtomicBool::new(false);
static CHECKED: AtomicBool = AtomicBool::new(false);

/// Installs the handler; `checked` says whether the command's work checks [`interrupted`].
pub fn install(checked: bool) {
    CHECKED.store(checked, Ordering::SeqCst);
    // A failure leaves the default disposition, which ends the process on Ctrl-C.
    let _ = ctrlc::set_handler(|| {
        if !CHECKED.load(Ordering::SeqCst) || INTERRUPTED.swap(true, Ordering::SeqCst) {
            // SAFETY: `_exit` ends the process without running exit handlers (HDF5's among
            // them), which could race a library call still running on another thread.
            unsafe { libc::_exit(i32::from(EXIT_CODE)) }
        }
        eprintln!("interrupted: stopping at the next check (Ctrl-C again to stop at once)");
    });
}

/// Whether Ctrl-C was pressed.
pub fn interrupted() -> bool {
    INTERRUPTED.load(Ordering::SeqCst)
}
