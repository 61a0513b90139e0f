"""scipy operators over a backend's products: ``F`` itself and the system ``I - diag(rho) F``.

The products are the backend's own (``FormFactors.multiply``), computed in Rust; scipy only
sees a ``LinearOperator``.
"""

import numpy as np
from scipy.sparse.linalg import LinearOperator


def form_factor_operator(ff):
    """``F`` of the backend ``ff`` as an ``n x n`` LinearOperator."""
    n = ff.n

    def product(x):
        return ff.multiply(np.ascontiguousarray(x, dtype=np.float64))

    return LinearOperator((n, n), matvec=product, matmat=product, dtype=np.float64)


def system_operator(scene, ff, channel=None):
    """``I - diag(rho_c) F`` of channel ``channel`` of ``scene`` as an ``n x n`` LinearOperator.

    ``channel`` may be left out on a grey scene (one channel).
    """
    if ff.n != scene.n:
        raise ValueError(f"the form factors have {ff.n} patches but the scene has {scene.n}")
    if channel is None:
        if scene.channels != 1:
            raise ValueError(f"the scene has {scene.channels} channels: name one (channel=0 to {scene.channels - 1})")
        channel = 0
    if not 0 <= channel < scene.channels:
        raise ValueError(f"channel {channel} is out of range: the scene has {scene.channels} channels")
    rho = scene.reflectivity[:, channel]
    n = scene.n

    def product(x):
        x = np.ascontiguousarray(x, dtype=np.float64)
        fx = ff.multiply(x)
        return x - (rho * fx.T).T

    return LinearOperator((n, n), matvec=product, matmat=product, dtype=np.float64)
