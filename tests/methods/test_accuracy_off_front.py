"""Points off the family front (the excursions into internal-resonance tongues) in contact:
their estimate at the start H comes from the 2H solve from the padded start, or from the
excursion's previous estimated point with the frequency-change check, never from the √2
steps; where neither solve converges the estimate is NaN and
``records["error_not_estimated"]`` says so. The front points, the backbone's contract, are
refined as before and no finding counts an off-front NaN."""

import warnings

import numpy as np
import pytest

import mmshbm
import mmshbm.methods.adaptive_climb as climb
import mmshbm.results.point_errors as pe
from mmshbm.results.tolerance_checks import tolerance_summary, unmet_points
from validation import corpus_exact as ce


def _chain():
    """Chain 3 of seed 5 (contact springs 10**U(0, 6)): two excursions off the front in
    contact near grazing and at 1.1-1.2 gaps, where the zero-padded 2H solve fails at some
    points and converges at others."""
    return ce.chains(4, seed=5, max_masses=3, contact_decades=(0, 6))[3].model()


def _run(model):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return mmshbm.backbone(model, tol=1e-4, max_amplitude=1.56 * model.gap)


@pytest.fixture(scope="module")
def runs():
    """The backbone, the amplitudes raise_point was called at, and the backbone with the
    off-front points refined as front points' estimates are (the √2 steps as the fallback)."""
    model = _chain()
    amplitudes = []
    original = pe.raise_point

    def counted(ladder, H, u, amplitude, H2, tol=1e-10):
        amplitudes.append(float(amplitude))
        return original(ladder, H, u, amplitude, H2, tol)

    mp = pytest.MonkeyPatch()
    mp.setattr(pe, "raise_point", counted)
    b = _run(model)
    mp.undo()

    class Stepped(climb._Point):  # every point in contact may fall back to the √2 steps
        def __init__(self, *args, off=False, **kwargs):
            super().__init__(*args, **kwargs)

    mp.setattr(climb, "_Point", Stepped)
    stepped = _run(model)
    mp.undo()
    return model, b, amplitudes, stepped


def test_off_front_points_carry_an_estimate_or_say_they_have_none(runs):
    model, b, amplitudes, _ = runs
    front = np.zeros(len(b), dtype=bool)
    front[b.family_front()] = True
    off = (b.contact_force_max > 0) & ~front
    flag = b.records["error_not_estimated"]
    assert flag.dtype == np.int8 and len(flag) == len(b)
    assert off.sum() >= 6
    finite = np.isfinite(b.frequency_error)
    assert np.array_equal(flag == 1, off & ~finite)  # flagged exactly where off the front and NaN
    assert np.sum(off & finite) >= 3 and np.sum(flag) >= 3  # both outcomes occur on this branch
    assert np.all(b.frequency_error[off & finite] >= 0)
    assert np.all(b.records["harmonics"][off] == 8)  # the start H, as before
    # the √2 steps served no off-front point
    assert amplitudes and not set(amplitudes) & set(b.amplitude[off].tolist())
    # the contract is the front's: a NaN off it is no unmet point, nor in the summary
    assert not set(unmet_points(b).tolist()) & set(np.flatnonzero(off).tolist())
    found = [f for f in b.findings if f.kind == "tolerance_not_met"]
    assert all(front[f.first] and front[f.last] for f in found)
    if not found:
        assert tolerance_summary(b).startswith("tolerance 0.0001 met at every point")


def test_the_front_is_refined_as_with_the_steps_off_it(runs):
    """The off-front points share the branch's memory of failed padded pairs (``stepped``)
    with the front points; they fill it as before, so every front point takes the same
    solves: frequency, H and estimate as with the √2 steps off the front (to the Newton
    tolerance 1e-10 of the pinned solves, which bounds any difference in the frequencies;
    estimates within 1e-9 absolute, a fraction 1e-5 of tol)."""
    _, b, _, stepped = runs
    front = np.asarray(b.family_front(), dtype=int)
    assert np.array_equal(front, stepped.family_front())
    assert np.array_equal(b.records["harmonics"][front], stepped.records["harmonics"][front])
    assert np.allclose(b.frequency[front], stepped.frequency[front], rtol=1e-10, atol=0)
    e, e_s = b.frequency_error[front], stepped.frequency_error[front]
    assert np.array_equal(np.isfinite(e), np.isfinite(e_s))
    assert np.allclose(e[np.isfinite(e)], e_s[np.isfinite(e_s)], rtol=0, atol=1e-9)
    assert np.all(stepped.records["error_not_estimated"][front] == 0)
