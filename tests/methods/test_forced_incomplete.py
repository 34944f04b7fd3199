"""A forced response that stops short of the end of its frequency range says so: its
status kind (max_steps, ds_min: structured, from :class:`~mmshbm.core.status.Status`), its
``completed`` flag, an ``"incomplete"`` finding and a BranchWarning of that kind; and so does
a backbone that runs out of steps."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import mmshbm
from mmshbm.core.status import Status
from mmshbm.results.response import FrequencyResponse

OSC = dict(m=1.0, k1=1.0, k2=4.0, gap=1.0)
F_OSC = np.array([0.1, 0.0])


@pytest.fixture(scope="module")
def osc():
    return mmshbm.OneDofOscillator(**OSC).model().with_damping(modal_ratio=0.02)


def _run(model, frange, **kw):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = mmshbm.frequency_response(model, F_OSC, frange, **({} if "tol" in kw else {"harmonics": 4}), **kw)
    kinds = [getattr(w.message, "kind", None) for w in caught if issubclass(w.category, mmshbm.BranchWarning)]
    return r, kinds


@pytest.mark.parametrize("stop, options", [
    (Status.MAX_STEPS, {"max_steps": 5}),
    # one Newton iteration cannot reach 1e-14 from a predictor: every step fails, ds halves below ds_min
    (Status.DS_MIN, {"ds_min": 0.019, "max_newton": 1, "newton_tol": 1e-14}),
])
def test_a_response_stopped_short_says_so(osc, stop, options, tmp_path):
    f1 = osc.linear_frequencies(1)[0]
    frange = (0.5 * f1, 1.6 * f1)
    r, kinds = _run(osc, frange, **options)
    assert isinstance(r.status, Status) and r.status.kind == stop
    assert r.frequency[-1] < frange[1] * (1 - 0.1)
    assert not r.completed
    assert [f.kind for f in r.findings] == ["incomplete"] and kinds == ["incomplete"]
    # read back from its file, the response still says so (the status kind parsed from the text,
    # the finding kept in the metadata)
    back = FrequencyResponse.load(r.save(tmp_path / "r.npz"))
    assert Status.parse(back.status).kind == stop and not back.completed
    assert [f.kind for f in back.findings] == ["incomplete"]


def test_a_response_to_tolerance_stopped_short_says_so(osc):
    f1 = osc.linear_frequencies(1)[0]
    r, kinds = _run(osc, (0.5 * f1, 1.6 * f1), tol=1e-3, max_steps=5)
    assert r.status.kind == Status.MAX_STEPS and not r.completed
    assert "incomplete" in [f.kind for f in r.findings] and "incomplete" in kinds


def test_a_response_reaching_the_end_is_complete(osc):
    f1 = osc.linear_frequencies(1)[0]
    r, kinds = _run(osc, (0.5 * f1, 1.6 * f1))
    assert r.status.kind == Status.BOUND and r.completed and not r.findings and kinds == []
    # refined onto the bound to the Newton tolerance's share of the frequency (1e-9 relative is ample)
    assert r.frequency[-1] == pytest.approx(1.6 * f1, rel=1e-9)


def test_leaving_at_the_start_of_the_range_is_not_complete(osc, tmp_path):
    f1 = osc.linear_frequencies(1)[0]
    r, _ = _run(osc, (0.5 * f1, 1.6 * f1))
    # the same points, as if the response had turned back and left the range at f_start
    back = FrequencyResponse(**{**{k: getattr(r, k) for k in (
        "frequency", "amplitude", "phase", "energy", "contact_force_max", "stable", "floquet_max",
        "newton_iterations", "step_size", "states", "status", "method", "harmonics", "metadata")},
        "frequency": r.frequency[::-1].copy()})
    assert back.status.kind == Status.BOUND and not back.completed
    path = r.save(tmp_path / "r.npz")
    assert FrequencyResponse.load(path).completed


def test_a_backbone_out_of_steps_says_so():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        b = mmshbm.backbone(mmshbm.OneDofOscillator(**OSC).model(), harmonics=4, max_steps=3)
    assert b.status.kind == Status.MAX_STEPS and not b.completed
    assert "incomplete" in [f.kind for f in b.findings]
    assert "incomplete" in [getattr(w.message, "kind", None) for w in caught]


def test_a_response_stopped_by_an_amplitude_bound_names_it(osc):
    """A bound of the caller's own (here on the amplitude, below the resonance peak) ends the
    response short of its range: the finding names that bound, not a turn out of the range."""
    f1 = osc.linear_frequencies(1)[0]
    free, _ = _run(osc, (0.5 * f1, 1.6 * f1))
    cap = 0.5 * float(np.max(free.amplitude))
    r, kinds = _run(osc, (0.5 * f1, 1.6 * f1), bounds={"amplitude": (0.0, cap)})
    assert r.status.kind == Status.BOUND and r.status.detail == "amplitude" and not r.completed
    assert kinds == ["incomplete"]
    (finding,) = r.findings
    assert "reached the bound on amplitude" in finding.message and "turned back" not in finding.message
    # refined onto the bound (the corrector's tolerance, relative)
    assert r.amplitude[-1] == pytest.approx(cap, rel=1e-8)
