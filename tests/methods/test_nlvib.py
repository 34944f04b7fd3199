"""Penalty-HBM on NLvib's full-mass cantilever against NLvib's own backbone.

The reference (tests/data/nlvib_cantilever_impact_H5.csv, see tests/data/README.md) is
NLvib's nonlinear-mode continuation of its 21-element Euler–Bernoulli cantilever with a
unilateral penalty spring k_p = 1e3·3EI/L³ at the tip, H = 5, N = 1024. Both codes solve the
same harmonic-balance equations (same matrices to NLvib's quadrature error 1e-9, same AFT),
so they must agree to the tolerance of NLvib's solver.

Compared at NLvib's own amplitudes, without interpolation: for each NLvib point the
penalty-HBM equations are solved by Newton with the amplitude fixed to NLvib's (the
largest excursion of the tip away from the stop, from NLvib's tip harmonics), starting from
the mmshbm branch; the frequencies are compared. "Up to the first corner": from the start
(below grazing) to the first turning point of the backbone after grazing, where the
frequency reaches its maximum (58.982 Hz at 2.271 mm) and the branch turns back toward the
5:1 internal resonance with mode 2 (f2/5 = 56.55 Hz).
"""


import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from locations import DATA as TEST_DATA
from shared_models import GAP, H_SEC, B, E, L

import mmshbm
from mmshbm.methods.registry import make_problem

DATA = TEST_DATA
K_P = 1e3 * 3 * (E * B * H_SEC**3 / 12) / L**3
H, N = 5, 1024
TIP = 40


def read_nlvib(name):
    d = np.genfromtxt(DATA / name, delimiter=",", names=True)
    cos = np.array([d[f"tip_c{h}"] for h in range(H + 1)])  # (H+1, n_points)
    sin = np.array([np.zeros(len(d))] + [d[f"tip_s{h}"] for h in range(1, H + 1)])
    return d["frequency_hz"], cos, sin


def away_from_stop(cos, sin=None):
    """Largest excursion -q(τ) of q = Σ c_k cos kτ + s_k sin kτ (stop on the + side), and
    where (τ*): a fine grid, then Newton on dq/dτ = 0 within one grid cell."""
    k = np.arange(H + 1)
    sin = np.zeros_like(cos) if sin is None else sin
    grid = np.linspace(0, 2 * np.pi, 4096, endpoint=False)
    y = -(cos @ np.cos(np.outer(k, grid)) + sin @ np.sin(np.outer(k, grid)))
    t = t0 = grid[np.argmax(y)]
    for _ in range(20):
        d1 = cos @ (k * np.sin(k * t)) - sin @ (k * np.cos(k * t))
        d2 = cos @ (k**2 * np.cos(k * t)) + sin @ (k**2 * np.sin(k * t))
        if d2 <= 0 or abs(t - d1 / d2 - t0) > grid[1]:
            break
        t -= d1 / d2
    return -(cos @ np.cos(k * t) + sin @ np.sin(k * t)), t


def first_corner(frequency, amplitude):
    """Index of the first turning point after grazing: the first frequency maximum."""
    above = np.flatnonzero(amplitude > GAP * (1 + 1e-6))[0]
    return above + int(np.flatnonzero(np.diff(frequency[above:]) < 0)[0])


def solve_at_amplitude(problem, u, amplitude, max_iter=20):
    """Penalty-HBM point whose tip excursion away from the stop is ``amplitude`` (m):
    Newton on [R(u); (A(u) − amplitude)/amplitude] with ∂A/∂Q_k = −cos kτ* (τ* the
    maximiser, envelope theorem)."""
    cols = np.arange(H + 1) * problem.n + TIP
    previous = np.inf
    for _ in range(max_iter):
        R, J = problem.evaluate(u)
        Q, _ = problem.unpack(u)
        A, t = away_from_stop(Q[:, TIP])
        c = np.zeros(problem.n_unknowns)
        c[cols] = -np.cos(np.arange(H + 1) * t) * problem.colscale[cols] / amplitude
        Jx = sp.vstack([J, sp.csr_matrix(c[None])]).tocsc()
        du = spla.splu(Jx).solve(-np.append(R, (A - amplitude) / amplitude))
        u = u + du
        step = np.linalg.norm(du) / np.linalg.norm(u)
        # converged, or at the round-off floor of the solve (ε·κ(J), 1e-11 to 5e-11 under some
        # BLAS kernels): small and no longer shrinking as Newton's steps do
        if step < 1e-11 or (step < 1e-9 and step > previous / 4):
            return u
        previous = step
    raise AssertionError(f"no convergence at amplitude {amplitude}")


def test_penalty_hbm_reproduces_nlvib_to_the_first_corner(full_mass):
    f_ref, cos, sin = read_nlvib("nlvib_cantilever_impact_H5.csv")
    assert np.abs(sin).max() < 1e-13 * np.abs(cos).max()  # NLvib's orbits are time-symmetric too
    A_ref = np.array([away_from_stop(cos[:, i], sin[:, i])[0] for i in range(len(f_ref))])
    corner = first_corner(f_ref, A_ref)
    assert f_ref[corner] == pytest.approx(58.982, abs=1e-3)
    assert A_ref[corner] == pytest.approx(2.271e-3, abs=1e-6)

    branch = mmshbm.backbone(full_mass, H, method="penalty", penalty_stiffness=K_P, n_samples=N)
    assert branch.status.startswith("bound")
    fold = first_corner(branch.frequency, branch.amplitude)
    problem = make_problem(full_mass, "penalty", harmonics=H, n_samples=N, penalty_stiffness=K_P)
    A_branch = branch.amplitude[:fold + 1]
    errors = []
    for i in range(corner + 1):
        j = int(np.clip(np.searchsorted(A_branch, A_ref[i]), 1, fold))
        s = (A_ref[i] - A_branch[j - 1]) / (A_branch[j] - A_branch[j - 1])
        u = solve_at_amplitude(problem, branch.states[j - 1] + s * (branch.states[j] - branch.states[j - 1]),
                               A_ref[i])
        errors.append(problem.unpack(u)[1] / (2 * np.pi) / f_ref[i] - 1)
    errors = np.abs(errors)
    # NLvib's points were converged to fsolve TolFun = TolX = 1e-10; measured: 1.1e-10
    assert errors.max() < 1e-8, f"worst {errors.max():.3g} at NLvib point {np.argmax(errors)}"
    # and the two codes turn at the same corner
    assert branch.frequency[fold] == pytest.approx(f_ref[corner], rel=2e-3)


def test_nlvib_with_its_default_tolerance_is_1e6_close(full_mass):
    """The same run with Octave's fsolve defaults (TolFun = TolX = 1e-6): the distance is
    NLvib's own solver error, the issue's "1.3e-6" (measured 1.6e-6); the tight run above
    shows that penalty-HBM is not the cause."""
    f_loose, cos_l, sin_l = read_nlvib("nlvib_cantilever_impact_H5_fsolve_defaults.csv")
    A_loose = np.array([away_from_stop(cos_l[:, i], sin_l[:, i])[0] for i in range(len(f_loose))])
    corner = first_corner(f_loose, A_loose)
    problem = make_problem(full_mass, "penalty", harmonics=H, n_samples=N, penalty_stiffness=K_P)
    u = problem.linear_point(A_loose[0])
    errors = []
    for i in range(0, corner + 1, 4):  # continuation along NLvib's amplitudes, every 4th point
        u = solve_at_amplitude(problem, u, A_loose[i])
        errors.append(abs(problem.unpack(u)[1] / (2 * np.pi) / f_loose[i] - 1))
    assert 1e-7 < max(errors) < 1e-5
