"""``mmshbm study``."""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

from .._method_info import backbone_methods
from .._warnings import MmshbmWarning
from . import common

#: amplitudes (gaps) of the table of a convergence study (f at 2, 5 and 10 gaps)
STUDY_MARKS = (2.0, 5.0, 10.0)


def _chunksize(text: str):
    return "auto" if text == "auto" else common.positive_int(text)


def register(sub) -> None:
    """Add the subcommand to the subparsers ``sub``."""
    p = sub.add_parser("study", help="convergence study over H, elements, methods, parameters")
    common.beam_options(p, elements=False)
    p.add_argument("--figure2", action="store_true",
                   help="Figure 2 of the paper: H 1 3 5 x elements 8 21 (figure2.png, figure2_table.csv)")
    p.add_argument("-H", "--harmonics", type=common.positive_int, nargs="+", default=None,
                   help="values of H (default 1 3 5)")
    p.add_argument("--elements", type=common.positive_int, nargs="+", default=None,
                   help="element counts (default 8 21)")
    p.add_argument("--tol", type=common.positive_float, default=None,
                   help="relative tolerance on the frequency of every point of every run: H chosen per point "
                        "(-H is then the H each run starts from, default 8); the report gives each cell's H "
                        "and the mesh error at the amplitudes (3 element counts or more)")
    p.add_argument("--max-harmonics", type=common.positive_int, default=None,
                   help="with --tol: the largest H of any solve (default 64)")
    p.add_argument("--methods", nargs="+", default=None, choices=backbone_methods(),
                   help="methods (default mmshbm)")
    p.add_argument("--param", action="append", default=None, metavar="NAME=V1,V2",
                   help="a further grid axis: a beam field (gap, E, rho, ...), grading or a backbone option; "
                        "normal_load=N1,N2,... runs the optimal-normal-load study of the beam with a "
                        "friction damper on its tip instead (with mu=, at=, band=LO,HI, force=)")
    p.add_argument("--amplitudes", type=common.positive_float, nargs="+", default=None,
                   help="amplitudes (gaps) of the table (default 2 5 10; 1.5 3 6 with --figure2)")
    p.add_argument("--max-amplitude", type=common.positive_float, default=None,
                   help="largest amplitude, in gaps (default 10)")
    p.add_argument("--max-steps", type=common.positive_int, default=None,
                   help="continuation step budget per run (default 1000); runs that use it up are incomplete")
    p.add_argument("--executor", default=None, choices=["process", "serial", "dask"],
                   help="where runs go (default a local process pool)")
    p.add_argument("--workers", type=common.positive_int, default=2, help="processes (default 2)")
    p.add_argument("--chunksize", type=_chunksize, default="auto",
                   help="runs per task sent to the executor (default auto: 1 for small studies, "
                        "about 16 tasks per worker for large ones)")
    common.measured_option(p)
    p.set_defaults(func=run)


def run(args) -> int:
    params = common.params(args.param)
    if "normal_load" in params:
        from .friction_study import run_normal_load

        return run_normal_load(args, params)
    with warnings.catch_warnings(record=True) as caught:
        # the package's warnings (the runs' checks, a model's truncation, ...) go to the
        # report file, one count on the terminal, every line with -v
        warnings.simplefilter("always", MmshbmWarning)
        study, name, marks, measured = _run_study(args)
        out = common.out_dir(args)
        table = study.table(marks, unit="gap")
        report = study.report(marks, unit="gap")
        accuracy = _accuracy_lines(study, table, marks) if args.tol is not None else []
        if accuracy:
            report += "\n\n" + "\n".join(accuracy)
        files = []

        def write_files():
            files.extend([study.save(out / f"{name}.npz"), table.to_csv(out / f"{name}_table.csv")])

        pictures = _plots(args, study, name, marks, measured, table, out, write_files)
    raised = [w for w in caught if issubclass(w.category, MmshbmWarning)]
    for w in caught:
        if not issubclass(w.category, MmshbmWarning):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    notes = list(dict.fromkeys(f"{w.category.__name__}: {w.message}" for w in raised))
    text = out / f"{name}_table.txt"
    text.write_text(report + ("\n\nWarnings raised while tabulating\n" + "\n".join(notes) if notes else "")
                    + "\n")
    files += [text, *pictures]
    if args.verbose:
        print(report)
        for line in notes:
            print(f"mmshbm study: warning: {line}", file=sys.stderr)
    print(study.findings())
    mesh = next((i for i, s in enumerate(accuracy) if s.startswith("mesh error")), len(accuracy))
    for line in accuracy[:1] + accuracy[mesh:]:  # the counts and the mesh errors; every line in the report
        print(line)
    if args.figure2:
        from .plot import _print_points

        _print_points(study, marks)
    elapsed = study.metadata.get("elapsed_s")
    timing = f"wall time: {len(study)} runs in {elapsed:.1f} s, {study.metadata.get('executor', '?')}; " \
        if elapsed is not None else ""
    more = f"{len(notes)} further warning{'s' * (len(notes) != 1)} and " if notes else ""
    print(f"{timing}{more}the frequency table, convergence and every message: {text}"
          + ("" if args.verbose else " (or -v)"))
    print(f"wrote {out}/: " + ", ".join(str(f.relative_to(out)) if f.is_relative_to(out) else str(f)
                                         for f in map(Path, files)))
    return common.exit_code(study.branches)


def _run_study(args):
    """(study, file stem, table amplitudes, measured backbone) of the options."""
    from ..analysis import studies

    params = common.params(args.param)
    if args.elements:
        from ..methods.limits import check_beam_elements

        check_beam_elements(max(args.elements))  # before any run assembles a model
    measured = common.measured(args)
    marks = common.DEFAULT_MARKS if args.figure2 else STUDY_MARKS
    marks = tuple(args.amplitudes) if args.amplitudes else marks
    executor = None if args.executor == "serial" else (args.executor or "process")
    # the workers tabulate their runs for the table written below (Study.table); this
    # process imports the plots meanwhile
    shared = {"executor": executor, "workers": args.workers, "chunksize": args.chunksize,
              "verbose": common.progress(args), "warn": False, "tabulate": (marks, "gap"),
              "while_running": _import_plots}
    if args.max_amplitude is not None:
        shared.update(max_amplitude=args.max_amplitude, unit="gap")
    if args.max_steps is not None:
        shared["max_steps"] = args.max_steps
    if args.tol is not None:
        shared["tol"] = args.tol
        if args.max_harmonics is not None:
            shared["max_harmonics"] = args.max_harmonics
    elif args.max_harmonics is not None:
        raise ValueError("--max-harmonics bounds H with --tol: pass --tol too")
    beam = common.beam(args)
    if args.figure2:
        if args.harmonics or args.elements or args.methods or params or args.model_file:
            raise ValueError("--figure2 fixes the grid (H 1 3 5, elements 8 21, mmshbm): drop -H, "
                             "--elements, --methods, --param and --model-file")
        study = studies.figure2_study(beam, grading=args.grading, **shared)
        name = "figure2"
    else:
        grid = {"harmonics": args.harmonics or ((8,) if args.tol is not None else (1, 3, 5)),
                "methods": args.methods or ("mmshbm",),
                "params": params}
        if args.model_file:
            if args.elements:
                raise ValueError("--elements applies to the beam, not to --model-file")
            study = studies.run_study(model=common.model_source(args), **grid, **shared)
        else:
            study = studies.run_study(beam, elements=args.elements or (8, 21), grading=args.grading, **grid,
                                      **shared)
        name = "study"
    return study, name, marks, measured


def _plots(args, study, name, marks, measured, table, out, write_files) -> list:
    """Write the files (``write_files``) and draw the figures; returns the figures' paths."""
    png = out / f"{name}.png"
    files = [png]
    if not args.figure2 and common.has_grid(study):
        from ..plotting import plot_convergence
        from ._plot_worker import draw_forked

        # the family grid in a forked child; the files and the convergence plot here meanwhile
        files.append(out / f"{name}_convergence.png")

        def here():
            write_files()
            plot_convergence(study, amplitudes=marks, table=table, path=files[-1])

        draw_forked([("plot_family_grid", (study,), {"amplitudes": marks, "path": png})], here=here)
        return files
    write_files()
    from ..plotting import plot_figure2, plot_study

    if args.figure2:
        plot_figure2(study, marks=marks, measured=measured, path=png)
    else:
        plot_study(study, measured=measured, path=png)
    return files


def _import_plots() -> None:
    """Import matplotlib and the study plots (~0.3 s)."""
    from ..plotting import grids, studies  # noqa: F401


def _accuracy_lines(study, table, marks) -> list[str]:
    """The tolerance lines of a study run with --tol: each run's summary, the H of each
    cell, and the mesh error at the amplitudes."""
    from ..analysis.study_tolerance import cell_harmonics, mesh_error_lines, tolerance_lines

    lines = tolerance_lines(study)
    H = cell_harmonics(study, marks, "gap")
    lines.append("H chosen by the tolerance at " + ", ".join(f"{a:g}" for a in marks)
                 + " gaps (-1: not reached)")
    lines += [f"  {', '.join(f'{k}={v}' for k, v in c.items())}: {' '.join(str(h) for h in row)}"
              for c, row in zip(study.runs, H, strict=True)]
    mesh = mesh_error_lines(table, study=study)
    lines.append("mesh error at the amplitudes:"
                 + ("" if mesh else " needs 3 element counts or more (--elements)"))
    return lines + mesh
