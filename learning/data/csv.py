"""CSV folder format: one ``trial_<id>.csv`` per trial (columns: see :mod:`learning.data`).

The reader only parses: it turns the files into the same stacked arrays an NPZ
file holds (one part per file) and hands them to
:func:`~learning.data.model.from_stacked_arrays`, so both formats are checked by
the same rules, once; errors name the file, the CSV column and the data row.
"""

from __future__ import annotations

import csv
import io
import itertools
import os
import re
import shutil
import tempfile
import warnings
from pathlib import Path

import numpy as np

from ..atomic import make_temp_dir
from .checks import CHANNEL_PREFIX, DataFormatError, Origin
from .model import Demonstrations, PathLike, Trial, from_stacked_arrays

__all__ = ["CSV_NAME", "csv_bytes_estimate", "load_csv_folder", "save_csv_folder"]

#: File names of a CSV folder: ``trial_<integer id>.csv``.
CSV_NAME = re.compile(r"^trial_(-?\d+)\.csv$")
_SPECIAL = ("t", "mode", "subject")


def _header(path: str) -> list[str]:
    with open(path, newline="", encoding="utf-8-sig") as f:  # tolerate a byte-order mark
        first = f.readline()
    if not first.strip():
        raise DataFormatError("empty file (no header line)", path=path)
    return [c.strip() for c in next(csv.reader([first]))]


def _body(path: str, header: list[str]) -> np.ndarray:
    """Numeric body (rows, columns); a bad cell raises naming its column and row."""
    ncols = len(header)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # "empty input file"
            data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2, dtype=float,
                              comments=None, encoding="utf-8")
        if data.size == 0:
            return np.zeros((0, ncols))
        if data.shape[1] == ncols:
            return data
    except ValueError:
        pass
    # Slow path: locate the problem.
    with open(path, newline="", encoding="utf-8") as f:
        reader = csv.reader(f)
        next(reader)
        for row, cells in enumerate(reader):
            if not cells:
                raise DataFormatError("blank line", path=path, row=row)
            if len(cells) != ncols:
                raise DataFormatError(f"{len(cells)} values but the header has {ncols} columns "
                                      f"(file line {row + 2})", path=path, row=row)
            for name, cell in zip(header, cells):
                try:
                    float(cell)
                except ValueError:
                    raise DataFormatError(f"not a number: {cell!r} (file line {row + 2})",
                                          path=path, field=name, row=row) from None
    raise DataFormatError("cannot parse the file as comma-separated numbers", path=path)


class _File:
    """One parsed CSV file: its columns by field and its numeric body."""

    def __init__(self, path: str, tid: int) -> None:
        self.path, self.tid = path, tid
        header = _header(path)
        self.cols: dict[str, list[int]] = {k: [] for k in CHANNEL_PREFIX}
        self.names: dict[str, list[str]] = {k: [] for k in CHANNEL_PREFIX}
        self.special: dict[str, int] = {}
        for j, c in enumerate(header):
            if c in header[:j]:
                raise DataFormatError("duplicate column", path=path, field=c)
            if c in _SPECIAL:
                self.special[c] = j
                continue
            kind = next((k for k, pre in CHANNEL_PREFIX.items()
                         if c.startswith(pre) and len(c) > len(pre)), None)
            if kind is None:
                raise DataFormatError("unknown column (allowed: t, mode, subject, obs_*, act_*, vol_*)",
                                      path=path, field=c)
            self.cols[kind].append(j)
            self.names[kind].append(c[len(CHANNEL_PREFIX[kind]):])
        if "t" not in self.special:
            raise DataFormatError("required column missing", path=path, field="t")
        for kind in ("obs", "act"):
            if not self.cols[kind]:
                pre = CHANNEL_PREFIX[kind]
                raise DataFormatError(f"no {pre}* column", path=path, field=f"{pre}*")
        self.data = _body(path, header)
        if self.data.shape[0] == 0:
            raise DataFormatError(f"trial {tid}: empty trial (no data rows)", path=path, field="t")

    def optional(self) -> tuple[bool, bool]:
        return "mode" in self.special, "subject" in self.special

    def column(self, name: str) -> np.ndarray | None:
        return self.data[:, self.special[name]] if name in self.special else None

    def channels(self, kind: str) -> np.ndarray | None:
        return self.data[:, self.cols[kind]] if self.cols[kind] else None

    def check_same_columns(self, ref: _File) -> None:
        for kind, pre in CHANNEL_PREFIX.items():
            if self.names[kind] != ref.names[kind]:
                raise DataFormatError(f"{pre}* columns {self.names[kind]} differ from {ref.names[kind]} "
                                      f"in {os.path.basename(ref.path)}", path=self.path, field=f"{pre}*")
        for k, here, there in zip(("mode", "subject"), self.optional(), ref.optional()):
            if here != there:
                raise DataFormatError(f"column {'present' if here else 'absent'} here but "
                                      f"{'present' if there else 'absent'} in {os.path.basename(ref.path)}",
                                      path=self.path, field=k)


def _trial_files(folder: str) -> list[tuple[int, str]]:
    files: list[tuple[int, str]] = []
    for name in sorted(os.listdir(folder)):
        if not name.lower().endswith(".csv"):
            continue
        m = CSV_NAME.match(name)
        if m is None:
            raise DataFormatError("CSV file name must be trial_<integer id>.csv", path=os.path.join(folder, name))
        files.append((int(m.group(1)), os.path.join(folder, name)))
    if not files:
        raise DataFormatError("no trial_<id>.csv files", path=folder)
    files.sort()
    for (a, fa), (b, fb) in itertools.pairwise(files):
        if a == b:
            raise DataFormatError(f"trial id {a} also given by {os.path.basename(fa)}", path=fb, field="trial")
    return files


def load_csv_folder(path: PathLike) -> Demonstrations:
    """Load and validate a CSV folder (one ``trial_<id>.csv`` per trial; see :mod:`learning.data`)."""
    p = str(path)
    if not os.path.isdir(p):
        raise DataFormatError("no such folder", path=p)
    parsed = [_File(fp, tid) for tid, fp in _trial_files(p)]
    for f in parsed[1:]:
        f.check_same_columns(parsed[0])

    def stack(get) -> np.ndarray | None:
        parts = [get(f) for f in parsed]
        return None if parts[0] is None else np.concatenate(parts)

    arrays = {
        "obs": stack(lambda f: f.channels("obs")), "act": stack(lambda f: f.channels("act")),
        "voluntary": stack(lambda f: f.channels("voluntary")), "t": stack(lambda f: f.column("t")),
        "mode": stack(lambda f: f.column("mode")), "subject": stack(lambda f: f.column("subject")),
        "trial": np.concatenate([np.full(len(f.data), f.tid) for f in parsed]),
        "obs_names": np.array(parsed[0].names["obs"], dtype=str),
        "act_names": np.array(parsed[0].names["act"], dtype=str),
        "vol_names": np.array(parsed[0].names["voluntary"], dtype=str),
    }
    starts = np.concatenate([[0], np.cumsum([len(f.data) for f in parsed])[:-1]])
    origin = Origin(path=p, part_starts=tuple(int(s) for s in starts),
                    part_paths=tuple(f.path for f in parsed), csv_columns=True)
    return from_stacked_arrays(arrays, origin)


def csv_bytes_estimate(demos: Demonstrations, sample_rows: int = 200) -> float:
    """About how many bytes :func:`save_csv_folder` writes: each trial's first ``sample_rows`` rows
    formatted as written, scaled to its length (within a few per cent on smooth recordings)."""
    with_subject = any(tr.subject != -1 for tr in demos.trials)
    total = 0.0
    for tr in demos.trials:
        header, table, fmt = _csv_table(demos, tr, with_subject)
        buf = io.StringIO()
        np.savetxt(buf, table[:sample_rows], fmt=fmt, delimiter=",", header=",".join(header), comments="")
        head = len(",".join(header)) + 1
        rows = max(1, min(sample_rows, len(table)))
        total += head + (len(buf.getvalue().encode()) - head) * len(table) / rows
    return total


def _csv_table(demos: Demonstrations, tr: Trial, with_subject: bool) -> tuple[list[str], np.ndarray, list[str]]:
    """A trial's CSV: (header, table, per-column format)."""
    header = ["t"] + [f"obs_{n}" for n in demos.obs_names] + [f"act_{n}" for n in demos.act_names]
    blocks = [tr.t[:, None], tr.obs, tr.act]
    fmt = ["%.17g"] * (1 + tr.obs.shape[1] + tr.act.shape[1])
    if tr.voluntary is not None:
        header += [f"vol_{n}" for n in demos.vol_names]
        blocks.append(tr.voluntary)
        fmt += ["%.17g"] * tr.voluntary.shape[1]
    if tr.mode is not None:
        header.append("mode")
        blocks.append(tr.mode[:, None].astype(float))
        fmt.append("%d")
    if with_subject:
        header.append("subject")
        blocks.append(np.full((len(tr), 1), float(tr.subject)))
        fmt.append("%d")
    return header, np.hstack(blocks), fmt


def _write_csv_trial(demos: Demonstrations, tr: Trial, path: str, with_subject: bool) -> None:
    header, table, fmt = _csv_table(demos, tr, with_subject)
    with open(path, "w", newline="", encoding="utf-8") as f:
        np.savetxt(f, table, fmt=fmt, delimiter=",", header=",".join(header), comments="")
        f.flush()
        os.fsync(f.fileno())


def save_csv_folder(demos: Demonstrations, path: PathLike) -> None:
    """Validate, then write one ``trial_<id:03d>.csv`` per trial atomically.

    Files are written into a temporary folder beside ``path`` that is then renamed.
    An existing target folder is replaced only if it holds nothing but
    ``trial_*.csv`` files (otherwise ``FileExistsError``); it is moved aside first
    and deleted after the rename, so a failure leaves it intact. A ``subject``
    column is written when any subject is known (≠ −1).
    """
    p = Path(path)
    demos.validate()
    if p.exists():
        if not p.is_dir():
            raise FileExistsError(f"{p}: exists and is not a folder")
        foreign = [n for n in os.listdir(p) if not CSV_NAME.match(n)]
        if foreign:
            raise FileExistsError(f"{p}: folder holds other files ({foreign[0]!r}); not replacing it")
    p.parent.mkdir(parents=True, exist_ok=True)
    with_subject = any(tr.subject != -1 for tr in demos.trials)
    tmp = make_temp_dir(p.parent, prefix=f".{p.name}.", suffix=".tmp")  # an ordinary folder's mode
    old: str | None = None
    try:
        for tr in demos.trials:
            _write_csv_trial(demos, tr, os.path.join(tmp, f"trial_{tr.trial_id:03d}.csv"), with_subject)
        if p.exists():
            old = tempfile.mkdtemp(prefix=f".{p.name}.", suffix=".old", dir=p.parent)
            os.rmdir(old)
            os.replace(p, old)
        os.replace(tmp, p)
    except BaseException:
        if os.path.isdir(tmp):
            shutil.rmtree(tmp, ignore_errors=True)
        if old is not None and os.path.isdir(old) and not p.exists():
            os.replace(old, p)  # put the previous folder back
            old = None
        raise
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)
