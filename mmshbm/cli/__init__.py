"""Command line: ``mmshbm modes | backbone | study | fit | bench | plot | frf``.

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
    mmshbm frf --force 2.3 --range 40 60   # forced response, 0.5 % modal damping, stability"""

from __future__ import annotations

import argparse
import logging
import sys

from .. import __version__
from . import backbone, bench, common, fit, frf, modes, plot, study

log = logging.getLogger("mmshbm")

#: the subcommands, in the order ``mmshbm -h`` lists them; each module has register(sub) and run(args)
COMMANDS = (modes, backbone, study, fit, bench, plot, frf)


def build_parser() -> argparse.ArgumentParser:
    """The ``mmshbm`` argument parser."""
    parser = common.Parser(prog="mmshbm", description=__doc__.splitlines()[0],
                           formatter_class=argparse.RawDescriptionHelpFormatter,
                           epilog="\n".join(__doc__.splitlines()[6:]))
    parser.add_argument("--version", action="version", version=f"mmshbm {__version__}")
    parser.add_argument("-v", "--verbose", action="count", default=0,
                        help="more output: -v progress bars (on a terminal) and info logs, -vv debug logs")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=common.Parser)
    for command in COMMANDS:
        command.register(sub)
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
        return args.func(args)
    except common.USER_ERRORS as err:
        message = str(err).splitlines()[0] if str(err) else type(err).__name__
        print(f"mmshbm {args.command}: error: {message}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("mmshbm: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
