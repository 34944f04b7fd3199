"""Command line: ``mmshbm modes | backbone | study | fit | bench | plot``.

Every subcommand writes its files into ``--out`` (default ``out/``) and prints one line
per file written. Bad input becomes a one-line message on stderr and exit code 2, never
a traceback; a branch that stops before its bounds gives exit code 1.

Examples::

    mmshbm backbone                        # default beam, 21 elements, H = 5
    mmshbm backbone -H 3 --elements 8 --measured measured.csv
    mmshbm study --figure2                 # the seed's Figure 2 and its table
    mmshbm study -H 1 3 5 7 --elements 8 21 --param gap=0.001,0.002
    mmshbm fit 45.8 286.5 --fit E          # Young's modulus from measured frequencies
    mmshbm plot out/backbone.npz --points 1.5 3 6
    mmshbm bench --quick
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
from pathlib import Path

from . import __version__

log = logging.getLogger("mmshbm")

#: exceptions that mean bad input or a failed run: one line on stderr, exit code 2
_USER_ERRORS = (ValueError, TypeError, OSError, KeyError, IndexError, RuntimeError, ImportError)
#: amplitudes (gaps) of the marked points and table columns
_DEFAULT_MARKS = (1.5, 3.0, 6.0)


class _Usage(Exception):
    """A command-line usage error (raised instead of argparse's exit)."""


class _StderrHandler(logging.StreamHandler):
    """Writes to the current ``sys.stderr`` (which tests and notebooks may swap)."""

    def emit(self, record):
        self.stream = sys.stderr
        super().emit(record)


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, no usage dump
        raise _Usage(f"{self.prog}: error: {message}")


def _out(args) -> Path:
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    return out


def _wrote(*paths) -> None:
    for p in paths:
        print(f"wrote {p}")


def _measured(args):
    """The measured backbone of ``--measured``, read before any computation (None without)."""
    if not getattr(args, "measured", None):
        return None
    from .analysis.measured import load_measured

    return load_measured(args.measured)


def _progress(args) -> bool:
    """Progress bars only with -v and on a terminal."""
    return args.verbose > 0 and sys.stderr.isatty()


# ---------------------------------------------------------------------- models
def _beam(args):
    from dataclasses import replace

    from .fe.beam import default_beam

    beam = default_beam()
    changes = {k: v for k, v in (("gap", args.gap), ("E", args.E), ("rho", args.rho)) if v is not None}
    return replace(beam, **changes) if changes else beam


def _model(args):
    if getattr(args, "model_file", None):
        from .model.model import Model

        model = Model.from_npz(args.model_file)
        return model.with_gap(args.gap) if args.gap is not None else model
    return _beam(args).model(args.elements, grading=args.grading)


# ---------------------------------------------------------------------- commands
def cmd_modes(args) -> int:
    model = _model(args)
    freqs = model.linear_frequencies(args.n)
    path = _out(args) / "modes.csv"
    path.write_text("mode,frequency_hz\n" + "".join(f"{i + 1},{f:.10g}\n" for i, f in enumerate(freqs)))
    for i, f in enumerate(freqs):
        print(f"mode {i + 1}: {f:.4f} Hz")
    _wrote(path)
    return 0


def cmd_backbone(args) -> int:
    from .methods.backbone import backbone
    from .plotting import plot_backbone, plot_frequency_energy

    measured = _measured(args)
    model = _model(args)
    max_amp = args.max_amplitude * model.gap if args.max_amplitude else None
    extra = {}
    if args.checkpoint:
        Path(args.checkpoint).parent.mkdir(parents=True, exist_ok=True)
        extra["checkpoint"] = args.checkpoint
    if args.resume:
        extra["resume"] = args.resume
    if args.max_steps is not None:
        extra["max_steps"] = args.max_steps
    branch = backbone(model, harmonics=args.harmonics, method=args.method, max_amplitude=max_amp,
                      verbose=_progress(args), **extra)
    out = _out(args)
    files = [branch.to_csv(out / "backbone.csv"), branch.save(out / "backbone.npz")]
    if len(branch):
        files += [out / "backbone.png", out / "frequency_energy.png"]
        plot_backbone(branch, measured=measured, model=model, path=files[-2])
        plot_frequency_energy(branch, path=files[-1])
    print(repr(branch))
    _wrote(*files)
    return 0 if branch.completed else 1


def cmd_study(args) -> int:
    from .analysis import studies
    from .plotting import plot_backbone, plot_figure2

    params = _params(args.param)
    measured = _measured(args)
    marks = tuple(args.amplitudes) if args.amplitudes else _DEFAULT_MARKS
    executor = None if args.executor == "serial" else args.executor
    common = {"executor": executor, "workers": args.workers, "verbose": _progress(args)}
    if args.max_amplitude is not None:
        common.update(max_amplitude=args.max_amplitude, unit="gap")
    beam = _beam(args)
    if args.figure2:
        if args.harmonics or args.elements or args.methods or params or args.model_file:
            raise ValueError("--figure2 fixes the grid (H 1 3 5, elements 8 21, mmshbm): drop -H, "
                             "--elements, --methods, --param and --model-file")
        study = studies.figure2_study(beam, grading=args.grading, **common)
        name = "figure2"
    else:
        grid = {"harmonics": args.harmonics or (1, 3, 5), "methods": args.methods or ("mmshbm",),
                "params": params}
        if args.model_file:
            if args.elements:
                raise ValueError("--elements applies to the beam, not to --model-file")
            study = studies.run_study(model=args.model_file, **grid, **common)
        else:
            study = studies.run_study(beam, elements=args.elements or (8, 21), grading=args.grading, **grid,
                                      **common)
        name = "study"
    out = _out(args)
    table = study.table(marks, unit="gap")
    report = study.report(marks, unit="gap")
    files = [study.save(out / f"{name}.npz"), table.to_csv(out / f"{name}_table.csv")]
    text = out / f"{name}_table.txt"
    text.write_text(report + "\n")
    files.append(text)
    png = out / f"{name}.png"
    if args.figure2 or _has_grid(study):
        plot_figure2(study, marks=marks, measured=measured, path=png)
    else:
        plot_backbone(study.branches, measured=measured, path=png)
    files.append(png)
    print(report)
    print(repr(study))
    _wrote(*files)
    return 0 if all(b.completed for b in study.branches) else 1


def _has_grid(study) -> bool:
    return all("harmonics" in r and "elements" in r for r in study.runs) and \
        len({r.get("method") for r in study.runs}) == 1 and len(study.axes) == 3


def _params(items) -> dict:
    """``["gap=0.001,0.002", "E=2e11"]`` -> ``{"gap": [0.001, 0.002], "E": [2e11]}``."""
    out = {}
    for item in items or ():
        name, sep, values = item.partition("=")
        if not sep or not name.strip() or not values.strip():
            raise ValueError(f"--param takes NAME=V1,V2,..., got {item!r}")
        parsed = []
        for v in values.split(","):
            v = v.strip()
            try:
                parsed.append(int(v) if v.lstrip("+-").isdigit() else float(v))
            except ValueError:
                parsed.append(v)
        out[name.strip()] = parsed
    return out


def cmd_fit(args) -> int:
    from .analysis.identification import fit_material

    beam = _beam(args)
    fitted, report = fit_material(beam, args.frequencies, args.elements, modes=args.modes,
                                  fit=tuple(args.fit), mass=args.mass, grading=args.grading)
    out = _out(args)
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
    _wrote(path, text)
    return 0 if report.success else 1


def cmd_bench(args) -> int:
    try:
        from .analysis import benchmarking
    except ImportError as err:
        raise ValueError(f"benchmarking is not available: {err}") from None
    kwargs = {"model": args.model, "quick": args.quick}
    if args.target is not None:
        kwargs["target"] = args.target
    if args.methods:
        kwargs["methods"] = tuple(args.methods)
    if args.repeats is not None:
        kwargs["repeats"] = args.repeats
    if args.amplitude is not None:
        kwargs["amplitude_gaps"] = args.amplitude
    rows = benchmarking.compare_methods(**kwargs)
    print(benchmarking.format_table(rows))
    _wrote(*benchmarking.write_results(rows, _out(args)))
    return 0


def cmd_plot(args) -> int:
    from . import plotting
    from .io import load
    from .results.branch import Branch

    data = load(args.file)
    measured = _measured(args)
    out = _out(args)
    stem = Path(args.file).stem
    kinds = set(args.kind)
    if "all" in kinds:
        kinds = {"backbone", "energy", "peak_force", "signals", "force", "harmonics"}
    marks = tuple(args.points) if args.points else _DEFAULT_MARKS
    files = []
    if not isinstance(data, Branch):  # a study
        if "backbone" in kinds:
            path = out / f"{stem}_backbone.png"
            if _has_grid(data):
                plotting.plot_figure2(data, marks=marks, measured=measured, path=path)
            else:
                plotting.plot_backbone(data.branches, measured=measured, path=path)
            files.append(path)
        styles = plotting.study_styles(data.runs)
        if "energy" in kinds:
            files.append(out / f"{stem}_energy.png")
            plotting.plot_frequency_energy(data.branches, styles=styles, path=files[-1])
        if "peak_force" in kinds:
            files.append(out / f"{stem}_peak_force.png")
            plotting.plot_peak_contact_force(data.branches, measured=measured, styles=styles, path=files[-1])
        _wrote(*files)
        return 0
    branch = data
    if not len(branch):
        raise ValueError(f"{args.file}: the branch has no points")
    gap = plotting._gap(branch)
    pts = plotting.points_at(branch, [m * gap for m in marks]) if gap > 0 else [len(branch) - 1]
    if "backbone" in kinds:
        files.append(out / f"{stem}_backbone.png")
        plotting.plot_backbone(branch, measured=measured, marks=[(0, p) for p in pts], path=files[-1])
    if "energy" in kinds:
        files.append(out / f"{stem}_energy.png")
        plotting.plot_frequency_energy(branch, path=files[-1])
    if "peak_force" in kinds:
        files.append(out / f"{stem}_peak_force.png")
        plotting.plot_peak_contact_force(branch, measured=measured, path=files[-1])
    if "signals" in kinds:
        files.append(out / f"{stem}_signals.png")
        plotting.plot_time_signals(branch, pts, path=files[-1])
    if "force" in kinds:
        files.append(out / f"{stem}_contact_force.png")
        plotting.plot_contact_force(branch, pts, path=files[-1])
    if "harmonics" in kinds:
        files.append(out / f"{stem}_harmonics.png")
        plotting.plot_harmonic_content(branch, pts[-1], path=files[-1])
    _wrote(*files)
    return 0


# ---------------------------------------------------------------------- parser
def build_parser() -> argparse.ArgumentParser:
    """The ``mmshbm`` argument parser."""
    parser = _Parser(prog="mmshbm", description=__doc__.splitlines()[0],
                     formatter_class=argparse.RawDescriptionHelpFormatter,
                     epilog="\n".join(__doc__.splitlines()[6:]))
    parser.add_argument("--version", action="version", version=f"mmshbm {__version__}")
    parser.add_argument("-v", "--verbose", action="count", default=0,
                        help="more output: -v progress bars (on a terminal) and info logs, -vv debug logs")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    def out_option(p):
        p.add_argument("--out", default="out", help="output folder (default ./out)")

    def beam_options(p, elements=True, model_file=True):
        if elements:
            p.add_argument("--elements", type=int, default=21, help="beam elements (default 21)")
        p.add_argument("--grading", type=float, default=10.0, help="root/tip element length ratio")
        p.add_argument("--gap", type=float, default=None, help="gap (m) (default: the beam's, 1 mm)")
        p.add_argument("--E", type=float, default=None, help="Young's modulus (Pa) (default 210e9)")
        p.add_argument("--rho", type=float, default=None, help="density (kg/m^3) (default 7850)")
        if model_file:
            p.add_argument("--model-file", default=None,
                           help="a user model (.npz of Model.save_npz) instead of the beam")
        out_option(p)

    p = sub.add_parser("modes", help="linear frequencies (contact open)")
    beam_options(p)
    p.add_argument("-n", type=int, default=3, help="number of modes (default 3)")
    p.set_defaults(func=cmd_modes)

    p = sub.add_parser("backbone", help="first nonlinear mode: backbone.csv/.npz/.png")
    beam_options(p)
    p.add_argument("-H", "--harmonics", type=int, default=5, help="harmonics (default 5)")
    p.add_argument("--method", default="mmshbm", choices=["mmshbm", "penalty", "shooting"])
    p.add_argument("--max-amplitude", type=float, default=None, help="in gaps (default 10)")
    p.add_argument("--max-steps", type=int, default=None, help="continuation step budget")
    p.add_argument("--measured", default=None, help="measured backbone CSV to overlay")
    p.add_argument("--checkpoint", default=None, metavar="FILE",
                   help="write converged points to FILE as they go")
    p.add_argument("--resume", default=None, metavar="FILE", help="continue from a checkpoint FILE")
    p.set_defaults(func=cmd_backbone)

    p = sub.add_parser("study", help="convergence study over H, elements, methods, parameters")
    beam_options(p, elements=False)
    p.add_argument("--figure2", action="store_true",
                   help="the seed's Figure 2: H 1 3 5 x elements 8 21 (figure2.png, figure2_table.csv)")
    p.add_argument("-H", "--harmonics", type=int, nargs="+", default=None, help="values of H (default 1 3 5)")
    p.add_argument("--elements", type=int, nargs="+", default=None, help="element counts (default 8 21)")
    p.add_argument("--methods", nargs="+", default=None, choices=["mmshbm", "penalty", "shooting"])
    p.add_argument("--param", action="append", default=None, metavar="NAME=V1,V2",
                   help="a further grid axis: a beam field (gap, E, rho, ...), grading or a backbone option")
    p.add_argument("--amplitudes", type=float, nargs="+", default=None,
                   help="amplitudes (gaps) of the table and the marked points (default 1.5 3 6)")
    p.add_argument("--max-amplitude", type=float, default=None, help="in gaps (default 10)")
    p.add_argument("--executor", default="process", choices=["process", "serial", "dask"],
                   help="where runs go (default a local process pool)")
    p.add_argument("--workers", type=int, default=2, help="processes (default 2)")
    p.add_argument("--measured", default=None, help="measured backbone CSV to overlay")
    p.set_defaults(func=cmd_study)

    p = sub.add_parser("fit", help="Young's modulus (and density) from measured linear frequencies")
    beam_options(p, model_file=False)
    p.add_argument("frequencies", type=float, nargs="+", help="measured frequencies (Hz)")
    p.add_argument("--modes", type=int, nargs="+", default=None,
                   help="their mode numbers (default 1 2 ...)")
    p.add_argument("--fit", nargs="+", default=["E"], choices=["E", "rho"], help="parameters (default E)")
    p.add_argument("--mass", type=float, default=None, help="measured beam mass (kg), to fit E and rho")
    p.set_defaults(func=cmd_fit)

    p = sub.add_parser("bench", help="MMS-HBM against penalty-HBM and shooting at equal accuracy")
    out_option(p)
    p.add_argument("--quick", action="store_true", help="a fast, rough run")
    p.add_argument("--model", default="beam21", choices=["beam21", "beam8", "oscillator"])
    p.add_argument("--target", type=float, default=None, help="relative frequency accuracy (default 1e-4)")
    p.add_argument("--methods", nargs="+", default=None, choices=["mmshbm", "penalty", "shooting"])
    p.add_argument("--repeats", type=int, default=None, help="timing repeats")
    p.add_argument("--amplitude", type=float, default=None, help="amplitude (gaps) compared at (default 2)")
    p.set_defaults(func=cmd_bench)

    p = sub.add_parser("plot", help="plots of a saved branch or study (.npz)")
    out_option(p)
    p.add_argument("file", help="a .npz written by Branch.save / Study.save (backbone, study)")
    p.add_argument("--kind", nargs="+", default=["all"],
                   choices=["all", "backbone", "energy", "peak_force", "signals", "force", "harmonics"])
    p.add_argument("--points", type=float, nargs="+", default=None,
                   help="amplitudes (gaps) of the marked points (default 1.5 3 6)")
    p.add_argument("--measured", default=None, help="measured backbone CSV to overlay")
    p.set_defaults(func=cmd_plot)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line with ``argv`` (default ``sys.argv[1:]``); returns the exit code."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except _Usage as err:
        print(f"{err} (see mmshbm -h)", file=sys.stderr)
        return 2
    except SystemExit as err:  # --help, --version
        return int(err.code or 0)
    level = logging.WARNING - 10 * min(args.verbose, 2)
    root = logging.getLogger("mmshbm")
    if not any(isinstance(h, _StderrHandler) for h in root.handlers):
        handler = _StderrHandler()
        handler.setFormatter(logging.Formatter("%(name)s: %(message)s"))
        root.addHandler(handler)
    root.setLevel(level)
    try:
        return args.func(args)
    except _USER_ERRORS as err:
        message = str(err).splitlines()[0] if str(err) else type(err).__name__
        print(f"mmshbm {args.command}: error: {message}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("mmshbm: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
