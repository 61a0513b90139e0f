"""A scene's arrays against what the scene is: areas, unit normals, the lights."""

import numpy as np

import radiosity


def faced_axes(scene):
    """How many of the six axis directions some patch's normal points along."""
    axes = np.vstack([np.eye(3), -np.eye(3)])
    return int(np.sum(np.any(scene.normals @ axes.T > 0.999, axis=0)))


def test_arrays_have_a_row_per_patch(cornell):
    n, k = cornell.n, cornell.channels
    assert (n, k) == (170, 3)
    assert cornell.areas.shape == (n,)
    assert cornell.reflectivity.shape == (n, k) and cornell.emission.shape == (n, k)
    assert cornell.centroids.shape == (n, 3) and cornell.normals.shape == (n, 3)


def test_the_box_is_the_box(cornell):
    # Unit normals, reflectivities in [0, 1), emission only on the light.
    assert np.allclose(np.linalg.norm(cornell.normals, axis=1), 1.0, atol=1e-12)
    assert np.all((cornell.reflectivity >= 0) & (cornell.reflectivity < 1))
    lit = np.any(cornell.emission > 0, axis=1)
    assert 0 < lit.sum() < cornell.n
    # A room, not a plane: the centroids spread along all three axes, and the walls face five
    # of the six axis directions (the box is open at the front).
    lo, hi = cornell.centroids.min(axis=0), cornell.centroids.max(axis=0)
    assert np.all(hi - lo > 0)
    assert faced_axes(cornell) == 5


def test_what_the_analysis_left_out_is_said(cornell):
    assert any("hidden" in phrase for phrase in cornell.left_out)
    assert all(isinstance(phrase, str) for phrase in cornell.left_out)


def test_a_grey_scene_has_one_channel():
    scene = radiosity.load("furnace:res=4")
    assert scene.channels == 1 and scene.reflectivity.shape == (scene.n, 1)
    # The furnace is a closed cube: its faces face all six axis directions.
    assert faced_axes(scene) == 6
