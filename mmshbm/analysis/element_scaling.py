"""Cost of MMS-HBM against the number of beam elements: whole backbones, Newton
iterations and one residual + Jacobian evaluation per mesh, and the fitted exponents."""

from __future__ import annotations

import math
import time

import numpy as np

from .backbone_timing import measure, reached_frequency

__all__ = ["element_scaling", "format_scaling"]


def element_scaling(elements=(8, 21, 100, 1000), harmonics: int = 5, amplitude_gaps: float = 2.0,
                    repeats: int = 3) -> tuple[list[dict], float]:
    """Cost of MMS-HBM against the number of beam elements.

    For each element count: the whole backbone up to ``amplitude_gaps`` (fastest of
    ``repeats``), its Newton iterations, and the time of one residual + Jacobian
    evaluation (fastest of 20). The branches differ between meshes (more points where a
    finer mesh meets more internal resonances), so the exponent is fitted to the time
    **per Newton iteration** (whole backbone time / Newton iterations), which is the
    cost the mesh size controls; each row also has the raw times.

    Returns
    -------
    rows : list of dict
        ``elements, n_dof, unknowns, time_s, newton_iterations, continuation_steps,
        time_per_iteration_s, evaluate_s, frequency_hz``.
    exponent : float
        Least-squares slope of log(time per Newton iteration) against log(elements).
    """
    import mmshbm

    from .. import _validate as check
    from ..methods.registry import make_problem

    elements = [check.integer("elements", n, minimum=1) for n in elements]
    if len(elements) < 2:
        raise ValueError(f"need at least two element counts, got {elements}")
    beam = mmshbm.default_beam()
    rows = []
    for n in elements:
        model = beam.model(n)
        amplitude = amplitude_gaps * model.gap
        seconds, _, branch = measure(model, "mmshbm", amplitude, {"harmonics": harmonics}, repeats)
        problem = make_problem(model, "mmshbm", harmonics=harmonics)
        u = branch.states[-1]
        # alternate two states whose Ω differ in the last digits: MMS-HBM reuses the
        # condensation at an unchanged Ω, and a Newton iteration always changes Ω
        states = [u, u.copy()]
        states[1][-1] *= 1 + 1e-12
        problem.residual_and_jacobian(u)
        ev = math.inf
        for i in range(20):
            t0 = time.perf_counter()
            problem.residual_and_jacobian(states[(i + 1) % 2])
            ev = min(ev, time.perf_counter() - t0)
        nit = int(np.sum(branch.newton_iterations))
        rows.append({"elements": n, "n_dof": model.n_dof, "unknowns": problem.n_unknowns, "time_s": seconds,
                     "newton_iterations": nit, "continuation_steps": len(branch) - 1,
                     "time_per_iteration_s": seconds / max(nit, 1), "evaluate_s": ev,
                     "frequency_hz": reached_frequency(branch, amplitude)})
    x = np.log([r["elements"] for r in rows])
    y = np.log([r["time_per_iteration_s"] for r in rows])
    exponent = float(np.polyfit(x, y, 1)[0])
    return rows, exponent


def format_scaling(rows: list[dict], exponent: float) -> str:
    """Markdown table of :func:`element_scaling`."""
    lines = ["| elements | DOFs | time (ms) | Newton it. | steps | ms / iteration | evaluate (µs) | f (Hz) |",
             "|" + "---|" * 8]
    for r in rows:
        lines.append(f"| {r['elements']} | {r['n_dof']} | {1e3 * r['time_s']:.1f} | {r['newton_iterations']} "
                     f"| {r['continuation_steps']} | {1e3 * r['time_per_iteration_s']:.3f} "
                     f"| {1e6 * r['evaluate_s']:.0f} | {r['frequency_hz']:.6g} |")
    x = np.log([r["elements"] for r in rows])
    y = np.log([r["time_s"] for r in rows])
    whole = float(np.polyfit(x, y, 1)[0])
    evaluate = float(np.polyfit(x, np.log([r["evaluate_s"] for r in rows]), 1)[0])
    lines.append("")
    lines.append(f"Cost exponent (time ∝ elements^p): per Newton iteration p = {exponent:.2f}; "
                 f"one residual + Jacobian evaluation p = {evaluate:.2f}; whole backbone p = {whole:.2f}.")
    return "\n".join(lines)
