//! `scene.form_factors(spec)`: a form-factor backend's columns, rows and products as numpy
//! arrays, each computed in Rust with the GIL released.
//!
//! A column backend borrows its scene (the analytic backend reads the scene's patches and BVH
//! in place), so the two are kept together in one [`self_cell`]: the scene's `Arc` and the
//! backend built on it. A stored matrix (`matrix`) is held as the lab holds it
//! ([`radiosity_eval::FormFactors`]), whose product is one parallel pass over its entries.

use crate::errors::{check_patch, value_error};
use numpy::ndarray::{Array2, ShapeBuilder};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArrayDyn, PyReadonlyArray1, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::prelude::*;
use radiosity_core::{ColumnSource, LinearSystem, Real, operator};
use radiosity_eval::exchange::{SparseColumns, write_files};
use radiosity_eval::{CACHE_DIR_VAR, Cache, NoProgress, backend, obtain_matrix};
use radiosity_ff::{BackendSpec, FormFactorBackend};
use radiosity_geom::PreparedScene;
use radiosity_solvers::Problem;
use rayon::prelude::*;
use self_cell::self_cell;
use std::sync::Arc;

/// A built backend borrowing its scene.
type BuiltBackend<'a> = Box<dyn FormFactorBackend + 'a>;

self_cell!(
    /// A backend with the scene it borrows.
    struct SceneBackend {
        owner: Arc<PreparedScene>,
        #[not_covariant]
        dependent: BuiltBackend,
    }
);

/// Where the entries come from.
enum Source {
    /// A column backend with its scene.
    Columns(SceneBackend),
    /// A stored matrix.
    Matrix(radiosity_eval::FormFactors),
}

/// The form factors `F` of one backend on one scene.
#[pyclass(frozen, module = "radiosity")]
pub struct FormFactors {
    source: Source,
    /// The system of the scene (its areas give rows from columns by reciprocity).
    system: LinearSystem,
    /// The backend's canonical spec.
    spec: String,
}

/// The cache of stored matrices, references and hierarchical operators: `$RADIOSITY_CACHE_DIR`
/// when it is set, otherwise none (a Python session caches nothing unless asked to).
pub(crate) fn cache() -> Option<Cache> {
    std::env::var_os(CACHE_DIR_VAR).filter(|d| !d.is_empty()).map(Cache::at)
}

impl FormFactors {
    /// The stored matrix's non-zero entries, or the error saying that this backend stores none.
    fn stored(&self) -> PyResult<SparseColumns> {
        match &self.source {
            Source::Matrix(m) => Ok(SparseColumns::of(m.stored().expect("a matrix read as stored"))),
            Source::Columns(_) => Err(value_error(format!(
                "{} is not a stored matrix: take form_factors(\"matrix:of={}\"), assembled where it fits the memory budget",
                self.spec, self.spec
            ))),
        }
    }

    /// Builds the backend `spec` on `prepared` (whose system is `system`), with the GIL
    /// released.
    pub(crate) fn build(
        py: Python<'_>,
        prepared: Arc<PreparedScene>,
        system: LinearSystem,
        spec: &str,
    ) -> PyResult<FormFactors> {
        let parsed = BackendSpec::parse(spec).map_err(value_error)?;
        let cache = cache();
        let source = py
            .detach(|| match parsed.stores() {
                Some(_) => obtain_matrix(&prepared, &parsed, cache.as_ref(), &NoProgress)
                    .map(|obtained| Source::Matrix(radiosity_eval::FormFactors::from_stored(obtained.matrix))),
                None => SceneBackend::try_new(prepared, |p| backend(p, &parsed, cache.as_ref(), &NoProgress))
                    .map(Source::Columns),
            })
            .map_err(value_error)?;
        Ok(FormFactors { source, system, spec: parsed.canonical() })
    }

    /// The number of patches.
    fn len(&self) -> usize {
        self.system.len()
    }

    /// Runs `f` on the backend.
    fn with<R>(&self, f: impl FnOnce(&dyn ColumnSource) -> R) -> R {
        match &self.source {
            Source::Columns(cell) => cell.with_dependent(|_, backend| f(backend)),
            Source::Matrix(m) => f(m),
        }
    }
}

#[pymethods]
impl FormFactors {
    /// The number of patches: `F` is `n × n`.
    #[getter]
    fn n(&self) -> usize {
        self.len()
    }

    /// The backend's canonical spec, every parameter spelled out.
    #[getter]
    fn spec(&self) -> &str {
        &self.spec
    }

    /// Column `j` of `F`: `F_ij` for every receiver `i`, shape `(n,)`.
    fn column<'py>(&self, py: Python<'py>, j: usize) -> PyResult<Bound<'py, PyArray1<Real>>> {
        let j = check_patch(j, self.len())?;
        let mut column = vec![0.0; self.len()];
        py.detach(|| self.with(|b| b.fill_column(j, &mut column)));
        Ok(column.into_pyarray(py))
    }

    /// Row `i` of `F`: `F_ij` for every sender `j`, shape `(n,)`. Backends that give rows
    /// exactly give them; the others give column `i` turned by reciprocity,
    /// `F_ij = F_ji A_j / A_i`, as a solver's rows are (`exact_rows`).
    fn row<'py>(&self, py: Python<'py>, i: usize) -> PyResult<Bound<'py, PyArray1<Real>>> {
        let i = check_patch(i, self.len())?;
        let mut row = vec![0.0; self.len()];
        py.detach(|| self.with(|b| Problem::new(&self.system, b).map(|problem| problem.row(i, &mut row))))
            .map_err(value_error)?;
        Ok(row.into_pyarray(py))
    }

    /// Whether `row` gives the matrix's rows exactly rather than columns turned by
    /// reciprocity.
    #[getter]
    fn exact_rows(&self) -> bool {
        match &self.source {
            Source::Columns(cell) => cell.with_dependent(|_, backend| backend.serves_rows()),
            Source::Matrix(_) => true,
        }
    }

    /// The columns `js` of `F` as an `n × len(js)` array (column-major), computed in
    /// parallel on the Rust thread pool with the GIL released.
    fn columns<'py>(&self, py: Python<'py>, js: PyReadonlyArray1<'py, i64>) -> PyResult<Bound<'py, PyArray2<Real>>> {
        let n = self.len();
        let js = js
            .as_array()
            .iter()
            .map(|&j| {
                usize::try_from(j)
                    .map_err(|_| value_error(format!("patch {j} is negative")))
                    .and_then(|j| check_patch(j, n))
            })
            .collect::<PyResult<Vec<usize>>>()?;
        let values = py.detach(|| {
            self.with(|b| {
                let mut values = vec![0.0; n * js.len()];
                values.par_chunks_mut(n.max(1)).zip(&js).for_each(|(column, &j)| b.fill_column(j, column));
                values
            })
        });
        let array = Array2::from_shape_vec((n, js.len()).f(), values).expect("n × len(js) values");
        Ok(array.into_pyarray(py))
    }

    /// The product `F x` for `x` of shape `(n,)` or `(n, k)` (each column of `x` a vector),
    /// in the shape of `x`: the backend's own product where it has one (a stored matrix's,
    /// the hierarchical operator's), else the columns where `x` is not zero.
    fn multiply<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArrayDyn<'py, Real>,
    ) -> PyResult<Bound<'py, PyArrayDyn<Real>>> {
        let n = self.len();
        let shape = x.shape().to_vec();
        let k = match shape.as_slice() {
            [rows] if *rows == n => 1,
            [rows, k] if *rows == n && *k > 0 => *k,
            _ => return Err(value_error(format!("x has shape {shape:?}; F x takes ({n},) or ({n}, k)"))),
        };
        // Patch-major, as the workspace's products take it: `x[i, c]` at `i·k + c`.
        let flat: Vec<Real> = x.as_array().iter().copied().collect();
        let out = py.detach(|| {
            let mut out = vec![0.0; n * k];
            self.with(|b| operator::multiply(b, &flat, k, &mut out));
            out
        });
        let array = numpy::ndarray::ArrayD::from_shape_vec(shape, out).expect("the shape of x");
        Ok(array.into_pyarray(py))
    }

    /// The stored matrix (`form_factors("matrix:...")`) as a `scipy.sparse.csc_array`: exactly
    /// the entries (rounded to `f32`, as stored) that solvers read and the `matrix` reference
    /// solves. Other backends raise `ValueError`: their matrix is `matrix:of=SPEC`, which is
    /// assembled only where it fits the memory budget.
    fn to_scipy<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let f = self.stored()?;
        let (n, indptr, indices, values) = (f.n, f.indptr, f.indices, f.values);
        let arrays = (values.into_pyarray(py), indices.into_pyarray(py), indptr.into_pyarray(py));
        py.import("scipy.sparse")?.getattr("csc_array")?.call1((arrays, (n, n)))
    }

    /// Writes the stored matrix with the scene's areas, emissions and reflectivities to `path`
    /// as `cargo xtask ff --out` does: `.mtx` (Matrix Market, the patches in `.patches.mtx`
    /// beside it) or `.npz` (NumPy, `F` as `scipy.sparse.load_npz` reads it); the paths
    /// written. `radiosity.read_system(path)` reads them back.
    fn write<'py>(&self, py: Python<'py>, path: std::path::PathBuf) -> PyResult<Vec<std::path::PathBuf>> {
        let f = self.stored()?;
        let comments = [format!("form factors F, backend {}", self.spec)];
        py.detach(|| write_files(&path, &f, &self.system, &comments)).map_err(value_error)
    }

    /// `F` as a `scipy.sparse.linalg.LinearOperator`, its products this backend's
    /// (`multiply`).
    fn as_linear_operator<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        slf.py().import("radiosity.operators")?.call_method1("form_factor_operator", (slf,))
    }

    fn __repr__(&self) -> String {
        format!("FormFactors({}: {} patches)", self.spec, self.len())
    }
}
