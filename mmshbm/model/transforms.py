"""Conversions of models as FE packages export them (mass on the contact DOF) into models
MMS-HBM can run (massless contact DOFs).

Two conversions, with different physics:

* :func:`with_contact_layer` keeps the structure as it is and adds, per contact, a new
  massless node joined to the contact DOF ``t`` by a spring ``k`` (the compliance of the
  contact element); the rigid stop moves onto the new node ``c``:

      K' = [[K + k e_t e_tᵀ, −k e_t], [−k e_tᵀ, k]],     M' = [[M, 0], [0, 0]].

  While the stop is open the node follows ``t`` with the spring unloaded (it is massless
  and has no other connection), so the largest excursion away from the stop is the same at
  ``t`` and at ``c``; while it is closed the spring carries the contact force, λ = k (q_t − gap)
  for a stop on the + side. The system is the same piecewise-linear one as a penalty spring
  of stiffness ``k`` acting on ``t``; ``k → ∞`` is a rigid stop on a DOF with mass.

* :func:`with_massless_contact` zeroes the mass rows and columns of the contact node's DOFs
  (what the seed paper does with its graded mesh). The structure changes: the report says by
  how much (mass removed, shift of the lowest eigenfrequencies) as a
  :class:`~mmshbm._warnings.ModelWarning` and in ``description["massless_contact"]``.

Both record themselves in ``description["transforms"]`` (``{"name": ..., "args": ...}``,
JSON-able, with every default resolved to its value) so that
:func:`mmshbm.results.branch.rebuild_model` replays them.

Default contact-layer stiffness: ``DEFAULT_LAYER_FACTOR`` (10⁵) times the static stiffness of
the structure at the contact DOF, k_s = (e_tᵀ K⁻¹ e_t)⁻¹ (for a cantilever 3EI/L³). The layer
is a spring in series with the structure, so the backbone's distance to the rigid limit
(k → ∞, a rigid stop on the DOF with mass) falls like k_s/k: measured with MMS-HBM (H = 5) on
the 21-element cantilever of ``docs/fe_models.md``, rate 1.00 per decade, and at 10⁵ k_s at
most 6.7e-6 in frequency between grazing and the first corner (10³ k_s: 6.7e-4, 10⁴ k_s:
6.8e-5). That is far below the harmonic truncation error at any practical H, while the
contact problem stays well conditioned: continuation works up to 10⁸ k_s and fails at 10⁹ k_s.
A measured contact stiffness (:func:`mmshbm.analysis.identification.fit_contact_stiffness`)
should replace it when there is one.
"""

from __future__ import annotations

import numbers
import warnings
from dataclasses import replace

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .._warnings import ModelWarning
from .contact import Contact

__all__ = ["with_contact_layer", "with_massless_contact", "static_contact_stiffness",
           "contact_node_dofs", "DEFAULT_LAYER_FACTOR"]

#: Default contact-layer stiffness in units of the static stiffness at the contact DOF.
DEFAULT_LAYER_FACTOR = 1e5
#: Eigenfrequencies compared before and after :func:`with_massless_contact`.
_N_REPORTED_MODES = 3


def static_contact_stiffness(model) -> np.ndarray:
    """Static stiffness (N/m) of the structure at each contact DOF, contact open:
    k_s,i = (e_iᵀ K⁻¹ e_i)⁻¹ with K the full stiffness (massless DOFs included, i.e. they
    follow statically); shape (n_contacts,)."""
    dofs = np.array(model.contact_dofs)
    E = np.zeros((model.n_dof, len(dofs)))
    E[dofs, np.arange(len(dofs))] = 1.0
    X = spla.splu(sp.csc_matrix(model.K)).solve(E)
    return 1.0 / X[dofs, np.arange(len(dofs))]


def with_contact_layer(model, stiffness=None):
    """The model with a massless contact node per contact, joined to the contact DOF by a
    spring; see the module notes.

    Parameters
    ----------
    model : Model
        Every contact DOF must carry mass (a massless one needs no layer).
    stiffness : float or sequence of float, optional
        Spring stiffness k (N/m) > 0, finite: one for all contacts or one per contact.
        Default ``DEFAULT_LAYER_FACTOR`` times :func:`static_contact_stiffness`.

    Returns
    -------
    Model
        ``n_dof + n_contacts`` DOFs: the original ones in their order, then the new nodes
        (contact ``i``'s node is DOF ``n_dof + i``), with the stops (same gaps and sides) on
        them; M and the damping padded with zeros. The amplitude is still measured at the
        original contact DOF (single contact) or at the model's amplitude DOF.
        ``description["contact_layer"]`` gives nodes, attachments, stiffnesses and their ratio
        to the static stiffness.

    Raises
    ------
    ValueError, TypeError
        A non-positive, non-finite or non-numeric stiffness, the wrong number of them, or a
        contact DOF that is already massless.
    """
    if not model.contacts:
        what = (f"friction on DOFs {[fc.dof for fc in model.friction]}" if model.friction else "no contact")
        raise ValueError(f"the model has no unilateral contact ({what}): a contact layer joins a massless "
                         "node to each stop's DOF. For friction at a DOF with mass, add the friction with "
                         "its slider: model.with_friction(dof, mu, normal_load=N, tangential_stiffness=k_t)")
    massless = set(model.c.tolist())
    already = sorted({c.dof for c in model.contacts if c.dof in massless})
    if already:
        raise ValueError(f"contact DOF{'s' if len(already) > 1 else ''} {already} "
                         f"{'are' if len(already) > 1 else 'is'} already massless: a contact layer joins a "
                         "massless node to a contact DOF that carries mass (MMS-HBM runs this model as it "
                         "is)")
    n, m = model.n_dof, model.n_contacts
    k_static = static_contact_stiffness(model)
    if stiffness is None:
        k = DEFAULT_LAYER_FACTOR * k_static
    else:
        k = _stiffnesses(stiffness, m)
    t = np.array(model.contact_dofs)
    nodes = n + np.arange(m)
    rows = np.concatenate([t, t, nodes, nodes])
    cols = np.concatenate([t, nodes, t, nodes])
    vals = np.concatenate([k, -k, -k, k])
    K = sp.block_diag([model.K, sp.csr_matrix((m, m))], format="csr") + \
        sp.csr_matrix((vals, (rows, cols)), shape=(n + m, n + m))
    M = sp.block_diag([model.M, sp.csr_matrix((m, m))], format="csr")
    C = None if model.damping is None else sp.block_diag([model.damping, sp.csr_matrix((m, m))], format="csr")
    contacts = tuple(Contact(int(node), c.gap, c.side) for node, c in zip(nodes, model.contacts, strict=True))
    amplitude_dof = model._amplitude_dof
    if amplitude_dof is None and m == 1:
        amplitude_dof = int(t[0])
    args = {"stiffness": float(k[0]) if np.all(k == k[0]) else [float(x) for x in k]}
    description = _with_transform(model.description, "with_contact_layer", args)
    description["contact_layer"] = {
        "nodes": nodes.tolist(), "attached_to": t.tolist(), "stiffness": k.tolist(),
        "static_stiffness": k_static.tolist(), "factor": (k / k_static).tolist(),
        "default": stiffness is None}
    return _build(model, M, K, contacts, description, C, amplitude_dof)


def with_massless_contact(model, dofs=None):
    """The model with the mass rows and columns of ``dofs`` zeroed, and a report of what
    that changed.

    Parameters
    ----------
    model : Model
    dofs : sequence of int, optional
        DOFs whose mass is removed. Default: :func:`contact_node_dofs` (every DOF of the
        contact node when the description names them, e.g. the tip deflection and rotation
        of a beam, else the contact DOFs).

    Returns
    -------
    Model
        Same DOFs, contacts and amplitude DOF; damping rows and columns of ``dofs`` are
        zeroed too (a massless DOF is static). ``description["massless_contact"]`` holds the
        report (also issued as a :class:`~mmshbm._warnings.ModelWarning`): ``dofs``,
        ``mass_removed`` and ``mass_total`` (kg, by ``mass_measure``), ``mass_fraction``,
        ``frequencies_before`` / ``frequencies_after`` (Hz, the lowest three) and
        ``relative_shift``.

    Raises
    ------
    ValueError, TypeError
        A DOF named twice, out of range or not an integer, an empty list, DOFs that are all
        massless already, or a result MMS-HBM cannot use (e.g. no DOF with mass left).

    Notes
    -----
    ``mass_measure`` is ``"rigid-body translation"`` when the description names the
    translational DOFs along the contact direction (beam models): the mass is uᵀ M u with
    u = 1 on them (for a clamped beam that is the mass of the beam less the share of the
    clamped node), the removed mass uᵀ ΔM u. Otherwise it is ``"trace"``: Σ ΔM_ii / Σ M_ii
    over all DOFs (it mixes kg and kg·m² when rotations carry mass).
    """
    n = model.n_dof
    dofs = contact_node_dofs(model) if dofs is None else _dof_list(dofs, n)
    massless = set(model.c.tolist())
    if all(d in massless for d in dofs):
        raise ValueError(f"dofs {dofs} are massless already: there is no mass to remove")
    keep = np.ones(n)
    keep[dofs] = 0.0
    D = sp.diags(keep, format="csr")
    M = (D @ model.M @ D).tocsr()
    M.eliminate_zeros()
    C = model.damping
    damping_removed = False
    if C is not None:
        C2 = (D @ C @ D).tocsr()
        C2.eliminate_zeros()
        damping_removed = (C2 != C).nnz > 0
        C = C2
    report = _mass_report(model, M, dofs)
    report["damping_removed"] = bool(damping_removed)
    description = _with_transform(model.description, "with_massless_contact", {"dofs": list(dofs)})
    new = _build(model, M, model.K, model.contacts, description, C, model._amplitude_dof)
    f0 = np.asarray(report["frequencies_before"])
    f1 = new.linear_frequencies(len(f0))
    report["frequencies_after"] = f1.tolist()
    report["relative_shift"] = (f1 / f0 - 1.0).tolist()
    new.description["massless_contact"] = report
    shifts = ", ".join(f"f{i + 1} {a:.5g} -> {b:.5g} Hz ({100 * (b / a - 1):+.2f} %)"
                       for i, (a, b) in enumerate(zip(f0, f1, strict=True)))
    warnings.warn(
        f"with_massless_contact removed the mass of DOFs {list(dofs)}: {report['mass_removed']:.4g} of "
        f"{report['mass_total']:.4g} ({100 * report['mass_fraction']:.2f} %, "
        f"{report['mass_measure']} measure)"
        f"{' and their damping' if damping_removed else ''}; {shifts}", ModelWarning, stacklevel=3)
    return new


def contact_node_dofs(model) -> list:
    """The DOFs of the contact node(s) as the model describes them: the tip deflection and
    rotation of a :class:`~mmshbm.fe.beam.TimoshenkoBeam` model (``kind`` and
    ``n_elements`` in the description), a description's ``contact_node_dofs`` list, or
    else the distinct contact DOFs."""
    d = model.description
    if d.get("kind") == "TimoshenkoBeam" and model.n_dof == 2 * int(d.get("n_elements", -1)):
        n_el = int(d["n_elements"])
        return [2 * n_el - 2, 2 * n_el - 1]  # TimoshenkoBeam.tip_dofs (clamped root)
    if "contact_node_dofs" in d:
        return _dof_list(d["contact_node_dofs"], model.n_dof)
    return sorted(set(model.contact_dofs))


# ---------------------------------------------------------------------- helpers
def _stiffnesses(stiffness, m: int) -> np.ndarray:
    values = list(np.ravel(stiffness)) if isinstance(stiffness, list | tuple | np.ndarray) else [stiffness]
    if len(values) not in (1, m):
        raise ValueError(f"stiffness must be one number or one per contact ({m}), got {len(values)}: "
                         f"{stiffness!r}")
    out = []
    for i, v in enumerate(values):
        where = f"[{i}]" if len(values) > 1 else ""
        if isinstance(v, bool) or not isinstance(v, numbers.Real):
            raise TypeError(f"stiffness{where} must be a real number (N/m), got {type(v).__name__} {v!r}")
        x = float(v)
        if not np.isfinite(x) or x <= 0:
            raise ValueError(f"stiffness{where} must be positive and finite (N/m), got {v!r}")
        out.append(x)
    return np.array(out * m if len(out) == 1 else out)


def _dof_list(dofs, n: int) -> list:
    if isinstance(dofs, numbers.Integral) and not isinstance(dofs, bool):
        dofs = [dofs]
    try:
        items = list(dofs)
    except TypeError:
        raise TypeError(f"dofs must be a sequence of DOF indices, got {type(dofs).__name__} "
                        f"{dofs!r}") from None
    if not items:
        raise ValueError("dofs is empty: name at least one DOF")
    out = []
    for i, d in enumerate(items):
        if isinstance(d, bool) or not isinstance(d, numbers.Integral):
            raise TypeError(f"dofs[{i}] must be an integer, got {type(d).__name__} {d!r}")
        d = int(d)
        if not 0 <= d < n:
            raise ValueError(f"dofs[{i}] = {d} is out of range [0, {n - 1}]")
        if d in out:
            raise ValueError(f"dofs names DOF {d} twice (dofs[{out.index(d)}] and dofs[{i}])")
        out.append(d)
    return out


def _translation_dofs(model) -> list | None:
    d = model.description
    if "translation_dofs" in d:
        return [int(i) for i in d["translation_dofs"]]
    if d.get("kind") == "TimoshenkoBeam" and "n_elements" in d:
        return list(range(0, 2 * int(d["n_elements"]), 2))  # [w1, θ1, w2, θ2, ...]
    return None


def _mass_report(model, M_new, dofs) -> dict:
    dM = (model.M - M_new).tocsr()
    trans = _translation_dofs(model)
    if trans is not None:
        u = np.zeros(model.n_dof)
        u[trans] = 1.0
        total, removed, measure = float(u @ (model.M @ u)), float(u @ (dM @ u)), "rigid-body translation"
    else:
        total, removed, measure = float(model.M.diagonal().sum()), float(dM.diagonal().sum()), "trace"
    n_modes = min(_N_REPORTED_MODES, len(model.l) - len(set(dofs) - set(model.c.tolist())))
    return {"dofs": list(dofs), "mass_measure": measure, "mass_total": total, "mass_removed": removed,
            "mass_fraction": removed / total if total > 0 else float("nan"),
            "frequencies_before": model.linear_frequencies(max(n_modes, 1)).tolist()}


def _with_transform(description: dict, name: str, args: dict) -> dict:
    out = dict(description)
    out["transforms"] = list(description.get("transforms", [])) + [{"name": name, "args": args}]
    return out


def _build(model, M, K, contacts, description, damping, amplitude_dof):
    """A validated Model (the partition checks of Model.from_matrices) of the same class."""
    cls = type(model)
    dofs = [c.dof for c in contacts]
    gaps = [c.gap for c in contacts]
    sides = [c.side for c in contacts]
    one = len(contacts) == 1
    new = cls.from_matrices(M, K, dofs[0] if one else dofs, gaps[0] if one else gaps,
                            sides[0] if one else sides, description, damping=damping,
                            amplitude_dof=amplitude_dof)
    if model.friction:  # the transforms keep the DOF numbers: the friction contacts carry over
        from .friction import add_friction, friction_args

        new = add_friction(new, [friction_args(fc) for fc in model.friction])
    if model.elements:  # so do the elements
        new = replace(new, elements=model.elements)
    return new
