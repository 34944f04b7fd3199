"""The accuracy-against-cost comparison behind ``mmshbm bench`` (quick mode, one-DOF
oscillator: closed-form reference). No assertions on timings: only on accuracy and on
the structure of the rows and files."""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest

from mmshbm.analysis import benchmarking as bm
from mmshbm.fe.oscillator import OneDofOscillator

TARGET = 1e-4


@pytest.fixture(scope="module")
def rows():
    return bm.compare_methods("oscillator", amplitude_gaps=2.0, target=TARGET, repeats=1, quick=True)


def test_rows_have_every_method_and_column(rows):
    assert [r["method"] for r in rows] == ["mmshbm", "penalty", "shooting"]
    for r in rows:
        assert set(bm._COLUMNS) <= set(r)
        assert r["model"] == "oscillator" and r["amplitude_gaps"] == 2.0 and r["target"] == TARGET
        assert r["time_s"] > 0 and r["peak_memory_mib"] > 0
        assert r["newton_iterations"] >= r["continuation_steps"] >= 1
        assert r["settings_tried"] >= 1
        assert r["status"] == "bound:amplitude"


def test_reference_is_the_closed_form(rows):
    exact = float(OneDofOscillator(1.0, 1.0, 4.0, 1.0).frequency(2.0))
    for r in rows:
        assert r["reference_hz"] == pytest.approx(exact, rel=1e-14)
        assert r["reference"].startswith("closed form")


def test_every_method_reaches_the_target_against_the_closed_form(rows):
    exact = float(OneDofOscillator(1.0, 1.0, 4.0, 1.0).frequency(2.0))
    for r in rows:
        assert r["target_met"], r
        # the error is recomputed here from the reported frequency, not trusted
        assert abs(r["frequency_hz"] - exact) / exact <= TARGET
        assert r["error"] == pytest.approx(abs(r["frequency_hz"] - exact) / exact, rel=1e-12)


def test_unknowns_and_settings_match_the_methods(rows):
    by = {r["method"]: r for r in rows}
    H = by["mmshbm"]["harmonics"]
    assert by["mmshbm"]["setting"] == f"H={H}"
    # one massless DOF: H+1 cosines and Ω, and one pole unknown: the oscillator with its
    # node clamped has ω₂ = √5, and ω₂/2 lies in its backbone's range [ω₁, ω_zero-gap]
    assert by["mmshbm"]["unknowns"] == H + 2 + 1
    Hp = by["penalty"]["harmonics"]
    assert by["penalty"]["unknowns"] == 2 * (Hp + 1) + 1  # all 2 DOFs
    assert by["penalty"]["penalty_factor"] > 0
    assert by["shooting"]["unknowns"] == 2              # x of the mass and Ω
    assert by["shooting"]["steps_per_period"] >= 8 and by["shooting"]["harmonics"] == 0
    assert by["mmshbm"]["time_ratio"] == 1.0
    for r in rows:
        assert r["time_ratio"] == pytest.approx(r["time_s"] / by["mmshbm"]["time_s"])


def test_the_chosen_setting_is_robust_on_the_ladder(rows):
    """The chosen H also meets the target at the next rung (the rule in the module docstring)."""
    by = {r["method"]: r for r in rows}
    model, osc = bm.load_model("oscillator")
    exact = float(osc.frequency(2.0))
    ladder = bm._H_LADDER[1]
    H = by["mmshbm"]["harmonics"]
    nxt = ladder[ladder.index(H) + 1]
    f = bm._reached_frequency(bm._backbone(model, "mmshbm", 2.0, {"harmonics": nxt}), 2.0)
    assert abs(f - exact) / exact <= TARGET


def test_write_results_and_table(rows, tmp_path):
    paths = bm.write_results(rows, tmp_path / "bench")
    assert [p.name for p in paths] == ["bench.csv", "bench.md"]
    with paths[0].open() as f:
        table = list(csv.DictReader(f))
    assert [t["method"] for t in table] == ["mmshbm", "penalty", "shooting"]
    for t, r in zip(table, rows, strict=True):
        assert float(t["frequency_hz"]) == r["frequency_hz"]  # full precision (repr)
        assert float(t["error"]) == r["error"]
    md = paths[1].read_text()
    assert md == bm.format_table(rows) + "\n"
    assert md.startswith("| method |") and md.count("\n| ") == 3  # header, then one line per method
    for name in ("MMS-HBM", "penalty-HBM", "shooting", "closed form"):
        assert name in md


def test_subset_of_methods_and_loose_target():
    rows = bm.compare_methods("oscillator", target=1e-2, methods=("mmshbm",), repeats=1, quick=True)
    assert len(rows) == 1 and rows[0]["target_met"]
    assert rows[0]["error"] <= 1e-2
    assert rows[0]["harmonics"] == 3  # H = 3 (7e-3) and H = 5 both meet 1e-2: the cheapest is 3


@pytest.mark.parametrize("kwargs, match", [
    ({"model": "plate"}, "unknown model"),
    ({"model": "beam0"}, "unknown model"),
    ({"methods": ("mmshbm", "fem")}, "unknown method"),
    ({"methods": ()}, "at least one"),
    ({"target": 0.0}, "target"),
    ({"target": 2.0}, "target"),
    ({"amplitude_gaps": -1.0}, "amplitude_gaps"),
    ({"repeats": 0}, "repeats"),
])
def test_bad_input(kwargs, match):
    with pytest.raises(ValueError, match=match):
        bm.compare_methods(**{"model": "oscillator", **kwargs})


def test_format_table_of_nothing():
    assert bm.format_table([]) == "(no results)"


def test_element_scaling_structure():
    rows, p = bm.element_scaling(elements=(2, 4), harmonics=1, repeats=1)
    assert [r["elements"] for r in rows] == [2, 4]
    assert all(r["unknowns"] == 2 * 2 + 1 for r in rows)  # tip w and θ, H+1 = 2 cosines, Ω
    assert math.isfinite(p)
    x = np.log([2, 4])
    y = np.log([r["time_per_iteration_s"] for r in rows])
    assert p == pytest.approx((y[1] - y[0]) / (x[1] - x[0]))
    assert "Cost exponent" in bm.format_scaling(rows, p)
    with pytest.raises(ValueError, match="two element counts"):
        bm.element_scaling(elements=(8,))


@pytest.mark.slow
def test_beam_reference_says_which_and_is_reproducible():
    """On the beam at 2 gaps the exact orbit and MMS-HBM in H do not converge (multiple
    contacts, internal resonances): the reference must say so and be the N-converged
    H = 5 MMS-HBM number; if the exact solver converges one day, it must say that."""
    import mmshbm

    model, osc = bm.load_model("beam8")
    assert osc is None and model.n_dof == 16
    amplitude = 2.0 * model.gap
    ref = bm._reference(model, None, amplitude, 1e-4)
    assert math.isfinite(ref.frequency)
    if ref.equal_h:
        assert ref.label.startswith("equal H: MMS-HBM H=5, N=1024")
        b = mmshbm.backbone(model, harmonics=5, max_amplitude=amplitude, n_samples=1024)
        assert ref.frequency == pytest.approx(b.frequency_at(amplitude), rel=1e-12)
        # the default N agrees with N = 1024 well below the target: N is converged
        b5 = mmshbm.backbone(model, harmonics=5, max_amplitude=amplitude)
        assert abs(b5.frequency_at(amplitude) - ref.frequency) / ref.frequency < 1e-4
    else:
        assert "exact" in ref.label or "H=40" in ref.label


class _StubBranch:
    """The three things ``_reached_frequency`` reads from a Branch."""

    def __init__(self, amplitude, frequency):
        self.amplitude, self.frequency = np.asarray(amplitude, float), np.asarray(frequency, float)

    def __len__(self):
        return len(self.amplitude)

    def frequency_at(self, a):  # Branch.frequency_at's contract: NaN unless reached (rtol 1e-9)
        A, f = self.amplitude, self.frequency
        if a > A.max() * (1 + 1e-9):
            return float("nan")
        return float(np.interp(a, A, f))


def test_reached_frequency_accepts_a_bound_refined_to_a_few_1e9():
    b = _StubBranch([0.5, 1.0, 1.5, 2.0 * (1 - 4e-9)], [1.0, 1.0, 1.2, 1.4])
    assert bm._reached_frequency(b, 2.0) == 1.4            # 4e-9 short: reached
    assert bm._reached_frequency(b, 1.25) == pytest.approx(1.1)
    short = _StubBranch([0.5, 1.0, 1.9], [1.0, 1.0, 1.3])
    assert math.isnan(bm._reached_frequency(short, 2.0))   # 5 % short: not reached
    assert math.isnan(bm._reached_frequency(_StubBranch([], []), 2.0))
