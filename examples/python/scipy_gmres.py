"""scipy's own GMRES over the workspace's operator, checked against its reference.

The operator I - diag(rho_c) F is a scipy LinearOperator whose products F x run in Rust;
scipy's GMRES solves each channel, and the answer is checked against the reference the lab
computes (the stored matrix's exact solution, whose entries the operator uses too).

    python examples/python/scipy_gmres.py [--scene SCENE]
"""

import argparse

import numpy as np
from scipy.sparse.linalg import gmres

import radiosity


def solve(scene_spec="cornell"):
    """The largest relative difference between scipy's GMRES and the reference on ``scene_spec``."""
    scene = radiosity.load(scene_spec)
    ff = scene.form_factors("matrix")
    reference = radiosity.solve(scene, "reference", ff="matrix").radiosity
    worst = 0.0
    for c in range(scene.channels):
        b, info = gmres(scene.operator(ff, channel=c), scene.emission[:, c], rtol=1e-12, atol=0, restart=30)
        if info != 0:
            raise RuntimeError(f"GMRES did not converge in channel {c} (info {info})")
        worst = max(worst, float(np.max(np.abs(b - reference[:, c])) / np.max(np.abs(reference[:, c]))))
    return worst


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="cornell")
    args = parser.parse_args()
    worst = solve(args.scene)
    print(f"scipy GMRES against the reference on {args.scene}: largest relative difference {worst:.2e}")
    assert worst <= 1e-8, worst
