"""3-D node-to-node contact pairs: a normal stop and Coulomb friction in the tangent plane.

A pair joins node a (three translational DOFs, or the ground) to node b across an
interface with unit normal n (pointing from a to b) and tangents t1, t2 (n, t1, t2 a
right-handed orthonormal frame; the tangents default to a frame built from n). The
relative displacement in that frame,

    d = R (u_b − u_a),    R = [n; t1; t2]  (3 × 3, rows),

is carried through the interface's stiffness (k_n, k_t, k_t) (N/m: the contact's
compliance, physical, or a stiff penalty) to three new massless DOFs per pair, the pair's
slip displacement s = (s_n, s_t1, s_t2) (m): the energy ½ (d − s)ᵀ diag(k_n, k_t, k_t) (d − s)
is added to the structure (a Jenkins element in three directions; the nodes keep their
mass, so FE exports run unchanged). On the new DOFs the laws of the model act, exactly as
:meth:`Model.with_friction` and the unilateral contacts put them:

* normal (``normal="unilateral"``): a stop at s_n = −gap (``side = −1``): the pair may open
  freely (s_n > −gap) and its contact force λ(t) >= 0 pushes it apart where it closes;
* tangent plane: Coulomb friction on s_t1 and s_t2, each pressed by the pair's normal
  force: slip force μ (N0 + λ(t)) (``normal_contact=`` of :mod:`mmshbm.model.friction`,
  the coupled law of :mod:`mmshbm.contact.coulomb_coupled`), N0 the pair's ``preload`` (N).
  Each tangent direction has its own scalar law: the friction set is the square
  |f_t1|, |f_t2| <= μN in the pair's frame, not the isotropic disc, so a pair's response is
  invariant under rotations of the whole problem (structure, normal and tangents together)
  but not under a rotation of t1, t2 alone about n.

``normal="bonded"``: the normal direction is a linear spring k_n between the nodes (no
stop, no normal DOF: the bolt's preload keeps the interface closed) and the friction on the
two tangent DOFs has the constant normal load N0 (slip force μ N0): two massless DOFs per
pair, the compiled friction rows.

The new DOFs are appended: pair p's DOFs are ``first + 3p + (0, 1, 2)`` = (s_n, s_t1, s_t2)
(``first + 2p + (0, 1)`` = (s_t1, s_t2) when bonded), ``first`` the model's former
``n_dof`` (:func:`pair_dofs`). The unilateral contacts of the pairs follow the model's own,
in pair order.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import scipy.sparse as sp

__all__ = ["with_contact_pairs", "pair_frames", "pair_dofs", "fe_pair_dofs", "interface_matrices",
           "pair_laws", "pair_step"]


def pair_frames(normals, tangents=None) -> np.ndarray:
    """The orthonormal frames R (n, 3, 3), rows (n, t1, t2), of the pairs.

    Parameters
    ----------
    normals : array_like (3,) or (n, 3)
        The normals (any length > 0; normalised here).
    tangents : array_like (n, 3) or (3,), optional
        The first tangent t1 of each pair (its component along n is removed, then it is
        normalised; t2 = n × t1). Default: the axis least aligned with n, projected.

    Raises
    ------
    ValueError
        A zero normal, or a tangent parallel to its normal.
    """
    n = np.atleast_2d(np.asarray(normals, dtype=float))
    if n.shape[-1] != 3 or n.ndim != 2:
        raise ValueError(f"normals must have shape (3,) or (n_pairs, 3), got {np.shape(normals)}")
    length = np.linalg.norm(n, axis=1)
    if not np.all(np.isfinite(length)) or np.any(length == 0):
        bad = np.flatnonzero(~(length > 0)).tolist()
        raise ValueError(f"normals must be finite and non-zero; pairs {bad} are not")
    n = n / length[:, None]
    if tangents is None:
        axis = np.argmin(np.abs(n), axis=1)
        t = np.eye(3)[axis]
    else:
        t = np.atleast_2d(np.asarray(tangents, dtype=float))
        t = np.broadcast_to(t, n.shape).copy()
    t = t - np.sum(t * n, axis=1)[:, None] * n
    tl = np.linalg.norm(t, axis=1)
    if np.any(~(tl > 1e-12)):
        bad = np.flatnonzero(~(tl > 1e-12)).tolist()
        raise ValueError(f"the tangents of pairs {bad} are parallel to their normals: give a tangent "
                         "direction in the contact plane")
    t = t / tl[:, None]
    return np.stack([n, t, np.cross(n, t)], axis=1)


def _pair_dof_array(name: str, dofs, n_dof: int, n_pairs: int | None):
    if dofs is None:
        return None
    arr = np.asarray(dofs)
    if arr.ndim == 1 and arr.shape[0] == 3 and n_pairs in (None, 1):
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != 3 or (n_pairs is not None and arr.shape[0] != n_pairs):
        want = "(n_pairs, 3)" if n_pairs is None else f"({n_pairs}, 3)"
        raise ValueError(f"{name} must hold the (u_x, u_y, u_z) DOFs of each pair's node, shape {want}, "
                         f"got {np.shape(dofs)}")
    if not np.issubdtype(arr.dtype, np.integer):
        if not np.all(np.equal(np.mod(arr, 1), 0)):
            raise TypeError(f"{name} must be integer DOF indices, got {arr.dtype}")
        arr = arr.astype(np.int64)
    bad = np.flatnonzero(((arr < 0) | (arr >= n_dof)).any(axis=1))
    if len(bad):
        raise ValueError(f"{name}: pairs {bad[:10].tolist()} name DOFs outside [0, {n_dof - 1}]")
    return arr.astype(np.int64)


def _per_pair(name: str, value, n: int, positive: bool = False) -> np.ndarray:
    arr = np.broadcast_to(np.asarray(value, dtype=float), (n,)) if np.ndim(value) <= 1 else None
    if arr is None or (np.ndim(value) == 1 and len(value) not in (1, n)):
        raise ValueError(f"{name} must be one number or one per pair ({n}), got shape {np.shape(value)}")
    ok = arr > 0 if positive else arr >= 0
    if not np.all(np.isfinite(arr) & ok):
        raise ValueError(f"{name} must be finite and {'> 0' if positive else '>= 0'}, got "
                         f"{arr[~(np.isfinite(arr) & ok)][:5].tolist()}")
    return np.array(arr, dtype=float)


def with_contact_pairs(model, dofs_b, normals, *, dofs_a=None, gap=0.0, mu=0.3, preload=0.0,
                       normal_stiffness, tangential_stiffness, tangents=None, normal: str = "unilateral"):
    """``model`` with node-to-node contact pairs (module docstring), a new Model.

    Parameters
    ----------
    model : Model
        The structure; its contacts, friction contacts, elements and damping are kept.
    dofs_b : array_like of int (n_pairs, 3)
        The (u_x, u_y, u_z) DOFs of node b of each pair (global axes).
    normals : array_like (3,) or (n_pairs, 3)
        Normal of each pair, from a to b (normalised here).
    dofs_a : array_like of int (n_pairs, 3), optional
        Node a of each pair; None: the ground (node-to-ground pairs).
    gap : float or (n_pairs,)
        Normal distance (m) the pair closes before it touches, >= 0 (unilateral only).
    mu : float or (n_pairs,)
        Friction coefficient >= 0.
    preload : float or (n_pairs,)
        Normal force N0 >= 0 (N) added to the contact force in the slip force (bonded: the
        constant normal load).
    normal_stiffness, tangential_stiffness : float or (n_pairs,)
        k_n, k_t > 0 (N/m), the interface's stiffness between the relative displacement of
        the nodes and the pair's slip DOFs.
    tangents : array_like (3,) or (n_pairs, 3), optional
        First tangent of each pair (:func:`pair_frames`).
    normal : {"unilateral", "bonded"}
        The normal law.

    Returns
    -------
    Model
        With the pairs' DOFs appended (:func:`pair_dofs`), their unilateral contacts after
        the model's own, their friction contacts after the model's own (t1 then t2 per
        pair), the call recorded in ``description["transforms"]`` (one
        ``with_contact_pairs`` step, then one ``with_friction`` step per friction DOF, so that
        saved results get the friction back).

    Raises
    ------
    ValueError, TypeError
        Naming the argument: shapes, DOFs out of range, a node in two pairs, a zero normal,
        non-positive stiffness, negative gap, μ or preload, an unknown ``normal``.
    """
    from .friction import add_friction, friction_args
    from .model import Model

    if normal not in ("unilateral", "bonded"):
        raise ValueError(f"normal must be 'unilateral' or 'bonded', got {normal!r}")
    n_dof = model.n_dof
    b = _pair_dof_array("dofs_b", dofs_b, n_dof, None)
    n_pairs = b.shape[0]
    a = _pair_dof_array("dofs_a", dofs_a, n_dof, n_pairs)
    used = b.ravel() if a is None else np.concatenate([a.ravel(), b.ravel()])
    values, counts = np.unique(used, return_counts=True)
    if np.any(counts > 1):
        raise ValueError(f"DOFs {values[counts > 1][:10].tolist()} belong to more than one pair's node: "
                         "each node in one pair")
    R = pair_frames(np.broadcast_to(np.asarray(normals, dtype=float), (n_pairs, 3))
                    if np.ndim(normals) == 1 else normals, tangents)
    if R.shape[0] != n_pairs:
        raise ValueError(f"normals: {R.shape[0]} given for {n_pairs} pairs")
    gap = _per_pair("gap", gap, n_pairs)
    mu = _per_pair("mu", mu, n_pairs)
    preload = _per_pair("preload", preload, n_pairs)
    k_n = _per_pair("normal_stiffness", normal_stiffness, n_pairs, positive=True)
    k_t = _per_pair("tangential_stiffness", tangential_stiffness, n_pairs, positive=True)

    bonded = normal == "bonded"
    K_add, K_lc, K_cc = interface_matrices(n_dof, b, R, a, k_n, k_t, bonded)
    n_new = K_cc.shape[0]
    K = sp.bmat([[model.K + K_add, K_lc], [K_lc.T, K_cc]], format="csr")
    K = (0.5 * (K + K.T)).tocsr()
    M = sp.block_diag([model.M, sp.csr_matrix((n_new, n_new))], format="csr")
    C = None if model.damping is None else sp.block_diag([model.damping, sp.csr_matrix((n_new, n_new))],
                                                         format="csr")
    first = n_dof
    dofs, gaps, sides, entries = pair_laws(first, n_pairs, bonded, gap, mu, preload, len(model.contacts))
    dofs = [c.dof for c in model.contacts] + dofs
    gaps = [c.gap for c in model.contacts] + gaps
    sides = [c.side for c in model.contacts] + sides
    amplitude_dof = model._amplitude_dof
    if amplitude_dof is None and len(model.contacts) == 1:
        amplitude_dof = model.contacts[0].dof
    if amplitude_dof is None:
        amplitude_dof = int(b[0, int(np.argmax(np.abs(R[0, 0])))])
    description = dict(model.description)
    out = Model.from_matrices(M, K, dofs, gaps, sides, description, damping=C, amplitude_dof=amplitude_dof)
    entries = [friction_args(fc) for fc in model.friction] + entries
    out = add_friction(out, entries)
    step = pair_step(first, normal, b, a, R, gap, mu, preload, k_n, k_t)
    steps = [step] + [{"name": "with_friction", "args": e} for e in entries[len(model.friction):]]
    description["transforms"] = list(description.get("transforms", [])) + steps
    return replace(out, description=description, elements=model.elements)


def interface_matrices(n_dof: int, dofs_b: np.ndarray, frames: np.ndarray, dofs_a: np.ndarray | None,
                       k_n: np.ndarray, k_t: np.ndarray, bonded: bool):
    """The stiffness the pairs add, as blocks of [[K_ss, K_sp], [K_spᵀ, K_pp]] over the
    structure's DOFs s and the pairs' slip DOFs p (module docstring): the energy
    ½ (B q − E p)ᵀ diag(k) (B q − E p), B (3 n_pairs × n_dof) the relative displacements in
    the pair frames, E picking the directions that slide (the normal too unless ``bonded``).

    Parameters
    ----------
    n_dof : int
        DOFs of the structure.
    dofs_b, dofs_a : ndarray of int (n_pairs, 3)
        The nodes' DOFs (``dofs_a`` None: the ground).
    frames : ndarray (n_pairs, 3, 3)
        :func:`pair_frames`.
    k_n, k_t : ndarray (n_pairs,)
        Interface stiffness (N/m).
    bonded : bool
        Normal spring between the nodes, no normal slip DOF.

    Returns
    -------
    K_ss (n_dof, n_dof), K_sp (n_dof, n_p), K_pp (n_p, n_p) : scipy.sparse.csr_matrix
        n_p = 2 or 3 per pair, in pair order ((s_n,) s_t1, s_t2).
    """
    n_pairs = dofs_b.shape[0]
    rows = np.repeat(np.arange(3 * n_pairs), 3)
    vals = frames.reshape(3 * n_pairs, 3).ravel()
    parts_r, parts_c, parts_v = [rows], [np.repeat(dofs_b, 3, axis=0).ravel()], [vals]
    if dofs_a is not None:
        parts_r.append(rows)
        parts_c.append(np.repeat(dofs_a, 3, axis=0).ravel())
        parts_v.append(-vals)
    B = sp.csr_matrix((np.concatenate(parts_v), (np.concatenate(parts_r), np.concatenate(parts_c))),
                      shape=(3 * n_pairs, n_dof))
    Kd = sp.diags(np.stack([k_n, k_t, k_t], axis=1).ravel(), format="csr")
    slid = np.ones(3 * n_pairs, dtype=bool)
    if bonded:
        slid[0::3] = False  # the normal spring joins the nodes directly
    n_new = int(slid.sum())
    E = sp.csr_matrix((np.ones(n_new), (np.flatnonzero(slid), np.arange(n_new))), shape=(3 * n_pairs, n_new))
    return ((B.T @ Kd @ B).tocsr(), (-(B.T @ Kd @ E)).tocsr(), (E.T @ Kd @ E).tocsr())


def pair_laws(first: int, n_pairs: int, bonded: bool, gap, mu, preload, first_contact: int = 0):
    """The laws on the pairs' slip DOFs ``first, first + 1, ...`` (module docstring):
    (contact DOFs, gaps, sides, friction entries) — the unilateral contacts (none when
    ``bonded``) as lists for :meth:`Model.from_matrices`, the friction contacts as
    :func:`~mmshbm.model.friction.friction_contact` arguments, pressed by contact
    ``first_contact + p`` (the index the pair's stop gets in the model)."""
    per = 2 if bonded else 3
    new = np.arange(first, first + per * n_pairs).reshape(n_pairs, per)
    dofs, gaps, sides, entries = [], [], [], []
    if not bonded:
        dofs, gaps, sides = new[:, 0].tolist(), [float(g) for g in gap], [-1] * n_pairs
    for p in range(n_pairs):
        for d in new[p, -2:]:
            if bonded:
                entries.append({"dof": int(d), "mu": float(mu[p]), "normal_load": float(preload[p])})
            else:
                entries.append({"dof": int(d), "mu": float(mu[p]), "normal_contact": first_contact + p,
                                "preload": float(preload[p])})
    return dofs, gaps, sides, entries


def pair_step(first, normal, dofs_b, dofs_a, frames, gap, mu, preload, k_n, k_t) -> dict:
    """The ``description["transforms"]`` record of a set of pairs (read by :func:`pair_dofs`)."""
    return {"name": "with_contact_pairs",
            "args": {"n_pairs": int(len(dofs_b)), "first_dof": int(first), "normal": normal,
                     "dofs_b": np.asarray(dofs_b).tolist(),
                     "dofs_a": None if dofs_a is None else np.asarray(dofs_a).tolist(),
                     "frames": np.asarray(frames).tolist(), "gap": list(map(float, gap)),
                     "mu": list(map(float, mu)), "preload": list(map(float, preload)),
                     "normal_stiffness": list(map(float, k_n)),
                     "tangential_stiffness": list(map(float, k_t))}}


def pair_dofs(model) -> np.ndarray:
    """The slip DOFs of the pairs of ``model`` (the last :func:`with_contact_pairs` step):
    (n_pairs, 3) (s_n, s_t1, s_t2), or (n_pairs, 2) (s_t1, s_t2) for bonded pairs.

    Raises
    ------
    ValueError
        The model has no contact pairs.
    """
    steps = [s for s in model.description.get("transforms", []) if s.get("name") == "with_contact_pairs"]
    if not steps:
        raise ValueError("the model has no contact pairs (mmshbm.model.contact_pairs.with_contact_pairs)")
    args = steps[-1]["args"]
    per = 2 if args["normal"] == "bonded" else 3
    return args["first_dof"] + np.arange(per * args["n_pairs"]).reshape(args["n_pairs"], per)


def fe_pair_dofs(fe, nodes) -> np.ndarray:
    """The (n, 3) rows of the u_x, u_y, u_z DOFs (components 1, 2, 3) of ``nodes`` (node ids
    of an FE export read by :func:`mmshbm.read_fe`, a
    :class:`~mmshbm.model.readers.fematrices.FEMatrices`): the ``dofs_a`` / ``dofs_b`` of
    :func:`with_contact_pairs`. ValueError naming a node or component the export lacks."""
    ids = np.atleast_1d(np.asarray(nodes))
    if ids.ndim != 1:
        raise ValueError(f"nodes must be a 1-D sequence of node ids, got shape {ids.shape}")
    return np.array([[fe.index(int(node), c) for c in (1, 2, 3)] for node in ids], dtype=np.int64)
