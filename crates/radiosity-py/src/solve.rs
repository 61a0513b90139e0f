//! `radiosity.solve(scene, solver, ...)`: one run of a built-in solver (or the reference) over
//! a backend, measured as `cargo xtask solve` measures it: its radiosity, its figures
//! (`stats`, the keys of the command's JSON `stats`) and its recorded points; for a solver
//! that samples transport, its rays and standard error too.

use crate::arrays::patch_major;
use crate::errors::{check_measurable, value_error};
use crate::form_factors::cache;
use crate::scene::Scene;
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use radiosity_core::Real;
use radiosity_eval::{
    Clock, ColumnCost, FinalMetrics, Lab, LabOptions, NoProgress, Point, RecordPlan, ReferenceKind, Transport,
};
use radiosity_ff::BackendSpec;
use radiosity_solvers::{SolverError, SolverRegistry, State, StopRules, Value};
use std::ops::ControlFlow;

/// How one run pays for its columns unless told: as `cargo xtask solve` does.
const ONE_RUN: ColumnCost = ColumnCost::Computed;

/// What a run left.
#[pyclass(frozen, module = "radiosity")]
pub struct Run {
    solver: String,
    backend: String,
    termination: String,
    state: State,
    last: FinalMetrics,
    record: Vec<(String, Value)>,
    points: Vec<Point>,
    /// With an `rms=` rule: where `e_rms` first fell to each power of ten.
    reached: Vec<(Real, Point)>,
    reference: (String, String),
    /// The clock of every seconds figure.
    clock: Clock,
    /// Where the rays went, when the solver samples transport.
    transport: Option<Transport>,
}

/// Runs `solver` (a built-in name, or `reference` for the exact solution) on `scene` over the
/// backend `ff` until `until` holds (a stop-rule list: `rms=1e-3`, `columns=2n`,
/// `residual=1e-6`, `time=10s`, comma-separated), measured against the reference `reference`
/// (`auto`, `matrix`, `shooting` or `none`), with the GIL released while it runs. `columns`
/// says how the run pays for its columns, and so which clock its seconds, its `time=` rule and
/// its timed group frequencies read (`stats["clock"]`): `computed` (the default, as `cargo
/// xtask solve`: every column computed, `measured` seconds) or `charged` (read from the stored
/// matrix of a `matrix` reference and each charged the backend's measured cost). `transport`
/// says where a solver that samples transport (`stochastic-jacobi`, `random-walk`) casts its
/// rays: `scene` (the default, through the scene's BVH) or `matrix` (the stored matrix of a
/// `matrix` reference, sampled exactly); such a solver stops on a `rays=`, `steps=`, `time=`
/// or `rms=` rule (`until="rays=1e7"`).
///
/// `callback(point)`, when given, is called with every recorded point, after every step and
/// on the initial state: a dict of `step`, `columns`, `products`, `rays`, `links`, `seconds`, `e_rms`,
/// `bound`, `std_error` (NaN where not known) and `radiosity` (`n × channels`). A true return value ends
/// the run there (`stats["termination"]` says so); an exception ends it and is raised again
/// from `solve`. Its time is not the run's.
#[pyfunction]
#[pyo3(signature = (
    scene, solver, ff = "analytic", until = "columns=2n", reference = "auto", callback = None, columns = None,
    transport = None
))]
#[allow(clippy::too_many_arguments)]
pub fn solve(
    py: Python<'_>,
    scene: &Scene,
    solver: &str,
    ff: &str,
    until: &str,
    reference: &str,
    callback: Option<Py<PyAny>>,
    columns: Option<&str>,
    transport: Option<&str>,
) -> PyResult<Run> {
    let spec = BackendSpec::parse(ff).map_err(value_error)?;
    let columns: ColumnCost = columns.map_or(Ok(ONE_RUN), str::parse).map_err(value_error)?;
    let transport: Transport = transport.map_or(Ok(Transport::default()), str::parse).map_err(value_error)?;
    // Built here to refuse a bad name before any work, and again inside the run: a solver
    // is not `Send`.
    let build = |name: &str| {
        SolverRegistry::builtin().build(name).map_err(|e| match e {
            SolverError::UnknownSolver { .. } => value_error(format!("{e};\n  or reference, the exact solution")),
            e => value_error(e),
        })
    };
    let built = (solver != "reference").then(|| build(solver)).transpose()?;
    let named = built.as_ref().map(|s| s.name());
    let kind: ReferenceKind = reference.parse().map_err(value_error)?;
    if named.is_none() && kind == ReferenceKind::None {
        return Err(value_error(
            "the solver reference needs a reference: use reference='auto', 'matrix' or 'shooting', not 'none'",
        ));
    }
    let rules = StopRules::parse(until).map_err(value_error)?;
    check_measurable(&rules, kind)?;
    if let Some(solver) = &built {
        radiosity_eval::check_rules(solver.as_ref(), &rules).map_err(value_error)?;
    }
    drop(built);
    let prepared = scene.prepared.clone();
    let solver = solver.to_string();
    let mut failure = None;
    let mut watch = |point: &Point, state: &State| match &callback {
        None => ControlFlow::Continue(()),
        Some(callback) => Python::attach(|py| match call_back(py, callback, point, state) {
            Ok(true) => ControlFlow::Break(()),
            Ok(false) => ControlFlow::Continue(()),
            Err(e) => {
                failure = Some(e);
                ControlFlow::Break(())
            }
        }),
    };
    let run = py.detach(|| {
        let mut built = named.map(|_| SolverRegistry::builtin().build(&solver)).transpose()?;
        let options = LabOptions::default()
            .with_cache(cache())
            .with_reference(kind)
            .with_columns(columns)
            .with_transport(transport);
        let lab = Lab::new(&prepared, &spec, options, &NoProgress)?;
        let chosen = (lab.chosen().kind.to_string(), lab.chosen().why.clone());
        let clock = lab.clock();
        let run = match built.as_mut() {
            None => {
                let state = lab.reference_state()?;
                let method = lab.reference().map(|r| r.method().to_string()).unwrap_or_default();
                Run {
                    state,
                    solver: "reference".into(),
                    backend: lab.backend().into(),
                    termination: format!("solved exactly: {method}"),
                    last: lab.reference_metrics()?,
                    record: Vec::new(),
                    points: Vec::new(),
                    reached: Vec::new(),
                    reference: chosen,
                    clock,
                    transport: None,
                }
            }
            Some(solver) => {
                let o =
                    lab.run_watched(solver.as_mut(), &rules, &RecordPlan::errors_only(), &NoProgress, &mut watch)?;
                let reached = if rules.needs_error() { o.reached_powers() } else { Vec::new() };
                Run {
                    record: o.record.iter().map(|(k, v)| (k.to_string(), v.clone())).collect(),
                    reached,
                    transport: (o.state.rays > 0).then(|| lab.transport()),
                    state: o.state,
                    solver: o.solver,
                    backend: lab.backend().into(),
                    termination: o.termination.to_string(),
                    last: o.last,
                    points: o.points,
                    reference: chosen,
                    clock,
                }
            }
        };
        Ok::<Run, Box<dyn std::error::Error + Send + Sync>>(run)
    });
    match failure {
        Some(e) => Err(e),
        None => run.map_err(value_error),
    }
}

/// Shows `callback` the point and its radiosity; whether it asked to stop.
fn call_back(py: Python<'_>, callback: &Py<PyAny>, point: &Point, state: &State) -> PyResult<bool> {
    let d = PyDict::new(py);
    d.set_item("step", point.step)?;
    d.set_item("columns", point.columns)?;
    d.set_item("products", point.products)?;
    d.set_item("rays", point.rays)?;
    d.set_item("links", point.links)?;
    d.set_item("seconds", point.seconds)?;
    d.set_item("e_rms", point.e_rms)?;
    d.set_item("bound", point.bound)?;
    d.set_item("std_error", point.std_error)?;
    d.set_item("radiosity", radiosity_array(py, state))?;
    callback.call1(py, (d,))?.is_truthy(py)
}

/// The state's radiosity as an `n × channels` array.
fn radiosity_array<'py>(py: Python<'py>, state: &State) -> Bound<'py, PyArray2<Real>> {
    patch_major(py, state.radiosity.clone(), state.channels)
}

#[pymethods]
impl Run {
    /// The radiosity, shape `(n, channels)`.
    #[getter]
    fn radiosity<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<Real>> {
        radiosity_array(py, &self.state)
    }

    /// The solver's name, parameters spelled out.
    #[getter]
    fn solver(&self) -> &str {
        &self.solver
    }

    /// The backend's canonical spec.
    #[getter]
    fn backend(&self) -> &str {
        &self.backend
    }

    /// The clock of every seconds figure of the run (`stats`, `points`): `measured` or
    /// `charged`.
    #[getter]
    fn clock(&self) -> &'static str {
        self.clock.name()
    }

    /// The rays the run cast (0 for a solver that does not sample transport).
    #[getter]
    fn rays(&self) -> u64 {
        self.state.rays
    }

    /// The solver's standard error of the final radiosity, relative as e_rms is (the spread of
    /// its independent replicates: a spread, not a bound), or `None` when the solver has none.
    #[getter]
    fn standard_error(&self) -> Option<Real> {
        self.last.standard_error
    }

    /// The run's figures, with the keys of `cargo xtask solve --json`'s `stats`: `clock` (of
    /// every seconds figure: `measured` or `charged`), `columns`,
    /// `columns_reused`, `products`, `steps`, `rays`, `links` (of a hierarchy, touched),
    /// `seconds`, `ff_seconds`, `group_seconds`,
    /// `e_rms`, `e_max`, `residual` and `residual_of` (which vector it is the residual of),
    /// `bound`, `standard_error` and `replicates` (a solver's error bar from its replicates),
    /// `transport` (where its rays went: `scene` or `matrix`, `None` without rays),
    /// `termination`, `reached` (with an `rms=` rule, where `e_rms` first fell to
    /// each power of ten), `record` (the solver's own figures) and `reference` (`kind`,
    /// `why`). Figures not known are `None`.
    #[getter]
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = &self.state;
        let d = PyDict::new(py);
        d.set_item("clock", self.clock.name())?;
        d.set_item("columns", s.columns)?;
        d.set_item("columns_reused", s.columns_reused)?;
        d.set_item("products", s.products)?;
        d.set_item("steps", s.step)?;
        d.set_item("rays", s.rays)?;
        d.set_item("links", s.links)?;
        d.set_item("seconds", s.ff_seconds + s.solve_seconds)?;
        d.set_item("ff_seconds", s.ff_seconds)?;
        d.set_item("group_seconds", s.group_seconds)?;
        d.set_item("e_rms", self.last.e_rms)?;
        d.set_item("e_max", self.last.e_max)?;
        let (residual, residual_of) = match (self.last.residual, self.last.solver_residual) {
            (Some(r), _) => (Some(r), Some("displayed radiosity")),
            (None, Some(r)) => (Some(r), Some("the solver's own (for shooting methods, the shot radiosity)")),
            (None, None) => (None, None),
        };
        d.set_item("residual", residual)?;
        d.set_item("residual_of", residual_of)?;
        d.set_item("bound", self.last.bound)?;
        d.set_item("standard_error", self.last.standard_error)?;
        d.set_item("replicates", self.last.replicates)?;
        d.set_item("transport", self.transport.map(|t| t.name()))?;
        d.set_item("termination", &self.termination)?;
        let reached = PyList::empty(py);
        for (e_rms, p) in &self.reached {
            let r = PyDict::new(py);
            r.set_item("e_rms", e_rms)?;
            r.set_item("steps", p.step)?;
            r.set_item("columns", p.columns)?;
            r.set_item("rays", p.rays)?;
            r.set_item("seconds", p.seconds)?;
            reached.append(r)?;
        }
        d.set_item("reached", reached)?;
        let record = PyDict::new(py);
        for (k, v) in &self.record {
            match v {
                Value::Count(c) => record.set_item(k, *c)?,
                Value::Real(r) => record.set_item(k, *r)?,
                other => record.set_item(k, other.to_string())?,
            }
        }
        d.set_item("record", record)?;
        let reference = PyDict::new(py);
        reference.set_item("kind", &self.reference.0)?;
        reference.set_item("why", &self.reference.1)?;
        d.set_item("reference", reference)?;
        Ok(d)
    }

    /// The recorded points as a dict of arrays: `step`, `columns`, `products`, `rays`, `links`,
    /// `seconds`, `e_rms`, `bound` and `std_error` (NaN where not known).
    #[getter]
    fn points<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        let column = |f: fn(&Point) -> Real| self.points.iter().map(f).collect::<Vec<Real>>();
        for (name, f) in [
            ("step", (|p: &Point| p.step as Real) as fn(&Point) -> Real),
            ("columns", |p| p.columns as Real),
            ("products", |p| p.products as Real),
            ("rays", |p| p.rays as Real),
            ("links", |p| p.links as Real),
            ("seconds", |p| p.seconds),
            ("e_rms", |p| p.e_rms),
            ("bound", |p| p.bound),
            ("std_error", |p| p.std_error),
        ] {
            d.set_item(name, PyArray1::from_vec(py, column(f)))?;
        }
        Ok(d)
    }

    fn __repr__(&self) -> String {
        format!("Run({} with {}: {})", self.solver, self.backend, self.termination)
    }
}
