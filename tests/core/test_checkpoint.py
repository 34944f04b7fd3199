"""Checkpointing of backbones: killed, interrupted and extended runs resume point for point."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import mmshbm
from mmshbm.core.checkpoint import CheckpointWriter, read_checkpoint
from mmshbm.fe.oscillator import OneDofOscillator

BEAM_SCRIPT = """
import signal, sys, time
import mmshbm
# as in a terminal: a child of a background job (`pytest &`) starts with SIGINT ignored
signal.signal(signal.SIGINT, signal.default_int_handler)
model = mmshbm.default_beam().model(8)
def slow(u, rec):
    time.sleep(0.04)
mmshbm.backbone(model, harmonics=5, checkpoint=sys.argv[1], callback=slow)
"""


@pytest.fixture(scope="module")
def beam_full(beam8):
    """The uninterrupted reference run."""
    return mmshbm.backbone(beam8, harmonics=5)


def assert_same_branch(a, b):
    """Point for point, bit for bit."""
    assert len(a) == len(b)
    assert a.status == b.status
    np.testing.assert_array_equal(a.states, b.states)
    for name in ("frequency", "amplitude", "energy", "contact_force_max", "step_size", "newton_iterations"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert a.special_points == b.special_points
    for ha, hb in zip(a.residual_histories, b.residual_histories, strict=True):
        np.testing.assert_array_equal(ha, hb)


def count_points(path: Path) -> int:
    try:
        return max(path.read_bytes().count(b"\n") - 1, 0)
    except FileNotFoundError:
        return 0


def run_until(path: Path, n_points: int, sig: int) -> subprocess.Popen:
    """Start the slow beam backbone in a subprocess and send ``sig`` once the checkpoint
    holds ``n_points`` points."""
    env = {**os.environ, "PYTHONPATH": str(Path(mmshbm.__file__).parents[1])}
    proc = subprocess.Popen([sys.executable, "-c", BEAM_SCRIPT, str(path)], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 120
    while count_points(path) < n_points:
        if proc.poll() is not None:
            out, err = proc.communicate()
            pytest.fail(f"the run ended before it could be stopped: {err.decode()[-2000:]}")
        if time.monotonic() > deadline:  # pragma: no cover - a hung machine
            proc.kill()
            pytest.fail("no checkpoint progress in 120 s")
        time.sleep(0.01)
    proc.send_signal(sig)
    proc.communicate(timeout=60)
    return proc


def test_killed_run_resumes_point_for_point(tmp_path, beam8, beam_full):
    path = tmp_path / "beam.ckpt"
    proc = run_until(path, 40, signal.SIGKILL)
    assert proc.returncode == -signal.SIGKILL
    ck = read_checkpoint(path)
    assert ck.end is None  # killed: no end line
    n_saved = len(ck.points)
    assert 40 <= n_saved < len(beam_full)
    resumed = mmshbm.backbone(beam8, harmonics=5, resume=path, checkpoint=path)
    assert resumed.metadata["resumed_points"] == n_saved
    # the saved points (another process) and the continued ones equal the uninterrupted run
    assert_same_branch(resumed, beam_full)
    again = read_checkpoint(path)
    assert again.end == beam_full.status and len(again.points) == len(beam_full)
    np.testing.assert_array_equal(np.array([p["u"] for p in again.points]), beam_full.states)


def test_ctrl_c_leaves_a_valid_file(tmp_path, beam8, beam_full):
    path = tmp_path / "beam.ckpt"
    proc = run_until(path, 20, signal.SIGINT)
    assert proc.returncode == 0  # the backbone returned with status "interrupted"
    ck = read_checkpoint(path)
    assert ck.end == "interrupted" and len(ck.points) >= 20
    resumed = mmshbm.backbone(beam8, harmonics=5, resume=path)
    assert_same_branch(resumed, beam_full)


def test_keyboard_interrupt_in_process_and_resume_to_another_file(tmp_path):
    model = OneDofOscillator(1.0, 1.0, 4.0, 1.0).model()
    full = mmshbm.backbone(model, harmonics=3)
    seen = []

    def stop_at_7(u, rec):
        seen.append(u)
        if len(seen) == 7:
            raise KeyboardInterrupt

    first, second = tmp_path / "a.ckpt", tmp_path / "b.ckpt"
    part = mmshbm.backbone(model, harmonics=3, checkpoint=first, callback=stop_at_7)
    assert part.status == "interrupted" and len(part) == 7
    np.testing.assert_array_equal(part.states, full.states[:7])
    rest = mmshbm.backbone(model, harmonics=3, resume=first, checkpoint=second)
    assert_same_branch(rest, full)
    assert len(read_checkpoint(first).points) == 7  # the source is left alone
    assert len(read_checkpoint(second).points) == len(full)


def test_a_finished_run_extends_with_more_steps(tmp_path, beam8, beam_full):
    path = tmp_path / "short.ckpt"
    short = mmshbm.backbone(beam8, harmonics=5, max_steps=30, checkpoint=path)
    assert short.status == "max_steps" and len(short) == 31
    same = mmshbm.backbone(beam8, harmonics=5, max_steps=30, resume=path)  # nothing left to do
    assert_same_branch(same, short)
    longer = mmshbm.backbone(beam8, harmonics=5, resume=path, checkpoint=path)
    assert_same_branch(longer, beam_full)
    # a branch that ended on its bound is returned as it is
    done = mmshbm.backbone(beam8, harmonics=5, resume=path)
    assert_same_branch(done, beam_full)


def test_partial_last_line_is_ignored_and_damage_elsewhere_is_an_error(tmp_path):
    model = OneDofOscillator(1.0, 1.0, 4.0, 1.0).model()
    path = tmp_path / "osc.ckpt"
    full = mmshbm.backbone(model, harmonics=3, max_steps=8, checkpoint=path)
    lines = path.read_text().splitlines(keepends=True)
    # killed in the middle of writing point 5: header + points 0..4 + half a line
    path.write_text("".join(lines[:6]) + lines[6][: len(lines[6]) // 2])
    ck = read_checkpoint(path)
    assert len(ck.points) == 5 and ck.end is None
    resumed = mmshbm.backbone(model, harmonics=3, max_steps=8, resume=path)
    assert_same_branch(resumed, full)
    damaged = tmp_path / "damaged.ckpt"
    damaged.write_text("".join(lines[:3]) + lines[3][:20] + "\n" + "".join(lines[4:]))
    with pytest.raises(ValueError, match="damaged at line 4"):
        read_checkpoint(damaged)


def test_interrupted_write_is_truncated_to_complete_lines(tmp_path):
    path = tmp_path / "w.ckpt"
    writer = CheckpointWriter(path, {"method": "test"})
    event = {"index": 0, "u": np.arange(3.0), "tangent": np.ones(3), "ds": 0.0, "ds_next": 0.1, "steps": 0,
             "newton": 2, "history": np.array([1e-3, 1e-12]), "record": {"x": np.float64(1.5)},
             "special": [], "status": None}
    writer.point(event)

    class HalfWrite:
        """A file whose write is cut by Ctrl-C half way."""

        def __init__(self, f):
            self.f = f

        def write(self, text):
            self.f.write(text[: len(text) // 2])
            raise KeyboardInterrupt

        def __getattr__(self, name):
            return getattr(self.f, name)

    writer._file = HalfWrite(writer._file)
    with pytest.raises(KeyboardInterrupt):
        writer.point({**event, "index": 1})
    writer._file = writer._file.f
    writer.close()
    ck = read_checkpoint(path)
    assert len(ck.points) == 1 and path.read_text().endswith("\n")
    np.testing.assert_array_equal(ck.state().u[0], np.arange(3.0))
    assert ck.points[0]["record"] == {"x": 1.5}


def test_resume_rejects_another_configuration(tmp_path):
    osc = OneDofOscillator(1.0, 1.0, 4.0, 1.0)
    path = tmp_path / "osc.ckpt"
    mmshbm.backbone(osc.model(), harmonics=3, max_steps=3, checkpoint=path)
    with pytest.raises(ValueError, match=r"harmonics \(H\): file 3, now 5;.*unknowns: file 6, now 8"):
        mmshbm.backbone(osc.model(), harmonics=5, resume=path)
    with pytest.raises(ValueError, match=r"n_samples \(N\): file 64, now 128"):
        mmshbm.backbone(osc.model(), harmonics=3, n_samples=128, resume=path)
    with pytest.raises(ValueError, match="model's matrices, contact DOF, gap"):
        mmshbm.backbone(OneDofOscillator(1.0, 1.0, 4.0, 2.0).model(), harmonics=3, resume=path)
    with pytest.raises(ValueError, match="method: file 'mmshbm', now 'penalty'"):
        mmshbm.backbone(osc.model(), harmonics=3, method="penalty", resume=path)


def test_header_differences_name_entries_as_the_caller_says():
    """The core compares a header without knowing its entries: a key is named as the caller
    names it (by the key when it says nothing), settings dicts entry by entry, fingerprints
    without their values, and entries that follow from others only last."""
    from mmshbm.core import checkpoint

    stored = {"n": 6, "solver": {"H": 3, "N": 64}, "model": "ab12", "method": "a"}
    current = {"n": 8, "solver": {"H": 5, "N": 64}, "model": "cd34", "method": "a"}
    keys = ("n", "solver", "model", "method")
    assert checkpoint.header_differences(stored, current, keys) == [
        "n: file 6, now 8", "solver: file {'H': 3, 'N': 64}, now {'H': 5, 'N': 64}",
        "model: file 'ab12', now 'cd34'"]
    assert checkpoint.header_differences(
        stored, current, keys, names={"H": "harmonics", "model": "the model"}, by_entry=("solver",),
        fingerprints=("model",), last=("n",)) == [
        "harmonics: file 3, now 5", "the model (another fingerprint)", "n: file 6, now 8"]
    assert not any(isinstance(v, dict) and "H" in v for v in vars(checkpoint).values())


def test_a_checkpoint_written_before_the_names_moved_resumes(tmp_path):
    """The header's format did not change: a file's header as written before (the entries
    of a header from version 1) is compared as ever, and a matching run resumes from it."""
    osc = OneDofOscillator(1.0, 1.0, 4.0, 1.0)
    path = tmp_path / "osc.ckpt"
    full = mmshbm.backbone(osc.model(), harmonics=3, max_steps=6)
    mmshbm.backbone(osc.model(), harmonics=3, max_steps=3, checkpoint=path)
    header = json.loads(path.read_text().splitlines()[0])
    assert {"format", "version", "method", "n_unknowns", "model", "solver", "method_options"} <= set(header)
    resumed = mmshbm.backbone(osc.model(), harmonics=3, max_steps=6, resume=path)
    np.testing.assert_array_equal(resumed.frequency, full.frequency)  # the same computation repeats


def test_resume_refuses_a_checkpoint_without_the_pole_scaling(tmp_path):
    """Checkpoints written before the pole unknowns' scaling was recorded hold states in
    another scaling: resuming one is refused by name, not continued from wrong states."""
    import json

    osc = OneDofOscillator(1.0, 1.0, 4.0, 1.0)
    path = tmp_path / "osc.ckpt"
    mmshbm.backbone(osc.model(), harmonics=3, max_steps=3, checkpoint=path)
    lines = path.read_text().splitlines(keepends=True)
    header = json.loads(lines[0])
    assert header["pole_scaling"] == "force-or-motion"
    del header["pole_scaling"]
    path.write_text(json.dumps(header, separators=(",", ":")) + "\n" + "".join(lines[1:]))
    with pytest.raises(ValueError, match="scaling of the pole unknowns: file not set, now 'force-or-motion'"):
        mmshbm.backbone(osc.model(), harmonics=3, resume=path)


@pytest.mark.parametrize("content, match", [
    (None, "cannot read checkpoint file"),
    (b"", "not an mmshbm checkpoint"),
    (b"\x89PNG\r\n\x1a\n\x00\xff", "cannot read checkpoint file"),
    (b'{"format": "something else"}\n', "not an mmshbm checkpoint"),
    (b'{"format": "mmshbm.checkpoint", "version": 99}\n', "version 99"),
    (b'{"format": "mmshbm.checkpoint", "version": 1}\n', "holds no converged point"),
    (b'{"format": "mmshbm.checkpoint", "version": 1}\n{"index": 3}\n', "damaged at line 2"),
])
def test_bad_checkpoint_files(tmp_path, content, match):
    path = tmp_path / "bad.ckpt"
    if content is not None:
        path.write_bytes(content)
    with pytest.raises(ValueError, match=match):
        read_checkpoint(path).state()


def test_checkpoint_into_a_missing_directory(tmp_path):
    model = OneDofOscillator().model()
    with pytest.raises(ValueError, match="checkpoint directory .*nope.* does not exist"):
        mmshbm.backbone(model, harmonics=3, checkpoint=tmp_path / "nope" / "x.ckpt")
    with pytest.raises(ValueError, match="is a directory; give a file name"):
        mmshbm.backbone(model, harmonics=3, checkpoint=tmp_path)
    with pytest.raises(TypeError, match="resume must be a file path"):
        mmshbm.backbone(model, harmonics=3, resume=42)


def test_file_is_plain_json_lines(tmp_path):
    path = tmp_path / "osc.ckpt"
    br = mmshbm.backbone(OneDofOscillator().model(), harmonics=3, max_steps=4, checkpoint=path)
    rows = [json.loads(line) for line in path.read_text().splitlines()]
    assert rows[0]["format"] == "mmshbm.checkpoint" and rows[0]["solver"]["H"] == 3
    assert rows[-1] == {"end": "max_steps"}
    assert [r["index"] for r in rows[1:-1]] == list(range(len(br)))
    assert rows[1]["record"]["frequency"] == br.frequency[0]


@pytest.mark.parametrize("method, options", [("penalty", {"harmonics": 5}), ("shooting", {})])
def test_baselines_resume_point_for_point_with_their_records(tmp_path, method, options):
    """The baselines share the driver: resuming them is exact too, and their extra
    monitored quantities (shooting: floquet_max) reach Branch.records through the file."""
    model = OneDofOscillator().model()
    full = mmshbm.backbone(model, method=method, max_steps=16, **options)
    path = tmp_path / f"{method}.ckpt"
    part = mmshbm.backbone(model, method=method, max_steps=8, checkpoint=path, **options)
    assert len(part) == 9
    resumed = mmshbm.backbone(model, method=method, max_steps=16, resume=path, **options)
    assert_same_branch(resumed, full)
    assert resumed.records.keys() == full.records.keys()
    for name, values in full.records.items():
        np.testing.assert_array_equal(resumed.records[name], values)
    if method == "shooting":
        assert "floquet_max" in full.records and len(full.records["floquet_max"]) == len(full)


def test_plain_gives_python_numbers_and_json_types():
    """The JSON conversion turns NumPy scalars (a subclass of float among them) into
    Python numbers and keeps Python leaves as they are; complex values tagged."""
    import numpy as np

    from mmshbm.core.checkpoint import _plain, _restore

    x = {"a": np.float64(0.1), "b": np.int64(3), "c": [True, None, "s", 2.5, 7], "d": np.arange(3.0),
         1: (np.bool_(True), 1e300), "z": np.array([1 + 2j])}
    out = _plain(x)
    assert out == {"a": 0.1, "b": 3, "c": [True, None, "s", 2.5, 7], "d": [0.0, 1.0, 2.0],
                   "1": [True, 1e300], "z": {"complex": [[1.0], [2.0]]}}
    assert type(out["a"]) is float and type(out["b"]) is int and type(out["1"][0]) is bool
    assert json.loads(json.dumps(out)) == out
    np.testing.assert_array_equal(_restore(out["z"]), x["z"])
