import os
import stat

import numpy as np
import pytest

from learning.atomic import atomic_open, default_dir_mode, default_file_mode
from learning.data import Demonstrations, Trial, load, save


@pytest.fixture
def umask_022():
    old = os.umask(0o022)
    yield
    os.umask(old)


def _mode(path) -> int:
    return stat.S_IMODE(os.stat(path).st_mode)


def test_written_file_has_ordinary_permissions(tmp_path, umask_022):
    p = tmp_path / "a.json"
    with atomic_open(p) as f:
        f.write("{}")
    assert p.read_text() == "{}"
    assert _mode(p) == 0o644 == default_file_mode()
    assert default_dir_mode() == 0o755
    assert [x.name for x in tmp_path.iterdir()] == ["a.json"]  # no temporary left


def test_failure_keeps_previous_file_and_leaves_no_temporary(tmp_path):
    p = tmp_path / "a.bin"
    p.write_bytes(b"old")
    with pytest.raises(RuntimeError, match="boom"), atomic_open(p, "wb") as f:
        f.write(b"half")
        raise RuntimeError("boom")
    assert p.read_bytes() == b"old"
    assert [x.name for x in tmp_path.iterdir()] == ["a.bin"]


def test_bad_mode_is_refused(tmp_path):
    with pytest.raises(ValueError, match="mode must be"), atomic_open(tmp_path / "x", "a"):
        pass


def test_saved_data_sets_are_readable_by_others(tmp_path, umask_022):
    tr = Trial(obs=np.arange(6.0).reshape(3, 2), act=np.ones((3, 1)), t=np.arange(3) / 100.0,
               trial_id=0)
    demos = Demonstrations([tr], rate_hz=100.0)
    save(demos, tmp_path / "d.npz")
    save(demos, tmp_path / "csv")
    assert _mode(tmp_path / "d.npz") == 0o644
    assert _mode(tmp_path / "csv") == 0o755
    assert _mode(tmp_path / "csv" / "trial_000.csv") == 0o644
    assert len(load(tmp_path / "d.npz")) == len(load(tmp_path / "csv")) == 1


@pytest.fixture
def umask_077():
    old = os.umask(0o077)
    yield
    os.umask(old)


def test_kernel_applies_the_umask_and_it_is_never_changed(tmp_path, umask_077, monkeypatch):
    """Files and folders get 0666/0777 less the umask from the kernel; nothing calls
    os.umask (setting it to read it would race with other threads)."""
    calls = []
    real = os.umask
    monkeypatch.setattr(os, "umask", lambda m: calls.append(m) or real(m))
    with atomic_open(tmp_path / "a.txt") as f:
        f.write("x")
    tr = Trial(obs=np.zeros((3, 1)), act=np.ones((3, 1)), t=np.arange(3) / 100.0)
    save(Demonstrations([tr], rate_hz=100.0), tmp_path / "csv")
    assert default_file_mode() == 0o600 and default_dir_mode() == 0o700
    monkeypatch.undo()
    assert calls == []
    assert _mode(tmp_path / "a.txt") == 0o600
    assert _mode(tmp_path / "csv") == 0o700
    assert _mode(tmp_path / "csv" / "trial_000.csv") == 0o600


def test_write_json_is_strict_atomic_and_ends_with_a_newline(tmp_path):
    import json

    from learning.atomic import write_json

    path = tmp_path / "out.json"
    write_json({"a": [1.0, float("nan"), (2, float("-inf"))], "b": {"c": float("inf")}}, path)
    text = path.read_text()
    assert text.endswith("}\n") and "NaN" not in text and "Infinity" not in text
    assert json.loads(text) == {"a": [1.0, None, [2, None]], "b": {"c": None}}
    with pytest.raises(ValueError):
        write_json({"a": float("nan")}, path, non_finite="raise")
    with pytest.raises(TypeError):
        write_json({"a": object()}, path)
    assert json.loads(path.read_text())["b"] == {"c": None}  # a refused write leaves the file as it was
    assert [p.name for p in tmp_path.iterdir()] == ["out.json"]  # and no temporary file
    write_json({"t": np.float64(2.5), "x": object()}, path, indent=None, default=lambda o: "obj")
    assert path.read_text() == '{"t": 2.5, "x": "obj"}\n'
    with pytest.raises(ValueError, match="non_finite"):
        write_json({}, path, non_finite="drop")
