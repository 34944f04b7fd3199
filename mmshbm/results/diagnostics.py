"""Checks that say what a branch is: family, contact admissibility, completeness.

A backbone is meant to be the nonlinear continuation of one linear mode up to a bound.
:func:`check_branch` tells when a computed branch is something else, with one
:class:`~mmshbm.BranchWarning` per kind of problem and a record in
``branch.metadata["checks"]`` (saved with the branch, read by the command line and by
study summaries):

``"left_family"``
    The family measure falls below :attr:`CheckThresholds.min_mode_share` (default 0.5):
    the fundamental harmonic's share of the motion (``records["fundamental_share"]``,
    MMS-HBM, see docs/resonances.md) or, for the methods without it, the starting mode's
    share of the period-mean kinetic energy (``records["mode_share"]``, 0..1, see
    :mod:`mmshbm.harmonic.modal_energy`): from there on the motion is mostly another
    harmonic, a k:1 internal-resonance tongue or another family of periodic motions. The
    message says where it leaves and whether it comes back. A branch followed plainly
    that comes back below its grazing amplitude after passing it is reported too, whatever
    share the fundamental holds: without contact its orbits are a linear mode's again
    (another mode's family, or the same one once more).
``"penetration"``
    The contact DOF, as the method represents it (for harmonic balance the truncated
    Fourier series), passes its stop by more than :attr:`CheckThresholds.penetration`
    gaps (default 0.05).
``"negative_force"``
    The contact force, as the method represents it, is negative by more than
    :attr:`CheckThresholds.negative_force` (default 0.05) times the point's peak force:
    a tensile contact force is not Signorini's (checked where the contact DOF comes
    within the penetration tolerance of its stop). Forces below
    :attr:`CheckThresholds.force_floor` (default 1e-9) times the larger of the branch's
    largest contact force and k_c·gap (the static contact stiffness times the gap) are
    round-off (Newton's tolerance leaves ~1e-9 N on the default beam) and not reported.
``"coexisting_orbits"``
    Points of the branch off its family front (a tongue, a loop's way down, a jump that
    landed at the frontier's amplitude at another frequency) share amplitudes with the
    front: the backbone is not the only orbit there (:mod:`mmshbm.results.coexisting`;
    the message names the intervals in gaps, ``first``/``last`` the off-front points,
    ``value`` the summed width of the intervals in gaps, or m without a gap).
``"tolerance_not_met"``
    A branch computed with ``tol`` misses it on part of its family front
    (:mod:`mmshbm.results.tolerance_checks`).
``"incomplete"``
    The branch ended short of its bounds (``not branch.completed``: its status is not
    ``"bound:<name>"`` (a step budget ``max_steps``, a step size below ``ds_min``, a failed
    start, ...), or it reached a bound coming back to its start amplitude or without
    leaving it).

For harmonic balance "penetration" and "negative_force" are truncation effects (more
harmonics reduce them); ``branch.time_signals(i, admissible=True)`` gives admissible signals
(:mod:`mmshbm.contact.static`), and ``branch.truncation_error(A)``
(:mod:`mmshbm.results.truncation`) estimates the frequency's truncation error at an
amplitude A, on demand: truncation moves it also where neither finding is made.

The mode shares come from ``records["mode_share"]`` when the method recorded them,
otherwise they are computed here from the solver's coefficients of all DOFs
(``solver.coefficients(u)``, NLvib order) or, for shooting, from the Fourier transform
of its time signals, with the model's open-contact linear modes.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import warnings
from dataclasses import fields

import numpy as np

from .._warnings import BranchWarning
from ..core.status import Status
from .contact_checks import contact_findings as _contact
from .findings import CheckThresholds, Finding
from .findings import where as _where
from .tolerance_checks import tolerance_findings

__all__ = ["CheckThresholds", "Finding", "check_branch", "mode_shares", "findings", "incomplete_reason"]

log = logging.getLogger(__name__)


def findings(branch) -> list[Finding]:
    """The findings recorded in ``branch.metadata["checks"]`` by :func:`check_branch`
    (empty when the branch was never checked)."""
    return [Finding.from_dict(d) for d in branch.metadata.get("checks", [])]


def check_branch(branch, thresholds: CheckThresholds | None = None, *, warn: bool = True,
                 stacklevel: int = 2) -> list[Finding]:
    """Check ``branch`` and record what it is.

    Computes ``branch.records["mode_share"]`` if missing, stores the findings in
    ``branch.metadata["checks"]`` (list of dicts) and the thresholds in
    ``branch.metadata["check_thresholds"]``, and issues one :class:`BranchWarning` per
    finding (unless ``warn`` is False).

    Parameters
    ----------
    branch : Branch
        A computed or loaded branch (its solver is rebuilt when needed; without a model
        only the completeness check runs).
    thresholds : CheckThresholds, optional
    warn : bool
        Issue the warnings.
    stacklevel : int
        Passed to :func:`warnings.warn`.

    Returns
    -------
    list of Finding
    """
    th = _DEFAULT_THRESHOLDS if thresholds is None else thresholds
    if not isinstance(th, CheckThresholds):
        raise TypeError(f"thresholds must be a CheckThresholds, got {type(th).__name__}")
    out: list[Finding] = []
    solver = None
    if len(branch):
        try:
            solver = branch._require_solver()
        except RuntimeError as err:
            log.info("branch checks without a solver: %s", err)
    if solver is not None:
        shares = branch.records.get("mode_share")
        if shares is None or len(shares) != len(branch):
            try:
                shares = mode_shares(branch, n_samples=th.n_samples)
                branch.records["mode_share"] = shares
            except (ValueError, AttributeError, np.linalg.LinAlgError) as err:
                log.info("no mode shares for this branch: %s", err)
                shares = None
        fundamental = branch.records.get("fundamental_share")
        if fundamental is not None and len(fundamental) == len(branch):
            out += _family(branch, _family_measure(branch, np.asarray(fundamental, dtype=float), th), th,
                           fundamental=True)
        elif shares is not None:
            out += _family(branch, np.asarray(shares, dtype=float), th)
        if not out:
            out += _back_below_grazing(branch)
        out += _coexisting(branch)
        out += _contact(branch, solver, th)
    out += tolerance_findings(branch)
    if not branch.completed:
        out.append(_incomplete(branch))
    branch.metadata["checks"] = [f.to_dict() for f in out]
    branch.metadata["check_thresholds"] = (dict(_DEFAULT_RECORD) if th is _DEFAULT_THRESHOLDS
                                           else {f.name: getattr(th, f.name) for f in fields(th)})
    if warn:
        for message, kind in _warnings(branch, out):
            warnings.warn(BranchWarning(message, kind), stacklevel=stacklevel + 1)
    return out


#: the thresholds of a check that names none (frozen: one instance serves every check) and
#: their record in ``metadata["check_thresholds"]`` (each branch gets its own copy)
_DEFAULT_THRESHOLDS = CheckThresholds()
_DEFAULT_RECORD = {f.name: getattr(_DEFAULT_THRESHOLDS, f.name) for f in fields(_DEFAULT_THRESHOLDS)}


def _coexisting(branch) -> list[Finding]:
    from .coexisting import coexisting_intervals

    found = coexisting_intervals(branch)
    if not found:
        return []
    gap = branch.gap or 1.0
    unit = " gaps" if branch.gap else " m"
    spans = ", ".join((f"{c.lo / gap:.4g}" if c.lo == c.hi else f"{c.lo / gap:.4g}-{c.hi / gap:.4g}")
                      + f"{unit} ({c.frequency_other[0]:.4g}-{c.frequency_other[1]:.4g} Hz besides the "
                      f"backbone's {c.frequency_family[0]:.4g}-{c.frequency_family[1]:.4g} Hz)"
                      for c in found[:4]) + (", ..." if len(found) > 4 else "")
    points = [i for c in found for i in c.points]
    message = (f"{branch.method} branch: other orbits coexist with the backbone at {spans}; "
               "frequency_at gives the backbone's")
    return [Finding("coexisting_orbits", message, min(points), max(points),
                    float(sum(c.hi - c.lo for c in found) / gap))]


def _warnings(branch, found: list[Finding]) -> list[tuple[str, str]]:
    """(message, finding kind) of one warning per finding, except that the two truncation effects of harmonic
    balance (penetration and a pulling force) make one, and orbits coexisting with a
    family that left into tongues are said in the family's warning."""
    kinds = {f.kind: f for f in found}
    if "coexisting_orbits" in kinds and "left_family" in kinds:
        both = kinds["coexisting_orbits"].message.split(": ", 1)[1]
        found = [dataclasses.replace(f, message=f"{f.message}; {both}") if f.kind == "left_family" else f
                 for f in found if f.kind != "coexisting_orbits"]
        kinds = {f.kind: f for f in found}
    if not ("penetration" in kinds and "negative_force" in kinds and branch.harmonics):
        return [(f.message, f.kind) for f in found]
    pen, neg = kinds["penetration"], kinds["negative_force"]
    joint = (f"{branch.method} branch, truncation effects of the Fourier series (more harmonics reduce "
             f"them): the contact DOF passes the stop by up to {pen.value:.3g} gaps (from "
             f"{_where(branch, pen.first)}) and the contact force pulls by up to {-neg.value:.3g} of the "
             f"peak (from point {neg.first}); branch.time_signals(i, admissible=True) gives admissible "
             "signals, branch.truncation_error(A) estimates the frequency's error at amplitude A"
             + _tolerance_tail(pen.message))
    out = []
    for f in found:
        if f.kind == "penetration":
            out.append((joint, "penetration"))
        elif f.kind != "negative_force":
            out.append((f.message, f.kind))
    return out


def _tolerance_tail(message: str) -> str:
    """The statement against the tolerance that ends a truncation finding's message (empty
    without one: :func:`mmshbm.results.contact_checks.contact_findings`)."""
    head, sep, tail = message.partition("; against the tolerance ")
    return sep + tail


# ---------------------------------------------------------------------- mode shares
def mode_shares(branch, mode: int | None = None, n_samples: int = 256) -> np.ndarray:
    """Share (0..1) of the period-mean kinetic energy in linear mode ``mode`` (1-based;
    default the branch's starting mode) at the fundamental harmonic, at every point, shape
    (n_points,): the quantity that decides membership of the starting mode's family (as
    MMS-HBM's ``records["mode_share"]``; energy of that mode in higher harmonics is a
    superharmonic or an internal resonance, not the family).

    Uses ``solver.coefficients(u)`` (all DOFs, NLvib order) when the solver has it, else
    the DFT of ``solver.time_signals(u, None, n_samples)``.
    """
    from ..harmonic.modal_energy import kinetic_energy_shares

    solver = branch._require_solver()
    model = branch.get_model()
    if mode is None:
        mode = int(getattr(solver, "mode", branch.metadata.get("method_options", {}).get("mode", 1)))
    _, Phi = model.linear_modes(mode)
    Phi = Phi[:, -1:]
    proj = (model.M @ Phi).T
    out = np.empty(len(branch))
    for i, u in enumerate(branch.states):
        omega = 2 * np.pi * float(branch.frequency[i])
        Q = _coefficients(solver, u, n_samples)
        shares, total = kinetic_energy_shares(Phi, proj, Q, omega, model.M)
        out[i] = float(shares[0, 1]) if total > 0 else float("nan")
    return out


def _coefficients(solver, u, n_samples: int) -> np.ndarray:
    if hasattr(solver, "coefficients"):
        return solver.coefficients(u)
    _, q = solver.time_signals(u, None, n_samples)
    c = np.fft.rfft(q, axis=1) / q.shape[1]
    H = n_samples // 2 - 1
    Q = np.empty((q.shape[0], 2 * H + 1))
    Q[:, 0] = c[:, 0].real
    Q[:, 1::2] = 2 * c[:, 1 : H + 1].real
    Q[:, 2::2] = -2 * c[:, 1 : H + 1].imag
    return Q


# ---------------------------------------------------------------------- checks
def _family_measure(branch, fundamental: np.ndarray, th: CheckThresholds) -> np.ndarray:
    """The fundamental's share where the point is off the family, 1 where it is on it: a
    branch followed plainly is classified by replaying the family guard over its points
    (:class:`mmshbm.family.guard.FamilyGuard`: a stretch where a higher harmonic holds most
    of the kinetic energy but the backbone keeps rising without folding or locking is the
    family, not a tongue; one still pending where the branch reaches its amplitude bound
    is judged there as the family follower judges it,
    :meth:`~mmshbm.family.guard.FamilyGuard.locked_at_bound`)."""
    if "on_family" in branch.records:
        return fundamental
    from ..family.guard import FamilyGuard

    guard = FamilyGuard(th.min_mode_share, max_excursion=len(branch) + 1)
    recs = [{"amplitude": float(branch.amplitude[i]), "frequency": float(branch.frequency[i]),
             "fundamental_share": float(fundamental[i])} for i in range(len(branch))]
    for i, rec in enumerate(recs):
        guard.observe(i, rec)
    if str(branch.status) == "bound:amplitude":
        guard.locked_at_bound()  # a pending climb the bound cut short, locked: a tongue
    on = np.array([rec.get("on_family", 1.0) for rec in recs]) > 0.5
    return np.where(on, np.maximum(fundamental, 1.0), fundamental)


def _family(branch, shares: np.ndarray, th: CheckThresholds, fundamental: bool = False) -> list[Finding]:
    low = np.flatnonzero(shares < th.min_mode_share)
    if not len(low):
        return []
    mode = int(branch.metadata.get("method_options", {}).get("mode", 1))
    on = branch.records.get("on_family")
    if on is not None and len(on) == len(shares) and on[-1] > 0.5:
        return _followed(branch, np.asarray(on, dtype=float), shares, mode)
    first, worst = int(low[0]), int(low[np.argmin(shares[low])])
    back = np.flatnonzero(shares[first:] >= th.min_mode_share)
    ended_low = shares[-1] < th.min_mode_share
    what = ("the fundamental harmonic's share of the kinetic energy" if fundamental
            else "that mode's share of the kinetic energy")
    head = (f"{branch.method} branch leaves the family of linear mode {mode}: {what} "
            f"falls below {th.min_mode_share:g} at {_where(branch, first)} "
            f"(lowest {shares[worst]:.3g} at point {worst})")
    if ended_low:
        tail = (f" and is {shares[-1]:.3g} at the end ({_where(branch, len(shares) - 1)}): "
                "the rest of the branch is another family, not this mode's backbone")
        last = len(shares) - 1
    else:
        last = first + int(back[0]) - 1
        tail = (f"; it returns at point {last + 1} ({branch.frequency[last + 1]:.4g} Hz): the "
                f"points {first}..{last} are an excursion into another mode (internal resonance)")
    return [Finding("left_family", head + tail, first, last, float(shares[worst]))]


#: a branch back below this fraction of its grazing amplitude has no contact left
_BELOW_GRAZING = 0.9


def _back_below_grazing(branch) -> list[Finding]:
    """The finding of a branch followed plainly that comes back below its grazing
    amplitude after passing it: without contact every periodic orbit is a linear mode's,
    so from there the branch follows a linear mode again (another mode's family, or this
    one's a second time) whatever share the fundamental holds. Branches that follow
    their family (``records["on_family"]``) jump instead and are not checked here."""
    if "on_family" in branch.records:
        return []
    grazing = [sp[1] for sp in branch.special_points if sp[0] == "grazing"]
    if not grazing:
        return []
    g = int(grazing[0])
    amplitude = np.asarray(branch.amplitude, dtype=float)
    below = np.flatnonzero(amplitude[g + 1:] < _BELOW_GRAZING * amplitude[g]) + g + 1
    if not len(below):
        return []
    mode = int(branch.metadata.get("method_options", {}).get("mode", 1))
    first = int(below[0])
    message = (f"{branch.method} branch leaves the family of linear mode {mode}: after grazing at point {g} "
               f"it comes back below its grazing amplitude at {_where(branch, first)}, where no contact is "
               "left and the orbit is a linear mode's: the rest of the branch follows a linear mode again "
               "(another mode's family, or this one's once more), not this mode's backbone")
    share = branch.records.get("fundamental_share", branch.records.get("mode_share"))
    lowest = float(np.min(share[first:])) if share is not None and len(share) == len(branch) else math.nan
    return [Finding("left_family", message, first, len(branch) - 1, lowest)]


def _followed(branch, on: np.ndarray, shares: np.ndarray, mode: int) -> list[Finding]:
    """The finding of a branch that followed its family (``follow="family"``) to the end:
    where its excursions into tongues are, and how to leave them out."""
    off = np.flatnonzero(on < 0.5)
    if not len(off):
        return []
    runs = np.split(off, np.flatnonzero(np.diff(off) > 1) + 1)
    spans = ", ".join(f"{r[0]}..{r[-1]}" for r in runs[:4]) + (", ..." if len(runs) > 4 else "")
    jumps = sum(1 for sp in branch.special_points if sp[0] == "jump")
    message = (f"{branch.method} branch follows the family of linear mode {mode} past internal resonances: "
               f"{len(off)} of {len(branch)} points (at {spans}) are excursions into other modes, kept in "
               f"the arrays" + (f", and it jumped over {jumps} tongue(s)" if jumps else "")
               + "; branch.family_front() selects the backbone (see special_points)")
    worst = int(off[np.argmin(shares[off])])
    return [Finding("left_family", message, int(off[0]), int(off[-1]), float(shares[worst]))]


_WHY = {
    "max_steps": "the step budget ran out (raise max_steps, --max-steps)",
    "ds_min": "the step size fell below ds_min (the corrector kept failing)",
    "start": "the first point failed",
    "interrupted": "the run was interrupted",
    "bound": "it reached a bound at no larger amplitude than its start (it came back, or never left it)",
}


def incomplete_reason(status: str, metadata: dict | None = None) -> str:
    """A short phrase saying why a branch with ``status`` ended short of its bounds."""
    kind = Status.parse(status).kind
    key = "start" if kind in (Status.START_FAILED, Status.START_OUTSIDE) else kind
    why = _WHY.get(key, status)
    steps = dict(dict(metadata or {}).get("continuation", {})).get("max_steps")
    if key == "max_steps" and steps is not None:
        why = f"the step budget max_steps = {steps} ran out (raise max_steps, --max-steps)"
    return why


def _incomplete(branch) -> Finding:
    n = len(branch)
    bound = branch.metadata.get("max_amplitude")
    reached = ""
    if n:
        gap = branch.gap
        a = float(np.nanmax(branch.amplitude))
        if gap:
            reached = f" at {a / gap:.3g} gaps"
            if bound:
                reached += f" of {float(bound) / gap:.3g}"
        else:
            reached = f" at {a:.3g} m"
    why = incomplete_reason(branch.status, branch.metadata)
    return Finding("incomplete", f"{branch.method} branch ended short of its bounds{reached}: {why} "
                   f"(status {branch.status!r}, {n} points)", n - 1, n - 1)
