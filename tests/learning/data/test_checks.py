"""Tests of learning.data's load errors: a bad NPZ file or CSV folder names its file, field and row."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from learning.data import DataFormatError, Demonstrations, load, save_csv_folder
from tests.learning.data_helpers import make_demos


def stacked_arrays(demos: Demonstrations) -> dict[str, np.ndarray]:
    arrays = demos.stacked()
    arrays.update(obs_names=np.array(demos.obs_names), act_names=np.array(demos.act_names),
                  rate_hz=np.array(demos.rate_hz))
    if demos.has_voluntary:
        arrays["vol_names"] = np.array(demos.vol_names)
    return arrays


def check_error(exc: pytest.ExceptionInfo, path, field, row) -> None:
    """The error names file, field and row (attributes and message)."""
    e = exc.value
    msg = str(e)
    assert e.path == str(path)
    assert str(path) in msg
    assert e.field == field
    if field is not None:
        assert f"field '{field}'" in msg
    assert e.row == row
    if row is not None:
        assert f"row {row}" in msg


# ------------------------------------------------------------------ NPZ errors


def write_npz(tmp_path: Path, **override) -> Path:
    arrays = stacked_arrays(make_demos())
    for k, v in override.items():
        if v is None:
            arrays.pop(k, None)
        else:
            arrays[k] = v
    p = tmp_path / "bad.npz"
    np.savez(p, **arrays)
    return p


def base() -> dict[str, np.ndarray]:
    return make_demos().stacked()


@pytest.mark.parametrize("fld, col, value, row", [
    ("obs", 2, np.nan, 17), ("act", 0, np.inf, 50), ("voluntary", 1, -np.inf, 3), ("t", None, np.nan, 90),
])
def test_npz_non_finite(tmp_path: Path, fld, col, value, row) -> None:
    a = base()[fld].copy()
    if col is None:
        a[row] = value
    else:
        a[row, col] = value
    p = write_npz(tmp_path, **{fld: a})
    with pytest.raises(DataFormatError, match="non-finite") as exc:
        load(p)
    check_error(exc, p, fld, row)
    if col is not None:
        assert f"column {col}" in str(exc.value)


def test_npz_ragged_act(tmp_path: Path) -> None:
    p = write_npz(tmp_path, act=base()["act"][:-3])
    with pytest.raises(DataFormatError, match="rows but obs has") as exc:
        load(p)
    check_error(exc, p, "act", 132)


def test_npz_ragged_names(tmp_path: Path) -> None:
    p = write_npz(tmp_path, obs_names=np.array(["a", "b"]))
    with pytest.raises(DataFormatError, match="2 names but 4 channels") as exc:
        load(p)
    check_error(exc, p, "obs_names", None)


def test_npz_ragged_mode(tmp_path: Path) -> None:
    p = write_npz(tmp_path, mode=base()["mode"][:100])
    with pytest.raises(DataFormatError, match="shape") as exc:
        load(p)
    check_error(exc, p, "mode", 100)


def test_npz_single_sample_trial(tmp_path: Path) -> None:
    tr = base()["trial"].copy()
    tr[-1] = 99  # the last row becomes its own trial
    p = write_npz(tmp_path, trial=tr)
    with pytest.raises(DataFormatError, match="single-sample") as exc:
        load(p)
    check_error(exc, p, "trial", 134)


def test_npz_empty(tmp_path: Path) -> None:
    p = tmp_path / "e.npz"
    np.savez(p, obs=np.zeros((0, 2)), act=np.zeros((0, 1)), trial=np.zeros(0, int), rate_hz=np.array(10.0))
    with pytest.raises(DataFormatError, match="no samples") as exc:
        load(p)
    check_error(exc, p, "obs", None)


def test_npz_non_contiguous_trial(tmp_path: Path) -> None:
    tr = base()["trial"].copy()
    tr[60:62] = 10  # trial 10 (rows 0..39) reappears inside trial 11
    p = write_npz(tmp_path, trial=tr)
    with pytest.raises(DataFormatError, match="not contiguous") as exc:
        load(p)
    check_error(exc, p, "trial", 60)


@pytest.mark.parametrize("delta", [0.0, -0.5])
def test_npz_time_not_increasing(tmp_path: Path, delta: float) -> None:
    t = base()["t"].copy()
    t[45] = t[44] + delta
    p = write_npz(tmp_path, t=t)
    with pytest.raises(DataFormatError, match="not strictly increasing") as exc:
        load(p)
    check_error(exc, p, "t", 45)


def test_npz_time_does_not_match_rate(tmp_path: Path) -> None:
    p = write_npz(tmp_path, rate_hz=np.array(50.0))
    with pytest.raises(DataFormatError, match="does not match rate_hz") as exc:
        load(p)
    check_error(exc, p, "t", None)


def test_npz_unknown_field(tmp_path: Path) -> None:
    p = write_npz(tmp_path, extra=np.zeros(3))
    with pytest.raises(DataFormatError, match="unknown field") as exc:
        load(p)
    check_error(exc, p, "extra", None)


@pytest.mark.parametrize("missing", ["obs", "act", "trial"])
def test_npz_missing_required(tmp_path: Path, missing: str) -> None:
    p = write_npz(tmp_path, **{missing: None})
    with pytest.raises(DataFormatError, match="required field missing") as exc:
        load(p)
    check_error(exc, p, missing, None)


def test_npz_neither_time_nor_rate(tmp_path: Path) -> None:
    p = write_npz(tmp_path, t=None, rate_hz=None)
    with pytest.raises(DataFormatError, match="neither") as exc:
        load(p)
    check_error(exc, p, "rate_hz", None)


def test_npz_subject_changes_within_trial(tmp_path: Path) -> None:
    s = base()["subject"].copy()
    s[70] = 5
    p = write_npz(tmp_path, subject=s)
    with pytest.raises(DataFormatError, match="subject changes") as exc:
        load(p)
    check_error(exc, p, "subject", 70)


def test_npz_non_integer_mode(tmp_path: Path) -> None:
    m = base()["mode"].astype(float)
    m[33] = 1.5
    p = write_npz(tmp_path, mode=m)
    with pytest.raises(DataFormatError, match="integer") as exc:
        load(p)
    check_error(exc, p, "mode", 33)


def test_npz_mode_below_minus_one(tmp_path: Path) -> None:
    m = base()["mode"].copy()
    m[81] = -2
    p = write_npz(tmp_path, mode=m)
    with pytest.raises(DataFormatError, match="< -1") as exc:
        load(p)
    check_error(exc, p, "mode", 81)


def test_npz_object_array_refused(tmp_path: Path) -> None:
    p = write_npz(tmp_path, obs_names=np.array(["a", 1, None, 2.0], dtype=object))
    with pytest.raises(DataFormatError, match="without pickle") as exc:
        load(p)
    check_error(exc, p, "obs_names", None)


def test_npz_not_a_zip(tmp_path: Path) -> None:
    p = tmp_path / "junk.npz"
    p.write_bytes(b"not a zip file at all")
    with pytest.raises(DataFormatError, match="not an NPZ archive .not a zip file") as exc:
        load(p)
    check_error(exc, p, None, None)


def test_npz_that_is_a_single_npy_array(tmp_path: Path) -> None:
    p = tmp_path / "one.npz"
    with open(p, "wb") as f:
        np.save(f, np.zeros(3))
    with pytest.raises(DataFormatError, match="single .npy array"):
        load(p)


def test_load_missing_and_unknown_format(tmp_path: Path) -> None:
    with pytest.raises(DataFormatError, match="no such"):
        load(tmp_path / "nope.npz")
    with pytest.raises(DataFormatError, match="no such"):
        load(tmp_path / "nope")
    (tmp_path / "x.txt").write_text("hi")
    with pytest.raises(DataFormatError, match="unknown format"):
        load(tmp_path / "x.txt")


# ------------------------------------------------------------------ CSV errors


@pytest.fixture
def csv_dir(tmp_path: Path) -> Path:
    p = tmp_path / "csv"
    save_csv_folder(make_demos(), p)
    return p


def edit_csv(path: Path, row: int, column: str, value: str) -> None:
    """Set one cell (data row ``row``, 0-based) of a CSV file."""
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    cells = lines[row + 1].split(",")
    cells[header.index(column)] = value
    lines[row + 1] = ",".join(cells)
    path.write_text("\n".join(lines) + "\n")


@pytest.mark.parametrize("name, row, column, value, match", [
    ("trial_011.csv", 7, "obs_y", "nan", "non-finite"),
    ("trial_011.csv", 7, "act_kz", "inf", "non-finite"),
    ("trial_011.csv", 7, "vol_prot", "-inf", "non-finite"),
    ("trial_011.csv", 7, "t", "nan", "non-finite"),
    ("trial_011.csv", 7, "obs_roll", "abc", "not a number"),
    ("trial_011.csv", 7, "act_kx", "", "not a number"),
    ("trial_011.csv", 12, "t", "0.0", "not strictly increasing"),
    ("trial_010.csv", 9, "subject", "3", "subject changes"),
    ("trial_011.csv", 21, "mode", "2.5", "integer"),
])
def test_csv_bad_cell(csv_dir: Path, name: str, row: int, column: str, value: str, match: str) -> None:
    """One bad cell: the error names its file, column and data row."""
    f = csv_dir / name
    edit_csv(f, row, column, value)
    with pytest.raises(DataFormatError, match=match) as exc:
        load(csv_dir)
    check_error(exc, f, column, row)


def test_csv_ragged_row(csv_dir: Path) -> None:
    f = csv_dir / "trial_012.csv"
    lines = f.read_text().splitlines()
    lines[5] = lines[5].rsplit(",", 1)[0]  # data row 4 loses its last cell
    f.write_text("\n".join(lines) + "\n")
    with pytest.raises(DataFormatError, match="values but the header has") as exc:
        load(csv_dir)
    check_error(exc, f, None, 4)
    assert "file line 6" in str(exc.value)


@pytest.mark.parametrize("text, match, column", [
    ("t,obs_a,act_b,speed\n0,1,2,1\n0.01,1,2,1\n", "unknown column", "speed"),
    ("obs_a,act_b\n1,2\n1,2\n", "required column missing", "t"),
    ("t,obs_a\n0,1\n0.01,2\n", "no act_", "act_*"),
    ("t,obs_a,obs_a,act_b\n0,1,1,1\n0.01,2,2,2\n", "duplicate column", "obs_a"),
])
def test_csv_bad_header(tmp_path: Path, text: str, match: str, column: str) -> None:
    """A header the format does not allow: the error names the file and the column."""
    f = tmp_path / "trial_000.csv"
    f.write_text(text)
    with pytest.raises(DataFormatError, match=match) as exc:
        load(tmp_path)
    check_error(exc, f, column, None)


def test_csv_empty_and_single_sample(tmp_path: Path) -> None:
    f = tmp_path / "trial_000.csv"
    f.write_text("t,obs_a,act_b\n")
    with pytest.raises(DataFormatError, match="empty trial") as exc:
        load(tmp_path)
    check_error(exc, f, "t", None)
    f.write_text("t,obs_a,act_b\n0,1,2\n")
    with pytest.raises(DataFormatError, match="single-sample") as exc:
        load(tmp_path)
    check_error(exc, f, "obs", 0)
    f.write_text("")
    with pytest.raises(DataFormatError, match="no header"):
        load(tmp_path)


def test_csv_inconsistent_channel_names(csv_dir: Path) -> None:
    f = csv_dir / "trial_012.csv"
    text = f.read_text().splitlines()
    f.write_text("\n".join([text[0].replace("obs_y", "obs_w")] + text[1:]) + "\n")
    with pytest.raises(DataFormatError, match="differ from") as exc:
        load(csv_dir)
    check_error(exc, f, "obs_*", None)
    assert "trial_010.csv" in str(exc.value)


def test_csv_optional_column_in_some_files_only(tmp_path: Path) -> None:
    (tmp_path / "trial_000.csv").write_text("t,obs_a,act_b,mode\n0,1,2,0\n0.01,1,2,1\n")
    (tmp_path / "trial_001.csv").write_text("t,obs_a,act_b\n0,1,2\n0.01,1,2\n")
    with pytest.raises(DataFormatError, match="absent here but present") as exc:
        load(tmp_path)
    check_error(exc, tmp_path / "trial_001.csv", "mode", None)


def test_csv_bad_file_names(csv_dir: Path) -> None:
    (csv_dir / "notes.txt").write_text("ignored")
    assert len(load(csv_dir)) == 3
    (csv_dir / "trial_11.csv").write_bytes((csv_dir / "trial_011.csv").read_bytes())
    with pytest.raises(DataFormatError, match="trial id 11 also given") as exc:
        load(csv_dir)
    check_error(exc, csv_dir / "trial_11.csv", "trial", None)
    os.unlink(csv_dir / "trial_11.csv")
    (csv_dir / "extra.csv").write_text("t,obs_a,act_b\n")
    with pytest.raises(DataFormatError, match="trial_<integer id>.csv") as exc:
        load(csv_dir)
    check_error(exc, csv_dir / "extra.csv", None, None)


def test_csv_empty_folder(tmp_path: Path) -> None:
    with pytest.raises(DataFormatError, match="no trial_"):
        load(tmp_path)
