//! `radiosity.load(spec)` and the `Scene`: a prepared scene (loaded, its BVH built, analysed)
//! with its patches' areas, reflectivities, emissions, centroids and normals as numpy arrays.

use crate::arrays::patch_major;
use crate::errors::value_error;
use crate::form_factors::FormFactors;
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use radiosity_core::{LinearSystem, Real};
use radiosity_geom::PreparedScene;
use std::sync::Arc;

/// A scene as the command line loads it (`--scene`), with its linear system.
#[pyclass(frozen, module = "radiosity")]
pub struct Scene {
    /// The prepared scene, shared with the form factors built on it.
    pub(crate) prepared: Arc<PreparedScene>,
    /// The system `(I − diag(ρ) F) B = E`: areas, reflectivities and emissions.
    pub(crate) system: LinearSystem,
    /// The spec it was loaded from.
    spec: String,
}

/// Loads and prepares the scene `spec`: a built-in name with `:key=value` parameters, or a
/// `.gltf`, `.glb` or `.mgf` path, as `--scene` takes it. Its load warnings are in
/// `Scene.warnings`.
#[pyfunction]
pub fn load(py: Python<'_>, spec: &str) -> PyResult<Scene> {
    let prepared = py.detach(|| PreparedScene::load(spec)).map_err(value_error)?;
    let system = LinearSystem::from_scene(prepared.scene());
    Ok(Scene { prepared: Arc::new(prepared), system, spec: spec.to_string() })
}

#[pymethods]
impl Scene {
    /// The number of patches.
    #[getter]
    fn n(&self) -> usize {
        self.system.len()
    }

    /// The number of channels: 1 (grey) or 3 (RGB).
    #[getter]
    fn channels(&self) -> usize {
        self.system.channels().count()
    }

    /// The spec the scene was loaded from.
    #[getter]
    fn spec(&self) -> &str {
        &self.spec
    }

    /// The patches' areas, shape `(n,)`.
    #[getter]
    fn areas<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<Real>> {
        PyArray1::from_slice(py, self.system.areas())
    }

    /// The patches' reflectivities, shape `(n, channels)`.
    #[getter]
    fn reflectivity<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<Real>> {
        patch_major(py, self.system.reflectivities().to_vec(), self.channels())
    }

    /// The patches' emissions, shape `(n, channels)`.
    #[getter]
    fn emission<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<Real>> {
        patch_major(py, self.system.emissions().to_vec(), self.channels())
    }

    /// The patches' centroids, shape `(n, 3)`.
    #[getter]
    fn centroids<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<Real>> {
        let values = self.prepared.scene().patches().iter().flat_map(|p| p.centroid().to_array()).collect();
        patch_major(py, values, 3)
    }

    /// The patches' unit normals, shape `(n, 3)`.
    #[getter]
    fn normals<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<Real>> {
        let values = self.prepared.scene().patches().iter().flat_map(|p| p.normal().to_array()).collect();
        patch_major(py, values, 3)
    }

    /// What the analysis left out of the pipeline because the scene does not need it (the
    /// phrases `cargo xtask scenes --explain` prints); empty when every stage is needed.
    #[getter]
    fn left_out(&self) -> Vec<String> {
        self.prepared.report().left_out
    }

    /// The warnings of loading the scene (each names its file), as the command line prints them.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.prepared.loaded.warnings.iter().map(ToString::to_string).collect()
    }

    /// The form factors of the backend `spec` (`analytic`, `hemicube`, `montecarlo`,
    /// `hierarchical` or `matrix`, with `:key=value` parameters, as `--ff` takes it). Stored
    /// matrices and hierarchical operators are read from and written to the cache in
    /// `$RADIOSITY_CACHE_DIR` when that is set.
    #[pyo3(signature = (spec = "analytic"))]
    fn form_factors(slf: &Bound<'_, Self>, spec: &str) -> PyResult<FormFactors> {
        let scene = slf.get();
        FormFactors::build(slf.py(), scene.prepared.clone(), scene.system.clone(), spec)
    }

    /// `I − diag(ρ_c) F` of channel `channel` (which may be left out on a grey scene) as a
    /// `scipy.sparse.linalg.LinearOperator`, its products those of `ff`.
    #[pyo3(signature = (ff, channel = None))]
    fn operator<'py>(
        slf: &Bound<'py, Self>,
        ff: &Bound<'py, FormFactors>,
        channel: Option<usize>,
    ) -> PyResult<Bound<'py, PyAny>> {
        slf.py().import("radiosity.operators")?.call_method1("system_operator", (slf, ff, channel))
    }

    fn __repr__(&self) -> String {
        format!("Scene({:?}: {} patches, {} channels)", self.spec, self.n(), self.channels())
    }
}
