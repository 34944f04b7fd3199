"""``mmshbm fit``: Young's modulus (and density) from measured linear frequencies, and the
contact-layer stiffness from a measured backbone (``--measured``)."""

from __future__ import annotations

import json
import math

from . import common


def register(sub) -> None:
    """Add the subcommand to the subparsers ``sub``."""
    p = sub.add_parser("fit", help="Young's modulus (and density) from measured linear frequencies; "
                                   "the contact stiffness from a measured backbone (--measured)")
    common.beam_options(p, model_file=True, conversions=False)
    p.add_argument("frequencies", type=common.positive_float, nargs="*",
                   help="measured linear frequencies (Hz)")
    p.add_argument("--modes", type=common.positive_int, nargs="+", default=None,
                   help="their mode numbers (default 1 2 ...)")
    p.add_argument("--fit", nargs="+", default=["E"], choices=["E", "rho"], help="parameters (default E)")
    p.add_argument("--mass", type=common.positive_float, default=None,
                   help="measured beam mass (kg), to fit E and rho")
    p.add_argument("--measured", default=None, metavar="CSV",
                   help="measured backbone (frequency, amplitude columns): fit the stiffness of a contact "
                        "layer on the model with the tip's mass (after E from the frequencies, if given)")
    p.add_argument("-H", "--harmonics", type=common.positive_int, default=5,
                   help="harmonics of the backbones (default 5)")
    p.add_argument("--initial", type=common.positive_float, default=None, metavar="K",
                   help="start value of the contact stiffness (N/m) (default: a scan)")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..analysis.identification import fit_contact_stiffness, fit_material

    if not args.frequencies and not args.measured:
        raise ValueError("give measured frequencies (Hz) to fit E, and/or --measured CSV to fit the contact "
                         "stiffness")
    if args.model_file and args.frequencies:
        raise ValueError("--model-file: E and rho are fitted on the beam only; give --measured alone")
    measured = common.measured(args)
    out = common.out_dir(args)
    record, texts, ok = {}, [], True
    beam = common.beam(args)
    if args.frequencies:
        # with a backbone to fit, the contact layer keeps the tip's mass: fit E on that model
        full_mass = measured is not None
        beam, report = fit_material(beam, args.frequencies, args.elements, modes=args.modes,
                                    fit=tuple(args.fit), mass=args.mass, grading=args.grading,
                                    massless_tip=not full_mass)
        record.update({
            "E": report.values["E"], "rho": report.values["rho"], "fitted": list(report.parameters),
            "initial": report.initial, "modes": report.modes.tolist(),
            "measured_hz": report.measured.tolist(), "model_hz": report.frequencies.tolist(),
            "relative_residuals": report.relative_residuals.tolist(),
            "condition_number": report.condition_number, "identifiable": report.identifiable,
            "relative_std": report.relative_std, "n_elements": args.elements, "grading": args.grading,
            "massless_tip": not full_mass,
            "beam": {k: getattr(beam, k) for k in ("length", "width", "height", "E", "rho", "nu", "gap")},
            "message": report.message, "notes": report.notes})
        texts.append(report.summary())
        ok = ok and report.success and report.identifiable
    if measured is not None:
        if args.model_file:
            model = common.model(args, layer=False)  # the contact keeps its mass: the layer is fitted
            if args.gap is not None:
                model = model.with_gap(args.gap)
        else:
            model = beam.model(args.elements, grading=args.grading, massless_tip=False)
        _, contact = fit_contact_stiffness(model, measured, args.harmonics, initial=args.initial)
        record["contact_layer"] = {
            "stiffness": contact.stiffness, "relative_std": _finite(contact.relative_std),
            "interval_95": [_finite(x) for x in contact.interval],
            "static_stiffness": contact.static_stiffness, "amplitudes_m": contact.amplitudes.tolist(),
            "measured_hz": contact.measured.tolist(), "model_hz": contact.frequencies.tolist(),
            "relative_residuals": contact.relative_residuals.tolist(),
            "sensitivity": contact.sensitivity.tolist(), "identifiable": contact.identifiable,
            "harmonics": contact.harmonics, "method": contact.method, "source": measured.source,
            "message": contact.message, "notes": contact.notes}
        texts.append(contact.summary())
        ok = ok and contact.success
    path = out / "fit.json"
    path.write_text(json.dumps(record, indent=2, allow_nan=True) + "\n")
    text = out / "fit.txt"
    text.write_text("\n\n".join(texts) + "\n")
    print("\n\n".join(texts))
    common.wrote(path, text)
    return 0 if ok else 1


def _finite(x: float):
    return float(x) if math.isfinite(x) else None
