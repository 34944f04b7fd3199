"""MMS-HBM backbones of models with nonlinear elements (cubic, polynomial springs, compliant stops).

A smooth element needs no massless DOF. The structure is condensed exactly, per harmonic,
onto the set s of the elements' DOFs, the rigid stops' (massless) contact DOFs and the
amplitude DOF (:mod:`~mmshbm.methods.mms.set_condense`), and harmonic balance is written
on that set alone, the elements' forces by alternating frequency–time
(:mod:`~mmshbm.methods.mms.element_aft`):

    D_k(Ω) a_k + F_k(a) = 0     (rows of the set's DOFs without a stop),
    proj_k[ f + r ((p − hi)₊ − (lo − p)₊) ] = 0,  f = D_k a_k    (rows of a contact DOF),

the contact rows being MMS-HBM's proximal Signorini law (the fused kernel
:func:`~mmshbm.methods.mms.contact_kernels._mmshbm_eval` with no pole unknowns). The
Jacobian is analytic: D_k, ∂D_k/∂Ω from the condensation, ∂F/∂a from the sampled φ'(δ).

As for MMS-HBM on stops (:mod:`~mmshbm.methods.mms.conservative`) the ansatz is
cosine-only, a_k the cosine coefficients: the elements are displacement laws, so the
structure stays conservative and time-reversible and its nonlinear modes are symmetric
about the turning point at τ = 0; that removes the phase and the energy degeneracy at
once, and (H+1) n_s equations in (H+1) n_s + 1 unknowns follow a regular branch.

An element may not act on a contact DOF (the contact rows see the structure's force
alone). Unknowns ``u = [a_0/s, ..., a_H/s, Ω/ω_ref]``, s the per-DOF length scale: the
first stop's gap, or with elements only the length at which an element's force matches
the linear stiffness it acts against (:meth:`~mmshbm.elements.Element.length_scale`),
times the linear mode's shape.
"""

from __future__ import annotations

import numpy as np

from ... import _validate as check
from ...core.problem import BackboneProblemBase, OneEvaluation
from ...harmonic.harmonics import check_harmonics
from ...model.contact import admissible_intervals
from ...model.linear_modes import amplitude_mode
from ...model.model import Model
from .contact_kernels import _mmshbm_eval
from .element_aft import ElementForces, series_peak
from .set_condense import SetCondensation
from .tables import _tables

__all__ = ["ElementBackboneProblem", "element_set"]


def element_set(model: Model) -> tuple[np.ndarray, np.ndarray]:
    """(the set s of condensed DOFs (sorted), the contact DOFs in first-appearance order) of
    a model with elements: the elements' DOFs, the contact DOFs and the amplitude DOF.

    Raises
    ------
    ValueError
        An element on a contact DOF, or a contact DOF with mass.
    """
    contact_dofs = admissible_intervals(model.contacts)[0] if model.contacts else np.zeros(0, dtype=int)
    on_contact = sorted({d for e in model.elements for d in e.dofs} & set(contact_dofs.tolist()))
    if on_contact:
        raise ValueError(f"an element acts on the contact DOF{'s' if len(on_contact) > 1 else ''} "
                         f"{on_contact}: MMS-HBM with elements takes elements beside the stops, not on "
                         "their DOFs (put the element on a neighbouring DOF, or make the stop a "
                         "CompliantStop)")
    if model.contacts:
        model.require_massless_contacts("MMS-HBM")
    dofs = {d for e in model.elements for d in e.dofs} | set(contact_dofs.tolist()) | {model.amplitude_dof}
    return np.array(sorted(dofs), dtype=int), np.asarray(contact_dofs, dtype=int)


def element_length(model: Model, D0: np.ndarray, s: np.ndarray) -> float:
    """The length (m) the unknowns are scaled by: the smallest gap of the stops, or the
    smallest :meth:`~mmshbm.elements.Element.length_scale` of the elements against the
    condensed static stiffness they act on (1/(wᵀ D_0⁻¹ w))."""
    if model.contacts and model.gap > 0:
        return float(model.gap)
    position = {int(d): i for i, d in enumerate(s)}
    D0inv = np.linalg.inv(D0)
    lengths = []
    for e in model.elements:
        pos = [position[d] for d in e.dofs]
        w = e.direction
        compliance = float(w @ D0inv[np.ix_(pos, pos)] @ w)
        lengths.append(e.length_scale(1.0 / compliance if compliance > 0 else 1.0))
    return float(min(lengths))


class ElementBackboneProblem(OneEvaluation, BackboneProblemBase):
    """The MMS-HBM backbone of a model with elements (module docstring), as a continuation
    problem.

    Parameters
    ----------
    model : Model
        With at least one element (``model.elements``); its stops, if any, on massless DOFs
        that no element acts on; no friction.
    harmonics : int
        H >= 1.
    n_samples : int, optional
        Samples per period N >= 2H+1 of the AFT and of the stops' bracketing grid; default
        :func:`~mmshbm.harmonic.harmonics.default_n_samples` (16 H rounded up to a power of
        two: at least (d + 1) H + 1, the exact count for a polynomial of degree d <= 15).
    r : float or "static", optional
        The proximal parameter (N/m) of the stops, one or one per contact DOF; default each
        contact DOF's condensed static stiffness.
    mode : int
        The linear mode (1-based) the branch starts from.
    projection : {"exact", "sampled"}
        The stops' projection (:mod:`~mmshbm.methods.mms.conservative`).
    """

    method = "mmshbm"
    #: ``r``: the proximal parameter of the first stop (set only when there are stops)
    setting_names = ("H", "N", "r", "mode")

    def __init__(self, model: Model, harmonics: int = 5, n_samples: int | None = None, r=None, mode: int = 1,
                 projection: str = "exact"):
        if not isinstance(model, Model):
            raise TypeError(f"model must be an mmshbm.Model, got {type(model).__name__}")
        if not model.elements:
            raise ValueError("the model has no elements: use MMSHBMProblem (mmshbm.backbone does)")
        if model.friction:
            raise ValueError("MMS-HBM with elements does not take friction contacts")
        if projection not in ("exact", "sampled"):
            raise ValueError(f"projection must be 'exact' or 'sampled', got {projection!r}")
        self.model = model
        self.H, self.N = check_harmonics(harmonics, n_samples)
        self.mode = check.integer("mode", mode, minimum=1)
        if self.mode > len(model.l):
            raise ValueError(f"mode must be <= the number of DOFs with mass ({len(model.l)}), "
                             f"got {self.mode}")
        self.projection = projection
        self.set_dofs, contact_dofs = element_set(model)
        s = self.set_dofs
        self.n_s = n_s = len(s)
        position = {int(d): i for i, d in enumerate(s)}
        self.cond = SetCondensation(model, s)
        D0 = self.cond.dynamic_stiffness(0.0, 0, derivative=False)[0][0]
        self.aft = ElementForces(model.elements, s, self.H, self.N, cosine_only=True)

        # the stops: their DOFs' positions in the set, intervals and proximal parameter
        if len(contact_dofs):
            _, lo, hi = admissible_intervals(model.contacts)
            self.cdof = np.array([position[int(d)] for d in contact_dofs], dtype=np.int64)
            self.lo, self.hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
            static = 1.0 / np.diag(np.linalg.inv(D0))[self.cdof]
            self.r_each = _proximal(r, static)
            self.r = float(self.r_each[0])
        else:
            if r is not None:
                raise ValueError("r is the stops' proximal parameter: the model has no stops")
            self.cdof = np.zeros(0, dtype=np.int64)
            self.lo = self.hi = self.r_each = np.zeros(0)
            static = np.zeros(0)

        # the linear mode: frequency, shape on the set (unit motion of the amplitude DOF)
        self.linear_frequency, shape = amplitude_mode(model, self.mode)
        self.omega_ref = 2 * np.pi * self.linear_frequency
        self.amplitude_dof = int(model.amplitude_dof)
        self.mode_shape_s = shape[s]
        self._amp = position[self.amplitude_dof]
        single = len(model.contacts) == 1 and model.contacts[0].dof == self.amplitude_dof
        self._amp_sign = float(-model.contacts[0].side) if single else 0.0
        if len(contact_dofs):
            self.open_amplitude = self._open_amplitude

        # scaling: unknowns by the length times the mode's shape, rows by the force that makes
        length = element_length(model, D0, s)
        shape = np.abs(self.mode_shape_s)
        self.xscale = length * np.maximum(shape, 1e-3 * shape.max())
        fscale = np.abs(D0) @ self.xscale
        fscale[self.cdof] = static * length
        self.colscale = np.concatenate([np.tile(self.xscale, self.H + 1), [self.omega_ref]])
        self.rowscale = np.tile(fscale, self.H + 1)
        self.n_unknowns = (self.H + 1) * n_s + 1

        H, N = self.H, self.N
        tau, cos_table, sin_table = (t.copy() for t in _tables(H, N)[:3])
        self._tau, self._cos_table, self._sin_table = tau, cos_table, sin_table
        self._work = (np.empty((H + 1, n_s)), np.empty((H + 1, n_s)), np.empty(H + 1), np.zeros(H + 1),
                      np.empty(H + 1), np.empty(N), np.empty(N), np.empty(2 * N + 2), np.empty(2 * H + 1),
                      np.empty(2 * H + 1), np.empty(2 * H + 1), np.empty((H + 1, H + 1)))
        self._no_poles = (np.zeros(0), np.zeros(0, dtype=np.int64), np.zeros((0, n_s)), np.zeros(0))
        self._unit = (np.ones(self.n_unknowns - 1), np.ones(self.n_unknowns))
        self._cached = (None, None)
        #: residual (+ Jacobian) evaluations so far
        self.evaluations = 0

    # ------------------------------------------------------------------ unknowns
    def unpack(self, u: np.ndarray) -> tuple[np.ndarray, float]:
        """Scaled unknowns -> (cosine coefficients a (H+1, n_s) of the set's DOFs, Ω rad/s)."""
        if np.shape(u) != (self.n_unknowns,):
            raise ValueError(f"u must have shape ({self.n_unknowns},), got {np.shape(u)}")
        x = np.asarray(u, dtype=float) * self.colscale
        return x[:-1].reshape(self.H + 1, self.n_s), float(x[-1])

    def pack(self, a: np.ndarray, omega: float) -> np.ndarray:
        """(a (H+1, n_s), Ω) -> scaled unknowns."""
        return np.concatenate([np.asarray(a, dtype=float).ravel(), [omega]]) / self.colscale

    def linear_mode_point(self, amplitude: float) -> np.ndarray:
        """Scaled unknowns of the linear mode whose amplitude DOF swings ``amplitude`` (m)."""
        a = np.zeros((self.H + 1, self.n_s))
        a[1] = amplitude * self.mode_shape_s
        return self.pack(a, self.omega_ref)

    def initial_tangent(self) -> np.ndarray:
        """Unit tangent of the linear branch (growing amplitude, constant Ω)."""
        t = self.linear_mode_point(1.0)
        t[-1] = 0.0
        return t / np.linalg.norm(t)

    def _open_amplitude(self) -> float:
        """The amplitude (m) at which the linear mode first reaches a stop."""
        out = np.inf
        for ct in self.model.contacts:
            motion = abs(self.mode_shape_s[list(self.set_dofs).index(ct.dof)])
            if motion > 0:
                out = min(out, ct.gap / motion)
        return float(out)

    def frequency_of(self, u: np.ndarray) -> float:
        """The frequency (Hz) of the scaled unknowns."""
        return float(u[-1] * self.colscale[-1]) / (2 * np.pi)

    # ------------------------------------------------------------------ residual
    def _condensed(self, omega: float, derivative: bool):
        """(D, dD, sgn det S_oo,k (H+1,)) at Ω (:class:`SetCondensation`)."""
        last, kept = self._cached
        if last == omega and (kept[1] is not None or not derivative):
            return kept
        D, dD = self.cond.dynamic_stiffness(omega, self.H, derivative=derivative)
        kept = (D, dD, self.cond.pole_signs.copy())
        self._cached = (omega, kept)
        return kept

    def _evaluate(self, u: np.ndarray, jacobian: bool):
        """Scaled residual ((H+1) n_s,) and, if asked, its Jacobian ((H+1) n_s, (H+1) n_s + 1)."""
        self.evaluations += 1
        a, omega = self.unpack(u)
        D, dD, signs = self._condensed(omega, jacobian)
        n_r = self.n_unknowns - 1
        R = np.empty(n_r)
        J = np.empty((n_r, n_r + 1)) if jacobian else np.empty((1, 1))
        eta, pole_k, pole_b, pole_w2 = self._no_poles
        rows, cols = self._unit
        _mmshbm_eval(D, D if dD is None else dD, np.ascontiguousarray(a), eta, omega, pole_k, pole_b, pole_w2,
                     self.cdof, self.lo, self.hi, self.r_each, self.projection == "exact", self._cos_table,
                     self._sin_table, self._tau, rows, cols, jacobian, R, J, *self._work)
        F, dF = self.aft.evaluate(a, jacobian)
        R += F.ravel()
        # the first row of harmonic k times sgn det S_oo,k: det J keeps its sign through a pole
        # of D_k (the zeros are the same)
        rows = self._row_scale(signs)
        R /= rows
        if not jacobian:
            return R
        J[:, :-1] += dF.reshape(n_r, n_r)
        J *= self.colscale[None, :] / rows[:, None]
        return R, J

    def _row_scale(self, signs: np.ndarray) -> np.ndarray:
        """The row scale with the first row of each harmonic k signed by sgn det S_oo,k."""
        if np.all(signs > 0):
            return self.rowscale
        rows = self.rowscale.copy()
        rows[np.arange(self.H + 1) * self.n_s] *= signs
        return rows

    # ------------------------------------------------------------------ results
    def coefficients(self, u: np.ndarray) -> np.ndarray:
        """NLvib-ordered coefficients (n_dof, 2H+1) of every DOF (sine terms zero)."""
        a, omega = self.unpack(u)
        return self._coefficients(a, omega)

    def _coefficients(self, a: np.ndarray, omega: float) -> np.ndarray:
        X = self.cond.recover(omega, self.H)
        Q = np.zeros((self.model.n_dof, 2 * self.H + 1))
        for k in range(self.H + 1):
            col = 0 if k == 0 else 2 * k - 1
            Q[self.cond.s, col] = a[k]
            if self.cond.n_o:
                Q[self.cond.o, col] = -X[k] @ a[k]
        return Q

    def monitor(self, u: np.ndarray) -> dict:
        """frequency (Hz), amplitude (m: the largest excursion of the amplitude DOF, away
        from the stop of a single one-sided contact on it), energy (J: the potential energy
        of structure and elements at the turning point τ = 0, where every velocity
        vanishes), contact_force_max (N, the stops' largest force; 0 without stops)."""
        a, omega = self.unpack(u)
        D = self._condensed(omega, False)[0]
        Q = self._coefficients(a, omega)
        q0 = Q[:, 0] + Q[:, 1::2].sum(axis=1)
        energy = 0.5 * float(q0 @ (self.model.K @ q0)) + self.aft.potential(q0[self.cond.s])
        amp = np.zeros(2 * self.H + 1)
        amp[0], amp[1::2] = a[0, self._amp], a[1:, self._amp]
        amplitude = series_peak(amp, self._amp_sign, max(512, 8 * self.N))
        force = 0.0
        for ct in self.model.contacts:
            i = list(self.cond.s).index(ct.dof)
            needed = np.zeros(2 * self.H + 1)
            needed[0] = D[0, i] @ a[0]
            needed[1::2] = np.einsum("kj,kj->k", D[1:, i], a[1:])
            force = max(force, series_peak(-ct.side * needed, 1.0, max(512, 8 * self.N)))
        return {"frequency": omega / (2 * np.pi), "amplitude": amplitude, "energy": energy,
                "contact_force_max": max(force, 0.0)}


def _proximal(r, static: np.ndarray) -> np.ndarray:
    """r per contact DOF: None or "static" the condensed static stiffness, else a positive
    number, one or one per contact DOF."""
    n = len(static)
    if r is None or (isinstance(r, str) and r == "static"):
        return np.array(static, dtype=float)
    if isinstance(r, str):
        raise ValueError(f"r must be a positive number, one per contact DOF, or 'static' (MMS-HBM with "
                         f"elements), got {r!r}")
    values = np.atleast_1d(np.asarray(r, dtype=float))
    if values.ndim != 1 or len(values) not in (1, n):
        raise ValueError(f"r must be a number or one per contact DOF ({n}), got {r!r}")
    for v in values:
        check.positive("r", float(v))
    return np.broadcast_to(values, (n,)).astype(float).copy()
