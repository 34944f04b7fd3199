"""Nonlinear modes (backbone curves) of structures with impact, by MMS-HBM.

Every subcommand writes its files into --out (default out/) and prints one line per
file written. Exit codes: 0 when every branch reached its bounds; 1 when a branch ended
short of them (step budget, step size, failed start); 2 for bad input (a one-line
message on stderr, never a traceback). Warnings about what a result is (another family
of motions, contact violated by the truncated series, short of its bounds) are printed
as "warning:" lines on stderr.

Examples:

    mmshbm backbone                        # default beam, 21 elements, H = 5
    mmshbm backbone -H 3 --elements 8 --measured measured.csv
    mmshbm study --figure2                 # Figure 2 of the paper and its table
    mmshbm study -H 1 3 5 7 --elements 8 21 --param gap=0.001,0.002
    mmshbm fit 45.8 286.5 --fit E          # Young's modulus from measured frequencies
    mmshbm plot out/backbone.npz --points 1.5 3 6
    mmshbm bench --quick
    mmshbm frf --force 2.3 --range 40 60   # forced response, 0.5 % modal damping, stability"""

from __future__ import annotations

import argparse
import logging
import os
import sys
import warnings

from .. import __version__
from .._warnings import MmshbmWarning
from . import backbone, bench, common, fit, frf, modes, plot, study

log = logging.getLogger("mmshbm")

#: the subcommands, in the order ``mmshbm -h`` lists them; each module has register(sub) and run(args)
COMMANDS = (modes, backbone, study, fit, bench, plot, frf)


def build_parser() -> argparse.ArgumentParser:
    """The ``mmshbm`` argument parser."""
    lines = __doc__.splitlines()
    parser = common.Parser(prog="mmshbm", description="\n".join(lines[:8]), formatter_class=common.Formatter,
                           epilog="\n".join(lines[9:]))
    parser.add_argument("--version", action="version", version=f"mmshbm {__version__}")
    parser.add_argument("-v", "--verbose", action="count", default=0,
                        help="more output: -v progress bars (on a terminal) and info logs, -vv debug logs")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=common.Parser)
    for command in COMMANDS:
        command.register(sub)
    common.finish_subparsers(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line with ``argv`` (default ``sys.argv[1:]``); returns the exit code."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except common.Usage as err:
        print(f"{err} (see mmshbm -h)", file=sys.stderr)
        return 2
    except SystemExit as err:  # --help, --version
        return int(err.code or 0)
    level = logging.WARNING - 10 * min(args.verbose, 2)
    root = logging.getLogger("mmshbm")
    if not any(isinstance(h, common.StderrHandler) for h in root.handlers):
        handler = common.StderrHandler()
        handler.setFormatter(logging.Formatter("%(name)s: %(message)s"))
        root.addHandler(handler)
    root.setLevel(level)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("always", MmshbmWarning)
            warnings.showwarning = _one_line_warning(args.command)
            return args.func(args)
    except common.USER_ERRORS as err:
        message = str(err).splitlines()[0] if str(err) else type(err).__name__
        print(f"mmshbm {args.command}: error: {message}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("mmshbm: interrupted", file=sys.stderr)
        return 130


def console() -> int:
    """The ``mmshbm`` program (console script and ``python -m mmshbm``): BLAS on one thread
    unless the environment says otherwise (:func:`mmshbm._threads.single_thread_env`),
    :func:`main`, then a fast interpreter exit.

    After the command the interpreter's finalisation would walk every object the
    imports made (Numba's typing and lowering registries are ~10⁵ objects) in repeated
    garbage collections: 0.3–0.5 s after a backbone. ``gc.freeze()`` moves them out of
    the collector's reach; reference counting still frees what it frees, atexit handlers
    and stream flushes still run. Only for a process that is about to end (not for
    :func:`main` called from Python).
    """
    import gc

    from .._threads import single_thread_env

    single_thread_env()  # before numpy loads: one BLAS thread unless the user set them (mmshbm._threads)
    code = main()
    gc.freeze()
    return code


def _one_line_warning(command: str):
    """A ``warnings.showwarning`` that prints the package's warnings as one line each: its
    own categories, and any other warning raised from its code (named by category)."""
    from pathlib import Path

    default = warnings.showwarning
    package = str(Path(__file__).resolve().parents[1]) + os.sep

    def show(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, MmshbmWarning):
            print(f"mmshbm {command}: warning: {message}", file=sys.stderr)
        elif str(filename).startswith(package):
            print(f"mmshbm {command}: warning: {category.__name__}: {message}", file=sys.stderr)
        else:
            default(message, category, filename, lineno, file, line)

    return show


if __name__ == "__main__":  # pragma: no cover
    sys.exit(console())
