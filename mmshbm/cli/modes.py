"""``mmshbm modes``."""

from __future__ import annotations

from . import common


def register(sub) -> None:
    """Add the subcommand to the subparsers ``sub``."""
    p = sub.add_parser("modes", help="linear frequencies (contact open); with --model-file the import's "
                                     "DOF table and checks")
    common.beam_options(p)
    p.add_argument("-n", type=common.positive_int, default=3,
                   help="number of modes (default 3; at most the model's DOFs with mass)")
    p.set_defaults(func=run)


def run(args) -> int:
    fe = common.fe_matrices(args)
    named = getattr(args, "contact", None) or getattr(args, "friction", None) or args.contact_dof
    if fe is not None:
        _describe(fe)
        model = common.model(args) if named else fe.open_model
    else:
        model = common.model(args)
    n_l = len(model.l)
    n = min(args.n, n_l)  # a model has as many modes as DOFs with mass
    freqs = model.linear_frequencies(n)
    if n < args.n:
        massless = model.n_dof - n_l
        print(f"the model has {n_l} DOF{'s' * (n_l != 1)} with mass: {n_l} mode{'s' * (n_l != 1)} (-n "
              f"{args.n} "
              f"asked for more; {'its ' + str(massless) + ' massless DOFs have none; ' if massless else ''}"
              f"all {n_l} computed)")
    path = common.out_dir(args) / "modes.csv"
    path.write_text("mode,frequency_hz\n" + "".join(f"{i + 1},{f:.10g}\n" for i, f in enumerate(freqs)))
    for i, f in enumerate(freqs):
        print(f"mode {i + 1}: {f:.4f} Hz")
    if fe is not None:
        print("(Hz if the export's units are consistent: SI, or mm-tonne-s; mm with kg gives sqrt(1000) "
              "x too "
              "high)")
    common.wrote(path)
    return 0


def _describe(fe) -> None:
    """The import: format, DOF count, nodes and components, what was removed."""
    from ..model.readers.fematrices import id_ranges

    plain = bool((fe.dofs[:, 1] == 0).all())
    print(f"read {', '.join(fe.source)} ({fe.format}): {fe.n_dof} DOFs"
          + ("" if fe.C is None else ", with damping"))
    if plain:
        print(f"DOFs: plain indices 0..{fe.n_dof - 1} (the format names no nodes; --contact ROW:0:GAP)")
    else:
        comps = sorted({int(c) for c in fe.dofs[:, 1]})
        print(f"nodes {id_ranges(fe.nodes)} ({len(fe.nodes)}), components {comps}")
    if fe.removed is not None and len(fe.removed):
        nodes = id_ranges(set(fe.removed[:, 0].tolist()))
        print(f"removed {len(fe.removed)} constrained DOFs (nodes {nodes})")
    massless = int((abs(fe.M).sum(axis=1) == 0).sum())
    if massless:
        print(f"{massless} DOFs carry no mass")
