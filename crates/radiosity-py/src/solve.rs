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
use pyo3::types::PyDict;
use radiosity_core::Real;
use radiosity_eval::{
    ColumnCost, Lab, LabOptions, NoProgress, Point, RecordPlan, ReferenceKind, RunSummary, Transport,
};
use radiosity_ff::BackendSpec;
use radiosity_solvers::{SolverError, SolverRegistry, State, StopRules, Unit};
use std::ops::ControlFlow;

/// How one run pays for its columns unless told: as `cargo xtask solve` does.
const ONE_RUN: ColumnCost = ColumnCost::Computed;

/// What a run left.
#[pyclass(frozen, module = "radiosity")]
pub struct Run {
    backend: String,
    state: State,
    points: Vec<Point>,
    /// The run's figures, as `cargo xtask solve --json` gives them.
    summary: RunSummary,
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
        let run = match built.as_mut() {
            None => {
                let state = lab.reference_state()?;
                let summary = lab.reference_summary(&state)?;
                Run { backend: lab.backend().into(), state, points: Vec::new(), summary }
            }
            Some(solver) => {
                let o =
                    lab.run_watched(solver.as_mut(), &rules, &RecordPlan::errors_only(), &NoProgress, &mut watch)?;
                let summary = lab.summary(&o, rules.needs_error());
                Run { backend: lab.backend().into(), state: o.state, points: o.points, summary }
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
    for unit in Unit::ALL.into_iter().filter(|u| u.paid()) {
        d.set_item(unit.key(), point.cost[unit])?;
    }
    d.set_item("seconds", point.cost.seconds())?;
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
        &self.summary.solver
    }

    /// The backend's canonical spec.
    #[getter]
    fn backend(&self) -> &str {
        &self.backend
    }

    /// The clock of every seconds figure of the run (`stats`, `points`): `measured` or
    /// `charged`.
    #[getter]
    fn clock(&self) -> &str {
        self.summary.cost.clock.name()
    }

    /// The rays the run cast (0 for a solver that does not sample transport).
    #[getter]
    fn rays(&self) -> u64 {
        self.state.cost[Unit::Rays]
    }

    /// The solver's standard error of the final radiosity, relative as e_rms is (the spread of
    /// its independent replicates: a spread, not a bound), or `None` when the solver has none.
    #[getter]
    fn standard_error(&self) -> Option<Real> {
        self.summary.standard_error
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
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        // The one run summary, as the command line's JSON gives it, read by Python's json.
        let text = serde_json::to_string(&self.summary).map_err(|e| value_error(e.to_string()))?;
        py.import("json")?.call_method1("loads", (text,))
    }

    /// The recorded points as a dict of arrays: `step`, what the run had spent in every paid
    /// unit of cost (`columns`, `products`, `rays`, `links`), `seconds`, `e_rms`, `bound` and
    /// `std_error` (NaN where not known).
    #[getter]
    fn points<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        let column = |f: &dyn Fn(&Point) -> Real| PyArray1::from_vec(py, self.points.iter().map(f).collect());
        d.set_item("step", column(&|p| p.step as Real))?;
        for unit in Unit::ALL.into_iter().filter(|u| u.paid()) {
            d.set_item(unit.key(), column(&|p| p.cost[unit] as Real))?;
        }
        d.set_item("seconds", column(&|p| p.cost.seconds()))?;
        d.set_item("e_rms", column(&|p| p.e_rms))?;
        d.set_item("bound", column(&|p| p.bound))?;
        d.set_item("std_error", column(&|p| p.std_error))?;
        Ok(d)
    }

    fn __repr__(&self) -> String {
        format!("Run({} with {}: {})", self.summary.solver, self.backend, self.summary.termination)
    }
}
