"""The convergence study in H and elements and the study throughput: tables honest about
empty cells (named resonances) and non-monotone series, chunked executors, Monte-Carlo samples,
the CLI on a tiny grid."""

import concurrent.futures as cf
import math

import numpy as np
import pytest

from mmshbm.analysis import skips as sk
from mmshbm.analysis import studies
from mmshbm.analysis.convergence import ConvergenceFit, local_order
from mmshbm.cli import main
from mmshbm.core.special_points import SpecialPoint
from mmshbm.io import load
from mmshbm.results.branch import Branch

# ----------------------------------------------------------------- convergence fits


def test_local_order_is_exact_for_power_laws_with_any_spacing():
    x = np.array([8.0, 21.0, 40.0])
    for p in (0.5, 1.0, 2.0, 4.0):
        f = 45.0 + 12.0 * x**-p
        assert local_order(x, f) == pytest.approx(p, rel=1e-8)
        assert local_order(x, -f) == pytest.approx(p, rel=1e-8)  # decreasing series too
    assert math.isnan(local_order(x, [1.0, 2.0, 1.5]))  # the steps change sign
    assert math.isnan(local_order([1.0, 2.0, 3.0], [0.0, 1.0, 3.0]))  # steps grow: no p > 0


def test_oscillating_series_has_no_rate_but_its_spread():
    """Harmonic balance on a contact problem: the frequency error changes sign with H."""
    H = np.array([3.0, 5.0, 7.0, 9.0, 11.0])
    f = np.array([65.0, 66.2, 66.4, 66.43, 66.40])
    fit = ConvergenceFit.fit("harmonics", {"elements": 21}, 5.0, "gap", H, f)
    assert math.isnan(fit.rate) and fit.n_fit == 0 and math.isnan(fit.error_estimate)
    assert fit.rate_note.startswith("oscillates") and "9→11" in fit.rate_note
    np.testing.assert_allclose(fit.steps, np.diff(f))
    assert fit.spread == pytest.approx(0.03) and not fit.monotone


def test_disagreeing_local_orders_and_missing_cells_give_no_rate():
    x = np.array([1.0, 3.0, 7.0, 9.0, 11.0, 15.0])
    f = np.array([52.0, 57.1, 57.46, 58.29, 58.89, 59.06])  # monotone, steps not a power law
    fit = ConvergenceFit.fit("harmonics", {}, 2.0, "gap", x, f)
    assert math.isnan(fit.rate) and "disagree" in fit.rate_note
    f[-2] = np.nan
    fit = ConvergenceFit.fit("harmonics", {}, 2.0, "gap", x, f)
    assert math.isnan(fit.rate) and fit.rate_note == "no value at H = 11"
    assert fit.spread == pytest.approx(59.06 - 57.46)  # the three finest with a value
    assert math.isnan(ConvergenceFit.fit("elements", {}, 2.0, "gap", x[:3], f[:3]).rate)


# ----------------------------------------------------------------- skipped intervals


def _synthetic_branch():
    """A first-mode family front 0..3, an excursion 4..6 into the 5:2 tongue, a jump
    landing at point 7 beyond it, the front going on to 10 gaps; gap 1 mm."""
    A = 1e-3 * np.array([1.0, 1.5, 1.8, 1.9, 1.95, 2.1, 2.3, 2.4, 4.0, 7.0, 10.0])
    f = np.array([46.0, 52.0, 55.0, 56.5, 57.2, 57.3, 57.1, 62.0, 66.0, 69.0, 70.0])
    on = np.array([1, 1, 1, 1, 0, 0, 0, 1, 1, 1, 1], dtype=float)
    shares = np.zeros((len(A), 3, 6))
    shares[:, 0, 1] = np.where(on > 0, 0.9, 0.1)
    shares[:, 1, 5] = 1.0 - shares[:, 0, 1]  # harmonic 5 of mode 2 takes the rest
    n = len(A)
    special = [SpecialPoint("start", 0),
               SpecialPoint("internal_resonance", 5, k=5, j=2, ratio=5 * 57.3 / 286.1, share=0.9,
                            mode_frequency=286.1),
               SpecialPoint("jump", 7, reason="excursion", from_index=3), SpecialPoint("endpoint", n - 1)]
    return Branch(frequency=f, amplitude=A, energy=np.ones(n), contact_force_max=np.ones(n),
                  newton_iterations=np.ones(n, dtype=int), step_size=np.ones(n), states=np.zeros((n, 3)),
                  status="bound:amplitude", method="mmshbm", harmonics=5, special_points=special,
                  metadata={"model_gap": 1e-3, "elapsed_s": 0.5},
                  records={"on_family": on, "mode_share": shares[:, 0, :].sum(axis=1),
                           "modal_shares": shares})


def test_nan_cells_name_the_skipped_resonance():
    b = _synthetic_branch()
    (s,) = sk.skips(b)
    assert (s.index_lo, s.index_hi, s.kind, s.reason, s.excursion) == (3, 7, "jump", "excursion", 3)
    assert s.resonances[0][:2] == (5, 2) and s.discontinuous
    a = 2.2e-3
    assert math.isnan(b.frequency_at(a))  # the branch's own answer: inside the skipped interval
    note = sk.explain(b, a, b.frequency_at(a))
    assert "5Ω ≈ ω2" in note and "k:j = 5:2" in note and "jumped 1.9–2.4 gaps" in note
    assert "beyond the branch" in sk.explain(b, 12e-3, math.nan)
    b.status = "max_steps"
    assert sk.explain(b, 12e-3, math.nan).startswith("not reached: stopped at 10 gaps")
    # finite values: a caution next to the frequency jump (56.5 -> 62 Hz), none far from it
    assert "discontinuity" in sk.explain(b, 2.44e-3, 62.1)
    assert sk.explain(b, 7e-3, 69.0) == ""
    assert sk.mode_share_at(b, 5.5e-3) == pytest.approx(0.9)
    assert sk.partner_at(b, 5.5e-3) == (5, 2, pytest.approx(0.1))
    assert math.isnan(sk.mode_share_at(b, 2.2e-3))
    c = sk.cell_summary(b)
    assert c["jumps"] == 1 and c["on_family"] == 8 and c["resonances"] == ["5:2"]
    assert c["skipped"] == [(pytest.approx(1.9), pytest.approx(2.4), (5, 2))]


def test_passage_without_resonance_point_named_from_modal_shares(monkeypatch):
    b = _synthetic_branch()
    b.special_points = [p for p in b.special_points if p[0] not in ("internal_resonance", "jump")]

    class _Model:
        @staticmethod
        def linear_frequencies(n):
            return np.array([45.8, 286.1, 796.9])[:n]

    monkeypatch.setattr(Branch, "get_model", lambda self: _Model())
    (s,) = sk.skips(b)
    assert s.kind == "passage" and s.resonances[0][:2] == (5, 2)
    assert s.resonances[0][2] == pytest.approx(5 * b.frequency[4] / 286.1)


# ----------------------------------------------------------------- real study

GRID = {"harmonics": (3, 5), "elements": (4, 6), "max_amplitude": 3.0, "unit": "gap"}


@pytest.fixture(scope="module")
def grid():
    return studies.run_study(executor="serial", **GRID)


def test_table_notes_every_empty_cell(grid):
    """The H5 runs cross 5Ω = ω2 (f2/5 ≈ 59–62 Hz on these coarse meshes) near 2–2.4 gaps
    without folding: the backbone goes on through the crossing (docs/resonances.md), the
    resonance is named, and no interval is skipped. Cells in a skipped interval would be
    NaN with the resonance named, or lie on its edge and say so; cells beyond the branch
    say so; the rest have no note."""
    amps = list(np.round(np.arange(1.9, 2.45, 0.01), 2)) + [4.0]
    table = grid.table(amps)
    nan_inside = 0
    for i, (r, b) in enumerate(grid):
        intervals = [s for s in sk.skips(b) if s.width > sk.WIDE * s.hi]
        for j, a in enumerate(amps):
            f, note = table.frequency[i, j], table.notes[i][j]
            assert f == b.frequency_at(a * 1e-3) or (np.isnan(f) and np.isnan(b.frequency_at(a * 1e-3)))
            inside = [s for s in intervals if s.lo <= a * 1e-3 <= s.hi]
            if a == 4.0:
                assert np.isnan(f) and "beyond the branch" in note
            elif inside and np.isnan(f):
                nan_inside += 1
                assert "k:j = 5:2" in note and "gaps" in note
                # the named resonance is real: five times the branch frequency in there is mode 2's
                s = inside[0]
                f2 = b.get_model().linear_frequencies(2)[1]
                assert np.any(np.abs(5 * b.frequency[s.index_lo + 1:s.index_hi + 1] / f2 - 1) < 0.02)
            elif inside:
                assert "at the edge of 5Ω ≈ ω2" in note
            elif np.isnan(f):
                raise AssertionError(f"NaN outside a skipped interval: {r}, {a}")
            elif not any(s.discontinuous and s.lo * 0.98 <= a * 1e-3 <= s.hi * 1.02 for s in intervals):
                assert note == "", (r, a, note)
        assert not intervals and np.all(np.isfinite(table.frequency[i, :-1]))
        if r["harmonics"] == 5:
            named = {(s.data["k"], s.data["j"]) for s in b.special_points if s.kind == "internal_resonance"}
            assert (5, 2) in named
            assert np.all(b.records["on_family"] == 1.0)
    assert nan_inside == 0
    text = table.pivot_text()
    assert "first mode's share of the kinetic energy" in text and "harmonics=5, elements=4: beyond" in text
    md = table.pivot_text(markdown=True)
    assert md.count("| elements \\ harmonics | 3 | 5 |") == len(amps)


def test_report_and_csv_carry_the_notes(grid, tmp_path):
    report = grid.report([2.3, 4.0])
    assert "Per run: points on the family" in report and "wall time: 4 runs" in report
    assert "beyond the branch" in report
    lines = grid.to_csv(tmp_path / "t.csv", [2.3]).read_text().splitlines()
    assert lines[0].split(",")[-3:] == ["mode_share_at_2.3gap", "partner_at_2.3gap", "note_at_2.3gap"]


# ----------------------------------------------------------------- executors and samples


def _same(a, b):
    assert a.runs == b.runs
    for x, y in zip(a.branches, b.branches, strict=True):
        assert x.states.tobytes() == y.states.tobytes() and x.frequency.tobytes() == y.frequency.tobytes()


def test_monte_carlo_is_a_seeded_latin_hypercube():
    s = studies.monte_carlo(8, {"gap": (1e-3, 2e-3), "E": (2e11, 2e11)}, seed=3)
    strata = np.floor((np.array(s["gap"]) - 1e-3) / 1e-3 * 8)
    assert sorted(strata) == list(range(8))  # one draw per stratum
    assert s["E"] == [2e11] * 8
    assert s == studies.monte_carlo(8, {"gap": (1e-3, 2e-3), "E": (2e11, 2e11)}, seed=3)
    with pytest.raises(ValueError, match="low <= high"):
        studies.monte_carlo(3, {"gap": (2.0, 1.0)})


def test_samples_vary_together_and_are_validated():
    specs = studies.grid_specs(harmonics=(1, 3), elements=(4,),
                               samples={"gap": [1e-3, 2e-3], "E": [2e11, 2.1e11]})
    got = [(s.harmonics, s.coords["sample"], s.source["beam"]["gap"], s.source["beam"]["E"]) for s in specs]
    assert got == [(1, 0, 1e-3, 2e11), (1, 1, 2e-3, 2.1e11), (3, 0, 1e-3, 2e11), (3, 1, 2e-3, 2.1e11)]
    assert all("sample" not in s.options and "E" not in s.options for s in specs)
    with pytest.raises(ValueError, match="equal lengths"):
        studies.grid_specs(elements=(4,), samples={"gap": [1e-3], "E": [2e11, 2.1e11]})
    with pytest.raises(ValueError, match="both"):
        studies.grid_specs(elements=(4,), params={"gap": [1e-3]}, samples={"gap": [1e-3]})


def test_chunked_executors_give_identical_numbers():
    samples = studies.monte_carlo(5, {"gap": (0.8e-3, 1.5e-3), "rho": (7.5e3, 8e3)}, seed=1)
    kw = {"harmonics": (1, 3), "elements": (4,), "samples": samples, "max_amplitude": 2.0, "unit": "gap"}
    serial = studies.run_study(executor="serial", **kw)
    assert len(serial) == 10
    pooled = studies.run_study(executor="process", workers=2, chunksize=3, **kw)
    _same(serial, pooled)
    assert pooled.metadata["tasks"] == 4 and pooled.metadata["chunksize"] == 3
    assert 0 < pooled.metadata["busy_s"]
    with cf.ThreadPoolExecutor(2) as pool:
        _same(serial, studies.run_study(executor=pool, chunksize=4, **kw))
    with pytest.raises(ValueError, match="chunksize"):
        studies.run_study(executor="serial", chunksize=0, **kw)


# ----------------------------------------------------------------- command line


def test_cli_study_grid_writes_table_and_plots(tmp_path, capsys):
    code = main(["study", "-H", "3", "5", "--elements", "4", "6", "--max-amplitude", "3",
                 "--amplitudes", "2.3", "--executor", "serial", "--out", str(tmp_path)])
    assert code == 0
    for name in ("study.png", "study_convergence.png", "study_table.csv", "study_table.txt", "study.npz"):
        assert (tmp_path / name).stat().st_size > 0, name
    out = capsys.readouterr().out
    assert "wall time: 4 runs" in out and "4 reached their bounds" in out
    # the details file's per-run table names the resonance the H = 5 runs cross (5Ω ≈ f₂)
    assert "5:2" in (tmp_path / "study_table.txt").read_text()
    study = load(tmp_path / "study.npz")
    rows = (tmp_path / "study_table.csv").read_text().splitlines()[1:]
    for r, line in zip(study.runs, rows, strict=True):
        f = study.branch(harmonics=r["harmonics"], elements=r["elements"]).frequency_at(2.3e-3)
        assert line.split(",")[3] == ("nan" if np.isnan(f) else f"{f:.10g}")
