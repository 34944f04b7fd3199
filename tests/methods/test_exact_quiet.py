"""The exact reference reports a failed point in its result, never on stderr: nothing it
logs reaches the WARNING level (which Python's last-resort handler prints when the caller
configured no logging)."""

from __future__ import annotations

import logging

import numpy as np

from mmshbm import OneDofOscillator, exact


def test_a_failed_point_is_in_the_result_not_on_stderr(caplog, capfd, monkeypatch):
    # as a library caller without logging configured: no handler a command line run in this
    # process may have left on the package's logger
    monkeypatch.setattr(logging.getLogger("mmshbm"), "handlers", [])
    model = OneDofOscillator(m=1.0, k1=1.0, k2=4.0, gap=1.0).model()
    caplog.set_level(logging.DEBUG, logger="mmshbm")
    # one Newton iteration from the open orbit's guess cannot reach the 1e-13 residual past the gap,
    # and no halving is allowed: the points above the gap fail
    bb = exact.backbone(model, np.array([0.5, 2.0, 3.0]), max_halvings=0, max_iter=1)
    assert not bb.converged.all()
    failed = [r for r in caplog.records if "no converged orbit" in r.getMessage()]
    assert len(failed) == np.count_nonzero(~bb.converged)
    assert all(r.levelno < logging.WARNING for r in caplog.records if r.name.startswith("mmshbm"))
    assert capfd.readouterr().err == ""
