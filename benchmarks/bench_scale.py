"""Scaling with the size of the FE model: the modal condensation against the banded LU, and a
3-D solid of 10⁵ DOFs (see docs/scale.md).

asv suites:

* ``NewtonIterationScale``: one MMS-HBM Newton iteration (residual, Jacobian, bordered
  solve) at H = 5, 1.5 gaps, per condensation back end and beam size; the reduction is
  done in ``setup``.
* ``ScaleRatios``: the acceptance ratios measured in one process (``track_``): modal
  iteration on 10 000 against 21 elements (goal <= 2), banded against modal on 1000
  elements (goal >= 20).
* ``ModalReductionScale``: the one-time reduction (eigen-solve, static parts) of beams:
  time and peak memory.
* The whole backbone after the reduction against the model size: ``bench_backbone_scale.py``.
* ``SolidScale``: the 3-D solid beam with >= 10⁵ DOFs: reduction time and peak memory,
  one condensation evaluation, one Newton iteration of penalty HBM on the condensed
  contact DOFs, and MMS-HBM's backbone to 10 gaps (skipped until MMS-HBM takes several
  contacts).
* ``SolidEqualAccuracy``: penalty HBM on the condensed DOFs / MMS-HBM at equal accuracy
  (1e-3 at 1.1 gaps) on a small solid (864 DOFs), tuned once in ``setup_cache``.

The 10⁵-DOF figures of docs/scale.md come from the script entry point, which prints them
all from one process:

    OPENBLAS_NUM_THREADS=1 python -m benchmarks.bench_scale --solid 667 2 2
    OPENBLAS_NUM_THREADS=1 python -m benchmarks.bench_scale --accuracy 667 2 2   # equal accuracy
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
    from mmshbm.core.bordered import bordered_solve as _bordered_solve

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
        import mmshbm.harmonic.modal_reduction as mr
        from mmshbm.harmonic.modal import ModalCondensation

        mr._MEMORY.clear()
        ModalCondensation(self.model, harmonics=5)

    def peakmem_reduction(self, elements):
        import mmshbm.harmonic.modal_reduction as mr
        from mmshbm.harmonic.modal import ModalCondensation

        mr._MEMORY.clear()
        ModalCondensation(self.model, harmonics=5)

    def track_modes_kept(self, elements):
        from mmshbm.harmonic.modal import ModalCondensation

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
        import mmshbm.harmonic.modal_reduction as mr
        from mmshbm.harmonic.modal import ModalCondensation

        mr._MEMORY.clear()
        ModalCondensation(model, harmonics=5)

    def peakmem_reduction(self, model):
        import mmshbm.harmonic.modal_reduction as mr
        from mmshbm.harmonic.modal import ModalCondensation

        mr._MEMORY.clear()
        ModalCondensation(model, harmonics=5)

    def time_penalty_reduced_iteration(self, model):
        _penalty_iteration(model)()

    def time_mmshbm_backbone_10_gaps(self, model):
        import mmshbm

        _require_multi_contact_mmshbm(model)
        mmshbm.backbone(model, harmonics=5, backend="modal")


class SolidEqualAccuracy:
    """Penalty-HBM on the condensed contact DOFs / MMS-HBM at equal accuracy on the small
    solid (16×1×1 Q2, 864 DOFs): 1e-3 relative frequency error at 1.1 gaps against MMS-HBM
    at H = 25 (``_solid_equal_accuracy``; the 10⁵-DOF figures come from the script,
    ``--accuracy 667 2 2``). The study runs once, in ``setup_cache`` (~15 s)."""

    timeout = 300

    def setup_cache(self):
        return _solid_equal_accuracy(SOLID_SMALL_MESH, echo=lambda *a: None)

    setup_cache.timeout = 600

    def _pick(self, study, key):
        if study[key] is None:
            raise NotImplementedError(f"{key} does not meet the target on the solid")
        return study[key]

    def track_penalty_over_mmshbm(self, study):
        """Time ratio at equal accuracy (same process)."""
        return study["ratio"]

    track_penalty_over_mmshbm.unit = "ratio"

    def track_mmshbm_s(self, study):
        return self._pick(study, "mmshbm")["seconds"]

    track_mmshbm_s.unit = "s"

    def track_penalty_s(self, study):
        return self._pick(study, "penalty")["seconds"]

    track_penalty_s.unit = "s"

    def track_mmshbm_rel_error(self, study):
        return abs(self._pick(study, "mmshbm")["error"])

    track_mmshbm_rel_error.unit = "relative"

    def track_penalty_rel_error(self, study):
        return abs(self._pick(study, "penalty")["error"])

    track_penalty_rel_error.unit = "relative"

    def track_reference_spread(self, study):
        """Relative difference of MMS-HBM H = 20 and H = 25 (the reference's own error)."""
        return study["reference"]["spread"]

    track_reference_spread.unit = "relative"


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
    import mmshbm.harmonic.modal_reduction as mr
    from mmshbm.harmonic.modal import ModalCondensation

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


# ------------------------------------------------------------ solid: equal accuracy
#: the solid's equal-accuracy comparison (docs/scale.md): amplitude (gaps), target error
SOLID_ACCURACY_GAPS = 1.1
SOLID_TARGET = 1e-3
#: reference: MMS-HBM at the last H, accepted if the one before agrees to a tenth of the target
SOLID_REFERENCE_H = (20, 25)
#: the ladder of H of both methods, and penalty-HBM's k_p / k_c (one ladder of H each)
SOLID_H_LADDER = (5, 7, 9, 11, 13, 15, 20)
SOLID_PENALTY_FACTORS = (1e2, 1e3, 1e4)
#: the small solid of the asv track (864 DOFs, 27 massless, 9 contacts)
SOLID_SMALL_MESH = (16, 1, 1)


def _solid_equal_accuracy(mesh=SOLID_SMALL_MESH, amplitude_gaps: float = SOLID_ACCURACY_GAPS,
                          target: float = SOLID_TARGET, ladder=SOLID_H_LADDER, factors=SOLID_PENALTY_FACTORS,
                          reference_h=SOLID_REFERENCE_H, repeats: int = 3, model=None, echo=print) -> dict:
    """Penalty-HBM on the condensed contact DOFs against MMS-HBM on the solid beam at equal
    accuracy, in one process (docs/scale.md, "Equal accuracy on the solid").

    The rule of ``mmshbm bench`` (:mod:`mmshbm.analysis.benchmarking`): the relative error of
    the backbone frequency at ``amplitude_gaps`` against a reference; a setting counts if it
    *and the next rung* of its ladder meet ``target``; the cheapest such setting of each
    method is timed again (fastest of ``repeats`` whole backbones from half a gap to the
    amplitude). Reference: MMS-HBM at ``reference_h[-1]``, accepted only if
    ``reference_h[-2]`` agrees with it to a tenth of the target. Both methods use the same
    modal reduction, computed once beforehand for the highest H (its time is reported
    apart, and no timed backbone contains reduction work). Penalty-HBM walks the ladder of
    H once per k_p = factor × k_c (k_c: its default's stiffest condensed contact stiffness).

    Returns a dict: ``model`` (n_dof, n_c, contacts), ``reduction_s``, ``reference``
    (frequency, label, per-H frequencies), ``runs`` (every tuning run: method, setting,
    frequency, error, seconds), ``mmshbm`` / ``penalty`` (the timed picks or None:
    setting, frequency, error, seconds), ``ratio`` (penalty time / MMS-HBM time, NaN when
    either misses the target).
    """
    import warnings

    with warnings.catch_warnings():  # branch warnings (internal resonances, truncation): expected here
        warnings.simplefilter("ignore", UserWarning)
        return _equal_accuracy(mesh, amplitude_gaps, target, ladder, factors, reference_h, repeats, model,
                               echo)


def _equal_accuracy(mesh, amplitude_gaps, target, ladder, factors, reference_h, repeats, model, echo) -> dict:
    import time

    import mmshbm
    import mmshbm.harmonic.modal_reduction as mr
    from mmshbm.analysis.benchmarking import _backbone, _meets, _reached_frequency, _tune_ladder
    from mmshbm.harmonic.modal import ModalCondensation
    from mmshbm.methods.registry import make_problem

    mmshbm.backbone(mmshbm.default_beam().model(8), harmonics=3, max_amplitude=2e-3, backend="modal")
    if model is None:
        model = mmshbm.default_beam().solid_model(*mesh)
    small = mmshbm.default_beam().solid_model(4, 1, 1)  # compile both methods' kernels
    for method in ("mmshbm", "penalty-reduced"):
        mmshbm.backbone(small, harmonics=3, method=method, backend="modal", max_amplitude=1.1 * small.gap)
    amplitude = amplitude_gaps * model.gap
    out = {"model": {"mesh": tuple(mesh), "n_dof": model.n_dof, "n_c": len(model.c),
                     "contacts": model.n_contacts},
           "amplitude_gaps": amplitude_gaps, "target": target, "runs": []}
    echo(f"solid {mesh}: {model.n_dof} DOFs, {len(model.c)} massless, {model.n_contacts} contacts; "
         f"{amplitude_gaps:g} gaps, target {target:g}")
    mr._MEMORY.clear()
    t0 = time.perf_counter()
    cond = ModalCondensation(model, harmonics=max(max(ladder), max(reference_h)))
    out["reduction_s"] = time.perf_counter() - t0
    echo(f"modal reduction for H = {max(max(ladder), max(reference_h))}: {out['reduction_s']:.1f} s; {cond}")

    def opts(H, factor=None):
        o = {"harmonics": H, "backend": "modal"}
        if factor is not None:
            o["penalty_stiffness"] = factor * k_c
        return o

    # reference
    ref_f = {}
    for H in reference_h:
        t0 = time.perf_counter()
        ref_f[H] = _reached_frequency(_backbone(model, "mmshbm", amplitude, opts(H)), amplitude)
        echo(f"reference run MMS-HBM H = {H}: {ref_f[H]:.9g} Hz ({time.perf_counter() - t0:.1f} s)")
    f_ref = ref_f[reference_h[-1]]
    spread = abs(ref_f[reference_h[-2]] - f_ref) / f_ref
    out["reference"] = {"frequency": f_ref, "by_h": ref_f, "spread": spread,
                        "accepted": bool(spread <= 0.1 * target),
                        "label": f"MMS-HBM H={reference_h[-1]} (H={reference_h[-2]} agrees to {spread:.1e})"}
    if not spread <= 0.1 * target:
        echo(f"reference not converged in H to a tenth of the target ({spread:.1e}): no comparison")
        out.update(mmshbm=None, penalty=None, ratio=float("nan"))
        return out

    k_c = make_problem(model, "penalty-reduced", harmonics=1, backend="modal").contact_stiffness
    ladders = {"mmshbm": [[opts(H) for H in ladder]],
               "penalty-reduced": [[opts(H, f) for H in ladder] for f in factors]}
    for method, method_ladders in ladders.items():
        picks = []
        for lad in method_ladders:
            chosen, runs = _tune_ladder(model, method, amplitude, f_ref, target, lad)
            for r in runs:
                row = {"method": method, "setting": _solid_setting(r.options, k_c), "frequency": r.frequency,
                       "error": (r.frequency - f_ref) / f_ref, "seconds": r.seconds,
                       "meets": _meets(r, target)}
                out["runs"].append(row)
                echo(f"  {method:15s} {row['setting']:22s} f = {r.frequency:.7f} Hz, "
                     f"error {row['error']:+.2e}, {r.seconds:.2f} s")
            if chosen is not None:
                picks.append(chosen)
        pick = min(picks, key=lambda r: r.seconds) if picks else None
        if pick is None:
            out[_key(method)] = None
            echo(f"{method}: no setting meets {target:g} robustly")
            continue
        best = float("inf")
        for _ in range(repeats):
            t0 = time.perf_counter()
            _backbone(model, method, amplitude, pick.options)
            best = min(best, time.perf_counter() - t0)
        out[_key(method)] = {"setting": _solid_setting(pick.options, k_c), "frequency": pick.frequency,
                             "error": (pick.frequency - f_ref) / f_ref, "seconds": best}
        echo(f"{method}: cheapest robust setting {out[_key(method)]['setting']}, "
             f"error {out[_key(method)]['error']:+.2e}, {best:.3f} s (fastest of {repeats})")
    m, p = out["mmshbm"], out["penalty"]
    out["ratio"] = p["seconds"] / m["seconds"] if m and p else float("nan")
    out["peak_rss_gib"] = _rss_peak_gib()
    echo(f"equal accuracy ({target:g} at {amplitude_gaps:g} gaps): "
         f"penalty-reduced / MMS-HBM = {out['ratio']:.2f}; peak RSS {out['peak_rss_gib']:.2f} GiB")
    return out


def _key(method: str) -> str:
    return "mmshbm" if method == "mmshbm" else "penalty"


def _solid_setting(options: dict, k_c: float) -> str:
    s = f"H={options['harmonics']}"
    if "penalty_stiffness" in options:
        s += f", k_p={options['penalty_stiffness'] / k_c:.0e} k_c"
    return s


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
    parser.add_argument("--accuracy", nargs=3, type=int, metavar=("NX", "NY", "NZ"),
                        help="only the equal-accuracy comparison penalty-reduced / MMS-HBM on the solid "
                             "with this Q2 mesh (e.g. 16 1 1, or 667 2 2)")
    parser.add_argument("--repeats", type=int, default=3, help="timed runs of each pick (--accuracy)")
    parser.add_argument("--target", type=float, default=SOLID_TARGET, help="relative error (--accuracy)")
    args = parser.parse_args(argv)
    if args.accuracy:
        _solid_equal_accuracy(tuple(args.accuracy), target=args.target, repeats=args.repeats)
        return
    _beam_report()
    if args.solid:
        _solid_report(tuple(args.solid), args.backbone)


if __name__ == "__main__":
    main()
