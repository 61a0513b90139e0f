"""The Python side of the package's overhead measurement (examples/overhead.rs is the Rust
side): the same analytic columns and stored-matrix products on ``office``, from Python.

    python crates/radiosity-py/bench/overhead.py columns|products

Run both sides interleaved, several times each, with the package installed in release
(``pip install .``) and ``$RADIOSITY_CACHE_DIR`` set for products (docs/python.md).
"""

import sys
import time

import numpy as np

import radiosity

what = sys.argv[1] if len(sys.argv) > 1 else "columns"
scene = radiosity.load("office")
n = scene.n
times = []
if what == "columns":
    ff = scene.form_factors("analytic")
    for k in range(40):
        start = time.perf_counter()
        ff.column(k * n // 40)
        times.append(time.perf_counter() - start)
    print(f"python column median {np.median(times):.6f} s")
else:
    f = scene.form_factors("matrix").as_linear_operator()
    x = np.ones(n)
    for _ in range(21):
        start = time.perf_counter()
        f @ x
        times.append(time.perf_counter() - start)
    print(f"python LinearOperator product median {np.median(times):.6f} s")
