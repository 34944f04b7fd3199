"""Right, not only complete: the default backbone against the exact single-contact orbit.

On random chains (1–4 masses ending in a massless contact node, one stop, gap 1 cm) the
exact symmetric orbit at a given amplitude (:func:`mmshbm.exact.periodic_orbit`) is the
reference wherever it is *clean*: Newton converged, one contact per period, and its
measured excursion equals the prescribed amplitude. :func:`compare` computes the default
branch at H harmonics to a little beyond that amplitude and compares its
``frequency_at`` with the exact frequency.

A miss (``|f_branch / f_exact − 1| > tol``) is *explained by the result itself* when the
branch says, at that amplitude, that it may differ from the single-contact orbit:

* its own truncation error estimate (:meth:`mmshbm.Branch.truncation_error`: re-solves
  at 2H and 4H, extrapolated) is at least ``tol``: its frequency is uncertain beyond the
  comparison tolerance;
* its orbit there is another orbit: the admissible contact force of its point at the
  amplitude (``solve_at``, ``contact_force(admissible=True)``) closes the contact more
  than once per period;
* or what its findings and special points report there (:func:`_reported`: a skipped
  interval, coexisting orbits, a truncation finding, a fold or branch point near it).

The stricter account (:meth:`ExactComparison.explanations`, the summary's "explained" and
"unexplained") asks the result three things about a miss, each a number it computes:

* the exact orbit is among the family's orbits the branch lists at the amplitude
  (:meth:`mmshbm.Branch.orbits_at` with ``search=True``): one of them within ``tol`` of
  its frequency, or one whose own truncation estimate
  (:func:`mmshbm.results.truncation.state_truncation_error`) is at least a third of its
  difference from it (the H-harmonic counterpart of the exact orbit);
* the exact orbit is not the mode's: its fundamental holds less than half the kinetic
  energy (:data:`EXACT_FAMILY_SHARE`);
* the exact orbit is not the mode's: its frequency lies outside the first mode's band of
  the definition (:func:`mmshbm.family.definition.frequency_band`: from the linear mode's
  to the first mode's with the contact held; without ``band_slack``, the margin for a
  truncated series; an orbit of the second mode can hold the fundamental's majority too);
* the branch's truncation estimate at the amplitude is at least a third of the difference
  (:data:`TRUNCATION_PART`).

With ``accuracy`` (``python -m validation exact N --tol TOL``) the branch is
``backbone(model, tol=TOL)``; its truncation estimate is its own per-point estimate at the
amplitude (the larger ``frequency_error`` of the two family points that bracket it), and a
``tolerance_not_met`` finding there explains a miss too (the result says the tolerance
does not hold there).
"""

from __future__ import annotations

import dataclasses
import math
import time
import warnings

import numpy as np

from .corpus import CorpusCase, generate

__all__ = ["EXACT_FAMILY_SHARE", "TRUNCATION_PART", "ExactComparison", "branch_orbit", "chains", "compare",
           "listed_orbit", "name", "report"]

#: an exact orbit is the first mode's when its fundamental holds at least this share of
#: the kinetic energy (the family rule of :mod:`mmshbm.results.orbits`)
EXACT_FAMILY_SHARE = 0.5
#: a truncation estimate accounts for a difference when it is at least this part of it
TRUNCATION_PART = 1 / 3


def name(case: CorpusCase) -> str:
    """``#index chain of m masses (seed s)``: the case without the corpus's own H (the
    comparison runs at its own number of harmonics)."""
    return f"#{case.index} chain of {len(case.params['masses'])} masses (seed {case.seed})"


def chains(n: int, seed: int = 0, max_masses: int = 4, gap: float = 0.01,
           contact_decades: tuple[float, float] | None = None) -> list[CorpusCase]:
    """``n`` one-sided chains of at most ``max_masses`` masses with the gap ``gap``, drawn
    from the corpus (:func:`validation.corpus.generate`; the gap replaced).

    ``contact_decades = (lo, hi)`` draws the contact node's spring anew as 10**U(lo, hi)
    N/m (the corpus draws it up to a hundred times stiffer than the other springs, whose
    range is (1, 5): contacts much stiffer than the structure, near impacts);
    reproducible from the seed and the chain's index."""
    out, i = [], 0
    while len(out) < n:
        batch = generate(4 * n + 16, seed=seed + i, kinds=("chain",), contacts=("one-sided",))
        for c in batch:
            if len(c.params["masses"]) <= max_masses:
                p = dict(c.params, gaps=[gap])
                if contact_decades is not None:
                    rng = np.random.default_rng([seed, 7777, len(out)])
                    p["node_k"] = (10 ** rng.uniform(*contact_decades, 1)).tolist()
                out.append(dataclasses.replace(c, index=len(out), params=p))
                if len(out) == n:
                    break
        i += 1
    return out


@dataclasses.dataclass
class ExactComparison:
    """One model: the exact orbit's frequency and cleanliness, the branch's frequency."""

    case: CorpusCase
    clean: bool
    exact: float
    branch: float
    status: str
    n_contacts: int
    seconds: float
    special: list
    branch_2h: float = math.nan
    continued: float = math.nan
    reported: str = ""
    estimate: float = math.nan
    estimate_note: str = ""
    branch_contacts: int = -1
    exact_share: float = math.nan
    continued_share: float = math.nan
    family_exact: float = math.nan
    family_share: float = math.nan
    orbits_hz: tuple = ()
    orbits_share: tuple = ()
    orbits_seconds: float = math.nan
    exact_listed: str = ""
    band: tuple = (0.0, math.inf)
    tolerance: float = math.nan
    tolerance_not_met: bool = False

    @property
    def in_band(self) -> bool:
        """The exact orbit's frequency lies in the first mode's band (:attr:`band`, Hz: the
        definition's second condition, :func:`mmshbm.family.definition.frequency_band`)."""
        return bool(self.band[0] <= self.exact <= self.band[1])

    @property
    def error(self) -> float:
        """|f_branch / f_exact − 1| (NaN when either is missing)."""
        return abs(self.branch / self.exact - 1.0) if self.exact > 0 else math.nan

    @property
    def error_2h(self) -> float:
        """The same at twice the harmonics (computed for disagreeing cases only)."""
        return abs(self.branch_2h / self.exact - 1.0) if self.exact > 0 else math.nan

    @property
    def coexisting(self) -> bool:
        """The exact orbit continued from the linear mode through grazing
        (:func:`mmshbm.exact.backbone`) agrees with the branch within 1e-3 while the
        single-contact orbit found from the linear mode's shape does not: two orbits
        coexist at that amplitude, and the branch is the first mode's."""
        return bool(abs(self.branch / self.continued - 1.0) <= 1e-3)

    @property
    def explained(self) -> bool:
        """The branch itself says why it may differ from the single-contact orbit at the
        amplitude (:attr:`reasons` is not empty, for the comparison tolerance 1e-3)."""
        return bool(self.reasons())

    def reasons(self, tol: float = 1e-3) -> list[str]:
        """What the branch says at the amplitude that sets it apart from the single-contact
        orbit: its truncation estimate at least ``tol``, an orbit that closes the contact
        more than once per period, and :attr:`reported` (module docstring)."""
        out = []
        if self.estimate >= tol:
            out.append(f"truncation estimate {self.estimate:.1e}")
        if self.branch_contacts > 1:
            out.append(f"{self.branch_contacts} contacts per period")
        if self.reported:
            out.append(self.reported)
        return out

    def explanations(self, tol: float = 1e-3) -> list[str]:
        """What the result computes that accounts for a miss (module docstring): the
        exact orbit listed by ``orbits_at`` (:attr:`exact_listed` says how), its
        fundamental share below :data:`EXACT_FAMILY_SHARE`, the branch's truncation
        estimate at least :data:`TRUNCATION_PART` of the difference; empty for a case
        within ``tol``."""
        if self.error <= tol:
            return []
        out = []
        if self.exact_listed:
            out.append(f"exact orbit listed ({self.exact_listed})")
        if self.exact_share < EXACT_FAMILY_SHARE:
            out.append(f"exact orbit's fundamental share {self.exact_share:.2f}")
        if not self.in_band:
            out.append(f"exact orbit's frequency outside the first mode's band {self.band[0]:.6g}-"
                       f"{self.band[1]:.6g} Hz")
        if self.estimate >= TRUNCATION_PART * self.error:
            out.append(f"truncation estimate {self.estimate:.1e} of a difference {self.error:.1e}")
        if self.tolerance_not_met:
            out.append(f"tolerance {self.tolerance:g} not met and said (tolerance_not_met)")
        return out

    @property
    def resonant(self) -> bool:
        """The exact orbit continued from the linear mode through grazing, or the
        single-contact orbit found from its shape, is an internal resonance's (its
        fundamental harmonic holds less than half the kinetic energy, docs/resonances.md),
        and the exact orbit found from the branch's own point at the amplitude holds the
        fundamental's majority and agrees with the branch within 1e-3: past the tongue the
        continuation climbs, the branch is the mode's orbit."""
        return bool(min(self.exact_share, self.continued_share) < 0.5 <= self.family_share
                    and abs(self.branch / self.family_exact - 1.0) <= 1e-3)

    @property
    def first_mode(self) -> bool:
        """The branch gives the first mode's orbit within 1e-3: the exact orbit found from
        the linear mode's shape, or, where another orbit coexists there, the exact orbit
        continued from the linear mode through grazing (:attr:`coexisting`), or, where the
        single-contact orbit is an internal resonance's, the exact orbit with the
        fundamental's majority found from the branch's point (:attr:`resonant`)."""
        return bool(self.error <= 1e-3 or self.coexisting or self.resonant)

    @property
    def truncation(self) -> bool:
        """The disagreement is the Fourier series' truncation: at 2H the branch is at least
        1.5 times closer to the exact orbit (the same orbit, converging in H); for a
        tolerance branch (no run at 2H), its own estimate is at least
        :data:`TRUNCATION_PART` of the difference."""
        if math.isfinite(self.tolerance):
            return bool(self.estimate >= TRUNCATION_PART * self.error)
        return bool(self.error_2h <= self.error / 1.5)


def compare(case: CorpusCase, amplitude_gaps: float = 1.3, harmonics: int = 31,
            tol: float = 1e-3, options: dict | None = None, accuracy: float | None = None) -> ExactComparison:
    """Exact orbit and default branch of ``case`` at ``amplitude_gaps`` gaps (and at
    2·``harmonics`` where the two differ by more than ``tol``); ``options``: further
    keyword arguments of :func:`~mmshbm.backbone` for both branches (e.g.
    ``{"r": "residual"}``); ``accuracy``: run ``backbone(tol=accuracy)`` instead of H
    harmonics (module docstring)."""
    from mmshbm import exact
    from mmshbm.methods.backbone import backbone

    model = case.model()
    A = amplitude_gaps * model.gap
    t0 = time.perf_counter()
    try:
        orbit = exact.periodic_orbit(model, A)
        clean = bool(orbit.converged and orbit.n_contacts == 1 and abs(orbit.max_excursion / A - 1) < 1e-6)
        f_exact, n_c = float(orbit.frequency), int(orbit.n_contacts)
    except (ValueError, ArithmeticError, np.linalg.LinAlgError, RuntimeError):
        clean, f_exact, n_c = False, math.nan, -1
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            fixed = {"harmonics": harmonics} if accuracy is None else {"tol": accuracy}
            b = backbone(model, max_amplitude=1.2 * A, **fixed, **(options or {}))
            f = float(b.frequency_at(A))
            status = b.status
            special = [(s.kind, round(float(b.amplitude[s.index]) / model.gap, 3)) for s in b.special_points
                       if s.kind in ("fold", "branch_point", "jump", "internal_resonance")
                       and b.amplitude[s.index] <= 1.2 * A]
            reported = _reported(b, A)
        except Exception as err:  # noqa: BLE001 - reported
            f, status, special, reported = math.nan, f"exception: {err}", [], ""
        out = ExactComparison(case, clean, f_exact, f, status, n_c, 0.0, special, reported=reported)
        if math.isfinite(f):
            out.band = _band(b)
        if accuracy is not None and math.isfinite(f):
            out.tolerance = float(accuracy)
            out.estimate, out.tolerance_not_met = _own_estimate(b, A)
        if clean and not out.error <= tol and math.isfinite(f):
            if accuracy is None:
                out.estimate, out.estimate_note, out.branch_contacts = _self_report(b, A)
            else:
                out.estimate_note, out.branch_contacts = "the branch's own estimate", contact_closings(b, A)
        if clean and not out.error <= tol:
            try:  # a tolerance branch carries its own estimate: no run at 2H
                if accuracy is None:
                    b2 = backbone(model, harmonics=2 * harmonics, max_amplitude=1.2 * A, **(options or {}))
                    out.branch_2h = float(b2.frequency_at(A))
            except Exception:  # noqa: BLE001
                pass
            try:  # two halvings per step: more cost minutes on rattling orbits, not the answer
                amps = np.linspace(0.5 * model.gap, A, 81)
                continued = exact.backbone(model, amps, max_halvings=2)
                out.continued = float(continued.frequency[-1])
                if continued.converged[-1]:
                    out.continued_share = continued.orbits[-1].fundamental_share()
            except Exception:  # noqa: BLE001
                pass
            out.exact_share = orbit.fundamental_share()
            if min(out.exact_share, out.continued_share) < 0.5 and math.isfinite(f):
                out.family_exact, out.family_share = branch_orbit(model, b, A)
            cheaper = (out.exact_share < EXACT_FAMILY_SHARE or not out.in_band or out.tolerance_not_met
                       or out.estimate >= TRUNCATION_PART * out.error)
            if math.isfinite(f) and not cheaper:
                _listed(out, b, A, tol)
    out.seconds = time.perf_counter() - t0
    return out


def _band(branch) -> tuple[float, float]:
    """The first mode's frequency band (Hz) of ``branch``'s problem by the definition
    (:func:`mmshbm.family.definition.frequency_band`) for an exact orbit: without the
    ``band_slack`` margin, which covers the truncated series of a harmonic balance orbit,
    not an exact one; (0, inf) where the solver offers none."""
    from mmshbm.core.problem import as_problem
    from mmshbm.family.definition import frequency_band

    solver = branch.attached_solver
    if solver is None or not len(branch):
        return 0.0, math.inf
    try:
        return frequency_band(as_problem(solver), [{"frequency": float(branch.frequency[0])}], 0.0)
    except (ValueError, RuntimeError, ArithmeticError, np.linalg.LinAlgError, AttributeError, TypeError):
        return 0.0, math.inf


def _own_estimate(branch, amplitude: float) -> tuple[float, bool]:
    """(the branch's own estimate at ``amplitude`` (m): the larger ``frequency_error`` of
    the two family points that bracket it, whether a ``tolerance_not_met`` finding covers
    it) of a tolerance branch."""
    front = np.asarray(branch.family_front(), dtype=int)
    A = np.asarray(branch.amplitude, dtype=float)[front]
    err = np.asarray(branch.frequency_error, dtype=float)[front]
    if not len(front):
        return math.nan, False
    below, above = np.flatnonzero(A <= amplitude), np.flatnonzero(A >= amplitude)
    near = [int(below[np.argmax(A[below])])] if len(below) else []
    near += [int(above[np.argmin(A[above])])] if len(above) else []
    estimate = float(np.max(err[near])) if np.all(np.isfinite(err[near])) else math.nan
    told = False
    for f in branch.findings:
        if f.kind == "tolerance_not_met" and 0 <= f.first <= f.last < len(branch):
            stretch = np.asarray(branch.amplitude, dtype=float)[f.first:f.last + 1]
            told = told or bool(stretch.min() <= amplitude * 1.02 and stretch.max() >= amplitude * 0.98)
    return estimate, told


def _listed(out: ExactComparison, branch, amplitude: float, tol: float) -> None:
    """The family's orbits of ``branch`` at ``amplitude`` (m) with the search
    (:meth:`mmshbm.Branch.orbits_at`), timed, and whether the exact orbit is among them
    (:func:`listed_orbit`), into ``out``. :func:`compare` asks it for the misses that
    neither the exact orbit's share nor the branch's truncation estimate explains (the
    search and the listed orbits' re-solves at 2H and 4H cost tens of pinned solves)."""
    t0 = time.perf_counter()
    try:
        orbits = branch.orbits_at(amplitude, search=True)
    except (ValueError, RuntimeError, ArithmeticError, np.linalg.LinAlgError):
        return
    out.orbits_seconds = time.perf_counter() - t0
    out.orbits_hz = tuple(float(o.frequency) for o in orbits)
    out.orbits_share = tuple(float(o.fundamental_share) for o in orbits)
    out.exact_listed = listed_orbit(branch, orbits, out.exact, tol)


def listed_orbit(branch, orbits, f_exact: float, tol: float = 1e-3, *, estimates: bool = True) -> str:
    """How the exact orbit of frequency ``f_exact`` (Hz) is among ``orbits`` (an
    :meth:`~mmshbm.Branch.orbits_at` answer): "within tol" when one orbit's frequency is
    within ``tol`` of it, "within its truncation estimate" when one orbit's own truncation
    estimate (re-solved at 2H and 4H) is at least :data:`TRUNCATION_PART` of its
    difference and its largest H lies closer to the exact frequency; empty when neither
    (the estimates are computed in increasing distance until one holds; not at all
    without ``estimates``)."""
    if any(abs(o.frequency / f_exact - 1) <= tol for o in orbits):
        return f"within {tol:g}"
    if not estimates:
        return ""
    from mmshbm.results.truncation import state_truncation_error

    for o in sorted(orbits, key=lambda o: abs(o.frequency / f_exact - 1)):
        try:
            est = state_truncation_error(branch, o.amplitude, o.frequency, o.state)
        except (ValueError, RuntimeError, ArithmeticError):
            continue
        closer = len(est.frequency) > 1 and abs(est.frequency[-1] - f_exact) < abs(o.frequency - f_exact)
        if closer and est.error >= TRUNCATION_PART * abs(o.frequency / f_exact - 1):
            return f"{o.frequency:.6g} Hz within its truncation estimate {est.error:.1e}"
    return ""


def branch_orbit(model, branch, amplitude: float, n_samples: int = 1024) -> tuple[float, float]:
    """(frequency in Hz, fundamental share) of the exact symmetric orbit at ``amplitude``
    (m) found by Newton shooting from the branch's own point there (the positions of the
    DOFs with mass at its turning point away from the stop, its half period); NaNs where
    the branch has no solved point there or Newton does not converge on an orbit of that
    excursion."""
    from mmshbm import exact
    from mmshbm.methods.exact.system import PiecewiseLinearSystem

    try:
        point = branch.solve_at([amplitude], stand_in=True)
        if not point.records["solved"][0]:
            return math.nan, math.nan
        _, q = point.time_signals(0, n_samples=n_samples)
        system = PiecewiseLinearSystem.of(model)
        q_l = q[model.l]
        x = q_l[:, int(np.argmax(system.amplitude_row @ q_l))]
        orbit = exact.periodic_orbit(model, amplitude, guess=(x, 0.5 / float(point.frequency[0])))
    except (ValueError, RuntimeError, ArithmeticError, np.linalg.LinAlgError):
        return math.nan, math.nan
    if not (orbit.converged and abs(orbit.max_excursion / amplitude - 1) < 1e-6):
        return math.nan, math.nan
    return float(orbit.frequency), orbit.fundamental_share()


def _self_report(branch, amplitude: float) -> tuple[float, str, int]:
    """(truncation error estimate, its note, contact closings per period of the branch's
    orbit) at ``amplitude`` (m); NaN, the reason and -1 where they cannot be had."""
    try:
        est = branch.truncation_error(amplitude)
        value, note = float(est.error), est.note
    except (ValueError, RuntimeError, ArithmeticError) as err:
        value, note = math.nan, str(err)
    return value, note, contact_closings(branch, amplitude)


def contact_closings(branch, amplitude: float, n_samples: int = 4096, floor: float = 1e-6) -> int:
    """How many times per period the contact closes on the branch's orbit at ``amplitude``
    (m): intervals where the admissible contact force (the exact static contact problem
    driven by the DOFs with mass) exceeds ``floor`` times its peak; -1 when the branch has
    no solved point there."""
    try:
        point = branch.solve_at([amplitude], stand_in=True)
        if not point.records["solved"][0]:
            return -1
        _, lam = point.contact_force(0, n_samples, admissible=True)
    except (ValueError, RuntimeError, ArithmeticError):
        return -1
    lam = np.atleast_2d(lam).max(axis=0)
    closed = lam > floor * max(float(lam.max()), 1e-300)
    if closed.all():
        return 1
    return int(np.sum(closed & ~np.roll(closed, 1)))


def _reported(branch, amplitude: float) -> str:
    """What ``branch`` itself reports at ``amplitude`` (m) that can set it apart from the
    single-contact orbit there, comma-separated (empty when nothing): "skipped" (inside the
    interval a jump skipped: ``frequency_at`` is NaN), "coexisting" (a coexisting-orbits
    interval holds it), "truncation" (the contact force of the truncated series pulls, or
    its contact DOF passes the stop, over a stretch of points whose amplitudes bracket
    it), "special point" (a fold or branch point within 5 % of it)."""
    from mmshbm.results.coexisting import coexisting_intervals

    A = np.asarray(branch.amplitude, dtype=float)
    out = []
    for s in branch.special_points:
        if s.kind == "jump":
            lo, hi = s.data.get("amplitude_frontier", math.nan), s.data.get("amplitude_to", math.nan)
            if lo < amplitude < hi:
                out.append("skipped")
                break
    if any(c.lo * (1 - 1e-9) <= amplitude <= c.hi * (1 + 1e-9) for c in coexisting_intervals(branch)):
        out.append("coexisting")
    for f in branch.findings:
        if f.kind in ("negative_force", "penetration") and 0 <= f.first <= f.last < len(A):
            stretch = A[f.first:f.last + 1]
            if stretch.min() <= amplitude * (1 + 0.02) and stretch.max() >= amplitude * (1 - 0.02):
                out.append("truncation")
                break
    if any(s.kind in ("fold", "branch_point") and abs(A[s.index] / amplitude - 1) <= 0.05
           for s in branch.special_points if 0 <= s.index < len(A)):
        out.append("special point")
    return ", ".join(out)


def _shares(r: ExactComparison) -> str:
    """The fundamental shares of a miss's exact orbits, and the exact orbit found from the
    branch's point where it was sought, for the report's line."""
    out = f"fundamental share {r.exact_share:.2f} (single-contact), {r.continued_share:.2f} (continued), "
    if math.isfinite(r.family_exact):
        out += f"exact from the branch {r.family_exact:.6g} Hz (share {r.family_share:.2f}), "
    return out


def _account(clean: list[ExactComparison], tol: float) -> str:
    """The summary's line of the stricter account of the ``clean`` cases (module
    docstring): within ``tol``, explained (and by what), unexplained (named), and the
    time per call of ``orbits_at(search=True)``."""
    bad = [r for r in clean if not r.error <= tol]
    good = len(clean) - len(bad)
    listed = sum(1 for r in bad if r.exact_listed)
    share = sum(1 for r in bad if r.exact_share < EXACT_FAMILY_SHARE)
    trunc = sum(1 for r in bad if r.estimate >= TRUNCATION_PART * r.error)
    band = sum(1 for r in bad if not r.in_band)
    unmet = sum(1 for r in bad if r.tolerance_not_met)
    explained = [r for r in bad if r.explanations(tol)]
    unexplained = [r for r in bad if not r.explanations(tol)]
    n = max(len(clean), 1)
    named = ", ".join(name(r.case) for r in unexplained)
    times = [r.orbits_seconds for r in clean if math.isfinite(r.orbits_seconds)]
    timing = (f"; orbits_at(search=True) {np.median(times):.2f} s median, {max(times):.2f} s at most "
              f"over {len(times)} calls" if times else "")
    return (f"within {tol:g}: {good} ({100 * good / n:.1f} %); explained: {len(explained)} "
            f"({100 * len(explained) / n:.1f} %: "
            f"the exact orbit listed by orbits_at {listed}, its fundamental share < {EXACT_FAMILY_SHARE:g} "
            f"{share}, its frequency outside the first mode's band {band}, "
            f"the truncation estimate >= {TRUNCATION_PART:.2g} of the difference {trunc}"
            + (f", tolerance_not_met said {unmet}" if any(math.isfinite(r.tolerance) for r in clean) else "")
            + "); "
            f"unexplained: {len(unexplained)}" + (f" ({named})" if unexplained else "") + timing)


def report(results: list[ExactComparison], tol: float = 1e-3) -> str:
    """Agreement within ``tol`` among the clean cases, the median error, and each
    disagreeing case with the special points of its branch up to the amplitude."""
    clean = [r for r in results if r.clean]
    errs = np.array([r.error for r in clean])
    good = np.sum(errs <= tol)
    lines = [f"{len(results)} models, {len(clean)} with a clean exact orbit; within {tol:g}: {good} "
             f"({100 * good / max(len(clean), 1):.1f} %), median error "
             f"{np.nanmedian(errs) if np.any(np.isfinite(errs)) else math.nan:.2e}"]
    bad = [r for r in clean if not r.error <= tol]
    lines.append(_account(clean, tol))
    coexist = [r for r in bad if r.coexisting]
    resonant = [r for r in bad if not r.coexisting and r.resonant]
    trunc = [r for r in bad if not r.coexisting and not r.resonant and r.truncation]
    lines.append(f"disagreeing: {len(bad)}; {len(coexist)} where another orbit coexists and the exact orbit "
                 f"continued from the linear mode agrees with the branch; {len(resonant)} where the "
                 "continued or single-contact orbit is an internal resonance's (fundamental share < 0.5) "
                 "and the branch "
                 f"is the exact orbit with the fundamental's majority; {len(trunc)} converging toward the "
                 "exact orbit at 2H (truncation of the Fourier series); "
                 f"{len(bad) - len(coexist) - len(resonant) - len(trunc)} other")
    right = [r for r in clean if r.first_mode]
    lines.append(f"on the first mode's orbit within {tol:g} (the exact orbit, or the exact orbit continued "
                 "from the linear mode where another coexists, or the exact orbit with the fundamental's "
                 f"majority where those are a resonance's): {len(right)} "
                 f"({100 * len(right) / max(len(clean), 1):.1f} %)")
    told = [r for r in bad if r.reasons(tol)]
    right_or_told = good + sum(1 for r in bad if r.reasons(tol) or r.first_mode)
    share_right_or_told = 100 * right_or_told / max(len(clean), 1)
    by_estimate = [r for r in bad if r.estimate >= tol]
    lines.append(f"explained by the branch itself (its truncation estimate >= {tol:g}, an orbit closing the "
                 f"contact more than once per period, its findings and special points at the amplitude): "
                 f"{len(told)} of {len(bad)} ({len(by_estimate)} by the truncation estimate); agreeing or "
                 f"explained: {100 * (good + len(told)) / max(len(clean), 1):.1f} %; "
                 f"on the first mode's orbit or explained: {share_right_or_told:.1f} %")
    for r in bad:
        kind = ("coexisting" if r.coexisting else "resonant" if r.resonant
                else "truncation" if r.truncation else "OTHER")
        why = "; ".join(r.reasons(tol)) or "not reported"
        account = "; ".join(r.explanations(tol)) or "UNEXPLAINED"
        orbits = ", ".join(f"{f:.6g} Hz ({share:.2f})"
                           for f, share in zip(r.orbits_hz, r.orbits_share, strict=True))
        lines.append(f"  {kind} [{why}] {{{account}; orbits_at: {orbits or 'none'}}} "
                     f"(estimate {r.estimate:.2e} {r.estimate_note}): {name(r.case)}: "
                     f"exact {r.exact:.6g} Hz, continued exact {r.continued:.6g} Hz, {_shares(r)}"
                     f"branch {r.branch:.6g} Hz (error {r.error:.2e}, at 2H "
                     f"{r.error_2h:.2e}, {r.status}); {r.special[:6]}")
    return "\n".join(lines)
