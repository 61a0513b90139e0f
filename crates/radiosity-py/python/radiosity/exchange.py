"""Reading back a system written by ``FormFactors.write`` or ``cargo xtask ff --out``.

``.npz`` holds ``F`` under scipy.sparse's own keys (``scipy.sparse.load_npz`` reads it) with
``area``, ``emission`` and ``reflectivity``; ``.mtx`` holds ``F`` as Matrix Market, with the
patches in ``.patches.mtx`` beside it (columns: area, emission per channel, reflectivity per
channel). Every value reads back to the bits written.
"""

from pathlib import Path

import numpy as np
import scipy.io
import scipy.sparse


def read_system(path):
    """The system in ``path``: a dict of ``F`` (``scipy.sparse.csc_array``), ``area`` (n,),
    ``emission`` and ``reflectivity`` (n, channels)."""
    path = Path(path)
    if path.suffix == ".npz":
        f = scipy.sparse.csc_array(scipy.sparse.load_npz(path))
        with np.load(path, allow_pickle=False) as archive:
            patches = {key: archive[key] for key in ("area", "emission", "reflectivity")}
        return {"F": f, **patches}
    if path.suffix == ".mtx":
        f = scipy.sparse.csc_array(scipy.io.mmread(path))
        patches = np.asarray(scipy.io.mmread(path.with_suffix(".patches.mtx")))
        k = (patches.shape[1] - 1) // 2
        return {"F": f, "area": patches[:, 0], "emission": patches[:, 1 : 1 + k], "reflectivity": patches[:, 1 + k :]}
    raise ValueError(f"cannot read {path}: a system is .mtx (Matrix Market) or .npz (NumPy)")
