//! `radiosity.Lab(scene, ff).compare([...])`: built-in solvers by name and solvers written in
//! Python in one comparison, each recorded, bounded, timed, tabled and plotted by the
//! workspace's own lab.
//!
//! A Python solver is an object with `step(problem, state)` (and, optionally, `name`, `kind`
//! — `"shot"`, `"gather"` or `"product"` —, `init(problem, state)`,
//! `residual_power(problem, state)` and `residual_bound(problem, state)`, which returns
//! `(d, e)` with `|r| ≤ ρ F |d| + |e|` elementwise, as [`ResidualBound`] states it, so the lab
//! certifies its runs as it does a built-in solver's). Inside the lab it is a [`Solver`] like any other, whose
//! calls are answered in Python. The lab runs on a worker thread (it holds the borrowed
//! problem, which never leaves it) while the calling thread runs Python: each call of the
//! solver is a message to the calling thread with the state's radiosity and unshot radiosity,
//! and every column, row or product the Python code asks of its `problem` is a message back
//! to the worker, which fetches it through the counted [`Problem`] and replies. So the
//! columns are counted and timed exactly as a built-in solver's are (a message costs
//! microseconds against the milliseconds of a column), and the state is copied to and from
//! numpy at each call (`O(n)`, the cost of one column's update). The time of the Python code
//! is the solver's time, as a built-in solver's arithmetic is.
//!
//! An exception raised by Python ends the comparison and is raised again from `compare`.

use crate::arrays::patch_major;
use crate::errors::{check_measurable, value_error};
use crate::form_factors::cache;
use crate::scene::Scene;
use numpy::{IntoPyArray, PyArray1, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use radiosity_core::Real;
use radiosity_eval::{ColumnCost, Comparison, Lab, LabOptions, NoProgress, ReferenceKind, Transport};
use radiosity_ff::BackendSpec;
use radiosity_solvers::{
    Problem, Record, ResidualBound, Solver, SolverError, SolverRegistry, State, StepKind, StopRules, Unit,
};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel};
use std::sync::{Arc, Mutex};

/// Which call of a Python solver the worker asks for.
#[derive(Clone, Copy, Debug)]
enum Call {
    Init,
    Step,
    Residual,
    Bound,
}

/// From the worker to the calling thread.
enum ToMain {
    /// Run `call` of solver `solver` on this state.
    Call { solver: usize, call: Call, radiosity: Vec<Real>, unshot: Vec<Real>, step: u64 },
    /// A column, a row or a product asked for.
    Reply(Vec<Real>),
    /// The comparison ended.
    Finished(Result<Box<Comparison>, String>),
}

/// From the calling thread to the worker.
enum ToWorker {
    Column(usize),
    Row(usize),
    Multiply(Vec<Real>),
    /// The call returned: the state as Python left it, and the residual power or the
    /// residual bound it stated.
    Done {
        radiosity: Vec<Real>,
        unshot: Vec<Real>,
        residual: Option<Real>,
        bound: Option<ResidualBound>,
    },
    /// The call raised (the exception is kept on the calling thread).
    Failed,
}

/// What a call of a Python solver gave back.
struct Answer {
    radiosity: Vec<Real>,
    unshot: Vec<Real>,
    residual: Option<Real>,
    bound: Option<ResidualBound>,
}

/// A Python solver inside the lab: its calls are answered by the calling thread.
struct PythonSolver {
    index: usize,
    name: String,
    kind: StepKind,
    has_init: bool,
    has_residual: bool,
    has_bound: bool,
    to_main: Sender<ToMain>,
    from_main: Arc<Mutex<Receiver<ToWorker>>>,
}

impl PythonSolver {
    /// Asks the calling thread to run `call` on `state`, serving its requests for columns,
    /// rows and products until it is done; the state as Python left it and the residual
    /// power it stated.
    fn call(&self, call: Call, problem: &Problem<'_>, state: &State) -> Result<Answer, SolverError> {
        let ended = || SolverError::BadParams(format!("{} ended without answering", self.name));
        let message = ToMain::Call {
            solver: self.index,
            call,
            radiosity: state.radiosity.clone(),
            unshot: state.unshot.clone(),
            step: state.step,
        };
        self.to_main.send(message).map_err(|_| ended())?;
        let from_main = self.from_main.lock().map_err(|_| ended())?;
        let (n, k) = (problem.n(), problem.channels());
        loop {
            let reply = match from_main.recv().map_err(|_| ended())? {
                ToWorker::Column(j) => {
                    let mut column = vec![0.0; n];
                    problem.column(j, &mut column);
                    column
                }
                ToWorker::Row(i) => {
                    let mut row = vec![0.0; n];
                    problem.row(i, &mut row);
                    row
                }
                ToWorker::Multiply(x) => {
                    let (mut out, mut column) = (vec![0.0; n * k], Vec::new());
                    problem.multiply(&x, &mut out, &mut column);
                    out
                }
                ToWorker::Done { radiosity, unshot, residual, bound } => {
                    return Ok(Answer { radiosity, unshot, residual, bound });
                }
                ToWorker::Failed => {
                    return Err(SolverError::BadParams(format!("{} raised an exception in Python", self.name)));
                }
            };
            self.to_main.send(ToMain::Reply(reply)).map_err(|_| ended())?;
        }
    }

    /// Runs `call` and takes the state Python left.
    fn call_updating(&mut self, call: Call, problem: &Problem<'_>, state: &mut State) -> Result<(), SolverError> {
        let answer = self.call(call, problem, state)?;
        state.radiosity = answer.radiosity;
        state.unshot = answer.unshot;
        Ok(())
    }
}

impl Solver for PythonSolver {
    fn name(&self) -> String {
        self.name.clone()
    }

    fn init(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<(), SolverError> {
        if self.has_init { self.call_updating(Call::Init, problem, state) } else { Ok(()) }
    }

    fn next_step(&mut self, problem: &Problem<'_>, state: &mut State) -> Result<Record, SolverError> {
        self.call_updating(Call::Step, problem, state)?;
        Ok(Record::new())
    }

    fn residual_power(&self, problem: &Problem<'_>, state: &State) -> Option<Real> {
        if !self.has_residual {
            return None;
        }
        self.call(Call::Residual, problem, state).ok().and_then(|a| a.residual)
    }

    fn residual_bound(&self, problem: &Problem<'_>, state: &State) -> Option<ResidualBound> {
        if !self.has_bound {
            return None;
        }
        self.call(Call::Bound, problem, state).ok().and_then(|a| a.bound)
    }

    fn step_kind(&self) -> StepKind {
        self.kind
    }
}

/// What the worker needs to build a solver: a built-in's name, or a Python solver's figures.
enum Entry {
    Builtin(String),
    Python { name: String, kind: StepKind, has_init: bool, has_residual: bool, has_bound: bool },
}

/// The step kind a Python solver names (`kind`), `shot` when it names none.
fn step_kind(object: &Bound<'_, PyAny>) -> PyResult<StepKind> {
    if !object.hasattr("kind")? {
        return Ok(StepKind::Shot);
    }
    match object.getattr("kind")?.extract::<String>()?.as_str() {
        "shot" => Ok(StepKind::Shot),
        "gather" => Ok(StepKind::Gather),
        "product" => Ok(StepKind::Product),
        other => Err(PyValueError::new_err(format!("a solver's kind is 'shot', 'gather' or 'product', not '{other}'"))),
    }
}

/// The problem a Python solver sees during one call: the system, and columns, rows and
/// products fetched and counted by the lab.
#[pyclass(frozen, name = "Problem", module = "radiosity")]
pub struct PyProblem {
    n: usize,
    channels: usize,
    areas: Vec<Real>,
    emission: Vec<Real>,
    reflectivity: Vec<Real>,
    link: Arc<Link>,
}

/// The calling thread's ends of the channels, and whether a call is under way.
struct Link {
    to_worker: Mutex<Sender<ToWorker>>,
    from_worker: Mutex<Receiver<ToMain>>,
    live: AtomicBool,
}

impl Link {
    /// Asks the worker for `request` during a call; its reply.
    fn ask(&self, py: Python<'_>, request: ToWorker) -> PyResult<Vec<Real>> {
        if !self.live.load(Ordering::SeqCst) {
            return Err(PyRuntimeError::new_err("the problem answers only during the call it was given to"));
        }
        let lost = || PyRuntimeError::new_err("the lab's run ended");
        self.to_worker.lock().map_err(|_| lost())?.send(request).map_err(|_| lost())?;
        let reply = py.detach(|| self.from_worker.lock().map_err(|_| ()).and_then(|r| r.recv().map_err(|_| ())));
        match reply {
            Ok(ToMain::Reply(values)) => Ok(values),
            _ => Err(lost()),
        }
    }
}

impl PyProblem {
    fn matrix<'py>(&self, py: Python<'py>, values: &[Real]) -> Bound<'py, numpy::PyArray2<Real>> {
        patch_major(py, values.to_vec(), self.channels)
    }

    fn patch(&self, index: usize) -> PyResult<usize> {
        crate::errors::check_patch(index, self.n)
    }
}

#[pymethods]
impl PyProblem {
    /// The number of patches.
    #[getter]
    fn n(&self) -> usize {
        self.n
    }

    /// The number of channels.
    #[getter]
    fn channels(&self) -> usize {
        self.channels
    }

    /// The patches' areas, `(n,)`.
    #[getter]
    fn areas<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<Real>> {
        PyArray1::from_slice(py, &self.areas)
    }

    /// The emissions `E`, `(n, channels)`.
    #[getter]
    fn emission<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray2<Real>> {
        self.matrix(py, &self.emission)
    }

    /// The reflectivities `ρ`, `(n, channels)`.
    #[getter]
    fn reflectivity<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray2<Real>> {
        self.matrix(py, &self.reflectivity)
    }

    /// Column `j` of `F`, counted as one column.
    fn column<'py>(&self, py: Python<'py>, j: usize) -> PyResult<Bound<'py, PyArray1<Real>>> {
        let j = self.patch(j)?;
        Ok(self.link.ask(py, ToWorker::Column(j))?.into_pyarray(py))
    }

    /// Row `i` of `F`, counted as one column (exact or by reciprocity, as for built-in
    /// solvers).
    fn row<'py>(&self, py: Python<'py>, i: usize) -> PyResult<Bound<'py, PyArray1<Real>>> {
        let i = self.patch(i)?;
        Ok(self.link.ask(py, ToWorker::Row(i))?.into_pyarray(py))
    }

    /// `F x` for `x` of shape `(n, channels)`: one product where the backend has its own,
    /// otherwise a column for each patch where `x` is not zero, counted.
    fn multiply<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArrayDyn<'py, Real>,
    ) -> PyResult<Bound<'py, numpy::PyArray2<Real>>> {
        if x.shape() != [self.n, self.channels] {
            return Err(value_error(format!(
                "x has shape {:?}; the problem multiplies ({}, {})",
                x.shape(),
                self.n,
                self.channels
            )));
        }
        let flat = x.as_array().iter().copied().collect();
        let out = self.link.ask(py, ToWorker::Multiply(flat))?;
        Ok(self.matrix(py, &out))
    }
}

/// The state's array `name` as Python left it, checked for its shape.
fn take(state: &Bound<'_, PyAny>, name: &str, n: usize, k: usize) -> PyResult<Vec<Real>> {
    let array = state.getattr(name)?;
    let array = array
        .cast::<numpy::PyArrayDyn<Real>>()
        .map_err(|_| value_error(format!("state.{name} is not a float64 numpy array")))?;
    if array.shape() != [n, k] {
        return Err(value_error(format!("state.{name} has shape {:?}; it must stay ({n}, {k})", array.shape())));
    }
    Ok(array.readonly().as_array().iter().copied().collect())
}

/// Runs one call of a Python solver; what goes back to the worker.
fn answer(
    py: Python<'_>,
    solver: &Bound<'_, PyAny>,
    call: Call,
    problem: &Bound<'_, PyProblem>,
    (radiosity, unshot, step): (Vec<Real>, Vec<Real>, u64),
) -> PyResult<ToWorker> {
    let (n, k) = (problem.get().n, problem.get().channels);
    let shape = |v: Vec<Real>| patch_major(py, v, k);
    let kwargs = PyDict::new(py);
    kwargs.set_item("radiosity", shape(radiosity))?;
    kwargs.set_item("unshot", shape(unshot))?;
    kwargs.set_item("step", step)?;
    let state = py.import("types")?.getattr("SimpleNamespace")?.call((), Some(&kwargs))?;
    let link = &problem.get().link;
    link.live.store(true, Ordering::SeqCst);
    let result = match call {
        Call::Init => solver.call_method1("init", (problem, &state)),
        Call::Step => solver.call_method1("step", (problem, &state)),
        Call::Residual => solver.call_method1("residual_power", (problem, &state)),
        Call::Bound => solver.call_method1("residual_bound", (problem, &state)),
    };
    link.live.store(false, Ordering::SeqCst);
    let result = result?;
    let residual = match call {
        Call::Residual => result.extract::<Option<Real>>()?,
        _ => None,
    };
    let bound = match call {
        Call::Bound if !result.is_none() => Some(residual_bound(&result, &problem.get().areas, k)?),
        _ => None,
    };
    Ok(ToWorker::Done {
        radiosity: take(&state, "radiosity", n, k)?,
        unshot: take(&state, "unshot", n, k)?,
        residual,
        bound,
    })
}

/// The bound a Python solver states as `(d, e)` or `(d, e, nonnegative)`: two
/// `(n, channels)` arrays with `|r| ≤ ρ F |d| + |e|` elementwise, and whether the residual is
/// known to be elementwise non-negative (`radiosity_solvers::ResidualBound`): their
/// area-weighted L1 norms per channel.
fn residual_bound(result: &Bound<'_, PyAny>, areas: &[Real], k: usize) -> PyResult<ResidualBound> {
    type Arrays<'py> = (PyReadonlyArrayDyn<'py, Real>, PyReadonlyArrayDyn<'py, Real>);
    let misshapen = || {
        value_error(
            "residual_bound returns (d, e) or (d, e, nonnegative), d and e float64 arrays of shape (n, channels), or None",
        )
    };
    let ((d, e), nonnegative) =
        match result.extract::<(PyReadonlyArrayDyn<'_, Real>, PyReadonlyArrayDyn<'_, Real>, bool)>() {
            Ok((d, e, nonnegative)) => ((d, e), nonnegative),
            Err(_) => (result.extract::<Arrays<'_>>().map_err(|_| misshapen())?, false),
        };
    let norms = |x: &PyReadonlyArrayDyn<'_, Real>, what: &str| -> PyResult<Vec<Real>> {
        if x.shape() != [areas.len(), k] {
            return Err(value_error(format!(
                "residual_bound's {what} has shape {:?}; it must be ({}, {k})",
                x.shape(),
                areas.len()
            )));
        }
        let mut norm = vec![0.0; k];
        for (idx, v) in x.as_array().iter().enumerate() {
            norm[idx % k] += areas[idx / k] * v.abs();
        }
        Ok(norm)
    };
    Ok(ResidualBound::new(norms(&d, "d")?, norms(&e, "e")?).with_nonnegative_residual(nonnegative))
}

/// Runs `solvers` (built-in names and Python solver objects) on `scene` over the backend `ff`
/// under `until`, measured against `reference`, their columns paid for as `columns` says
/// (`computed` or `charged`; by default as `cargo xtask compare`, computed), the rays of the
/// solvers that sample transport cast as `transport` says (`scene`, the default, or
/// `matrix`); the comparison.
#[pyfunction]
#[pyo3(signature = (
    scene, solvers, ff = "analytic", until = "columns=2n", reference = "auto", columns = None, transport = None
))]
#[allow(clippy::too_many_arguments)]
pub fn compare(
    py: Python<'_>,
    scene: &Scene,
    solvers: &Bound<'_, PyList>,
    ff: &str,
    until: &str,
    reference: &str,
    columns: Option<&str>,
    transport: Option<&str>,
) -> PyResult<PyComparison> {
    let spec = BackendSpec::parse(ff).map_err(value_error)?;
    let columns: ColumnCost = columns.map_or(Ok(ColumnCost::default()), str::parse).map_err(value_error)?;
    let transport: Transport = transport.map_or(Ok(Transport::default()), str::parse).map_err(value_error)?;
    let rules = StopRules::parse(until).map_err(value_error)?;
    let kind: ReferenceKind = reference.parse().map_err(value_error)?;
    check_measurable(&rules, kind)?;
    let registry = SolverRegistry::builtin();
    let mut entries = Vec::new();
    let mut objects = Vec::new();
    for item in solvers.iter() {
        if let Ok(name) = item.extract::<String>() {
            let solver = registry.build(&name).map_err(value_error)?;
            radiosity_eval::check_rules(solver.as_ref(), &rules).map_err(value_error)?;
            entries.push(Entry::Builtin(name));
            continue;
        }
        if !item.hasattr("step")? {
            return Err(value_error(format!(
                "{} is neither a solver's name nor an object with step(problem, state)",
                item.repr()?
            )));
        }
        let name = if item.hasattr("name")? {
            item.getattr("name")?.extract::<String>()?
        } else {
            item.get_type().name()?.to_string()
        };
        entries.push(Entry::Python {
            name,
            kind: step_kind(&item)?,
            has_init: item.hasattr("init")?,
            has_residual: item.hasattr("residual_power")?,
            has_bound: item.hasattr("residual_bound")?,
        });
        objects.push((entries.len() - 1, item.clone()));
    }
    let system = &scene.system;
    let (to_worker, from_main) = channel::<ToWorker>();
    let (to_main, from_worker) = channel::<ToMain>();
    let link = Arc::new(Link {
        to_worker: Mutex::new(to_worker),
        from_worker: Mutex::new(from_worker),
        live: AtomicBool::new(false),
    });
    let problem = Bound::new(
        py,
        PyProblem {
            n: system.len(),
            channels: system.channels().count(),
            areas: system.areas().to_vec(),
            emission: system.emissions().to_vec(),
            reflectivity: system.reflectivities().to_vec(),
            link: link.clone(),
        },
    )?;
    let prepared = scene.prepared.clone();
    let from_main = Arc::new(Mutex::new(from_main));
    let worker_to_main = to_main.clone();
    let worker = std::thread::spawn(move || {
        let run = || -> Result<Box<Comparison>, String> {
            let options = LabOptions::default()
                .with_cache(cache())
                .with_reference(kind)
                .with_columns(columns)
                .with_transport(transport);
            let lab = Lab::new(&prepared, &spec, options, &NoProgress).map_err(|e| e.to_string())?;
            let registry = SolverRegistry::builtin();
            let mut built: Vec<Box<dyn Solver>> = Vec::new();
            for (index, entry) in entries.into_iter().enumerate() {
                built.push(match entry {
                    Entry::Builtin(name) => registry.build(&name).map_err(|e| e.to_string())?,
                    Entry::Python { name, kind, has_init, has_residual, has_bound } => Box::new(PythonSolver {
                        index,
                        name,
                        kind,
                        has_init,
                        has_residual,
                        has_bound,
                        to_main: worker_to_main.clone(),
                        from_main: from_main.clone(),
                    }),
                });
            }
            lab.compare(built, &rules, &NoProgress).map(Box::new).map_err(|e| e.to_string())
        };
        let _ = worker_to_main.send(ToMain::Finished(run()));
    });
    drop(to_main);
    let mut raised: Option<PyErr> = None;
    let outcome = loop {
        let message = py.detach(|| link.from_worker.lock().map_err(|_| ()).and_then(|r| r.recv().map_err(|_| ())));
        match message {
            Ok(ToMain::Call { solver, call, radiosity, unshot, step }) => {
                let object = &objects.iter().find(|(i, _)| *i == solver).expect("a Python solver's index").1;
                let reply = if raised.is_some() {
                    ToWorker::Failed
                } else {
                    answer(py, object, call, &problem, (radiosity, unshot, step)).unwrap_or_else(|e| {
                        raised = Some(e);
                        ToWorker::Failed
                    })
                };
                let _ = link.to_worker.lock().map(|t| t.send(reply));
            }
            Ok(ToMain::Reply(_)) => {}
            Ok(ToMain::Finished(result)) => break result,
            Err(()) => break Err("the lab's worker ended without a result".to_string()),
        }
    };
    if worker.join().is_err() {
        return Err(PyRuntimeError::new_err("the lab's worker panicked"));
    }
    match (raised, outcome) {
        (Some(e), _) => Err(e),
        (None, Ok(comparison)) => Ok(PyComparison { comparison: *comparison }),
        (None, Err(message)) => Err(value_error(message)),
    }
}

/// A comparison's runs: its table, summary and report.
#[pyclass(frozen, name = "Comparison", module = "radiosity")]
pub struct PyComparison {
    comparison: Comparison,
}

#[pymethods]
impl PyComparison {
    /// The solvers' names, in order.
    #[getter]
    fn solvers(&self) -> Vec<String> {
        self.comparison.outcomes.iter().map(|o| o.solver.clone()).collect()
    }

    /// The clock of every seconds figure of the comparison (its table, summary, report and
    /// plots): `measured` or `charged`.
    #[getter]
    fn clock(&self) -> &'static str {
        self.comparison.clock.name()
    }

    /// The terminal summary `cargo xtask compare` prints.
    fn summary(&self) -> String {
        self.comparison.summary()
    }

    /// Writes `convergence.csv`, `report.md` and the plots into `dir`; the files written.
    fn write(&self, py: Python<'_>, dir: std::path::PathBuf) -> PyResult<Vec<std::path::PathBuf>> {
        py.detach(|| self.comparison.write(&dir)).map(|w| w.files).map_err(value_error)
    }

    /// Every recorded row of every run, as `convergence.csv` holds them: a dict of `solver`
    /// (a list of names), `clock` (the clock of the seconds, `measured` or `charged`) and numpy
    /// arrays `step`, `columns`, `products`, `rays`, `links`, `seconds`, `ff_seconds`, `e_rms`, `e_max`,
    /// `residual`, `bound` and `std_error` (the standard error of a solver whose answer is an
    /// estimate, NaN for the others).
    fn table<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let rows: Vec<_> = self.comparison.outcomes.iter().flat_map(|o| &o.rows).collect();
        let d = PyDict::new(py);
        d.set_item("solver", rows.iter().map(|r| r.solver.clone()).collect::<Vec<_>>())?;
        d.set_item("clock", self.comparison.clock.name())?;
        let column =
            |f: &dyn Fn(&radiosity_eval::TableRow) -> Real| PyArray1::from_vec(py, rows.iter().map(|r| f(r)).collect());
        d.set_item("step", column(&|r| r.step as Real))?;
        for unit in Unit::ALL.into_iter().filter(|u| u.paid()) {
            d.set_item(unit.key(), column(&|r| r.cost[unit] as Real))?;
        }
        d.set_item("seconds", column(&|r| r.cost.seconds()))?;
        d.set_item("ff_seconds", column(&|r| r.cost.ff_seconds))?;
        d.set_item("e_rms", column(&|r| r.e_rms))?;
        d.set_item("e_max", column(&|r| r.e_max))?;
        d.set_item("residual", column(&|r| r.residual))?;
        d.set_item("bound", column(&|r| r.bound))?;
        d.set_item("std_error", column(&|r| r.std_error))?;
        Ok(d)
    }
}
