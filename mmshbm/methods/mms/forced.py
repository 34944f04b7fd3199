"""Forced responses by MMS-HBM: a damped structure with impact under harmonic excitation.

The structure of :class:`~mmshbm.model.Model` with its damping C and a harmonic force on
the DOFs with mass,

    M q'' + C q' + K q = Σ w_i λ_i + Re(F̂ e^{iΩt}),     Signorini at every stop,

has periodic responses of the excitation's period 2π/Ω (subharmonic and quasi-periodic
responses are outside the ansatz; Floquet multipliers say when the periodic one loses
stability). Unknowns: the cosine *and* sine coefficients of the massless DOFs up to
harmonic H (n_c (2H+1) numbers) and Ω, the continuation parameter; the equations are
the projected contact residual of :mod:`mmshbm.methods.mms.damped` with the force
condensed per harmonic onto the massless DOFs (:mod:`mmshbm.methods.mms.condensation.damped_condense`):

    F = 𝔇(Ω) x − σ(Ω) P(Ω),    P̂_1 = −Z_1ᵀ F̂_l,     ∂F/∂Ω = (∂𝔇/∂Ω) x − σ ∂P/∂Ω − σ' P,

σ(Ω) = 1 for a force, Ω² for a base displacement. The excitation breaks time invariance,
so there is no phase anchor; the system is square in x at fixed Ω and pseudo-arclength
continuation in (x, Ω) passes the folds of the resonance peak.

Excitations (:class:`Excitation`): :func:`harmonic_force` (a force vector, complex for
phase shifts between DOFs) and :func:`base_excitation` (the structure's support moves
harmonically; in coordinates relative to the support, which carries the stops, the load
is the inertia force −M r ü_b with r the rigid motion of a unit support displacement;
damping acts on the relative motion).

The response phase is the lag of the amplitude DOF's fundamental behind the excitation
force (``Excitation.reference``; for base excitation the inertia force −M r ü_b): π/2 at
phase resonance, the criterion of the phase-locked-loop test.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ... import _validate as check
from ...core.measures import check_dof, harmonic_content, mean_energy
from ...core.problem import ForcedProblemBase, OneEvaluation
from ...model.model import Model
from .damped import DampedHBMBase, synthesis_matrix

__all__ = ["Excitation", "harmonic_force", "base_excitation", "ForcedResponseProblem"]


@dataclass(frozen=True, eq=False)
class Excitation:
    """A harmonic excitation at the response frequency Ω.

    Attributes
    ----------
    vector : ndarray, complex, shape (n_dof,)
        F̂: the force on every DOF is Re(σ(Ω) F̂ e^{iΩt}) (N, N·m); zero on massless DOFs.
    omega_power : int
        σ(Ω) = Ω**omega_power: 0 for a force or base acceleration, 2 for a base
        displacement amplitude.
    reference : complex
        The phase reference: the response phase is the lag of the fundamental behind
        arg(reference).
    kind : str
        "force", "base_acceleration" or "base_displacement".
    description : dict
        JSON-able facts to rebuild it (``{"kind": ..., ...}``).
    """

    vector: np.ndarray
    omega_power: int = 0
    reference: complex = 1.0
    kind: str = "force"
    description: dict = field(default_factory=dict)

    def scale(self, omega: float) -> tuple[float, float]:
        """(σ(Ω), σ'(Ω))."""
        p = self.omega_power
        return omega**p, (p * omega ** (p - 1) if p else 0.0)

    def to_json(self) -> dict:
        """JSON-able form (``Excitation.from_json`` inverts it)."""
        v = np.asarray(self.vector)
        return {"kind": self.kind, "omega_power": int(self.omega_power), "real": v.real.tolist(),
                "imag": v.imag.tolist(), "reference": [float(np.real(self.reference)),
                                                       float(np.imag(self.reference))],
                "description": self.description}

    @classmethod
    def from_json(cls, d: dict) -> Excitation:
        try:
            v = np.asarray(d["real"], dtype=float) + 1j * np.asarray(d["imag"], dtype=float)
            ref = complex(d["reference"][0], d["reference"][1])
            return cls(v, int(d["omega_power"]), ref, str(d["kind"]), dict(d.get("description", {})))
        except (KeyError, TypeError, ValueError, IndexError) as err:
            raise ValueError(f"malformed excitation record: {err}") from None


def harmonic_force(model: Model, force) -> Excitation:
    """A harmonic force vector F̂ (n_dof,) on the DOFs with mass, as an :class:`Excitation`.

    Raises
    ------
    ValueError, TypeError
        A vector of the wrong length, non-finite entries, all zeros, or a force on a
        massless DOF (its equation is static: put the force on a DOF with mass).
    """
    if isinstance(force, Excitation):
        force = force.vector
    try:
        F = np.asarray(force, dtype=complex)
    except (TypeError, ValueError) as err:
        raise TypeError(f"force must be a vector of numbers: {err}") from None
    if F.ndim != 1 or F.shape[0] != model.n_dof:
        raise ValueError(f"force must have length n_dof = {model.n_dof}, got shape {F.shape}")
    if not np.all(np.isfinite(F)):
        raise ValueError(f"force has non-finite entries at DOFs {np.flatnonzero(~np.isfinite(F)).tolist()}")
    on_c = model.c[np.abs(F[model.c]) > 0]
    if len(on_c):
        raise ValueError(f"force acts on the massless DOFs {on_c.tolist()}: their equations are static, so "
                         "apply the force to DOFs with mass")
    if not np.any(F):
        raise ValueError("force is zero everywhere")
    ref = F[int(np.argmax(np.abs(F)))]
    return Excitation(F, 0, complex(ref), "force", {"kind": "force"})


def base_excitation(model: Model, direction, acceleration: float | None = None,
                    displacement: float | None = None) -> Excitation:
    """The support moves harmonically, ü_b = Re(a e^{iΩt}) (or u_b = Re(d e^{iΩt})).

    Parameters
    ----------
    model : Model
    direction : array_like, shape (n_dof,), or "transverse"
        r: the displacement of every DOF for a unit rigid displacement of the support
        (for the beam's transverse support motion: 1 on deflections, 0 on rotations,
        ``"transverse"``).
    acceleration : float, optional
        Support acceleration amplitude a (m/s²): F̂ = −M r a.
    displacement : float, optional
        Support displacement amplitude d (m): F̂ = Ω² M r d (grows with Ω²).

    The response is relative to the support, which carries the stops (the gap is
    relative); the phase reference is the inertia force −M r ü_b.
    """
    if (acceleration is None) == (displacement is None):
        raise ValueError("give exactly one of acceleration= (m/s^2) and displacement= (m)")
    if isinstance(direction, str):
        if direction != "transverse" or model.description.get("kind") != "TimoshenkoBeam":
            raise ValueError(f"direction {direction!r} is only known for TimoshenkoBeam models "
                             "('transverse'): "
                             "give the vector r")
        r = np.zeros(model.n_dof)
        r[0::2] = 1.0
    else:
        r = np.asarray(direction, dtype=float)
        if r.shape != (model.n_dof,) or not np.all(np.isfinite(r)):
            raise ValueError(f"direction must be a finite vector of length {model.n_dof}, "
                             f"got shape {r.shape}")
    Mr = model.M @ r
    if not np.any(Mr):
        raise ValueError("the direction moves no mass: M r = 0")
    if acceleration is not None:
        a = check.real_number("acceleration", acceleration)
        if a == 0:
            raise ValueError("acceleration is 0: nothing excites the structure")
        return Excitation(-Mr * a + 0j, 0, complex(-a), "base_acceleration",
                          {"kind": "base_acceleration", "acceleration": a, "direction": r.tolist()})
    d = check.real_number("displacement", displacement)
    if d == 0:
        raise ValueError("displacement is 0: nothing excites the structure")
    return Excitation(Mr * d + 0j, 2, complex(d), "base_displacement",
                      {"kind": "base_displacement", "displacement": d, "direction": r.tolist()})


class ForcedResponseProblem(OneEvaluation, DampedHBMBase, ForcedProblemBase):
    """MMS-HBM forced response as a continuation problem in (x, Ω).

    Parameters
    ----------
    model : Model
        Damped (``model.damping``; undamped works away from resonances) with massless
        contact DOFs.
    force : Excitation or array_like (n_dof,)
        The excitation (:func:`harmonic_force`, :func:`base_excitation`).
    harmonics : int
        H >= 1.
    n_samples, r, backend, projection
        As in :class:`~mmshbm.methods.mms.damped.DampedHBMBase`.
    stability : bool or "auto"
        Floquet multipliers at every point (:mod:`mmshbm.methods.mms.stability`); "auto": when
        the model has at most 200 DOFs with mass.

    Notes
    -----
    Scaled unknowns ``u = [x / xscale, Ω / ω_ref]``; ω_ref the first open-contact
    frequency (rad/s). Monitored per point: frequency (Hz), amplitude (largest |q| of
    ``model.amplitude_dof``, m), phase (rad, lag of its fundamental behind the force),
    energy (J, period mean of kinetic + potential), contact_force_max (N), and with
    stability ``floquet_max`` and ``stable`` (1.0/0.0) and the multipliers ``floquet``.
    """

    method = "mmshbm"
    _away_convention = False

    def __init__(self, model: Model, force, harmonics: int = 5, n_samples: int | None = None,
                 r: float | None = None, backend: str = "auto", stability: bool | str = "auto",
                 projection: str = "exact"):
        excitation = force if isinstance(force, Excitation) else harmonic_force(model, force)
        if isinstance(force, Excitation):
            harmonic_force(model, force.vector)  # validate length and massless DOFs
        self.excitation = excitation
        self.force_l = np.ascontiguousarray(excitation.vector[model.l])
        super().__init__(model, harmonics, n_samples, r, backend, "MMS-HBM", rhs=self.force_l[:, None],
                         projection=projection)
        self.amplitude_dof = model.amplitude_dof
        if not (isinstance(stability, bool) or stability == "auto"):
            raise ValueError(f"stability must be True, False or 'auto', got {stability!r}")
        self.stability = (self.cond.n_l <= 200) if stability == "auto" else bool(stability)
        self._floquet = None
        self.colscale = np.concatenate([self.xscale, [self.omega_ref]])
        self.n_unknowns = self.n_x + 1

    # ------------------------------------------------------------------ unknowns
    def unpack(self, u: np.ndarray) -> tuple[np.ndarray, float]:
        """Scaled unknowns -> (x (n_x,) in m/rad, Ω in rad/s)."""
        if np.shape(u) != (self.n_unknowns,):
            raise ValueError(f"u must have shape ({self.n_unknowns},), got {np.shape(u)}")
        y = np.asarray(u, dtype=float) * self.colscale
        return y[:-1], float(y[-1])

    def pack(self, x: np.ndarray, omega: float) -> np.ndarray:
        return np.concatenate([np.asarray(x, dtype=float), [omega]]) / self.colscale

    def linear_response_point(self, frequency: float) -> np.ndarray:
        """Scaled unknowns of the linear response (contacts ignored) at ``frequency`` (Hz)."""
        omega = 2 * np.pi * check.positive("frequency", frequency)
        ch = self._condensed(omega)
        s, _ = self.excitation.scale(omega)
        # the massless DOFs of the linear response: D_1 Q̂_c = P̂_1 (no contact force)
        Qc = np.linalg.solve(ch.D[1], s * ch.P[:, 0])
        x = np.zeros(self.n_x)
        x[self.n_c:2 * self.n_c] = Qc.real
        x[2 * self.n_c:3 * self.n_c] = -Qc.imag
        return self.pack(x, omega)

    def start_point(self, frequency: float, max_iter: int = 30) -> np.ndarray:
        """Scaled unknowns of a converged response at ``frequency`` (Hz): the linear response
        when it stays off the stops, otherwise continued from a force level that does (σ from
        below the gap up to 1 in steps, Newton at fixed Ω, the step halved on failure).
        Falls back to the linear response (the continuation's first corrector then tries)."""
        u_lin = self.linear_response_point(frequency)
        x_lin, omega = self.unpack(u_lin)
        peak = max(abs(x_lin[self.n_c + i]) + abs(x_lin[2 * self.n_c + i]) for i in self.contact_rows)
        length = self.model.gap if self.model.gap > 0 else np.inf
        if not np.isfinite(length) or peak < 0.9 * length:
            return u_lin
        sigma, x = 0.5 * length / peak, x_lin * (0.5 * length / peak)
        step = sigma
        for _ in range(200):
            target = min(1.0, sigma + step)
            y = x * (target / sigma)
            ok = False
            for _ in range(max_iter):
                R, Jx, _, _ = self.residual_parts(y, omega, target, True)
                if not np.all(np.isfinite(R)):
                    break
                if np.abs(R / self.rowscale).max() < 1e-10:
                    ok = True
                    break
                try:
                    y = y - np.linalg.solve(Jx, R)
                except np.linalg.LinAlgError:
                    break
            if ok:
                x, sigma = y, target
                if sigma >= 1.0:
                    return self.pack(x, omega)
                step *= 1.5
            else:
                step *= 0.5
                if step < 1e-6:
                    break
        return u_lin

    def initial_tangent(self, u: np.ndarray | None = None) -> np.ndarray:
        """Increasing Ω."""
        t = np.zeros(self.n_unknowns)
        t[-1] = 1.0
        return t

    # ------------------------------------------------------------------ residual
    def residual_parts(self, x: np.ndarray, omega: float, sigma: float = 1.0, jacobian: bool = True):
        """Unscaled residual R (n_x,) and, if asked, ∂R/∂x (n_x, n_x), ∂R/∂Ω (n_x,) and
        ∂R/∂σ (n_x,) for the force scaled by σ (the phase-resonance problem's unknown)."""
        ch = self._condensed(omega, 0.0, jacobian)
        s, ds = self.excitation.scale(omega)
        Pv = self.first_harmonic_vector(s * ch.P[:, 0])
        if not jacobian:
            return self.fused_residual(ch.D, x, sigma * Pv)[0], None, None, None
        dP_hat = s * ch.dP_domega[:, 0] + ds * ch.P[:, 0]
        # parameters (Ω, σ): ∂F/∂Ω = (∂𝔇/∂Ω) x − σ ∂P/∂Ω, ∂F/∂σ = −P
        dD = np.zeros((2,) + ch.D.shape, dtype=complex)
        dD[0] = ch.dD_domega
        dload = np.column_stack([sigma * self.first_harmonic_vector(dP_hat), Pv])
        R, Jx, Jp = self.fused_residual(ch.D, x, sigma * Pv, dD, dload)
        return R, Jx, Jp[:, 0], Jp[:, 1]


    def _evaluate(self, u: np.ndarray, jacobian: bool):
        """Scaled residual (n_x,) and, if asked, its Jacobian (n_x, n_x + 1)."""
        x, omega = self.unpack(u)
        R, Jx, Jw, _ = self.residual_parts(x, omega, 1.0, jacobian)
        R = R / self.rowscale
        if not jacobian:
            return R
        J = np.empty((self.n_x, self.n_x + 1))
        J[:, :-1] = Jx * self.xscale[None, :]
        J[:, -1] = Jw * self.omega_ref
        J /= self.rowscale[:, None]
        return R, J

    # ------------------------------------------------------------------ results
    def _state(self, u: np.ndarray) -> tuple[np.ndarray, float, float]:
        """(x, Ω, σ) of the scaled unknowns (σ = 1: the force as given)."""
        x, omega = self.unpack(u)
        return x, omega, 1.0

    def coefficients(self, u: np.ndarray) -> np.ndarray:
        """NLvib-ordered coefficients of all DOFs, shape (n_dof, 2H+1)."""
        x, omega, sigma = self._state(u)
        return self._coefficients(x, omega, sigma)

    def _coefficients(self, x: np.ndarray, omega: float, sigma: float) -> np.ndarray:
        ch = self._condensed(omega, recover=True)
        s, _ = self.excitation.scale(omega)
        return self.full_coefficients(x, ch, sigma * s * ch.Y[:, 0])

    def needed_force_coefficients(self, u: np.ndarray) -> np.ndarray:
        """F (n_x,): the force (N) the structure needs at the massless DOFs (the stop's
        reaction at a contact DOF is −F there for a stop on the + side)."""
        x, omega, sigma = self._state(u)
        return self._needed(x, omega, sigma)

    def _needed(self, x: np.ndarray, omega: float, sigma: float) -> np.ndarray:
        ch = self._condensed(omega)
        s, _ = self.excitation.scale(omega)
        return self.needed_force(x, ch.D, sigma * s * ch.P[:, 0])

    def angular_frequency(self, u: np.ndarray) -> float:
        """Ω (rad/s) of the scaled unknowns ``u``."""
        return self._state(u)[1]

    def contact_force(self, u: np.ndarray, n_samples: int = 256):
        """(t (n_samples,) s, λ (n_contacts, n_samples) N): the force of each stop (>= 0 in
        the exact law; the degree-H signal may dip below)."""
        _, omega, _ = self._state(u)
        F = self.needed_force_coefficients(u)
        tau = 2 * np.pi * np.arange(check.integer("n_samples", n_samples, minimum=1)) / n_samples
        E = synthesis_matrix(self.H, tau)
        c = self.model.c
        lam = np.array([-ct.side * (E @ F[self._coef_index[int(np.searchsorted(c, ct.dof))]])
                        for ct in self.model.contacts])
        return tau / omega, lam

    def harmonic_content(self, u: np.ndarray, dof: int | None = None) -> np.ndarray:
        """|Q̂_k| for k = 0..H of ``dof`` (default the amplitude DOF); shape (H+1,)."""
        dof = check_dof(dof, self.model.n_dof, self.amplitude_dof)
        return harmonic_content(self.coefficients(u)[dof])

    def phase(self, q_coeffs: np.ndarray) -> float:
        """Lag (rad) of the fundamental of ``q_coeffs`` behind the excitation, in [−π/2, 3π/2)."""
        q1 = q_coeffs[1] - 1j * q_coeffs[2]
        lag = np.angle(self.excitation.reference) - np.angle(q1)
        return float((lag + 0.5 * np.pi) % (2 * np.pi) - 0.5 * np.pi)

    def monitor(self, u: np.ndarray) -> dict:
        """frequency (Hz), amplitude (m), phase (rad), energy (J), contact_force_max (N), and
        with stability floquet_max, stable, floquet (multipliers, complex (2 n_l,))."""
        x, omega, sigma = self._state(u)
        return self._record(x, omega, sigma)

    def _record(self, x: np.ndarray, omega: float, sigma: float) -> dict:
        Q = self._coefficients(x, omega, sigma)
        q = Q[self.amplitude_dof]
        F = self._needed(x, omega, sigma)
        rec = {"frequency": omega / (2 * np.pi), "amplitude": self.amplitude(q), "phase": self.phase(q),
               "energy": mean_energy(self.model, Q, omega),
               "contact_force_max": self.contact_force_max(x, F)}
        if self.stability:
            mu = self._multipliers(Q, omega)
            rec["floquet_max"] = float(np.abs(mu[0]))
            rec["stable"] = float(np.abs(mu[0]) <= 1.0 + 1e-6)
            rec["floquet"] = mu
        return rec

    def _multipliers(self, Q: np.ndarray, omega: float) -> np.ndarray:
        from .stability import FloquetSolver

        if self._floquet is None:
            self._floquet = FloquetSolver(self.model)
        return self._floquet.multipliers(Q[self.model.l], omega)

    def floquet_multipliers(self, u: np.ndarray) -> np.ndarray:
        """Floquet multipliers of the orbit at ``u`` (monodromy of the piecewise-linear
        flow along it, :mod:`mmshbm.methods.mms.stability`), sorted by decreasing modulus."""
        x, omega, sigma = self._state(u)
        return self._multipliers(self._coefficients(x, omega, sigma), omega)
