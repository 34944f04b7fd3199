"""Figures of studies read at a glance whatever the number of runs: no layout warning, no
text over text, nothing clipped at the figure's edge, a legend that does not grow with the
runs; resonance lines and markers only where the runs can and do resonate."""

import warnings
from dataclasses import replace

import numpy as np
import pytest
from matplotlib.text import Text

import mmshbm
from mmshbm import BranchWarning, ModelWarning, plotting
from mmshbm.analysis import studies
from mmshbm.cli import main


@pytest.fixture(scope="module")
def grid():
    """15 runs (H 1 3 5 7 11 x 6 8 21 elements) to 10 gaps: internal resonances, jumps and
    skipped intervals in most of them."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BranchWarning)
        return studies.run_study(harmonics=(1, 3, 5, 7, 11), elements=(6, 8, 21), executor="serial")


def _render(make):
    """Draw the figure ``make()`` returns (to PNG) and return it with the warnings raised."""
    import io

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fig = make()
        fig.savefig(io.BytesIO(), format="png", dpi=100)
    return fig, [str(w.message) for w in caught if not issubclass(w.category, BranchWarning)]


def _drawn_texts(fig) -> list[Text]:
    """The texts the figure draws: titles, axis and tick labels of the ticks in view,
    annotations, legends, figure texts."""
    out = list(fig.texts) + [t for leg in fig.legends for t in leg.get_texts()]
    for ax in fig.axes:
        if not ax.get_visible():
            continue
        out += [ax.title, ax._left_title, ax._right_title, ax.xaxis.label, ax.yaxis.label, *ax.texts]
        for axis in (ax.xaxis, ax.yaxis):
            out += [tick.label1 for tick in axis._update_ticks()]
        if ax.get_legend() is not None:
            out += ax.get_legend().get_texts()
    return [t for t in out if t.get_visible() and t.get_text().strip()]


def _overlaps(fig) -> list[tuple[str, str]]:
    """Pairs of drawn texts whose boxes overlap; and texts reaching past the figure's edge,
    paired with "figure edge"."""
    renderer = fig._get_renderer()
    frame = fig.bbox
    boxes = [(t.get_text(), t.get_window_extent(renderer)) for t in _drawn_texts(fig)]
    out = []
    for n, (a, box) in enumerate(boxes):
        if box.x0 < frame.x0 - 1 or box.x1 > frame.x1 + 1 or box.y0 < frame.y0 - 1 or box.y1 > frame.y1 + 1:
            out.append((a, "figure edge"))
        for b, other in boxes[n + 1:]:
            if box.overlaps(other):
                out.append((a, b))
    return out


def test_cli_plot_of_a_large_grid_study_reads_at_a_glance(grid, tmp_path, capsys):
    from mmshbm.plotting.grids import plot_family_grid

    path = tmp_path / "study.npz"
    grid.save(path)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert main(["plot", str(path), "--out", str(tmp_path)]) == 0
    assert not [w for w in caught if "layout" in str(w.message)]
    out, err = capsys.readouterr()
    points = [line for line in out.splitlines() if line.startswith("point ")]
    assert len(points) == 3 and all(line.endswith("(H11, 21 el.)") for line in points)
    assert "constrained_layout" not in err
    # what the runs' checks found: one line of counts, not a warning per finding
    assert len(err.splitlines()) == 1 and "mmshbm plot: warning: 15 runs: 15 reached their bounds" in err
    fig, messages = _render(lambda: plot_family_grid(grid, amplitudes=(), marks=(1.5, 3.0, 6.0)))
    assert messages == []
    assert _overlaps(fig) == []
    titles = [ax.get_title() for ax in fig.axes if ax.get_visible()]
    assert titles == ["6 elements", "8 elements", "21 elements"]
    legend = fig.legends[0].get_texts()
    assert len(legend) <= 5 + 3 + 3  # H values, marked points, three kinds of line: not one per run


@pytest.mark.parametrize("make", ["figure2", "family_grid", "convergence", "energy"])
def test_grid_figures_have_no_layout_warning_and_no_overlapping_text(grid, make):
    from mmshbm.plotting.grids import plot_convergence, plot_family_grid

    runs, styles = grid.runs, plotting.study_styles(grid.runs)
    labels = plotting.study_labels(runs)

    def energy():
        fig = plotting.plot_frequency_energy(grid.branches, labels, styles=styles)
        plotting.studies.study_legend(fig.axes[0], runs, styles, labels, fontsize=7, ncol=2)
        return fig

    makers = {"figure2": lambda: plotting.plot_figure2(grid, marks=(1.5, 3.0, 6.0)),
              "family_grid": lambda: plot_family_grid(grid, amplitudes=(2.0, 5.0, 10.0)),
              "convergence": lambda: plot_convergence(grid, amplitudes=(2.0, 5.0, 10.0)),
              "energy": energy}
    fig, messages = _render(makers[make])
    assert messages == []
    if make != "energy":  # the energy plot's legend may cover curves, not texts
        assert _overlaps(fig) == []
    if make in ("figure2", "energy"):  # an entry per value of H and of elements, not one per run
        legend = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
        assert not set(labels) & set(legend)
        assert {"H1", "H11", "6 el.", "21 el."} <= set(legend)


def test_figure2_marks_points_on_the_family_of_the_marked_run(grid):
    fig = plotting.plot_figure2(grid, marks=(1.5, 3.0, 6.0))
    marked = grid.branch(harmonics=11, elements=21)
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts() if t.get_text().startswith("marked")]
    front = marked.family_front()
    expected = []
    for a in (1.5, 3.0, 6.0):
        f = marked.frequency_at(a * marked.gap)
        if np.isnan(f):  # inside a skipped interval: the front's nearest point stands in
            f = marked.frequency[front[np.argmin(np.abs(marked.amplitude[front] - a * marked.gap))]]
        expected.append(f)
    assert [float(lab.split(": ")[1].split(" Hz")[0]) for lab in labels] == pytest.approx(expected, abs=0.006)


def test_resonance_markers_only_where_the_branch_resonates(tmp_path, capsys):
    """The default backbone names 4Ω≈f₂ at its last point (10 gaps, kΩ/ω = 0.97, on its
    way there): not a resonance it met; 5Ω≈f₂ it passed is."""
    model = mmshbm.default_beam().model(21)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BranchWarning)
        branch = mmshbm.backbone(model, harmonics=5)
    last = [sp for sp in branch.special_points
            if sp[0] == "internal_resonance" and int(sp[1]) == len(branch) - 1]
    assert last  # what the continuation names at its end
    texts = [t.get_text() for t in plotting.plot_backbone(branch).axes[0].texts]
    assert "5Ω≈f₂" in texts and "4Ω≈f₂" not in texts
    assert main(["backbone", "-v", "--out", str(tmp_path)]) == 0  # -v: the resonances it met
    out = capsys.readouterr().out
    assert "5Ω≈f₂ at" in out and "4Ω≈f₂" not in out


def test_symmetric_clearance_has_odd_resonance_lines_only():
    from mmshbm.plotting.data import BranchData, reference_frequencies, resonance_orders, symmetric_clearance

    clearance = mmshbm.ClearanceOscillator(m=1.0, k1=1.0, k2=4.0, gap=1.0).model()
    assert symmetric_clearance(clearance)
    assert not symmetric_clearance(mmshbm.default_beam().model(6))
    assert resonance_orders(7, 10, odd=True) == [3, 5, 7]
    assert resonance_orders(3, 10) == [2, 3] and resonance_orders(0, 4) == [2, 3, 4]
    model = mmshbm.default_beam().model(6)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BranchWarning)
        data = BranchData.of(mmshbm.backbone(model, harmonics=7, max_amplitude=4e-3))
    f2 = model.linear_frequencies(2)[1]

    def lines(d):
        fig = plotting.plot_backbone(d, model=reference_frequencies(model))
        return {round(f2 / ln.get_xdata()[0], 6) for ln in fig.axes[0].get_lines()
                if len(ln.get_xdata()) == 2 and ln.get_xdata()[0] == ln.get_xdata()[1]
                and abs(f2 / ln.get_xdata()[0] - round(f2 / ln.get_xdata()[0])) < 1e-9}

    assert {6.0, 5.0} <= lines(data)  # f2/6 and f2/5 fall in the range at H = 7
    odd = lines(replace(data, odd_harmonics=True))
    assert 5.0 in odd and 6.0 not in odd


def test_frequency_energy_is_drawn_like_the_backbone():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BranchWarning)
        branch = mmshbm.backbone(mmshbm.default_beam().model(21), harmonics=5)
    front = branch.family_front()
    assert len(front) < len(branch)  # the branch has an excursion into the 5:2 tongue
    ax = plotting.plot_frequency_energy(branch).axes[0]
    solid, thin = ax.get_lines()[:2]
    assert np.count_nonzero(np.isfinite(solid.get_ydata())) == len(front)
    np.testing.assert_allclose(np.sort(solid.get_ydata()[np.isfinite(solid.get_ydata())]),
                               np.sort(np.log10(branch.energy[front])))
    assert thin.get_linewidth() < 0.5 * solid.get_linewidth()


def test_backbone_labels_do_not_overlap_at_h15():
    """H = 15 names a dozen resonances and skipped intervals near 1.2–2 gaps: their labels
    are moved apart (or left to the legend), never drawn over each other."""
    from matplotlib.text import Annotation

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BranchWarning)
        warnings.simplefilter("ignore", ModelWarning)  # a left-out mode's pole reached once (the run's own)
        branch = mmshbm.backbone(mmshbm.default_beam().model(21), harmonics=15)
    fig, messages = _render(lambda: plotting.plot_backbone(branch))
    assert messages == []
    ax = fig.axes[0]
    labels = [t for t in ax.texts if isinstance(t, Annotation) and t.get_visible()]
    assert len(labels) >= 8
    renderer = fig._get_renderer()
    boxes = [(t.get_text(), t.get_window_extent(renderer)) for t in labels]
    clashes = [(a, b) for n, (a, p) in enumerate(boxes) for b, q in boxes[n + 1:] if p.overlaps(q)]
    assert clashes == []
