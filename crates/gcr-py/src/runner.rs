//! Long work with the GIL released, and its progress in Python.
//!
//! [`run`] hands the work to a worker thread and waits on the calling thread with the GIL
//! released, waking every [`TICK`]: then (holding the GIL) it hands the latest progress event to
//! the Python callback, at most ten times a second and once more at the end, and checks for
//! signals (Ctrl-C). The callback thus runs on the thread that called gcr, as Python code
//! expects. When the callback raises (or a signal handler does, as Ctrl-C's does), the work is
//! told to stop: the next progress report of the solve or the gathers unwinds the worker with a
//! private payload (no panic message: `resume_unwind` runs no panic hook), rayon carries it out of
//! its pool, and [`run`] raises the callback's exception. Work that reports nothing more (the
//! last steps of a write) runs to its end, and the exception is raised then.

use gcr::{GatherProgress, Progress};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::panic::{AssertUnwindSafe, catch_unwind, resume_unwind};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::time::Duration;

/// How often the calling thread wakes to report progress and check signals: at most ten
/// callbacks a second.
const TICK: Duration = Duration::from_millis(100);

/// Stack of the worker thread: as the main thread's, so that deep recursion in the solver
/// behaves as in the program.
const WORKER_STACK: usize = 8 << 20;

/// A progress event: the training of the networks, or a gather at output points.
#[derive(Clone, Copy, Debug)]
enum Event {
    Solve(Progress),
    Gather(GatherProgress),
}

/// The unwinding payload that stops the work when Python asked it to.
struct Aborted;

/// What the worker and the calling thread share.
#[derive(Default)]
pub(crate) struct Monitor {
    /// The latest event not yet handed to Python.
    latest: Mutex<Option<Event>>,
    /// The work has ended (returned or unwound).
    finished: Mutex<bool>,
    woken: Condvar,
    /// Python asked the work to stop.
    abort: AtomicBool,
}

impl Monitor {
    /// Unwinds the worker when Python asked the work to stop; otherwise records `event`.
    fn post(&self, event: Event) {
        if self.abort.load(Ordering::Relaxed) {
            resume_unwind(Box::new(Aborted));
        }
        *self.latest.lock().unwrap_or_else(|e| e.into_inner()) = Some(event);
    }

    /// The observer of a solve (`gcr::solve_for_outputs`).
    pub(crate) fn solve_observer(&self) -> impl FnMut(&Progress) + '_ {
        move |p| self.post(Event::Solve(*p))
    }

    /// Runs `f` with the gathers it starts reporting here ([`gcr::observe_gathers`]).
    pub(crate) fn observing<R>(self: &Arc<Self>, f: impl FnOnce() -> R) -> R {
        let me = Arc::clone(self);
        gcr::observe_gathers(move |p: &GatherProgress| me.post(Event::Gather(*p)), f)
    }

    /// Waits up to `timeout` for the work to end; whether it has.
    fn wait(&self, timeout: Duration) -> bool {
        let finished = self.finished.lock().unwrap_or_else(|e| e.into_inner());
        if *finished {
            return true;
        }
        let (finished, _) =
            (self.woken.wait_timeout(finished, timeout)).unwrap_or_else(|e| e.into_inner());
        *finished
    }

    fn take(&self) -> Option<Event> {
        self.latest.lock().unwrap_or_else(|e| e.into_inner()).take()
    }

    fn set_finished(&self) {
        *self.finished.lock().unwrap_or_else(|e| e.into_inner()) = true;
        self.woken.notify_all();
    }
}

/// Marks the work finished when dropped: on return and on unwinding.
struct FinishOnDrop<'a>(&'a Monitor);

impl Drop for FinishOnDrop<'_> {
    fn drop(&mut self) {
        self.0.set_finished();
    }
}

/// Runs `work` on a worker thread with the GIL released (module docs); `progress`, when given,
/// is called with a dict per event ([`event_dict`]). Raises the callback's exception (or a
/// signal's, e.g. `KeyboardInterrupt`) when it stopped the work; a panic of the work is resumed
/// here (PyO3 raises it as `PanicException`).
pub(crate) fn run<T: Send>(
    py: Python<'_>,
    progress: Option<&Bound<'_, PyAny>>,
    work: impl FnOnce(&Arc<Monitor>) -> T + Send,
) -> PyResult<T> {
    let monitor = Arc::new(Monitor::default());
    let mut failure: Option<PyErr> = None;
    let outcome = std::thread::scope(|scope| {
        let worker = std::thread::Builder::new()
            .name("gcr".into())
            .stack_size(WORKER_STACK)
            .spawn_scoped(scope, || {
                let _finish = FinishOnDrop(&monitor);
                catch_unwind(AssertUnwindSafe(|| work(&monitor)))
            })
            .expect("a worker thread starts");
        loop {
            let finished = py.detach(|| monitor.wait(TICK));
            if failure.is_none() {
                failure = deliver(py, &monitor, progress).err();
                if failure.is_some() {
                    monitor.abort.store(true, Ordering::Relaxed);
                }
            }
            if finished {
                break;
            }
        }
        worker.join().expect("the worker catches its unwinding")
    });
    match (outcome, failure) {
        (Ok(_) | Err(_), Some(e)) => Err(e),
        (Ok(value), None) => Ok(value),
        (Err(payload), None) => resume_unwind(payload),
    }
}

/// Hands the latest event to the callback, then checks for signals.
fn deliver(py: Python<'_>, monitor: &Monitor, progress: Option<&Bound<'_, PyAny>>) -> PyResult<()> {
    if let (Some(event), Some(callback)) = (monitor.take(), progress) {
        callback.call1((event_dict(py, &event)?,))?;
    }
    py.check_signals()
}

/// The dict a progress callback gets: `phase` (`training`, `final` while the networks train;
/// `mesh`, `refinement`, `probes`, `pixels` or `gather` while B is gathered at output points),
/// `elapsed` seconds, and for gathers `points`, `rays` per point, `error` (the estimated
/// relative error bound, None before the first round ends), `target`, `done` (share of the
/// predicted work) and `eta` (seconds left, None until predictable); for the training
/// `kernel_cells`, `kernel_budget`, `shading_cells`, `samples` and `fem_steps`. Keys that do not
/// apply are None.
fn event_dict<'py>(py: Python<'py>, event: &Event) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let none = py.None();
    let gather_keys = ["points", "rays", "error", "target", "done", "eta"];
    let solve_keys = [
        "kernel_cells",
        "kernel_budget",
        "shading_cells",
        "samples",
        "fem_steps",
    ];
    for key in gather_keys.iter().chain(&solve_keys) {
        d.set_item(key, &none)?;
    }
    match event {
        Event::Solve(p) => {
            d.set_item("stage", "solve")?;
            d.set_item("phase", p.phase)?;
            d.set_item("elapsed", p.elapsed)?;
            d.set_item("kernel_cells", p.kernel_cells)?;
            d.set_item("kernel_budget", p.kernel_budget)?;
            d.set_item("shading_cells", p.shading_cells)?;
            d.set_item("samples", p.samples)?;
            d.set_item("fem_steps", p.fem_steps)?;
        }
        Event::Gather(p) => {
            d.set_item("stage", "gather")?;
            d.set_item("phase", p.phase)?;
            d.set_item("elapsed", p.elapsed)?;
            d.set_item("points", p.points)?;
            d.set_item("rays", p.rays)?;
            d.set_item("error", p.error)?;
            d.set_item("target", p.target)?;
            d.set_item("done", p.done)?;
            d.set_item("eta", p.remaining)?;
        }
    }
    Ok(d)
}
