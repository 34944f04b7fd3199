"""Many contacts: the dense and the Newton–Krylov MMS-HBM correctors against the number of
contact DOFs n_c and H, on the contact string (:func:`mmshbm.fe.contact_string.contact_string`:
n masses on n massless contact nodes, every pair of contacts coupled; docs/scale.md).

asv suites:

* ``InterfaceIteration``: one Newton iteration (residual, Jacobian and the bordered solve:
  LAPACK's LU for "dense", preconditioned GMRES for "krylov") at a contact point of the
  branch (1.5 gaps), per linear solver, n_c and H.
* ``InterfaceCorrector``: one corrector call (the continuation's, the compiled loop for
  "dense") from a predictor 5 % beyond a step of the branch, with its iteration count.
* ``InterfaceBackbone``: the backbone to 1.5 gaps (H = 5): its time, its points and the
  cost per point (``track_ms_per_point``, timed in one process).

* ``LapJointIteration``: one Newton iteration of the forced response with friction on the
  lap joint (:func:`mmshbm.lap_joint`, 2 slip DOFs per pair) at its bending frequency:
  residual and Jacobian, then the linear solve (dense LU; or the harmonics' blocks and
  GMRES, :mod:`mmshbm.methods.mms.forced_krylov`, multiplying by the assembled Jacobian or
  by the operator of :mod:`mmshbm.methods.mms.forced_operator`), per solver, pairs and H;
  its memory.
* ``LapJointResponse``: the lap joint's forced response over its frequency range at H = 5
  (the points and the cost per point), for the pair counts that fit asv's timeout.

The table of docs/scale.md comes from the script entry point:

    OPENBLAS_NUM_THREADS=1 python -m benchmarks.bench_interfaces 8 16 32 64

and that of docs/interfaces.md from ``python -m benchmarks.bench_interfaces --lap 8 32 100 400``
(processor times, one BLAS thread).
"""

from __future__ import annotations

import sys
import time
import timeit

import numpy as np

#: contact counts of the suites
CONTACTS = (8, 16, 32, 64)
SOLVERS = ("dense", "krylov")
#: the backbone's amplitude bound (gaps)
MAX_GAPS = 1.5


def _branch(n: int, harmonics: int, solver: str):
    import mmshbm
    from mmshbm.fe.contact_string import contact_string

    model = contact_string(n)
    return model, mmshbm.backbone(model, harmonics=harmonics, max_amplitude=MAX_GAPS, max_steps=200,
                                  linear_solver=solver)


def _predictor(branch):
    """(u_prev + 1.05 ds t, t) at the branch's step two thirds along (contacts closed)."""
    i = max(1, 2 * len(branch.states) // 3)
    u_prev, u = branch.states[i - 1], branch.states[i]
    ds = float(np.linalg.norm(u - u_prev))
    t = (u - u_prev) / ds
    return u_prev + 1.05 * ds * t, t, u


def _setup(n: int, harmonics: int, solver: str):
    import warnings

    from mmshbm.methods.mms.conservative import MMSHBMProblem

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model, branch = _branch(n, harmonics, "dense")
    problem = MMSHBMProblem(model, harmonics, linear_solver=solver)
    u_pred, t, u = _predictor(branch)
    return problem, u_pred, t, u


def _seconds(f, number: int = 5, repeat: int = 5) -> float:
    """Fastest of ``repeat`` means over ``number`` calls (s)."""
    return min(timeit.repeat(f, number=number, repeat=repeat)) / number


class InterfaceIteration:
    """One Newton iteration at a contact point (residual, Jacobian, bordered solve)."""

    params = [SOLVERS, CONTACTS, (3, 5)]
    param_names = ["solver", "contacts", "harmonics"]
    timeout = 600

    def setup(self, solver, contacts, harmonics):
        problem, u_pred, t, u = _setup(contacts, harmonics, solver)
        if solver == "krylov":
            corrector = problem.krylov

            def iterate():
                R, J = problem.residual_and_jacobian(u_pred)
                return corrector.solve(J, t, np.append(R, 0.0))
        else:
            def iterate():
                R, J = problem.residual_and_jacobian(u_pred)
                return np.linalg.solve(np.vstack([J, t]), np.append(R, 0.0))
        iterate()
        self.iterate = iterate

    def time_iteration(self, solver, contacts, harmonics):
        self.iterate()


class InterfaceCorrector:
    """One corrector call of the continuation from a predictor off the branch."""

    params = [SOLVERS, CONTACTS, (3, 5)]
    param_names = ["solver", "contacts", "harmonics"]
    timeout = 600

    def setup(self, solver, contacts, harmonics):
        self.problem, self.u_pred, self.t, _ = _setup(contacts, harmonics, solver)
        self.call()

    def call(self):
        return self.problem.fast_newton(self.u_pred.copy(), self.u_pred, self.t, 1e-10, 12, 0.0)

    def time_corrector(self, solver, contacts, harmonics):
        self.call()

    def track_iterations(self, solver, contacts, harmonics):
        return self.call()[1]


class InterfaceBackbone:
    """The backbone of the contact string to 1.5 gaps at H = 5."""

    params = [SOLVERS, CONTACTS]
    param_names = ["solver", "contacts"]
    timeout = 900

    def setup(self, solver, contacts):
        import warnings

        warnings.simplefilter("ignore")
        _branch(contacts, 5, solver)  # kernels compiled, the reduction cached

    def time_backbone(self, solver, contacts):
        _branch(contacts, 5, solver)

    def track_points(self, solver, contacts):
        return len(_branch(contacts, 5, solver)[1].states)

    def track_ms_per_point(self, solver, contacts):
        start = time.perf_counter()
        branch = _branch(contacts, 5, solver)[1]
        return 1e3 * (time.perf_counter() - start) / len(branch.states)

    track_ms_per_point.unit = "ms"


#: pair counts of the lap-joint suites (an nx × ny grid each)
PAIRS = (8, 32, 100, 400)


def _joint(pairs: int):
    from mmshbm.fe.lap_joint import lap_joint

    return lap_joint(pairs)


#: the lap joint's linear solves: the dense LU of the assembled Jacobian, GMRES multiplying
#: by the assembled Jacobian, GMRES with the Jacobian as an operator (never assembled,
#: :mod:`mmshbm.methods.mms.forced_operator`)
LAP_SOLVERS = ("dense", "krylov-assembled", "krylov")
#: the largest dense Jacobian the dense and assembled suites form (n_x² numbers: 1.6 GB at 400
#: pairs, H = 5): above, those parameters are skipped
ASSEMBLED_MAX_PAIRS = 100


def _forced_setup(pairs: int, harmonics: int, solver: str):
    """(problem, x, Ω) at 0.98 of the joint's bending frequency, from its linear response."""
    from mmshbm.methods.mms.friction_forced import FrictionForcedProblem

    joint = _joint(pairs)
    problem = FrictionForcedProblem(joint.model, joint.force, harmonics=harmonics,
                                    linear_solver="dense" if solver == "dense" else "krylov")
    if solver == "krylov-assembled":
        problem._matrix_free = False
    f = 0.98 * joint.bending_frequency
    x, omega = problem.unpack(problem.linear_response_point(f))
    return problem, x, omega


class LapJointIteration:
    """One Newton iteration of the lap joint's forced response at fixed frequency: residual
    and Jacobian (assembled, or the operator's law blocks), then the linear solve."""

    params = [LAP_SOLVERS, PAIRS, (3, 5)]
    param_names = ["solver", "pairs", "harmonics"]
    timeout = 900

    def setup(self, solver, pairs, harmonics):
        if solver != "krylov" and pairs > ASSEMBLED_MAX_PAIRS:
            raise NotImplementedError("the assembled Jacobian is not formed at this size")
        from mmshbm.methods.mms.forced_operator import square_operator

        problem, x, omega = _forced_setup(pairs, harmonics, solver)

        def iterate():
            if problem._matrix_free:
                R, op = square_operator(problem, x, omega)
                return problem._krylov.square_solve(op, -R)
            R, Jx, _, _ = problem.residual_parts(x, omega, 1.0, True)
            if problem._krylov is not None:
                return problem._krylov.square_solve(Jx, -R)
            return np.linalg.solve(Jx, -R)

        iterate()
        self.iterate = iterate
        self.problem = problem

    def time_iteration(self, solver, pairs, harmonics):
        self.iterate()

    def peakmem_iteration(self, solver, pairs, harmonics):
        self.iterate()

    def track_unknowns(self, solver, pairs, harmonics):
        return self.problem.n_x


class LapJointResponse:
    """The lap joint's forced response over its frequency range at H = 5 (the dense solves
    up to 32 pairs: 208 s processor at 100 pairs, docs/interfaces.md)."""

    params = [SOLVERS, (8, 32, 100)]
    param_names = ["solver", "pairs"]
    timeout = 1800

    def setup(self, solver, pairs):
        if solver == "dense" and pairs > 32:
            raise NotImplementedError("the dense response at this size exceeds the suite's budget")
        self.joint = _joint(pairs)

    def _run(self, solver):
        import mmshbm

        return mmshbm.frequency_response(self.joint.model, self.joint.force, self.joint.frequency_range,
                                         harmonics=5, linear_solver=solver)

    def track_ms_per_point(self, solver, pairs):
        start = time.perf_counter()
        res = self._run(solver)
        return 1e3 * (time.perf_counter() - start) / len(res.frequency)

    track_ms_per_point.unit = "ms"

    def track_points(self, solver, pairs):
        return len(self._run(solver).frequency)


def lap_main(pairs: list[int]) -> None:
    """Print, per pair count: unknowns, one fixed-frequency Newton iteration (dense and
    Krylov, H = 5) and the joint's build time."""
    print("| pairs | unknowns (H = 5) | build (s) | dense iteration (s) | Krylov, assembled (s) "
          "| Krylov, operator (s) |")
    print("|---:|---:|---:|---:|---:|---:|")
    for n in pairs:
        start = time.process_time()
        _joint(n)
        build = time.process_time() - start
        row = []
        for solver in LAP_SOLVERS:
            it = LapJointIteration()
            try:
                it.setup(solver, n, 5)
            except NotImplementedError:
                row.append(float("nan"))
                continue
            start = time.process_time()
            for _ in range(3):
                it.iterate()
            row.append((time.process_time() - start) / 3)
        print(f"| {n} | {it.problem.n_x} | {build:.1f} | {row[0]:.3f} | {row[1]:.3f} | {row[2]:.3f} |",
              flush=True)


def main(argv: list[str]) -> None:
    """Print, per n_c: the bordered system's size, the corrector call and iterations, the
    iteration, and the backbone's points and cost per point, dense beside Krylov."""
    import warnings

    warnings.simplefilter("ignore")
    contacts = [int(a) for a in argv] or list(CONTACTS)
    print("| n_c | unknowns | solver | corrector call (ms) | iterations | iteration (ms) | points "
          "| per point (ms) |")
    print("|---:|---:|---|---:|---:|---:|---:|---:|")
    for n in contacts:
        for solver in SOLVERS:
            corr = InterfaceCorrector()
            corr.setup(solver, n, 5)
            t_call = _seconds(corr.call)
            its = corr.call()[1]
            it = InterfaceIteration()
            it.setup(solver, n, 5)
            t_it = _seconds(it.iterate)
            bb = InterfaceBackbone()
            bb.setup(solver, n)
            start = time.perf_counter()
            branch = _branch(n, 5, solver)[1]
            per_point = (time.perf_counter() - start) / len(branch.states)
            print(f"| {n} | {corr.problem.n_unknowns} | {solver} | {1e3 * t_call:.2f} | {its} | "
                  f"{1e3 * t_it:.2f} | {len(branch.states)} | {1e3 * per_point:.2f} |", flush=True)


if __name__ == "__main__":
    if sys.argv[1:2] == ["--lap"]:
        lap_main([int(a) for a in sys.argv[2:]] or [8, 32, 100])
    else:
        main(sys.argv[1:])
