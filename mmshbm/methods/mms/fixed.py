"""The numbers of an MMS-HBM problem that its model and options fix: the contact DOFs,
their intervals and stiffness, r, the linear mode, the amplitude's rule and the scaling of
the unknowns and residual rows; kept per model for the problems with a named r."""

from __future__ import annotations

import copy
import weakref

import numpy as np

from ...model.contact import admissible_intervals
from ...model.model import Model
from .proximal import proximal_parameter

__all__ = ["fixed_contacts", "fixed_scaling", "kept_entries"]

#: model -> {(class, H, N, mode, backend, projection, poles[, rule]): the attributes below}
#: of the problems with a named r (:func:`fixed_contacts`, :func:`fixed_scaling`)
_FIXED: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
_FIXED_CONTACTS = ("contact_dofs", "cdof", "lo", "hi", "contact_stiffness_each", "r_each",
                   "contact_stiffness", "r", "gap", "linear_frequency", "omega_ref", "amplitude_dof",
                   "mode_shape_c", "_amp_sign", "_amp_in_c", "_amp_index")
_FIXED_SCALING = ("xscale", "eta_scale", "pole_scaling", "_eta_scale_force", "colscale", "rowscale")


def kept_entries(fixed: dict | None) -> dict | None:
    """The compiled overloads (dispatcher -> entry point,
    :func:`~mmshbm.core._entry.compiled_entry`) shared by the problems built from the kept
    numbers ``fixed``; None for a problem that computed its own (``fixed`` None). Those
    problems make their kernels' arguments by the same code from copies of the same arrays
    (C-contiguous, writeable float64 or int64, the scalars' Python types), so the types
    agree: the first of them types each kernel's arguments, the others take its entries."""
    if fixed is None:
        return None
    return fixed.setdefault("_entries", {})


def _own(value):
    """A copy of a kept attribute's value (each problem its own arrays and lists)."""
    return copy.copy(value) if isinstance(value, (np.ndarray, list)) else value


def fixed_contacts(problem, model: Model, r) -> None:
    """Set on ``problem`` (an MMS-HBM problem with ``cond`` and ``n_c`` set) the contact
    DOFs, their intervals and stiffness, r, the linear mode and the amplitude's rule
    (:data:`_FIXED_CONTACTS`)."""
    c_list = model.c.tolist()
    dofs, lo, hi = admissible_intervals(model.contacts)
    problem.contact_dofs = dofs
    problem.cdof = np.array([c_list.index(d) for d in dofs], dtype=np.int64)
    problem.lo, problem.hi = lo, hi
    D0inv = np.linalg.inv(problem.cond.D0)
    problem.contact_stiffness_each = 1.0 / np.diag(D0inv)[problem.cdof]
    problem.r_each = proximal_parameter(r, problem.contact_stiffness_each, model, problem.cond.D0,
                                        problem.cdof, problem.H, problem.mode)
    # the 0.1 names of a single contact
    problem.contact_stiffness = float(problem.contact_stiffness_each[0])
    problem.r = float(problem.r_each[0])
    problem.gap = model.gap

    freqs, modes = model.linear_modes(problem.mode)
    problem.linear_frequency = float(freqs[-1])
    problem.omega_ref = 2 * np.pi * problem.linear_frequency
    phi = modes[:, -1]
    problem.amplitude_dof = model.amplitude_dof
    ref = phi[problem.amplitude_dof]
    if abs(ref) < 1e-12 * np.max(np.abs(phi)):
        raise ValueError(f"linear mode {problem.mode} does not move the amplitude DOF "
                         f"{problem.amplitude_dof}")
    # unit motion of the amplitude DOF at τ = 0 (linear_modes orients the modes so that
    # the first contact DOF moves toward its stop)
    problem.mode_shape_c = phi[model.c] / abs(ref)
    contact_motion = np.abs(problem.mode_shape_c[problem.cdof]).max()
    if contact_motion < 1e-12 * np.abs(phi).max():
        raise ValueError(f"linear mode {problem.mode} does not move any contact DOF: no impact")
    # amplitude: excursion away from the stop of a single one-sided contact, else |q|
    single = len(model.contacts) == 1 and model.contacts[0].dof == problem.amplitude_dof
    problem._amp_sign = float(-model.contacts[0].side) if single else 0.0
    problem._amp_in_c = problem.amplitude_dof in c_list
    problem._amp_index = c_list.index(problem.amplitude_dof) if problem._amp_in_c else -1


def fixed_scaling(problem, n_p: int) -> None:
    """Set on ``problem`` (its pole terms set) the scaling of the unknowns and residual rows
    (:data:`_FIXED_SCALING`)."""
    length = problem.gap if problem.gap > 0 else 1.0
    shape = np.abs(problem.mode_shape_c)
    problem.xscale = length * np.maximum(shape, 1e-3 * shape.max())
    fscale = np.abs(problem.cond.D0) @ problem.xscale
    fscale[problem.cdof] = problem.contact_stiffness_each * length
    # η_jk gives the force b_j η and moves the DOFs with mass by −φ_j η: scale it by the
    # larger of the η that gives the force scale and the η that moves them by the length
    # scale (by the force alone, a stiff contact spring makes the scaled η, and the
    # pole row's sensitivity to Ω, grow with the spring; by the motion alone, a mode
    # that barely touches the contact makes η a free direction that the arclength
    # spends itself on)
    bnorm = np.abs(problem._pole_b).max(axis=1) if n_p else np.zeros(0)
    by_force = np.where(bnorm > 0, fscale.max() / np.maximum(bnorm, 1e-300), 1.0)
    phimax = (np.abs(problem.pole_set.phi[:, [j for _, j in problem.pole_set.pairs]]).max(axis=0)
              if n_p else np.zeros(0))
    by_motion = np.where(phimax > 0, length / np.maximum(phimax, 1e-300), 1.0)
    problem.eta_scale = np.maximum(by_force, by_motion)
    #: how the pole unknowns are scaled (recorded with a branch: results saved before it
    #: scaled them by the force alone, :meth:`states_from_force_scaling`)
    problem.pole_scaling = "force-or-motion"
    problem._eta_scale_force = by_force
    problem.colscale = np.concatenate([np.tile(problem.xscale, problem.H + 1), problem.eta_scale,
                                       [problem.omega_ref]])
    problem.rowscale = np.concatenate([np.tile(fscale, problem.H + 1), problem._pole_w2 * problem.eta_scale])
