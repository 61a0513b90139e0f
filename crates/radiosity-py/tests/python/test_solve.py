"""Solving from Python: scipy over the operator against the workspace's own reference, and
built-in solvers measured as the command line measures them."""

import numpy as np
from scipy.sparse.linalg import gmres

import radiosity


def test_scipy_gmres_over_the_operator_finds_the_reference(cornell):
    # A stored matrix: the reference solves exactly these entries.
    ff = cornell.form_factors("matrix")
    reference = radiosity.solve(cornell, "reference", ff="matrix").radiosity
    for c in range(cornell.channels):
        b, info = gmres(cornell.operator(ff, channel=c), cornell.emission[:, c], rtol=1e-13, atol=0, restart=50)
        assert info == 0
        assert np.max(np.abs(b - reference[:, c])) <= 1e-8 * np.max(np.abs(reference[:, c]))


def test_a_run_stops_at_its_rule_and_reports_it(cornell):
    run = radiosity.solve(cornell, "xu", until="rms=1e-3")
    stats = run.stats
    assert stats["e_rms"] <= 1e-3 and stats["columns"] > 0 and stats["steps"] == stats["columns"]
    assert "e_rms reached" in stats["termination"]
    assert stats["reference"]["kind"] == "matrix" and stats["residual_of"] == "displayed radiosity"
    # Where e_rms first fell to each power of ten, in order, the last at the rule.
    reached = stats["reached"]
    assert [r["e_rms"] for r in reached] == [1e-1, 1e-2, 1e-3]
    assert all(a["columns"] <= b["columns"] for a, b in zip(reached, reached[1:]))
    assert reached[-1]["columns"] == stats["columns"]
    # The certified bound covers the error it bounds, and the recorded points end where the run did.
    assert stats["bound"] is not None and stats["bound"] > 0
    assert run.points["columns"][-1] == stats["columns"]
    assert run.radiosity.shape == (cornell.n, cornell.channels)


def test_the_reference_solves_the_system(cornell):
    ff = cornell.form_factors("matrix")
    b = radiosity.solve(cornell, "reference", ff="matrix").radiosity
    # B = E + diag(rho) F B, channel by channel.
    residual = cornell.emission + cornell.reflectivity * ff.multiply(b) - b
    assert np.max(np.abs(residual)) <= 1e-10 * np.max(np.abs(b))


def test_scipy_over_the_furnace_finds_the_furnace_identity():
    # A closed furnace with one reflectivity and one emission everywhere: B = E / (1 - rho),
    # independent of F; the analytic rows sum to 1 within their shadow rays' noise.
    scene = radiosity.load("furnace:res=4:rho=0.9")
    ff = scene.form_factors("analytic")
    e, rho = scene.emission[:, 0], scene.reflectivity[:, 0]
    assert np.ptp(e) == 0 and np.ptp(rho) == 0 and rho[0] > 0.5
    b, info = gmres(scene.operator(ff), e, rtol=1e-12, atol=0)
    assert info == 0
    assert np.allclose(b, e / (1 - rho), rtol=1e-2)


def test_scipy_spsolve_on_the_stored_matrix_finds_the_reference():
    # The exported system (I - diag(rho) F) B = E, F the stored matrix as scipy holds it,
    # solved by scipy's direct solver against the workspace's reference, on two scenes.
    from scipy.sparse import identity
    from scipy.sparse.linalg import spsolve

    for spec in ("cornell:res=4", "multi-cubes"):
        scene = radiosity.load(spec)
        ff = scene.form_factors("matrix")
        f = ff.to_scipy()
        assert f.shape == (scene.n, scene.n) and f.nnz > 0
        reference = radiosity.solve(scene, "reference", ff="matrix").radiosity
        for c in range(scene.channels):
            system = identity(scene.n, format="csc") - f.multiply(scene.reflectivity[:, c][:, None])
            b = spsolve(system.tocsc(), scene.emission[:, c])
            assert np.max(np.abs(b - reference[:, c])) <= 1e-10 * np.max(np.abs(reference[:, c]))


def test_only_a_stored_matrix_goes_to_scipy(cornell_ff):
    import pytest

    with pytest.raises(ValueError, match="not a stored matrix"):
        cornell_ff.to_scipy()


def test_a_callback_sees_every_point_and_can_stop_the_run(cornell):
    seen = []

    def watch(point):
        seen.append((point["step"], point["e_rms"], point["radiosity"].copy()))
        return point["step"] == 12

    run = radiosity.solve(cornell, "xu", until="columns=2n", callback=watch)
    assert [s for s, _, _ in seen] == list(range(13))
    assert run.stats["steps"] == 12 and run.stats["termination"] == "stopped by its observer after 12 steps"
    # The last point the callback saw is the run's final state and error.
    assert np.array_equal(seen[-1][2], run.radiosity)
    assert seen[-1][1] == run.stats["e_rms"]
    # Errors fall as the run goes, and the first point is the emission alone.
    assert np.array_equal(seen[0][2], cornell.emission) and seen[-1][1] < seen[0][1]


def test_an_exception_in_a_callback_ends_the_run_and_is_raised_again(cornell):
    class Enough(Exception):
        pass

    def watch(point):
        if point["step"] == 3:
            raise Enough("seen enough")

    import pytest

    with pytest.raises(Enough, match="seen enough"):
        radiosity.solve(cornell, "xu", callback=watch)


def test_a_node_shooter_runs_on_the_hierarchy_counted_in_links(cornell):
    # Shooting from the tree's nodes through their links: no column, links counted, and the
    # run ends near the reference, which solves the operator's entries rounded to f32 (a floor
    # of about 6e-8 relative), where the run's residual power of 1e-8 leaves it.
    run = radiosity.solve(cornell, "h-southwell", ff="hierarchical:eps=5e-2", until="residual=1e-8")
    stats = run.stats
    assert stats["columns"] == 0 and stats["links"] > 0 and "residual power reached" in stats["termination"]
    assert stats["record"]["rounds"] == stats["steps"]
    assert stats["e_rms"] < 1e-5
    assert run.points["links"][-1] == stats["links"]
