"""``mmshbm study --param normal_load=...``: the optimal-normal-load study of the default
beam with a Coulomb friction damper on its massless tip (:func:`mmshbm.fe.damper.tip_damper_model`)."""

from __future__ import annotations

import functools

import numpy as np

from .._method_info import DEFAULT_METHOD
from . import common

#: defaults of the study's further parameters: friction coefficient, position of the force
#: and of the amplitude (fraction of the length), frequency band (Hz), force (N)
DEFAULTS = {"mu": 0.5, "at": 0.5, "band": (30.0, 250.0), "force": 1.0}


def run_normal_load(args, params: dict) -> int:
    """Run the study, write normal_load.txt, normal_load.csv and normal_load.png."""
    from ..analysis.friction_study import normal_load_study
    from ..fe.damper import tip_damper_force, tip_damper_model
    from ..plotting.friction import plot_normal_load

    unknown = sorted(set(params) - {"normal_load", "mu", "at", "band", "force"})
    if unknown:
        raise ValueError(f"the normal-load study takes normal_load, mu, at, band and force, got {unknown}")
    if args.figure2 or args.model_file or args.methods not in (None, [DEFAULT_METHOD]):
        raise ValueError("the normal-load study runs MMS-HBM on the beam with a tip damper: drop --figure2, "
                         "--model-file and --methods")
    if args.harmonics and len(args.harmonics) > 1:
        raise ValueError("the normal-load study takes one value of -H")
    opts = dict(DEFAULTS)
    for name in ("mu", "at", "force"):
        if name in params:
            if len(params[name]) != 1:
                raise ValueError(f"{name} takes one value in the normal-load study, got {params[name]}")
            opts[name] = float(params[name][0])
    if "band" in params:
        if len(params["band"]) != 2:
            raise ValueError(f"band takes two frequencies LO,HI (Hz), got {params['band']}")
        opts["band"] = tuple(float(b) for b in params["band"])
    loads = [float(v) for v in params["normal_load"]]
    elements = args.elements[0] if args.elements else 21
    make = functools.partial(tip_damper_model, common.beam(args), elements, mu=opts["mu"],
                             grading=args.grading, at=opts["at"])
    force = tip_damper_force(make(normal_load=0.0), opts["force"])
    harmonics = args.harmonics[0] if args.harmonics else 7
    study = normal_load_study(make, loads, force, opts["band"], harmonics=harmonics, workers=args.workers)
    out = common.out_dir(args)
    text = study.to_text()
    (out / "normal_load.txt").write_text(text + "\n")
    table = np.column_stack([study.normal_load, study.peak_amplitude, study.peak_frequency,
                             study.slip_fraction, study.converged, study.at_band_edge])
    np.savetxt(out / "normal_load.csv", table, delimiter=",",
               header="normal_load_N,peak_amplitude_m,peak_frequency_Hz,slip_fraction,converged,at_band_edge",
               comments="")
    plot_normal_load(study, path=out / "normal_load.png")
    print(text)
    common.wrote(out / "normal_load.txt", out / "normal_load.csv", out / "normal_load.png")
    return 0 if study.converged.all() else 1
