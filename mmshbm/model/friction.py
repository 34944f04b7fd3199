"""Coulomb friction contacts of a model: a massless DOF, a friction coefficient and the
normal force that presses the contact.

A :class:`FrictionContact` puts dry friction on the massless DOF ``dof`` (a tangential
direction of a contact node): with slip force s(t) = μ N(t) >= 0 the support's force on
the node is −f with f ∈ s·Sign(u̇), u = q[dof] (:mod:`mmshbm.contact.coulomb`). The
normal force is either a constant ``normal_load`` N (newtons: a damper pad pressed by a
spring or a bolt) or, with ``normal_contact = j``, ``preload`` plus the contact force
λ_j(t) of the model's unilateral contact j (impact with friction).

The friction DOF must be massless, as the unilateral contact DOFs: its equation is then
static and the law holds pointwise in time. FE exports carry mass on the contact node;
give it a massless slider joined by a tangential spring k_t (a Jenkins element: the
spring is physical compliance, k_t → ∞ the rigid contact) or remove the node's mass
(``Model.with_massless_contact``), and say which.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .. import _validate as check

__all__ = ["FrictionContact", "with_friction", "add_friction", "saved_friction", "friction_contact",
           "friction_args",
           "friction_to_json",
           "friction_from_json", "no_contacts"]


@dataclass(frozen=True)
class FrictionContact:
    """Coulomb friction on one massless DOF.

    Attributes
    ----------
    dof : int
        The massless DOF that slides (m, the tangential displacement).
    mu : float
        Friction coefficient μ >= 0.
    normal_load : float or None
        Constant normal force N >= 0 (N); None when coupled to a unilateral contact.
    normal_contact : int or None
        Index j into ``model.contacts`` whose force λ_j(t) presses the contact; None for
        a constant load.
    preload : float
        Normal force (N) added to λ_j(t) (coupled contacts only; 0 otherwise).
    """

    dof: int
    mu: float
    normal_load: float | None = None
    normal_contact: int | None = None
    preload: float = 0.0

    @property
    def slip_force(self) -> float:
        """s = μN (N) of a constant normal load (ValueError for a coupled contact)."""
        if self.normal_load is None:
            raise ValueError(f"the friction contact on DOF {self.dof} is coupled to contact "
                             f"{self.normal_contact}: its slip force varies in time")
        return self.mu * self.normal_load


def with_friction(model, dof, mu, normal_load=None, normal_contact=None, preload=None,
                  tangential_stiffness=None):
    """``model`` with Coulomb friction added (a new Model; the call recorded in
    ``description["transforms"]``).

    Parameters
    ----------
    dof : int
        The tangential displacement of a contact node. Without ``tangential_stiffness`` it
        must be massless (the friction acts on it, rigid Coulomb); with it, any DOF.
    mu : float
        Friction coefficient >= 0.
    normal_load : float, optional
        Constant normal force N >= 0 (N): slip force μN.
    normal_contact : int, optional
        Index of the unilateral contact whose force λ_j(t) (plus ``preload``, N) is the
        normal force. Exactly one of ``normal_load`` and ``normal_contact``.
    tangential_stiffness : float, optional
        k_t > 0 (N/m, finite): a massless slider node is appended (DOF ``n_dof``), joined to
        ``dof`` by a spring k_t, and the friction acts on the slider (a Jenkins element: the
        spring is the contact's tangential compliance). None (default): no spring, the
        friction on ``dof`` itself, which must then be massless.

    Raises
    ------
    ValueError, TypeError
        Naming the offending input (:func:`friction_contact`); a ``dof`` with mass without
        ``tangential_stiffness``.
    """
    from dataclasses import replace

    args = {"dof": dof, "mu": mu}
    given = {"normal_load": normal_load, "normal_contact": normal_contact, "preload": preload}
    args.update({k: v for k, v in given.items() if v is not None})
    step = {"name": "with_friction"}
    if tangential_stiffness is None:
        out = add_friction(model, [args])
    else:
        k_t = check.positive("tangential_stiffness", tangential_stiffness)
        d = check.integer("dof", dof)
        if not 0 <= d < model.n_dof:
            raise ValueError(f"dof must be in [0, {model.n_dof - 1}], got {d}")
        slider_model, slider = with_slider(model, d, k_t)
        out = add_friction(slider_model, [dict(args, dof=slider)])
        args["tangential_stiffness"] = k_t
        step["slider"] = slider  # where the friction acts: the models saved with their matrices
    description = dict(model.description)
    step["args"] = {k: (v.item() if isinstance(v, np.generic) else v) for k, v in args.items()}
    description["transforms"] = list(description.get("transforms", [])) + [step]
    return replace(out, description=description)


def with_slider(model, dof: int, stiffness: float):
    """The model with a new massless DOF (the last, index ``n_dof``) joined to ``dof`` by a
    spring of ``stiffness`` (N/m): K' = [[K + k e_d e_dᵀ, −k e_d], [−k e_dᵀ, k]], M and the
    damping padded with zeros; contacts, friction contacts and the amplitude DOF kept (the
    amplitude DOF defaults to ``dof`` when the model has no contact and names none).
    Nothing recorded in the description. Returns (Model, index of the new DOF)."""
    import scipy.sparse as sp

    n = model.n_dof
    k = float(stiffness)
    K = sp.block_diag([model.K, sp.csr_matrix((1, 1))], format="csr") + \
        sp.csr_matrix(([k, -k, -k, k], ([dof, dof, n, n], [dof, n, dof, n])), shape=(n + 1, n + 1))
    M = sp.block_diag([model.M, sp.csr_matrix((1, 1))], format="csr")
    C = None if model.damping is None else sp.block_diag([model.damping, sp.csr_matrix((1, 1))], format="csr")
    amplitude_dof = model._amplitude_dof
    if amplitude_dof is None and not model.contacts:
        amplitude_dof = int(dof)
    dofs, gaps, sides = ([c.dof for c in model.contacts], [c.gap for c in model.contacts],
                         [c.side for c in model.contacts])
    if len(dofs) == 1:
        dofs, gaps, sides = dofs[0], gaps[0], sides[0]
    new = type(model).from_matrices(M, K, dofs, gaps, sides, dict(model.description), damping=C,
                                    amplitude_dof=amplitude_dof)
    return add_friction(new, [friction_args(fc) for fc in model.friction]), n


def saved_friction(step: dict) -> dict:
    """The :func:`friction_contact` arguments of a recorded ``with_friction`` step applied to
    the matrices it produced (a slider's friction acts on the slider, ``step["slider"]``)."""
    kw = dict(step.get("args", {}))
    if "tangential_stiffness" in kw:
        kw.pop("tangential_stiffness")
        kw["dof"] = step["slider"]
    return kw


def add_friction(model, entries):
    """``model`` with the friction contacts of ``entries`` (dicts of :func:`friction_contact`
    arguments) added, nothing recorded (loading a saved model)."""
    from dataclasses import replace

    for kw in entries:
        model = replace(model, friction=model.friction + (friction_contact(model, **kw),))
    return model


def friction_contact(model, dof, mu, normal_load=None, normal_contact=None, preload=None) -> FrictionContact:
    """Validate the arguments of :meth:`Model.with_friction` against ``model``.

    Raises
    ------
    ValueError, TypeError
        Naming the offending input: a DOF out of range, with mass, already carrying
        friction or a unilateral contact; μ < 0; N < 0; both or neither of
        ``normal_load`` and ``normal_contact``; a contact index out of range; a negative
        preload, or a preload with a constant load.
    """
    dof = check.integer("dof", dof)
    if not 0 <= dof < model.n_dof:
        raise ValueError(f"dof must be in [0, {model.n_dof - 1}], got {dof}")
    if dof not in set(model.c.tolist()):
        raise ValueError(
            f"dof {dof} carries mass, but rigid Coulomb friction needs a massless DOF (its equation is "
            "static): give the contact's tangential stiffness, model.with_friction(dof, mu, ..., "
            "tangential_stiffness=k_t), which joins a massless slider to it by that spring (a Jenkins "
            "element), or remove its mass (model.with_massless_contact([...]))")
    if any(fc.dof == dof for fc in model.friction):
        raise ValueError(f"dof {dof} already carries a friction contact: one per DOF")
    if any(ct.dof == dof for ct in model.contacts):
        raise ValueError(f"dof {dof} carries a unilateral contact: friction acts on a tangential DOF, "
                         "another DOF of the contact node")
    mu = check.non_negative("mu", mu)
    if (normal_load is None) == (normal_contact is None):
        raise ValueError("give exactly one of normal_load= (a constant normal force, N) and normal_contact= "
                         "(the index of the unilateral contact whose force presses the friction contact)")
    if normal_load is not None:
        if preload is not None:
            raise ValueError("preload= goes with normal_contact=; with a constant load put it in normal_load")
        return FrictionContact(dof, mu, check.non_negative("normal_load", normal_load), None, 0.0)
    j = check.integer("normal_contact", normal_contact)
    if not 0 <= j < len(model.contacts):
        raise ValueError(f"normal_contact must index one of the model's {len(model.contacts)} unilateral "
                         f"contacts, got {j}")
    pre = 0.0 if preload is None else check.non_negative("preload", preload)
    return FrictionContact(dof, mu, None, j, pre)


def friction_args(fc: FrictionContact) -> dict:
    """Keyword arguments of :func:`friction_contact` that rebuild ``fc``."""
    if fc.normal_contact is None:
        return {"dof": fc.dof, "mu": fc.mu, "normal_load": fc.normal_load}
    return {"dof": fc.dof, "mu": fc.mu, "normal_contact": fc.normal_contact, "preload": fc.preload}


def friction_to_json(friction: Sequence[FrictionContact]) -> str:
    """JSON text of the friction contacts (``friction_from_json`` inverts it)."""
    import json

    return json.dumps([{"dof": fc.dof, "mu": fc.mu, "normal_load": fc.normal_load,
                        "normal_contact": fc.normal_contact, "preload": fc.preload} for fc in friction])


def friction_from_json(text) -> list[dict]:
    """Keyword arguments of :meth:`Model.with_friction`, one dict per friction contact."""
    import json

    entries = json.loads(str(text))
    if not isinstance(entries, list) or not all(isinstance(e, dict) for e in entries):
        raise ValueError(f"'friction' must be a JSON list of objects, got {text!r}")
    out = []
    for e in entries:
        kw = {"dof": e.get("dof"), "mu": e.get("mu")}
        if e.get("normal_contact") is None:
            kw["normal_load"] = e.get("normal_load")
        else:
            kw["normal_contact"], kw["preload"] = e["normal_contact"], e.get("preload", 0.0)
        out.append(kw)
    return out


def no_contacts(contact_dof, gap, stop_side) -> bool:
    """True when ``contact_dof`` is an empty sequence (a model without unilateral contacts);
    ``gap`` must then be an empty sequence (a gap of no stop is a mistake) and ``stop_side``
    an empty sequence or its scalar default."""
    if isinstance(contact_dof, str | bytes) or np.ndim(contact_dof) != 1 or len(contact_dof) != 0:
        return False
    if np.ndim(gap) != 1:
        raise ValueError(f"contact_dof is empty but gap is {gap!r}: a model without stops takes gap=[]")
    for name, value in (("gap", gap), ("stop_side", stop_side)):
        if np.ndim(value) == 1 and len(value) != 0:
            raise ValueError(f"contact_dof is empty but {name} has {len(value)} entries: give none")
    return True
