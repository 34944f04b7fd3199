"""``mmshbm frf``: forced response of the default beam (or a model file), with stability."""

from __future__ import annotations

from .._method_info import forced_methods, is_harmonic_balance
from . import common


def register(sub) -> None:
    """Add the subcommand to the subparsers ``sub``."""
    p = sub.add_parser("frf", help="forced response (damped, harmonic force): frf.csv/.npz/.png",
                       description="Frequency response of a damped structure with impact by MMS-HBM (or a "
                                   "baseline), continued through folds, stable parts solid and unstable "
                                   "dashed. Default: the default beam with 0.5 % modal damping, a force at "
                                   "the last node with mass.")
    common.beam_options(p)
    p.add_argument("-H", "--harmonics", type=common.positive_int, default=None,
                   help="harmonics (default 5); not with --tol")
    p.add_argument("--tol", type=common.positive_float, default=None,
                   help="relative tolerance on every point's amplitude at its frequency (on its frequency "
                        "near folds): H chosen per point from an error estimate (docs/accuracy.md) instead "
                        "of a fixed -H")
    p.add_argument("--max-harmonics", type=common.positive_int, default=None,
                   help="with --tol: the largest H of any solve (default 64)")
    p.add_argument("--method", default="mmshbm", choices=forced_methods(),
                   help="MMS-HBM, or a baseline on the same forced problem: penalty harmonic balance or "
                        "time-domain shooting (default mmshbm)")
    p.add_argument("--damping", type=common.non_negative_float, default=0.005,
                   help="modal damping ratio of every mode (default 0.005)")
    p.add_argument("--rayleigh", type=common.non_negative_float, nargs=2, default=None,
                   metavar=("ALPHA", "BETA"),
                   help="Rayleigh damping alpha (1/s) and beta (s) instead of --damping")
    p.add_argument("--force", type=common.positive_float, default=2.3,
                   help="force amplitude (N) (default 2.3)")
    p.add_argument("--force-dof", type=common.non_negative_int, default=None,
                   help="DOF the force acts on (default: the last DOF with mass before the contact DOF)")
    p.add_argument("--base-acceleration", type=common.positive_float, default=None, metavar="A",
                   help="excite the support instead: acceleration amplitude (m/s^2) (beam models)")
    p.add_argument("--range", type=common.positive_float, nargs=2, default=(40.0, 60.0), metavar=("F0", "F1"),
                   help="excitation frequency range in Hz (default 40 60)")
    p.add_argument("--max-steps", type=common.positive_int, default=None, help="continuation step budget")
    p.add_argument("--phase-resonance", action="store_true",
                   help="also the phase-resonance backbone with the damped (EPMC) and conservative backbones "
                        "(phase_resonance.png/.csv)")
    p.add_argument("--max-amplitude", type=common.positive_float, default=6.0,
                   help="phase resonance: in gaps (default 6)")
    common.measured_option(p)
    p.set_defaults(func=run)


def run(args) -> int:
    from ..methods.frequency_response import frequency_response
    from ..methods.mms.forced import base_excitation
    from ..plotting.response import plot_frequency_response, plot_phase_resonance

    measured = common.measured(args)
    if (args.damping == 0) if args.rayleigh is None else not any(args.rayleigh):
        raise ValueError("a forced response needs damping (without it the response grows along the backbone "
                         "without bound): give --damping > 0 or --rayleigh, or compute the conservative "
                         "backbone with mmshbm backbone")
    model = common.model(args)
    if args.rayleigh is not None:
        model = model.with_damping(rayleigh=tuple(args.rayleigh))
    else:
        model = model.with_damping(modal_ratio=args.damping)
    if args.base_acceleration is not None:
        force = base_excitation(model, "transverse", acceleration=args.base_acceleration)
    else:
        dof = args.force_dof
        if dof is None:
            # the beam: the deflection of the last node with mass (its DOFs are (w, θ) pairs)
            with_mass = model.l[model.l < model.amplitude_dof]
            beam = model.description.get("kind") == "TimoshenkoBeam"
            dof = int(with_mass[-2] if beam and len(with_mass) > 1 else model.l[-1])
        if not 0 <= dof < model.n_dof:
            raise ValueError(f"--force-dof must be in [0, {model.n_dof - 1}], got {dof}")
        import numpy as np

        force = np.zeros(model.n_dof)
        force[dof] = args.force
    extra = {} if args.max_steps is None else {"max_steps": args.max_steps}
    options = _accuracy(args)
    resp = frequency_response(model, force, tuple(args.range), method=args.method,
                              verbose=common.progress(args), **options, **extra)
    out = common.out_dir(args)
    files = [resp.to_csv(out / "frf.csv"), resp.save(out / "frf.npz")]
    if len(resp):
        files.append(out / "frf.png")
        plot_frequency_response(resp, measured=measured, path=files[-1])
    print(repr(resp))
    if args.tol is not None:
        from ..results.response_tolerance import response_tolerance_summary

        print(response_tolerance_summary(resp))
        for f in resp.findings:
            print(f"mmshbm frf: {f.kind}: {f.message}")
    if args.phase_resonance:
        from ..analysis.phase_resonance import compare_backbones
        from .backbone import gaps_in_m

        both = compare_backbones(model, force, harmonics=5 if args.harmonics is None else args.harmonics,
                                 max_amplitude=gaps_in_m(args.max_amplitude, model))
        pr = both["phase_resonance"]
        files += [pr.to_csv(out / "phase_resonance.csv"), out / "phase_resonance.png"]
        plot_phase_resonance(pr, both["epmc"], both["conservative"], measured=measured, path=files[-1])
        print(repr(pr))
    common.wrote(*files)
    return 0 if resp.completed else 1


def _accuracy(args) -> dict:
    """The H options of the run: a fixed -H, or --tol (with --max-harmonics)."""
    if args.tol is not None:
        if args.harmonics is not None:
            raise ValueError(f"pass either -H {args.harmonics} (a fixed H) or --tol {args.tol:g} (H chosen "
                             "to meet it), not both")
        cap = {} if args.max_harmonics is None else {"max_harmonics": args.max_harmonics}
        return {"tol": args.tol, **cap}
    if args.max_harmonics is not None:
        raise ValueError("--max-harmonics bounds H with --tol: pass --tol too, or a fixed -H")
    if not is_harmonic_balance(args.method):
        return {}
    return {"harmonics": 5 if args.harmonics is None else args.harmonics}
