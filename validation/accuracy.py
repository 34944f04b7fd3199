"""Accuracy asked for: ``backbone(model, tol=...)`` against the exact orbit, and the
per-point error estimate against the true error.

:func:`compare_tolerance` runs, on one random chain (:func:`validation.corpus_exact.chains`),
the exact symmetric single-contact orbit at ``amplitude_gaps`` gaps, the fixed-H backbone
(H = 31, or several fixed H) and the backbone with ``tol``, and compares them with the exact
frequency. The
reference counts where the exact orbit is *the mode's*: clean (converged, one contact per
period, the prescribed excursion) and with the fundamental harmonic's majority of the
kinetic energy (not an internal resonance's orbit).

:func:`estimator_ratios` measures ``estimate / true error`` of the per-point estimate
(:mod:`mmshbm.results.point_errors`) at several H: on the chains and on clearance
oscillators against :func:`mmshbm.exact.periodic_orbit`, on the default beam against the
same point re-solved at a much higher H.
"""

from __future__ import annotations

import dataclasses
import math
import time
import warnings

import numpy as np

__all__ = ["ToleranceComparison", "compare_tolerance", "report_tolerance", "estimator_ratios",
           "report_ratios"]


@dataclasses.dataclass
class ToleranceComparison:
    """One chain: the exact frequency, the fixed-H and the tolerance branch's (Hz), their
    processor times (s); ``ringing`` q = √(k_node / m_host) / (2π f_exact), how many times
    faster than the orbit the contact rings (its contact time about T / (2q)), and the
    tolerance run's cap on H. ``fixed``/``fixed_s`` are the run at ``fixed_harmonics``;
    ``more_fixed`` maps each further fixed H to its (frequency Hz, processor time s)."""

    label: str
    reference: bool
    exact: float
    fixed: float
    fixed_s: float
    adaptive: float
    adaptive_s: float
    estimate: float = math.nan
    point_error: float = math.nan
    harmonics: int = 0
    findings: str = ""
    status: str = ""
    ringing: float = math.nan
    max_harmonics: int = 64
    fixed_harmonics: int = 31
    more_fixed: dict = dataclasses.field(default_factory=dict)

    @property
    def fixed_error(self) -> float:
        return abs(self.fixed / self.exact - 1.0) if self.exact > 0 else math.nan

    def fixed_runs(self) -> dict:
        """Every fixed-H run: H -> (frequency Hz, processor time s), the first H first."""
        return {self.fixed_harmonics: (self.fixed, self.fixed_s), **self.more_fixed}

    def error_at(self, harmonics: int) -> float:
        """The relative frequency error of the fixed-H run at ``harmonics`` (NaN without
        an exact frequency or that run)."""
        f = self.fixed_runs().get(harmonics, (math.nan, 0.0))[0]
        return abs(f / self.exact - 1.0) if self.exact > 0 else math.nan

    @property
    def adaptive_error(self) -> float:
        return abs(self.adaptive / self.exact - 1.0) if self.exact > 0 else math.nan


def compare_tolerance(case, tol: float = 1e-4, amplitude_gaps: float = 1.3,
                      harmonics: int | tuple = 31, options: dict | None = None) -> ToleranceComparison:
    """The exact orbit, the fixed-H and the tolerance backbone of ``case`` at
    ``amplitude_gaps`` gaps (module docstring); ``harmonics``: the fixed H, or several (the
    first into ``fixed``, the others into ``more_fixed``, run after the tolerance run);
    ``options``: further keyword arguments of the tolerance run (e.g. ``max_harmonics``)."""
    from mmshbm import exact
    from mmshbm.methods.backbone import backbone

    from .corpus_exact import name

    model = case.model()
    A = amplitude_gaps * model.gap
    first, *others = (harmonics,) if isinstance(harmonics, int) else tuple(harmonics)
    others = [int(H) for H in dict.fromkeys(others) if H != first]
    try:
        orbit = exact.periodic_orbit(model, A)
        ref = bool(orbit.converged and orbit.n_contacts == 1 and abs(orbit.max_excursion / A - 1) < 1e-6
                   and orbit.fundamental_share() >= 0.5)
        f_exact = float(orbit.frequency)
    except (ValueError, ArithmeticError, np.linalg.LinAlgError, RuntimeError):
        ref, f_exact = False, math.nan
    out = ToleranceComparison(name(case), ref, f_exact, math.nan, 0.0, math.nan, 0.0,
                              ringing=ringing(case, f_exact),
                              max_harmonics=int((options or {}).get("max_harmonics", 64)),
                              fixed_harmonics=int(first))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        out.fixed, out.fixed_s, out.status = _fixed_run(model, first, A)
        t = time.process_time()
        try:
            b = backbone(model, tol=tol, max_amplitude=1.2 * A, **(options or {}))
            out.adaptive_s = time.process_time() - t  # the run; what follows is the comparison
            out.adaptive = float(b.frequency_at(A))
            front = np.asarray(b.family_front(), dtype=int)
            i = int(front[np.argmin(np.abs(b.amplitude[front] - A))])
            out.estimate = float(b.frequency_error[i])
            if ref:  # the branch's own point nearest A against the exact orbit at its amplitude
                o = exact.periodic_orbit(model, float(b.amplitude[i]))
                if o.converged and o.n_contacts == 1:
                    out.point_error = abs(float(b.frequency[i]) / float(o.frequency) - 1.0)
            out.harmonics = int(b.harmonics)
            out.findings = ", ".join(sorted({f.kind for f in b.findings if _concerns(b, f, A)}))
            out.status += b.status
        except Exception as err:  # noqa: BLE001 - reported
            out.status += f"tol: exception {err}"
            out.adaptive_s = time.process_time() - t
        for H in others:
            f, s, status = _fixed_run(model, int(H), A)
            out.more_fixed[int(H)] = (f, s)
            out.status += status
    return out


def _fixed_run(model, harmonics: int, amplitude: float) -> tuple[float, float, str]:
    """(frequency_at(amplitude) Hz, processor time s, status) of the fixed-H backbone up to
    1.2 × ``amplitude`` (m); NaN and the exception in the status where it raised."""
    from mmshbm.methods.backbone import backbone

    t = time.process_time()
    try:
        fixed = backbone(model, harmonics=harmonics, max_amplitude=1.2 * amplitude)
        s = time.process_time() - t
        return float(fixed.frequency_at(amplitude)), s, ""
    except Exception as err:  # noqa: BLE001 - reported
        return math.nan, time.process_time() - t, f"fixed H = {harmonics}: exception {err}; "


def ringing(case, frequency: float) -> float:
    """q = √(k_node / m_host) / (2π f) of a one-contact chain (its contact spring and the
    mass it hangs on; NaN for other cases): the contact rings q times faster than the
    orbit at f (Hz)."""
    p = case.params
    try:
        k, m = float(p["node_k"][0]), float(p["masses"][p["hosts"][0]])
    except (KeyError, IndexError, TypeError):
        return math.nan
    return math.sqrt(k / m) / (2 * math.pi * frequency) if frequency > 0 else math.nan


#: the H a single-contact chain needs for a relative frequency error of 1e-3 and of 1e-4,
#: in units of its ringing ratio q: measured by pinned solves at H = 16 … 256 on chains
#: with q = 15–31 (docs/accuracy.md, "Stiff contacts"): the error falls at an order below
#: 1 until H resolves the contact time, then at 2–4
NEEDED_H_PER_Q = {1e-3: 4.0, 1e-4: 8.0}


def warm_up(case) -> None:
    """Run both backbones once on ``case``'s model, untimed: the first run of a process
    compiles the numba kernels (cached on disk afterwards), which is no part of either
    method's cost."""
    from mmshbm.methods.backbone import backbone

    if case is None:
        return
    model = case.model()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for kw in ({"harmonics": 31}, {"tol": 1e-4}):
            try:
                backbone(model, max_amplitude=1.2 * model.gap, **kw)
            except Exception:  # noqa: BLE001 - the timed runs report it
                pass


def _concerns(branch, finding, amplitude: float) -> bool:
    """Whether ``finding`` concerns the amplitude (its stretch of points brackets it within
    2 %, or it names no points)."""
    if finding.first < 0:
        return True
    A = np.asarray(branch.amplitude, dtype=float)[finding.first:finding.last + 1]
    return bool(len(A) and A.min() <= amplitude * 1.02 and A.max() >= amplitude * 0.98)


def report_tolerance(results: list[ToleranceComparison], tol: float, within: float = 1e-3) -> str:
    """The agreement of both runs within ``within`` on the reference cases, their total
    processor times (s), and each miss of the tolerance run with what its branch says
    there; then each further fixed H (``more_fixed``) against the tolerance run."""
    ref = [r for r in results if r.reference]
    H0 = results[0].fixed_harmonics if results else 31
    n = max(len(ref), 1)
    fixed = sum(r.fixed_error <= within for r in ref)
    adaptive = sum(r.adaptive_error <= within for r in ref)
    points = sum(r.point_error <= within for r in ref)
    t_fixed = sum(r.fixed_s for r in ref)
    t_adaptive = sum(r.adaptive_s for r in ref)
    lines = [f"{len(results)} chains, {len(ref)} whose exact single-contact orbit is the mode's",
             f"within {within:g} of the exact frequency: fixed H = {H0} {fixed} ({100 * fixed / n:.1f} %), "
             f"tol = {tol:g} {adaptive} ({100 * adaptive / n:.1f} %) by frequency_at, {points} "
             f"({100 * points / n:.1f} %) by the branch's own point nearest the amplitude against the exact "
             "orbit at its amplitude",
             f"processor time: fixed H = {H0} {t_fixed:.1f} s, tol {t_adaptive:.1f} s "
             f"(ratio {t_adaptive / max(t_fixed, 1e-9):.2f})"]
    misses = [r for r in ref if not (r.adaptive_error <= within or r.point_error <= within)]
    told = [r for r in misses if r.findings]
    lines.append(f"tol misses (by both): {len(misses)}, {len(told)} with a finding at the amplitude; "
                 f"agreeing or told: {100 * (n - len(misses) + len(told)) / n:.1f} %")
    for r in misses:
        lines.append(f"  {r.label}: exact {r.exact:.7g} Hz, tol {r.adaptive:.7g} Hz "
                     f"(error {r.adaptive_error:.2e}, own point {r.point_error:.2e}, "
                     f"estimate {r.estimate:.2e}, H {r.harmonics}), "
                     f"fixed error {r.fixed_error:.2e}; q {r.ringing:.3g}: H needed for 1e-3 about "
                     f"{NEEDED_H_PER_Q[1e-3] * r.ringing:.0f}, for 1e-4 "
                     f"{NEEDED_H_PER_Q[1e-4] * r.ringing:.0f} (cap {r.max_harmonics}); "
                     f"findings [{r.findings or 'none'}] {r.status[:60]}")
    for name_, sel in (("q <= cap / 4", [r for r in ref if r.ringing <= r.max_harmonics / 4]),
                       ("q > cap / 4", [r for r in ref if not r.ringing <= r.max_harmonics / 4])):
        if not sel:
            continue
        ok = sum(r.adaptive_error <= within for r in sel)
        told = sum((r.adaptive_error <= within) or bool(r.findings) for r in sel)
        fx = sum(r.fixed_error <= within for r in sel)
        lines.append(f"{name_}: {len(sel)} chains, tol within {within:g} {ok} ({100 * ok / len(sel):.1f} %), "
                     f"within or a finding {told} ({100 * told / len(sel):.1f} %), "
                     f"fixed H = {H0} within {fx}; "
                     f"processor time tol / fixed {sum(r.adaptive_s for r in sel):.2f} s / "
                     f"{sum(r.fixed_s for r in sel):.2f} s")
    errs = np.array([r.adaptive_error for r in ref])
    if len(errs):
        lines.append(f"tol errors: median {np.nanmedian(errs):.2e}, 99th percentile "
                     f"{np.nanpercentile(errs, 99):.2e}, "
                     f"share <= tol: {100 * np.mean(errs <= tol):.1f} %")
    lines += _more_fixed_lines(ref, within)
    return "\n".join(lines)


def _more_fixed_lines(ref: list[ToleranceComparison], within: float) -> list[str]:
    """For each further fixed H of the reference cases ``ref``: its count within
    ``within``, its processor time (s) and the tolerance run's time over it."""
    if not ref:
        return []
    n = len(ref)
    t_adaptive = sum(r.adaptive_s for r in ref)
    adaptive = sum(r.adaptive_error <= within for r in ref)
    lines = []
    for H in ref[0].fixed_runs():
        ok = sum(r.error_at(H) <= within for r in ref)
        t = sum(r.fixed_runs().get(H, (math.nan, 0.0))[1] for r in ref)
        lines.append(f"fixed H = {H}: within {within:g} {ok} ({100 * ok / n:.1f} %), processor time "
                     f"{t:.2f} s; tol within {adaptive} at {t_adaptive:.2f} s (ratio tol / fixed "
                     f"{t_adaptive / max(t, 1e-9):.2f})")
    return lines if len(lines) > 1 else []


# ---------------------------------------------------------------------- the estimator
def _point_ratio(model, A: float, H: int, reference) -> tuple[float, float]:
    """(estimate, true error) of the fixed-H backbone's point at A (m); ``reference`` is
    the exact frequency (Hz) or a callable(branch point) -> reference frequency."""
    from mmshbm.methods.backbone import backbone

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        b = backbone(model, harmonics=H, max_amplitude=1.2 * A)
        p = b.solve_at([A])
        if not p.records["solved"][0]:
            return math.nan, math.nan
        est = float(p.estimate_frequency_error()[0])
        f_ref = reference(p) if callable(reference) else reference
    return est, abs(float(p.frequency[0]) / f_ref - 1.0)


def estimator_ratios(n: int, seed: int = 0, contact_decades=(0.0, 6.0), harmonics=(8, 16, 32),
                     beam: bool = True, progress=None) -> list[tuple]:
    """Rows (kind, label, H, estimate, true error) on ``n`` chains, ``n`` clearance
    oscillators and (``beam``) the default beam (module docstring)."""
    from mmshbm import ClearanceOscillator, default_beam, exact

    from .corpus_exact import chains, name

    rows = []

    def add(kind, label, model, A, f_ref):
        for H in harmonics:
            try:
                est, true = _point_ratio(model, A, H, f_ref)
            except Exception:  # noqa: BLE001 - a failed case is left out, counted by its absence
                continue
            rows.append((kind, label, H, est, true))
            if progress:
                progress(rows[-1])

    for case in chains(n, seed=seed, max_masses=3, contact_decades=contact_decades):
        model = case.model()
        A = 1.3 * model.gap
        try:
            o = exact.periodic_orbit(model, A)
        except (ValueError, ArithmeticError, RuntimeError, np.linalg.LinAlgError):
            continue
        if (o.converged and o.n_contacts == 1 and abs(o.max_excursion / A - 1) < 1e-6
                and o.fundamental_share() >= 0.5):
            add("chain", name(case), model, A, float(o.frequency))
    rng = np.random.default_rng([seed, 4242])
    for i in range(n):
        m, k1 = rng.uniform(0.5, 2), rng.uniform(1, 5)
        k2 = k1 * 10 ** rng.uniform(0, 4)
        model = ClearanceOscillator(m, k1, k2, 1.0).model()
        A = rng.uniform(1.05, 3.0)
        o = exact.periodic_orbit(model, A)
        if o.converged:
            add("clearance", f"clearance #{i} (m {m:.3g}, k1 {k1:.3g}, k2 {k2:.3g}, A {A:.3g})", model, A,
                float(o.frequency))
    if beam:
        model = default_beam().model(21)
        for A in (1.02, 1.1, 1.5, 3.0):
            def reference(p, H_ref=96):
                from mmshbm.results.point_errors import SolverLadder, raise_point

                ladder = SolverLadder(p)
                u = raise_point(ladder, p.harmonics, p.states[0], float(p.amplitude[0]), H_ref)
                return float(ladder.at(H_ref).monitor(u)["frequency"])

            add("beam", f"default beam at {A:g} gaps (reference H = 96)", model, A * model.gap, reference)
    return rows


def report_ratios(rows: list[tuple], floor: float = 1e-7) -> str:
    """The distribution of estimate / true error where the true error exceeds ``floor``."""
    lines = []
    kinds = sorted({r[0] for r in rows})
    for kind in [*kinds, "all"]:
        sel = [r for r in rows if (kind == "all" or r[0] == kind)]
        big = [r for r in sel if r[4] > floor and math.isfinite(r[3])]
        ratio = np.array([r[3] / r[4] for r in big])
        if not len(ratio):
            lines.append(f"{kind}: {len(sel)} points, none with a true error above {floor:g}")
            continue
        inside = np.mean((ratio >= 1 / 3) & (ratio <= 3))
        q = np.percentile(ratio, [0, 5, 25, 50, 75, 95, 100])
        lines.append(f"{kind}: {len(sel)} points, {len(big)} with a true error above {floor:g}; ratio "
                     f"estimate/true in [1/3, 3]: {100 * inside:.1f} %; min/5/25/50/75/95 %/max "
                     + " ".join(f"{v:.3g}" for v in q)
                     + f"; below 1/3: {int(np.sum(ratio < 1 / 3))}, above 3: {int(np.sum(ratio > 3))}")
    return "\n".join(lines)


# ---------------------------------------------------------------------- command line
def arguments(p) -> None:
    """The arguments of ``python -m validation accuracy``."""
    from mmshbm.cli import common

    p.add_argument("n", type=common.positive_int, metavar="N", help="chains of 1-3 masses (and clearances)")
    p.add_argument("--seed", type=common.non_negative_int, default=0, help="the corpus seed")
    p.add_argument("--contact-decades", type=common.finite_float, nargs=2, default=(0.0, 6.0),
                   metavar=("LO", "HI"), help="the contact spring as 10**U(LO, HI) N/m")
    p.add_argument("--tol", type=common.positive_float, default=1e-4, help="the tolerance asked for")
    p.add_argument("--max-harmonics", type=common.positive_int, default=None,
                   help="the tolerance run's cap on H (default the backbone's, 64)")
    p.add_argument("--fixed-harmonics", type=common.positive_int, nargs="+", default=[31], metavar="H",
                   help="the fixed-H runs compared with the tolerance run (default 31); the first "
                        "fills the fixed_hz / fixed_s columns, the others fixed_hz_H / fixed_s_H")
    p.add_argument("--estimator", action="store_true",
                   help="measure the per-point estimate against the true error instead")
    p.add_argument("--no-beam", action="store_true", help="with --estimator: leave the beam out")
    p.add_argument("--only", type=common.non_negative_int, nargs="+", default=None, metavar="I",
                   help="compare these chains only (their indices among the N)")
    p.add_argument("--out", default="out", help="folder of accuracy.csv / estimator.csv")


def main(args) -> int:
    """Run ``python -m validation accuracy`` (exit 1 when a reference case misses without
    a finding at the amplitude)."""
    import csv
    from pathlib import Path

    from mmshbm.cli import common

    from .corpus_exact import chains

    lo, hi = args.contact_decades
    if not lo < hi:
        raise ValueError(f"--contact-decades: LO must be below HI, got {lo:g} {hi:g}")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.estimator:
        rows = estimator_ratios(args.n, args.seed, (lo, hi), beam=not args.no_beam,
                                progress=lambda r: print(f"{r[1]:<60} H {r[2]:3d} estimate {r[3]:.2e} "
                                                         f"true {r[4]:.2e}", flush=True))
        print(report_ratios(rows))
        path = out / "estimator.csv"
        with open(path, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["kind", "case", "harmonics", "estimate", "true_error"])
            w.writerows([r[0], r[1], r[2], repr(r[3]), repr(r[4])] for r in rows)
        common.wrote(path)
        return 0
    results = []
    cases = chains(args.n, seed=args.seed, max_masses=3, contact_decades=(lo, hi))
    if args.only is not None:
        cases = [c for c in cases if c.index in set(args.only)]
    warm_up(cases[0] if cases else None)
    for case in cases:
        r = compare_tolerance(case, args.tol, harmonics=tuple(args.fixed_harmonics),
                              options=({} if args.max_harmonics is None
                                       else {"max_harmonics": args.max_harmonics}))
        results.append(r)
        more = "".join(f" H{H} {r.error_at(H):.1e} {s:5.2f} s" for H, (_, s) in r.more_fixed.items())
        print(f"{r.label:<34} {'ref' if r.reference else '   '} fixed {r.fixed_error:.1e} "
              f"{r.fixed_s:6.2f} s  "
              f"tol {r.adaptive_error:.1e} (point {r.point_error:.1e}) {r.adaptive_s:6.2f} s "
              f"H {r.harmonics:3d} "
              f"est {r.estimate:.1e} "
              f"[{r.findings}]{more}", flush=True)
    print(report_tolerance(results, args.tol))
    path = out / "accuracy.csv"
    more = list(results[0].more_fixed) if results else []
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["case", "reference", "exact_hz", "fixed_hz", "fixed_s", "tol_hz", "tol_s", "estimate",
                    "harmonics", "findings", "status", "point_error", "ringing_q"]
                   + [c for H in more for c in (f"fixed_hz_{H}", f"fixed_s_{H}")])
        w.writerows([r.label, int(r.reference), repr(r.exact), repr(r.fixed), f"{r.fixed_s:.4f}",
                     repr(r.adaptive), f"{r.adaptive_s:.4f}", repr(r.estimate), r.harmonics, r.findings,
                     r.status, repr(r.point_error), repr(r.ringing)]
                    + [v for H in more for v in (repr(r.more_fixed[H][0]), f"{r.more_fixed[H][1]:.4f}")]
                    for r in results)
    common.wrote(path)
    silent = [r for r in results if r.reference and not r.adaptive_error <= 1e-3 and not r.findings]
    return 1 if silent else 0
