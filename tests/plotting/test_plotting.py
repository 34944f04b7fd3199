"""Plots: headless, files written, and the drawn data are the branch's numbers."""

import sys

import numpy as np
import pytest
from locations import TESTS
from matplotlib.figure import Figure

import mmshbm
from mmshbm import plotting
from mmshbm.analysis import studies
from mmshbm.analysis.measured import MeasuredBackbone


@pytest.fixture(scope="module")
def branch():
    return mmshbm.backbone(mmshbm.default_beam().model(6), harmonics=3, max_amplitude=6e-3)


def _vlines(ax):
    """x positions of the vertical reference lines (axvline: two equal x data)."""
    return [ln.get_xdata()[0] for ln in ax.get_lines()
            if len(ln.get_xdata()) == 2 and ln.get_xdata()[0] == ln.get_xdata()[1]]


def test_backbone_data_and_reference_lines(branch, tmp_path):
    model = branch.get_model()
    fig = plotting.plot_backbone(branch, path=tmp_path / "b.png")
    assert isinstance(fig, Figure) and (tmp_path / "b.png").stat().st_size > 10_000
    ax = fig.axes[0]
    curve = ax.get_lines()[0]
    np.testing.assert_array_equal(curve.get_xdata(), branch.frequency)
    np.testing.assert_allclose(curve.get_ydata(), branch.amplitude / model.gap, rtol=1e-15)
    xs = _vlines(ax)
    f = model.linear_frequencies(3)
    assert f[0] in xs and model.zero_gap_frequency() in xs
    lo, hi = branch.frequency.min(), branch.frequency.max()
    # f_j/n only for the harmonics n <= H = 3 the ansatz carries (f2/4, f2/5 would fall in range too)
    inside = {n: {fk / n for fk in f[1:] if 0.97 * lo <= fk / n <= 1.03 * hi} for n in range(2, 11)}
    expected = set().union(*(inside[n] for n in (2, 3)))
    beyond = set().union(*(inside[n] for n in range(4, 11)))
    assert beyond and not beyond & set(xs)
    assert expected <= set(xs)


def test_several_branches_and_measured_overlay(branch, tmp_path):
    other = mmshbm.backbone(mmshbm.default_beam().model(6), harmonics=1, max_amplitude=6e-3)
    meas = MeasuredBackbone.from_arrays([50.0, 55.0], [2e-3, 4e-3], source="lab")
    fig = plotting.plot_backbone([branch, other], labels=["a", "b"], measured=meas, reference_lines=False)
    lines = fig.axes[0].get_lines()
    assert [ln.get_label() for ln in lines[:3]] == ["a", "b", "measured (lab)"]
    np.testing.assert_allclose(lines[2].get_ydata(), [2.0, 4.0])
    with pytest.raises(ValueError):
        plotting.plot_backbone([branch], labels=["a", "b"])
    with pytest.raises(ValueError):
        plotting.plot_backbone([])


def test_frequency_energy(branch):
    fig = plotting.plot_frequency_energy(branch)
    np.testing.assert_allclose(fig.axes[0].get_lines()[0].get_ydata(), np.log10(branch.energy))


def test_time_signals_are_the_branch_signals(branch, tmp_path):
    pts = plotting.points_at(branch, [1.5e-3, 4e-3])
    assert branch.amplitude[pts[0]] >= 1.5e-3 > branch.amplitude[pts[0] - 1]
    fig = plotting.plot_time_signals(branch, pts, path=tmp_path / "t.png", signals="series")
    model = branch.get_model()
    assert len(fig.axes) == len(model.c) == 2  # tip deflection and tip rotation
    t, q = branch.time_signals(pts[1], dofs=[int(d) for d in model.c], n_samples=256)
    for ax, qd in zip(fig.axes, q, strict=True):
        np.testing.assert_allclose(ax.get_lines()[1].get_ydata()[:-1], 1e3 * qd)
    assert "deflection" in fig.axes[0].get_ylabel() and "rotation" in fig.axes[1].get_ylabel()


def test_contact_force_and_harmonics(branch, tmp_path):
    i = len(branch) - 1
    fig = plotting.plot_contact_force(branch, [i], path=tmp_path / "f.png")
    lam = branch.contact_force(i, 512)[1]
    np.testing.assert_allclose(fig.axes[0].get_lines()[0].get_ydata()[:-1], lam)
    assert lam.max() == pytest.approx(branch.contact_force_max[i], rel=0.05)
    fig = plotting.plot_harmonic_content(branch, i, path=tmp_path / "h.png")
    heights = [p.get_height() for p in fig.axes[0].patches]
    np.testing.assert_allclose(heights, 1e3 * branch.harmonic_content(i))
    assert len(heights) == branch.harmonics + 1


def test_figure2_layout(tmp_path):
    st = studies.run_study(harmonics=(1, 3), elements=(4, 6), executor="serial", max_amplitude=4.0,
                           unit="gap")
    fig = plotting.plot_figure2(st, marks=(1.5, 3.0), path=tmp_path / "fig2.png")
    left, top, middle, bottom = fig.axes
    assert len(left.get_legend().get_texts()) >= 4
    assert "deflection" in top.get_ylabel() and "rotation" in middle.get_ylabel()
    assert "contact force" in bottom.get_ylabel()
    assert len(bottom.get_lines()) == 2  # one per marked point
    marked = st.branch(harmonics=3, elements=6)
    f_lin = marked.get_model().linear_frequencies(1)[0]
    assert f_lin in _vlines(left)  # reference lines of the marked run's model


def test_headless_no_pyplot_state(branch):
    before = len(sys.modules["matplotlib.pyplot"].get_fignums()) if "matplotlib.pyplot" in sys.modules else 0
    plotting.plot_backbone(branch)
    plotting.plot_contact_force(branch, [0])
    after = len(sys.modules["matplotlib.pyplot"].get_fignums()) if "matplotlib.pyplot" in sys.modules else 0
    assert after == before


def test_plotting_never_imports_pyplot(tmp_path):
    import subprocess

    code = ("import sys, mmshbm, mmshbm.plotting as p; "
            "b = mmshbm.backbone(mmshbm.OneDofOscillator().model(), harmonics=3, max_amplitude=2.0); "
            f"p.plot_backbone(b, path={str(tmp_path / 'o.png')!r}); "
            "assert 'matplotlib.pyplot' not in sys.modules")
    env = {"MPLBACKEND": "", "PATH": "/usr/bin:/bin", "HOME": str(tmp_path)}
    subprocess.run([sys.executable, "-c", code], check=True, env=env, timeout=120)
    assert (tmp_path / "o.png").is_file()


def test_point_index_checks(branch):
    with pytest.raises(IndexError):
        plotting.plot_contact_force(branch, [len(branch)])


def test_a_family_that_turns_back_in_amplitude_after_grazing_is_drawn_as_the_family():
    """A chain whose contact-DOF amplitude falls after grazing (0.94 → 0.78 gaps while the
    frequency rises from 1.177 to 1.19 Hz), on the family throughout: those points are
    not on the family front (single-valued in amplitude) but are the family's, so the
    backbone's line runs through them; only the tongue's excursion is drawn thin."""
    import warnings

    sys.path.insert(0, str(TESTS))
    from test_homotopy import _rattling_chain

    model = _rattling_chain()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", mmshbm.BranchWarning)
        b = mmshbm.backbone(model, harmonics=5, max_amplitude=10 * model.gap)
    on = np.asarray(b.records["on_family"]) > 0.5
    first = np.arange(int(np.argmin(on)))  # the stretch on the family from the start
    A = np.asarray(b.amplitude)
    turned = first[A[first] < np.maximum.accumulate(A[first]) * (1 - 1e-9)]
    assert len(turned) >= 5 and not set(turned) & set(b.family_front().tolist())
    line = plotting.plot_backbone(b).axes[0].get_lines()[0]
    drawn = set(np.asarray(line.get_xdata())[np.isfinite(line.get_xdata())].tolist())
    assert {float(b.frequency[i]) for i in first} <= drawn
    assert not {float(b.frequency[i]) for i in np.flatnonzero(~on)} & drawn


def test_amplitude_axis_names_what_the_amplitude_measures(branch):
    """A user's chain is labelled by its amplitude DOF, not as a beam's tip; a beam and a
    chain (models with different numbers of modes) drawn together."""
    M = np.diag([1.0, 1.0, 0.0])
    K = np.array([[2000.0, -1000, 0], [-1000, 6000, -5000], [0, -5000, 5000]])
    on_contact = mmshbm.Model.from_matrices(M, K, contact_dof=2, gap=0.01, stop_side=1)
    on_mass = mmshbm.Model.from_matrices(M, K, contact_dof=2, gap=0.01, stop_side=1, amplitude_dof=1)
    chain = mmshbm.backbone(on_contact, harmonics=3, max_amplitude=0.03)
    assert plotting.plot_backbone(branch).axes[0].get_ylabel() == "tip amplitude / gap"
    assert plotting.plot_backbone(chain).axes[0].get_ylabel() == "contact DOF amplitude / gap"
    by_mass = mmshbm.backbone(on_mass, harmonics=3, max_amplitude=0.03)
    assert plotting.plot_backbone(by_mass).axes[0].get_ylabel() == "amplitude of q[1] / gap"
    both = plotting.plot_backbone([branch, chain]).axes[0]
    assert both.get_ylabel() == "amplitude / its gap"
    assert len([t for t in both.get_legend().get_texts() if t.get_text().startswith("linear f")]) == 2


def test_a_clearance_is_drawn_with_its_limit_with_the_node_held():
    """Both gaps → 0 (or the amplitude → ∞): the node is held between its stops all the
    time, so the backbone rises toward the first frequency of M, K with the node held
    (an eigenproblem of the 2 × 2 blocks), drawn as the zero-gap limit."""
    import scipy.linalg as sl

    M = np.diag([1.0, 1.0, 0.0])
    K = np.array([[2000.0, -1000, 0], [-1000, 6000, -5000], [0, -5000, 5000]])
    model = mmshbm.Model.from_matrices(M, K, contact_dof=[2, 2], gap=[0.01, 0.01], stop_side=[1, -1])
    f_held = np.sqrt(sl.eigh(K[:2, :2], M[:2, :2], eigvals_only=True)[0]) / (2 * np.pi)
    b = mmshbm.backbone(model, harmonics=7)
    ax = plotting.plot_backbone(b).axes[0]
    assert any(abs(x - f_held) <= 1e-9 * f_held for x in _vlines(ax))
    assert b.frequency[-1] < f_held < 1.02 * b.frequency[-1]


def test_the_one_dof_zero_gap_limit_is_labelled_an_estimate_on_a_chain():
    """2/(1/f_open + 1/f_held) is the bilinear limit of one DOF with mass; a chain's first
    mode can pass it (docs/resonances.md), so on a chain the legend calls it an estimate."""
    osc = mmshbm.OneDofOscillator(1, 1, 4, 1).model()
    M = np.diag([1.0, 1.0, 0.0])
    K = np.array([[2000.0, -1000, 0], [-1000, 6000, -5000], [0, -5000, 5000]])
    chain = mmshbm.Model.from_matrices(M, K, contact_dof=2, gap=0.01, stop_side=1)
    labels = {}
    for name, model in (("oscillator", osc), ("chain", chain)):
        b = mmshbm.backbone(model, harmonics=3, max_amplitude=2 * model.gap)
        texts = [t.get_text() for t in plotting.plot_backbone(b).axes[0].get_legend().get_texts()]
        labels[name] = [t for t in texts if t.startswith("zero-gap limit")]
    assert labels["oscillator"] == [f"zero-gap limit {osc.zero_gap_frequency():.2f} Hz"]
    assert labels["chain"] == [f"zero-gap limit (one-DOF estimate) {chain.zero_gap_frequency():.2f} Hz"]


def test_labels_of_special_points_do_not_crowd():
    """A clearance that jumps ten tongues within a few tenths of a gap (corpus seed 28
    index 225): of the labels of its special points (tongues named, skipped intervals)
    none is placed next to another (anchors at least 0.12 of the width or 0.035 of the
    height apart) nor runs past the right edge; every marker stays."""
    from validation import corpus

    model = corpus.generate(226, 28)[225].model()
    b = mmshbm.backbone(model, harmonics=15, max_amplitude=10 * model.gap)
    ax = plotting.plot_backbone(b).axes[0]
    mine = [t for t in ax.texts if t.get_text().startswith("skipped") or "Ω≈" in t.get_text()]
    assert len(mine) >= 3
    to_axes = ax.transData + ax.transAxes.inverted()
    anchors = [to_axes.transform(t.xy) for t in mine]
    for i, p in enumerate(anchors):
        for q in anchors[:i]:
            assert abs(p[0] - q[0]) >= 0.12 or abs(p[1] - q[1]) >= 0.035
    jumps = sum(1 for sp in b.special_points if sp.kind == "jump")
    diamonds = [ln for ln in ax.get_lines() if ln.get_marker() == "D"]
    assert jumps >= 8 and len(diamonds) >= 8
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    renderer = FigureCanvasAgg(ax.figure).get_renderer()  # labels near the right edge open to the left
    assert all(t.get_window_extent(renderer).x1 <= ax.bbox.x1 + 1 for t in mine)
