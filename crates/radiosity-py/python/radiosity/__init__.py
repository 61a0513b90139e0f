"""Radiosity from Python: the workspace's scenes, form factors and solvers over numpy and scipy.

    import radiosity
    scene = radiosity.load("cornell")          # any --scene the command line takes
    ff = scene.form_factors("analytic")        # any --ff backend
    column = ff.column(0)                      # numpy arrays, computed in Rust
    F = ff.as_linear_operator()                # scipy.sparse.linalg.LinearOperator
    run = radiosity.solve(scene, "xu", until="rms=1e-3")
    run.radiosity, run.stats

The heavy work runs in Rust with the GIL released; errors are ``ValueError`` (bad specs, names,
rules or shapes) and ``IndexError`` (patch indices), with the command line's messages.
"""

from ._radiosity import FormFactors, Run, Scene, __version__, load, solve
from .exchange import read_system

__all__ = ["FormFactors", "Run", "Scene", "__version__", "load", "read_system", "solve"]
