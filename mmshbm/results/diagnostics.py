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
    :mod:`mmshbm.core.modal_energy`): from there on the motion is mostly another
    harmonic, a k:1 internal-resonance tongue or another family of periodic motions. The
    message says where it leaves and whether it comes back.
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
``"incomplete"``
    The branch ended short of its bounds (its status is not ``"bound:<name>"``: a step
    budget ``max_steps``, a step size below ``ds_min``, a failed start, ...).

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
import warnings
from dataclasses import dataclass, fields

import numpy as np

from .._warnings import BranchWarning
from ..core.status import Status

__all__ = ["CheckThresholds", "Finding", "check_branch", "mode_shares", "findings", "incomplete_reason"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class CheckThresholds:
    """The tolerances of :func:`check_branch` (all dimensionless).

    Attributes
    ----------
    min_mode_share : float
        A point belongs to the family of its starting mode while that mode carries at
        least this share of the period-mean kinetic energy.
    penetration : float
        Allowed excursion of a contact DOF beyond its stop, in gaps (in amplitudes of the
        point when the gap is 0).
    negative_force : float
        Allowed tensile contact force, as a fraction of the point's peak force.
    force_floor : float
        Forces below this fraction of max(branch's largest contact force, k_c·gap) are
        round-off.
    n_samples : int
        Time samples per period for the signal checks and for shooting's coefficients.
    """

    min_mode_share: float = 0.5
    penetration: float = 0.05
    negative_force: float = 0.05
    force_floor: float = 1e-9
    n_samples: int = 256

    def __post_init__(self):
        for name in ("min_mode_share", "penetration", "negative_force", "force_floor"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and np.isfinite(value) and value >= 0):
                raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")
        if not isinstance(self.n_samples, int) or self.n_samples < 8:
            raise ValueError(f"n_samples must be an integer >= 8, got {self.n_samples!r}")


@dataclass(frozen=True)
class Finding:
    """One problem of a branch.

    Attributes
    ----------
    kind : str
        "left_family", "coexisting_orbits", "penetration", "negative_force" or
        "incomplete".
    message : str
        One line for a person.
    first, last : int
        The first and last branch point concerned (-1 when none, e.g. an empty branch).
    value : float
        The extreme value (lowest share, deepest penetration in gaps, most negative
        force ratio; NaN for "incomplete").
    """

    kind: str
    message: str
    first: int = -1
    last: int = -1
    value: float = float("nan")

    def to_dict(self) -> dict:
        """The fields as a dict (``asdict``'s, its fields being plain values), ``value``
        None when not finite."""
        value = self.value
        return {"kind": self.kind, "message": self.message, "first": self.first, "last": self.last,
                "value": None if not np.isfinite(value) else float(value)}

    @classmethod
    def from_dict(cls, d: dict) -> Finding:
        value = d.get("value")
        return cls(str(d["kind"]), str(d["message"]), int(d.get("first", -1)), int(d.get("last", -1)),
                   float("nan") if value is None else float(value))


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
    th = CheckThresholds() if thresholds is None else thresholds
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
        out += _coexisting(branch)
        out += _contact(branch, solver, th)
    if Status.parse(branch.status).kind != Status.BOUND:
        out.append(_incomplete(branch))
    branch.metadata["checks"] = [f.to_dict() for f in out]
    branch.metadata["check_thresholds"] = {f.name: getattr(th, f.name) for f in fields(th)}  # asdict(th)
    if warn:
        for message in _warnings(branch, out):
            warnings.warn(message, BranchWarning, stacklevel=stacklevel + 1)
    return out


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


def _warnings(branch, found: list[Finding]) -> list[str]:
    """One warning per finding, except that the two truncation effects of harmonic
    balance (penetration and a pulling force) make one, and orbits coexisting with a
    family that left into tongues are said in the family's warning."""
    kinds = {f.kind: f for f in found}
    if "coexisting_orbits" in kinds and "left_family" in kinds:
        both = kinds["coexisting_orbits"].message.split(": ", 1)[1]
        found = [dataclasses.replace(f, message=f"{f.message}; {both}") if f.kind == "left_family" else f
                 for f in found if f.kind != "coexisting_orbits"]
        kinds = {f.kind: f for f in found}
    if not ("penetration" in kinds and "negative_force" in kinds and branch.harmonics):
        return [f.message for f in found]
    pen, neg = kinds["penetration"], kinds["negative_force"]
    joint = (f"{branch.method} branch, truncation effects of the Fourier series (more harmonics reduce "
             f"them): the contact DOF passes the stop by up to {pen.value:.3g} gaps (from "
             f"{_where(branch, pen.first)}) and the contact force pulls by up to {-neg.value:.3g} of the "
             f"peak (from point {neg.first}); branch.time_signals(i, admissible=True) gives admissible "
             "signals, branch.truncation_error(A) estimates the frequency's error at amplitude A")
    out = []
    for f in found:
        if f.kind == "penetration":
            out.append(joint)
        elif f.kind != "negative_force":
            out.append(f.message)
    return out


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
    from ..core.modal_energy import kinetic_energy_shares

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
def _where(branch, i: int) -> str:
    gap = branch.gap
    amp = branch.amplitude[i]
    a = f"{amp / gap:.3g} gaps" if gap else f"{amp:.3g} m"
    return f"point {i}, {branch.frequency[i]:.4g} Hz, {a}"


def _family_measure(branch, fundamental: np.ndarray, th: CheckThresholds) -> np.ndarray:
    """The fundamental's share where the point is off the family, 1 where it is on it: a
    branch followed plainly is classified by replaying the family guard over its points
    (:class:`mmshbm.core.family.FamilyGuard`: a stretch where a higher harmonic holds most
    of the kinetic energy but the backbone keeps rising without folding or locking is the
    family, not a tongue)."""
    if "on_family" in branch.records:
        return fundamental
    from ..core.family import FamilyGuard

    guard = FamilyGuard(th.min_mode_share, max_excursion=len(branch) + 1)
    recs = [{"amplitude": float(branch.amplitude[i]), "frequency": float(branch.frequency[i]),
             "fundamental_share": float(fundamental[i])} for i in range(len(branch))]
    for i, rec in enumerate(recs):
        guard.observe(i, rec)
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


def _contact(branch, solver, th: CheckThresholds) -> list[Finding]:
    model = getattr(solver, "model", None)
    if model is None or not hasattr(solver, "time_signals") or not hasattr(solver, "contact_force"):
        return []
    n = th.n_samples
    dofs = [c.dof for c in model.contacts]
    sides = np.array([c.side for c in model.contacts], dtype=float)[:, None]
    gaps = np.array([c.gap for c in model.contacts], dtype=float)[:, None]
    f_all = np.asarray(branch.contact_force_max, dtype=float)
    f_scale = float(np.nanmax(np.abs(f_all))) if len(f_all) and np.any(np.isfinite(f_all)) else 0.0
    k_c = getattr(solver, "contact_stiffness", None)  # a number, or one per contact DOF
    k_c = None if k_c is None else float(np.max(np.atleast_1d(np.asarray(k_c, dtype=float))))
    if k_c is not None and np.isfinite(k_c):
        f_scale = max(f_scale, k_c * float(np.max(gaps)))
    tau = 2 * np.pi * np.arange(n) / n
    cheap = model.n_contacts == 1 and hasattr(solver, "contact_signals")
    # the signals of every point first, the reductions over points and samples at once
    # (numpy calls per point cost more than the signals of a small model)
    n_pts, n_k = len(branch), len(dofs)
    amp = np.maximum(np.asarray(branch.amplitude, dtype=float), 1e-300)[:, None, None]
    scale = np.where(gaps[None] > 0, gaps[None], amp)  # (n_pts, n_k, 1)
    many = cheap and hasattr(solver, "contact_signals_many") and n_pts
    if many:  # every point's contact DOF and force at once, (n_pts, n_k, n) each
        Q, L = solver.contact_signals_many(np.asarray(branch.states, dtype=float), tau)
    else:
        Q = np.empty((n_pts, n_k, n))
        L = np.zeros((n_pts, n_k, n))  # the force of each stop, > 0 when it pushes
    for i, u in enumerate(() if many else branch.states):
        if cheap:  # the contact DOF and the force without recovering every DOF
            _, Q[i, 0], L[i, 0] = solver.contact_signals(u, tau)
        else:
            Q[i] = solver.time_signals(u, dofs, n)[1]
            # the force right after the motion: a solver may cache the last point's orbit
            if np.max((sides * Q[i] - gaps) / scale[i]) >= -th.penetration:
                L[i] = _stop_forces(model, Q[i], np.atleast_2d(solver.contact_force(u, n)[1]))
    # the deepest sample past each stop, (n_pts, n_k) gaps: (s·q − gap)/scale of the extreme
    # sample of s·q (the largest q for s >= 0, the smallest for s < 0), the same number as the
    # largest of every sample's depth (each operation is monotone in q, the scale positive)
    depth = np.zeros((n_pts, n_k))
    if n_pts:
        s = sides[None, :, 0]
        reach = np.where(s >= 0, s * Q.max(axis=2), s * Q.min(axis=2))
        depth = (reach - gaps[None, :, 0]) / scale[:, :, 0]
    pen = depth.max(axis=1) if n_pts else np.zeros(0)
    # a contact that never comes near its stop carries no force but Newton's residual
    need_force = pen >= -th.penetration
    neg = np.zeros(n_pts)
    if n_pts:  # per stop: its pull against its own peak push
        floor = th.force_floor * f_scale
        near = depth >= -th.penetration  # (n_pts, n_k)
        peak = np.maximum(L.max(axis=2), floor)
        lo = L.min(axis=2)
        ratio = np.where(near & (peak > 0) & (lo < -floor), -lo / peak, 0.0)
        neg = ratio.max(axis=1) * need_force
    out = []
    bad = np.flatnonzero(pen > th.penetration)
    if len(bad):
        worst = int(bad[np.argmax(pen[bad])])
        what = "truncated Fourier series of the contact DOF" if branch.harmonics else "contact DOF"
        out.append(Finding(
            "penetration",
            f"{branch.method} branch: the {what} passes the stop by more than {th.penetration:g} gaps at "
            f"{len(bad)} of {len(branch)} points, from {_where(branch, int(bad[0]))}; deepest "
            f"{pen[worst]:.3g} gaps at point {worst} ({branch.frequency[worst]:.4g} Hz)"
            + ("; more harmonics reduce it, branch.time_signals(i, admissible=True) gives admissible "
               "signals, branch.truncation_error(A) estimates the frequency's error at amplitude A"
               if branch.harmonics else ""),
            int(bad[0]), int(bad[-1]), float(pen[worst])))
    bad = np.flatnonzero(neg > th.negative_force)
    if len(bad):
        worst = int(bad[np.argmax(neg[bad])])
        out.append(Finding(
            "negative_force",
            f"{branch.method} branch: the contact force changes sign (pulls) by more than "
            f"{th.negative_force:g} of the peak force at {len(bad)} of {len(branch)} points, from "
            f"{_where(branch, int(bad[0]))}; worst {neg[worst]:.3g} of the peak at point {worst}"
            + (" (a truncation effect of the Fourier series; branch.truncation_error(A) estimates the "
               "frequency's error at amplitude A)" if branch.harmonics else ""),
            int(bad[0]), int(bad[-1]), float(-neg[worst])))
    return out


def _stop_forces(model, q: np.ndarray, lam: np.ndarray) -> np.ndarray:
    """The force of each stop (rows in the order of ``model.contacts``, > 0 when it pushes)
    from a solver's contact forces ``lam``: one row per contact (already per stop), or one
    per contact DOF (:func:`~mmshbm.model.contact.admissible_intervals` order; the net force
    the structure needs, > 0 for a push of an upper stop, < 0 for one of a lower stop).
    On a DOF between two stops the net force is the upper stop's where the DOF is nearer
    to it and the lower one's elsewhere: the two never push at once. ``q`` (n_contacts, n)
    is the motion of each contact's DOF."""
    from ..model.contact import admissible_intervals

    contacts = model.contacts
    if lam.shape[0] == len(contacts):
        return lam
    dofs, lo, hi = admissible_intervals(contacts)
    if lam.shape[0] != len(dofs):  # a solver reporting fewer rows: the same force for every stop
        return np.broadcast_to(lam, (len(contacts), lam.shape[1]))
    row = {int(d): i for i, d in enumerate(dofs)}
    out = np.zeros((len(contacts), lam.shape[1]))
    for i, ct in enumerate(contacts):
        r = row[ct.dof]
        if np.isfinite(lo[r]) and np.isfinite(hi[r]):
            mid = 0.5 * (lo[r] + hi[r])
            mine = q[i] >= mid if ct.side > 0 else q[i] < mid
            out[i] = np.where(mine, ct.side * lam[r], 0.0)
        else:
            out[i] = lam[r]
    return out


#: what an unfinished status means, by its first word
_WHY = {
    "max_steps": "the step budget ran out (raise max_steps, --max-steps)",
    "ds_min": "the step size fell below ds_min (the corrector kept failing)",
    "start": "the first point failed",
    "interrupted": "the run was interrupted",
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
