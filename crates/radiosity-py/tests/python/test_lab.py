"""Python solvers in the lab: measured exactly like built-in ones."""

import numpy as np
import pytest

import radiosity


class NumpyPR:
    """Progressive refinement in numpy: the built-in `pr`'s rule, step for step."""

    name = "numpy-pr"

    def step(self, problem, state):
        power = problem.areas * np.abs(state.unshot).sum(axis=1)
        j = int(np.argmax(power))
        amount = state.unshot[j].copy()
        f = problem.column(j)
        delta = problem.reflectivity * f[:, None] * amount[None, :]
        state.radiosity += delta
        state.unshot += delta
        # The shooter keeps only its own share of the shot (zero for a flat patch).
        state.unshot[j] = problem.reflectivity[j] * f[j] * amount

    def residual_power(self, problem, state):
        a = problem.areas[:, None]
        return float((a * np.abs(state.unshot)).sum() / (a * np.abs(problem.emission)).sum())

    def residual_bound(self, problem, state):
        # Shooting keeps the unshot radiosity the residual of the shot one: r = rho F dB,
        # non-negative while dB is.
        return state.unshot, np.zeros_like(state.unshot), bool(np.all(state.unshot >= 0))


def rows_of(table, solver):
    picked = np.array([s == solver for s in table["solver"]])
    return {key: value[picked] for key, value in table.items() if key not in ("solver", "clock")}


def test_a_python_solver_is_measured_like_the_builtin_running_the_same_rule(cornell, tmp_path):
    comparison = radiosity.Lab(cornell).compare(["pr", NumpyPR()], until="columns=n")
    assert comparison.solvers == ["pr", "numpy-pr"]
    table = comparison.table()
    builtin, python = rows_of(table, "pr"), rows_of(table, "numpy-pr")
    assert np.array_equal(builtin["step"], python["step"]) and np.array_equal(builtin["columns"], python["columns"])
    assert python["columns"][-1] == cornell.n
    for key in ("e_rms", "e_max", "residual", "bound"):
        assert np.allclose(builtin[key], python[key], rtol=1e-9, atol=0), key
    # Certified: the bound covers the error at every recorded row.
    assert np.all(np.isfinite(python["bound"])) and python["bound"][-1] < python["bound"][0]
    written = comparison.write(tmp_path / "report")
    names = {p.name for p in written}
    assert {"convergence.csv", "report.md"} <= names
    assert "numpy-pr" in (tmp_path / "report" / "report.md").read_text()
    assert "numpy-pr" in comparison.summary()


class Jacobi:
    """Jacobi in numpy through whole products: a `product` step."""

    name = "numpy-jacobi"
    kind = "product"

    def step(self, problem, state):
        new = problem.emission + problem.reflectivity * problem.multiply(state.radiosity)
        state.unshot[:] = new - state.radiosity
        state.radiosity[:] = new


def test_a_product_solver_is_counted_in_products_or_columns(cornell):
    comparison = radiosity.Lab(cornell, ff="matrix").compare([Jacobi()], until="steps=30")
    rows = rows_of(comparison.table(), "numpy-jacobi")
    # A stored matrix multiplies itself: one product a step, no column.
    assert rows["products"][-1] == 30 and rows["columns"][-1] == 0
    assert rows["e_rms"][-1] < 1e-3 * rows["e_rms"][0]


def test_an_exception_in_a_python_solver_ends_the_comparison_and_is_raised_again(cornell):
    class Broken:
        def step(self, problem, state):
            if state.step == 3:
                raise ArithmeticError("step 3 fails")
            problem.column(state.step)

    with pytest.raises(ArithmeticError, match="step 3 fails"):
        radiosity.Lab(cornell).compare(["pr", Broken()])


def test_the_problem_answers_only_during_its_call(cornell):
    kept = []

    class Keeper:
        def step(self, problem, state):
            kept.append(problem)

    radiosity.Lab(cornell).compare([Keeper()], until="steps=1")
    with pytest.raises(RuntimeError, match="only during the call"):
        kept[0].column(0)


def test_bad_solvers_and_states_raise(cornell):
    with pytest.raises(ValueError, match="neither a solver's name"):
        radiosity.Lab(cornell).compare([42])
    with pytest.raises(ValueError, match="or reference|unknown solver|no-such"):
        radiosity.Lab(cornell).compare(["no-such-solver"])

    class Shrinks:
        def step(self, problem, state):
            state.radiosity = state.radiosity[:3]

    with pytest.raises(ValueError, match="must stay"):
        radiosity.Lab(cornell).compare([Shrinks()], until="steps=2")
