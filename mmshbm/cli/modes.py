"""``mmshbm modes``."""

from __future__ import annotations

from . import common


def register(sub) -> None:
    """Add the subcommand to the subparsers ``sub``."""
    p = sub.add_parser("modes", help="linear frequencies (contact open)")
    common.beam_options(p)
    p.add_argument("-n", type=common.positive_int, default=3,
                   help="number of modes (default 3; at most the model's DOFs with mass)")
    p.set_defaults(func=run)


def run(args) -> int:
    model = common.model(args)
    n = min(args.n, len(model.l))  # a model has as many modes as DOFs with mass
    freqs = model.linear_frequencies(n)
    if n < args.n:
        print(f"the model has {n} DOF{'s' * (n != 1)} with mass: {n} mode{'s' * (n != 1)}")
    path = common.out_dir(args) / "modes.csv"
    path.write_text("mode,frequency_hz\n" + "".join(f"{i + 1},{f:.10g}\n" for i, f in enumerate(freqs)))
    for i, f in enumerate(freqs):
        print(f"mode {i + 1}: {f:.4f} Hz")
    common.wrote(path)
    return 0
