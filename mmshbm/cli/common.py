"""What the subcommands share: the parser class, output folder, models from options."""

from __future__ import annotations

import argparse
import logging
import math
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


class Formatter(argparse.RawDescriptionHelpFormatter):
    """Plain-text help: descriptions as written, and every option's default shown
    ("(default: X)") unless its help text already names it."""

    def _get_help_string(self, action):
        text = action.help or ""
        default = action.default
        quiet = (argparse._HelpAction, argparse._VersionAction, argparse._CountAction)
        if ("default" in text or default is None or default is False or default is argparse.SUPPRESS
                or isinstance(action, quiet) or not action.option_strings):
            return text
        if isinstance(default, list | tuple):
            default = " ".join(str(d) for d in default)
        return f"{text} (default: {str(default).replace('%', '%%')})".lstrip()


def finish_subparsers(sub) -> None:
    """Give every subcommand (also those registered later by other modules) plain-text
    help with defaults, a description, and the global ``-v`` after the subcommand."""
    for name, p in sub.choices.items():
        p.formatter_class = Formatter
        if p.description is None:
            helps = {a.dest: a.help for a in sub._choices_actions}
            p.description = helps.get(name)
        if not any("-v" in a.option_strings for a in p._actions):
            p.add_argument("-v", "--verbose", action="count", default=argparse.SUPPRESS,
                           help="more output (as before the subcommand): -v progress bars and info logs, "
                                "-vv debug logs")


# ---------------------------------------------------------------------- option types
def _number(text: str, kind, what: str, ok) -> float:
    try:
        value = kind(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be {what}, got {text!r}") from None
    if kind is float and not math.isfinite(value) or not ok(value):
        raise argparse.ArgumentTypeError(f"must be {what}, got {text!r}")
    return value


def positive_int(text: str) -> int:
    """argparse type: an integer >= 1."""
    return _number(text, int, "an integer >= 1", lambda v: v >= 1)


def positive_float(text: str) -> float:
    """argparse type: a finite number > 0 (0 is refused, not ignored)."""
    return _number(text, float, "a finite number > 0", lambda v: v > 0)


def non_negative_int(text: str) -> int:
    """argparse type: an integer >= 0."""
    return _number(text, int, "an integer >= 0", lambda v: v >= 0)


def finite_float(text: str) -> float:
    """argparse type: any finite number (e.g. a decimal exponent)."""
    return _number(text, float, "a finite number", lambda v: True)


def non_negative_float(text: str) -> float:
    """argparse type: a finite number >= 0 (for options where 0 means something, e.g. no
    damping)."""
    return _number(text, float, "a finite number >= 0", lambda v: v >= 0)


def out_dir(args) -> Path:
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    return out


def exit_code(branches) -> int:
    """0 when every branch reached its bounds, else 1 (their warnings say why)."""
    return 0 if all(b.completed for b in branches) else 1


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
    """The default beam with the options' ``--gap``, ``--E``, ``--rho``."""
    from ..fe.beam import default_beam

    return default_beam(**{k: v for k, v in (("gap", args.gap), ("E", args.E), ("rho", args.rho))
                           if v is not None})


def model(args, layer: bool = True):
    """The model of the options: ``--model-file`` or the default beam, converted by
    ``--contact-layer K`` / ``--massless-contact [DOF ...]`` (the beam then starts from its
    full-mass model: the tip keeps its mass). An FE export given with ``--contact`` /
    ``--friction`` gets its massless layer on the named DOFs that carry mass (stiffness
    ``--contact-layer K``, default 10⁵ x the static stiffness there) unless ``layer`` is
    False (the named DOFs keep their mass)."""
    layer_k = getattr(args, "contact_layer", None)
    massless = getattr(args, "massless_contact", None)
    if layer_k is not None and massless is not None:
        raise ValueError("--contact-layer and --massless-contact are two ways to the same end: give one")
    convert = layer_k is not None or massless is not None
    if getattr(args, "model_file", None):
        fe = fe_matrices(args)
        if fe is not None:
            return _fe_model(args, fe, layer)
        model = _model_file(args)
    else:
        from ..methods.limits import check_beam_elements

        check_beam_elements(args.elements)  # before assembling anything
        model = beam(args).model(args.elements, grading=args.grading, massless_tip=not convert)
    if layer_k is not None:
        model = model.with_contact_layer(None if layer_k == "default" else layer_k)
    elif massless is not None:
        model = model.with_massless_contact(massless or None)
    return model


def fe_matrices(args):
    """The :class:`~mmshbm.model.readers.FEMatrices` of ``--model-file`` when it is an FE
    export, or an own ``.npz`` given with ``--contact`` / ``--friction``; None for the
    beam and for an own ``.npz`` model read as it is (its contacts kept)."""
    paths = getattr(args, "model_file", None)
    if not paths:
        return None
    from ..model.readers import detect_format, read_fe

    paths = [paths] if isinstance(paths, str) else list(paths)
    named = bool(getattr(args, "contact", None) or getattr(args, "friction", None))
    if len(paths) == 1 and not named and Path(paths[0]).is_file() and detect_format(Path(paths[0])) == "npz":
        return None
    memo = getattr(args, "_fe_memo", None)
    if memo is None:
        memo = read_fe(*paths)
        args._fe_memo = memo
    return memo


def _fe_model(args, fe, layer: bool):
    """The model of an FE export with the contacts of ``--contact`` (or ``--contact-dof``
    rows) and the friction of ``--friction``."""
    if getattr(args, "massless_contact", None) is not None:
        raise ValueError("--massless-contact applies to .npz models; an FE export given with --contact "
                         "gets a "
                         "massless layer (its stiffness: --contact-layer K)")
    contacts = []
    for node, comp, gap, side in getattr(args, "contact", None) or ():
        gap = gap if gap is not None else args.gap
        if gap is None:
            raise ValueError(f"--contact {node}:{comp}: give the gap (NODE:COMPONENT:GAP) or --gap (m)")
        contacts.append((node, comp, gap, side))
    rows = getattr(args, "contact_dof", None)
    if rows:
        if contacts:
            raise ValueError("give --contact NODE:COMPONENT[:GAP[:SIDE]] or --contact-dof ROW, not both")
        if args.gap is None:
            raise ValueError("--contact-dof with an FE export: give --gap (m)")
        sides = getattr(args, "stop_side", None) or [1]
        if len(sides) not in (1, len(rows)):
            raise ValueError(f"--stop-side: one side, or one per --contact-dof ({len(rows)}); got "
                             f"{len(sides)}")
        for k, r in enumerate(rows):
            if not r < fe.n_dof:
                raise ValueError(f"--contact-dof {r}: the export has DOFs 0..{fe.n_dof - 1}")
            node, comp = (int(v) for v in fe.dofs[r])
            contacts.append((node, comp, args.gap, sides[k if len(sides) > 1 else 0]))
    friction = list(getattr(args, "friction", None) or ())
    if not contacts and not friction:
        raise ValueError(f"{', '.join(fe.source)} names no contact: give --contact NODE:COMPONENT:GAP (nodes "
                         f"{_node_list(fe)}; `mmshbm modes --model-file ...` lists the DOFs)")
    k = getattr(args, "contact_layer", None)
    if not layer:
        return _fe_model_with_mass(fe, contacts, friction)
    k = None if k in (None, "default") else k
    model = fe.model(contact=contacts, friction=friction, layer_stiffness=k)
    info = model.description.get("contact_layer")
    if info:
        for (node, comp), kk, ratio in zip(info["attached_to"], info["stiffness"], info["ratio_to_static"],
                                           strict=True):
            print(f"massless layer at node {node} component {comp}: k = {kk:.6g} N/m ({ratio:.3g} x the "
                  f"static "
                  "stiffness there; --contact-layer K sets it)")
    return model


def _fe_model_with_mass(fe, contacts, friction):
    from ..model.model import Model

    if friction:
        raise ValueError("--friction needs a massless DOF: this command keeps the named DOFs' mass")
    rows = [fe.index(n, c) for n, c, _, _ in contacts]
    return Model.from_matrices(fe.M, fe.K, rows, [c[2] for c in contacts], [c[3] for c in contacts],
                               {"kind": "FEMatrices", "source": list(fe.source)}, damping=fe.C)


def _node_list(fe) -> str:
    from ..model.readers.fematrices import id_ranges

    return id_ranges(fe.nodes)


def model_source(args):
    """What the analysis functions take as a model: the ``--model-file`` path when it is one
    own ``.npz`` read as it is, else the :class:`~mmshbm.model.Model` of the options."""
    paths = args.model_file
    if fe_matrices(args) is None:
        return paths[0] if isinstance(paths, list) else paths
    return model(args)


def _model_file(args):
    """The model of ``--model-file`` (an own .npz), with ``--contact-dof``, ``--gap`` and
    ``--stop-side`` given in place of (or over) the file's entries."""
    import re

    from ..model.model import Model

    def one_or_list(values):
        return None if values is None else values[0] if len(values) == 1 else list(values)

    path = args.model_file[0] if isinstance(args.model_file, list) else args.model_file
    try:
        return Model.from_npz(path, contact_dof=one_or_list(getattr(args, "contact_dof", None)),
                              gap=args.gap, stop_side=one_or_list(getattr(args, "stop_side", None)))
    except ValueError as err:  # the library's "pass name=..." is an option here
        raise ValueError(re.sub(r"pass (\w+)=\.\.\.", lambda m: f"give --{m.group(1).replace('_', '-')}",
                                str(err))) from None


def contact_spec(text: str) -> tuple:
    """``--contact`` value ``NODE:COMPONENT[:GAP[:SIDE]]`` -> (node, component, gap or None,
    side)."""
    parts = text.split(":")
    if not 2 <= len(parts) <= 4:
        raise argparse.ArgumentTypeError(f"expected NODE:COMPONENT[:GAP[:SIDE]], got {text!r}")
    try:
        node, comp = int(parts[0]), int(parts[1])
        gap = float(parts[2]) if len(parts) > 2 and parts[2] else None
        side = int(parts[3]) if len(parts) > 3 else 1
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected integers NODE:COMPONENT, a gap in m and a side "
                                         f"+1/-1, got "
                                         f"{text!r}") from None
    if gap is not None and not (math.isfinite(gap) and gap > 0):
        raise argparse.ArgumentTypeError(f"the gap must be a finite number > 0 (m), got {text!r}")
    if side not in (1, -1):
        raise argparse.ArgumentTypeError(f"the side must be +1 or -1, got {text!r}")
    return node, comp, gap, side


def friction_spec(text: str) -> tuple:
    """``--friction`` value ``NODE:COMPONENT:MU:LOAD`` -> (node, component, mu, normal load)."""
    parts = text.split(":")
    try:
        if len(parts) != 4:
            raise ValueError
        node, comp, mu, load = int(parts[0]), int(parts[1]), float(parts[2]), float(parts[3])
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected NODE:COMPONENT:MU:LOAD (integers, then the friction "
                                         f"coefficient and the normal load in N), got {text!r}") from None
    if not (math.isfinite(mu) and mu >= 0 and math.isfinite(load) and load >= 0):
        raise argparse.ArgumentTypeError(f"MU and LOAD must be finite and >= 0, got {text!r}")
    return node, comp, mu, load


def stop_side(text: str) -> int:
    """argparse type: +1 or -1."""
    return _number(text, int, "+1 or -1", lambda v: v in (1, -1))


def stiffness(text: str):
    """``--contact-layer`` value: a stiffness (N/m) or ``default``."""
    if text.strip().lower() == "default":
        return "default"
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a stiffness in N/m or 'default', got {text!r}") from None


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



#: the help of --measured: the CSV format load_measured reads
MEASURED_HELP = ("measured backbone to overlay: a CSV file with a header line naming the columns frequency "
                 "(Hz) and amplitude (m), optionally contact_force (N); units may be written into the names "
                 "(frequency_hz, amplitude [m]) but must be these; ',', ';' or tab separate fields, lines "
                 "starting with # are skipped (a backbone.csv this program wrote is one)")


def measured_option(p) -> None:
    """--measured, with the file format in its help."""
    p.add_argument("--measured", default=None, metavar="CSV", help=MEASURED_HELP)


def out_option(p):
    """--out."""
    p.add_argument("--out", default="out", help="output folder (default ./out)")


def beam_options(p, elements=True, model_file=True, conversions=None):
    """The default beam's options (and --model-file, and with it, unless ``conversions`` is
    False, --contact-layer / --massless-contact)."""
    if elements:
        p.add_argument("--elements", type=positive_int, default=21, help="beam elements (default 21)")
    p.add_argument("--grading", type=positive_float, default=10.0, help="root/tip element length ratio")
    p.add_argument("--gap", type=positive_float, default=None,
                   help="gap (m) (default: the beam's, 1 mm; with --model-file the file's)")
    p.add_argument("--E", type=positive_float, default=None, help="Young's modulus (Pa) (default 210e9)")
    p.add_argument("--rho", type=positive_float, default=None, help="density (kg/m^3) (default 7850)")
    if model_file:
        fe_options(p)
        p.add_argument("--contact-dof", type=non_negative_int, nargs="+", default=None, metavar="DOF",
                       help="--model-file: the contact DOF(s) as row indices, over the file's 'contact_dof' "
                            "(default: the file's)")
        p.add_argument("--stop-side", type=stop_side, nargs="+", default=None, metavar="SIDE",
                       help="--model-file: +1 (stop at +gap) or -1 per contact (default: the file's, "
                            "else +1)")
    if conversions if conversions is not None else model_file:
        g = p.add_mutually_exclusive_group()
        g.add_argument("--contact-layer", type=stiffness, default=None, metavar="K",
                       help="keep the contact DOF's mass and join a massless contact node to it by a spring "
                            "of K N/m ('default': 1e5 x the static stiffness at the contact)")
        g.add_argument("--massless-contact", type=non_negative_int, nargs="*", default=None, metavar="DOF",
                       help="remove the mass of the contact node's DOFs (or of the DOFs given); reports the "
                            "mass removed and the frequency shift")
    out_option(p)


#: the help of --model-file: what it reads
MODEL_FILE_HELP = ("a model instead of the beam: an .npz of Model.save_npz (or any .npz with M and K), "
                   "or an FE "
                   "export: Abaqus job_MASS1.mtx job_STIF1.mtx (FORMAT=MATRIX INPUT) or a *USER ELEMENT "
                   "file, "
                   "ANSYS .full, NASTRAN .op4 / DMIG .pch / .op2, Matrix Market or Harwell-Boeing mass and "
                   "stiffness files, MATLAB .mat (M, K), code_aster triplets .npz (docs/fe_models.md); "
                   "name contacts with --contact")


def fe_options(p) -> None:
    """--model-file PATH [PATH ...], --contact, --friction: the model options every subcommand
    with a model shares."""
    p.add_argument("--model-file", nargs="+", default=None, metavar="PATH", help=MODEL_FILE_HELP)
    p.add_argument("--contact", type=contact_spec, action="append", default=None,
                   metavar="NODE:COMPONENT[:GAP[:SIDE]]",
                   help="--model-file: a rigid stop at the DOF (node id, component 1..6; 0 and the row index "
                        "where the format names no DOFs), GAP in m (default --gap), SIDE +1 (stop at +GAP, "
                        "default) or -1; repeat for several. A DOF with mass gets a massless layer "
                        "(--contact-layer K)")
    p.add_argument("--friction", type=friction_spec, action="append", default=None,
                   metavar="NODE:COMPONENT:MU:LOAD",
                   help="--model-file: Coulomb friction at the DOF, coefficient MU, constant normal "
                        "load LOAD "
                        "(N); repeatable")
