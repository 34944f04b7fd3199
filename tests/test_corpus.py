"""The corpus of random models (mmshbm.analysis.corpus): reproducible cases, valid models,
and a fast slice of the defaults' figures (every model of the slice reaches its bound on
the first mode's family, none raises, none runs past its limit)."""

import numpy as np
import pytest

from mmshbm.analysis import corpus
from mmshbm.cli import main


def test_cases_are_reproducible_and_independent_of_the_count():
    a = corpus.generate(30, seed=4)
    b = corpus.generate(12, seed=4)
    assert a[:12] == b
    assert corpus.generate(5, seed=5) != corpus.generate(5, seed=4)
    kinds = {(c.kind, c.contact) for c in corpus.generate(200, seed=0)}
    assert {("chain", "one-sided"), ("tree", "clearance"), ("beam", "one-sided"), ("beam", "clearance"),
            ("chain", "several")} <= kinds
    assert ("beam", "several") not in kinds


def test_models_are_valid_and_clearances_measure_a_dof_with_mass():
    for case in corpus.generate(60, seed=1):
        m = case.model()
        assert m.massless_contacts
        if case.contact == "clearance":
            assert m.n_contacts == 2 and len(set(m.contact_dofs)) == 1
            assert m.amplitude_dof in set(m.l.tolist())
        elif case.contact == "several":
            assert len(set(m.contact_dofs)) == 2
        assert np.all(np.isfinite(m.linear_frequencies(1)))


def test_bad_corpus_requests():
    with pytest.raises(ValueError, match="unknown kind"):
        corpus.generate(3, kinds=("plate",))
    with pytest.raises(ValueError, match="unknown contact type"):
        corpus.generate(3, contacts=("glue",))


#: a slice chosen for speed (small H), not for success: every case of it is run
SLICE = [c for c in corpus.generate(40, seed=0, harmonics=(1, 3, 5)) if c.kind != "beam"][:16]


@pytest.mark.parametrize("case", SLICE, ids=lambda c: c.label)
def test_the_defaults_reach_the_bound_on_the_family(case):
    r = corpus.run_case(case, time_limit=30.0)
    assert r.completed, (case, r.status)
    assert r.seconds < 30.0


def test_cli_corpus(tmp_path, capsys):
    assert main(["bench", "--corpus", "4", "--seed", "2", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "complete" in out and "exceptions: 0" in out
    rows = (tmp_path / "corpus.csv").read_text().splitlines()
    assert len(rows) == 5
