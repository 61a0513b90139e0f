"""Radiosity from Python: the workspace's scenes, form factors and solvers over numpy and scipy.

    import radiosity
    scene = radiosity.load("cornell")          # any --scene the command line takes
    ff = scene.form_factors("analytic")        # any --ff backend
    column = ff.column(0)                      # numpy arrays, computed in Rust
    F = ff.as_linear_operator()                # scipy.sparse.linalg.LinearOperator
    run = radiosity.solve(scene, "xu", until="rms=1e-3")
    run.radiosity, run.stats
    radiosity.Lab(scene).compare(["pr", "xu", MySolver()]).write("results/mine")

The heavy work runs in Rust with the GIL released; errors are ``ValueError`` (bad specs, names,
rules or shapes) and ``IndexError`` (patch indices), with the command line's messages.
"""

from ._radiosity import Comparison, FormFactors, Problem, Run, Scene, __version__, load, solve
from .exchange import read_system
from .lab import Lab

__all__ = [
    "Comparison",
    "FormFactors",
    "Lab",
    "Problem",
    "Run",
    "Scene",
    "__version__",
    "load",
    "read_system",
    "solve",
]
