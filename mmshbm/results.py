"""Branch: the result of a backbone computation.

A :class:`Branch` is a struct of arrays, one entry per converged point, plus the status
saying why the branch stopped, the special points, and the metadata needed to redo the
run. Per-point time signals, contact force and harmonic content come from the solver
object that computed the branch (``branch.solver``), which knows the model.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["Branch"]


@dataclass(eq=False)
class Branch:
    """A computed nonlinear mode (backbone curve).

    Attributes
    ----------
    frequency : ndarray, shape (n_points,)
        Oscillation frequency (Hz).
    amplitude : ndarray, shape (n_points,)
        Largest excursion (m) of the contact DOF away from the stop over a period.
    energy : ndarray, shape (n_points,)
        Mechanical energy (J) (period average of kinetic + potential energy).
    contact_force_max : ndarray, shape (n_points,)
        Largest contact force (N) over a period.
    newton_iterations : ndarray of int, shape (n_points,)
        Corrector iterations per point.
    step_size : ndarray, shape (n_points,)
        Arclength step (scaled units) that led to each point.
    states : ndarray, shape (n_points, n_unknowns)
        The solver's scaled unknowns per point (for MMS-HBM: contact-DOF cosine
        coefficients and Ω); ``solver`` turns them into signals.
    status : str
        Why the branch stopped ("bound:amplitude" is a normal end).
    method : str
        "mmshbm", "penalty" or "shooting".
    harmonics : int
        H (0 for shooting).
    special_points : list of (str, int)
        Named points: "start", "grazing", "fold", bound hits, "endpoint".
    metadata : dict
        Model description, solver options, versions, timings.
    solver : object
        The problem object that computed the branch (not saved).
    """

    frequency: np.ndarray
    amplitude: np.ndarray
    energy: np.ndarray
    contact_force_max: np.ndarray
    newton_iterations: np.ndarray
    step_size: np.ndarray
    states: np.ndarray
    status: str
    method: str
    harmonics: int
    special_points: list = field(default_factory=list)
    metadata: dict = field(default_factory=dict)
    solver: object = field(default=None, repr=False)
    residual_histories: list = field(default_factory=list, repr=False)

    def __len__(self) -> int:
        return len(self.frequency)

    @property
    def completed(self) -> bool:
        """True when the branch ended on a requested bound or the step budget."""
        return self.status.startswith("bound:") or self.status == "max_steps"

    # ------------------------------------------------------------------ per point
    def _require_solver(self):
        if self.solver is None:
            raise RuntimeError("this branch has no solver attached (loaded without its model?)")
        return self.solver

    def time_signals(self, point: int, dofs=None, n_samples: int = 256):
        """Displacements of ``dofs`` over one period at branch point ``point``.

        Returns
        -------
        t : ndarray, shape (n_samples,)
            Time (s) over one period.
        q : ndarray, shape (len(dofs), n_samples)
            Displacements (m) / rotations (rad); all DOFs when ``dofs`` is None.
        """
        return self._require_solver().time_signals(self.states[self._index(point)], dofs, n_samples)

    def contact_force(self, point: int, n_samples: int = 256):
        """Contact force λ(t) (N) over one period at ``point``: returns (t, λ)."""
        return self._require_solver().contact_force(self.states[self._index(point)], n_samples)

    def harmonic_content(self, point: int, dof: int | None = None) -> np.ndarray:
        """Amplitudes √(c_k² + s_k²) of harmonics 0..H of ``dof`` (default the contact DOF)
        at ``point``; shape (H+1,)."""
        return self._require_solver().harmonic_content(self.states[self._index(point)], dof)

    def frequency_at(self, amplitude: float) -> float:
        """Frequency (Hz) at ``amplitude`` (m), linearly interpolated on the first
        stretch of the branch that reaches it; NaN if the branch never does."""
        A, f = self.amplitude, self.frequency
        for i in range(len(A) - 1):
            lo, hi = sorted((A[i], A[i + 1]))
            if lo <= amplitude <= hi and hi > lo:
                s = (amplitude - A[i]) / (A[i + 1] - A[i])
                return float(f[i] + s * (f[i + 1] - f[i]))
        if len(A) and np.isclose(A[-1], amplitude, rtol=1e-9, atol=0):
            return float(f[-1])
        return float("nan")

    def _index(self, point: int) -> int:
        n = len(self)
        if isinstance(point, bool) or not isinstance(point, int | np.integer):
            raise TypeError(f"point must be an integer index, got {point!r}")
        if not -n <= point < n:
            raise IndexError(f"point {point} out of range for a branch of {n} points")
        return int(point) % n

    def __repr__(self) -> str:
        if len(self) == 0:
            return f"Branch(method={self.method!r}, empty, status={self.status!r})"
        return (f"Branch(method={self.method!r}, H={self.harmonics}, points={len(self)}, "
                f"frequency={self.frequency[0]:.4g}..{self.frequency[-1]:.4g} Hz, "
                f"amplitude up to {self.amplitude.max():.3g} m, status={self.status!r})")
