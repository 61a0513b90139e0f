"""The system written for other programs reads back to the same bits, and scipy solves it to
the workspace's reference."""

import numpy as np
import pytest
from scipy.sparse import identity
from scipy.sparse.linalg import spsolve

import radiosity


@pytest.mark.parametrize("name", ["system.npz", "F.mtx"])
def test_a_written_system_reads_back_exactly_and_solves_to_the_reference(cornell, tmp_path, name):
    ff = cornell.form_factors("matrix")
    written = ff.write(tmp_path / name)
    assert written[0] == tmp_path / name and all(p.is_file() for p in written)
    system = radiosity.read_system(tmp_path / name)
    f = ff.to_scipy()
    assert system["F"].shape == f.shape and system["F"].nnz == f.nnz
    assert abs(system["F"] - f).max() == 0
    assert np.array_equal(system["area"], cornell.areas)
    assert np.array_equal(system["emission"], cornell.emission)
    assert np.array_equal(system["reflectivity"], cornell.reflectivity)
    reference = radiosity.solve(cornell, "reference", ff="matrix").radiosity
    for c in range(cornell.channels):
        a = identity(cornell.n, format="csc") - system["F"].multiply(system["reflectivity"][:, c][:, None])
        b = spsolve(a.tocsc(), system["emission"][:, c])
        assert np.max(np.abs(b - reference[:, c])) <= 1e-10 * np.max(np.abs(reference[:, c]))


def test_only_known_formats_are_written_or_read(cornell, tmp_path):
    ff = cornell.form_factors("matrix")
    with pytest.raises(ValueError, match=".mtx"):
        ff.write(tmp_path / "F.csv")
    with pytest.raises(ValueError, match=".npz"):
        radiosity.read_system(tmp_path / "F.csv")
    with pytest.raises(ValueError, match="not a stored matrix"):
        cornell.form_factors("analytic").write(tmp_path / "F.npz")
