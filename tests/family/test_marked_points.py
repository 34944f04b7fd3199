"""Points chosen by amplitude are solved on the family front, and frequency_at says when
an amplitude is outside the backbone (metres or gaps)."""

import re
import warnings

import numpy as np
import pytest

import mmshbm
from mmshbm import BranchWarning, plotting
from mmshbm.cli import main


@pytest.fixture(scope="module")
def h5():
    """The default backbone (21 elements, H = 5): past 2 gaps it makes an excursion into
    the 5:2 tongue whose stored points lie near 3 gaps at 58 Hz, off the family."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BranchWarning)
        return mmshbm.backbone(mmshbm.default_beam().model(21), harmonics=5)


def test_frequency_at_outside_the_backbone_warns_with_the_range_in_m_and_gaps(h5):
    with pytest.warns(BranchWarning, match=r"0\.0005\.\.0\.01 m \(0\.5\.\.10 gaps\).*unit='gap'"):
        assert np.isnan(h5.frequency_at(2))  # 2 m: a user thinking in gaps
    with pytest.warns(BranchWarning, match=r"frequency_at\(-1 m\).*0\.5\.\.10 gaps"):
        assert np.isnan(h5.frequency_at(-1))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # inside the range: not a word
        assert h5.frequency_at(3, unit="gap") == h5.frequency_at(3e-3)
    with pytest.raises(ValueError, match="unit"):
        h5.frequency_at(3, unit="mm")


def test_marked_points_are_solved_on_the_family_not_the_nearest_stored_point(h5):
    gap = h5.gap
    marked = h5.solve_at([1.5, 3.0, 6.0], unit="gap")
    np.testing.assert_allclose(marked.amplitude / gap, [1.5, 3.0, 6.0], rtol=1e-8)
    for a, f in zip((1.5, 3.0, 6.0), marked.frequency, strict=True):
        assert f == pytest.approx(h5.frequency_at(a * gap), rel=1e-9)
    assert marked.records["solved"].tolist() == [1, 1, 1]
    assert np.all(marked.records["mode_share"] >= 0.5)  # the first mode's family
    # the first stored point reaching 3 gaps is on the tongue, > 4 Hz below the backbone
    (i,) = plotting.points_at(h5, [3e-3])
    assert marked.frequency[1] - h5.frequency[i] > 4.0
    # its signals are the solved orbit's: the contact DOF's excursion is the amplitude
    _, q = marked.time_signals(1, dofs=[h5.get_model().contact_dof], n_samples=1024)
    assert np.max(np.abs(q)) == pytest.approx(3 * gap, rel=0.02)


def test_plot_prints_and_labels_the_marked_points(h5, tmp_path, capsys):
    path = tmp_path / "b.npz"
    h5.save(path)
    assert main(["plot", str(path), "--kind", "backbone", "harmonics", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    lines = [ln for ln in out.splitlines() if ln.startswith("point ")]
    assert len(lines) == 3
    found = [re.fullmatch(r"point (\d): (\d+\.\d\d) Hz, ([\d.]+) gaps", ln) for ln in lines]
    assert all(found)
    f = [float(m.group(2)) for m in found]
    assert [float(m.group(3)) for m in found] == [1.5, 3.0, 6.0]
    np.testing.assert_allclose(f, [h5.frequency_at(a * h5.gap) for a in (1.5, 3, 6)], atol=0.006)
    fig = plotting.plot_backbone(h5, marks=h5.solve_at([1.5, 3, 6], unit="gap"))
    labels = fig.axes[0].get_legend_handles_labels()[1]
    expected = [f"marked point {n}: {x:.2f} Hz, {a:.2g} gaps"
                for n, x, a in zip((1, 2, 3), f, (1.5, 3, 6), strict=True)]
    assert [lab for lab in labels if lab.startswith("marked point")] == expected


def test_a_point_beyond_the_front_is_the_nearest_family_point(h5):
    marked = h5.solve_at([20.0], unit="gap", stand_in=True)
    assert marked.records["solved"].tolist() == [0]
    assert marked.amplitude[0] == pytest.approx(h5.amplitude[h5.family_front()[-1]], rel=1e-9)


def test_without_a_solver_the_stored_family_points_stand_in(h5):
    from dataclasses import replace

    bare = replace(h5, solver=None, model=None, metadata={**h5.metadata, "model": {}})
    with pytest.raises(RuntimeError, match="no solver"):
        bare._require_solver()
    marked = bare.solve_at([1.5 * h5.gap, 3.0 * h5.gap], stand_in=True)
    front = h5.family_front()
    assert marked.solver is None and marked.records["solved"].tolist() == [0, 0]
    for a, f in zip((1.5, 3.0), marked.frequency, strict=True):
        i = front[np.argmin(np.abs(h5.amplitude[front] - a * h5.gap))]
        assert f == h5.frequency[i]
