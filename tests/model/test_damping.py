"""Model.with_damping: modal ratios and Rayleigh damping on the DOFs with mass."""

from __future__ import annotations

import numpy as np
import pytest

import mmshbm
from mmshbm.model.damping import modal_damping_ratios
from mmshbm.results.branch import rebuild_model


def _modal_matrix(model):
    freqs, modes = model.linear_modes(len(model.l))
    return 2 * np.pi * freqs, modes.T @ (model.damping @ modes)


def test_modal_ratio_diagonalises_in_the_open_modes(beam8):
    model = beam8.with_damping(modal_ratio=0.02)
    w, CPhi = _modal_matrix(model)
    scale = np.abs(np.diag(CPhi)).max()
    np.testing.assert_allclose(np.diag(CPhi), 2 * 0.02 * w, rtol=1e-8)
    assert np.abs(CPhi - np.diag(np.diag(CPhi))).max() < 1e-8 * scale


def test_modal_ratio_per_mode_leaves_the_higher_modes_undamped(beam8):
    model = beam8.with_damping(modal_ratio=[0.01, 0.03])
    np.testing.assert_allclose(modal_damping_ratios(model, 4), [0.01, 0.03, 0, 0], atol=1e-12)


def test_rayleigh_gives_the_textbook_ratios_of_the_open_modes(beam8):
    alpha, beta = 3.0, 2e-6
    model = beam8.with_damping(rayleigh=(alpha, beta))
    w = 2 * np.pi * beam8.linear_frequencies(5)
    np.testing.assert_allclose(modal_damping_ratios(model, 5), alpha / (2 * w) + beta * w / 2, rtol=1e-9)


def test_damping_leaves_massless_dofs_static_and_is_recorded(beam8, tmp_path):
    model = beam8.with_damping(modal_ratio=0.01, rayleigh=(1.0, 0.0))
    C = model.damping.toarray()
    assert np.all(C[model.c] == 0) and np.all(C[:, model.c] == 0)
    np.testing.assert_allclose(C, C.T, atol=1e-12 * np.abs(C).max())
    assert np.linalg.eigvalsh(C[np.ix_(model.l, model.l)]).min() > -1e-10 * np.abs(C).max()
    assert model.description["transforms"][-1] == {"name": "with_damping",
                                                   "args": {"modal_ratio": 0.01, "rayleigh": [1.0, 0.0]}}
    assert rebuild_model(model.description).same_as(model)
    model.save_npz(tmp_path / "m.npz")
    assert mmshbm.Model.from_npz(tmp_path / "m.npz").same_as(model)


@pytest.mark.parametrize("kwargs, match", [
    ({}, "give modal_ratio"),
    ({"modal_ratio": -0.01}, "modal_ratio must be >= 0"),
    ({"modal_ratio": [0.01, -0.02]}, r"modal_ratio\[1\] must be >= 0"),
    ({"modal_ratio": []}, "modal_ratio is an empty sequence"),
    ({"modal_ratio": [0.01] * 100}, "modal_ratio has 100 ratios"),
    ({"modal_ratio": float("nan")}, "modal_ratio must be finite"),
    ({"rayleigh": (-1.0, 0.0)}, "rayleigh alpha must be >= 0"),
    ({"rayleigh": (0.0, -1e-6)}, "rayleigh beta must be >= 0"),
    ({"rayleigh": 1.0}, "rayleigh must be a pair"),
])
def test_bad_damping_is_refused_by_name(beam8, kwargs, match):
    with pytest.raises(ValueError, match=match):
        beam8.with_damping(**kwargs)
