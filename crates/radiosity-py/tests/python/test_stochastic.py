"""Solvers that sample transport from Python: `solve` with a `rays=` rule, their rays and
standard error on the `Run`, `transport=` choosing where the rays go, and a `Lab` comparison
that mixes them with a deterministic solver."""

import numpy as np
import pytest

import radiosity


def test_stochastic_jacobi_runs_to_a_rays_budget_with_its_standard_error(cornell):
    run = radiosity.solve(cornell, "stochastic-jacobi:seq=sobol", until="rays=2e5")
    stats = run.stats
    assert run.rays == stats["rays"] >= 200_000 and stats["columns"] == 0
    assert "rays" in stats["termination"] and stats["transport"] == "scene"
    assert stats["replicates"] == 4
    spread = run.standard_error
    assert spread == stats["standard_error"] and 0 < spread < 1
    # Every step recorded, with the rays so far and the spread (none on the initial state).
    points = run.points
    assert points["rays"][-1] == run.rays and np.all(np.diff(points["rays"]) > 0)
    assert np.isnan(points["std_error"][0]) and np.all(np.isfinite(points["std_error"][1:]))
    assert run.radiosity.shape == (cornell.n, cornell.channels)


def test_on_the_stored_matrix_the_estimate_is_within_its_standard_errors_of_the_reference(cornell):
    # Sampling the stored matrix, the solver estimates the very system the reference solves:
    # its e_rms is of the size of its standard error (their squares have the same
    # expectation). 3 standard errors leave room for the spread of 4 replicates at a fixed
    # seed.
    run = radiosity.solve(cornell, "stochastic-jacobi:seed=5", until="rays=3e5", transport="matrix")
    stats = run.stats
    assert stats["transport"] == "matrix" and stats["reference"]["kind"] == "matrix"
    assert stats["e_rms"] <= 3 * stats["standard_error"], stats
    # A deterministic solver has neither rays nor a standard error.
    pr = radiosity.solve(cornell, "pr", until="columns=n")
    assert pr.rays == 0 and pr.standard_error is None and pr.stats["transport"] is None


def test_misuses_are_value_errors_before_any_work(cornell):
    with pytest.raises(ValueError, match="spends no columns, products or links"):
        radiosity.solve(cornell, "stochastic-jacobi")
    with pytest.raises(ValueError, match="scene or matrix"):
        radiosity.solve(cornell, "stochastic-jacobi", until="rays=1e4", transport="nowhere")
    with pytest.raises(ValueError, match="keeps none"):
        radiosity.solve(cornell, "stochastic-jacobi", until="rays=1e4", transport="matrix", reference="none")


def test_a_lab_compares_deterministic_and_stochastic_solvers_in_one_table(cornell, tmp_path):
    lab = radiosity.Lab(cornell, transport="matrix")
    comparison = lab.compare(["pr", "stochastic-jacobi"], until="columns=n,rays=5e4")
    table = comparison.table()
    solvers = np.array(table["solver"])
    pr, sj = solvers == "pr", solvers == "stochastic-jacobi"
    assert pr.any() and sj.any()
    assert np.all(table["rays"][pr] == 0) and np.all(np.isnan(table["std_error"][pr]))
    assert table["rays"][sj][-1] >= 50_000 and np.isfinite(table["std_error"][sj][-1])
    assert "std error" in comparison.summary().splitlines()[0]
    names = {p.name for p in comparison.write(tmp_path / "mixed")}
    assert {"e_rms-rays.svg", "e_rms-seconds.svg", "convergence.csv"} <= names
