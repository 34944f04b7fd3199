"""Exact (round-off accurate) solutions of the piecewise-linear impact problem.

The structure of :class:`~mmshbm.model.Model`,

    M q'' + K q = W λ,    g_N = gap + w_c · q_c,    0 <= g_N ⊥ λ >= 0,

has massless DOFs ``c`` that follow the DOFs with mass ``l`` statically. Its motion is
piecewise linear with two phases, each a linear ODE in ``q_l`` with constant coefficients:

* **open** (λ = 0): ``q_c = -K_cc⁻¹ K_cl q_l`` and ``M_ll q_l'' + K_open q_l = 0``,
  ``K_open = K_ll - K_lc K_cc⁻¹ K_cl`` (``model.reduced_stiffness``);
* **closed** (g_N = 0): the contact DOF is held at the stop,
  ``q[contact_dof] = stop_side * gap``, the other massless DOFs are condensed statically,
  ``M_ll q_l'' + K_closed q_l = f_closed``, and λ follows from the static equation of
  the contact DOF.

Each phase is solved in closed form by its own modal decomposition (dense generalized
eigenproblem with ``M_ll``, mass-normalised modes, computed once per model):
``q_l(t) = q_static + Σ_j φ_j (α_j cos ω_j t + β_j sin ω_j t)``.

Several contacts (``model.contacts``, e.g. a clearance: two stops on one DOF) make one
phase per set J of closed contacts: their DOFs held at their stops, the other massless
DOFs condensed statically (``PiecewiseLinearSystem.phase(J)``, built when the motion
first enters it; a set that closes both stops of one DOF has no room and never occurs).
A phase has one switching function per contact, the gap of each open contact and the
force of each closed one; the phase ends at the first zero of any of them, and the next
phase toggles that contact. Everything below holds contact by contact: at fixed ``q_l``
the contact forces solve the LCP ``g = h(q_l) + G λ >= 0, λ >= 0, gᵀλ = 0`` with the free
gaps ``h_i = gap_i + a_i·q_l`` and the Delassus matrix ``G = Wᵀ K_cc⁻¹ W``; its solution
is unique and continuous in ``q_l`` (for a clearance G is singular, but the two stops of
a DOF cannot both be closed), so again nothing jumps at a switch and the saltation
matrices are the identity. Contacts that switch at the same instant (e.g. identical
uncoupled substructures) are taken one after the other with zero-length phases between.
Contact DOFs must be massless (``model.require_massless_contacts``: a ValueError names
``with_contact_layer`` and ``with_massless_contact``).

Facts this module relies on (derived here, checked in ``tests/methods/test_exact.py``)
--------------------------------------------------------------------------------------
* At fixed ``q_l`` the contact problem of the massless DOFs is a scalar LCP whose
  solution is ``λ = k_c max(0, -h(q_l))`` with the *free gap* ``h(q_l) = gap + a·q_l``
  (the gap the open condensation would give, ``a = -K_lc K_cc⁻¹ w_c``) and the condensed
  contact stiffness ``k_c = 1 / (w_cᵀ K_cc⁻¹ w_c)``. So the contact state is a function of
  ``q_l`` alone (:meth:`PiecewiseLinearSystem.state_to_full`), both switching functions
  (g_N in the open phase, λ in the closed one) vanish on the same hyperplane ``h = 0``,
  and ``K_closed = K_open + k_c a aᵀ``, ``f_closed = -k_c gap a``: the system is a
  *continuous* bilinear oscillator in ``q_l``. Its potential energy is
  ``½ q_lᵀ K_open q_l + ½ k_c min(0, h)²`` (= ½ qᵀ K q over all DOFs).
* Consequently nothing jumps at a switch: positions, velocities *and accelerations* of
  ``q_l`` are continuous (λ = 0 and g_N = 0 at the switching instant); only the third
  derivative jumps. There are no impacts and no impulses.
* Saltation matrix. For a switch at time t_e of the state z = (q_l, v_l) with vector
  fields f⁻ before and f⁺ after, ``S = I + (f⁺ - f⁻) ∇hᵀ / (∇h · f⁻)``. Here
  ``f⁺ - f⁻ = (0, -M_ll⁻¹ k_c h a) = 0`` on ``h = 0``, so **S = I**: the derivative of the
  flow with respect to the initial state is the plain product of the phases' transition
  matrices evaluated at the actual event times (``Trajectory.transition``). The flow is
  C¹ in the initial state even at grazing (only its second derivative blows up there).

Event location
--------------
In a phase the switching function is ``u(t) = u_s + Σ_j c_j (α_j cos ω_j t + β_j sin ω_j t)``
(g_N in the open phase, λ in the closed one; the phase holds while u > 0). It is sampled
on a step of ``1/samples_per_period`` of the shortest period among the modes that take
part (|c_j| |(α_j, β_j)| above 1e-15 of the signal's scale), together with its
derivative. The first sample below ``-1e-12·scale`` brackets the switch; local minima
between samples (sign change of u' from - to +, refined by brentq) catch shallow
crossings that no sample sees. A minimum that dips to within ``1e-12·scale`` of zero is a
*grazing* touch with zero contact force and does not switch (it is recorded as a
``"graze"`` event); the error of ignoring a penetration of that depth is far below
round-off of the trajectory because the vector field is continuous. The crossing is
refined by brentq to ~1e-15 relative in time. A phase that starts on the switching
surface (right after a switch) does not use the sign of u at t = 0: the left bracket of
its own switch is the first sample with u > 0 or, for a short phase, the maximum of u
located from u'.

Symmetric periodic orbits
-------------------------
The system is reversible, so a symmetric periodic orbit has all velocities zero at t = 0
and at t = T/2. :func:`periodic_orbit` solves for ``x = q_l(0)`` and ``T/2`` from
``v_l(T/2; x) = 0`` (n_l equations) and the **amplitude convention**:

    amplitude = -stop_side * q[contact_dof](0),

i.e. t = 0 is the turning point farthest from the stop, and the amplitude is the contact
DOF's excursion away from the stop there (below the gap this is the linear mode's
amplitude). For the orbits of the first-mode family this is the largest excursion away
from the stop over the period; each result also reports the measured maximum
(``max_excursion``) so that this can be checked. With several contacts the amplitude is
``model.amplitude_dof``'s value at t = 0, signed so that it is positive at the start of
the first-mode family (t = 0 is the turning point where the first contact is farthest
from its stop; ``PiecewiseLinearSystem.amplitude_row``), and ``max_excursion`` is the
measured largest |q| of that DOF: they agree on symmetric orbits (a symmetric clearance,
identical substructures), not in general (with unequal stops the other turning point may
go farther). The default guess of the half period is then the first return to zero of
the start mode's modal velocity along the exact motion; a clearance's orbits also have
the half-period antisymmetry q(t + T/2) = −q(t), which is not used. The Jacobian is exact:
``∂v_l(T/2)/∂x`` is the velocity-position block of the product of the transition
matrices (saltation = I, see above) and ``∂v_l(T/2)/∂(T/2)`` is the acceleration at T/2.
Newton converges quadratically wherever the number of switches does not change.

What the exact solutions of the beam look like
----------------------------------------------
(docs/exact.md has the numbers.) Single-contact symmetric orbits of the default beam end
within ~1e-4 (relative) of grazing (earlier for the finer tip element); beyond, orbits with
several contacts per period and internal resonances with high modes take over, strongly
unstable, and above ~1e-3 this Newton shooting does not converge from the continuation.
Always check ``converged`` and ``n_contacts``.
"""

from __future__ import annotations

from .friction import FrictionOrbit, FrictionSystem, friction_orbit
from .orbits import Backbone, PeriodicOrbit, backbone, periodic_orbit
from .phase import Phase
from .system import PiecewiseLinearSystem
from .trajectory import Event, Trajectory, integrate

__all__ = [
    "Event",
    "Phase",
    "PiecewiseLinearSystem",
    "Trajectory",
    "PeriodicOrbit",
    "Backbone",
    "integrate",
    "periodic_orbit",
    "backbone",
    "FrictionSystem",
    "FrictionOrbit",
    "friction_orbit",
]
