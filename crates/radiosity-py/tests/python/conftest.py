"""Shared scenes of the pytest suite: small ones, loaded once per session."""

import pytest

import radiosity


@pytest.fixture(scope="session")
def cornell():
    """The Cornell box at a coarse mesh: RGB, 170 patches, one hidden."""
    return radiosity.load("cornell:res=4")


@pytest.fixture(scope="session")
def cornell_ff(cornell):
    """Its analytic form factors."""
    return cornell.form_factors("analytic")
