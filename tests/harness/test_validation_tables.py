"""The generated tables of docs/validation.md (validation.tables): counts
from hand-made run files, the columns the CLI writes, the blocks between their markers."""

import csv
from pathlib import Path

import pytest
from locations import ROOT

from mmshbm.cli import main
from validation import tables as vt
from validation.__main__ import main as validation_main

CORPUS_COLUMNS = ["index", "seed", "kind", "contact", "harmonics", "completed", "status", "seconds", "points",
                  "jumps", "frequency", "path_completed", "same_as_path", "cpu_seconds"]


def _write(path: Path, columns: list[str], rows: list[dict]) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, columns, restval="")
        w.writeheader()
        w.writerows(rows)
    return path


def _corpus(path, seed, outcomes, cpu=1.0):
    """``outcomes``: (contact, completed) per model."""
    rows = [{"index": i, "seed": seed, "kind": "chain", "contact": c, "harmonics": 5, "completed": int(done),
             "status": "bound:amplitude", "seconds": 9.0, "cpu_seconds": cpu + i} for i, (c, done) in
            enumerate(outcomes)]
    return _write(path, CORPUS_COLUMNS, rows)


def test_corpus_rows_count_each_contact_type(tmp_path):
    a = [("one-sided", True)] * 3 + [("one-sided", False), ("clearance", True), ("several", False)]
    b = [("one-sided", True), ("clearance", True), ("clearance", False)]
    groups = {"early": [_corpus(tmp_path / "e1.csv", 19, a), _corpus(tmp_path / "e2.csv", 21, a[:2])],
              "late": [_corpus(tmp_path / "l.csv", 37, b, cpu=3.5)]}
    lines = vt.corpus_table(groups).split("\n")
    # 5 of 6 one-sided, 1 clearance, 0 of 1 two contacts; the longest run: processor time 1 + 5
    assert lines[2] == "| seeds 19, 21 (8 models) | 5 / 6 (83.33 %) | 1 / 1 (100 %) | 0 / 1 | 6.0 s |"
    assert lines[3] == "| seed 37 (3 models) | 1 / 1 (100 %) | 1 / 2 (50.00 %) | — | 5.5 s |"
    assert lines[4] == "| all 3 seeds (11 models) | 6 / 7 (85.71 %) | 2 / 3 (66.67 %) | 0 / 1 | 6.0 s |"


def test_seed_ranges():
    assert vt._ranges([21, 19, 20, 25, 26, 27, 30]) == "19–21, 25–27, 30"


EXACT_COLUMNS = ["index", "seed", "clean", "error", "first_mode", "estimate", "reasons", "proximal",
                 "contact_decades"]


def test_exact_rows_put_both_proximal_parameters_side_by_side(tmp_path):
    def rows(r, errors, estimates, first, reasons, decades=""):
        return [{"index": i, "seed": 31, "clean": int(e is not None), "error": "nan" if e is None else e,
                 "first_mode": int(f), "estimate": s, "reasons": why, "proximal": r,
                 "contact_decades": decades}
                for i, (e, s, f, why) in enumerate(zip(errors, estimates, first, reasons, strict=True))]

    # four chains, three clean: static r misses two (one by its estimate, one coexisting orbit
    # that is the first mode's), residual r misses one, explained by nothing
    static = rows("static", [1e-4, 5e-3, 2e-3, None], [1e-5, 6e-3, 1e-4, 0], [1, 0, 1, 0],
                  ["", "truncation estimate 6.0e-03", "coexisting orbits", ""], "1 5")
    residual = rows("residual", [1e-4, 2e-4, 2e-3, None], [1e-5, 1e-4, 1e-4, 0], [1, 1, 0, 0],
                    ["", "", "", ""], "1 5")
    paths = [_write(tmp_path / "s.csv", EXACT_COLUMNS, static),
             _write(tmp_path / "r.csv", EXACT_COLUMNS, residual)]
    lines = vt.exact_table(paths).split("\n")
    assert lines[2] == ("| 4, seed 31, contact spring 10¹–10⁵ N/m | 3 | 1 (33.3 %); 2 (66.7 %) | 2 (66.7 %); "
                        "2 (66.7 %) | 100 %; 66.7 % | 100 %; 0.0 % |")
    assert len(lines) == 3  # one seed: no total row


def test_grid_marks_cautions_and_empty_cells(tmp_path):
    columns = ["method", "elements", "harmonics", "f_at_2gap_hz", "f_at_5gap_hz", "status", "note_at_2gap",
               "note_at_5gap"]
    rows = [{"elements": 8, "harmonics": 1, "f_at_2gap_hz": 52.957, "f_at_5gap_hz": 59.5501},
            {"elements": 8, "harmonics": 3, "f_at_2gap_hz": 57.064, "f_at_5gap_hz": "nan",
             "note_at_2gap": "next to a discontinuity", "note_at_5gap": "inside 5:2"}]
    text = vt.grid_table(_write(tmp_path / "study_table.csv", columns, rows))
    assert text.split("\n")[-1] == "| 8 | 52.96 / 59.55 | 57.06\\* / — |"
    assert text.startswith("f (Hz) at 2 / 5 gaps:")


def test_update_writes_between_the_markers_only(tmp_path):
    begin, end = vt.markers("corpus")
    doc = tmp_path / "v.md"
    doc.write_text(f"# V\n\n{begin}\nold\n{end}\n\ntail\n")
    assert vt.update_block(doc, "corpus", "| new |")
    assert doc.read_text() == f"# V\n\n{begin}\n| new |\n{end}\n\ntail\n"
    assert not vt.update_block(doc, "corpus", "| new |")
    with pytest.raises(ValueError, match="no generated grid block"):
        vt.update_block(doc, "grid", "x")


def test_the_runs_the_cli_writes_make_the_tables(tmp_path, capsys):
    """A small study, corpus and exact comparison through the command line, then the one command: the files
    the CLI writes carry the columns the tables read, and the document is rewritten."""
    runs = tmp_path / "runs"
    assert main(["study", "-H", "1", "3", "--elements", "4", "--executor", "serial", "--max-amplitude", "2",
                 "--amplitudes", "1.5", "2", "--out", str(runs / "grid")]) == 0
    seed_2 = runs / "corpus" / "a" / "seed-2"
    assert validation_main(["corpus", "3", "--seed", "2", "--out", str(seed_2)]) == 0
    rows = list(csv.DictReader(open(seed_2 / "corpus.csv")))
    for r in ("static", "residual"):
        out = str(runs / "exact" / r)
        assert validation_main(["exact", "2", "--seed", "3", "--proximal", r, "--out", out]) == 0
    doc = tmp_path / "validation.md"
    blocks = "\n\n".join("\n".join(vt.markers(n)) for n in ("grid", "corpus", "exact"))
    doc.write_text(f"# Validation\n\n{blocks}\n")
    capsys.readouterr()
    assert validation_main(["tables", str(runs), "--update", str(doc)]) == 0
    out = capsys.readouterr().out
    assert all(f"updated {doc}: {name}" in out for name in ("grid", "corpus", "exact"))
    text = doc.read_text()
    assert "| elements \\ H | 1 | 3 |" in text and "| 4 | " in text
    assert f"| seed 2 ({len(rows)} models) |" in text
    # seed 3's second chain is clean and on the exact orbit with either r, its first is not
    # clean (test_corpus.py::test_cli_corpus_exact)
    exact = list(csv.DictReader(open(runs / "exact" / "static" / "corpus_exact.csv")))
    assert [r["clean"] for r in exact] == ["0", "1"] and exact[0]["proximal"] == "static"
    both = "1 (100 %); 1 (100 %)"
    assert f"| 2, seed 3 | 1 | {both} | {both} | 100 %; 100 % | 100 %; 100 % |" in text
    assert vt.main([str(tmp_path / "nothing"), "--asv", str(tmp_path / "no-asv")]) == 2  # no runs at all


def test_published_blocks_are_the_generators_output():
    """docs/validation.md has every generated block, and its benchmark tables are those
    the committed asv record gives (rerunning the generator changes nothing)."""
    from validation import asv_tables

    root = ROOT
    text = (root / "docs" / "validation.md").read_text()
    for name in ("grid", "corpus", "exact"):
        begin, end = vt.markers(name)
        assert text.index(begin) < text.index(end)
    block = text.split(asv_tables.BEGIN + "\n", 1)[1].split("\n" + asv_tables.END, 1)[0]
    assert block == asv_tables.tables(asv_tables.load_run(root / "benchmarks" / "results"))
