"""The continuation problem protocol (mmshbm.core.problem), the Status of a branch, the
driver's event plug-ins and the family options forwarded by ContinuationOptions."""

import ast
import copy
import json
import pickle
from pathlib import Path

import numpy as np
import pytest
from roundoff import assert_roundoff_close, product_scale

import mmshbm
from mmshbm.core import problem as protocol
from mmshbm.core.continuation import ContinuationOptions, continue_branch
from mmshbm.core.events import BranchEvents, NoEvents, Relocation
from mmshbm.core.special_points import SpecialPoint
from mmshbm.core.status import Status
from mmshbm.family.follower import FamilyFollower, default_events
from mmshbm.family.options import FamilyOptions
from mmshbm.methods.frequency_response import FORCED_METHODS, make_forced_problem
from mmshbm.methods.registry import METHODS, make_problem

PACKAGE = Path(mmshbm.__file__).parent
CAPABILITIES = (protocol.StepControl, protocol.PinnedSolves, protocol.FamilyEvents, protocol.BranchRecords)


def _member_names(proto) -> set:
    names = set(getattr(proto, "__annotations__", {}))
    names |= {n for n, v in vars(proto).items() if callable(v) and not n.startswith("_")}
    return names


#: every name of the protocol (required and capabilities)
PROTOCOL_NAMES = set().union(*(_member_names(p) for p in (
    protocol.ContinuationProblem, *CAPABILITIES, protocol.AmplitudeStart, protocol.FrequencyStart)))
#: names that hold problems in the code of the driver and the runners
PROBLEM_NAMES = {"problem", "aux", "filt", "solver"}


def _probe_lines(source: str) -> list:
    """Lines of the getattr/hasattr calls in ``source`` on a problem object, for a
    protocol name, or on ``self`` for a fixed name (a capability or a cache that a class
    should declare)."""
    out = []
    for node in ast.walk(ast.parse(source)):
        if not (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
                and node.func.id in ("getattr", "hasattr") and len(node.args) >= 2):
            continue
        target, name = node.args[0], node.args[1]
        fixed = isinstance(name, ast.Constant)
        on_problem = ((isinstance(target, ast.Name) and target.id in PROBLEM_NAMES)
                      or (isinstance(target, ast.Attribute) and target.attr == "problem"))
        on_self = isinstance(target, ast.Name) and target.id == "self" and fixed
        for_protocol = fixed and name.value in PROTOCOL_NAMES
        if on_problem or on_self or for_protocol:
            out.append(node.lineno)
    return sorted(out)


def test_no_probing_of_problems_in_the_driver_and_the_methods():
    """Neither the driver (core/) nor any method module (methods/) asks a problem, or a
    problem class itself, whether it has an attribute: capabilities and caches are
    declared (``ContinuationProblemBase``, class attributes, ``__init__``). Probes of
    other objects (a model's ``friction``, a modal condensation's ``reduction``, a
    matrix's ``toarray``) stay."""
    files = sorted((PACKAGE / "core").glob("*.py")) + sorted((PACKAGE / "methods").rglob("*.py"))
    found = [f"{f.relative_to(PACKAGE)}:{n}" for f in files
             for n in _probe_lines(f.read_text(encoding="utf-8"))]
    assert found == []


def test_the_probe_rule_sees_a_probe():
    source = ("def f(problem, self, model, other, names):\n"
              "    return (hasattr(problem, 'x'), getattr(self, '_cache', None),\n"
              "            getattr(model, 'friction', ()), getattr(self.cond, 'backend', None),\n"
              "            hasattr(other, 'fast_newton'), [getattr(self, n) for n in names])\n")
    assert _probe_lines(source) == [2, 2, 4]


def test_the_driver_reads_no_domain_record():
    """continue_branch and its steps name no record of a backbone or a response."""
    domain = {"amplitude", "frequency", "mode_share", "fundamental_share", "on_family", "energy"}
    for name in ("continuation.py", "steps.py", "events.py"):
        tree = ast.parse((PACKAGE / "core" / name).read_text(encoding="utf-8"))
        docstrings = {id(n.body[0].value) for n in ast.walk(tree)
                      if isinstance(n, ast.Module | ast.FunctionDef | ast.ClassDef) and n.body
                      and isinstance(n.body[0], ast.Expr) and isinstance(n.body[0].value, ast.Constant)}
        used = {n.value for n in ast.walk(tree) if isinstance(n, ast.Constant) and id(n) not in docstrings
                and isinstance(n.value, str)}
        assert not used & domain, (name, used & domain)


def test_continue_branch_reads_in_one_sitting():
    tree = ast.parse((PACKAGE / "core" / "continuation.py").read_text(encoding="utf-8"))
    fn = next(n for n in tree.body if isinstance(n, ast.FunctionDef) and n.name == "continue_branch")
    assert fn.end_lineno - fn.body[0].end_lineno < 120  # the code after the docstring


# --------------------------------------------------------------------------- registered problems
@pytest.fixture(scope="module")
def models():
    beam = mmshbm.default_beam().model(8)
    damped = beam.with_damping(modal_ratio=0.01)
    M = np.diag([1.0, 0.0])
    K = np.array([[3.0, -2.0], [-2.0, 2.0]])
    base = mmshbm.Model.from_matrices(M, K, [], [], [], damping=np.diag([0.05, 0.0]), amplitude_dof=0)
    return beam, damped, base.with_friction(1, 0.5, normal_load=1.0)


def _force(model):
    """A unit force on the first DOF with mass."""
    dof = next(i for i in range(model.n_dof) if i not in set(model.c.tolist()))
    return np.eye(model.n_dof)[dof]


def _backbone_problems(models):
    beam, damped, friction = models
    for method in METHODS:
        model = damped if method in ("epmc", "phase_resonance") else beam
        options = {} if method == "shooting" else {"harmonics": 3}
        if method == "phase_resonance":
            options["force"] = _force(model)
        yield method, make_problem(model, method, **options)
    yield "epmc (friction)", make_problem(friction, "epmc", harmonics=3)


def _forced_problems(models):
    _, damped, friction = models
    force = _force(damped)
    for method in FORCED_METHODS:
        yield method, make_forced_problem(damped, force, method, 3)
        yield f"{method} (friction)", make_forced_problem(friction, [1.0, 0.0], method, 3)


def test_every_registered_problem_satisfies_the_protocol(models):
    seen = set()
    for kind, start, problems in (("backbone", protocol.AmplitudeStart, _backbone_problems(models)),
                                  ("forced", protocol.FrequencyStart, _forced_problems(models))):
        for name, p in problems:
            seen.add(type(p).__name__)
            assert isinstance(p, protocol.ContinuationProblemBase), name
            for proto in (protocol.ContinuationProblem, *CAPABILITIES, start):
                assert isinstance(p, proto), (kind, name, proto.__name__)
            assert protocol.as_problem(p) is p
            assert p.step_control in ("effort", "residual")
            u = p.linear_mode_point(1e-4) if kind == "backbone" else p.linear_response_point(1.0)
            assert u.shape == (p.n_unknowns,)
            R, J = p.residual_and_jacobian(u)
            assert R.shape == (p.n_unknowns - 1,) and J.shape == (p.n_unknowns - 1, p.n_unknowns)
            # residual() and residual_and_jacobian() may take different paths to R: equal to
            # the round-off of R's terms, |J||u| (the linear part) summed over the unknowns;
            # the transforms between time and harmonics mix every row, so each row's round-off
            # is also ε times the largest row's terms (a row of zeros computed as 1e-18·1e-19)
            J = J.toarray() if hasattr(J, "toarray") else J
            terms = product_scale(J, u) + np.abs(R)
            residual = p.residual(u)
            assert_roundoff_close(residual, R, terms + terms.max(), terms=p.n_unknowns,
                                  err_msg=f"{kind} {name}")
            np.testing.assert_array_equal(p.evaluate(u, jacobian=False), residual)  # the same call
            np.testing.assert_array_equal(p.linear_point(1e-4 if kind == "backbone" else 1.0), u)  # alias
    assert len(seen) == 13


def test_capabilities_not_offered_are_none(models):
    beam, _, _ = models
    mms = make_problem(beam, "mmshbm", harmonics=3)
    shooting = make_problem(beam, "shooting")
    assert mms.step_control == "residual" and shooting.step_control == "effort"
    assert mms.family_predictor is not None and shooting.family_predictor is None
    assert mms.amplitude_and_gradient is not None and shooting.amplitude_and_gradient is None
    assert shooting.H == 0 and shooting.solver_settings() == {"N": shooting.N, "mode": 1}


#: the numbers a resumed backbone of each method must match (its checkpoint's "solver" entry)
SETTINGS = {"mmshbm": {"H", "N", "r", "mode"}, "penalty": {"H", "N", "mode", "penalty_stiffness"},
            "penalty-reduced": {"H", "N", "mode", "penalty_stiffness"}, "shooting": {"N", "mode"},
            "epmc": {"H", "N", "mode"}}


@pytest.mark.parametrize("method", sorted(SETTINGS))
def test_solver_settings_name_what_a_resume_must_match(models, method):
    """Each problem class names its settings (setting_names): a class that forgot one
    would let a checkpoint resume with another penalty stiffness, proximal parameter or
    mode. The pole scaling is MMS-HBM's own convention, not a member of the base."""
    beam, damped, _ = models
    options = {} if method == "shooting" else {"harmonics": 3}
    p = make_problem(damped if method == "epmc" else beam, method, **options)
    settings = p.solver_settings()
    assert set(settings) == SETTINGS[method]
    assert all(isinstance(v, int | float) and not isinstance(v, bool) for v in settings.values())
    assert p.state_convention() == ({"pole_scaling": "force-or-motion"} if method == "mmshbm" else {})
    assert "pole_scaling" not in vars(protocol.ContinuationProblemBase)


class Circle:
    """x² + y² = 1: a problem with the required protocol only."""

    n_unknowns = 2
    step_control = "residual"  # not a capability of a plain object: the driver ignores it

    def residual(self, u):
        return np.array([u @ u - 1.0])

    def residual_and_jacobian(self, u):
        return self.residual(u), 2 * u[None, :]

    def monitor(self, u):
        return {"x": float(u[0]), "y": float(u[1])}


class OldCircle:
    """The circle with the earlier protocol: one ``evaluate`` for R and (R, J)."""

    n_unknowns = 2

    def evaluate(self, u, jacobian=True):
        R = np.array([u @ u - 1.0])
        return (R, 2 * u[None, :]) if jacobian else R

    def monitor(self, u):
        return {"x": float(u[0]), "y": float(u[1])}


class OldCircleProblem(OldCircle, protocol.ContinuationProblemBase):
    """The earlier protocol on the base: ``evaluate`` overridden, nothing else."""

    measure = None


class NewCircleProblem(Circle, protocol.ContinuationProblemBase):
    """The circle on the base with the two methods."""

    measure = None
    step_control = "effort"


def test_a_plain_problem_gets_the_defaults():
    wrapped = protocol.as_problem(Circle())
    assert isinstance(wrapped, protocol.ContinuationProblemBase)
    assert wrapped.step_control == "effort" and wrapped.fast_newton is None
    with pytest.raises(TypeError, match="n_unknowns, residual"):
        protocol.as_problem(object())


def test_residual_and_jacobian_agree_with_the_compatibility_evaluate():
    u = np.array([0.6, -0.3])
    R, J = np.array([u @ u - 1.0]), 2 * u[None, :]
    for p in (NewCircleProblem(), OldCircleProblem(), protocol.as_problem(Circle()),
              protocol.as_problem(OldCircle())):
        np.testing.assert_array_equal(p.residual(u), R)
        np.testing.assert_array_equal(p.residual_and_jacobian(u)[1], J)
        np.testing.assert_array_equal(p.evaluate(u, jacobian=False), R)
        np.testing.assert_array_equal(p.evaluate(u)[1], J)
    assert isinstance(OldCircle(), protocol.EvaluateProblem)
    assert not isinstance(OldCircle(), protocol.ContinuationProblem)


def test_a_problem_with_only_the_old_evaluate_runs_the_driver():
    """The earlier protocol (``evaluate`` alone) on the base and as a plain object follows
    the same circle, point for point, as the two new methods do."""
    start, tangent = np.array([0.0, -1.0]), np.array([1.0, 0.0])
    opt = ContinuationOptions(bounds={"x": (-0.5, 2.0)})
    runs = [continue_branch(p, start, tangent, opt)
            for p in (NewCircleProblem(), OldCircleProblem(), Circle(), OldCircle())]
    for res in runs:
        assert res.status == "bound:x" and len(res.u) > 5
        np.testing.assert_allclose(np.hypot(*res.u.T), 1.0, atol=1e-10)
    np.testing.assert_array_equal(runs[1].u, runs[0].u)  # measure None on both
    np.testing.assert_array_equal(runs[3].u, runs[2].u)  # the plain objects: every default


def test_a_problem_with_neither_protocol_says_so():
    class Empty(protocol.ContinuationProblemBase):
        n_unknowns = 2

    for call in (lambda p: p.residual(np.zeros(2)), lambda p: p.residual_and_jacobian(np.zeros(2)),
                 lambda p: p.evaluate(np.zeros(2))):
        with pytest.raises(NotImplementedError, match="defines neither"):
            call(Empty())


# --------------------------------------------------------------------------- Status
@pytest.mark.parametrize("kind, detail, text", [
    ("max_steps", "", "max_steps"),
    ("bound", "amplitude", "bound:amplitude"),
    ("ds_min", "step size fell below 1e-07 (x)", "ds_min: step size fell below 1e-07 (x)"),
    ("jump failed", "no landing", "jump failed: no landing"),
    ("start failed", "singular Jacobian", "start failed: singular Jacobian"),
    ("start outside bounds", "", "start outside bounds"),
    ("interrupted", "", "interrupted"),
])
def test_status_round_trips(kind, detail, text):
    s = Status(kind, detail)
    assert s == text and str(s) == text and type(str(s)) is str
    back = Status.parse(text)
    assert (back.kind, back.detail, back) == (kind, detail, text)
    for copied in (pickle.loads(pickle.dumps(s)), copy.deepcopy(s)):
        assert isinstance(copied, Status) and (copied.kind, copied.detail) == (kind, detail)
    assert json.loads(json.dumps({"status": s})) == {"status": text}
    assert hash(s) == hash(text)
    with pytest.raises(AttributeError):
        s.kind = "other"


def test_status_with_a_failed_rescue_keeps_its_kind():
    s = Status(Status.DS_MIN, "step size fell below 1e-07 (x)").with_detail("jump failed too")
    assert s == "ds_min: step size fell below 1e-07 (x); jump failed too" and s.kind == "ds_min"
    assert Status.parse("whatever text").kind == "whatever text"


def test_the_driver_returns_a_status():
    res = continue_branch(Circle(), np.array([0.0, -1.0]), np.array([1.0, 0.0]),
                          ContinuationOptions(bounds={"x": (-0.5, 2.0)}))
    assert isinstance(res.status, Status)
    assert res.status == "bound:x" and (res.status.kind, res.status.detail) == ("bound", "x")


# --------------------------------------------------------------------------- events and options
class Teleport:
    """A plug-in that moves the circle's branch once, at its fourth point, to the angle
    -π/4 (an event plug-in that knows nothing of families)."""

    def __init__(self):
        self.moved = False
        self.registered = []

    def replay(self, records, special):
        pass

    def observe(self, index, record):
        return "teleport" if index == 3 and not self.moved else None

    def at_bound(self, index, record):
        return None

    def at_ds_min(self):
        return None

    def relocate(self, problem, points, records, reason, index):
        self.moved = True
        u = np.array([np.cos(-np.pi / 4), np.sin(-np.pi / 4)])
        t = np.array([-u[1], u[0]])
        return Relocation([(u, 0, np.zeros(1), problem.monitor(u), t)], SpecialPoint("teleport", index))

    def register(self, index, record, first):
        self.registered.append((index, first))


def test_an_event_plug_in_relocates_the_branch():
    events = Teleport()
    assert isinstance(events, BranchEvents) and isinstance(NoEvents(), BranchEvents)
    res = continue_branch(Circle(), np.array([0.0, -1.0]), np.array([1.0, 0.0]),
                          ContinuationOptions(ds=0.05, ds_max=0.05, max_steps=10), events=events)
    assert events.registered == [(4, True)]
    assert ("teleport", 4) in res.special_points
    np.testing.assert_allclose(res.u[4], [np.sqrt(0.5), -np.sqrt(0.5)])
    np.testing.assert_allclose(np.hypot(*res.u.T), 1.0, atol=1e-10)
    # after the move the branch goes on counter-clockwise from -π/4 with the initial step
    angles = np.arctan2(res.u[4:, 1], res.u[4:, 0])
    assert np.all(np.diff(angles) > 0)
    assert res.step_size[5] == pytest.approx(0.05)


def test_the_family_fields_are_read_by_the_family_follower():
    opt = ContinuationOptions(family_share=0.6, max_excursion=7, jump_step=0.01, max_jumps=3)
    expected = FamilyOptions(family_share=0.6, max_excursion=7, jump_step=0.01, max_jumps=3)
    assert FamilyOptions.of(opt) == expected
    events = default_events(opt, continue_branch)
    assert isinstance(events, FamilyFollower) and events.family is not None
    assert events.guard.family_share == 0.6 and events.guard.max_excursion == 7
    path = ContinuationOptions(follow="path", family_share=0.6)
    assert FamilyOptions.of(path) is None and isinstance(default_events(path, continue_branch), NoEvents)
    with pytest.raises(ValueError, match="family_share must be in"):
        ContinuationOptions(family_share=1.5)
    with pytest.raises(ValueError, match="family_share must be in"):
        FamilyOptions(family_share=0.0)
    with pytest.raises(ValueError, match="max_jumps"):
        ContinuationOptions(max_jumps=-1)


@pytest.mark.filterwarnings("ignore::mmshbm.BranchWarning")
def test_backbone_takes_the_family_options_by_their_old_names():
    """``max_jumps`` given to mmshbm.backbone by its old name reaches the family plug-in:
    the 8-element beam at H = 7 jumps over two tongues below 4 gaps, and not at all with
    ``max_jumps=0`` (it then ends off the family)."""
    beam = mmshbm.default_beam().model(8)
    kw = {"harmonics": 7, "max_amplitude": 4 * beam.gap, "max_steps": 200}
    free = mmshbm.backbone(beam, **kw)
    one = mmshbm.backbone(beam, **kw, max_jumps=1)
    capped = mmshbm.backbone(beam, **kw, max_jumps=0)
    assert [p.kind for p in free.special_points].count("jump") == 2
    assert [p.kind for p in one.special_points].count("jump") == 1
    assert [p.kind for p in capped.special_points].count("jump") == 0
    assert capped.metadata["continuation"]["max_jumps"] == 0
