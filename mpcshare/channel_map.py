"""The channel map: which of a data set's channels play the roles the controller and the simulator need.

The roles (``docs/design.md``, "Data format") are channel names: the knife tip ``knife_x/y/z`` (act,
metres, plate frame), the fork ``fork_x/y/z`` (obs, metres) with ``fork_roll/pitch/yaw`` (obs, rad;
optional, else a level fork) and the shoulder's ``shoulder_elevation``, ``shoulder_protraction``,
``shoulder_abduction`` (voluntary, rad; any of them, or 1 to 3 channels taken in that order:
:meth:`sim.task.eating.Eating.shoulder_map`). A map ``NAME=CHANNEL`` gives the data's CHANNEL the
name NAME (:meth:`learning.data.Demonstrations.renamed`). ``train``, ``sim`` and ``inspect`` take it as
``--map``; ``train`` records it in the bundle (``config["channel_map"]``) and ``sim`` applies it again.

:func:`simulator_gaps` says what keeps channel names from driving the closed-loop simulator, each
with the ``--map`` that fixes it; analysis and training need none of the roles. :func:`bundle_wearer`
gives the simulated wearer the shoulder map of the bundle's channels (the controller's).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any, Iterable, Sequence

import numpy as np

from learning.data import Demonstrations
from sim.task import EATING, Task, recorded_task
from sim.wearer import WearerConfig

__all__ = ["KNIFE", "FORK_POSITION", "FORK_ANGLES", "apply_map", "bundle_map", "bundle_wearer", "parse_map",
           "simulator_gaps", "simulator_line"]

KNIFE = ("knife_x", "knife_y", "knife_z")
FORK_POSITION = ("fork_x", "fork_y", "fork_z")
FORK_ANGLES = ("fork_roll", "fork_pitch", "fork_yaw")


def parse_map(items: Iterable[Any], option: str = "--map") -> dict[str, str]:
    """``NAME=CHANNEL`` words → {NAME: CHANNEL}; raises ValueError naming the bad word."""
    mapping: dict[str, str] = {}
    for item in items:
        name, sep, channel = str(item).partition("=")
        if not sep or not name or not channel:
            raise ValueError(f"{option} {item!r}: expected NAME=CHANNEL")
        if name in mapping:
            raise ValueError(f"{option} {item!r}: {name} is mapped twice")
        mapping[name] = channel
    return mapping


def apply_map(demos: Demonstrations, mapping: dict[str, str]) -> Demonstrations:
    """``demos`` with the map's channels renamed (ValueError naming the entry: see ``Demonstrations.renamed``)."""
    return demos.renamed(mapping) if mapping else demos


def bundle_map(recorded: dict[str, str] | None, demos: Demonstrations, given: dict[str, str]) -> dict[str, str]:
    """The map ``sim`` applies: each entry of the bundle's ``recorded`` map whose channel the data has and
    whose name it has not (data named as the training data was), then ``given`` (``--map``) on top."""
    names = {n for kind in demos.names().values() for n in kind}
    out = {}
    for name, channel in (recorded or {}).items():
        kind, sep, bare = channel.partition(":")
        if name not in given and (bare if sep and kind in demos.names() else channel) in names and name not in names:
            out[name] = channel
    out.update(given)
    return out


def _flags(roles: Sequence[str], names: Sequence[str]) -> str:
    """``ROLE=CHANNEL`` per role, CHANNEL the one channel of ``names`` ending in ``_<axis>`` where there is one."""
    out = []
    for role in roles:
        axis = "_" + role.rsplit("_", 1)[1]
        guess = [n for n in names if n.endswith(axis)]
        out.append(f"{role}={guess[0] if len(guess) == 1 else 'CHANNEL'}")
    return " ".join(out)


def simulator_gaps(obs_names: Sequence[str], act_names: Sequence[str], vol_names: Sequence[str],
                   rate_hz: float | None = None, task: Task = EATING) -> list[str]:
    """What keeps data (or a bundle) with these channels from driving the simulator and its controller,
    each with how to fix it; [] when nothing does. ``rate_hz``: the data's rate (None: not checked); ``task``:
    whose shoulder roles the voluntary channels must play (:meth:`sim.task.Task.shoulder_map`)."""
    obs, act, vol = list(obs_names), list(act_names), list(vol_names)
    gaps = []
    knife = [c for c in KNIFE if c not in act]
    if knife:
        gaps.append(f"no knife tip channel(s) {', '.join(knife)} among the act channels ({', '.join(act)}): "
                    f"--map {_flags(knife, act)} names the knife tip's position [m, plate frame]")
    fork = [c for c in FORK_POSITION if c not in obs]
    if fork:
        gaps.append(f"no fork channel(s) {', '.join(fork)} among the obs channels ({', '.join(obs)}): "
                    f"--map {_flags(fork, obs)} names the fork's position [m, plate frame]")
    angles = [c for c in FORK_ANGLES if c not in obs]
    if 0 < len(angles) < len(FORK_ANGLES):
        gaps.append(f"the fork's angles lack {', '.join(angles)}: --map {_flags(angles, obs)} names them [rad, ZYX] "
                    f"(or map none: a level fork)")
    elif fork and angles and "CHANNEL" not in _flags(FORK_ANGLES, obs):
        gaps[-1] += f" (and --map {_flags(FORK_ANGLES, obs)} its angles [rad, ZYX])"
    try:
        task.shoulder_map(vol)
    except ValueError as exc:
        gaps.append(f"{exc}: --map {task.shoulder_channels[0]}=CHANNEL ... names them")
    if rate_hz is not None:
        from sim.scene import SceneConfig  # imports MuJoCo

        sim_hz = 1.0 / SceneConfig().control_period
        if abs(float(rate_hz) - sim_hz) > 1e-6 * sim_hz:
            gaps.append(f"the data is sampled at {float(rate_hz):g} Hz, the simulator runs at {sim_hz:g} Hz: "
                        f"resample it to {sim_hz:g} Hz (bags: mpcshare import --rate {sim_hz:g})")
    return gaps


def simulator_line(obs_names: Sequence[str], act_names: Sequence[str], vol_names: Sequence[str],
                   rate_hz: float | None = None, task: Task = EATING) -> str:
    """Whether these channels can drive the simulator, in one line: ``yes (what plays each role)`` or
    ``no: why, and how`` (the shoulder roles ``task``'s)."""
    gaps = simulator_gaps(obs_names, act_names, vol_names, rate_hz, task)
    if gaps:
        return "no: " + "; ".join(gaps)
    m, channels = task.shoulder_map(vol_names), task.shoulder_channels
    roles = {j: r for j in range(m.n_channels) for r in range(len(channels))
             if np.array_equal(m.matrix[:, j], task.shoulder_to_plate[:, r])}
    used = [n if n == channels[roles[j]] else f"{n} as {channels[roles[j]]}"
            for j, n in enumerate(vol_names) if j in roles]
    shoulder = f"shoulder {', '.join(used)}" if vol_names else "no shoulder channels (a simulated 3-angle shoulder)"
    fork = "pose" if all(c in obs_names for c in FORK_ANGLES) else "position (a level fork)"
    return f"yes (knife tip {', '.join(KNIFE)}; fork {fork}; {shoulder})"


def bundle_wearer(bundle: Any, wearer: Any) -> Any:
    """The wearer commanding through the bundle's shoulder channels: a :class:`WearerConfig` ``wearer``
    (None: ``WearerConfig()``) with its shoulder map's gain and dead zone on the bundle's ``vol_names``
    (the map of the task the bundle was trained for, :func:`sim.task.recorded_task`: the controller's map);
    ``wearer`` itself where that is its map or for a wearer of another kind. Raises ValueError for channels no map
    reads or a task that cannot be found."""
    wc = WearerConfig() if wearer is None else wearer
    if not isinstance(wc, WearerConfig):
        return wearer
    task = recorded_task(getattr(bundle, "config", None))
    m = task.shoulder_map(getattr(bundle, "vol_names", ()) or (), wc.shoulder.gain, wc.shoulder.deadband_rad)
    return wearer if np.array_equal(m.matrix, wc.shoulder.matrix) else replace(wc, shoulder=m)
