"""The tables of docs/validation.md, generated from the runs that measure them.

Each table is written between its own pair of markers (:func:`markers`) in a Markdown
file, so that a published table is the output of this module on recorded runs, never
typed by hand:

* ``grid``: the convergence grid of the default beam in H and elements, f (Hz) at the
  study's amplitudes, from the ``study_table.csv`` of ``mmshbm study``;
* ``corpus``: completion to 10 gaps on random models per contact type, one row per
  group of seeds, from the ``corpus.csv`` files of ``python -m validation corpus``;
* ``exact``: the default branch against the exact single-contact orbit, one row per
  seed with the static and the residual proximal parameter side by side, from the
  ``corpus_exact.csv`` files of ``python -m validation exact``;
* ``asv``: the benchmark tables of one recorded asv run
  (:func:`validation.asv_tables.tables`, between that module's markers).

The runs lie in one folder ``RUNS``: ``RUNS/grid/study_table.csv``,
``RUNS/corpus/<group>/**/corpus.csv`` (one row of the table per ``<group>`` folder, a
total row over all) and ``RUNS/exact/**/corpus_exact.csv``. From the repository root::

    python -m validation tables RUNS --update docs/validation.md docs/benchmarks.md

rewrites every table whose runs are present and leaves the others as they are
(docs/validation.md gives the commands that make the runs).
"""

from __future__ import annotations

import argparse
import csv
import math
import re
import sys
from collections.abc import Iterable, Sequence
from pathlib import Path

__all__ = ["markers", "grid_table", "corpus_table", "exact_table", "update_block", "generate", "main"]

#: the comparison tolerance of the exact comparison (relative frequency error)
EXACT_TOL = 1e-3
_COMMAND = "python -m validation tables"


def markers(name: str) -> tuple[str, str]:
    """The lines that open and close the generated table ``name`` in a Markdown file."""
    return (f"<!-- begin: generated {name} table ({_COMMAND}) -->", f"<!-- end: generated {name} table -->")


def _read(path: Path) -> list[dict]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def _float(text: str | None) -> float:
    try:
        return float(text) if text not in (None, "") else math.nan
    except ValueError:
        return math.nan


def _ranges(values: Iterable[int]) -> str:
    """``19–21, 25–36`` for the sorted integers ``values``."""
    values = sorted(set(values))
    parts, start = [], None
    for i, v in enumerate(values):
        if start is None:
            start = v
        if i + 1 == len(values) or values[i + 1] != v + 1:
            parts.append(f"{start}" if start == v else f"{start}–{v}")
            start = None
    return ", ".join(parts)


def _share(done: int, total: int, percent: bool = True) -> str:
    """``done / total (pp.pp %)``; ``100 %`` when all."""
    if not total:
        return "—"
    if not percent:
        return f"{done} / {total}"
    pct = "100 %" if done == total else f"{100 * done / total:.2f} %"
    return f"{done} / {total} ({pct})"


# ---------------------------------------------------------------------- the beam grid


def grid_table(path: str | Path) -> str:
    """The grid of ``study_table.csv`` (``mmshbm study`` over H and elements): rows
    elements, columns H, each cell f (Hz) at the study's amplitudes, ``—`` where the
    family front has no value there, ``*`` on a value next to a discontinuity of the
    family (the file's note)."""
    rows = _read(Path(path))
    if not rows:
        raise ValueError(f"{path}: no runs")
    amps = [m.group(1) for k in rows[0] if (m := re.fullmatch(r"f_at_(.+)gap_hz", k))]
    Hs = sorted({int(r["harmonics"]) for r in rows})
    els = sorted({int(r["elements"]) for r in rows})
    cells = {(int(r["elements"]), int(r["harmonics"])): r for r in rows}

    def cell(r: dict | None) -> str:
        if r is None:
            return ""
        out = []
        for a in amps:
            f = _float(r[f"f_at_{a}gap_hz"])
            note = r.get(f"note_at_{a}gap", "")
            out.append("—" if not math.isfinite(f) else f"{f:.2f}" + ("\\*" if note else ""))
        return " / ".join(out)

    lines = [f"f (Hz) at {' / '.join(amps)} gaps:", "",
             "| elements \\ H | " + " | ".join(map(str, Hs)) + " |", "|---" * (len(Hs) + 1) + "|"]
    for e in els:
        lines.append(f"| {e} | " + " | ".join(cell(cells.get((e, h))) for h in Hs) + " |")
    return "\n".join(lines)


# ---------------------------------------------------------------------- the corpus


_CONTACTS = (("one-sided", True), ("clearance", True), ("several", False))


def _corpus_row(label: str, rows: list[dict]) -> str:
    cells = []
    for contact, percent in _CONTACTS:
        rs = [r for r in rows if r["contact"] == contact]
        cells.append(_share(sum(r["completed"] == "1" for r in rs), len(rs), percent))
    cpu = [_float(r.get("cpu_seconds") or r["seconds"]) for r in rows]
    longest = max((t for t in cpu if math.isfinite(t)), default=math.nan)
    return f"| {label} | " + " | ".join(cells) + f" | {longest:.1f} s |"


def _seeds_label(rows: list[dict], prefix: str = "") -> str:
    seeds = {int(r["seed"]) for r in rows}
    word = "seed" if len(seeds) == 1 else "seeds"
    return f"{prefix}{word} {_ranges(seeds)} ({len(rows)} models)"


def corpus_table(groups: dict[str, Sequence[str | Path]]) -> str:
    """Completion to 10 gaps per contact type (one-sided, clearance, two contacts) and the
    longest run (processor time), one row per group of ``corpus.csv`` files (name ->
    paths) and, with several groups, a total row."""
    head = ["| | one-sided | clearance | two contacts | longest run |", "|---|---|---|---|---|"]
    every = []
    for _, paths in sorted(groups.items(), key=lambda kv: min(_first_seed(p) for p in kv[1])):
        rows = [r for p in paths for r in _read(Path(p))]
        if rows:
            head.append(_corpus_row(_seeds_label(rows), rows))
            every += rows
    if not every:
        raise ValueError("no corpus runs")
    if len(head) > 3:
        n_seeds = len({int(r["seed"]) for r in every})
        head.append(_corpus_row(f"all {n_seeds} seeds ({len(every)} models)", every))
    return "\n".join(head)


def _first_seed(path) -> int:
    rows = _read(Path(path))
    return min((int(r["seed"]) for r in rows), default=sys.maxsize)


# ---------------------------------------------------------------------- the exact comparison


def _exact_counts(rows: list[dict], tol: float = EXACT_TOL) -> dict:
    clean = [r for r in rows if r["clean"] == "1"]
    within = [r for r in clean if _float(r["error"]) <= tol]
    misses = [r for r in clean if not _float(r["error"]) <= tol]
    first = [r for r in clean if r["first_mode"] == "1"]
    told = [r for r in clean if r["first_mode"] == "1" or _float(r["estimate"]) >= tol]
    explained = [r for r in misses if r["reasons"]]
    return {"n": len(rows), "clean": len(clean), "within": len(within), "first": len(first),
            "told": len(told), "misses": len(misses), "explained": len(explained)}


def _sup(x: float) -> str:
    """``x`` as a superscript exponent (``1`` -> ``¹``)."""
    return f"{x:g}".translate(str.maketrans("0123456789-.", "⁰¹²³⁴⁵⁶⁷⁸⁹⁻·"))


def _pct(k: int, n: int) -> str:
    return "—" if not n else ("100 %" if k == n else f"{100 * k / n:.1f} %")


def _exact_row(label: str, by_r: dict[str, dict]) -> str:
    order = [r for r in ("static", "residual") if r in by_r]
    c0 = by_r[order[0]]

    def both(fmt):
        return "; ".join(fmt(by_r[r]) for r in order)

    return (f"| {label} | {c0['clean']} | "
            + both(lambda c: f"{c['within']} ({_pct(c['within'], c['clean'])})")
            + " | " + both(lambda c: f"{c['first']} ({_pct(c['first'], c['clean'])})")
            + " | " + both(lambda c: _pct(c["told"], c["clean"]))
            + " | " + both(lambda c: _pct(c["explained"], c["misses"]) if c["misses"] else "100 %") + " |")


def exact_table(paths: Sequence[str | Path], tol: float = EXACT_TOL) -> str:
    """The exact comparison of the ``corpus_exact.csv`` files: one row per seed and
    contact-spring range, the static and the residual proximal parameter side by side
    (``static; residual``), and a total row."""
    runs: dict[tuple, dict[str, list]] = {}
    for p in paths:
        rows = _read(Path(p))
        if not rows:
            continue
        key = (int(rows[0]["seed"]), rows[0].get("contact_decades", ""))
        runs.setdefault(key, {}).setdefault(rows[0].get("proximal") or "static", []).extend(rows)
    if not runs:
        raise ValueError("no exact-comparison runs")
    lines = ["| chains | clean exact orbits | within 1e-3 | on the first mode's orbit | first mode's orbit, "
             "or 1e-3 within its own truncation estimate | misses explained by the branch |",
             "|---|---|---|---|---|---|"]
    total: dict[str, list] = {}
    for (seed, decades), by_r in sorted(runs.items()):
        n = len(next(iter(by_r.values())))
        spring = ""
        if decades:
            lo, hi = (float(x) for x in decades.split())
            spring = f", contact spring 10{_sup(lo)}–10{_sup(hi)} N/m"
        counts = {r: _exact_counts(rs, tol) for r, rs in by_r.items()}
        lines.append(_exact_row(f"{n}, seed {seed}{spring}", counts))
        for r, rs in by_r.items():
            total.setdefault(r, []).extend(rs)
    if len(runs) > 1:
        n = len(next(iter(total.values())))
        lines.append(_exact_row(f"all, {n} chains", {r: _exact_counts(rs, tol) for r, rs in total.items()}))
    return "\n".join(lines)


# ---------------------------------------------------------------------- writing


def update_block(path: str | Path, name: str, block: str, begin: str | None = None,
                 end: str | None = None) -> bool:
    """Replace the text between the markers of ``name`` (or ``begin``/``end``) in the file
    ``path`` by ``block``; True when the file changed. Raises ValueError when the file has
    no such block."""
    if begin is None or end is None:
        begin, end = markers(name)
    path = Path(path)
    text = path.read_text()
    lines = text.split("\n")
    try:
        i, j = lines.index(begin), lines.index(end)
    except ValueError:
        raise ValueError(f"{path}: no generated {name} block (lines {begin!r} ... {end!r})") from None
    if j < i:
        raise ValueError(f"{path}: the {name} block ends before it begins")
    new = "\n".join(lines[: i + 1] + block.rstrip("\n").split("\n") + lines[j:])
    if new == text:
        return False
    path.write_text(new)
    return True


def generate(runs: str | Path, asv_results: str | Path | None = None) -> dict[str, str]:
    """The tables whose runs lie under ``runs`` (name -> Markdown); ``"asv"`` from the
    asv results ``asv_results`` (default: :func:`validation.asv_tables.find_results`'s)
    when any are found."""
    runs = Path(runs)
    out = {}
    grid = sorted((runs / "grid").rglob("study_table.csv")) if (runs / "grid").is_dir() else []
    if grid:
        out["grid"] = grid_table(grid[-1])
    corpus_dir = runs / "corpus"
    if corpus_dir.is_dir():
        groups: dict[str, list] = {}
        for p in sorted(corpus_dir.rglob("corpus.csv")):
            rel = p.relative_to(corpus_dir).parts
            groups.setdefault(rel[0] if len(rel) > 1 else ".", []).append(p)
        if groups:
            out["corpus"] = corpus_table(groups)
    exact = sorted((runs / "exact").rglob("corpus_exact.csv")) if (runs / "exact").is_dir() else []
    if exact:
        out["exact"] = exact_table(exact)
    from . import asv_tables

    try:
        out["asv"] = asv_tables.tables(asv_tables.load_run(asv_results))
    except FileNotFoundError:
        pass
    return out


def main(argv: list[str] | None = None) -> int:
    """``python -m validation tables RUNS [--update FILE ...]``."""
    parser = argparse.ArgumentParser(prog=_COMMAND, description=__doc__.split("\n\n")[0])
    parser.add_argument("runs", help="folder of the runs (grid/, corpus/<group>/, exact/)")
    parser.add_argument("--asv", default=None, metavar="RESULTS",
                        help="asv results file or folder (default .asv/results, then benchmarks/results)")
    parser.add_argument("--update", nargs="+", default=(), metavar="FILE",
                        help="write the tables into FILEs between their markers (else print them)")
    args = parser.parse_args(argv)
    tables = generate(args.runs, args.asv)
    if not tables:
        print(f"{_COMMAND}: no runs under {args.runs}", file=sys.stderr)
        return 2
    for name, block in tables.items():
        if not args.update:
            print(f"## {name}\n\n{block}\n")
        for path in args.update:
            if name == "asv":
                from .asv_tables import BEGIN, END

                begin, end = BEGIN, END
            else:
                begin, end = markers(name)
            if begin not in Path(path).read_text().split("\n"):
                continue
            changed = update_block(path, name, block, begin, end)
            print(f"{'updated' if changed else 'unchanged'} {path}: {name}")
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
