"""Scaling with the size of the FE model: the modal condensation against the banded LU, and a
3-D solid of 10⁵ DOFs (see docs/scale.md).

asv suites:

* ``NewtonIterationScale``: one MMS-HBM Newton iteration (residual, Jacobian, bordered
  solve) at H = 5, 1.5 gaps, per condensation back end and beam size; the reduction is
  done in ``setup``.
* ``ScaleRatios``: the acceptance ratios measured in one process (``track_``): modal
  iteration on 10 000 against 21 elements (goal <= 2), banded against modal on 1000
  elements (goal >= 20).
* ``ModalReductionScale``: the one-time reduction (eigen-solve, static parts) of beams.
* ``SolidScale``: the 3-D solid beam with >= 10⁵ DOFs: reduction time and peak memory,
  one condensation evaluation, one Newton iteration of penalty HBM on the condensed
  contact DOFs, and MMS-HBM's backbone to 10 gaps (skipped until MMS-HBM takes several
  contacts).

The 10⁵-DOF figures of docs/scale.md come from the script entry point, which prints them
all from one process:

    OPENBLAS_NUM_THREADS=1 python -m benchmarks.bench_scale --solid 667 2 2
"""

from __future__ import annotations

import timeit

import numpy as np

#: beam sizes (elements) of the scaling suites
SCALE_ELEMENTS = (21, 1000, 10000)
#: the solid mesh of >= 10⁵ DOFs: elements along the length, width, height (Q2)
SOLID_MESH = (667, 2, 2)


def _problem(elements: int, backend: str, harmonics: int = 5):
    import mmshbm
    from mmshbm.methods.registry import make_problem

    model = mmshbm.default_beam().model(elements)
    return make_problem(model, "mmshbm", harmonics=harmonics, backend=backend)


def _iteration(problem):
    """A callable doing one Newton iteration at 1.5 gaps (Ω perturbed in the last digits so
    that no condensation is reused, as in a real iteration)."""
    from mmshbm.core.continuation import _bordered_solve

    u0 = problem.linear_point(1.5 * problem.model.gap)
    t = problem.initial_tangent()
    state = {"calls": 0}

    def iterate():
        state["calls"] += 1
        u = u0.copy()
        if state["calls"] % 2:
            u[-1] *= 1 + 1e-12
        R, J = problem.evaluate(u, jacobian=True)
        return _bordered_solve(J, t, np.append(R, 0.0))

    iterate()
    return iterate


def _seconds(f, number: int = 20, repeat: int = 7) -> float:
    """Fastest of ``repeat`` means over ``number`` calls (s)."""
    return min(timeit.repeat(f, number=number, repeat=repeat)) / number


class NewtonIterationScale:
    """One MMS-HBM Newton iteration at H = 5, 1.5 gaps."""

    params = [("banded", "modal"), SCALE_ELEMENTS]
    param_names = ["backend", "elements"]
    timeout = 300

    def setup(self, backend, elements):
        from benchmarks.common import warm_up

        warm_up("mmshbm")
        self.iterate = _iteration(_problem(elements, backend))

    def time_newton_iteration(self, backend, elements):
        self.iterate()


class ScaleRatios:
    """The issue's ratios, measured in one process."""

    timeout = 600

    def setup(self):
        from benchmarks.common import warm_up

        warm_up("mmshbm")

    def track_modal_iteration_10000_over_21(self):
        """Modal Newton iteration on 10 000 elements / on 21 elements (goal <= 2)."""
        small = _seconds(_iteration(_problem(21, "modal")), 50)
        large = _seconds(_iteration(_problem(10000, "modal")), 50)
        return large / small

    track_modal_iteration_10000_over_21.unit = "ratio"

    def track_banded_over_modal_iteration_1000(self):
        """Banded Newton iteration / modal one on 1000 elements (goal >= 20)."""
        banded = _seconds(_iteration(_problem(1000, "banded")), 10)
        modal = _seconds(_iteration(_problem(1000, "modal")), 50)
        return banded / modal

    track_banded_over_modal_iteration_1000.unit = "ratio"


class ModalReductionScale:
    """The one-time reduction of the beam (memory cache emptied, so it is computed)."""

    params = [SCALE_ELEMENTS]
    param_names = ["elements"]
    timeout = 300

    def setup(self, elements):
        import mmshbm

        self.model = mmshbm.default_beam().model(elements)

    def time_reduction(self, elements):
        import mmshbm.core.modal_reduction as mr
        from mmshbm.core.modal import ModalCondensation

        mr._MEMORY.clear()
        ModalCondensation(self.model, harmonics=5)

    def track_modes_kept(self, elements):
        from mmshbm.core.modal import ModalCondensation

        return ModalCondensation(self.model, harmonics=5).n_modes


class SolidScale:
    """The 3-D solid beam with >= 10⁵ DOFs (Q2 hexahedra, 25 contacts under the tip face)."""

    timeout = 600
    number = 1
    repeat = 1

    def setup_cache(self):
        import mmshbm

        model = mmshbm.default_beam().solid_model(*SOLID_MESH)
        return model

    def setup(self, model):
        self.model = model

    def time_reduction(self, model):
        import mmshbm.core.modal_reduction as mr
        from mmshbm.core.modal import ModalCondensation

        mr._MEMORY.clear()
        ModalCondensation(model, harmonics=5)

    def peakmem_reduction(self, model):
        import mmshbm.core.modal_reduction as mr
        from mmshbm.core.modal import ModalCondensation

        mr._MEMORY.clear()
        ModalCondensation(model, harmonics=5)

    def time_penalty_reduced_iteration(self, model):
        _penalty_iteration(model)()

    def time_mmshbm_backbone_10_gaps(self, model):
        import mmshbm

        _require_multi_contact_mmshbm(model)
        mmshbm.backbone(model, harmonics=5, backend="modal")


def _penalty_iteration(model):
    from mmshbm.methods.registry import make_problem

    return _iteration(make_problem(model, "penalty-reduced", harmonics=5, backend="modal"))


def _require_multi_contact_mmshbm(model):
    from mmshbm.methods.registry import make_problem

    try:
        make_problem(model, "mmshbm", harmonics=1, backend="modal")
    except ValueError as err:
        raise NotImplementedError(f"MMS-HBM does not take this model yet: {err}") from None


# ---------------------------------------------------------------------------- script
def _rss_peak_reset() -> None:
    """Reset the kernel's peak-RSS counter of this process (Linux)."""
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
    except OSError:  # pragma: no cover - not Linux
        pass


def _rss_peak_gib() -> float:
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 2**20
    except OSError:  # pragma: no cover
        pass
    return float("nan")


def _solid_report(mesh, backbone: bool) -> None:
    import time

    import mmshbm
    import mmshbm.core.modal_reduction as mr
    from mmshbm.core.modal import ModalCondensation

    mmshbm.backbone(mmshbm.default_beam().model(8), harmonics=3, max_amplitude=2e-3, backend="modal")
    t0 = time.perf_counter()
    model = mmshbm.default_beam().solid_model(*mesh)
    t1 = time.perf_counter()
    print(f"solid {mesh}: {model.n_dof} DOFs, {len(model.c)} massless, {model.n_contacts} contacts; "
          f"model built and validated in {t1 - t0:.1f} s; peak RSS so far {_rss_peak_gib():.2f} GiB")
    _rss_peak_reset()
    mr._MEMORY.clear()
    t0 = time.perf_counter()
    cond = ModalCondensation(model, harmonics=5)
    t1 = time.perf_counter()
    print(f"reduction: {t1 - t0:.1f} s, peak RSS during it {_rss_peak_gib():.2f} GiB; {cond}")
    omega = 2 * np.pi * 50.0
    ev = _seconds(lambda: cond.dynamic_stiffness(omega, 5), 20, 5)
    print(f"one condensation (H = 5, D and dD): {ev * 1e6:.0f} us")
    it = _seconds(_penalty_iteration(model), 5, 3)
    print(f"one penalty-reduced Newton iteration (H = 5, {6 * len(model.c) + 1} unknowns): {it * 1e3:.1f} ms")
    if backbone:
        _rss_peak_reset()
        for method in ("mmshbm", "penalty-reduced"):
            try:
                t0 = time.perf_counter()
                b = mmshbm.backbone(model, harmonics=5, method=method, backend="modal")
                print(f"{method} backbone to 10 gaps: {time.perf_counter() - t0:.1f} s, {len(b)} points, "
                      f"status {b.status}, peak RSS {_rss_peak_gib():.2f} GiB")
            except ValueError as err:
                print(f"{method} backbone: not run ({err})")


def _beam_report() -> None:
    from benchmarks.common import warm_up

    warm_up("mmshbm")
    times = {}
    for elements in SCALE_ELEMENTS:
        for backend in ("banded", "modal"):
            number = 50 if backend == "modal" or elements < 1000 else 5
            times[backend, elements] = _seconds(_iteration(_problem(elements, backend)), number)
            print(f"MMS-HBM Newton iteration, H = 5, {elements:5d} elements, {backend:6s}: "
                  f"{times[backend, elements] * 1e6:8.1f} us")
    print(f"modal 10000 / modal 21: {times['modal', 10000] / times['modal', 21]:.2f} (goal <= 2)")
    print(f"banded 1000 / modal 1000: {times['banded', 1000] / times['modal', 1000]:.1f} (goal >= 20)")


def main(argv=None) -> None:
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--solid", nargs=3, type=int, metavar=("NX", "NY", "NZ"),
                        help="also the solid beam with this Q2 mesh (e.g. 667 2 2: 100 050 DOFs)")
    parser.add_argument("--backbone", action="store_true", help="and its backbones to 10 gaps")
    args = parser.parse_args(argv)
    _beam_report()
    if args.solid:
        _solid_report(tuple(args.solid), args.backbone)


if __name__ == "__main__":
    main()
