//! Long work without the GIL, stoppable by Ctrl-C: the work runs on a worker thread while the
//! calling thread waits with the GIL released and, every 50 ms, lets Python run its signal
//! handlers; a KeyboardInterrupt sets the flag the library's loops poll (a run stops at the end
//! of its step, writing its checkpoint when it has a folder, exactly as on SIGINT in the CLI).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::time::Duration;

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

/// The worker's stack: the CLI runs on the main thread (8 MB on Linux), a spawned thread gets 2 MB
/// by default; the worker gets more than the main thread so nothing the CLI runs overflows here.
const STACK: usize = 64 << 20;

/// `work(flag)` on a worker thread without the GIL. Returns its result and the Python
/// exception a signal handler raised meanwhile (KeyboardInterrupt), if any: the caller raises
/// it after the work has stopped cleanly.
pub fn interruptible<T: Send>(
    py: Python<'_>,
    work: impl FnOnce(Arc<AtomicBool>) -> T + Send,
) -> PyResult<(T, Option<PyErr>)> {
    let flag = Arc::new(AtomicBool::new(false));
    let done = (Mutex::new(false), Condvar::new());
    let mut signal = None;
    let result = std::thread::scope(|s| {
        let (f, done_ref) = (Arc::clone(&flag), &done);
        let worker = std::thread::Builder::new()
            .name("dyncontact".into())
            .stack_size(STACK)
            .spawn_scoped(s, move || {
                // the flag is set even when `work` panics, so the wait below ends
                struct Finished<'a>(&'a (Mutex<bool>, Condvar));
                impl Drop for Finished<'_> {
                    fn drop(&mut self) {
                        *self.0.0.lock().unwrap_or_else(|p| p.into_inner()) = true;
                        self.0.1.notify_all();
                    }
                }
                let _finished = Finished(done_ref);
                work(f)
            })
            .map_err(|e| PyRuntimeError::new_err(format!("cannot start the solver thread: {e}")))?;
        loop {
            let finished = py.detach(|| {
                let (lock, cv) = &done;
                let guard = lock.lock().unwrap_or_else(|p| p.into_inner());
                let (guard, _) = cv
                    .wait_timeout_while(guard, Duration::from_millis(50), |finished| !*finished)
                    .unwrap_or_else(|p| p.into_inner());
                *guard
            });
            if finished {
                break;
            }
            if signal.is_none()
                && let Err(e) = py.check_signals()
            {
                flag.store(true, Ordering::SeqCst);
                signal = Some(e);
            }
        }
        worker.join().map_err(|_| {
            PyRuntimeError::new_err(
                "internal error (a defect of dyncontact: please report it): the solver thread panicked",
            )
        })
    })?;
    Ok((result, signal))
}
