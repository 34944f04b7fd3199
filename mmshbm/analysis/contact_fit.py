"""Contact-layer stiffness from a measured backbone, with its uncertainty.

The seed paper fits only E and ρ to the linear frequencies, and names the compliance of
the contact element as the likely reason why the measured backbone is slightly softer than
the rigid-stop model. :func:`fit_contact_stiffness` identifies that compliance: the model
keeps the tip's mass and gets a contact layer of stiffness k
(:meth:`~mmshbm.model.Model.with_contact_layer`); k is fitted to the measured frequencies at
the measured amplitudes above the gap. Fit E and ρ first
(:func:`~mmshbm.analysis.identification.fit_material`, on the model with the tip's mass):
below the gap the layer does not act, so the two fits separate.

Model frequencies are evaluated exactly at the measured amplitudes, not interpolated: the
backbone is computed once per k, and each measured amplitude is located on its first
rising stretch and refined by a secant iteration in the arclength along the chord between
the two branch points that bracket it (Newton corrector of
:func:`mmshbm.core.continuation.newton` on the same problem, to its tolerance 1e-10). The
residuals are r_i = ln(f_model(A_i; k) / f_i); the parameter is p = ln k, bounded to
[k_s, 10⁸ k_s] (k_s the static stiffness at the contact; the contact problem becomes
ill-conditioned beyond, see :mod:`mmshbm.model.transforms`). A scan over decades of k
gives the start, :func:`scipy.optimize.least_squares` the optimum.

Uncertainty (Gauss–Newton, from the Jacobian and the residual): with J = ∂r/∂p at the
optimum (central differences), m points, s² = Σ r_i² / (m − 1), the standard deviation of
ln k is σ = s / ‖J‖, i.e. k's relative standard deviation; the 95 % interval is
k·exp(± t₀.₉₇₅,ₘ₋₁ σ). It assumes independent frequency errors of equal variance and a
model that is right but for k; the sensitivity ‖J‖ falls like k_s/k, so a nearly rigid
contact gives a large σ (a lower bound on k, not a value), and the report says so.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from .._method_info import is_harmonic_balance

__all__ = ["fit_contact_stiffness", "ContactFitReport", "backbone_frequencies"]

log = logging.getLogger(__name__)

#: bounds of k in units of the static contact stiffness k_s
_K_RANGE = (1.0, 1e8)
#: start scan: k/k_s on these decades
_SCAN = 10.0 ** np.arange(1, 8)
#: central-difference step in ln k
_FD_STEP = 0.02
#: points closer than this (relative) to the gap are left out: the layer has no effect there
_ABOVE_GAP = 1e-3
#: samples along a chord where Newton fails near a pole (cubic interpolation error ~ h^4)
_SAMPLES = 65
#: a fit whose relative standard deviation exceeds this is reported as not identifiable
_IDENTIFIABLE_STD = 0.5


@dataclass(frozen=True)
class ContactFitReport:
    """What :func:`fit_contact_stiffness` found.

    Attributes
    ----------
    stiffness : float
        Fitted contact-layer stiffness k (N/m).
    relative_std : float
        Standard deviation of ln k (≈ of k relative to itself); NaN with a single point.
    std : float
        ``stiffness * relative_std`` (N/m).
    interval : tuple of float
        95 % confidence interval of k (N/m), k·exp(± t σ).
    static_stiffness : float
        k_s (N/m); ``stiffness / static_stiffness`` is the ratio to it.
    amplitudes, measured, frequencies : ndarray, shape (m,)
        The measured points used (m, Hz) and the fitted model's frequencies there (Hz).
    relative_residuals : ndarray, shape (m,)
        f_model / f_measured − 1.
    rms_relative_error : float
    sensitivity : ndarray, shape (m,)
        ∂ ln f / ∂ ln k at each point (the Jacobian).
    identifiable : bool
        relative_std < 0.5 and k inside its bounds.
    harmonics, method : int, str
        How the backbones were computed.
    success : bool
    message : str
    n_backbones : int
        Backbones computed (model evaluations).
    notes : list of str
    """

    stiffness: float
    relative_std: float
    std: float
    interval: tuple
    static_stiffness: float
    amplitudes: np.ndarray
    measured: np.ndarray
    frequencies: np.ndarray
    relative_residuals: np.ndarray
    rms_relative_error: float
    sensitivity: np.ndarray
    identifiable: bool
    harmonics: int
    method: str
    success: bool
    message: str
    n_backbones: int
    notes: list = field(default_factory=list)

    def summary(self) -> str:
        """A few lines for people (what the CLI prints)."""
        lo, hi = self.interval
        sd = f" ± {100 * self.relative_std:.2g} %" if np.isfinite(self.relative_std) else ""
        lines = [f"fitted the contact-layer stiffness to {len(self.measured)} measured backbone points "
                 f"({self.method}, H = {self.harmonics}): {self.message}",
                 f"  k = {self.stiffness:.6g} N/m{sd} (95 %: {lo:.4g} .. {hi:.4g} N/m) = "
                 f"{self.stiffness / self.static_stiffness:.4g} x the static stiffness "
                 f"{self.static_stiffness:.4g} N/m",
                 "  amplitude (m)  measured (Hz)  model (Hz)  residual (%)  dlnf/dlnk"]
        for a, fm, f, r, s in zip(self.amplitudes, self.measured, self.frequencies, self.relative_residuals,
                                  self.sensitivity, strict=True):
            lines.append(f"  {a:13.6g}  {fm:13.6g}  {f:10.6g}  {100 * r:+12.3g}  {s:9.3g}")
        status = "identifiable" if self.identifiable else "NOT identifiable"
        lines.append(f"  rms relative error {self.rms_relative_error:.3g} ({status})")
        lines.extend(f"  note: {n}" for n in self.notes)
        return "\n".join(lines)


def backbone_frequencies(model, amplitudes, harmonics: int = 5, method: str = "mmshbm",
                         **options) -> np.ndarray:
    """Frequencies (Hz) of ``model``'s backbone at ``amplitudes`` (m), each on the first
    rising stretch of the branch that reaches it, refined onto it (not interpolated).

    Parameters
    ----------
    model : Model
    amplitudes : array_like, shape (m,)
        Amplitudes (m), > 0, in the model's convention (largest excursion away from the stop).
    harmonics, method, **options
        As for :func:`mmshbm.backbone` (``n_samples``, continuation options, ...).

    Returns
    -------
    ndarray, shape (m,)
        NaN where the branch does not reach an amplitude before it stops.
    """
    import dataclasses

    from ..core.continuation import ContinuationOptions
    from ..methods.backbone import backbone
    from ..methods.registry import make_problem

    A = np.atleast_1d(np.asarray(amplitudes, dtype=float))
    if A.ndim != 1 or len(A) == 0 or not np.all(np.isfinite(A)) or np.any(A <= 0):
        raise ValueError(f"amplitudes must be finite numbers > 0 (m), got {amplitudes!r}")
    fields = {f.name for f in dataclasses.fields(ContinuationOptions)}
    cont = {k: options.pop(k) for k in list(options) if k in fields}
    branch = backbone(model, harmonics=harmonics, method=method, max_amplitude=float(A.max()) * (1 + 1e-6),
                      **cont, **options)
    if is_harmonic_balance(method):
        options["harmonics"] = harmonics
    problem = make_problem(model, method, **options)
    copts = ContinuationOptions(**{k: v for k, v in cont.items() if k != "bounds"})
    amp = branch.amplitude
    out = np.full(len(A), np.nan)
    for i, a in enumerate(A):
        j = _first_crossing(amp, a)
        if j is None:
            continue
        if amp[j + 1] == a:
            out[i] = branch.frequency[j + 1]
            continue
        f = _refine(problem, copts, branch.states[j], branch.states[j + 1], amp[j] - a, amp[j + 1] - a, a)
        if f is None:
            # the secant's Newton failed on this chord (semismooth residual): let the
            # continuation itself refine onto the amplitude as a bound
            log.debug("amplitude %.6g m: chord refinement failed, refining by continuation", a)
            b = backbone(model, harmonics=harmonics, method=method, max_amplitude=float(a), **cont,
                         **{k: v for k, v in options.items() if k != "harmonics"})
            ok = b.status == "bound:amplitude" and abs(b.amplitude[-1] / a - 1) < 1e-9
            f = b.frequency[-1] if ok else np.nan
        out[i] = f
    return out


def _refine(problem, copts, u0, u1, g0, g1, a):
    """Frequency (Hz) where the amplitude is ``a`` between the branch points u0, u1 (their
    amplitudes minus ``a``: g0 <= 0 <= g1), or None.

    Secant in the arclength s along the chord u0 → u1, each point corrected by Newton on
    the hyperplane through u0 + s t normal to it. MMS-HBM's condensed residual is singular
    where a harmonic kΩ meets an eigenfrequency of the structure with the massless DOFs
    held (a pole of D_k(Ω); the solution itself passes smoothly), so Newton may fail in a
    narrow window of s: then the chord is sampled at 65 points, and the root is found on a
    cubic through the four successful samples around it (logged)."""
    from ..core.continuation import _Failure as NewtonFailure  # what newton raises
    from ..core.continuation import newton

    ds = float(np.linalg.norm(u1 - u0))
    t = (u1 - u0) / ds

    def correct(s, start):
        try:
            u, *_ = newton(problem, start, t, u0 + s * t, copts.newton_tol, copts.max_newton, copts.step_tol)
        except NewtonFailure:
            return None
        if np.linalg.norm(u - (u0 + s * t)) > ds:  # converged elsewhere (another solution)
            return None
        rec = problem.monitor(u)
        return u, rec["amplitude"] - a, rec["frequency"]

    s0, s1, near_s, near_u = 0.0, ds, 0.0, u0
    for _ in range(30):
        if g1 == g0:
            break
        s = min(max(s1 - g1 * (s1 - s0) / (g1 - g0), 0.0), ds)
        got = correct(s, near_u + (s - near_s) * t)  # from the nearest corrected point
        if got is None:
            break
        near_u, g, f = got
        if abs(g) <= 1e-11 * a:
            return f
        if abs(s - s1) < 1e-15 * ds:
            break
        near_s = s
        s0, g0, s1, g1 = s1, g1, s, g
    samples = []
    for s in np.linspace(0.0, ds, _SAMPLES):
        got = correct(s, u0 + s * t)
        if got is not None:
            samples.append((s, got[1], got[2]))
    samples = np.array(samples)
    if len(samples) < 4:
        return None
    k = int(np.searchsorted(samples[:, 1], 0.0))  # g rises along the chord
    if not 0 < k < len(samples):
        return None
    pick = samples[max(0, min(k - 2, len(samples) - 4)):][:4]
    from scipy.interpolate import CubicSpline
    from scipy.optimize import brentq

    g_of, f_of = CubicSpline(pick[:, 0], pick[:, 1]), CubicSpline(pick[:, 0], pick[:, 2])
    lo, hi = samples[k - 1, 0], samples[k, 0]
    if g_of(lo) * g_of(hi) > 0:
        return None
    root = brentq(lambda x: float(g_of(x)), lo, hi, xtol=1e-14 * ds)
    log.info("amplitude %.6g m: Newton failed on part of the chord (a pole of the condensed stiffness?); "
             "frequency interpolated from the samples around it", a)
    return float(f_of(root))


def _first_crossing(amp: np.ndarray, a: float) -> int | None:
    """Index j of the first segment [j, j+1] of the rising stretch from the start that
    contains ``a``; None when the stretch turns back or ends below it."""
    for j in range(len(amp) - 1):
        if amp[j + 1] < amp[j]:
            return None
        if amp[j] <= a <= amp[j + 1]:
            return j
    return None


def fit_contact_stiffness(model, measured, harmonics: int = 5, *, method: str = "mmshbm",
                          initial: float | None = None, amplitude_range=None,
                          max_iterations: int | None = None, **options):
    """Fit the stiffness of a contact layer to a measured backbone.

    Parameters
    ----------
    model : Model
        The structure with its contact DOF carrying mass (as exported, or
        ``beam.model(n, massless_tip=False)``), E and ρ already fitted; one contact.
    measured : MeasuredBackbone or str or Path
        Measured frequency (Hz) against amplitude (m) (CSV: :mod:`mmshbm.analysis.measured`).
        The amplitude is the contact DOF's largest excursion away from the stop.
    harmonics : int
        H of the backbones (default 5).
    method : str
        Method that computes them on the layered model (default MMS-HBM).
    initial : float, optional
        Start value of k (N/m); default: the best of a scan over k = 10..10⁷ k_s.
    amplitude_range : (float, float), optional
        Use only measured points with amplitudes in this range (m); default every point
        above the gap.
    max_iterations : int, optional
        Cap on the optimiser's residual evaluations (each is one backbone; the Jacobian costs
        two more per iteration); default scipy's.
    **options
        Passed to :func:`mmshbm.backbone` (``n_samples``, continuation options).

    Returns
    -------
    model : Model
        ``model.with_contact_layer(k)`` with the fitted k.
    report : ContactFitReport

    Raises
    ------
    ValueError, TypeError
        A model with a massless or more than one contact, fewer than one usable point, a
        measured amplitude the model's backbone does not reach, a bad ``initial`` or range.
    """
    from ..model.model import Model
    from ..model.transforms import static_contact_stiffness
    from .measured import MeasuredBackbone, load_measured

    if not isinstance(model, Model):
        raise TypeError(f"model must be an mmshbm.Model, got {type(model).__name__}")
    if model.n_contacts != 1:
        raise ValueError(f"fit_contact_stiffness needs a model with one contact, got {model.n_contacts}")
    if model.massless_contacts:
        raise ValueError(f"contact DOF {model.contact_dof} is massless: a contact layer joins a massless "
                         "node to a DOF with mass (build the model with the contact node's mass, e.g. "
                         "beam.model(n, massless_tip=False))")
    if not isinstance(measured, MeasuredBackbone):
        measured = load_measured(measured)
    gap = model.gap
    lo, hi = (gap * (1 + _ABOVE_GAP), math.inf) if amplitude_range is None else amplitude_range
    if not (0 <= lo < hi):
        raise ValueError(f"amplitude_range must be (lo, hi) with 0 <= lo < hi (m), got {amplitude_range!r}")
    lo = max(lo, gap * (1 + _ABOVE_GAP))
    use = (measured.amplitude >= lo) & (measured.amplitude <= hi)
    if not np.any(use):
        raise ValueError(f"no measured point of {measured.source or 'the data'} lies above the gap "
                         f"({gap:g} m) within {amplitude_range!r}: the contact stiffness acts only in "
                         "contact")
    A, f_meas = measured.amplitude[use], measured.frequency[use]
    order = np.argsort(A)
    A, f_meas = A[order], f_meas[order]
    k_s = float(static_contact_stiffness(model)[0])
    p_lo, p_hi = (math.log(k_s * x) for x in _K_RANGE)
    count = [0]

    def frequencies(p):
        count[0] += 1
        f = backbone_frequencies(model.with_contact_layer(math.exp(p)), A, harmonics, method, **dict(options))
        if np.any(~np.isfinite(f)):
            bad = A[~np.isfinite(f)]
            raise ValueError(f"the model's backbone with k = {math.exp(p):.4g} N/m does not reach the "
                             f"measured amplitude(s) {bad.tolist()} m on its first rising stretch: restrict "
                             "amplitude_range")
        return f

    def residuals(p):
        return np.log(frequencies(float(p[0])) / f_meas)

    def jacobian(p):
        h = _FD_STEP
        return ((residuals(p + h) - residuals(p - h)) / (2 * h))[:, None]

    if initial is None:
        costs = [float(np.sum(residuals(np.array([math.log(k_s * x)])) ** 2)) for x in _SCAN]
        p0 = math.log(k_s * _SCAN[int(np.argmin(costs))])
    else:
        from .. import _validate as check

        p0 = math.log(check.positive("initial", initial))
        p0 = min(max(p0, p_lo), p_hi)
    if max_iterations is not None:
        from .. import _validate as check

        max_iterations = check.integer("max_iterations", max_iterations, minimum=1)
    sol = least_squares(residuals, [p0], jac=jacobian, method="trf", bounds=([p_lo], [p_hi]),
                        xtol=1e-8, ftol=1e-10, gtol=1e-10, max_nfev=max_iterations)
    p = float(sol.x[0])
    k = math.exp(p)
    r = residuals(np.array([p]))
    J = jacobian(np.array([p]))[:, 0]
    m = len(r)
    notes = []
    if m > 1 and np.any(J != 0):
        from scipy.stats import t as student

        s2 = float(r @ r) / (m - 1)
        sigma = math.sqrt(s2) / float(np.linalg.norm(J))
        q = float(student.ppf(0.975, m - 1))
        with np.errstate(over="ignore"):  # a flat fit: the interval reaches inf
            interval = (float(k * np.exp(-q * sigma)), float(k * np.exp(q * sigma)))
    else:
        sigma, interval = math.nan, (math.nan, math.nan)
        notes.append("one point (or no sensitivity): no uncertainty")
    at_bound = p <= p_lo + 1e-6 or p >= p_hi - 1e-6
    if at_bound:
        notes.append(f"k reached its bound ({k / k_s:.3g} x the static stiffness): the data "
                     + ("cannot tell the contact from a rigid one: k is only a lower bound"
                        if p >= p_hi - 1e-6 else "ask for a softer contact than the model allows"))
    identifiable = bool(np.isfinite(sigma) and sigma < _IDENTIFIABLE_STD and not at_bound)
    if np.isfinite(sigma) and sigma >= _IDENTIFIABLE_STD:
        notes.append(f"relative standard deviation {sigma:.3g}: the backbone hardly depends on k here "
                     "(∂ln f/∂ln k ~ k_s/k); more points further above the gap, or a softer contact, help")
    f_fit = f_meas * np.exp(r)
    rel = f_fit / f_meas - 1.0
    report = ContactFitReport(
        stiffness=k, relative_std=sigma, std=k * sigma, interval=interval, static_stiffness=k_s,
        amplitudes=A, measured=f_meas, frequencies=f_fit, relative_residuals=rel,
        rms_relative_error=float(np.sqrt(np.mean(rel**2))), sensitivity=J, identifiable=identifiable,
        harmonics=int(harmonics), method=method, success=bool(sol.success),
        message=sol.message if sol.success else f"not converged: {sol.message}", n_backbones=count[0],
        notes=notes)
    log.info("contact fit: k = %.6g N/m (%.3g k_s), relative std %.3g, rms %.3g", k, k / k_s, sigma,
             report.rms_relative_error)
    return model.with_contact_layer(k), report
