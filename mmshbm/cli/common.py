"""What the subcommands share: the parser class, output folder, models from options."""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path

#: exceptions that mean bad input or a failed run: one line on stderr, exit code 2
USER_ERRORS = (ValueError, TypeError, OSError, KeyError, IndexError, RuntimeError, ImportError)
#: amplitudes (gaps) of the marked points and table columns
DEFAULT_MARKS = (1.5, 3.0, 6.0)


class Usage(Exception):
    """A command-line usage error (raised instead of argparse's exit)."""


class StderrHandler(logging.StreamHandler):
    """Writes to the current ``sys.stderr`` (which tests and notebooks may swap)."""

    def emit(self, record):
        self.stream = sys.stderr
        super().emit(record)


class Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, no usage dump
        raise Usage(f"{self.prog}: error: {message}")


def out_dir(args) -> Path:
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    return out


def wrote(*paths) -> None:
    for p in paths:
        print(f"wrote {p}")


def measured(args):
    """The measured backbone of ``--measured``, read before any computation (None without)."""
    if not getattr(args, "measured", None):
        return None
    from ..analysis.measured import load_measured

    return load_measured(args.measured)


def progress(args) -> bool:
    """Progress bars only with -v and on a terminal."""
    return args.verbose > 0 and sys.stderr.isatty()


def beam(args):
    from dataclasses import replace

    from ..fe.beam import default_beam

    beam = default_beam()
    changes = {k: v for k, v in (("gap", args.gap), ("E", args.E), ("rho", args.rho)) if v is not None}
    return replace(beam, **changes) if changes else beam


def model(args):
    if getattr(args, "model_file", None):
        from ..model.model import Model

        model = Model.from_npz(args.model_file)
        return model.with_gap(args.gap) if args.gap is not None else model
    return beam(args).model(args.elements, grading=args.grading)


def has_grid(study) -> bool:
    return all("harmonics" in r and "elements" in r for r in study.runs) and \
        len({r.get("method") for r in study.runs}) == 1 and len(study.axes) == 3


def params(items) -> dict:
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



def out_option(p):
    """--out."""
    p.add_argument("--out", default="out", help="output folder (default ./out)")

def beam_options(p, elements=True, model_file=True):
    """The default beam's options (and --model-file)."""
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
