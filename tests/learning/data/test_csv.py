"""CSV-folder data sets (learning.data.csv): round trips, atomic saves, other files, CRLF and BOM."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

import learning.data.csv as csv_format
from learning.data import load, save
from tests.learning.data_helpers import OBS, assert_same, make_demos
from tests.learning.data_helpers import leftovers as _leftovers


@pytest.mark.parametrize("optional", [True, False])
def test_csv_round_trip(tmp_path: Path, optional: bool) -> None:
    d = make_demos(optional=optional)
    save(d, tmp_path / "folder")
    files = sorted(os.listdir(tmp_path / "folder"))
    assert files == ["trial_010.csv", "trial_011.csv", "trial_012.csv"]
    header = (tmp_path / "folder" / "trial_010.csv").read_text().splitlines()[0].split(",")
    assert header[:1 + len(OBS)] == ["t"] + [f"obs_{n}" for n in OBS]
    back = load(tmp_path / "folder")
    assert_same(d, back)  # floats written with 17 significant digits: exact
    assert [tr.trial_id for tr in back] == [10, 11, 12]


def test_csv_save_failure_keeps_old_folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    p = tmp_path / "f"
    old = make_demos(seed=1)
    save(old, p)
    calls = {"n": 0}
    real = csv_format._write_csv_trial

    def flaky(*args, **kwargs):
        calls["n"] += 1
        if calls["n"] == 2:
            raise OSError("disk full")
        return real(*args, **kwargs)

    monkeypatch.setattr(csv_format, "_write_csv_trial", flaky)
    with pytest.raises(OSError, match="disk full"):
        save(make_demos(seed=2), p)
    monkeypatch.undo()
    assert_same(load(p), old)
    assert _leftovers(tmp_path) == []


def test_csv_save_replaces_existing_folder(tmp_path: Path) -> None:
    p = tmp_path / "f"
    save(make_demos(n_trials=4), p)
    new = make_demos(n_trials=2, seed=5)
    save(new, p)
    assert sorted(os.listdir(p)) == ["trial_010.csv", "trial_011.csv"]
    assert_same(load(p), new)
    assert _leftovers(tmp_path) == []


def test_csv_save_refuses_folder_with_other_files(tmp_path: Path) -> None:
    p = tmp_path / "f"
    p.mkdir()
    (p / "precious.txt").write_text("keep me")
    with pytest.raises(FileExistsError, match="precious.txt"):
        save(make_demos(), p)
    assert os.listdir(p) == ["precious.txt"]
    assert _leftovers(tmp_path) == []


def test_csv_tolerates_crlf_and_byte_order_mark(tmp_path: Path) -> None:
    (tmp_path / "trial_004.csv").write_bytes(
        b"\xef\xbb\xbft,obs_a,act_b,subject\r\n0,1,2,3\r\n0.01,1,2,3\r\n0.02,3,4,3\r\n")
    d = load(tmp_path)
    assert d.trial_ids == [4] and d.subjects == [3] and d.rate_hz == 100.0
    np.testing.assert_array_equal(d[0].obs[:, 0], [1, 1, 3])
