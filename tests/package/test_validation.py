"""Bad input at every public entry point: the right exception, and a message naming the value.

Run as a script (``python tests/package/test_validation.py``) to print the table "bad input →
message" of docs/reliability.md from these very cases.
"""

from __future__ import annotations

import re
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest
import scipy.io
import scipy.sparse as sp

import mmshbm
from mmshbm import Model, TimoshenkoBeam, default_beam
from mmshbm.fe import assembly, element
from mmshbm.fe.oscillator import OneDofOscillator
from mmshbm.harmonic.condense import Condensation
from mmshbm.methods.mms.conservative import MMSHBMProblem

M2 = np.diag([1.0, 0.0])
K2 = np.array([[5.0, -4.0], [-4.0, 4.0]])  # the one-DOF oscillator, m = k1 = 1, k2 = 4
STEEL = {"length": 0.5, "width": 0.02, "height": 0.0135, "E": 210e9, "rho": 7850.0}


def osc():
    return OneDofOscillator().model()


def beam(**changes):
    return TimoshenkoBeam(**{**STEEL, **changes})


def from_matrices(M=M2, K=K2, contact_dof=1, gap=0.1, stop_side=1):
    return Model.from_matrices(M, K, contact_dof=contact_dof, gap=gap, stop_side=stop_side)


def npz(tmp: Path, **arrays) -> Path:
    path = tmp / "model.npz"
    np.savez(path, **arrays)
    return path


def garbage(tmp: Path, name: str, content: bytes = b"\x00\x01 not what you think") -> Path:
    path = tmp / name
    path.write_bytes(content)
    return path


def mtx(tmp: Path, name: str, A) -> Path:
    path = tmp / name
    scipy.io.mmwrite(str(path), sp.csr_matrix(A))
    return path


def bad_csr(tmp: Path) -> Path:
    return npz(tmp, M_data=np.ones(2), M_indices=np.array([0, 5]), M_indptr=np.array([0, 1, 2]),
               M_shape=np.array([2, 2]), K=K2, contact_dof=1, gap=0.1)


def problem():
    return MMSHBMProblem(osc(), 3)


# (kind, bad input, call(tmp), exception, regex the message must match: it names the value)
CASES = [
    ("dimension", "TimoshenkoBeam(length=0)", lambda t: beam(length=0.0), ValueError,
     r"length must be positive, got 0\.0"),
    ("dimension", "TimoshenkoBeam(width=-0.02)", lambda t: beam(width=-0.02), ValueError,
     r"width must be positive, got -0\.02"),
    ("material", "TimoshenkoBeam(E=nan)", lambda t: beam(E=float("nan")), ValueError,
     r"E must be finite, got nan"),
    ("material", "TimoshenkoBeam(rho=inf)", lambda t: beam(rho=float("inf")), ValueError,
     r"rho must be finite, got inf"),
    ("material", "TimoshenkoBeam(nu=0.6)", lambda t: beam(nu=0.6), ValueError,
     r"nu must be in \(-1, 0\.5\), got 0\.6"),
    ("material", "TimoshenkoBeam(E='steel')", lambda t: beam(E="steel"), TypeError,
     r"E must be a real number, got str 'steel'"),
    ("dimension", "element_matrices(L=[0.1, -0.1])",
     lambda t: element.element_matrices([0.1, -0.1], **default_beam().section()), ValueError,
     r"L\[1\] = -0\.1"),
    ("material", "element stiffness with kappa=0",
     lambda t: element.stiffness([0.1], 1.0, 1.0, 1.0, 1.0, 0.0), ValueError,
     r"kappa must be positive, got 0\.0"),
    ("mesh", "beam.model(n_elements=0)", lambda t: default_beam().model(0), ValueError,
     r"n_elements must be >= 1, got 0"),
    ("mesh", "beam.model(8, grading=-2)", lambda t: default_beam().model(8, grading=-2.0), ValueError,
     r"grading must be positive, got -2\.0"),
    ("mesh", "assemble with a DOF index 9 of 4", lambda t: assembly.assemble(np.ones((1, 4, 4)),
     np.array([[0, 1, 2, 9]]), 4), ValueError, r"dofs\[0, 3\] = 9 is outside \[0, 3\]"),
    ("material", "OneDofOscillator(k2=0)", lambda t: OneDofOscillator(k2=0.0), ValueError,
     r"k2 must be positive, got 0\.0"),
    ("matrix", "M of shape (2, 3)", lambda t: from_matrices(M=np.ones((2, 3))), ValueError,
     r"M must be square, got shape \(2, 3\)"),
    ("matrix", "M of shape (2, 2, 2)", lambda t: from_matrices(M=np.ones((2, 2, 2))), ValueError,
     r"M must be 2-D, got an array of shape \(2, 2, 2\)"),
    ("matrix", "K non-symmetric", lambda t: from_matrices(K=np.array([[5.0, -4.0], [-3.0, 4.0]])), ValueError,
     r"K must be symmetric: K\[0,1\] = -4\.0 but K\[1,0\] = -3\.0"),
    ("matrix", "K with a NaN", lambda t: from_matrices(K=np.array([[np.nan, -4.0], [-4.0, 4.0]])), ValueError,
     r"K has a non-finite entry nan at \(0, 0\)"),
    ("matrix", "M with an inf", lambda t: from_matrices(M=np.diag([np.inf, 0.0])), ValueError,
     r"M has a non-finite entry inf at \(0, 0\)"),
    ("matrix", "K indefinite (−K)", lambda t: from_matrices(K=-K2), ValueError,
     r"K restricted to the massless DOFs is indefinite \(smallest pivot -4\.000e\+00"),
    ("matrix", "M indefinite (negative mass)", lambda t: from_matrices(M=np.diag([-1.0, 0.0])), ValueError,
     r"M restricted to the DOFs with mass is indefinite \(smallest pivot -1\.000e\+00"),
    ("matrix", "K singular (free-floating mass)", lambda t: from_matrices(K=np.array([[4.0, -4.0],
     [-4.0, 4.0]])), ValueError, r"condensed on the DOFs with mass is singular"),
    ("shape", "M 3×3 with K 2×2", lambda t: from_matrices(M=np.diag([1.0, 0.0, 0.0])), ValueError,
     r"M and K must have the same shape, got \(3, 3\) and \(2, 2\)"),
    ("contact", "contact_dof=2 of 2 DOFs", lambda t: from_matrices(contact_dof=2), ValueError,
     r"contact_dof must be in \[0, 1\], got 2"),
    ("contact", "contact_dof=-1", lambda t: from_matrices(contact_dof=-1), ValueError,
     r"contact_dof must be in \[0, 1\], got -1"),
    ("contact", "contact_dof=1.0 (float)", lambda t: from_matrices(contact_dof=1.0), TypeError,
     r"contact_dof must be an integer, got float 1\.0"),
    ("contact", "MMS-HBM on a contact DOF carrying mass",
     lambda t: mmshbm.backbone(from_matrices(contact_dof=0)), ValueError,
     r"contact DOF \[0\] carries mass, but MMS-HBM needs massless contact DOFs.*with_contact_layer"),
    ("gap", "gap=-1e-3", lambda t: from_matrices(gap=-1e-3), ValueError, r"gap must be >= 0, got -0\.001"),
    ("gap", "beam gap=-1e-3", lambda t: beam(gap=-1e-3), ValueError, r"gap must be >= 0, got -0\.001"),
    ("gap", "model.with_gap(nan)", lambda t: osc().with_gap(float("nan")), ValueError,
     r"gap must be finite, got nan"),
    ("contact", "stop_side=0", lambda t: from_matrices(stop_side=0), ValueError,
     r"stop_side must be \+1 or -1, got 0"),
    ("harmonics", "backbone(harmonics=0)", lambda t: mmshbm.backbone(osc(), harmonics=0), ValueError,
     r"harmonics must be >= 1, got 0"),
    ("harmonics", "backbone(harmonics='5')", lambda t: mmshbm.backbone(osc(), harmonics="5"), TypeError,
     r"harmonics must be an integer, got str '5'"),
    ("harmonics", "backbone(harmonics=5, n_samples=10)",
     lambda t: mmshbm.backbone(osc(), harmonics=5, n_samples=10), ValueError,
     r"n_samples must be >= 2\*harmonics\+1 = 11, got 10"),
    ("amplitude", "start_amplitude=3 >= max_amplitude=2",
     lambda t: mmshbm.backbone(osc(), start_amplitude=3.0, max_amplitude=2.0), ValueError,
     r"start_amplitude \(3 m = 3 gaps\) must be below max_amplitude \(2 m = 2 gaps\)"),
    ("amplitude", "max_amplitude=-1", lambda t: mmshbm.backbone(osc(), max_amplitude=-1.0), ValueError,
     r"max_amplitude must be positive, got -1\.0"),
    ("amplitude", "max_amplitude=nan", lambda t: mmshbm.backbone(osc(), max_amplitude=float("nan")),
     ValueError, r"max_amplitude must be finite, got nan"),
    ("bounds", "bounds={'frequency': (2, 1)}", lambda t: mmshbm.backbone(osc(), bounds={"frequency": (2, 1)}),
     ValueError, r"bounds\['frequency'\] must satisfy lo < hi, got \(2, 1\)"),
    ("bounds", "bounds={'energy': 3.0}", lambda t: mmshbm.backbone(osc(), bounds={"energy": 3.0}),
     ValueError, r"bounds\['energy'\] must be a pair \(lo, hi\), got 3\.0"),
    ("bounds", "bounds on a misspelt quantity 'frequncy'",
     lambda t: mmshbm.backbone(osc(), bounds={"frequncy": (0, 1)}), ValueError,
     r"bounds on unknown quantity 'frequncy'; the problem monitors \['amplitude'"),
    ("method", "method='harmonic'", lambda t: mmshbm.backbone(osc(), method="harmonic"), ValueError,
     r"unknown method 'harmonic'; choose one of \[.*'mmshbm', 'penalty',.* 'shooting'\]"),
    ("option", "misspelt continuation option ds_mx=1",
     lambda t: mmshbm.backbone(osc(), ds_mx=1.0), TypeError,
     r"unknown option 'ds_mx' \(did you mean 'ds_max'\?\) for method 'mmshbm'"),
    ("option", "misspelt method option n_sample=64",
     lambda t: mmshbm.backbone(osc(), n_sample=64), TypeError,
     r"unknown option 'n_sample' \(did you mean 'n_samples'\?\)"),
    ("option", "penalty option given to shooting on massless contacts",
     lambda t: mmshbm.backbone(osc(), method="shooting", penalty_stiffness=1e3), ValueError,
     r"penalty_stiffness applies to contact DOFs with mass"),
    ("option", "r given to shooting",
     lambda t: mmshbm.backbone(osc(), method="shooting", r=1e3), TypeError,
     r"unknown option 'r' .*for method 'shooting'"),
    ("option", "ds=10 > ds_max=1", lambda t: mmshbm.backbone(osc(), ds=10.0, ds_max=1.0), ValueError,
     r"need ds_min <= ds <= ds_max, got 1e-07 <= 10\.0 <= 1\.0"),
    ("option", "max_steps=10.5", lambda t: mmshbm.backbone(osc(), max_steps=10.5), TypeError,
     r"max_steps must be an integer, got float 10\.5"),
    ("option", "r=-1 (proximal parameter)", lambda t: mmshbm.backbone(osc(), r=-1.0), ValueError,
     r"r must be positive, got -1\.0"),
    ("option", "mode=2 on a 1-DOF model", lambda t: mmshbm.backbone(osc(), mode=2), ValueError,
     r"mode must be <= the number of DOFs with mass \(1\), got 2"),
    ("option", "backend='dense'", lambda t: Condensation(osc(), "dense"), ValueError,
     r"backend must be 'auto', 'banded' or 'splu', got 'dense'"),
    ("option", "callback=3", lambda t: mmshbm.backbone(osc(), callback=3), TypeError,
     r"callback must be callable, got int 3"),
    ("type", "backbone('beam')", lambda t: mmshbm.backbone("beam"), TypeError,
     r"model must be an mmshbm.Model, got str"),
    ("index", "time_signals(dofs=[5]) on 2 DOFs",
     lambda t: problem().time_signals(problem().linear_point(0.5), dofs=[5]), ValueError,
     r"dofs must be integer indices in \[0, 1\], got \[5\]"),
    ("index", "harmonic_content(dof=5) on 2 DOFs",
     lambda t: problem().harmonic_content(problem().linear_point(0.5), dof=5), ValueError,
     r"dof must be in \[0, 1\], got 5"),
    ("shape", "evaluate(u) with 3 of 6 unknowns (H+1 cosines, the 2Ω = ω₂ pole, Ω)",
     lambda t: problem().evaluate(np.zeros(3)), ValueError, r"u must have shape \(6,\), got \(3,\)"),
    ("index", "linear_modes(5) on 1 DOF with mass", lambda t: osc().linear_modes(5), ValueError,
     r"n must be <= the number of DOFs with mass \(1\), got 5"),
    ("file", "Model.from_npz(missing file)", lambda t: Model.from_npz(t / "missing.npz"), ValueError,
     r"cannot read model file '.*missing\.npz'.*No such file"),
    ("file", "Model.from_npz(garbage bytes)", lambda t: Model.from_npz(garbage(t, "junk.npz")), ValueError,
     r"cannot read model file '.*junk\.npz': not an \.npz archive"),
    ("file", "Model.from_npz(no K)", lambda t: Model.from_npz(npz(t, M=M2, contact_dof=1, gap=0.1)),
     ValueError, r"model file '.*model\.npz' has no matrix 'K'"),
    ("file", "Model.from_npz(no contact_dof)", lambda t: Model.from_npz(npz(t, M=M2, K=K2)), ValueError,
     r"model file '.*model\.npz' has no 'contact_dof'; pass contact_dof=\.\.\."),
    ("file", "Model.from_npz(contact_dof=[1, 2]) on 2 DOFs",
     lambda t: Model.from_npz(npz(t, M=M2, K=K2, contact_dof=np.array([1, 2]), gap=0.1)), ValueError,
     r"contact_dof\[1\] must be in \[0, 1\], got 2"),
    ("file", "Model.from_npz(contact_dof=[[1]])",
     lambda t: Model.from_npz(npz(t, M=M2, K=K2, contact_dof=np.array([[1]]), gap=0.1)), ValueError,
     r"'contact_dof' must be a number or a 1-D array of numbers"),
    ("file", "Model.from_npz(CSR index 5 in a 2×2)", lambda t: Model.from_npz(bad_csr(t)), ValueError,
     r"the CSR parts of 'M' are malformed: indices must be < 2"),
    ("file", "Model.from_npz(description not JSON)",
     lambda t: Model.from_npz(npz(t, M=M2, K=K2, contact_dof=1, gap=0.1, description="{oops")), ValueError,
     r"'description' is not valid JSON"),
    ("file", "Model.from_matrix_market(missing M)",
     lambda t: Model.from_matrix_market(t / "M.mtx", mtx(t, "K.mtx", K2), 1, 0.1), ValueError,
     r"cannot read M from '.*M\.mtx'"),
    ("file", "Model.from_matrix_market(garbage K)",
     lambda t: Model.from_matrix_market(mtx(t, "M.mtx", M2), garbage(t, "K.mtx", b"hello\n"), 1, 0.1),
     ValueError, r"cannot read K from '.*K\.mtx'"),
    ("file", "backbone(resume=garbage file)",
     lambda t: mmshbm.backbone(osc(), resume=garbage(t, "x.ckpt", b"{}\n")), ValueError,
     r"'.*x\.ckpt' is not an mmshbm checkpoint"),
    ("file", "backbone(checkpoint=in a missing directory)",
     lambda t: mmshbm.backbone(osc(), checkpoint=t / "no" / "x.ckpt"), ValueError,
     r"checkpoint directory '.*no' does not exist"),
]


@pytest.mark.parametrize("kind, what, call, error, match", CASES, ids=[c[1] for c in CASES])
def test_bad_input_is_named(tmp_path, kind, what, call, error, match):
    with pytest.raises(error) as info:
        call(tmp_path)
    assert info.type is error  # exactly the documented type, not a subclass surprise
    assert re.search(match, str(info.value)), f"{info.value!s} does not match {match!r}"


def test_there_are_at_least_twenty_kinds():
    assert len({c[1] for c in CASES}) >= 20 and len({c[0] for c in CASES}) >= 10


def table() -> str:
    """The markdown table "bad input → message" of all cases."""
    rows = ["| kind | bad input | exception: message |", "|---|---|---|"]
    with tempfile.TemporaryDirectory() as tmp:
        for kind, what, call, error, _ in CASES:
            try:
                call(Path(tmp))
                message = "(no error!)"
            except error as err:
                message = f"{type(err).__name__}: {err}".replace(tmp, "<dir>").replace("|", "\\|")
            rows.append(f"| {kind} | {what} | `{message}` |")
    return "\n".join(rows)


if __name__ == "__main__":  # pragma: no cover
    sys.stdout.write(table() + "\n")


# ---------------------------------------------------------------------------- failing Newton
def converged(problem, states, tol=1e-8):
    """Largest scaled residual over the states (the real problem, no failure injection)."""
    return max(float(np.max(np.abs(problem.evaluate(u, jacobian=False)))) for u in states)


def test_exact_pole_at_the_start_is_regular_with_pole_unknowns():
    """k2 = 3 k1: the closed-contact frequency ω2 = 2 rad/s is exactly twice the linear
    one, so D_2(Ω) has a pole on the whole linear part of the backbone and the
    factorisation of K_ll − (2Ω)² M_ll is exactly singular at the first point. With the
    pole carried by an unknown (the default) the branch starts there and runs to its
    bound against the closed form; without (poles=False) the start fails with a status
    saying why, not a crash."""
    from mmshbm.harmonic.condense import SingularDynamicStiffness

    osc = OneDofOscillator(1.0, 1.0, 3.0, 0.1)
    model = osc.model()
    p = MMSHBMProblem(model, 3, poles=False)
    assert p.unpack(p.linear_point(0.05))[1] == 1.0  # Ω exactly ω1, 2Ω exactly ω2
    with pytest.raises(SingularDynamicStiffness, match=r"harmonic 2 of Ω sits on (an|the) "):
        p.evaluate(p.linear_point(0.05))
    br = mmshbm.backbone(model, harmonics=3, poles=False)
    assert len(br) == 0
    assert br.status.startswith("start failed") and "harmonic 2 of Ω" in br.status
    br = mmshbm.backbone(model, harmonics=3)
    assert br.status == "bound:amplitude" and br.frequency[0] == pytest.approx(1 / (2 * np.pi), rel=1e-12)
    f = osc.frequency(br.amplitude[-1])
    assert abs(br.frequency[-1] - f) / f < 1e-2  # H = 3 truncation error


class PoleWindow:
    """The MMS-HBM problem of the oscillator, whose condensation raises the genuine
    SingularDynamicStiffness within a relative ``width`` of the pole 2Ω = ω2 (as a
    factorisation with a pivot threshold would)."""

    def __init__(self, width):
        from mmshbm.harmonic.condense import SingularDynamicStiffness

        self.osc = OneDofOscillator(1.0, 1.0, 4.0, 1.0)
        # the LU back end: its dynamic_stiffness is what the Python corrector calls (the
        # modal one runs a compiled corrector that this injection cannot reach)
        self.problem = MMSHBMProblem(self.osc.model(), 3, projection="sampled", poles=False, backend="banded")
        self.pole = self.osc.omega_closed / 2
        self.hits = 0
        real = self.problem.cond.dynamic_stiffness

        def dynamic_stiffness(omega, harmonics, derivative=True):
            if abs(omega - self.pole) < width * self.pole:
                self.hits += 1
                raise SingularDynamicStiffness(f"K_ll - (2·{omega:.6g} rad/s)^2 M_ll is singular")
            return real(omega, harmonics, derivative)

        self.problem.cond.dynamic_stiffness = dynamic_stiffness
        self.reference = MMSHBMProblem(self.osc.model(), 3, projection="sampled", poles=False)

    def run(self, follow="path"):
        from mmshbm.core.continuation import ContinuationOptions, continue_branch
        from mmshbm.family.follower import default_events

        p = self.problem
        # the effort rule's steps (as in mmshbm 0.1): halving then carries the branch over the
        # injected window; the residual rule creeps up to it instead (then a jump passes it)
        opt = ContinuationOptions(bounds={"amplitude": (0.0, 10.0)}, follow=follow, step_control="effort")
        return continue_branch(p, p.linear_point(0.5), p.initial_tangent(), opt,
                               events=default_events(opt, continue_branch))


def test_a_singular_step_is_halved_and_the_branch_goes_on():
    case = PoleWindow(2e-3)
    res = case.run()
    assert case.hits >= 1  # an iterate met the singular factorisation
    assert res.status == "bound:amplitude"
    omega = 2 * np.pi * res.records["frequency"]
    assert omega.min() < case.pole < omega.max()  # the branch crossed kΩ = ω2
    assert converged(case.reference, res.u) < 1e-8
    f_exact = case.osc.frequency(res.records["amplitude"])
    assert np.max(np.abs(res.records["frequency"] / f_exact - 1)) < 2e-2  # H = 3 truncation error ~1 %


def test_a_singular_region_stops_the_branch_with_every_converged_point():
    width = 5e-3
    case = PoleWindow(width)
    res = case.run()
    assert res.status.startswith("ds_min: step size fell below 1e-07")
    assert "is singular" in res.status
    omega = 2 * np.pi * res.records["frequency"]
    assert len(res.u) > 5 and omega.max() < case.pole
    # halving crept up to the edge of the singular region
    assert omega.max() > case.pole * (1 - width) * (1 - 1e-4)
    assert converged(case.reference, res.u) < 1e-8
    assert res.special_points[-1] == ("endpoint", len(res.u) - 1)
    # following the family (the default), the branch jumps the region and reaches its bound
    res = PoleWindow(width).run(follow="family")
    assert res.status == "bound:amplitude"
    jumps = [s for s in res.special_points if s[0] == "jump"]
    assert len(jumps) == 1 and jumps[0].data["reason"] == "ds_min"
    assert converged(case.reference, res.u) < 1e-8


def test_ds_min_status_through_backbone_keeps_the_branch():
    """A step budget that Newton cannot meet: one iteration to a tolerance of 1e-14 (too tight
    for the accept-by-prediction rule) fails every corrector off the linear part; the
    Branch still holds the converged points and says why."""
    model = OneDofOscillator(1.0, 1.0, 4.0, 1.0).model()
    br = mmshbm.backbone(model, harmonics=3, max_newton=1, newton_tol=1e-14, ds_min=1e-3)
    assert br.status.startswith("ds_min") and "no convergence in 1 iterations" in br.status
    assert len(br) >= 2 and not br.completed
    assert converged(br.solver, br.states) < 1e-8
