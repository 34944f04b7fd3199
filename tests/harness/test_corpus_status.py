"""The corpus harness classifies each case from structured values (validation.corpus):
the status kind and detail of :class:`~mmshbm.core.status.Status`, the family search's
:class:`~mmshbm.family.end.FamilyEnd` on the status, and the raised exception, never
from the status text; corpus.csv keeps its columns in order and adds the new ones at the
end."""

import csv
import math
import re

import pytest

from mmshbm.core.status import Status
from validation import corpus
from validation.__main__ import main as validation_main

#: the columns corpus.csv had before the structured ones, in order
OLD_COLUMNS = ("index", "seed", "kind", "contact", "harmonics", "completed", "status", "seconds", "points",
               "jumps", "frequency", "path_completed", "same_as_path", "cpu_seconds")

CASES = corpus.generate(3, seed=0)


def _result(i, status, **kw):
    return corpus.CaseResult(CASES[i], False, status, 0.1, 10, 0, 1.0, **kw)


def test_the_summary_counts_from_the_fields_not_the_text():
    """A status text that names an exception or a family's end does not count as one; the
    fields do, whatever the text says."""
    misleading = [
        _result(0, "max_steps: exception: family ended",
                status_kind=Status.MAX_STEPS, status_detail="exception"),
        _result(1, "ds_min: family ended: ...", status_kind=Status.DS_MIN),
    ]
    for r in misleading:
        assert not r.raised and not r.family_ended
    text = corpus.summary(misleading)
    assert "exceptions: 0;" in text
    assert "family ended (" not in text

    counted = [
        _result(0, "a text without a kind", status_kind=corpus.EXCEPTION, status_detail="ValueError: x"),
        _result(1, "jump failed: ...", status_kind=Status.JUMP_FAILED),
        _result(2, "family ended: ...", status_kind=Status.FAMILY_ENDED),
    ]
    assert [r.raised for r in counted] == [True, False, False]
    assert [r.family_ended for r in counted] == [False, False, True]
    text = corpus.summary(counted)
    assert "exceptions: 1;" in text
    assert re.search(r"^family ended \(.*\): 1$", text, re.M)
    assert "exception: ValueError: x" in text  # the failure's reason, from kind and detail


def test_a_status_read_back_as_text_has_its_kind_and_detail():
    """Without a kind (a result built from a status read back from a file) the kind and
    detail are those of ``Status.parse``; an exception's text has the kind EXCEPTION."""
    r = _result(0, "ds_min: step size fell below 1e-07 (at 2.1 gaps)")
    assert (r.status_kind, r.status_detail) == (Status.DS_MIN, "step size fell below 1e-07 (at 2.1 gaps)")
    assert r.reason == "ds_min: step size fell below 1e-07 (at 2.1 gaps)"
    r = _result(1, "exception: ZeroDivisionError: float division by zero")
    assert r.raised and r.status_detail == "ZeroDivisionError: float division by zero"
    r = _result(2, "bound:frequency")
    assert (r.status_kind, r.status_detail, r.reason) == (Status.BOUND, "frequency", "bound:frequency")
    assert _result(2, "bound:amplitude").reason == "bound off the family"


def test_csv_columns_keep_the_old_ones_first():
    assert corpus.CSV_COLUMNS[:len(OLD_COLUMNS)] == OLD_COLUMNS
    assert {"status_kind", "status_detail", "raised", "family_ended"} <= set(
        corpus.CSV_COLUMNS[len(OLD_COLUMNS):])
    assert len(set(corpus.CSV_COLUMNS)) == len(corpus.CSV_COLUMNS)
    r = _result(1, "jump failed: x", status_kind=Status.JUMP_FAILED, status_detail="x")
    row = dict(zip(corpus.CSV_COLUMNS, corpus.csv_row(r), strict=True))
    assert (row["index"], row["status"], row["status_kind"], row["status_detail"]) == (1, "jump failed: x",
                                                                                      "jump failed", "x")
    assert (row["raised"], row["family_ended"], row["completed"]) == (0, 0, 0)


def _raise(*args, **kwargs):
    raise RuntimeError("no model")


def test_a_case_that_raises_is_an_exception_result_and_the_command_fails(monkeypatch, tmp_path, capsys):
    monkeypatch.setattr(corpus, "_spring_mass_model", _raise)
    monkeypatch.setattr(corpus, "_beam_model", _raise)
    r = corpus.run_case(CASES[0])
    assert r.raised and not r.completed and r.status_kind == corpus.EXCEPTION
    assert r.status_detail == "RuntimeError: no model"
    assert validation_main(["corpus", "1", "--seed", "0", "--out", str(tmp_path)]) == 1
    capsys.readouterr()
    rows = list(csv.DictReader(open(tmp_path / "corpus.csv")))
    assert len(rows) == 1 and rows[0]["raised"] == "1" and rows[0]["status_kind"] == corpus.EXCEPTION


#: two models that reach their bound in a fraction of a second (one-sided, two contacts)
QUICK = [corpus.generate(10, seed=1, harmonics=(1, 3))[i] for i in (2, 5)]


@pytest.mark.parametrize("case", QUICK, ids=lambda c: c.label)
def test_a_real_run_carries_the_status_value(case):
    """The default run to 10 gaps: the kind and detail are the branch status's; with
    ``max_steps`` 3 the run stops short, of kind ``max_steps``."""
    r = corpus.run_case(case, time_limit=30.0)
    assert r.completed and (r.status_kind, r.status_detail) == (Status.BOUND, "amplitude")
    assert not (r.raised or r.family_ended) and math.isfinite(r.frequency)
    assert r.status == "bound:amplitude" and type(r.status) is str
    short = corpus.run_case(case, time_limit=30.0, options={"max_steps": 3})
    assert not short.completed and short.status_kind == Status.MAX_STEPS and not short.raised
    row = dict(zip(corpus.CSV_COLUMNS, corpus.csv_row(short), strict=True))
    assert row["status_kind"] == "max_steps" and row["completed"] == 0 and row["raised"] == 0
