"""The examples in examples/python run and show what they claim."""

import importlib.util
from pathlib import Path

import numpy as np

EXAMPLES = Path(__file__).resolve().parents[4] / "examples" / "python"


def example(name):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_scipy_gmres_finds_the_reference():
    assert example("scipy_gmres").solve("cornell:res=4") <= 1e-8


def test_own_solver_is_compared_with_the_builtins_and_converges(tmp_path):
    comparison = example("own_solver").compare("multi-cubes", tmp_path / "report")
    assert comparison.solvers == ["pr", "xu", "cg", "numpy-chebyshev"]
    table = comparison.table()
    mine = np.array([s == "numpy-chebyshev" for s in table["solver"]])
    e_rms, bound = table["e_rms"][mine], table["bound"][mine]
    # Chebyshev reaches the rule at one product (at most n columns) a step, certified on the way.
    assert e_rms[-1] <= 1e-6
    steps, columns = table["step"][mine], table["columns"][mine]
    assert np.all(columns <= steps * 480) and columns[-1] > 0
    assert np.all(np.isfinite(bound)) and bound[-1] < 1e-4 and bound[-1] < bound[0]
    names = {p.name for p in (tmp_path / "report").iterdir()}
    assert {"report.md", "convergence.csv"} <= names and any(n.endswith(".png") for n in names)
