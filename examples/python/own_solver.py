"""A solver of one's own, written in numpy, beside the built-in ones.

Jacobi-preconditioned Chebyshev iteration on (I - diag(rho) F) B = E: the eigenvalues of
diag(rho) F lie in the disc of radius max(rho) (rows of F sum to at most 1), so those of the
system lie in [1 - max(rho), 1 + max(rho)] for a symmetrizable F, and Chebyshev's three-term
recurrence on that interval converges as ((1 - sqrt(1 - r^2)) / r)^k with r = max(rho)
(Golub & Van Loan, Matrix Computations, section 11.2.8; Saad, Iterative Methods for Sparse
Linear Systems, section 12.1). Each step is one product F x, pulled through the problem so the
lab counts it (n columns over the analytic backend), and its certified bound needs no other.

    python examples/python/own_solver.py [--out DIR] [--scene SCENE]

compares it with pr, xu and cg on multi-cubes, each run to e_rms 1e-6, and writes report.md, convergence.csv and the
plots into DIR (results/own-solver by default).
"""

import argparse

import numpy as np

import radiosity


class Chebyshev:
    """Chebyshev iteration for (I - diag(rho) F) B = E on [1 - r, 1 + r], r = max(rho)."""

    name = "numpy-chebyshev"
    kind = "product"

    def init(self, problem, state):
        r = float(problem.reflectivity.max())
        self.centre, self.half = 1.0, r
        self.previous = None
        self.alpha = 0.0
        # B = E is one change E from zero: r(E) = rho F E, so |r| <= rho F |E| (d = E, e = 0).
        self.d, self.e = problem.emission.copy(), np.zeros_like(problem.emission)

    def residual(self, problem, b):
        return problem.emission + problem.reflectivity * problem.multiply(b) - b

    def step(self, problem, state):
        r = self.residual(problem, state.radiosity)
        d, c = self.centre, self.half
        if self.previous is None:
            self.alpha = 1.0 / d
            update = self.alpha * r
        else:
            beta = (c * self.alpha / 2.0) ** 2
            self.alpha = 1.0 / (d - beta / self.alpha)
            update = self.alpha * r + (self.alpha * beta / self.alpha_before) * self.previous
        self.alpha_before = self.alpha
        self.previous = update
        state.radiosity += update
        state.unshot[:] = update
        # r(B + u) = rho F u + (r - u): the new residual without another product.
        self.d, self.e = update, r - update

    def residual_bound(self, problem, state):
        return self.d, self.e


def compare(scene="multi-cubes", out="results/own-solver"):
    """The comparison of Chebyshev with pr, xu and cg on ``scene``, written into ``out``."""
    lab = radiosity.Lab(radiosity.load(scene))
    comparison = lab.compare(["pr", "xu", "cg", Chebyshev()], until="rms=1e-6")
    comparison.write(out)
    return comparison


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="multi-cubes")
    parser.add_argument("--out", default="results/own-solver")
    args = parser.parse_args()
    print(compare(args.scene, args.out).summary())
    print(f"wrote {args.out} (report.md, convergence.csv and plots)")
