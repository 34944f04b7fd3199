"""The run shared by backbone and frequency_response (mmshbm.methods.runner): checkpoints of
forced responses, the damped backbone's method, grazing, metadata."""

from __future__ import annotations

import logging

import numpy as np
import pytest

import mmshbm
from mmshbm.methods.runner import jsonable

pytestmark = pytest.mark.filterwarnings("ignore::mmshbm.BranchWarning")

OSC = mmshbm.OneDofOscillator(1.0, 1.0, 4.0, 1.0).model()
DAMPED = OSC.with_damping(modal_ratio=0.02)
FORCE = np.array([0.3, 0.0])
RANGE = (0.1, 0.3)


@pytest.fixture(scope="module")
def forced_full():
    return mmshbm.frequency_response(DAMPED, FORCE, RANGE, harmonics=3)


def test_forced_response_resumes_point_for_point(forced_full, tmp_path):
    ck = tmp_path / "f.jsonl"
    part = mmshbm.frequency_response(DAMPED, FORCE, RANGE, harmonics=3, max_steps=20, checkpoint=ck)
    assert part.status == "max_steps" and len(part) < len(forced_full)
    done = mmshbm.frequency_response(DAMPED, FORCE, RANGE, harmonics=3, resume=ck, checkpoint=ck)
    assert done.status == forced_full.status and len(done) == len(forced_full)
    np.testing.assert_array_equal(done.states, forced_full.states)
    np.testing.assert_array_equal(done.frequency, forced_full.frequency)
    np.testing.assert_array_equal(done.stable, forced_full.stable)
    assert done.special_points == forced_full.special_points
    assert done.metadata["resumed_points"] == len(part) and done.metadata["resumed_from"] == str(ck)


def test_forced_resume_refuses_another_excitation(tmp_path):
    ck = tmp_path / "f.jsonl"
    mmshbm.frequency_response(DAMPED, FORCE, RANGE, harmonics=3, max_steps=5, checkpoint=ck)
    with pytest.raises(ValueError, match="excitation"):
        mmshbm.frequency_response(DAMPED, 2 * FORCE, RANGE, harmonics=3, resume=ck)


def test_damped_backbone_says_it_is_epmc(caplog):
    with caplog.at_level(logging.INFO, logger="mmshbm.methods.backbone"):
        branch = mmshbm.backbone(DAMPED, harmonics=3, max_amplitude=1.5)
    assert branch.method == "epmc" and branch.metadata["method"] == "epmc"
    assert branch.metadata["requested_method"] == "mmshbm"
    assert any("damped nonlinear mode" in r.getMessage() for r in caplog.records)
    assert "requested_method" not in mmshbm.backbone(OSC, harmonics=3, max_amplitude=1.5).metadata


@pytest.mark.parametrize("kind", ["backbone", "forced"])
def test_grazing_is_where_the_stop_first_carries_force(kind, forced_full):
    """The oscillator's stop (gap 1 under the massless node, which follows the mass
    statically while open) is touched exactly when the amplitude passes the gap."""
    result = mmshbm.backbone(OSC, harmonics=3, max_amplitude=2.0) if kind == "backbone" else forced_full
    g = [p.index for p in result.special_points if p.kind == "grazing"]
    assert len(g) == 1
    i = g[0]
    assert result.contact_force_max[i] > 0 and np.all(result.contact_force_max[:i] == 0)
    assert result.amplitude[i - 1] <= OSC.gap * (1 + 1e-9) < result.amplitude[i]


def test_metadata_keeps_integers_and_arrays_as_json():
    out = jsonable({"modes": (1, 2), "r": np.float64(2.5), "nested": {"w": np.arange(2)}, "flag": [True]})
    assert out == {"modes": [1, 2], "r": 2.5, "nested": {"w": [0, 1]}, "flag": [True]}
    assert type(out["modes"][0]) is int and type(out["flag"][0]) is bool


def test_one_option_check_for_both_entry_points():
    with pytest.raises(TypeError, match=r"'n_sample' \(did you mean 'n_samples'\?\) for method 'mmshbm'"):
        mmshbm.backbone(OSC, harmonics=3, n_sample=16)
    with pytest.raises(TypeError, match=r"'n_sample' \(did you mean 'n_samples'\?\) for the forced method"):
        mmshbm.frequency_response(DAMPED, FORCE, RANGE, harmonics=3, n_sample=16)
