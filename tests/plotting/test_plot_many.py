"""Plots for many branches and the special points."""

import warnings

import numpy as np
import pytest
import scipy.linalg as la

import mmshbm
from mmshbm import BranchWarning, plotting
from mmshbm.analysis.studies import run_study
from mmshbm.core.special_points import SpecialPoint


@pytest.fixture(scope="module")
def gap_study():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BranchWarning)
        return run_study(harmonics=(3,), elements=(4, 6), params={"gap": [1e-3, 2e-3]}, max_amplitude=3,
                         unit="gap", executor="serial")


def test_each_branch_in_its_own_gap(gap_study):
    fig = plotting.plot_study(gap_study)
    ax = fig.axes[0]
    lines = {line.get_label(): line for line in ax.get_lines()}
    labels = plotting.study_labels(gap_study.runs)
    assert len(set(labels)) == len(labels) == 4  # every varying coordinate named: no repeated labels
    assert all("gap=" in lab and "el." in lab for lab in labels)
    for label, branch in zip(labels, gap_study.branches, strict=True):
        y = lines[label].get_ydata()
        np.testing.assert_allclose(y, branch.amplitude / branch.gap)  # its own gap, not the first one's
        assert y.max() == pytest.approx(3.0, rel=1e-6)
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert len(legend) == len(set(legend))
    # reference lines per model: 4 and 6 elements have different linear frequencies
    f1 = [t for t in legend if t.startswith("linear")]
    assert len(f1) == 2 and any("4 el." in t for t in f1) and any("6 el." in t for t in f1)


def test_styles_distinct_for_any_number_of_lines():
    for n in (3, 12, 45, 130):
        runs = [{"harmonics": 5, "E": 2e11 + i} for i in range(n)]
        styles = plotting.study_styles(runs)
        keys = {(s["color"], s["ls"], s.get("marker")) for s in styles}
        assert len(keys) == n
    grid = [{"harmonics": h, "elements": e, "gap": g}
            for h in (1, 3, 5) for e in (8, 21) for g in (1e-3, 2e-3)]
    keys = {(s["color"], s["ls"], s.get("marker")) for s in plotting.study_styles(grid)}
    assert len(keys) == len(grid)


def test_special_points_and_short_end_marked():
    model = mmshbm.OneDofOscillator(1, 1, 4, 1).model()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BranchWarning)
        branch = mmshbm.backbone(model, harmonics=5, max_amplitude=3.0, max_steps=12)
    assert not branch.completed
    branch.special_points += [SpecialPoint("internal_resonance", 5, k=5, j=2, ratio=1.0),
                              SpecialPoint("fold", 7), SpecialPoint("branch_point", 8),
                              SpecialPoint("jump", 10, amplitude_frontier=1.1, amplitude_to=1.4)]
    ax = plotting.plot_backbone(branch).axes[0]
    labels = [line.get_label() for line in ax.get_lines()]
    for name in ("internal resonance", "fold", "branch point", "jump (family not sampled)",
                 "stopped short of its bounds"):
        assert name in labels, name
    texts = [t.get_text() for t in ax.texts]
    assert "5Ω≈f₂" in texts and "max_steps" in texts and any(t.startswith("skipped 1.1") for t in texts)
    jump = next(line for line in ax.get_lines() if line.get_label() == "jump (family not sampled)")
    np.testing.assert_array_equal(jump.get_xdata(), branch.frequency[9:11])


def test_the_family_is_the_line_and_tongues_are_thin():
    """H = 7 on the default beam goes up the 6:1 tongue and back: the branch's line is the
    first mode's family front (NaN-broken at the jumps), the excursion a thin line, and
    each jump is dotted from the family's last point before it."""
    model = mmshbm.default_beam().model(21)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BranchWarning)
        branch = mmshbm.backbone(model, harmonics=7)
    front = branch.family_front()
    assert len(front) < len(branch)
    ax = plotting.plot_backbone(branch, labels=["H7"]).axes[0]
    main = next(line for line in ax.get_lines() if line.get_label() == "H7")
    x = np.asarray(main.get_xdata(), dtype=float)
    np.testing.assert_array_equal(x[np.isfinite(x)], branch.frequency[front])
    thin = next(line for line in ax.get_lines() if line.get_label().startswith("off the family"))
    xt = np.asarray(thin.get_xdata(), dtype=float)
    np.testing.assert_array_equal(xt[np.isfinite(xt)], branch.frequency)
    assert thin.get_linewidth() < main.get_linewidth()
    jumps = [s for s in branch.special_points if s.kind == "jump"]
    dotted = [line for line in ax.get_lines()
              if line.get_linestyle() == ":" and line.get_color() == main.get_color()]
    assert len(dotted) == len(jumps)
    for s, line in zip(jumps, dotted, strict=True):
        i0 = front[front < s.index][-1]
        np.testing.assert_array_equal(line.get_xdata(), branch.frequency[[i0, s.index]])


def test_signal_plots_say_what_they_show():
    model = mmshbm.default_beam().model(8)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BranchWarning)
        branch = mmshbm.backbone(model, harmonics=3, max_amplitude=3e-3)
    i = len(branch) - 1
    fig = plotting.plot_time_signals(branch, [i])
    title = fig.axes[0].get_title(loc="left")
    assert "admissible" in title and "truncated Fourier series (H = 3)" in title
    tip = fig.axes[0].get_lines()
    solid, dashed = tip[0].get_ydata(), tip[1].get_ydata()
    assert solid.max() <= model.gap * 1e3 * (1 + 1e-9) < dashed.max()  # admissible stays off the stop
    force = plotting.plot_contact_force(branch, [i]).axes[0].get_title(loc="left")
    assert "truncated Fourier series of λ (H = 3)" in force and "truncation effect" in force
    exact = plotting.plot_contact_force(branch, [i], admissible=True)
    assert "admissible" in exact.axes[0].get_title(loc="left")
    with pytest.raises(ValueError, match="signals"):
        plotting.plot_time_signals(branch, [i], signals="exact")


def test_zero_gap_frequency_sparse_matches_dense():
    """The reference line on large models comes from a sparse eigen-solve; it equals the
    dense generalized eigenproblem of the closed structure."""
    model = mmshbm.default_beam().model(310)  # 620 DOFs with mass: the sparse path
    closed = np.setdiff1d(np.arange(model.n_dof), [model.contact_dof])
    K, M = model.K.toarray()[np.ix_(closed, closed)], model.M.toarray()[np.ix_(closed, closed)]
    mass = np.flatnonzero(np.diag(M) > 0)
    free = np.setdiff1d(np.arange(len(closed)), mass)
    K_red = K[np.ix_(mass, mass)] - K[np.ix_(mass, free)] @ la.solve(K[np.ix_(free, free)],
                                                                      K[np.ix_(free, mass)])
    n = len(mass)  # inverted form M φ = μ K φ: the lowest λ = 1/μ to full relative accuracy
    lam = 1 / la.eigh(M[np.ix_(mass, mass)], K_red, eigvals_only=True, subset_by_index=(n - 1, n - 1))[0]
    f_open = model.linear_frequencies(1)[0]
    expected = 2 / (1 / f_open + 2 * np.pi / np.sqrt(lam))
    assert model.zero_gap_frequency() == pytest.approx(expected, rel=1e-9)
