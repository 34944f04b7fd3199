"""``mmshbm bench``."""

from __future__ import annotations

from .._method_info import benchmarked_methods
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
    p.add_argument("--methods", nargs="+", default=None, choices=benchmarked_methods(),
                   help="methods (default all three)")
    p.add_argument("--repeats", type=common.positive_int, default=None, help="timing repeats (default 3)")
    p.add_argument("--amplitude", type=common.positive_float, default=None,
                   help="amplitude (gaps) compared at (default: oscillator 2, beam 1.5)")
    p.set_defaults(func=run)


def run(args) -> int:
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
