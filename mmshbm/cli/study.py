"""``mmshbm study``."""

from __future__ import annotations

from . import common


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
    p.add_argument("--methods", nargs="+", default=None, choices=["mmshbm", "penalty", "shooting"],
                   help="methods (default mmshbm)")
    p.add_argument("--param", action="append", default=None, metavar="NAME=V1,V2",
                   help="a further grid axis: a beam field (gap, E, rho, ...), grading or a backbone option")
    p.add_argument("--amplitudes", type=common.positive_float, nargs="+", default=None,
                   help="amplitudes (gaps) of the table and the marked points (default 1.5 3 6)")
    p.add_argument("--max-amplitude", type=common.positive_float, default=None,
                   help="largest amplitude, in gaps (default 10)")
    p.add_argument("--max-steps", type=common.positive_int, default=None,
                   help="continuation step budget per run (default 1000); runs that use it up are incomplete")
    p.add_argument("--executor", default="process", choices=["process", "serial", "dask"],
                   help="where runs go (default a local process pool)")
    p.add_argument("--workers", type=common.positive_int, default=2, help="processes (default 2)")
    p.add_argument("--measured", default=None, help="measured backbone CSV to overlay")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..analysis import studies
    from ..plotting import plot_figure2, plot_study

    params = common.params(args.param)
    if args.elements:
        from ..methods.limits import check_beam_elements

        check_beam_elements(max(args.elements))  # before any run assembles a model
    measured = common.measured(args)
    marks = tuple(args.amplitudes) if args.amplitudes else common.DEFAULT_MARKS
    executor = None if args.executor == "serial" else args.executor
    shared = {"executor": executor, "workers": args.workers, "verbose": common.progress(args)}
    if args.max_amplitude is not None:
        shared.update(max_amplitude=args.max_amplitude, unit="gap")
    if args.max_steps is not None:
        shared["max_steps"] = args.max_steps
    beam = common.beam(args)
    if args.figure2:
        if args.harmonics or args.elements or args.methods or params or args.model_file:
            raise ValueError("--figure2 fixes the grid (H 1 3 5, elements 8 21, mmshbm): drop -H, "
                             "--elements, --methods, --param and --model-file")
        study = studies.figure2_study(beam, grading=args.grading, **shared)
        name = "figure2"
    else:
        grid = {"harmonics": args.harmonics or (1, 3, 5), "methods": args.methods or ("mmshbm",),
                "params": params}
        if args.model_file:
            if args.elements:
                raise ValueError("--elements applies to the beam, not to --model-file")
            study = studies.run_study(model=args.model_file, **grid, **shared)
        else:
            study = studies.run_study(beam, elements=args.elements or (8, 21), grading=args.grading, **grid,
                                      **shared)
        name = "study"
    out = common.out_dir(args)
    table = study.table(marks, unit="gap")
    report = study.report(marks, unit="gap")
    files = [study.save(out / f"{name}.npz"), table.to_csv(out / f"{name}_table.csv")]
    text = out / f"{name}_table.txt"
    text.write_text(report + "\n")
    files.append(text)
    png = out / f"{name}.png"
    if args.figure2 or common.has_grid(study):
        plot_figure2(study, marks=marks, measured=measured, path=png)
    else:
        plot_study(study, measured=measured, path=png)
    files.append(png)
    print(report)
    print(repr(study))
    common.wrote(*files)
    return common.exit_code(study.branches)
