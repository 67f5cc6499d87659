"""NPZ data sets (learning.data.npz): round trips, minimal fields, the rate from time, atomic saves."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from learning.data import load, load_npz, save
from tests.learning.data_helpers import assert_same, make_demos
from tests.learning.data_helpers import leftovers as _leftovers


@pytest.mark.parametrize("optional", [True, False])
def test_npz_round_trip(tmp_path: Path, optional: bool) -> None:
    d = make_demos(optional=optional)
    save(d, tmp_path / "d.npz")
    back = load(tmp_path / "d.npz")
    assert_same(d, back)
    assert back.has_modes == optional and back.has_voluntary == optional
    assert [tr.subject for tr in back] == [tr.subject for tr in d]


def test_npz_minimal_fields_time_from_rate(tmp_path: Path) -> None:
    p = tmp_path / "m.npz"
    obs = np.arange(12.0).reshape(6, 2)
    np.savez(p, obs=obs, act=obs[:, :1], trial=np.array([3, 3, 3, 1, 1, 1]), rate_hz=np.array(50.0))
    d = load_npz(p)
    assert d.trial_ids == [3, 1]
    np.testing.assert_allclose(d[0].t, [0, 0.02, 0.04])
    np.testing.assert_allclose(d[1].t, [0, 0.02, 0.04])
    assert d.obs_names == ["0", "1"] and d.act_names == ["0"]
    assert [tr.subject for tr in d] == [-1, -1] and not d.has_modes


def test_npz_rate_inferred_from_time(tmp_path: Path) -> None:
    p = tmp_path / "m.npz"
    obs = np.zeros((8, 1))
    np.savez(p, obs=obs, act=obs, trial=np.repeat([0, 1], 4), t=np.tile(np.arange(4) * 0.01, 2),
             mode=np.array([0, 0, 1, 1, 2, 2, -1, -1], dtype=float))  # integral floats are fine
    d = load_npz(p)
    assert d.rate_hz == 100.0
    assert d[1].mode.dtype.kind == "i"


def test_npz_save_failure_keeps_old_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    p = tmp_path / "d.npz"
    old = make_demos(seed=1)
    save(old, p)
    before = p.read_bytes()

    def broken(f, **arrays):
        f.write(b"PK partial garbage")
        raise OSError("disk full")

    monkeypatch.setattr(np, "savez", broken)
    with pytest.raises(OSError, match="disk full"):
        save(make_demos(seed=2), p)
    monkeypatch.undo()
    assert p.read_bytes() == before
    assert_same(load(p), old)
    assert _leftovers(tmp_path) == []
