"""Floquet multipliers of periodic orbits with Coulomb friction at massless DOFs (constant
normal loads, no unilateral contact).

The flow of the DOFs with mass is piecewise linear: in a phase where the friction nodes of
the set S stick (held at their stuck positions u_S) and the others slip (their force ±s,
constant), the massless DOFs f = c \\ S follow statically and a perturbation obeys

    M δq'' + C δq' + K_S δq + B_S δu_S = 0,    K_S = K_ll − K_lf K_ff⁻¹ K_fl,
    B_S = K_lS − K_lf K_ff⁻¹ K_fS,

with δu_S constant while S holds. The stuck positions are states: the augmented state
X = (δq, δq', δu) (2 n_l + m, m friction nodes) evolves by exp(A_S Δt) in a phase, δu_j of
a slipping node playing no part (its column of B is zero; it is set to 0). At a stick-to-slip switch the
force is continuous (|F_t| reaches s), at a slip-to-stick switch too (the node stops where
it is), so the vector field is continuous and (δq, δq') pass unchanged; the new stuck
position is the node's static position at the switch, δu_j = −[K_ff⁻¹ (K_fl δq + K_fS δu_S)]_j
(its dependence on the switch instant vanishes: the node's velocity is zero there). The
monodromy is the ordered product of the phase exponentials and these resets, its
eigenvalues the multipliers; those of the stuck positions are 0 for a node that slips in
the period (its position is forgotten) and 1 for one that sticks throughout (history).

A phase's generator depends on its state only (which nodes stick or slip, which contacts
are closed), not on the orbit: :class:`PhaseExponentials` eigendecomposes each state's
generator once, A = V Λ V⁻¹, and every phase of that state on every orbit of a branch costs
exp(A Δt) = V e^{ΛΔt} V⁻¹ (two products instead of a Padé approximant with squarings); a
generator whose eigenvectors are ill-conditioned (a defective one: a free rigid-body motion)
is exponentiated by ``scipy.linalg.expm`` instead.

The phases are taken from the converged harmonic-balance orbit: the stick and slip pieces
of the play projection (:func:`mmshbm.contact.coulomb.play_pieces`) of every node. The
multipliers are those of the exact flow linearised about the approximate orbit.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as la

__all__ = ["FrictionFloquet", "ImpactFrictionFloquet", "PhaseExponentials", "merge_phases"]

#: condition number of a generator's eigenvector matrix above which its exponential is taken
#: by ``scipy.linalg.expm``: V e^{ΛΔt} V⁻¹ is accurate to about κ(V)·ε relative, expm to
#: about ε·‖AΔt‖, so up to this limit the two agree to ~1e-12 of ‖e^{AΔt}‖
EIGEN_CONDITION_LIMIT = 1e4


class PhaseExponentials:
    """exp(A Δt) of the generators of a Floquet solver, by state: each generator ``A``
    ((k, k) real) is eigendecomposed once (the first time its ``key`` is asked) and then
    exponentiated for any Δt by V e^{ΛΔt} V⁻¹; one whose eigenvector matrix has a condition
    number above ``condition_limit`` by :func:`scipy.linalg.expm`."""

    def __init__(self, condition_limit: float = EIGEN_CONDITION_LIMIT):
        self.condition_limit = float(condition_limit)
        self._eig = {}

    def __call__(self, key, A: np.ndarray, dt: float) -> np.ndarray:
        """exp(A dt) (k, k) of the generator ``A`` of state ``key`` over ``dt`` (s)."""
        hit = self._eig.get(key)
        if hit is None:
            hit = self._eig[key] = self._decompose(A)
        if hit is False:
            return la.expm(A * dt)
        lam, V, Vinv = hit
        return ((V * np.exp(lam * dt)) @ Vinv).real

    def _decompose(self, A: np.ndarray):
        lam, V = la.eig(A)
        if not np.all(np.isfinite(lam)) or np.linalg.cond(V) > self.condition_limit:
            return False
        return lam, V, np.linalg.inv(V)


class FrictionFloquet:
    """Monodromy of orbits with friction of a :class:`~mmshbm.model.Model` (dense; small
    models).

    Parameters
    ----------
    model : Model
        Friction contacts with constant normal loads, no unilateral contact.
    """

    def __init__(self, model):
        if model.contacts or any(fc.normal_contact is not None for fc in model.friction):
            raise NotImplementedError("Floquet multipliers with friction are available for friction "
                                      "contacts with constant normal loads and no unilateral contact")
        b = model.blocks
        self.M = b["M_ll"].toarray()
        self.C = b["C_ll"].toarray() if b["C_ll"] is not None else np.zeros_like(self.M)
        self.K_ll = b["K_ll"].toarray()
        self.K_lc = np.asarray(b["K_lc"].toarray() if hasattr(b["K_lc"], "toarray") else b["K_lc"])
        self.K_cc = np.asarray(b["K_cc"].toarray() if hasattr(b["K_cc"], "toarray") else b["K_cc"])
        self.rows = np.searchsorted(model.c, [fc.dof for fc in model.friction])
        self.n, self.m, self.n_c = self.M.shape[0], len(self.rows), self.K_cc.shape[0]
        self.Minv = np.linalg.inv(self.M)
        self._phase = {}
        self._resets = {}
        self.exponential = PhaseExponentials()

    def _split(self, stuck: frozenset):
        held = [int(self.rows[j]) for j in sorted(stuck)]
        free = np.array([i for i in range(self.n_c) if i not in held], dtype=int)
        return np.array(held, dtype=int), free

    def generator(self, stuck: frozenset) -> np.ndarray:
        """A_S (2n + m, 2n + m) of the phase where the friction nodes ``stuck`` stick."""
        A = self._phase.get(stuck)
        if A is not None:
            return A
        n, m = self.n, self.m
        held, free = self._split(stuck)
        K, B = self.K_ll.copy(), np.zeros((n, m))
        Kff_lf = la.solve(self.K_cc[np.ix_(free, free)], self.K_lc[:, free].T) if len(free) else None
        if len(free):
            K -= self.K_lc[:, free] @ Kff_lf
        for col, j in zip(held, sorted(stuck), strict=True):
            B[:, j] = self.K_lc[:, col]
            if len(free):
                B[:, j] -= Kff_lf.T @ self.K_cc[free, col]
        A = np.zeros((2 * n + m, 2 * n + m))
        A[:n, n:2 * n] = np.eye(n)
        A[n:2 * n, :n] = -self.Minv @ K
        A[n:2 * n, n:2 * n] = -self.Minv @ self.C
        A[n:2 * n, 2 * n:] = -self.Minv @ B
        self._phase[stuck] = A
        return A

    def reset(self, stuck: frozenset, j: int) -> np.ndarray:
        """The map (2n + m square) at the instant node j starts sticking in phase ``stuck``:
        δu_j := its static position −[K_ff⁻¹ (K_fl δq + K_fS δu_S)]_j (computed once per
        (stuck, j): it depends on the state only)."""
        E = self._resets.get((stuck, j))
        if E is None:
            E = self._resets[(stuck, j)] = self._reset(stuck, j)
        return E

    def _reset(self, stuck: frozenset, j: int) -> np.ndarray:
        n = self.n
        held, free = self._split(stuck)
        E = np.eye(2 * n + self.m)
        E[2 * n + j] = 0.0
        k = int(np.flatnonzero(free == self.rows[j])[0])
        row = la.solve(self.K_cc[np.ix_(free, free)], np.eye(len(free))[k])  # (K_ff⁻¹)_k·
        E[2 * n + j, :n] = -row @ self.K_lc[:, free].T
        for col, i in zip(held, sorted(stuck), strict=True):
            E[2 * n + j, 2 * n + i] = -row @ self.K_cc[free, col]
        return E

    def monodromy(self, stick_arcs: list, omega: float) -> np.ndarray:
        """Φ(T) (2n + m square) for the stick arcs of every node, ``stick_arcs[j]`` a list of
        (τ_a, τ_b) with τ in radians (any start; taken modulo 2π), at Ω (rad/s)."""
        arcs = [[(a % (2 * np.pi), (a % (2 * np.pi)) + (b - a)) for a, b in node] for node in stick_arcs]
        events = {0.0, 2 * np.pi}
        for node in arcs:
            for a, b in node:
                for t in (a, b):
                    events.add(t % (2 * np.pi))
        grid = np.array(sorted(events))

        def stuck_at(j, t):
            return any(a <= t < b or a <= t + 2 * np.pi < b for a, b in arcs[j])

        Phi = np.eye(2 * self.n + self.m)
        prev = None
        for a, b in zip(grid[:-1], grid[1:], strict=True):
            if b - a <= 0:
                continue
            mid = 0.5 * (a + b)
            S = frozenset(j for j in range(self.m) if stuck_at(j, mid))
            if prev is not None:
                for j in sorted(S - prev):  # nodes that start sticking at τ = a
                    Phi = self.reset(prev, j) @ Phi
                    prev = prev | {j}
            Phi = self.exponential(S, self.generator(S), (b - a) / omega) @ Phi
            for j in set(range(self.m)) - S:  # a slipping node's stuck position is no state
                Phi[2 * self.n + j] = 0.0
            prev = S
        # close the period: nodes stuck at τ = 0 that slipped just before it
        S0 = frozenset(j for j in range(self.m) if stuck_at(j, 0.0))
        for j in sorted(S0 - prev):
            Phi = self.reset(prev, j) @ Phi
            prev = prev | {j}
        return Phi

    def multipliers(self, stick_arcs: list, omega: float) -> np.ndarray:
        """Eigenvalues of :meth:`monodromy`, sorted by decreasing modulus."""
        mu = la.eigvals(self.monodromy(stick_arcs, omega))
        return mu[np.argsort(-np.abs(mu), kind="stable")]


def _dense(a) -> np.ndarray:
    return np.asarray(a.toarray() if hasattr(a, "toarray") else a)


def merge_phases(normal: list, pieces: list) -> list:
    """Phases (τ_a, τ_b, closed, tang) over [0, 2π) from the unilateral contacts' phases
    ``normal`` [(τ_a, τ_b, {(j, side), ...}), ...] (:meth:`FloquetSolver.phases`) and every
    friction node's pieces ``pieces[j]`` [(τ_a, τ_b, σ), ...] (σ = 0 stick, ±1 slip; any
    start, taken modulo 2π); consecutive intervals with the same state merged."""
    two_pi = 2 * np.pi
    events = {0.0, two_pi}
    for a, b, _ in normal:
        events.update((a % two_pi, b % two_pi))
    for node in pieces:
        for a, b, _ in node:
            events.update((a % two_pi, b % two_pi))
    grid = sorted(events)

    def at(intervals, t):
        for a, b, v in intervals:
            a0 = a % two_pi
            if a0 <= t < a0 + (b - a) or a0 <= t + two_pi < a0 + (b - a):
                return v
        raise RuntimeError(f"no phase covers τ = {t}")

    out = []
    for a, b in zip(grid[:-1], grid[1:], strict=True):
        if b - a <= 1e-15:
            continue
        t = 0.5 * (a + b)
        key = (frozenset(j for j, _ in at(normal, t)), tuple(int(at(node, t)) for node in pieces))
        if out and (out[-1][2], out[-1][3]) == key:
            out[-1] = (out[-1][0], b) + key
        else:
            out.append((a, b) + key)
    return out


class ImpactFrictionFloquet:
    """Monodromy of orbits with unilateral contacts and friction (constant or coupled loads)
    of a :class:`~mmshbm.model.Model` (dense; small models).

    In a phase the state of every massless DOF fixes one linear condition on its
    perturbation (δq_i, δF_i), F the force the structure needs there: a free DOF
    δF_i = 0, a closed stop δq_i = 0, a stuck friction node δq_t = δu_j, a slipping one
    δF_t = −σ μ δλ_k with δλ_k = −side_k δF_n when it is pressed by the closed contact k
    (0 otherwise). With K_cl δq + K_cc δq_c = δF these give δq_c = L_q δq + L_u δu and
    M δq'' + C δq' + (K_ll + K_lc L_q) δq + K_lc L_u δu = 0. The vector field is continuous
    at every switch (a closing contact's force and an opening one's gap vanish, the friction
    force is continuous), so the saltation matrices are the identity; a node that starts to
    stick takes its static position, δu_j = (L_q δq + L_u δu)_t of the phase before.
    """

    def __init__(self, model):
        b = model.blocks
        self.M = b["M_ll"].toarray()
        self.C = b["C_ll"].toarray() if b["C_ll"] is not None else np.zeros_like(self.M)
        self.K_ll, self.K_lc, self.K_cc = b["K_ll"].toarray(), _dense(b["K_lc"]), _dense(b["K_cc"])
        c = model.c
        self.t_rows = np.searchsorted(c, [fc.dof for fc in model.friction])
        self.n_rows = np.searchsorted(c, [ct.dof for ct in model.contacts])
        self.sides = [int(ct.side) for ct in model.contacts]
        self.friction = model.friction
        self.n, self.m, self.n_c = self.M.shape[0], len(self.t_rows), self.K_cc.shape[0]
        self.Minv = np.linalg.inv(self.M)
        self._cache = {}
        self._generators = {}
        self.exponential = PhaseExponentials()

    def _maps(self, closed: frozenset, tang: tuple):
        """(L_q (n_c, n), L_u (n_c, m)) of the phase: contacts ``closed`` (indices), friction
        node j stuck (tang[j] = 0) or slipping in direction tang[j] = ±1."""
        key = (closed, tang)
        hit = self._cache.get(key)
        if hit is not None:
            return hit
        n_c, n, m = self.n_c, self.n, self.m
        A = np.zeros((2 * n_c, 2 * n_c))
        A[:n_c, :n_c], A[:n_c, n_c:] = self.K_cc, -np.eye(n_c)
        Bq, Bu = np.zeros((2 * n_c, n)), np.zeros((2 * n_c, m))
        Bq[:n_c] = -self.K_lc.T
        rows = {}
        for k in closed:
            rows[int(self.n_rows[k])] = ("held",)
        for j in range(m):
            rows[int(self.t_rows[j])] = ("stuck", j) if tang[j] == 0 else ("slip", j)
        for i in range(n_c):
            r = n_c + i
            kind = rows.get(i, ("free",))
            if kind[0] == "held":
                A[r, i] = 1.0
            elif kind[0] == "stuck":
                A[r, i], Bu[r, kind[1]] = 1.0, 1.0
            else:
                A[r, n_c + i] = 1.0
                if kind[0] == "slip":
                    fc = self.friction[kind[1]]
                    k = fc.normal_contact
                    if k is not None and k in closed:
                        # δF_t = −σ μ δλ, δλ = −side δF_n
                        A[r, n_c + int(self.n_rows[k])] = -tang[kind[1]] * fc.mu * self.sides[k]
        L = np.linalg.solve(A, np.hstack([Bq, Bu]))
        out = (L[:n_c, :n], L[:n_c, n:])
        self._cache[key] = out
        return out

    def generator(self, closed: frozenset, tang: tuple) -> np.ndarray:
        """G (2n + m, 2n + m) of the phase with contacts ``closed`` and friction states ``tang``."""
        G = self._generators.get((closed, tang))
        if G is None:
            G = self._generators[(closed, tang)] = self._generator(closed, tang)
        return G

    def _generator(self, closed: frozenset, tang: tuple) -> np.ndarray:
        n, m = self.n, self.m
        Lq, Lu = self._maps(closed, tang)
        G = np.zeros((2 * n + m, 2 * n + m))
        G[:n, n:2 * n] = np.eye(n)
        G[n:2 * n, :n] = -self.Minv @ (self.K_ll + self.K_lc @ Lq)
        G[n:2 * n, n:2 * n] = -self.Minv @ self.C
        G[n:2 * n, 2 * n:] = -self.Minv @ (self.K_lc @ Lu)
        return G

    def monodromy(self, phases: list, omega: float) -> np.ndarray:
        """Φ(T) (2n + m square) over ``phases`` = [(τ_a, τ_b, closed, tang), ...] covering
        [0, 2π) in order, at Ω (rad/s)."""
        n, m = self.n, self.m
        Phi = np.eye(2 * n + m)

        def resets(before, after, Phi):
            for j in range(m):
                if after[3][j] == 0 and before[3][j] != 0:  # node j starts to stick
                    Lq, Lu = self._maps(before[2], before[3])
                    E = np.eye(2 * n + m)
                    E[2 * n + j] = 0.0
                    E[2 * n + j, :n] = Lq[self.t_rows[j]]
                    E[2 * n + j, 2 * n:] += Lu[self.t_rows[j]]
                    Phi = E @ Phi
            return Phi

        for i, ph in enumerate(phases):
            if i:
                Phi = resets(phases[i - 1], ph, Phi)
            key = (ph[2], ph[3])
            Phi = self.exponential(key, self.generator(*key), (ph[1] - ph[0]) / omega) @ Phi
            for j in range(m):
                if ph[3][j] != 0:  # a slipping node's stuck position is no state
                    Phi[2 * n + j] = 0.0
        return resets(phases[-1], phases[0], Phi)

    def multipliers(self, phases: list, omega: float) -> np.ndarray:
        mu = la.eigvals(self.monodromy(phases, omega))
        return mu[np.argsort(-np.abs(mu), kind="stable")]
