"""learning.data load and save: the format from the path, no pickle, invalid sets unwritten, one check per trial."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from learning import data
from learning.data import DataFormatError, load, load_csv_folder, load_npz, save, save_csv_folder, save_npz
from tests.learning.data_helpers import assert_same, make_demos


def test_save_dispatch_and_no_pickle(tmp_path: Path) -> None:
    d = make_demos()
    save_npz(d, tmp_path / "a.npz")
    with np.load(tmp_path / "a.npz", allow_pickle=False) as z:
        assert set(z.files) <= set(data.NPZ_FIELDS)
        for k in z.files:
            assert z[k].dtype != object
    save_csv_folder(d, tmp_path / "c")
    assert_same(load_csv_folder(tmp_path / "c"), load_npz(tmp_path / "a.npz"))


# ------------------------------------------------------------ in-memory checks


def test_invalid_demos_are_not_written(tmp_path: Path) -> None:
    d = make_demos()
    d.trials[0].act[3, 1] = np.nan
    with pytest.raises(DataFormatError):
        save(d, tmp_path / "x.npz")
    with pytest.raises(DataFormatError):
        save(d, tmp_path / "x")
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("fmt", ["d.npz", "folder"])
def test_each_trial_is_checked_once_on_load(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                            fmt: str) -> None:
    """NPZ and CSV go through the same checks, once per trial."""
    from learning.data import checks

    d = make_demos()
    save(d, tmp_path / fmt)
    seen: list[int] = []
    real = checks.check_trial

    def counting(tr, start, origin):
        seen.append(tr.trial_id)
        return real(tr, start, origin)

    monkeypatch.setattr(checks, "check_trial", counting)
    assert_same(load(tmp_path / fmt), d)
    assert seen == [10, 11, 12]
