"""Tests of learning.data: NPZ / CSV round-trips, in-memory validation, atomic saves, summary."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

import learning.data.csv as csv_format
from learning import data
from learning.data import (
    DataFormatError,
    Demonstrations,
    Trial,
    load,
    load_csv_folder,
    load_npz,
    save,
    save_csv_folder,
    save_npz,
)
from tests.learning.data_helpers import ACT, OBS, VOL, assert_same, make_demos

# ------------------------------------------------------------------ round trips


@pytest.mark.parametrize("optional", [True, False])
def test_npz_round_trip(tmp_path: Path, optional: bool) -> None:
    d = make_demos(optional=optional)
    save(d, tmp_path / "d.npz")
    back = load(tmp_path / "d.npz")
    assert_same(d, back)
    assert back.has_modes == optional and back.has_voluntary == optional
    assert [tr.subject for tr in back] == [tr.subject for tr in d]


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


def test_from_stacked_matches_stacked() -> None:
    d = make_demos()
    s = d.stacked()
    back = Demonstrations.from_stacked(rate_hz=d.rate_hz, obs_names=OBS, act_names=ACT, vol_names=VOL, **s)
    assert_same(d, back)


def test_save_dispatch_and_no_pickle(tmp_path: Path) -> None:
    d = make_demos()
    save_npz(d, tmp_path / "a.npz")
    with np.load(tmp_path / "a.npz", allow_pickle=False) as z:
        assert set(z.files) <= set(data.NPZ_FIELDS)
        for k in z.files:
            assert z[k].dtype != object
    save_csv_folder(d, tmp_path / "c")
    assert_same(load_csv_folder(tmp_path / "c"), load_npz(tmp_path / "a.npz"))


def test_summary() -> None:
    d = make_demos()
    s = d.summary()
    assert s["n_trials"] == 3 and s["n_samples"] == 40 + 45 + 50
    assert s["subjects"] == [0, 1]
    assert s["duration_s"] == pytest.approx(1.35)
    assert s["duration_s_per_subject"] == {0: pytest.approx(0.9), 1: pytest.approx(0.45)}
    assert s["rate_hz"] == 100.0 and s["obs_names"] == OBS and s["vol_names"] == VOL
    assert sum(s["mode_counts"].values()) == 135
    assert make_demos(optional=False).summary()["mode_counts"] is None
    import json
    json.dumps(s)


def test_renamed_gives_channels_new_names_and_refuses_what_does_not_fit() -> None:
    d = make_demos()
    r = d.renamed({"knife_x": ACT[0], "shoulder_elevation": VOL[-1]})
    assert r.act_names == ["knife_x", *ACT[1:]] and r.vol_names == [*VOL[:-1], "shoulder_elevation"]
    assert r.obs_names == OBS and r.trials[0] is d.trials[0] and d.act_names == ACT  # the set itself unchanged
    with pytest.raises(ValueError, match="no channel 'nope'"):
        d.renamed({"a": "nope"})
    with pytest.raises(ValueError, match="renamed twice"):
        d.renamed({"a": ACT[0], "b": f"act:{ACT[0]}"})
    with pytest.raises(ValueError, match="twice"):
        d.renamed({OBS[1]: OBS[0]})
    both = Demonstrations(d.trials, d.rate_hz, [str(j) for j in range(len(OBS))],
                          [str(j) for j in range(len(ACT))], VOL)
    with pytest.raises(ValueError, match="obs and act; write knife_x=obs:0 or knife_x=act:0"):
        both.renamed({"knife_x": "0"})
    assert both.renamed({"knife_x": "act:0"}).act_names[0] == "knife_x"


# ------------------------------------------------------------ in-memory checks


def test_trial_rejects_non_integer_mode() -> None:
    with pytest.raises(DataFormatError, match="integer") as exc:
        Trial(obs=np.zeros((3, 1)), act=np.zeros((3, 1)), t=np.arange(3.0), mode=[0, 1.5, 2])
    assert exc.value.field == "mode" and exc.value.row == 1


def test_validate_catches_problems() -> None:
    d = make_demos()
    assert d.validate() is d
    d.trials[1].trial_id = d.trials[0].trial_id
    with pytest.raises(DataFormatError, match="duplicate trial id"):
        d.validate()
    d = make_demos()
    d.trials[2].mode = None
    with pytest.raises(DataFormatError, match="some trials only"):
        d.validate()
    d = make_demos()
    d.obs_names[1] = "a,b"
    with pytest.raises(DataFormatError, match="channel name"):
        d.validate()
    d = make_demos()
    d.trials[0].act = d.trials[0].act[:, :2]
    with pytest.raises(DataFormatError, match="act channels"):
        d.validate()
    d = make_demos()
    d.trials[1].obs[4, 0] = np.nan
    with pytest.raises(DataFormatError, match="trial 11: non-finite") as exc:
        d.validate()
    assert exc.value.row == 4 and exc.value.field == "obs"
    with pytest.raises(DataFormatError, match="no trials"):
        Demonstrations([], 10.0).validate()
    with pytest.raises(DataFormatError, match="rate_hz"):
        Demonstrations(make_demos().trials, -1.0).validate()


# --------------------------------------------------------------- atomic saves


def _leftovers(folder: Path) -> list[str]:
    return sorted(n for n in os.listdir(folder) if n.startswith("."))


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


def test_invalid_demos_are_not_written(tmp_path: Path) -> None:
    d = make_demos()
    d.trials[0].act[3, 1] = np.nan
    with pytest.raises(DataFormatError):
        save(d, tmp_path / "x.npz")
    with pytest.raises(DataFormatError):
        save(d, tmp_path / "x")
    assert os.listdir(tmp_path) == []


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
