"""Command line: ``mmshbm backbone | modes ...``.

Every subcommand writes its files into ``--out`` and prints one line per file. Bad input
becomes a one-line error and exit code 2, never a traceback.
"""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path

from . import __version__

log = logging.getLogger("mmshbm")


def _beam_model(args):
    from .fe.beam import default_beam

    beam = default_beam()
    return beam.model(args.elements, grading=args.grading)


def cmd_modes(args) -> int:
    model = _beam_model(args)
    freqs = model.linear_frequencies(args.n)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    path = out / "modes.csv"
    path.write_text("mode,frequency_hz\n" + "".join(f"{i + 1},{f:.10g}\n" for i, f in enumerate(freqs)))
    for i, f in enumerate(freqs):
        print(f"mode {i + 1}: {f:.4f} Hz")
    print(f"wrote {path}")
    return 0


def cmd_backbone(args) -> int:
    import numpy as np

    from .api import backbone

    model = _beam_model(args)
    max_amp = args.max_amplitude * model.gap if args.max_amplitude else None
    branch = backbone(model, harmonics=args.harmonics, method=args.method, max_amplitude=max_amp,
                      verbose=args.verbose > 0)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    data = out / "backbone.csv"
    np.savetxt(data, np.column_stack([branch.frequency, branch.amplitude, branch.energy,
                                      branch.contact_force_max, branch.newton_iterations]),
               delimiter=",", header="frequency_hz,amplitude_m,energy_j,contact_force_max_n,newton_iterations",
               comments="")
    figure = out / "backbone.png"
    _plot_backbone(branch, model, figure)
    print(f"{branch!r}")
    print(f"wrote {data}")
    print(f"wrote {figure}")
    return 0 if branch.completed else 1


def _plot_backbone(branch, model, path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4.5), layout="constrained")
    ax.plot(branch.frequency, branch.amplitude / model.gap, "-", label=f"MMS-HBM, H = {branch.harmonics}")
    f_lin = model.linear_frequencies(2)
    ax.axvline(f_lin[0], color="0.6", ls=":", label=f"linear {f_lin[0]:.2f} Hz")
    ax.axvline(model.zero_gap_frequency(), color="0.3", ls="--", label="zero-gap limit")
    ax.axvline(f_lin[1] / 5, color="C3", ls="-.", lw=0.8, label="f2/5")
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("tip amplitude / gap")
    ax.legend()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="mmshbm", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"mmshbm {__version__}")
    parser.add_argument("-v", "--verbose", action="count", default=0, help="more output (progress, logs)")
    sub = parser.add_subparsers(dest="command", required=True)

    def beam_options(p):
        p.add_argument("--elements", type=int, default=21, help="beam elements (default 21)")
        p.add_argument("--grading", type=float, default=10.0, help="root/tip element length ratio")
        p.add_argument("--out", default="out", help="output folder (default ./out)")

    p = sub.add_parser("modes", help="linear frequencies of the default beam (contact open)")
    beam_options(p)
    p.add_argument("-n", type=int, default=3, help="number of modes")
    p.set_defaults(func=cmd_modes)

    p = sub.add_parser("backbone", help="first nonlinear mode of the default beam")
    beam_options(p)
    p.add_argument("-H", "--harmonics", type=int, default=5)
    p.add_argument("--method", default="mmshbm", choices=["mmshbm", "penalty", "shooting"])
    p.add_argument("--max-amplitude", type=float, default=None, help="in gaps (default 10)")
    p.set_defaults(func=cmd_backbone)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.WARNING - 10 * min(args.verbose, 2), format="%(name)s: %(message)s")
    try:
        return args.func(args)
    except (ValueError, TypeError, OSError) as err:
        print(f"mmshbm: error: {err}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
