"""``python -m validation``: the runs of docs/validation.md and the one command that
writes their tables.

    python -m validation corpus N [--seed S] [--compare-path] [--workers W] [--out DIR]
    python -m validation exact N [--seed S] [--contact-decades LO HI] [--proximal residual] [--workers W]
    python -m validation accuracy N [--seed S] [--contact-decades LO HI] [--tol 1e-4] [--estimator]
    python -m validation throughput N [-H 3] [--elements 8] [--workers 2]
    python -m validation tables [RUNS] --update docs/validation.md docs/benchmarks.md
    python -m validation nlvib --nlvib DIR [--case C ...] [--repeats 2] [--out DIR]

Exit codes: 0, 1 when a run failed as the subcommand says, 2 for bad input.
"""

from __future__ import annotations

import argparse
import csv
import functools
import sys
from pathlib import Path

from mmshbm.cli import common

from .accuracy import arguments as accuracy_arguments


def _out(args) -> Path:
    path = Path(args.out)
    path.mkdir(parents=True, exist_ok=True)
    return path


def _proximal(args) -> dict:
    """The backbone options the corpus runs take from the command line."""
    return {} if args.proximal == "static" else {"r": args.proximal}


def _corpus(args) -> int:
    """The corpus run: one line per model as it ends, then the summary; writes
    corpus.csv. Exit 1 when a model raised."""
    from . import corpus

    cases = corpus.generate(args.n, args.seed)
    if args.only:
        cases = [c for c in cases if c.index in set(args.only)]

    def progress(r):
        print(f"{r.case.label:<34} {r.seconds:7.2f} s  {'ok ' if r.completed else 'NOT'} {r.status[:90]}",
              flush=True)

    results = corpus.run_corpus(cases, workers=args.workers, progress=progress, time_limit=args.time_limit,
                                compare_path=args.compare_path, options=_proximal(args))
    print(corpus.summary(results))
    path = _out(args) / "corpus.csv"
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(corpus.CSV_COLUMNS)
        for r in results:
            w.writerow(corpus.csv_row(r))
    common.wrote(path)
    return 1 if any(r.raised for r in results) else 0


def _exact(args) -> int:
    """The exact comparison: one line per chain as it ends, then the report; writes
    corpus_exact.csv. Exit 1 when a clean case misses by more than 1e-3 and nothing the
    result computes explains it (``ExactComparison.explanations``)."""
    from . import corpus_exact

    if args.contact_decades and not args.contact_decades[0] < args.contact_decades[1]:
        raise ValueError(f"--contact-decades: LO must be below HI, got {args.contact_decades}")
    cases = corpus_exact.chains(args.n, seed=args.seed,
                                contact_decades=tuple(args.contact_decades) if args.contact_decades else None)
    results = []
    compare = functools.partial(corpus_exact.compare, options=_proximal(args), accuracy=args.tol)
    if args.workers > 1:  # each chain in its own task; the lines still in chain order
        from concurrent.futures import ProcessPoolExecutor

        pool = ProcessPoolExecutor(args.workers)
        outcomes = pool.map(compare, cases)
    else:
        pool, outcomes = None, map(compare, cases)
    for case, r in zip(cases, outcomes, strict=True):
        results.append(r)
        print(f"{corpus_exact.name(case):<34} {r.seconds:7.2f} s  {'clean' if r.clean else 'not clean':9} "
              f"error {r.error:.2e}  {r.status[:60]}", flush=True)
    if pool is not None:
        pool.shutdown()
    print(corpus_exact.report(results))
    path = _out(args) / "corpus_exact.csv"
    decades = " ".join(f"{x:g}" for x in args.contact_decades) if args.contact_decades else ""
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["index", "seed", "clean", "exact_hz", "branch_hz", "error", "error_2h", "continued_hz",
                    "first_mode", "estimate", "reasons", "status", "seconds", "exact_share",
                    "continued_share", "branch_orbit_hz", "branch_orbit_share", "proximal",
                    "contact_decades", "orbits_hz", "orbits_share", "orbits_seconds", "exact_listed",
                    "explained", "band_lo_hz", "band_hi_hz", "tol", "tolerance_not_met"])
        for r in results:
            w.writerow([r.case.index, r.case.seed, int(r.clean), repr(r.exact), repr(r.branch),
                        f"{r.error:.3e}", f"{r.error_2h:.3e}", repr(r.continued), int(r.first_mode),
                        f"{r.estimate:.3e}", "; ".join(r.reasons()), r.status, f"{r.seconds:.3f}",
                        f"{r.exact_share:.4f}", f"{r.continued_share:.4f}", repr(r.family_exact),
                        f"{r.family_share:.4f}", args.proximal, decades,
                        " ".join(repr(f) for f in r.orbits_hz), " ".join(f"{x:.4f}" for x in r.orbits_share),
                        f"{r.orbits_seconds:.3f}", r.exact_listed, "; ".join(r.explanations()),
                        repr(r.band[0]), repr(r.band[1]), repr(r.tolerance), int(r.tolerance_not_met)])
    common.wrote(path)
    unexplained = [r for r in results if r.clean and not r.error <= 1e-3 and not r.explanations()]
    return 1 if unexplained else 0


def _accuracy(args) -> int:
    """``backbone(tol=...)`` against the exact orbit and fixed H = 31 (validation/accuracy.py),
    or with ``--estimator`` the per-point estimate against the true error."""
    from . import accuracy

    return accuracy.main(args)


def _chunksize(text: str):
    return "auto" if text == "auto" else common.positive_int(text)


def _throughput(args) -> int:
    """A Monte-Carlo study of N backbones timed per executor; writes throughput.txt and
    throughput.json. Exit 1 when an executor's numbers differ from the serial ones."""
    from .throughput import measure_throughput

    executors = ("process", "dask") if args.executor is None else (args.executor,)
    if executors == ("serial",):
        executors = ()
    result = measure_throughput(args.n, harmonics=args.harmonics, elements=args.elements,
                                max_amplitude=args.max_amplitude, workers=args.workers, executors=executors,
                                chunksize=args.chunksize, verbose=args.verbose > 0 and sys.stderr.isatty())
    out = _out(args)
    text = out / "throughput.txt"
    text.write_text(result.to_text() + "\n")
    print(result.to_text())
    common.wrote(text, result.to_json(out / "throughput.json"))
    return 0 if all(r.identical for r in result.runs) else 1


def _nlvib(args) -> int:
    """NLvib under Octave and MMS-HBM side by side (validation/nlvib_compare.py); writes
    nlvib.txt and NLvib's points under --out. Exit 2 without Octave."""
    from . import nlvib_compare

    if nlvib_compare.octave_available() is None:
        print("python -m validation nlvib: octave is not on PATH (apt-get install octave)", file=sys.stderr)
        return 2
    out = _out(args)
    results = nlvib_compare.run(Path(args.nlvib), args.case, args.repeats, out)
    text = nlvib_compare.report(results)
    print(text)
    path = out / "nlvib.txt"
    path.write_text(text + "\n")
    common.wrote(path)
    return 0


def _tables(args) -> int:
    from . import tables

    argv = [args.runs] + (["--asv", args.asv] if args.asv else []) + (["--update", *args.update]
                                                                      if args.update else [])
    return tables.main(argv)


def build_parser() -> argparse.ArgumentParser:
    parser = common.Parser(prog="python -m validation", description=__doc__.split("\n\n")[0],
                           formatter_class=common.Formatter)
    sub = parser.add_subparsers(dest="command", required=True, parser_class=common.Parser)

    def add(name, func, help_):
        p = sub.add_parser(name, help=help_, formatter_class=common.Formatter)
        p.add_argument("-v", "--verbose", action="count", default=0, help="progress bars (on a terminal)")
        p.set_defaults(func=func)
        return p

    p = add("corpus", _corpus, "the default backbone on N random models: completion, failures, times")
    p.add_argument("n", type=common.positive_int, metavar="N", help="models")
    p.add_argument("--seed", type=common.non_negative_int, default=0, help="the corpus seed")
    p.add_argument("--compare-path", action="store_true",
                   help="also follow each branch plainly and check that the default gives the same branch "
                        "wherever that one reaches the bound without a tongue")
    p.add_argument("--time-limit", type=common.positive_float, default=30.0,
                   help="seconds of processor time per model before it is interrupted")
    p.add_argument("--workers", type=common.positive_int, default=1, help="processes")
    p.add_argument("--proximal", choices=("static", "residual"), default="static",
                   help="MMS-HBM's proximal parameter r (docs/exact.md)")
    p.add_argument("--only", type=common.non_negative_int, nargs="+", default=None, metavar="I",
                   help="run only the models of these indices (of the N drawn)")
    p.add_argument("--out", default="out", help="folder of corpus.csv")

    p = add("exact", _exact, "the default backbone against the exact single-contact orbit on N random chains")
    p.add_argument("n", type=common.positive_int, metavar="N", help="chains of 1-4 masses")
    p.add_argument("--seed", type=common.non_negative_int, default=0, help="the corpus seed")
    p.add_argument("--contact-decades", type=common.finite_float, nargs=2, default=None, metavar=("LO", "HI"),
                   help="draw the contact spring as 10**U(LO, HI) N/m (default: the corpus's, up to 100 "
                        "times stiffer than the other springs)")
    p.add_argument("--proximal", choices=("static", "residual"), default="static",
                   help="MMS-HBM's proximal parameter r (docs/exact.md)")
    p.add_argument("--workers", type=common.positive_int, default=1, help="processes (chains in parallel)")
    p.add_argument("--tol", type=common.positive_float, default=None,
                   help="run backbone(tol=TOL) instead of H = 31 (its own error estimate explains misses)")
    p.add_argument("--out", default="out", help="folder of corpus_exact.csv")

    p = add("accuracy", _accuracy, "backbone(tol=...) against the exact orbit and fixed H = 31 on N chains")
    accuracy_arguments(p)

    p = add("throughput", _throughput, "time a Monte-Carlo study of N backbones serially, on a process pool "
                                       "and on a Dask cluster")
    p.add_argument("n", type=common.positive_int, metavar="N", help="backbones")
    p.add_argument("-H", "--harmonics", type=common.positive_int, default=3, help="H")
    p.add_argument("--elements", type=common.positive_int, default=8, help="elements of the beam")
    p.add_argument("--max-amplitude", type=common.positive_float, default=10.0, help="gaps")
    p.add_argument("--workers", type=common.positive_int, default=2, help="processes")
    p.add_argument("--executor", default=None, choices=["process", "serial", "dask"],
                   help="one executor besides the serial reference (default both pool and dask)")
    p.add_argument("--chunksize", type=_chunksize, default="auto", help="runs per task, or auto")
    p.add_argument("--out", default="out", help="folder of throughput.txt and throughput.json")

    p = add("nlvib", _nlvib, "NLvib (under Octave) and MMS-HBM on NLvib's example 08 with a Jenkins element "
                             "and on the Jenkins oscillator: times, points, peaks")
    p.add_argument("--nlvib", required=True, help="an NLvib checkout (github.com/maltekrack/NLvib)")
    p.add_argument("--case", action="append", default=None, choices=("ex08-kt1e7", "ex08-kt1e9",
                   "oscillator-N128", "oscillator-N1024"), help="a case (repeatable; default all)")
    p.add_argument("--repeats", type=common.positive_int, default=2, help="warm runs of each side")
    p.add_argument("--out", default="out/nlvib", help="folder of nlvib.txt and NLvib's points")

    p = add("tables", _tables, "write the tables of docs/validation.md from the runs")
    p.add_argument("runs", nargs="?", default="runs",
                   help="folder of the runs (grid/, corpus/<group>/, exact/)")
    p.add_argument("--asv", default=None, metavar="RESULTS",
                   help="asv results file or folder (default .asv/results, then benchmarks/results)")
    p.add_argument("--update", nargs="+", default=None, metavar="FILE",
                   help="write the tables into FILEs between their markers (else print them)")
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run ``python -m validation`` with ``argv`` (default ``sys.argv[1:]``)."""
    try:
        args = build_parser().parse_args(argv)
    except common.Usage as err:
        print(err, file=sys.stderr)
        return 2
    except SystemExit as err:  # --help
        return int(err.code or 0)
    try:
        return args.func(args)
    except common.USER_ERRORS as err:
        message = str(err).splitlines()[0] if str(err) else type(err).__name__
        print(f"python -m validation {args.command}: error: {message}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
