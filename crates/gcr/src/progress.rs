//! Progress of the output gathers (the mesh's vertices, its refinement, probes, pixels), for a
//! caller that shows it: [`observe_gathers`] runs a closure with an observer that each gather to a
//! target error calls as its work goes, with the phase, the points, the rays, the error so far
//! and an estimate of the time left.
//!
//! The estimate of the time left: the work of a gather is points × rays per point, and its time is
//! proportional to it. Until the first round ends, the total is the points × the pilot's rays;
//! after a round, the rays per point the estimated error says are needed (variance ∝ 1/rays, as
//! the rounds themselves extrapolate), so time left = elapsed × (total − done) / done. It covers
//! the current gather; an output mesh's refinement levels are gathers of their own.

use std::cell::{Cell, RefCell};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::time::Instant;

/// Where an output gather stands (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GatherProgress {
    /// What is gathered: `"mesh"` (the output mesh's vertices), `"refinement"` (new vertices at
    /// shadow edges), `"probes"`, `"pixels"`, or `"gather"` for a direct library call.
    pub phase: &'static str,
    /// Points (or pixels) in this gather.
    pub points: usize,
    /// Rays per point of the rounds finished and the one running.
    pub rays: usize,
    /// The estimated relative error after the last finished round (its 90 % upper bound, what the
    /// rounds compare with the target); None before the first round ends.
    pub error: Option<f64>,
    /// The target error.
    pub target: f64,
    /// Share of the predicted work done, in [0, 1].
    pub done: f64,
    /// Seconds since this gather started.
    pub elapsed: f64,
    /// Seconds left, predicted (module docs); None until some work is done.
    pub remaining: Option<f64>,
}

/// An observer of gathers.
type Observer = Arc<dyn Fn(&GatherProgress) + Send + Sync>;

thread_local! {
    static OBSERVER: RefCell<Option<Observer>> = const { RefCell::new(None) };
    static PHASE: Cell<&'static str> = const { Cell::new("gather") };
}

/// Runs `f` with `observer` called by the gathers to a target error that `f` runs on this thread
/// (from any of the pool's threads, at most every 0.2 s and at the end of every round).
pub fn observe_gathers<R>(
    observer: impl Fn(&GatherProgress) + Send + Sync + 'static,
    f: impl FnOnce() -> R,
) -> R {
    struct Restore(Option<Observer>);
    impl Drop for Restore {
        fn drop(&mut self) {
            let previous = self.0.take();
            OBSERVER.with(|o| *o.borrow_mut() = previous);
        }
    }
    let previous = OBSERVER.with(|o| o.borrow_mut().replace(Arc::new(observer)));
    let _restore = Restore(previous);
    f()
}

/// Until the guard is dropped, the gathers on this thread are reported as `phase`.
#[must_use = "the phase lasts as long as the guard"]
pub(crate) fn phase(phase: &'static str) -> PhaseGuard {
    PhaseGuard(PHASE.with(|p| p.replace(phase)))
}

/// Restores the previous phase when dropped ([`phase`]).
pub(crate) struct PhaseGuard(&'static str);

impl Drop for PhaseGuard {
    fn drop(&mut self) {
        PHASE.with(|p| p.set(self.0));
    }
}

/// The progress of one gather to a target: created on the calling thread (which holds the
/// observer), updated from the pool's threads.
pub(crate) struct Reporter {
    observer: Option<Observer>,
    phase: &'static str,
    points: usize,
    target: f64,
    started: Instant,
    /// Work (points × rays) finished, in all rounds.
    done: AtomicUsize,
    /// Work predicted in all.
    total: AtomicUsize,
    /// Rays per point including the running round.
    rays: AtomicUsize,
    /// The last error bound (f64 bits; NaN: none yet).
    error: AtomicU64,
    /// Milliseconds since `started` of the last report.
    last: AtomicU64,
}

impl Reporter {
    /// A gather of `points` points to `target`, its first round of `rays` rays a point.
    pub(crate) fn new(points: usize, rays: usize, target: f64) -> Self {
        Self {
            observer: OBSERVER.with(|o| o.borrow().clone()),
            phase: PHASE.with(Cell::get),
            points,
            target,
            started: Instant::now(),
            done: AtomicUsize::new(0),
            total: AtomicUsize::new(points * rays),
            rays: AtomicUsize::new(rays),
            error: AtomicU64::new(f64::NAN.to_bits()),
            last: AtomicU64::new(0),
        }
    }

    /// `points` points finished `rays` rays each (a group of a round).
    pub(crate) fn finished(&self, points: usize, rays: usize) {
        if self.observer.is_none() {
            return;
        }
        self.done.fetch_add(points * rays, Ordering::Relaxed);
        let now = self.started.elapsed().as_millis() as u64;
        let last = self.last.load(Ordering::Relaxed);
        if now >= last + 200
            && self
                .last
                .compare_exchange(last, now, Ordering::Relaxed, Ordering::Relaxed)
                .is_ok()
        {
            self.report();
        }
    }

    /// A round ended with the error bound `error` after `rays` rays a point; the next (if any)
    /// brings them to `next` rays, of `needed` predicted in all.
    pub(crate) fn round(&self, error: f64, next: usize, needed: usize) {
        if self.observer.is_none() {
            return;
        }
        self.error.store(error.to_bits(), Ordering::Relaxed);
        self.rays.store(next, Ordering::Relaxed);
        let done = self.done.load(Ordering::Relaxed);
        self.total.store(
            (self.points * needed.max(next)).max(done),
            Ordering::Relaxed,
        );
        self.report();
    }

    /// The gather ended after `rays` rays a point with the error bound `error` (None: nothing
    /// measured); passes `values` through.
    pub(crate) fn last_round<T>(&self, error: Option<f64>, rays: usize, values: T) -> T {
        self.round(error.unwrap_or(0.0), rays, rays);
        values
    }

    fn report(&self) {
        let Some(observer) = &self.observer else {
            return;
        };
        let (done, total) = (
            self.done.load(Ordering::Relaxed) as f64,
            self.total.load(Ordering::Relaxed).max(1) as f64,
        );
        let elapsed = self.started.elapsed().as_secs_f64();
        let error = f64::from_bits(self.error.load(Ordering::Relaxed));
        observer(&GatherProgress {
            phase: self.phase,
            points: self.points,
            rays: self.rays.load(Ordering::Relaxed),
            error: (!error.is_nan()).then_some(error),
            target: self.target,
            done: (done / total).min(1.0),
            elapsed,
            remaining: (done > 0.0).then(|| elapsed * (total - done).max(0.0) / done),
        });
    }
}
