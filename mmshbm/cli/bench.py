"""``mmshbm bench``."""

from __future__ import annotations

from . import common


def register(sub) -> None:
    """Add the subcommand to the subparsers ``sub``."""
    p = sub.add_parser("bench", help="MMS-HBM against penalty-HBM and shooting at equal accuracy")
    common.out_option(p)
    p.add_argument("--quick", action="store_true", help="a fast, rough run")
    p.add_argument("--model", default="beam21", choices=["beam21", "beam8", "oscillator"],
                   help="the benchmark model")
    p.add_argument("--target", type=common.positive_float, default=None,
                   help="relative frequency accuracy (default 1e-4)")
    p.add_argument("--methods", nargs="+", default=None, choices=["mmshbm", "penalty", "shooting"],
                   help="methods (default all three)")
    p.add_argument("--repeats", type=common.positive_int, default=None, help="timing repeats (default 3)")
    p.add_argument("--amplitude", type=common.positive_float, default=None,
                   help="amplitude (gaps) compared at (default: oscillator 2, beam 1.5)")
    p.add_argument("--from-asv", nargs="?", const="", default=None, metavar="RESULTS",
                   help="print the tables of a recorded asv run instead (a results file or folder, default "
                        ".asv/results and the committed benchmarks/results: the newest run with the "
                        "bench_goals figures)")
    p.add_argument("--update", nargs="+", default=None, metavar="FILE",
                   help="with --from-asv: write the tables into FILEs (docs/validation.md "
                        "docs/benchmarks.md) between their generated-block markers")
    p.add_argument("--corpus", type=common.positive_int, default=None, metavar="N",
                   help="run the default backbone on N random models (mmshbm.analysis.corpus: chains, "
                        "trees, beams; one-sided, clearance, several contacts) and tabulate completion, "
                        "failures and times instead")
    p.add_argument("--corpus-exact", type=common.positive_int, default=None, metavar="N",
                   help="compare the default backbone with the exact single-contact orbit on N random "
                        "chains of 1-4 masses (mmshbm.analysis.corpus_exact: gap 1 cm, 1.3 gaps, H = 31) "
                        "and report agreement and why each miss differs instead")
    p.add_argument("--contact-decades", type=common.finite_float, nargs=2, default=None, metavar=("LO", "HI"),
                   help="with --corpus-exact: draw the contact spring as 10**U(LO, HI) N/m (default: the "
                        "corpus's, up to 100 times stiffer than the other springs)")
    p.add_argument("--proximal", choices=("static", "residual"), default="static",
                   help="with --corpus or --corpus-exact: the MMS-HBM proximal parameter r (default static: "
                        "the contact DOFs' static stiffness; residual: the compliance of the modes above the "
                        "truncation frequency, docs/exact.md)")
    p.add_argument("--seed", type=common.non_negative_int, default=0,
                   help="with --corpus or --corpus-exact: the corpus seed (default 0)")
    p.add_argument("--compare-path", action="store_true",
                   help="with --corpus: also follow each branch plainly and check that the default gives the "
                        "same branch wherever that one reaches the bound without a tongue")
    p.add_argument("--time-limit", type=common.positive_float, default=30.0,
                   help="with --corpus: seconds per model before it is interrupted (default 30)")
    p.add_argument("--workers", type=common.positive_int, default=1,
                   help="with --corpus: processes (default 1)")
    p.set_defaults(func=run)


def _from_asv(args) -> int:
    from ..analysis import asv_tables

    run = asv_tables.load_run(args.from_asv or None)
    block = asv_tables.tables(run)
    print(block)
    for path in args.update or ():
        changed = asv_tables.update_file(path, block)
        print(f"{'updated' if changed else 'unchanged'} {path}")
    return 0


def _options(args) -> dict:
    """The backbone options the corpus runs take from the command line."""
    return {} if args.proximal == "static" else {"r": args.proximal}


def _corpus(args) -> int:
    """The corpus run: one line per model as it ends, then the summary; writes
    corpus.csv. Exit 1 when a model raised."""
    import csv

    from ..analysis import corpus

    cases = corpus.generate(args.corpus, args.seed)

    def progress(r):
        print(f"{r.case.label:<34} {r.seconds:7.2f} s  {'ok ' if r.completed else 'NOT'} {r.status[:90]}",
              flush=True)

    results = corpus.run_corpus(cases, workers=args.workers, progress=progress, time_limit=args.time_limit,
                                compare_path=args.compare_path, options=_options(args))
    print(corpus.summary(results))
    path = common.out_dir(args) / "corpus.csv"
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["index", "seed", "kind", "contact", "harmonics", "completed", "status", "seconds",
                    "points", "jumps", "frequency", "path_completed", "same_as_path", "cpu_seconds"])
        for r in results:
            w.writerow([r.case.index, r.case.seed, r.case.kind, r.case.contact, r.case.harmonics,
                        int(r.completed), r.status, f"{r.seconds:.4f}", r.points, r.jumps, repr(r.frequency),
                        r.path_completed, r.same_as_path, f"{r.cpu_seconds:.4f}"])
    common.wrote(path)
    return 1 if any(r.status.startswith("exception") for r in results) else 0


def _corpus_exact(args) -> int:
    """The exact comparison: one line per chain as it ends, then the report; writes
    corpus_exact.csv. Exit 1 when a clean case misses without the branch saying why."""
    import csv

    from ..analysis import corpus_exact

    if args.contact_decades and not args.contact_decades[0] < args.contact_decades[1]:
        raise ValueError(f"--contact-decades: LO must be below HI, got {args.contact_decades}")
    cases = corpus_exact.chains(args.corpus_exact, seed=args.seed,
                                contact_decades=tuple(args.contact_decades) if args.contact_decades else None)
    results = []
    for case in cases:
        r = corpus_exact.compare(case, options=_options(args))
        results.append(r)
        print(f"{corpus_exact.name(case):<34} {r.seconds:7.2f} s  {'clean' if r.clean else 'not clean':9} "
              f"error {r.error:.2e}  {r.status[:60]}", flush=True)
    print(corpus_exact.report(results))
    path = common.out_dir(args) / "corpus_exact.csv"
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["index", "seed", "clean", "exact_hz", "branch_hz", "error", "error_2h", "continued_hz",
                    "first_mode", "estimate", "reasons", "status", "seconds", "exact_share",
                    "continued_share", "branch_orbit_hz", "branch_orbit_share", "proximal",
                    "contact_decades"])
        decades = " ".join(f"{x:g}" for x in args.contact_decades) if args.contact_decades else ""
        for r in results:
            w.writerow([r.case.index, r.case.seed, int(r.clean), repr(r.exact), repr(r.branch),
                        f"{r.error:.3e}", f"{r.error_2h:.3e}", repr(r.continued), int(r.first_mode),
                        f"{r.estimate:.3e}",
                        "; ".join(r.reasons()), r.status, f"{r.seconds:.3f}", f"{r.exact_share:.4f}",
                        f"{r.continued_share:.4f}", repr(r.family_exact), f"{r.family_share:.4f}",
                        args.proximal, decades])
    common.wrote(path)
    unexplained = [r for r in results if r.clean and not r.first_mode and not r.explained]
    return 1 if unexplained else 0


def run(args) -> int:
    if args.corpus_exact is not None:
        return _corpus_exact(args)
    if args.corpus is not None:
        return _corpus(args)
    if args.from_asv is not None:
        return _from_asv(args)
    if args.update:
        raise ValueError("--update needs --from-asv")
    try:
        from ..analysis import benchmarking
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
    import warnings

    from .._warnings import BranchWarning

    with warnings.catch_warnings(record=True) as caught:  # the tuning runs many backbones: one line each
        warnings.simplefilter("always", BranchWarning)
        rows = benchmarking.compare_methods(**kwargs)
    seen: dict[str, int] = {}
    for w in caught:
        if issubclass(w.category, BranchWarning):
            seen[str(w.message)] = seen.get(str(w.message), 0) + 1
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    for message, count in seen.items():
        warnings.warn(message + (f" ({count} runs)" if count > 1 else ""), BranchWarning, stacklevel=2)
    print(benchmarking.format_table(rows))
    common.wrote(*benchmarking.write_results(rows, common.out_dir(args)))
    return 0
