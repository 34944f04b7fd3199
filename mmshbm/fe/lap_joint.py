"""A bolted lap joint of two solid plates: the benchmark structure for many contact pairs.

Two equal steel plates (length L, width b, thickness h; scikit-fem triquadratic hexahedra,
:func:`~mmshbm.fe.solid.box_matrices`) overlap over a length ``overlap``: plate A on
x ∈ [0, L], z ∈ [−h, 0], clamped at x = 0; plate B on x ∈ [L − overlap, 2L − overlap],
z ∈ [0, h], free at its end x = 2L − overlap (the tip). In the overlap the interface z = 0
carries an nx × ny grid of node pairs (the element vertices of both faces, nx·ny =
``contact_nodes``), each a contact pair of :mod:`mmshbm.model.contact_pairs` (normal +z
from A to B, tangents x, y) with the interface stiffness of its tributary area
(``normal_stiffness``, ``tangential_stiffness`` in N/m³, times the area) and μ = 0.3.

The bolt at the overlap's centre clamps the plates with ``preload`` (N), shared by the
pairs as a pressure cone, p ∝ exp(−r²/(2σ²)) with σ a quarter of the overlap's shorter
side (times each pair's tributary area, summing to the preload). It also joins the plates
elastically: springs ``bolt_stiffness`` (N/m, in x, y and z, shared equally) between the
paired nodes of the four pairs nearest its axis (the shank; without it a frictionless
joint would be a mechanism).

Normal law (``normal=``): "bonded" (default) — the preload keeps the interface closed, the
normal stiffness is linear and each pair's slip force is μ N0 (constant load); the linear
limits are the bonded joint (μ → ∞) and the plates joined by the bolt and the normal
stiffness alone (μ = 0). "unilateral" — a stop per pair at gap 0 and the slip force
μ (N0 + λ(t)) (the coupled law): the preload enters the friction limit only, the normal
contact force λ(t) is the dynamic one (no static normal load in the harmonic balance).

Reduction (:func:`~mmshbm.model.interface_reduction.reduce_to_interface`): onto the pairs'
slip DOFs (massless, exact static interface flexibility) and the tip's vertical DOF
(DOF 0, the amplitude DOF and where :attr:`LapJoint.force` acts), with ``n_modes`` modes of
the bonded joint and ``n_interface`` interface modes.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from .. import _validate as check

__all__ = ["LapJoint", "lap_joint", "grid_shape"]

_STEEL = {"E": 210e9, "nu": 0.3, "rho": 7850.0}


@dataclass(frozen=True, eq=False)
class LapJoint:
    """The lap joint and what its benchmark needs.

    Attributes
    ----------
    model : Model
        The reduced model: DOF 0 the tip's u_z (amplitude DOF), then the generalised
        coordinates, then the pairs' slip DOFs (:func:`~mmshbm.model.contact_pairs.pair_dofs`).
    force : ndarray (n_dof,)
        The tip load (N) on DOF 0.
    frequency_range : (float, float)
        Hz, around the bonded joint's first bending mode (0.85 f_1 to 1.05 f_1).
    bending_frequency : float
        The bonded joint's first bending frequency (Hz) of the reduced model.
    pair_positions : ndarray (n_pairs, 2)
        (x, y) of each pair (m).
    preloads : ndarray (n_pairs,)
        Each pair's share of the bolt's preload (N).
    full : dict
        The unreduced structure: ``M``, ``K`` (plates, bolt and bonded-normal springs, the
        DOFs with mass), ``K_lc``, ``K_cc`` (the pairs' slip DOFs), ``tip`` (its index)
        and ``reduction`` (:class:`~mmshbm.model.interface_reduction.InterfaceReduction`).
    """

    model: object
    force: np.ndarray
    frequency_range: tuple
    bending_frequency: float
    pair_positions: np.ndarray
    preloads: np.ndarray
    full: dict = field(repr=False, default_factory=dict)


def grid_shape(contact_nodes: int) -> tuple[int, int]:
    """(nx, ny) with nx·ny = ``contact_nodes``, ny the largest divisor <= √N (nx >= ny; N >= 1)."""
    n = check.integer("contact_nodes", contact_nodes, minimum=1)
    ny = max(d for d in range(1, int(np.sqrt(n)) + 1) if n % d == 0)
    return n // ny, ny


def _tributary(coords: np.ndarray) -> np.ndarray:
    """Trapezoidal weights (m) of 1-D grid points."""
    if len(coords) == 1:
        return np.ones(1)
    d = np.diff(coords)
    w = np.zeros(len(coords))
    w[:-1] += d / 2
    w[1:] += d / 2
    return w


def lap_joint(contact_nodes: int = 100, *, mu: float = 0.3, preload: float = 2000.0, length: float = 0.2,
              width: float = 0.04, thickness: float = 0.005, overlap: float = 0.05,
              normal_stiffness: float = 1e13, tangential_stiffness: float = 4e12, bolt_stiffness: float = 1e7,
              normal: str = "bonded", modal_damping: float = 0.002, tip_load: float = 1.0,
              outer_elements: int = 4, n_modes: int = 8, n_interface: int = 12) -> LapJoint:
    """The bolted lap joint with ``contact_nodes`` node pairs (module docstring).

    Parameters
    ----------
    contact_nodes : int
        Node pairs in the overlap, >= 1 (an nx × ny grid, :func:`grid_shape`).
    mu : float
        Friction coefficient >= 0.
    preload : float
        The bolt's clamping force (N), >= 0.
    length, width, thickness, overlap : float
        Each plate's L, b, h and the overlap (m), 0 < overlap < length.
    normal_stiffness, tangential_stiffness : float
        Interface stiffness per area (N/m³), > 0.
    bolt_stiffness : float
        The shank's stiffness (N/m) in each direction, > 0.
    normal : {"bonded", "unilateral"}
        The pairs' normal law.
    modal_damping : float
        Modal damping ratio of the reduced model's modes with free sliders (>= 0).
    tip_load : float
        Amplitude (N) of :attr:`LapJoint.force`.
    outer_elements : int
        Elements of each plate outside the overlap along x (>= 1).
    n_modes, n_interface : int
        Bonded-joint modes and interface modes of the reduction.

    Returns
    -------
    LapJoint
    """
    from ..model.contact_pairs import interface_matrices, pair_laws, pair_step
    from ..model.friction import add_friction
    from ..model.interface_reduction import reduce_to_interface
    from ..model.model import Model
    from .solid import box_matrices

    nx, ny = grid_shape(contact_nodes)
    if ny == 1:
        raise ValueError("contact_nodes must be a composite number >= 4 (an nx × ny grid of pairs, "
                         f"nx, ny >= 2), got {contact_nodes}")
    for name, value in (("length", length), ("width", width), ("thickness", thickness),
                        ("overlap", overlap), ("normal_stiffness", normal_stiffness),
                        ("tangential_stiffness", tangential_stiffness), ("bolt_stiffness", bolt_stiffness)):
        check.positive(name, value)
    if not overlap < length:
        raise ValueError(f"overlap must be shorter than the plates' length {length}, got {overlap}")
    mu = check.non_negative("mu", mu)
    preload = check.non_negative("preload", preload)
    modal_damping = check.non_negative("modal_damping", modal_damping)
    outer = check.integer("outer_elements", outer_elements, minimum=1)
    if normal not in ("bonded", "unilateral"):
        raise ValueError(f"normal must be 'bonded' or 'unilateral', got {normal!r}")
    L, b, h, ov = float(length), float(width), float(thickness), float(overlap)
    x_ov = np.linspace(L - ov, L, nx)
    y = np.linspace(-b / 2, b / 2, ny)
    xa = np.concatenate([np.linspace(0.0, L - ov, outer + 1)[:-1], x_ov])
    xb = np.concatenate([x_ov, np.linspace(L, 2 * L - ov, outer + 1)[1:]])
    Ma, Ka, la_, ca = box_matrices(xa, y, [-h, 0.0], **_STEEL)
    Mb, Kb, lb, cb = box_matrices(xb, y, [0.0, h], **_STEEL)
    # plate A clamped at x = 0; DOFs [A kept, B]
    keep_a = np.flatnonzero(la_[0] > 1e-9 * L)
    Ma, Ka, la_, ca = Ma[keep_a][:, keep_a], Ka[keep_a][:, keep_a], la_[:, keep_a], ca[keep_a]
    na = len(keep_a)
    M = sp.block_diag([Ma, Mb], format="csr")
    K = sp.block_diag([Ka, Kb], format="csr")
    n_l = M.shape[0]

    # the pairs: the vertex grid of the interface, nx × ny
    px, py = x_ov, y
    X, Y = np.meshgrid(px, py, indexing="ij")
    pos = np.column_stack([X.ravel(), Y.ravel()])

    def face_dofs(loc, comp, offset):
        out = np.empty((len(pos), 3), dtype=np.int64)
        on_face = np.flatnonzero(np.abs(loc[2]) <= 1e-9 * h)
        key = {(round(loc[0, i] / L, 9), round(loc[1, i] / L, 9), int(comp[i])): i for i in on_face}
        for p, (xp, yp) in enumerate(pos):
            for c in range(3):
                out[p, c] = key[(round(xp / L, 9), round(yp / L, 9), c)] + offset
        return out

    dofs_a = face_dofs(la_, ca, 0)
    dofs_b = face_dofs(lb, cb, na)
    area = np.outer(_tributary(px), _tributary(py)).ravel()
    centre = np.array([L - ov / 2, 0.0])
    r2 = np.sum((pos - centre) ** 2, axis=1)
    sigma = min(ov, b) / 4
    weight = np.exp(-r2 / (2 * sigma**2)) * area
    preloads = preload * weight / weight.sum()
    n_pairs = len(pos)
    frames = np.broadcast_to(np.eye(3), (n_pairs, 3, 3)).copy()
    bonded = normal == "bonded"
    K_add, K_lc, K_cc = interface_matrices(n_l, dofs_b, frames, dofs_a, normal_stiffness * area,
                                           tangential_stiffness * area, bonded)
    # the bolt's shank: springs in x, y, z between the four pairs nearest its axis
    bolt = np.argsort(r2, kind="stable")[:min(4, n_pairs)]
    k_b = bolt_stiffness / len(bolt)
    K_bolt, _, _ = interface_matrices(n_l, dofs_b[bolt], frames[bolt], dofs_a[bolt], np.full(len(bolt), k_b),
                                      np.full(len(bolt), k_b), True)
    K_ll = (K + K_add + K_bolt).tocsr()
    K_ll = 0.5 * (K_ll + K_ll.T)
    tip_x = 2 * L - ov
    cand = np.flatnonzero((np.abs(lb[0] - tip_x) <= 1e-9 * L) & (cb == 2))
    tip = int(na + cand[np.argmin(np.hypot(lb[1, cand], lb[2, cand] - h / 2))])
    red = reduce_to_interface(M, K_ll, K_lc, K_cc, tip, n_modes=n_modes, n_interface=n_interface)
    n_r = red.n_reduced
    dofs, gaps, sides, entries = pair_laws(n_r, n_pairs, bonded, np.zeros(n_pairs), np.full(n_pairs, mu),
                                           preloads)
    description = {"kind": "LapJoint", "contact_nodes": int(n_pairs), "grid": [int(nx), int(ny)], "mu": mu,
                   "preload": preload, "length": L, "width": b, "thickness": h, "overlap": ov,
                   "normal_stiffness": float(normal_stiffness),
                   "tangential_stiffness": float(tangential_stiffness),
                   "bolt_stiffness": float(bolt_stiffness), "normal": normal, "n_modes": int(n_modes),
                   "n_interface": int(n_interface), "full_dofs": int(n_l)}
    model = Model.from_matrices(sp.csr_matrix(red.M), sp.csr_matrix(red.K), dofs, gaps, sides, description,
                                amplitude_dof=0)
    if modal_damping > 0:
        model = model.with_damping(modal_ratio=modal_damping)
    model = add_friction(model, entries)
    step = pair_step(n_r, normal, dofs_b, dofs_a, frames, np.zeros(n_pairs), np.full(n_pairs, mu), preloads,
                     normal_stiffness * area, tangential_stiffness * area)
    d = dict(model.description)
    d["transforms"] = list(d.get("transforms", [])) + [step] + [{"name": "with_friction", "args": e}
                                                                for e in entries]
    from dataclasses import replace

    model = replace(model, description=d)
    f1 = _bonded_frequency(red)
    force = np.zeros(model.n_dof)
    force[0] = float(tip_load)
    full = {"M": M, "K": K_ll, "K_lc": K_lc, "K_cc": K_cc, "tip": tip, "reduction": red}
    return LapJoint(model, force, (0.85 * f1, 1.05 * f1), f1, pos, preloads, full)


def _bonded_frequency(red) -> float:
    """First frequency (Hz) of the reduced model with the slip DOFs held (the bonded joint)."""
    import scipy.linalg as la

    n = red.n_reduced
    w2 = la.eigh(red.K[:n, :n], red.M[:n, :n], eigvals_only=True, subset_by_index=[0, 0])[0]
    return float(np.sqrt(w2) / (2 * np.pi))
