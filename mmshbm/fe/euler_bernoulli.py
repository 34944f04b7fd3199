"""The Euler–Bernoulli cantilever of general FE packages: Hermite-cubic elements with
consistent mass, a uniform mesh, full mass on every node (the tip included).

This is the element of NLvib's ``FE_EulerBernoulliBeam`` (Krack & Gross 2019) and of most
textbooks: per element of length l, with EI and ρA constant,

    k = EI/l³ [[12, 6l, −12, 6l], [6l, 4l², −6l, 2l²], [−12, −6l, 12, −6l], [6l, 2l², −6l, 4l²]],
    m = ρA l/420 [[156, 22l, 54, −13l], [22l, 4l², 13l, −3l²], [54, 13l, 156, −22l],
                  [−13l, −3l², −22l, 4l²]],

local order ``[w1, θ1, w2, θ2]`` (θ = dw/dx); no shear, no rotary inertia (the Φ → 0,
ρI → 0 limit of :mod:`mmshbm.fe.element`). It serves to bring models as FE packages export
them (the contact DOF carries mass) and to compare with those packages; the benchmark
structure of Schreyer, Peter & Leine is :class:`~mmshbm.fe.beam.TimoshenkoBeam`.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .. import _validate as check
from ..model.model import Model
from . import assembly

__all__ = ["element_matrices", "cantilever", "cantilever_model"]


def element_matrices(L, E: float, I: float, rho: float, A: float) -> tuple[np.ndarray, np.ndarray]:
    """Hermite-cubic stiffness and consistent mass of elements of lengths ``L`` (m), shape
    (n_e,); E (Pa), I (m⁴), ρ (kg/m³), A (m²). Returns ``(K, M)``, each (n_e, 4, 4), in N/m,
    N, N·m/rad and kg, kg·m, kg·m²."""
    L = np.atleast_1d(np.asarray(L, dtype=float))
    if L.ndim != 1 or not np.all(np.isfinite(L)) or np.any(L <= 0):
        raise ValueError(f"element lengths must be a 1-D array of finite values > 0 (m), got {L!r}")
    for name, v in (("E", E), ("I", I), ("rho", rho), ("A", A)):
        check.positive(name, v)
    l = L[:, None, None]  # noqa: E741 - the element length's name in the formulas
    one = np.ones_like(l)
    Ke = np.block([[12 * one, 6 * l, -12 * one, 6 * l],
                   [6 * l, 4 * l**2, -6 * l, 2 * l**2],
                   [-12 * one, -6 * l, 12 * one, -6 * l],
                   [6 * l, 2 * l**2, -6 * l, 4 * l**2]]) * (E * I / l**3)
    Me = np.block([[156 * one, 22 * l, 54 * one, -13 * l],
                   [22 * l, 4 * l**2, 13 * l, -3 * l**2],
                   [54 * one, 13 * l, 156 * one, -22 * l],
                   [-13 * l, -3 * l**2, -22 * l, 4 * l**2]]) * (rho * A * l / 420.0)
    return Ke, Me


def cantilever(length: float, width: float, height: float, E: float, rho: float,
               n_elements: int) -> tuple[sp.csr_matrix, sp.csr_matrix, np.ndarray]:
    """Mass and stiffness of a uniform clamped-free Euler–Bernoulli beam of rectangular
    section (bending about the ``width`` axis: the tip moves along ``height``).

    Parameters
    ----------
    length, width, height : float
        L, b, h (m), > 0.
    E, rho : float
        Young's modulus (Pa) and density (kg/m³), > 0.
    n_elements : int
        Number of equal elements (NLvib's ``n_nodes - 1``).

    Returns
    -------
    M, K : scipy.sparse.csr_matrix, shape (2 n_elements, 2 n_elements)
        Consistent mass and stiffness with the root removed: order
        ``[w1, θ1, ..., wn, θn]`` (NLvib's order for ``'clamped-free'``).
    dofs : ndarray of int, shape (n_elements + 1, 2)
        ``dofs[node] = [index of w, index of θ]`` (node 0 = root: ``[-1, -1]``, clamped);
        the tip deflection is ``dofs[-1, 0] = 2 n − 2``, its rotation ``dofs[-1, 1]``.
    """
    length = check.positive("length", length)
    width = check.positive("width", width)
    height = check.positive("height", height)
    n = check.integer("n_elements", n_elements, minimum=1)
    Ke, Me = element_matrices(np.full(n, length / n), E, width * height**3 / 12.0, rho, width * height)
    chain = assembly.chain_dofs(n)
    root = assembly.clamped_root_dofs()
    K = assembly.remove_dofs(assembly.assemble(Ke, chain), root)
    M = assembly.remove_dofs(assembly.assemble(Me, chain), root)
    dofs = np.arange(-2, 2 * n).reshape(n + 1, 2)
    dofs[0] = -1
    return M, K, dofs


def cantilever_model(length: float, width: float, height: float, E: float, rho: float, n_elements: int,
                     gap: float, stop_side: int = 1) -> Model:
    """The :func:`cantilever` as a :class:`~mmshbm.model.Model` with a stop at the tip
    deflection, every DOF with its mass (as an FE package exports it).

    The description names the contact node's DOFs (tip deflection and rotation, the
    default of :meth:`Model.with_massless_contact`) and the translational DOFs (for its mass
    report). Run it with ``method="penalty"``, or convert it for MMS-HBM with
    :meth:`Model.with_contact_layer` or :meth:`Model.with_massless_contact`.
    """
    M, K, dofs = cantilever(length, width, height, E, rho, n_elements)
    description = {"kind": "EulerBernoulliCantilever", "length": float(length), "width": float(width),
                   "height": float(height), "E": float(E), "rho": float(rho), "n_elements": int(n_elements),
                   "contact_node_dofs": dofs[-1].tolist(), "translation_dofs": dofs[1:, 0].tolist()}
    return Model.from_matrices(M, K, contact_dof=int(dofs[-1, 0]), gap=gap, stop_side=stop_side,
                               description=description)
