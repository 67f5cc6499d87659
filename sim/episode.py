"""The record of one closed-loop episode and its run file (NPZ): :class:`Episode`."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from learning.atomic import atomic_open
from sim.task import EATING

__all__ = ["CONTROL_KEYS", "OPTIONAL_KEYS", "PHYSICS_KEYS", "Episode", "run_file_bytes_estimate"]


#: run-file arrays: physics rate, then control rate (the run file's keys, ``docs/design.md``)
PHYSICS_KEYS = ("t_physics", "q", "v", "tau")
CONTROL_KEYS = ("t", "alpha", "beta", "mode", "tip", "tip_reference", "tip_intent", "voluntary", "status",
                "step_time", "base_pose", "novelty")
#: control-rate arrays of the keep-out, absent from older run files
OPTIONAL_KEYS = ("fork_pose", "knife_heel")

#: the run file's size [bytes]: the arrays are stored uncompressed (float64 trajectories barely compress, and
#: compressing cost 25x the CPU of writing): per physics step the time and per joint its q, v and τ (8 bytes
#: each); per control step every control-rate array (fork pose and knife heel included, the status as 8 characters
#: of 4 bytes); per file the archive's headers (about 260 bytes an array) and ``info``
_NPZ_BYTES_PER_PHYSICS_STEP = 8.0
_NPZ_BYTES_PER_JOINT_STEP = 24.0
_NPZ_BYTES_PER_CONTROL_STEP = 376.0
_NPZ_BYTES_PER_FILE = 10_500.0


def run_file_bytes_estimate(seconds: float, physics_hz: float, control_hz: float, n_joints: int = 3) -> float:
    """About how many bytes :meth:`Episode.save` writes for ``seconds`` of a run of an arm with ``n_joints``
    joints (within 10 % on the project's runs of 2 s and more; the status's width moves it by a few %)."""
    physics = physics_hz * (_NPZ_BYTES_PER_PHYSICS_STEP + n_joints * _NPZ_BYTES_PER_JOINT_STEP)
    return _NPZ_BYTES_PER_FILE + seconds * (physics + control_hz * _NPZ_BYTES_PER_CONTROL_STEP)


@dataclass
class Episode:
    """The record of one closed-loop run.

    Physics rate (1 kHz): ``t_physics`` (Np,) [s] (time after each step), ``q``,
    ``v`` (Np, n) realized [rad, rad/s], ``tau`` (Np, n) applied [N·m] (n: the arm's joints).
    Control rate (100 Hz): ``t`` (Nc,) [s], ``alpha``, ``beta`` (Nc,), ``mode`` (Nc,)
    int (argmax of ``mode_proba``, −1 if none), ``tip``, ``tip_reference``,
    ``tip_intent`` (Nc, 3) [m] plate frame, ``voluntary`` (Nc, n) [rad] (n shoulder angles, 3 by default), ``status``
    (Nc,) str, ``step_time`` (Nc,) [s], ``base_pose`` (Nc, 4, 4), ``novelty`` (Nc,)
    (the command's ``novelty`` where it has one, else NaN); ``fork_pose`` (Nc, 6) the fork
    pose the scene showed (x, y, z [m], roll, pitch, yaw [rad], plate frame: the truth, also
    while the controller's marker is lost), ``knife_heel`` (Nc, 3) [m] the blade's heel (plate
    frame; the knife body is the segment tip–heel); None in older run files.
    ``info``: scalars — limit_violations (physics steps with any limit exceeded),
    the largest excesses, servo counters, wall_time_s, shoulder gain/deadband, the
    trial id, render result, ``body_zones`` (JSON: the wearer's body zones, ``robot.wearer_body``),
    ``shoulder_roles`` and ``shoulder_layout`` (JSON: the task's shoulder roles and layout; older run files: none).
    """

    t_physics: np.ndarray
    q: np.ndarray
    v: np.ndarray
    tau: np.ndarray
    t: np.ndarray
    alpha: np.ndarray
    beta: np.ndarray
    mode: np.ndarray
    tip: np.ndarray
    tip_reference: np.ndarray
    tip_intent: np.ndarray
    voluntary: np.ndarray
    status: np.ndarray
    step_time: np.ndarray
    base_pose: np.ndarray
    novelty: np.ndarray
    info: dict[str, Any] = field(default_factory=dict)
    fork_pose: np.ndarray | None = None
    knife_heel: np.ndarray | None = None

    @property
    def shoulder_names(self) -> list[str]:
        """The names of the ``voluntary`` columns: each column's role in the wearer's shoulder map
        (``info["shoulder_matrix"]``; absent: eating's P, as :mod:`sim.wearer_protocol` records it), by the column
        of the task's layout it equals (the roles and layout the episode recorded, ``info["shoulder_roles"]`` and
        ``info["shoulder_layout"]``; a run file without them: eating's); ``shoulder_<j>`` for a column of no role."""
        recorded = self.info.get("shoulder_roles")
        roles = tuple(json.loads(recorded)) if recorded else EATING.shoulder_channels
        layout = np.array(json.loads(self.info["shoulder_layout"]), dtype=float) if recorded else \
            np.asarray(EATING.shoulder_to_plate, dtype=float)
        matrix = self.info.get("shoulder_matrix")
        P = np.array(json.loads(matrix), dtype=float) if matrix else np.asarray(EATING.shoulder_to_plate, dtype=float)
        names = []
        for j, col in enumerate(P.T):
            role = [r for r in range(len(roles)) if np.array_equal(col, layout[:, r])]
            names.append(roles[role[0]] if role else f"shoulder_{j}")
        return names

    def save(self, path: str | Path) -> Path:
        """Write the run file (NPZ, uncompressed, atomic): every array above plus ``info_<name>`` scalars."""
        path = Path(path)
        if path.suffix != ".npz":
            raise ValueError(f"run file must end in .npz, got {path.name!r}")
        arrays = {k: getattr(self, k) for k in PHYSICS_KEYS + CONTROL_KEYS}
        arrays["status"] = np.asarray(self.status, dtype=str)
        arrays.update({k: getattr(self, k) for k in OPTIONAL_KEYS if getattr(self, k) is not None})
        for k, v in self.info.items():
            arrays[f"info_{k}"] = np.asarray("" if v is None else v)
        with atomic_open(path, "wb") as fh:
            np.savez(fh, **arrays)
        return path

    @classmethod
    def load(cls, path: str | Path) -> Episode:
        """Read a run file written by :meth:`save`."""
        with np.load(path, allow_pickle=False) as z:
            missing = [k for k in PHYSICS_KEYS + CONTROL_KEYS if k not in z.files]
            if missing:
                raise ValueError(f"{path}: not a run file, missing {missing}")
            arrays = {k: z[k] for k in PHYSICS_KEYS + CONTROL_KEYS + OPTIONAL_KEYS if k in z.files}
            info = {k[5:]: z[k].item() for k in z.files if k.startswith("info_")}
        return cls(**arrays, info=info)
