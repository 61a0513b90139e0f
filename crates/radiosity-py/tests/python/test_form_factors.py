"""Form factors from Python against the properties they must have: reciprocity, the same
numbers however they are fetched, and products equal to the columns they sum."""

import numpy as np
import pytest

import radiosity


def test_rows_and_columns_are_reciprocal(cornell, cornell_ff):
    a = cornell.areas
    for i in (0, 57, 169):
        row, column = cornell_ff.row(i), cornell_ff.column(i)
        # A_i F_ij = A_j F_ji, exact for the analytic backend (each pair computed once).
        assert np.allclose(a[i] * row, a * column, rtol=1e-12, atol=0)


def test_a_batch_of_columns_is_the_columns_one_by_one(cornell_ff):
    js = np.array([3, 0, 169, 3])
    batch = cornell_ff.columns(js)
    assert batch.shape == (cornell_ff.n, 4)
    for k, j in enumerate(js):
        assert np.array_equal(batch[:, k], cornell_ff.column(j))


def test_rows_sum_to_at_most_one(cornell_ff):
    sums = cornell_ff.as_linear_operator() @ np.ones(cornell_ff.n)
    assert sums.max() <= 1.01 and sums.min() >= 0


@pytest.mark.parametrize("spec", ["analytic", "hierarchical"])
def test_the_product_is_the_sum_of_the_columns(cornell, spec):
    ff = cornell.form_factors(spec)
    x = np.random.default_rng(0).random((cornell.n, 3))
    columns = ff.columns(np.arange(cornell.n))
    assert np.allclose(ff.multiply(x), columns @ x, rtol=1e-10, atol=1e-14)
    assert np.allclose(ff.multiply(x[:, 1]), columns @ x[:, 1], rtol=1e-10, atol=1e-14)
