"""Models of saved results: rebuilt from their description (beam, oscillator, solid,
Euler–Bernoulli cantilever, plus the recorded transforms), or stored with their matrices
when the description cannot rebuild them."""

from __future__ import annotations

import numpy as np

__all__ = ["rebuild_model"]


def rebuild_model(description: dict, gap: float | None = None):
    """Rebuild a :class:`~mmshbm.model.Model` from its ``description``.

    The ``transforms`` the description records (a list of ``{"name": ..., "args": ...}``
    appended by the ``Model.with_*`` methods that change the structure) are applied in
    order after the base model is built.

    Parameters
    ----------
    description : dict
        ``model.description`` of a :class:`~mmshbm.fe.beam.TimoshenkoBeam` model
        (``kind = "TimoshenkoBeam"``) or of :class:`~mmshbm.fe.oscillator.OneDofOscillator`.
    gap : float, optional
        The model's gap (m) if it differs from the description's (``Model.with_gap``).

    Raises
    ------
    ValueError
        For any other kind of description (user matrices: store them in the file).
    """
    kind = description.get("kind") if isinstance(description, dict) else None
    if kind == "TimoshenkoBeam":
        from ..fe.beam import TimoshenkoBeam

        model = TimoshenkoBeam.rebuild(description)
    elif kind == "OneDofOscillator":
        from ..fe.oscillator import OneDofOscillator

        try:
            model = OneDofOscillator(*(description[k] for k in ("m", "k1", "k2", "gap"))).model()
        except KeyError as err:
            raise ValueError(f"description lacks the entry {err.args[0]!r}") from None
    elif kind == "SolidBeam":
        from ..fe.solid import rebuild_solid

        model = rebuild_solid(description)
    elif kind == "EulerBernoulliCantilever":
        from ..fe.euler_bernoulli import cantilever_model

        try:
            model = cantilever_model(*(description[k] for k in ("length", "width", "height", "E", "rho",
                                                                "n_elements")),
                                     gap=0.0 if gap is None else float(np.atleast_1d(gap)[0]))
        except KeyError as err:
            raise ValueError(f"description lacks the entry {err.args[0]!r}") from None
    else:
        raise ValueError(f"a model of kind {kind!r} cannot be rebuilt from its description "
                         "(save it with its matrices)")
    for step in description.get("transforms", []):
        try:
            model = getattr(model, step["name"])(**dict(step.get("args", {})))
        except (KeyError, AttributeError, TypeError) as err:
            raise ValueError(f"cannot replay the model transform {step!r}: {err}") from None
    if gap is not None:
        gaps = [float(g) for g in np.atleast_1d(gap)]
        if gaps != [c.gap for c in model.contacts]:
            model = model.with_gap(gaps[0] if len(gaps) == 1 else gaps)
    return model


def _model_arrays(model) -> dict:
    out = {}
    mats = [("M", model.M), ("K", model.K)] + ([("C", model.damping)] if model.damping is not None else [])
    for name, A in mats:
        A = A.tocsr()
        out.update({f"model_{name}_data": A.data, f"model_{name}_indices": A.indices,
                    f"model_{name}_indptr": A.indptr, f"model_{name}_shape": np.array(A.shape)})
    return out


def _model_from_arrays(arrays: dict, info: dict):
    import scipy.sparse as sp

    from ..model.model import Model

    mats = {}
    for name in ("M", "K", "C"):
        if f"model_{name}_data" not in arrays:
            continue
        d, i, p, shape = (arrays[f"model_{name}_{q}"] for q in ("data", "indices", "indptr", "shape"))
        mats[name] = sp.csr_matrix((d, i, p), shape=tuple(int(v) for v in shape))
    if "contacts" in info:
        dofs, gaps, sides = ((list(v) for v in zip(*info["contacts"], strict=True)) if info["contacts"]
                             else ([], [], []))
    else:
        dofs, gaps, sides = int(info["contact_dof"]), float(info["gap"]), int(info["stop_side"])
    model = Model.from_matrices(mats["M"], mats["K"], dofs, gaps, sides, dict(info.get("description", {})),
                                damping=mats.get("C"), amplitude_dof=info.get("amplitude_dof"))
    from ..model.friction import add_friction, saved_friction

    friction = [saved_friction(step) for step in model.description.get("transforms", [])
                if step.get("name") == "with_friction"]
    if friction:  # recorded by Model.with_friction; added here without recording them again
        model = add_friction(model, friction)
    return model._with_recorded_elements()  # recorded by Model.with_element
