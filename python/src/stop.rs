//! Ctrl-C inside one long library call: the library asks a stop hook between its solves
//! ([`morphkit::springs::PhysicalBlend::prepare_interactive_until`]), and the hook given here
//! checks for signals on the calling thread, the only one where Python runs its handlers.

use crate::blend::lock;
use crate::errors::{IntoPyResult, Kind};
use morphkit::springs::BlendError;
use pyo3::prelude::*;
use std::sync::Mutex;

/// Runs `work` with the GIL released, handing it a stop hook that checks for signals
/// (`PyErr_CheckSignals`, taking the GIL for that moment) when the library asks from this
/// thread; from its other threads the hook says "go on" (they stop once this thread's answer
/// is "stop"). A signal handler that raised (Ctrl-C: `KeyboardInterrupt`) stops the work,
/// and its exception is what this returns, not the library's [`BlendError::Stopped`];
/// other library errors are `BlendError`s.
pub(crate) fn with_signal_checks<R: Send>(
    py: Python<'_>,
    work: impl FnOnce(&(dyn Fn() -> bool + Sync)) -> Result<R, BlendError> + Send,
) -> PyResult<R> {
    let caller = std::thread::current().id();
    let raised: Mutex<Option<PyErr>> = Mutex::new(None);
    let stop = || {
        if std::thread::current().id() != caller {
            return false;
        }
        match Python::attach(|py| py.check_signals()) {
            Ok(()) => false,
            Err(e) => {
                *lock(&raised) = Some(e);
                true
            }
        }
    };
    let result = py.detach(|| work(&stop));
    if let Some(e) = lock(&raised).take() {
        return Err(e);
    }
    result.py(Kind::Blend)
}
