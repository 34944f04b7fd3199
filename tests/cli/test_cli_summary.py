"""``mmshbm backbone`` prints one line saying what the result is and how far to trust it;
the findings stay in the result and behind ``-v``, and a result that is not the backbone
asked for (cut short, another family beyond it) still warns and exits 1."""

import warnings

import mmshbm
from mmshbm.cli import main

SMALL = ["--elements", "4", "-H", "3", "--max-amplitude", "3"]  # 4 elements, H = 3, to 3 gaps


def _run(argv, tmp_path, capsys):
    code = main(["backbone", *argv, "--out", str(tmp_path)])
    out, err = capsys.readouterr()
    return code, out.splitlines(), err.splitlines(), mmshbm.load(tmp_path / "backbone.npz")


def test_a_complete_run_prints_one_line_and_the_files(tmp_path, capsys):
    code, out, err, branch = _run(SMALL, tmp_path, capsys)
    assert code == 0 and err == []
    assert [line for line in out[1:] if not line.startswith("wrote ")] == []
    summary = out[0]
    front = branch.family_front()
    top = branch.amplitude[front].max()
    f = branch.frequency[front]
    assert summary.startswith("mmshbm backbone: MMS-HBM, H = 3: complete: the backbone of linear mode 1 to "
                              f"3 gaps, {f.min():.4g}–{f.max():.4g} Hz; ")
    # how far to trust it: the branch's own truncation estimate at the top of its backbone
    est = branch.truncation_error(top)
    assert est.harmonics == (3, 6, 12)
    trust = f"frequency error from truncation ≈ {est.error:.1e} at 3 gaps (estimate from H = 3, 6, 12"
    assert trust in summary
    # the findings are kept in the result; the line names the truncated series' pass of the stop
    kinds = {x.kind: x for x in branch.findings}
    assert {"penetration", "negative_force"} <= set(kinds)
    assert f"passes the stop by up to {kinds['penetration'].value:.2g} gaps" in summary
    assert summary.endswith("; details: -v")


def test_verbose_prints_every_finding(tmp_path, capsys):
    code, out, err, branch = _run([*SMALL, "-v"], tmp_path, capsys)
    assert code == 0
    warned = [line for line in err if line.startswith("mmshbm backbone: warning: ")]
    # the two truncation effects make one warning (mmshbm.results.diagnostics)
    assert len(warned) == 1 and "passes the stop" in warned[0] and "pulls" in warned[0]
    assert out[0].startswith("mmshbm backbone: MMS-HBM, H = 3: complete")


def test_cut_short_warns_and_exits_1(tmp_path, capsys):
    code, out, err, branch = _run([*SMALL, "--max-steps", "3"], tmp_path, capsys)
    assert code == 1 and not branch.completed
    assert out[0].startswith("mmshbm backbone: MMS-HBM, H = 3: incomplete (max_steps): ")
    assert len(err) == 1 and "warning: mmshbm branch ended short of its bounds" in err[0]
    assert "max_steps = 3" in err[0]


def test_another_family_beyond_the_backbone_warns_and_exits_1(tmp_path, capsys):
    """Shooting's branch leaves mode 1 just above grazing (docs/shooting.md): the summary
    says how far the backbone goes, the warnings say what the rest is."""
    code, out, err, branch = _run([*SMALL, "--method", "shooting"], tmp_path, capsys)
    assert code == 1
    end = branch.amplitude[branch.family_front()].max() / branch.gap
    assert end < 1.5
    assert f"to {end:.3g} gaps (another family beyond)" in out[0] and "no truncation in H" in out[0]
    assert any("shooting branch leaves the family of linear mode 1" in line for line in err)
    assert any(f"the backbone of linear mode 1 ends at {end:.3g} gaps" in line and "(exit code 1)" in line
               for line in err)


def test_a_warning_the_summary_does_not_cover_is_printed(tmp_path, capsys, monkeypatch):
    import mmshbm.methods.backbone as api

    real = api.backbone

    def warns(model, **kwargs):
        branch = real(model, **kwargs)
        warnings.warn("something the checks do not know", mmshbm.BranchWarning, stacklevel=2)
        return branch

    monkeypatch.setattr(api, "backbone", warns)
    code, out, err, branch = _run(SMALL, tmp_path, capsys)
    assert code == 0
    assert err == ["mmshbm backbone: warning: something the checks do not know"]
