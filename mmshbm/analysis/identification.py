"""Material identification: Young's modulus and density from measured linear frequencies
(and, in :mod:`mmshbm.analysis.contact_fit`, re-exported here, the contact-layer stiffness
from a measured backbone: :func:`fit_contact_stiffness`).

The paper (Part I) fits only E and ρ of the beam model to the measured linear eigenfrequencies
(contact open). What the frequencies can tell: in the Timoshenko model every stiffness
term is proportional to E (bending E·I, shear κ·G·A with G = E / (2 (1 + ν)) at fixed ν)
and every mass term to ρ (ρ·A and rotary ρ·I), so K = E·K̂ and M = ρ·M̂ and

    f_k = sqrt(E / ρ) · f̂_k(geometry, ν)

exactly, shear and rotary inertia included. Frequencies alone therefore determine E/ρ
and nothing else. :func:`fit_material` hence fits E with ρ fixed by default (the density
of a steel beam is known far better than its modulus), and fits both when asked only
with a measured ``mass`` (kg) as a further residual; without it the report says that the
problem is rank deficient (condition number of the Jacobian, ``identifiable=False``)
and that the split between E and ρ merely follows the initial values.

The fit is a least-squares problem (:func:`scipy.optimize.least_squares`) in the log
parameters log(E/E₀), log(ρ/ρ₀) on the relative residuals log(f_model / f_measured).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.linalg as la
from scipy.optimize import least_squares

from .. import _validate as check
from .contact_fit import ContactFitReport, fit_contact_stiffness

__all__ = ["fit_material", "FitReport", "beam_frequencies", "fit_contact_stiffness", "ContactFitReport"]

log = logging.getLogger(__name__)

_FITTABLE = ("E", "rho")
#: Jacobians with a larger condition number count as rank deficient
_COND_LIMIT = 1e6
#: step (in log parameters) of the central-difference Jacobian
_FD_STEP = 1e-3
#: a fit whose rms relative frequency error exceeds this does not reproduce the data: the
#: parameters are then not identified whatever the conditioning (a model error dominates)
_RMS_LIMIT = 0.05
#: nor are parameters whose standard deviation exceeds this fraction of their value
_STD_LIMIT = 0.5


@dataclass(frozen=True)
class FitReport:
    """What :func:`fit_material` found.

    Attributes
    ----------
    parameters : tuple of str
        The fitted parameters ("E", "rho").
    initial, values : dict
        E (Pa) and ρ (kg/m³) before and after the fit.
    modes : ndarray of int, shape (m,)
        Mode numbers (1-based) the measured frequencies belong to.
    measured, initial_frequencies, frequencies : ndarray, shape (m,)
        Measured, initial-model and fitted-model linear frequencies (Hz).
    relative_residuals : ndarray, shape (m,)
        f_model / f_measured − 1 after the fit.
    rms_relative_error : float
        Root mean square of ``relative_residuals``.
    mass, model_mass : float or None
        Measured beam mass (kg) if given, and ρ·A·L of the fitted beam (kg).
    singular_values : ndarray, shape (n_params,)
        Of the Jacobian of the residuals in the log parameters at the solution.
    condition_number : float
        Their ratio (inf when one vanishes).
    identifiable : bool
        True when the condition number is below 1e6, the fitted model reproduces the
        frequencies (rms relative error at most 5 %) and no parameter's relative standard
        deviation exceeds 50 %.
    relative_std : dict
        Standard deviation of each parameter relative to its value, from the residual
        variance and (JᵀJ)⁻¹; NaN when not identifiable or with no redundancy.
    ratio : float
        E/ρ (m²/s²), the combination the frequencies determine.
    success : bool
    message : str
        The optimiser's message, plus the identifiability note.
    nfev : int
        Model evaluations.
    """

    parameters: tuple
    initial: dict
    values: dict
    modes: np.ndarray
    measured: np.ndarray
    initial_frequencies: np.ndarray
    frequencies: np.ndarray
    relative_residuals: np.ndarray
    rms_relative_error: float
    mass: float | None
    model_mass: float
    singular_values: np.ndarray
    condition_number: float
    identifiable: bool
    relative_std: dict
    ratio: float
    success: bool
    message: str
    nfev: int
    notes: list = field(default_factory=list)

    def summary(self) -> str:
        """A few lines for people (what the CLI prints)."""
        lines = [f"fitted {', '.join(self.parameters)} to {len(self.measured)} frequencies "
                 f"(modes {', '.join(str(int(m)) for m in self.modes)}): {self.message}"]
        for name, unit in (("E", "Pa"), ("rho", "kg/m^3")):
            mark = " (fitted)" if name in self.parameters else " (fixed)"
            std = self.relative_std.get(name)
            sd = f" ± {100 * std:.2g} %" if std is not None and np.isfinite(std) else ""
            lines.append(f"  {name:>3} = {self.values[name]:.6g} {unit}{sd}{mark}; "
                         f"initial {self.initial[name]:.6g}")
        lines.append(f"  E/rho = {self.ratio:.6g} m^2/s^2 (determined by the frequencies)")
        if self.mass is not None:
            lines.append(f"  mass: measured {self.mass:.6g} kg, model {self.model_mass:.6g} kg")
        lines.append("  mode  measured (Hz)  model (Hz)  residual (%)")
        for k, fm, f, r in zip(self.modes, self.measured, self.frequencies, self.relative_residuals,
                               strict=True):
            lines.append(f"  {int(k):>4}  {fm:13.6g}  {f:10.6g}  {100 * r:+12.3g}")
        status = "identifiable" if self.identifiable else "NOT identifiable"
        lines.append(f"  rms relative error {self.rms_relative_error:.3g}; condition number "
                     f"{self.condition_number:.3g} ({status})")
        lines.extend(f"  note: {n}" for n in self.notes)
        return "\n".join(lines)


def beam_frequencies(beam, n_elements: int = 21, n_modes: int = 3, grading: float = 10.0,
                     massless_tip: bool = True) -> np.ndarray:
    """The ``n_modes`` lowest linear frequencies (Hz, contact open) of ``beam`` meshed with
    ``n_elements``; shape (n_modes,)."""
    return beam.model(n_elements, grading=grading, massless_tip=massless_tip).linear_frequencies(n_modes)


def fit_material(beam, measured_frequencies, n_elements: int = 21, *, modes=None, fit=("E",),
                 mass: float | None = None, grading: float = 10.0, massless_tip: bool = True,
                 weights=None):
    """Identify Young's modulus (and density) of ``beam`` from measured linear frequencies.

    Parameters
    ----------
    beam : TimoshenkoBeam
        Geometry, ν, κ, gap, and the initial E (Pa) and ρ (kg/m³); the unfitted one stays.
    measured_frequencies : array_like, shape (m,)
        Measured linear eigenfrequencies (Hz) with the contact open.
    n_elements : int
        Elements of the model the frequencies are fitted with (the backbone's model).
    modes : array_like of int, shape (m,), optional
        Mode numbers (1-based) of the measured frequencies; default 1..m.
    fit : sequence of {"E", "rho"}
        Parameters to fit. ``("E",)`` (default) keeps ρ; ``("rho",)`` keeps E;
        ``("E", "rho")`` needs ``mass`` to be identifiable (see the module notes).
    mass : float, optional
        Measured mass of the beam (kg), compared with ρ·A·L as one more residual
        (relative, in log, like the frequencies). Only used when ρ is fitted.
    grading : float
        Mesh grading of the model.
    massless_tip : bool
        Fit the model with the massless tip node (default, the model the backbone uses,
        so that its linear frequency matches the measured one) or the consistent mass.
    weights : array_like, shape (m,), optional
        Weights of the relative frequency residuals (default 1).

    Returns
    -------
    beam : TimoshenkoBeam
        ``dataclasses.replace(beam, E=..., rho=...)`` with the fitted values.
    report : FitReport
        Fitted values, residuals, conditioning and identifiability.

    Raises
    ------
    ValueError, TypeError
        For non-positive or non-finite frequencies, bad modes or weights, unknown
        parameters, or a beam that is not a :class:`~mmshbm.fe.beam.TimoshenkoBeam`.
    """
    from ..fe.beam import TimoshenkoBeam

    if not isinstance(beam, TimoshenkoBeam):
        raise TypeError(f"beam must be a TimoshenkoBeam, got {type(beam).__name__}")
    f_meas = np.atleast_1d(np.asarray(measured_frequencies, dtype=float))
    if f_meas.ndim != 1 or len(f_meas) == 0 or not np.all(np.isfinite(f_meas)) or np.any(f_meas <= 0):
        raise ValueError("measured_frequencies must be positive finite numbers (Hz), "
                         f"got {measured_frequencies!r}")
    n_elements = check.integer("n_elements", n_elements, minimum=1)
    modes = np.arange(1, len(f_meas) + 1) if modes is None else np.atleast_1d(np.asarray(modes))
    if modes.dtype.kind not in "iu" or modes.shape != f_meas.shape or np.any(modes < 1) \
            or len(set(modes.tolist())) != len(modes):
        raise ValueError(f"modes must be {len(f_meas)} distinct mode numbers >= 1, got {modes!r}")
    if isinstance(fit, str):
        fit = (fit,)
    fit = tuple(fit)
    if not fit or any(p not in _FITTABLE for p in fit) or len(set(fit)) != len(fit):
        raise ValueError(f"fit must name distinct parameters among {_FITTABLE}, got {fit!r}")
    if mass is not None:
        mass = check.positive("mass", mass)
    w = np.ones(len(f_meas)) if weights is None else np.asarray(weights, dtype=float).ravel()
    if w.shape != f_meas.shape or not np.all(np.isfinite(w)) or np.any(w <= 0):
        raise ValueError(f"weights must be {len(f_meas)} positive numbers, got {weights!r}")
    use_mass = mass is not None and "rho" in fit
    if mass is not None and not use_mass:
        log.info("mass given but rho is not fitted: the mass is only reported")

    x0 = {name: float(getattr(beam, name)) for name in _FITTABLE}
    n_modes = int(modes.max())
    idx = modes - 1
    volume = beam.area * beam.length

    def candidate(p):
        values = dict(x0)
        for name, pi in zip(fit, p, strict=True):
            values[name] = x0[name] * math.exp(pi)
        return replace(beam, **values)

    def residuals(p):
        b = candidate(p)
        f = beam_frequencies(b, n_elements, n_modes, grading, massless_tip)[idx]
        r = w * np.log(f / f_meas)
        if use_mass:
            r = np.append(r, math.log(b.rho * volume / mass))
        return r

    def jacobian(p):
        # central differences: the log residuals are smooth (exactly linear in log E and log rho
        # for this model), so a large step is accurate and resolves the conditioning honestly
        J = np.empty((len(residuals(p)), len(p)))
        for j in range(len(p)):
            e = np.zeros(len(p))
            e[j] = _FD_STEP
            J[:, j] = (residuals(p + e) - residuals(p - e)) / (2 * _FD_STEP)
        return J

    f_initial = beam_frequencies(beam, n_elements, n_modes, grading, massless_tip)[idx]
    sol = least_squares(residuals, np.zeros(len(fit)), jac=jacobian, method="trf", x_scale=1.0, xtol=1e-14,
                        ftol=1e-14, gtol=1e-14, bounds=(-math.log(1e3), math.log(1e3)))
    fitted = candidate(sol.x)
    f_fit = beam_frequencies(fitted, n_elements, n_modes, grading, massless_tip)[idx]

    sv = la.svdvals(np.atleast_2d(sol.jac))
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else math.inf
    identifiable = bool(cond < _COND_LIMIT) and len(sol.fun) >= len(fit)
    notes = []
    if set(fit) == {"E", "rho"} and not use_mass:
        notes.append("frequencies determine only E/rho (K is proportional to E and M to rho at fixed nu): "
                     "the split between E and rho follows the initial values; pass mass=... or fix rho")
    if not identifiable:
        log.warning("material fit is rank deficient (condition number %.3g): %s", cond,
                    notes[0] if notes else "too few data")
    dof = len(sol.fun) - len(fit)
    std = {name: float("nan") for name in fit}
    if identifiable and dof > 0:
        s2 = 2.0 * sol.cost / dof
        cov = s2 * la.inv(sol.jac.T @ sol.jac)
        std = {name: float(math.sqrt(max(cov[i, i], 0.0))) for i, name in enumerate(fit)}
    rel = f_fit / f_meas - 1.0
    rms = float(np.sqrt(np.mean(rel**2)))
    order = np.argsort(modes)
    if np.any(np.diff(f_meas[order]) <= 0):
        notes.append("the measured frequencies do not increase with the mode number: they cannot be "
                     "these modes' eigenfrequencies")
    if rms > _RMS_LIMIT:
        identifiable = False
        notes.append(f"the fitted model misses the measured frequencies by {100 * rms:.3g} % rms (more than "
                     f"{100 * _RMS_LIMIT:g} %): the data and the model disagree, so nothing is identified; "
                     "check the mode numbers and the geometry")
    wide = [name for name, v in std.items() if np.isfinite(v) and v > _STD_LIMIT]
    if wide:
        identifiable = False
        notes.append(f"{', '.join(wide)} uncertain by more than {100 * _STD_LIMIT:g} % (relative standard "
                     "deviation)")
    values = {name: float(getattr(fitted, name)) for name in _FITTABLE}
    message = sol.message if sol.success else f"not converged: {sol.message}"
    report = FitReport(
        parameters=fit, initial=x0, values=values, modes=modes.astype(int), measured=f_meas,
        initial_frequencies=f_initial, frequencies=f_fit, relative_residuals=rel,
        rms_relative_error=rms, mass=mass, model_mass=float(fitted.rho * volume),
        singular_values=sv, condition_number=cond, identifiable=identifiable, relative_std=std,
        ratio=values["E"] / values["rho"], success=bool(sol.success), message=message, nfev=int(sol.nfev),
        notes=notes)
    log.info("material fit: E = %.6g Pa, rho = %.6g kg/m^3, rms relative error %.3g, cond %.3g",
             values["E"], values["rho"], report.rms_relative_error, cond)
    return fitted, report
