"""Bad input raises a Python exception with the command line's one-sentence message, and
never ends the interpreter."""

import numpy as np
import pytest

import radiosity


def test_an_unknown_scene_is_a_value_error():
    with pytest.raises(ValueError, match="scene"):
        radiosity.load("no-such-scene")


def test_an_unknown_backend_is_a_value_error(cornell):
    with pytest.raises(ValueError, match="backend"):
        cornell.form_factors("radiance")


def test_an_unknown_solver_names_the_known_ones(cornell):
    with pytest.raises(ValueError, match="or reference, the exact solution"):
        radiosity.solve(cornell, "no-such-solver")


def test_a_bad_stop_rule_is_a_value_error(cornell):
    with pytest.raises(ValueError):
        radiosity.solve(cornell, "xu", until="sometime")
    with pytest.raises(ValueError, match="needs a reference"):
        radiosity.solve(cornell, "xu", until="rms=1e-3", reference="none")


def test_a_patch_out_of_range_is_an_index_error(cornell_ff):
    with pytest.raises(IndexError, match="170 patches"):
        cornell_ff.column(170)
    with pytest.raises(IndexError):
        cornell_ff.columns(np.array([0, 10_000]))
    with pytest.raises(ValueError, match="negative"):
        cornell_ff.columns(np.array([-1]))


def test_a_misshapen_vector_is_a_value_error(cornell_ff):
    with pytest.raises(ValueError, match="shape"):
        cornell_ff.multiply(np.ones(3))
    with pytest.raises(ValueError, match="shape"):
        cornell_ff.multiply(np.ones((cornell_ff.n, 2, 2)))
