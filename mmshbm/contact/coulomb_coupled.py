"""Coulomb friction pressed by a unilateral contact: the displacement-level ("play")
projection with a slip force that varies in time.

A friction node t whose normal force is N(τ) = N0 + λ(τ), λ the force of a unilateral
contact on a massless DOF n (impact with friction). In the proximal form of the unilateral
law (:mod:`mmshbm.methods.mms.damped`) the contact force is

    λ(τ) = r_n (z(τ) − gap)₊,     z = side·p_n,   p_n = q_n − F_n/r_n,

a trigonometric polynomial on the closed arcs (z > gap, located as zeros of z − gap by the
unilateral projection's root finder) and 0 on the open ones; it is continuous and vanishes
at every switch. The slip force s = μ (N0 + λ) is therefore continuous, and with
y = u − F_t/ρ (:func:`mmshbm.contact.coulomb.project_coulomb_play`) Coulomb's law says that
u is the play operator of y with the time-varying half-width w = s/ρ (a sweeping process
in the moving band [α, β] = [y − w, y + w]): u stays put while α < u < β, and is pushed
along α (slip up, support force F_t = −s) while α rises into it, along β (slip down,
F_t = +s) while β falls into it. α and β are trigonometric polynomials on each normal arc
(α = y − w0 − κ (z − gap) on a closed arc, y − w0 on an open one; w0 = μN0/ρ, κ = μ r_n/ρ).

Periodic orbit in one pass. At the instant τ_A of α's global maximum every orbit that has
passed β's global minimum earlier sits at u = α(τ_A) when max α > min β (u only rises along
α, which never exceeds its maximum, and it must lie above α(τ_A)): the walk starts there.
Otherwise (max α <= min β) the node may stick throughout; its position is history and the
symmetric position, mean force zero (u = mean(y) clamped into [max α, min β]), is taken.

Between consecutive breakpoints (normal switches, zeros of α′ and β′ on their arcs) α and β
are monotone; the walk goes over these segments, a stick-to-slip instant being the zero of
α − u_s (or β − u_s) in its segment. The support's force F_t(τ) = g: ρ (u_s − y) on a stick
piece, −σ s(τ) on a slip piece σ = ±1, projected in closed form (the product of y or z with
the piece's indicator). g is continuous at every switch, so the Jacobian has no boundary
terms; u_s depends on the unknowns through the instant τ_e that set it: at a smooth
extremum of α or β only through α(τ_e) (α′ = 0 there), at a normal switch (a kink of α)
also through the switch instant, ∂τ_e = −∂z(τ_e)/z′(τ_e), which gives
∂u_s/∂z = −(y′(τ_e)/z′(τ_e)) φ(τ_e)ᵀ (the open side's α, y − w0, is the same function
there). Hence, with P_χ[v] = proj[χ v] the product matrix of the indicator χ,

    ∂g/∂y = Σ_stick ρ (ind_i φ(τ_e)ᵀ − P_χi),
    ∂g/∂z = Σ_stick ρ κ_i ind_i φ(τ_e)ᵀ − Σ_slip,closed σ_i μ r_n P_χi,

κ_i = ∂u_s/∂z (per φ(τ_e)): −σ_e κ at a smooth extremum of a closed arc, 0 on an open arc,
−y′/z′ at a switch.
"""

from __future__ import annotations

import numpy as np

from .coulomb import _phi, _sample_basis
from .trig import _TWO_PI, _refine, _zeros

__all__ = ["project_coulomb_play_coupled", "coupled_play_pieces"]

_ROOT = np.int64(0)


def _split(v: np.ndarray):
    """NLvib-ordered (2H+1,) -> cosine (H+1,) and sine (H+1,) coefficient arrays."""
    return np.concatenate([[v[0]], v[1::2]]), np.concatenate([[0.0], v[2::2]])


def _deriv(c: np.ndarray, sn: np.ndarray):
    k = np.arange(c.shape[0])
    return k * sn, -k * c


def _all_zeros(c, sn, tables):
    """Zeros on [0, 2π) of the trigonometric polynomial (c, sn), sorted."""
    tau, cos_t, sin_t = tables
    dc, ds = _deriv(c, sn)
    g = c @ cos_t + sn @ sin_t
    dg = dc @ cos_t + ds @ sin_t
    roots = np.empty(2 * len(tau) + 2)
    n = _zeros(np.ascontiguousarray(c), np.ascontiguousarray(sn), g, dg, tau, roots)
    return roots[:n].copy()


def _ev(c, sn, t):
    k = np.arange(c.shape[0])
    return c @ np.cos(k * t) + sn @ np.sin(k * t)


def _ev_many(c, sn, t):
    """(c, sn) evaluated at every τ of ``t`` (n,)."""
    kt = np.outer(np.asarray(t, dtype=float), np.arange(c.shape[0]))
    return np.cos(kt) @ c + np.sin(kt) @ sn


class _Bands:
    """α, β, y, z as trigonometric polynomials, the band's formulas per normal arc."""

    def __init__(self, y, z, w0, kappa, gap):
        self.yc, self.ys = _split(y)
        self.zc, self.zs = _split(z)
        self.w0, self.kappa, self.gap = w0, kappa, gap

    def coeffs(self, which: int, closed: bool):
        """(c, sn) of α (which = −1) or β (+1) on an open or closed arc."""
        c = self.yc.copy()
        sn = self.ys.copy()
        c[0] += which * self.w0
        if closed:
            c += which * self.kappa * self.zc
            sn += which * self.kappa * self.zs
            c[0] -= which * self.kappa * self.gap
        return c, sn

    def value(self, which, closed, t):
        return _ev(*self.coeffs(which, closed), t)

    def closed_at(self, t):
        return _ev(self.zc, self.zs, t) > self.gap

    def closed_many(self, t):
        return _ev_many(self.zc, self.zs, t) > self.gap


def coupled_play_pieces(y, z, w0: float, kappa: float, gap: float, n_samples: int | None = None):
    """Stick and slip pieces of the periodic sweeping process in the band [y − w, y + w],
    w = w0 + κ (z − gap)₊ (module docstring), over one period.

    Parameters
    ----------
    y, z : ndarray (2H+1,)
        NLvib-ordered coefficients of the driving signal y (m) and of side·p_n (m).
    w0 : float
        μ N0/ρ (m), the half-width where the contact is open.
    kappa : float
        μ r_n/ρ (dimensionless): the half-width grows by κ (z − gap) on closed arcs.
    gap : float
        The contact closes where z > gap (m).

    Returns
    -------
    list of (a, b, σ, u_s, τ_e, κ_e, closed): the arc [a, b], σ = 0 stick at u_s (set at τ_e:
    ∂u_s/∂y = φ(τ_e), ∂u_s/∂z = κ_e φ(τ_e); τ_e = NaN: the symmetric position, ∂u_s/∂y = e_0),
    σ = ±1 slip (u_s, τ_e, κ_e NaN), ``closed`` whether the normal contact is closed on it.
    """
    y = np.asarray(y, dtype=float)
    H = (y.shape[0] - 1) // 2
    N = 16 * (2 * H + 1) if n_samples is None else int(n_samples)
    tables = _sample_basis(H, N)
    bd = _Bands(y, np.asarray(z, dtype=float), float(w0), float(kappa), float(gap))
    zc = bd.zc.copy()
    zc[0] -= bd.gap
    switches = _all_zeros(zc, bd.zs, tables)
    # breakpoints: switches (kind 2) and the zeros of α′ and β′ on their own arcs
    pts, kinds = [switches], [np.full(len(switches), 2)]
    arcs = [False, True] if len(switches) else [bool(bd.closed_at(0.0))]
    for closed in arcs:
        # on open arcs α′ = β′ = y′: listed once
        for which in ((-1, 1) if closed else (-1,)):
            ext = _all_zeros(*_deriv(*bd.coeffs(which, closed)), tables)
            if len(switches) and len(ext):
                ext = ext[bd.closed_many(ext) == closed]
            pts.append(ext)
            kinds.append(np.full(len(ext), 0 if which == -1 else 1))
    pts = np.concatenate(pts)
    kinds = np.concatenate(kinds)
    order = np.argsort(pts)
    pts, kinds = pts[order], kinds[order]
    if len(pts) == 0:  # y constant on an always open or always closed contact
        return [(0.0, _TWO_PI, 0, float(y[0]), np.nan, 0.0, bool(bd.closed_at(0.0)))]
    mids = 0.5 * (pts + np.roll(pts, -1) + np.where(np.arange(len(pts)) == len(pts) - 1, _TWO_PI, 0.0))
    seg_closed = bd.closed_many(mids % _TWO_PI)   # segment i: [pts[i], pts[i+1]]
    # α and β at every breakpoint (the band is continuous: the arc after it)
    alpha = np.where(seg_closed, _ev_many(*bd.coeffs(-1, True), pts), _ev_many(*bd.coeffs(-1, False), pts))
    beta = np.where(seg_closed, _ev_many(*bd.coeffs(1, True), pts), _ev_many(*bd.coeffs(1, False), pts))
    i_a, i_b = int(np.argmax(alpha)), int(np.argmin(beta))

    def kappa_at(i, sigma):
        """∂u_s/∂z per φ(τ_e) for a node set at breakpoint i by α (σ = +1) or β (σ = −1)."""
        if kinds[i] == 2:
            yd = _ev(*_deriv(bd.yc, bd.ys), pts[i])
            zd = _ev(*_deriv(bd.zc, bd.zs), pts[i])
            return -yd / zd
        closed = bd.closed_at(pts[i])
        return -sigma * bd.kappa if closed else 0.0

    if alpha[i_a] <= beta[i_b]:  # full stick possible: the symmetric position
        u = float(y[0])
        if u < alpha[i_a]:
            return [(0.0, _TWO_PI, 0, float(alpha[i_a]), float(pts[i_a]), kappa_at(i_a, 1), False)]
        if u > beta[i_b]:
            return [(0.0, _TWO_PI, 0, float(beta[i_b]), float(pts[i_b]), kappa_at(i_b, -1), False)]
        return [(0.0, _TWO_PI, 0, u, np.nan, 0.0, False)]
    n = len(pts)
    idx = [(i_a + m) % n for m in range(n)]
    start = pts[i_a]
    P = [pts[i] + (_TWO_PI if pts[i] < start else 0.0) for i in idx] + [start + _TWO_PI]
    out = []
    # α and β of both arc kinds at every point of the walk, evaluated at once
    band = {}
    for which in (-1, 1):
        for closed in (False, True):
            cs = bd.coeffs(which, closed)
            band[(which, closed)] = (cs, _ev_many(*cs, P))
    mode, u, t_e, k_e = 1, float(alpha[i_a]), float(start), kappa_at(i_a, 1)
    for m in range(n):
        i = idx[m]
        a, b, closed = P[m], P[m + 1], bool(seg_closed[i])
        if b <= a:
            continue
        (al_c, al_s), al_v = band[(-1, closed)]
        (be_c, be_s), be_v = band[(1, closed)]
        al_a, al_b = al_v[m], al_v[m + 1]
        be_a, be_b = be_v[m], be_v[m + 1]
        if mode == 1 and not al_b > al_a:
            mode, u, t_e, k_e = 0, float(al_a), a, kappa_at(i, 1)
        elif mode == -1 and not be_b < be_a:
            mode, u, t_e, k_e = 0, float(be_a), a, kappa_at(i, -1)
        if mode != 0:
            out.append((a, b, mode, np.nan, np.nan, np.nan, closed))
            continue
        if al_b > u:
            sigma, c, sn, fa = 1, al_c, al_s, al_a - u
        elif be_b < u:
            sigma, c, sn, fa = -1, be_c, be_s, be_a - u
        else:
            out.append((a, b, 0, u, t_e, k_e, closed))
            continue
        if sigma * fa >= 0:
            t_sw = a
        else:
            c = c.copy()
            c[0] -= u
            t_sw = float(_refine(c, sn, a, b, fa, _ROOT))
        if t_sw > a:
            out.append((a, t_sw, 0, u, t_e, k_e, closed))
        out.append((t_sw, b, sigma, np.nan, np.nan, np.nan, closed))
        mode = sigma
    return out


def project_coulomb_play_coupled(y, z, rho: float, mu: float, preload: float, r_n: float, gap: float,
                                 n_samples: int | None = None, jacobian: bool = True):
    """Exact harmonic projection of the support's force g on a friction node pressed by
    N0 + λ(τ), λ = r_n (z − gap)₊ (module docstring), and its exact Jacobian.

    Parameters
    ----------
    y : ndarray (2H+1,)
        NLvib-ordered y = u_t − F_t/ρ (m).
    z : ndarray (2H+1,)
        side·p_n = side·(q_n − F_n/r_n) of the normal contact (m).
    rho : float
        The friction node's stiffness parameter ρ > 0 (N/m).
    mu, preload : float
        Friction coefficient >= 0 and constant normal force N0 >= 0 (N).
    r_n : float
        The normal contact's proximal parameter (N/m).
    gap : float
        The normal contact closes where z > gap (m).
    n_samples : int, optional
        Bracketing grid of the root finder, default 16 (2H+1).
    jacobian : bool
        Without it, both derivatives are None.

    Returns
    -------
    g : ndarray (2H+1,)
        NLvib-ordered projection of the support's force on the node (N).
    dg_dy, dg_dz : ndarray (2H+1, 2H+1) or None
    slip : float
        Fraction of the period in slip.
    """
    from .projection import _product_matrix

    y = np.asarray(y, dtype=float)
    z = np.asarray(z, dtype=float)
    if y.ndim != 1 or y.shape[0] % 2 != 1 or z.shape != y.shape:
        raise ValueError(f"y and z must be 1-D with 2H+1 entries each, got {y.shape} and {z.shape}")
    rho, mu, preload, r_n = float(rho), float(mu), float(preload), float(r_n)
    if not (rho > 0 and r_n > 0 and mu >= 0 and preload >= 0):
        raise ValueError(f"need rho > 0, r_n > 0, mu >= 0, preload >= 0; got {rho}, {r_n}, {mu}, {preload}")
    H = (y.shape[0] - 1) // 2
    pieces = coupled_play_pieces(y, z, mu * preload / rho, mu * r_n / rho, gap, n_samples)
    a = np.array([p[0] for p in pieces])
    b = np.array([p[1] for p in pieces])
    sigma = np.array([p[2] for p in pieces], dtype=float)
    u = np.array([p[3] for p in pieces])
    t_e = np.array([p[4] for p in pieces])
    k_e = np.array([p[5] for p in pieces])
    closed = np.array([p[6] for p in pieces], dtype=bool)
    nn = np.arange(1, 2 * H + 1)
    C = np.empty((len(a), 2 * H + 1))
    S = np.empty((len(a), 2 * H + 1))
    C[:, 0], S[:, 0] = b - a, 0.0
    C[:, 1:] = (np.sin(np.outer(b, nn)) - np.sin(np.outer(a, nn))) / nn
    S[:, 1:] = (np.cos(np.outer(a, nn)) - np.cos(np.outer(b, nn))) / nn
    C /= 2 * np.pi
    S /= 2 * np.pi
    ind = np.empty((len(a), 2 * H + 1))
    ind[:, 0] = C[:, 0]
    ind[:, 1::2] = 2 * C[:, 1:H + 1]
    ind[:, 2::2] = 2 * S[:, 1:H + 1]
    stick = sigma == 0
    slipc = (~stick) & closed
    slip = float(np.sum((b - a)[~stick]) / (2 * np.pi))
    # slip pieces: −σ μ (N0 + r_n (z − gap) on closed arcs); stick pieces: ρ (u_s − y)
    g = -mu * preload * (sigma[~stick] @ ind[~stick]) + mu * r_n * gap * (sigma[slipc] @ ind[slipc])
    g += rho * (u[stick] @ ind[stick])
    G_y = _product_matrix(C[stick].sum(axis=0), S[stick].sum(axis=0), H)
    G_z = _product_matrix(sigma[slipc] @ C[slipc], sigma[slipc] @ S[slipc], H)
    g -= rho * (G_y @ y) + mu * r_n * (G_z @ z)
    if not jacobian:
        return g, None, None, slip
    Jy = -rho * G_y
    Jz = -mu * r_n * G_z
    for i in np.flatnonzero(stick):
        if np.isnan(t_e[i]):
            Jy[:, 0] += rho * ind[i]
        else:
            ph = _phi(H, t_e[i])
            Jy += rho * np.outer(ind[i], ph)
            if k_e[i] != 0.0:
                Jz += rho * k_e[i] * np.outer(ind[i], ph)
    return g, Jy, Jz, slip
