//! What changes while a comparison runs, shared between the run and the page's clients
//! ([`Feed`]), and the watch that fills it ([`FeedWatch`]).

use crate::lab::compare::ComparisonWatch;
use crate::lab::outcome::Outcome;
use crate::lab::recorder::Point;
use crate::live::scene_view::LiveScene;
use radiosity_core::Real;
use radiosity_solvers::{State, Unit};
use serde_json::{Value, json};
use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// The shortest time between two live moments of one run, in seconds: five a second.
pub const FRAME_INTERVAL: Real = 0.2;
/// Moments kept for the page's slider are taken at steps spaced by this factor (and at each
/// run's end), at most [`KEPT_MOST`] a run.
pub const KEPT_FACTOR: Real = 1.25;
/// The most moments kept a run: past it every other one (but the first and last) is dropped.
pub const KEPT_MOST: usize = 64;
/// Points are kept at steps spaced by this factor, or [`POINT_INTERVAL`] seconds apart.
const POINT_FACTOR: Real = 1.01;
/// See [`POINT_FACTOR`].
const POINT_INTERVAL: Real = 0.05;

/// One run's radiosity at one moment, as the page draws it.
#[derive(Debug)]
pub struct Frame {
    /// A number that grows with every frame of the feed.
    pub serial: u64,
    /// The point measured on this state (its step, cost and metrics).
    pub point: Point,
    /// The exposure [`crate::render`] would choose for it at the start camera.
    pub exposure: Real,
    /// The displayed radiosity, patch-major, as `f32`.
    pub values: Vec<f32>,
}

/// One run as the page knows it.
#[derive(Debug, Default)]
pub(crate) struct RunFeed {
    pub(crate) started: bool,
    pub(crate) points: Vec<Point>,
    pub(crate) latest: Option<Arc<Frame>>,
    pub(crate) kept: Vec<Arc<Frame>>,
    /// How it ended: termination and final figures, as JSON.
    pub(crate) end: Option<Value>,
}

/// The feed's state, under its lock.
#[derive(Debug, Default)]
pub(crate) struct FeedState {
    pub(crate) runs: Vec<RunFeed>,
    /// Set when the comparison has ended: its notes and what was written.
    pub(crate) done: Option<Value>,
    /// Grows with every change.
    pub(crate) version: u64,
}

/// A comparison's live record: the scene sent once, and what every run has shown so far.
pub struct Feed {
    /// What is sent once.
    pub scene: LiveScene,
    state: Mutex<FeedState>,
    changed: Condvar,
    serial: AtomicU64,
    /// Radiosity updates written to clients, and their bytes.
    pub(crate) sent: (AtomicU64, AtomicU64),
    closed: AtomicBool,
}

/// What clients were sent ([`Feed::sent`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sent {
    /// Radiosity updates written, over every client.
    pub updates: u64,
    /// Their bytes, as written (base64 in server-sent events).
    pub bytes: u64,
}

impl Feed {
    /// An empty feed over `scene`, for `runs` runs.
    pub fn new(scene: LiveScene, runs: usize) -> Arc<Feed> {
        let state = FeedState { runs: (0..runs).map(|_| RunFeed::default()).collect(), ..FeedState::default() };
        Arc::new(Feed {
            scene,
            state: Mutex::new(state),
            changed: Condvar::new(),
            serial: AtomicU64::new(0),
            sent: (AtomicU64::new(0), AtomicU64::new(0)),
            closed: AtomicBool::new(false),
        })
    }

    pub(crate) fn lock(&self) -> MutexGuard<'_, FeedState> {
        // A client thread that panicked while holding the lock left nothing half-written that
        // matters more than the run: go on with the state as it is.
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Changes the state and wakes every client.
    fn change(&self, f: impl FnOnce(&mut FeedState)) {
        let mut state = self.lock();
        f(&mut state);
        state.version += 1;
        drop(state);
        self.changed.notify_all();
    }

    /// Waits until the state's version passes `seen`, the feed closes, or `timeout` passes.
    pub(crate) fn wait<'a>(&'a self, seen: u64, timeout: Duration) -> MutexGuard<'a, FeedState> {
        let guard = self.lock();
        let (guard, _) = self
            .changed
            .wait_timeout_while(guard, timeout, |s| s.version == seen && !self.closed.load(Ordering::Relaxed))
            .unwrap_or_else(|e| e.into_inner());
        guard
    }

    /// Marks the comparison ended, with `summary` (its notes and what was written) for the page.
    pub fn finish(&self, summary: Value) {
        self.change(|s| s.done = Some(summary));
    }

    /// Wakes every client for the last time: the server is stopping.
    pub fn close(&self) {
        self.closed.store(true, Ordering::Relaxed);
        self.change(|_| {});
    }

    /// Whether [`Feed::close`] was called.
    pub fn closed(&self) -> bool {
        self.closed.load(Ordering::Relaxed)
    }

    /// What clients were sent so far.
    pub fn sent(&self) -> Sent {
        Sent { updates: self.sent.0.load(Ordering::Relaxed), bytes: self.sent.1.load(Ordering::Relaxed) }
    }

    /// A frame of `state` at `point`.
    fn frame(&self, point: &Point, state: &State) -> Arc<Frame> {
        let values: Vec<f32> = state.radiosity.iter().map(|&b| b as f32).collect();
        Arc::new(Frame {
            serial: self.serial.fetch_add(1, Ordering::Relaxed),
            point: *point,
            exposure: self.scene.exposure(&values),
            values,
        })
    }
}

/// A point as the page reads it: `[step, seconds, wall, e_rms, bound, std_error, cost in
/// each unit of [`Unit::ALL`]…]`, NaN as `null`.
pub(crate) fn point_json(p: &Point) -> Value {
    let mut row = vec![json!(p.step), number(p.cost.seconds()), number(p.wall), number(p.e_rms), number(p.bound)];
    row.push(number(p.std_error));
    row.extend(Unit::ALL.iter().map(|&u| json!(p.cost[u])));
    Value::Array(row)
}

/// A finite number, or `null` (JSON has no NaN or infinity).
pub(crate) fn number(x: Real) -> Value {
    if x.is_finite() { json!(x) } else { Value::Null }
}

/// Fills a [`Feed`] from a comparison ([`crate::Lab::compare_watched`]); `Break`s every run
/// once `stop` is set (Ctrl-C).
pub struct FeedWatch {
    feed: Arc<Feed>,
    stop: Arc<AtomicBool>,
    /// Per run: when the last live frame was taken, the next step to keep a frame at, and the
    /// next step and time to keep a point at.
    last_frame: Option<Instant>,
    next_kept: u64,
    next_point: (u64, Real),
}

impl FeedWatch {
    /// A watch that fills `feed` and ends the comparison once `stop` is set.
    pub fn new(feed: Arc<Feed>, stop: Arc<AtomicBool>) -> FeedWatch {
        FeedWatch { feed, stop, last_frame: None, next_kept: 0, next_point: (0, 0.0) }
    }

    /// The feed it fills.
    pub fn feed(&self) -> Arc<Feed> {
        self.feed.clone()
    }
}

impl ComparisonWatch for FeedWatch {
    fn begin(&mut self, index: usize, _name: &str) {
        self.last_frame = None;
        self.next_kept = 0;
        self.next_point = (0, 0.0);
        self.feed.change(|s| {
            if let Some(run) = s.runs.get_mut(index) {
                run.started = true;
            }
        });
    }

    fn point(&mut self, index: usize, point: &Point, state: &State) -> ControlFlow<()> {
        let step = state.step;
        let keep_point = step >= self.next_point.0 || point.wall >= self.next_point.1;
        let live = self.last_frame.is_none_or(|t| t.elapsed().as_secs_f64() >= FRAME_INTERVAL);
        let kept = step >= self.next_kept;
        if keep_point {
            self.next_point = (spaced(step, POINT_FACTOR), point.wall + POINT_INTERVAL);
        }
        let frame = (live || kept).then(|| {
            self.last_frame = Some(Instant::now());
            self.feed.frame(point, state)
        });
        if kept {
            self.next_kept = spaced(step, KEPT_FACTOR);
        }
        if keep_point || frame.is_some() {
            self.feed.change(|s| {
                let Some(run) = s.runs.get_mut(index) else { return };
                if keep_point {
                    run.points.push(*point);
                }
                if let Some(frame) = frame {
                    if kept {
                        keep(&mut run.kept, frame.clone());
                    }
                    run.latest = Some(frame);
                }
            });
        }
        if self.stop.load(Ordering::Relaxed) { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
    }

    fn end(&mut self, index: usize, outcome: &Outcome) {
        let last = outcome.points.last().copied();
        let frame = last.map(|p| self.feed.frame(&p, &outcome.state));
        let end = json!({
            "termination": outcome.termination.to_string(),
            "steps": outcome.state.step,
            "unit": outcome.state.cost.principal().key(),
            "last": last.as_ref().map(point_json),
        });
        self.feed.change(|s| {
            let Some(run) = s.runs.get_mut(index) else { return };
            if let Some(p) = last
                && run.points.last() != Some(&p)
            {
                run.points.push(p);
            }
            if let Some(frame) = frame {
                keep(&mut run.kept, frame.clone());
                run.latest = Some(frame);
            }
            run.end = Some(end);
        });
    }
}

/// The next step after `step` on a grid spaced by `factor`.
fn spaced(step: u64, factor: Real) -> u64 {
    ((step as Real * factor).ceil() as u64).max(step + 1)
}

/// Keeps `frame`, thinning `kept` to [`KEPT_MOST`].
fn keep(kept: &mut Vec<Arc<Frame>>, frame: Arc<Frame>) {
    if kept.last().is_some_and(|k| k.point.step == frame.point.step) {
        kept.pop();
    }
    kept.push(frame);
    if kept.len() > KEPT_MOST {
        let last = kept.len() - 1;
        let mut i = 0;
        kept.retain(|_| {
            i += 1;
            (i - 1) % 2 == 0 || i - 1 == last
        });
    }
}
