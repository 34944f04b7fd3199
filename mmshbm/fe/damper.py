"""A friction damper pad on the massless tip of a beam, in place of the stop.

The beam's matrices (:meth:`~mmshbm.fe.beam.TimoshenkoBeam.model`, tip DOFs massless)
without the unilateral contact, modal damping, and Coulomb friction with constant normal
load on the tip's transverse DOF (a pad pressed on the tip with normal force N, friction
coefficient μ: slip force μN). The tip node has no mass and no tangential spring: the
friction acts on the tip itself, so the node is as stiff as the beam makes it (its
stiffness with the DOFs with mass held, ρ = 1/(K_cc⁻¹)_ww, is 2.4e9 N/m on the default
beam with 21 elements) and the law is Coulomb's without regularisation.

The force of :func:`tip_damper_force` acts at the transverse DOF of the node before the
tip, which is also the amplitude DOF (it carries mass).

:func:`solid_tip_friction_model` is the solid beam (:mod:`mmshbm.fe.solid`) with impact and
friction on its tip face: each contact node's tangential DOFs pressed by its own contact
force (``normal_contact=``).
"""

from __future__ import annotations

import numpy as np

from .. import _validate as check
from ..model.model import Model

__all__ = ["tip_damper_model", "tip_damper_force", "solid_tip_friction_model"]


def tip_damper_model(beam=None, n_elements: int = 21, *, mu: float = 0.5, normal_load: float = 1.0,
                     modal_damping: float = 0.01, grading: float = 10.0, at: float | None = None) -> Model:
    """The clamped beam with a Coulomb friction damper on its massless tip.

    Parameters
    ----------
    beam : TimoshenkoBeam, optional
        Default :func:`~mmshbm.fe.beam.default_beam`.
    n_elements : int
        Elements of the beam (>= 2: the amplitude DOF is the node before the tip).
    mu : float
        Friction coefficient >= 0.
    normal_load : float
        Normal force N >= 0 (N); the slip force is μN.
    modal_damping : float
        Modal damping ratio of every linear mode of the free-tip structure (0 for none:
        friction alone then damps the response).
    grading : float
        Ratio of the root to the tip element length.
    at : float, optional
        Position of the amplitude DOF (where :func:`tip_damper_force` acts and the
        amplitude is read) as a fraction of the length, 0 < at < 1: the transverse DOF of
        the nearest node other than the tip. Default: the node before the tip.

    Returns
    -------
    Model
        DOFs ``[w1, θ1, ..., wn, θn]`` of the clamped beam, no unilateral contact,
        ``amplitude_dof`` the transverse DOF at ``at`` (default ``2n − 4``, the node before
        the tip), one friction
        contact on ``2n − 2`` (tip deflection, massless); the ``with_damping`` and
        ``with_friction`` calls recorded in ``description["transforms"]``.
    """
    from .beam import default_beam

    beam = default_beam() if beam is None else beam
    n = check.integer("n_elements", n_elements, minimum=2)
    if not (np.isfinite(modal_damping) and modal_damping >= 0):
        raise ValueError(f"modal_damping must be finite and >= 0, got {modal_damping!r}")
    stop = beam.model(n, grading)
    tip, _ = beam.tip_dofs(n)
    if at is None:
        node = n - 1
    else:
        if not (np.isfinite(at) and 0 < at < 1):
            raise ValueError(f"at must be a fraction of the length in (0, 1), got {at!r}")
        x = beam.node_coordinates(n, grading)  # root first, clamped root included
        node = int(np.clip(np.argmin(np.abs(x / x[-1] - at)), 1, n - 1))
    model = Model.from_matrices(stop.M, stop.K, [], [], [], amplitude_dof=2 * node - 2)
    if modal_damping > 0:
        model = model.with_damping(modal_ratio=modal_damping)
    return model.with_friction(tip, mu, normal_load=normal_load)


def tip_damper_force(model: Model, amplitude: float = 1.0) -> np.ndarray:
    """Force vector (n_dof,) of ``amplitude`` newtons on the amplitude DOF of ``model``
    (the node before the tip for :func:`tip_damper_model`)."""
    force = np.zeros(model.n_dof)
    force[model.amplitude_dof] = float(amplitude)
    return force


def solid_tip_friction_model(beam=None, n_length: int = 4, n_width: int = 1, n_height: int = 1, *,
                             mu: float = 0.3, preload: float = 0.0, directions: str = "x",
                             modal_damping: float = 0.01, contact: str = "face", grading: float = 10.0,
                             order: int = 2) -> Model:
    """The solid beam (:func:`~mmshbm.fe.solid.solid_beam_model`, massless tip face) with impact and friction
    on its tip face: every contact node's tangential DOFs (``directions``, u_x and/or u_y,
    the plane's tangents) carry Coulomb friction pressed by that node's own contact force,
    slip force μ (preload + λ_j(t)) (``with_friction(dof, mu, normal_contact=j, preload=)``).

    Each direction has its own scalar law (a square friction set |f_x|, |f_y| <= μN, not the
    isotropic disc |f| <= μN); with ``directions="x"`` (default) the friction acts along the
    beam, where the tip face slides as the beam bends toward the plane (u_x = −z θ).

    Parameters
    ----------
    beam : TimoshenkoBeam, optional
        Default :func:`~mmshbm.fe.beam.default_beam`.
    n_length, n_width, n_height, grading, order, contact
        Mesh and contacts (:func:`~mmshbm.fe.solid.solid_beam_model`); the defaults give a small model
        (order 2, 4 × 1 × 1 elements: 189 DOFs with mass, 27 massless, 9 contacts; first
        mode 49.7 Hz against the fine mesh's 45.8 Hz).
    mu : float
        Friction coefficient >= 0.
    preload : float
        Normal force (N) on every friction node besides its contact force, >= 0.
    directions : {"x", "y", "xy"}
        Tangential DOFs that carry friction.
    modal_damping : float
        Modal damping ratio of every mode of the open-contact structure (0: none).

    Returns
    -------
    Model
        ``contacts`` as :func:`~mmshbm.fe.solid.solid_beam_model`; ``friction`` ordered by contact, then
        direction; the transforms recorded in ``description``.
    """
    from .beam import default_beam

    beam = default_beam() if beam is None else beam
    if directions not in ("x", "y", "xy"):
        raise ValueError(f"directions must be 'x', 'y' or 'xy', got {directions!r}")
    if not (np.isfinite(modal_damping) and modal_damping >= 0):
        raise ValueError(f"modal_damping must be finite and >= 0, got {modal_damping!r}")
    from .solid import _kept_locations, solid_beam_model

    model = solid_beam_model(beam, n_length, n_width, n_height, grading, order, True, contact=contact)
    if modal_damping > 0:
        model = model.with_damping(modal_ratio=modal_damping)
    # a contact node's tangential DOFs: the DOFs at its position, by component
    loc, comp = _kept_locations(beam, model.description)
    for j, ct in enumerate(model.contacts):
        here = np.flatnonzero(np.all(np.abs(loc - loc[:, [ct.dof]]) <= 1e-9 * beam.length, axis=0))
        for d in directions:
            dof = int(here[comp[here] == "xyz".index(d)][0])
            model = model.with_friction(dof, mu, normal_contact=j, preload=preload)
    return model
