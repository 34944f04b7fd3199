"""``mmshbm fit``."""

from __future__ import annotations

import json

from . import common


def register(sub) -> None:
    """Add the subcommand to the subparsers ``sub``."""
    p = sub.add_parser("fit", help="Young's modulus (and density) from measured linear frequencies")
    common.beam_options(p, model_file=False)
    p.add_argument("frequencies", type=common.positive_float, nargs="+", help="measured frequencies (Hz)")
    p.add_argument("--modes", type=common.positive_int, nargs="+", default=None,
                   help="their mode numbers (default 1 2 ...)")
    p.add_argument("--fit", nargs="+", default=["E"], choices=["E", "rho"], help="parameters (default E)")
    p.add_argument("--mass", type=common.positive_float, default=None,
                   help="measured beam mass (kg), to fit E and rho")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..analysis.identification import fit_material

    beam = common.beam(args)
    fitted, report = fit_material(beam, args.frequencies, args.elements, modes=args.modes,
                                  fit=tuple(args.fit), mass=args.mass, grading=args.grading)
    out = common.out_dir(args)
    path = out / "fit.json"
    record = {"E": report.values["E"], "rho": report.values["rho"], "fitted": list(report.parameters),
              "initial": report.initial, "modes": report.modes.tolist(),
              "measured_hz": report.measured.tolist(), "model_hz": report.frequencies.tolist(),
              "relative_residuals": report.relative_residuals.tolist(),
              "condition_number": report.condition_number, "identifiable": report.identifiable,
              "relative_std": report.relative_std, "n_elements": args.elements, "grading": args.grading,
              "beam": {k: getattr(fitted, k) for k in ("length", "width", "height", "E", "rho", "nu", "gap")},
              "message": report.message, "notes": report.notes}
    path.write_text(json.dumps(record, indent=2, allow_nan=True) + "\n")
    text = out / "fit.txt"
    text.write_text(report.summary() + "\n")
    print(report.summary())
    common.wrote(path, text)
    return 0 if report.success and report.identifiable else 1
