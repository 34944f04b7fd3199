"""The study throughput (validation.throughput, ``python -m validation throughput``):
every executor gives the serial numbers, and the efficiency is the ratio it says."""

import json

import pytest

from validation.__main__ import main


def test_cli_throughput(tmp_path):
    assert main(["throughput", "4", "-H", "1", "--elements", "4", "--max-amplitude", "2",
                 "--executor", "process", "--chunksize", "2", "--out", str(tmp_path)]) == 0
    data = json.loads((tmp_path / "throughput.json").read_text())
    runs = {(r["executor"], r["warm"]): r for r in data["runs"]}
    assert set(runs) == {("serial", True), ("process", False), ("process", True)}
    assert all(r["identical"] for r in runs.values())
    r = runs[("process", True)]
    assert r["tasks"] == 2 and r["efficiency"] == pytest.approx(data["serial_s"] / (2 * r["wall_s"]))
    assert "backbones/s" in (tmp_path / "throughput.txt").read_text()
    assert main(["throughput", "0"]) == 2
