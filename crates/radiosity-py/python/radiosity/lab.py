"""The laboratory: built-in solvers and solvers written in Python, compared on one scene.

A Python solver is any object with ``step(problem, state)``; optionally ``name``, ``kind``
(``"shot"``, the default, ``"gather"`` or ``"product"``), ``init(problem, state)``,
``residual_power(problem, state)`` and ``residual_bound(problem, state)``. ``problem`` gives
``n``, ``channels``, ``areas``, ``emission``, ``reflectivity`` and the counted
``column(j)``, ``row(i)`` and ``multiply(x)``; ``state`` has ``radiosity`` and ``unshot``,
``(n, channels)`` arrays to update in place (or replace with arrays of the same shape), and
``step``. ``residual_bound`` returns ``(d, e)`` or ``(d, e, nonnegative)``: two
``(n, channels)`` arrays with ``|r| <= rho F |d| + |e|`` elementwise for the residual
``r = E + rho F B - B`` of ``state.radiosity`` (a shooting method's is ``(state.unshot, 0)``),
and whether ``r >= 0`` is known (which tightens the bound); the lab then certifies the run's
error as it does a built-in solver's.
"""

from . import _radiosity


class Lab:
    """A scene and a form-factor backend on which solvers are compared.

    ``reference`` is the reference kind (``auto``, ``matrix``, ``shooting`` or ``none``). The
    reference is computed for each comparison unless ``$RADIOSITY_CACHE_DIR`` keeps it.
    ``columns`` says how solvers pay for their columns, and so which clock every seconds
    figure, ``time=`` rule and timed group frequency reads: ``"computed"`` (every column
    computed when asked for, ``measured`` seconds) or ``"charged"`` (read from the stored
    matrix of a ``matrix`` reference, each charged the backend's measured cost); ``None``,
    the default, is ``cargo xtask compare``'s default, ``"computed"``. ``Comparison.clock``
    names the clock. ``transport`` says where the solvers that sample transport
    (``stochastic-jacobi``, ``random-walk``) cast their rays: ``"scene"`` (``None``, the
    default: through the scene's BVH) or ``"matrix"`` (the stored matrix of a ``matrix``
    reference, sampled exactly); they stop on a ``rays=``, ``steps=``, ``time=`` or ``rms=``
    rule, so a comparison mixing them with deterministic solvers gives both kinds of rule
    (``until="columns=2n,rays=1e6"``).
    """

    def __init__(self, scene, ff="analytic", reference="auto", columns=None, transport=None):
        self.scene = scene
        self.ff = ff
        self.reference = reference
        self.columns = columns
        self.transport = transport

    def compare(self, solvers, until="columns=2n"):
        """Runs ``solvers`` (names and Python solver objects) under the stop rules ``until``;
        a ``Comparison`` with ``clock``, ``table()``, ``summary()`` and ``write(dir)``."""
        return _radiosity.compare(
            self.scene,
            list(solvers),
            ff=self.ff,
            until=until,
            reference=self.reference,
            columns=self.columns,
            transport=self.transport,
        )
