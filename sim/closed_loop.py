"""Closed-loop episode: controller at 100 Hz, joint servo and MuJoCo at 1 kHz, simulated wearer.

Per control step k (t_k = k·T, T = 10 ms):

1. the torso at its sway pose, ``mj_step1``: the knife tip p(t_k) and the base pose ``T_plate_torso``;
2. the fork (mocap) at the demonstration's pose of sample k (``fork_truth``: the world's fork where the
   controller's marker reads otherwise); the wearer's forearm with it on video frames only (drawn, no contacts);
3. the wearer (any :class:`sim.wearer_protocol.Wearer`; default :mod:`sim.wearer`) gives the shoulder angles,
   cued by the previous command's α (NaN before the first command or after a step without one);
4. ``controller.step(t_k, obs_k, voluntary, q, v, base_pose)`` (timed); a command that is not finite or not of
   shape (n,) holds the servo (status ``invalid_command``), an exception in ``step`` too
   (``controller_error``): the loop never stops for the controller;
5. ten physics steps (servo torque, :mod:`sim.servo`; ``mj_step2``), q, v and the applied force recorded and
   checked against the limits (positions and velocities at 1e-6, torques at 1e-9 N·m).

The controller needs only ``step`` (``reset()`` first if it has one); ``obs`` columns go in the trial's order. Use::

    ep = run_episode(controller, trial, duration_s=60.0, seed=0, render="trial.mp4")
    ep.save("run.npz")
    figures = sim.metrics.episode_metrics(ep)   # the comparison.json keys
"""

from __future__ import annotations

import dataclasses
import json
import math
import time
import warnings
from pathlib import Path
from typing import Any, Callable, Protocol

import mujoco
import numpy as np

from learning.data import Trial
from sim.episode import Episode
from sim.scene import EatingScene, SceneConfig
from sim.servo import JointServo, ServoConfig
from sim.task import EATING, Task
from sim.wearer_presets import DEFAULT_WEARER
from sim.wearer_protocol import Wearer, WearerFactory, make_wearer

__all__ = ["FORK_CHANNELS", "LIMIT_TOL", "TIP_CHANNELS", "TORQUE_TOL", "Controller", "Episode", "fork_pose_rows",
           "run_episode"]

LIMIT_TOL = 1e-6  # [rad, rad/s] tolerance of the position and velocity limit checks
TORQUE_TOL = 1e-9  # [N·m] rounding allowance of the torque check
TIP_CHANNELS = ("knife_x", "knife_y", "knife_z")
FORK_CHANNELS = ("fork_x", "fork_y", "fork_z", "fork_roll", "fork_pitch", "fork_yaw")


class Controller(Protocol):
    """What the loop needs: ``SharedController.step``'s signature."""

    def step(self, t: float, obs: np.ndarray, voluntary: np.ndarray, q: np.ndarray, v: np.ndarray,
             base_pose: np.ndarray | None = None) -> Any: ...


def fork_pose_rows(obs: np.ndarray, names: list[str] | None, where: str = "trial obs") -> np.ndarray:
    """(T, 6) the fork pose of each row of ``obs``: the :data:`FORK_CHANNELS` columns, the angles 0 (a level
    fork) where ``names`` has none of them. Raises ValueError naming a missing position channel."""
    cols = _columns(names, FORK_CHANNELS[:3], where)
    names = list(names or ())
    if any(c in names for c in FORK_CHANNELS[3:]):
        cols += _columns(names, FORK_CHANNELS[3:], where)  # some angles: all three (names those missing)
    obs = np.asarray(obs, dtype=float)
    return obs[:, cols] if len(cols) == 6 else np.concatenate([obs[:, cols], np.zeros((len(obs), 3))], axis=1)


def _columns(names: list[str] | None, wanted: tuple[str, ...], where: str) -> list[int]:
    if names is None:
        raise ValueError(f"{where}: channel names are needed to find {wanted}")
    missing = [w for w in wanted if w not in names]
    if missing:
        raise ValueError(f"{where} has no channel(s) {missing}; it has {list(names)}")
    return [names.index(w) for w in wanted]


def _vec(x: Any, n: int = 3) -> np.ndarray | None:
    """``x`` as a finite (n,) float array, else None."""
    try:
        a = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        return None
    return a if a.shape == (n,) and _all_finite(a) else None


def _all_finite(a: np.ndarray) -> bool:
    """Whether every entry of the 1-D float array ``a`` is finite (plain floats: on a few entries, several
    times cheaper than ``np.isfinite(a).all()``)."""
    return all(map(math.isfinite, a.tolist()))


def _scalar(x: Any) -> float:
    try:
        return float(x)
    except (TypeError, ValueError):
        return float("nan")


class _Loop:
    """The state of one episode between control steps: the world, the wearer, the servo and the logs.

    One control period is :meth:`control_step` (items 1–4 of the module docstring) then
    :meth:`physics_period` (item 5); hooks (video, progress) run after each period.
    """

    def __init__(self, controller: Controller, trial: Trial, sc: SceneConfig, person: Wearer,
                 servo: ServoConfig | None, seed: int, n_ctrl: int, fork: np.ndarray, record: bool,
                 fork_truth: np.ndarray | None = None, task: Task = EATING) -> None:
        self.controller, self.trial, self.sc, self.person, self.task = controller, trial, sc, person, task
        self.fork_truth = fork if fork_truth is None else fork_truth
        self.n_ctrl, self.record = n_ctrl, record
        self.drawn: Callable[[int], bool] = lambda k: False  # whether step k is a video frame
        self.world = EatingScene(sc, seed=seed)
        robot = sc.robot
        self.n = n = robot.n
        q0 = robot.inverse_kinematics(self.world.plate_to_torso(self.world.base_pose(0.0),
                                                                self.person.intent[0][None])[0])
        self.world.set_state(q0, np.zeros(n), 0.0)
        self.world.set_fork(self.fork_truth[0], 0.0)
        self.servo = JointServo(self.world.model, self.world.data, robot, servo)
        # control-rate log
        self.out = {k: np.full((n_ctrl, 3), np.nan) for k in ("tip", "tip_reference", "voluntary", "knife_heel")}
        self.fork_pose = np.full((n_ctrl, 6), np.nan)
        self.alpha, self.beta, self.novelty = (np.full(n_ctrl, np.nan) for _ in range(3))
        self.mode = np.full(n_ctrl, -1, dtype=int)
        self.status = np.empty(n_ctrl, dtype=object)
        self.step_time = np.zeros(n_ctrl)
        self.base_poses = np.zeros((n_ctrl, 4, 4))
        # physics-rate log and the limits checked on it
        n_sub, n_phys = sc.substeps, n_ctrl * sc.substeps if record else 0
        self.rec_t, self.rec_q = np.zeros(n_phys), np.zeros((n_phys, n))
        self.rec_v, self.rec_tau = np.zeros((n_phys, n)), np.zeros((n_phys, n))
        self._buf = (np.zeros(n_sub), np.zeros((n_sub, n)), np.zeros((n_sub, n)), np.zeros((n_sub, n)))
        lim = robot.limits
        self.q_lo, self.q_hi = lim.q_min - LIMIT_TOL, lim.q_max + LIMIT_TOL
        self.v_lim = lim.v_max + LIMIT_TOL
        self.tau_lim = lim.tau_max + TORQUE_TOL
        self.violations, self.worst = 0, {"q": 0.0, "v": 0.0, "tau": 0.0}

    def control_step(self, k: int) -> None:
        """Sense, let the wearer act, call the controller (timed, never fatal) and give the servo its segment."""
        sc, world, d = self.sc, self.world, self.world.data
        t_k = k * sc.control_period
        world.set_time(t_k)
        # the forearm is drawn only (contacts are off): placed on the steps a video frame shows
        world.set_fork(self.fork_truth[k], t_k if self.drawn(k) else None)
        mujoco.mj_step1(world.model, d)
        tip = world.tip_in_plate().copy()
        self.out["knife_heel"][k], self.fork_pose[k] = world.knife_heel_in_plate(), world.fork_pose
        base = world.base_pose(t_k)
        cue = self.alpha[k - 1] if k > 0 else None  # what the controller showed at the previous step
        theta = self.person.step(k, tip, alpha_cue=cue)
        if k == 0 and np.ndim(theta) == 1 and np.size(theta) != self.out["voluntary"].shape[1]:  # not 3 angles
            self.out["voluntary"] = np.full((self.n_ctrl, theta.size), np.nan)
        q, v = d.qpos.copy(), d.qvel.copy()  # the arm is the whole state
        t0 = time.perf_counter()
        try:
            cmd = self.controller.step(t_k, self.trial.obs[k].copy(), theta.copy(), q, v, base)
            err = None
        except Exception as exc:  # noqa: BLE001  (the loop must go on: hold, and say why)
            cmd, err = None, f"controller_error: {type(exc).__name__}: {exc}"
        self.step_time[k] = time.perf_counter() - t0
        seg = None if cmd is None else [_vec(getattr(cmd, a, None), self.n) for a in ("q_cmd", "v_cmd", "a_cmd")]
        if seg is not None and all(x is not None for x in seg):
            self.servo.set_segment(seg[0], seg[1], seg[2], t_k + sc.control_period)
            self.status[k] = str(getattr(cmd, "status", "ok"))
        else:
            self.servo.hold()
            self.status[k] = err or "invalid_command"
        if cmd is not None:
            self._log_command(k, cmd)
        self.out["tip"][k], self.out["voluntary"][k], self.base_poses[k] = tip, theta, base

    def caption(self, k: int) -> Any:
        """What the video shows on control step ``k``'s frame: time, who leads (α), the demonstration's task mode
        (its name and colour in the task's ``mode_names`` and ``mode_colours``)."""
        from sim.render import Caption

        a = self.alpha[k]
        who = "no command" if not np.isfinite(a) else (f"robot leads (alpha {a:.2f})" if a >= 0.5
                                                        else f"wearer leads (alpha {a:.2f})")
        parts = [f"t = {k * self.sc.control_period:.1f} s", who]
        label = int(self.trial.mode[k]) if self.trial.mode is not None and k < len(self.trial.mode) else -1
        if label < 0:
            return Caption(parts)
        names = self.task.mode_names
        name = names[label] if label < len(names) else f"mode {label}"
        return Caption(parts + [name], self.task.mode_colours.get(name))

    def _log_command(self, k: int, cmd: Any) -> None:
        self.alpha[k], self.beta[k] = _scalar(getattr(cmd, "alpha", np.nan)), _scalar(getattr(cmd, "beta", np.nan))
        self.novelty[k] = _scalar(getattr(cmd, "novelty", np.nan))
        ref = _vec(getattr(cmd, "tip_reference", None))
        if ref is not None:
            self.out["tip_reference"][k] = ref
        proba = np.asarray(getattr(cmd, "mode_proba", ()), dtype=float).reshape(-1)
        if proba.size and _all_finite(proba):
            self.mode[k] = int(np.argmax(proba))

    def physics_period(self, k: int) -> None:
        """The period's physics steps (servo torque, ``mj_step2``), recorded and checked against the limits."""
        sc, world, m, d = self.sc, self.world, self.world.model, self.world.data
        n_sub, t_k = sc.substeps, k * sc.control_period
        if self.record:
            blk = slice(k * n_sub, (k + 1) * n_sub)
            bt, bq, bv, bf = self.rec_t[blk], self.rec_q[blk], self.rec_v[blk], self.rec_tau[blk]
        else:
            bt, bq, bv, bf = self._buf
        qpos, qvel, force, ctrl = d.qpos, d.qvel, d.actuator_force, d.ctrl  # views into MuJoCo's state
        set_time, torque_into, step1, step2, h = world.set_time, self.servo.torque_into, mujoco.mj_step1, \
            mujoco.mj_step2, sc.timestep
        for j in range(n_sub):
            if j:  # the first sub-step's kinematics were computed by control_step
                set_time(t_k + j * h)
                step1(m, d)
            torque_into(ctrl)
            step2(m, d)
            bt[j] = d.time
            bq[j], bv[j], bf[j] = qpos, qvel, force  # the arm is the whole state
        if not self.record:  # a recorded episode is checked once, at its end (check_recording)
            self._check_limits(bq, bv, bf, n_sub)

    def check_recording(self) -> None:
        """Count the recorded episode's limit violations, as :meth:`physics_period` does per period unrecorded."""
        if self.record:
            self._check_limits(self.rec_q, self.rec_v, self.rec_tau, self.sc.substeps)

    def _check_limits(self, bq: np.ndarray, bv: np.ndarray, bf: np.ndarray, n_sub: int) -> None:
        """Count the physics steps (rows of ``bq``, ``bv``, ``bf``) with any limit exceeded; ``worst`` takes each
        period's (``n_sub`` rows') largest excesses where the period has a violation (vectorised over periods)."""
        eq = np.maximum(self.q_lo - bq, bq - self.q_hi).max(axis=1)
        ev = (np.abs(bv) - self.v_lim).max(axis=1)
        et = (np.abs(bf) - self.tau_lim).max(axis=1)
        bad = (eq > 0.0) | (ev > 0.0) | (et > 0.0)
        if bad.any():
            self.violations += int(bad.sum())
            w = self.worst
            periods = bad.reshape(-1, n_sub).any(axis=1)
            for e, key in ((eq, "q"), (ev, "v"), (et, "tau")):
                for peak in e.reshape(-1, n_sub).max(axis=1)[periods].tolist():
                    w[key] = max(w[key], peak)

    def info(self, seed: int, wall: float, cpu: float) -> dict[str, Any]:
        sc, srv, w = self.sc, self.servo, self.worst
        return {
            "trial_id": self.trial.trial_id, "seed": seed, "duration_s": self.n_ctrl * sc.control_period,
            "control_period_s": sc.control_period, "physics_dt_s": sc.timestep, "wall_time_s": wall,
            "cpu_time_s": cpu,
            "limit_violations": self.violations, "max_q_excess_rad": w["q"], "max_v_excess_rad_s": w["v"],
            "max_tau_excess_nm": w["tau"], "servo_qp_steps": srv.qp_steps,
            "servo_fallback_steps": srv.fallback_steps, "brake_infeasible_steps": srv.brake_infeasible,
            **self.person.info(),
            "video": None, "render_message": None,
            "body_zones": json.dumps({**sc.body.to_dict(), "blade_length": sc.blade_length}),
            "shoulder_roles": json.dumps(list(self.task.shoulder_channels)),
            "shoulder_layout": json.dumps(np.asarray(self.task.shoulder_to_plate, dtype=float).tolist()),
        }

    def episode(self, info: dict[str, Any]) -> Episode:
        o = self.out
        t = np.arange(self.n_ctrl) * self.sc.control_period
        return Episode(self.rec_t, self.rec_q, self.rec_v, self.rec_tau, t, self.alpha, self.beta, self.mode,
                       o["tip"], o["tip_reference"], self.person.intent[:self.n_ctrl].copy(), o["voluntary"],
                       self.status.astype(str), self.step_time, self.base_poses, self.novelty, info,
                       fork_pose=self.fork_pose, knife_heel=o["knife_heel"])


def _check_inputs(controller: Controller, trial: Trial, sc: SceneConfig, obs_names: list[str],
                  act_names: list[str], duration_s: float | None) -> tuple[np.ndarray, np.ndarray, int]:
    """(the fork poses (T, 6), the intended knife tip (n_ctrl, 3), n_ctrl), or a clear error naming what is
    wrong."""
    if not callable(getattr(controller, "step", None)):
        raise TypeError(f"controller must have a step(t, obs, voluntary, q, v, base_pose) method, "
                        f"got {type(controller).__name__}")
    tip_cols = _columns(act_names, TIP_CHANNELS, "trial act")
    if trial.obs.shape[1] != len(obs_names) or trial.act.shape[1] != len(act_names):
        raise ValueError(f"trial {trial.trial_id}: obs/act have {trial.obs.shape[1]}/{trial.act.shape[1]} "
                         f"columns, names give {len(obs_names)}/{len(act_names)}")
    fork = fork_pose_rows(trial.obs, obs_names)
    if len(trial) < 2:
        raise ValueError(f"trial {trial.trial_id} has {len(trial)} samples; need at least 2")
    dt_trial = float(np.median(np.diff(trial.t)))
    if abs(dt_trial - sc.control_period) > 1e-6:
        raise ValueError(f"trial {trial.trial_id} is sampled every {dt_trial:g} s; the loop runs at "
                         f"{sc.control_period:g} s (resample the trial to {1 / sc.control_period:g} Hz)")
    n_ctrl = len(trial)
    if duration_s is not None:
        if not duration_s > 0:
            raise ValueError(f"duration_s must be > 0, got {duration_s}")
        n_ctrl = min(n_ctrl, round(duration_s / sc.control_period))
    intent_raw = trial.act[:n_ctrl][:, tip_cols]
    bad = ~np.isfinite(intent_raw).all(axis=1)
    if bad.any():
        raise ValueError(f"trial {trial.trial_id}: knife tip not finite at row {int(np.flatnonzero(bad)[0])}")
    return fork, intent_raw, n_ctrl


def run_episode(controller: Controller, trial: Trial, *, scene: SceneConfig | None = None,
                wearer: Wearer | WearerFactory | None = None, duration_s: float | None = None, seed: int = 0,
                record: bool = True, render: str | Path | None = None, progress: bool = False,
                obs_names: list[str] | None = None, act_names: list[str] | None = None,
                servo: ServoConfig | None = None, fork_truth: np.ndarray | None = None,
                task: Task = EATING) -> Episode:
    """Run ``controller`` beside a simulated wearer whose intent is ``trial``'s knife (module docstring).

    Args:
        controller: any object with ``step(t, obs, voluntary, q, v, base_pose)``.
        trial: raw 100 Hz demonstration; ``trial.obs`` rows are given to the controller as
            they are; the knife channels (``knife_x/y/z`` in ``act_names``, default the
            generator's) are the intent, the fork pose channels drive the fork (``fork_x/y/z``; without
            ``fork_roll/pitch/yaw`` the fork is level).
        scene, servo: settings (defaults if None).
        wearer: a :class:`sim.wearer_protocol.Wearer`, or a factory of one called on the trial's
            knife tip (a :class:`sim.wearer.WearerConfig` is one); default
            ``sim.wearer_presets.DEFAULT_WEARER`` (the preset ``DEFAULT_WEARER_PRESET``).
        duration_s: simulated time [s] (default: the whole trial).
        seed: torso sway phases and the wearer's noise.
        record: keep the physics-rate arrays (False: empty arrays, metrics still work).
        render: path of a video (.mp4 if ffmpeg is available, else a .gif beside it).
        progress: show a tqdm bar.
        fork_truth: (T, 6) the world's fork pose per sample (plate frame) when it differs from
            what the controller reads in ``trial.obs`` (a lost or faulty marker); default: the
            trial's fork channels.
        task: the task (:class:`sim.task.Task`): the wearer's body zones in the scene (they replace
            ``scene.body``), the names and colours of the modes in the video's caption, and the roles of the
            shoulder channels the episode records (``info["shoulder_roles"]``, ``info["shoulder_layout"]``).
    """
    from sim.demonstrator import ACT_NAMES, OBS_NAMES

    sc = scene or SceneConfig()
    if sc.body != task.body:
        sc = dataclasses.replace(sc, body=task.body)
    obs_names = list(OBS_NAMES) if obs_names is None else list(obs_names)
    act_names = list(ACT_NAMES) if act_names is None else list(act_names)
    fork, intent_raw, n_ctrl = _check_inputs(controller, trial, sc, obs_names, act_names, duration_s)
    if fork_truth is not None:
        fork_truth = np.asarray(fork_truth, dtype=float)
        if fork_truth.shape != (len(trial), 6):
            raise ValueError(f"fork_truth must have shape ({len(trial)}, 6), got {fork_truth.shape}")
    person = make_wearer(DEFAULT_WEARER if wearer is None else wearer, intent_raw, 1.0 / sc.control_period, seed)
    loop = _Loop(controller, trial, sc, person, servo, seed, n_ctrl, fork, record, fork_truth, task)
    if callable(getattr(controller, "reset", None)):
        controller.reset()
    renderer = bar = None
    if render is not None:
        from sim.render import VideoRecorder

        renderer = VideoRecorder(loop.world.model, render, fps=25, control_rate_hz=1.0 / sc.control_period)
        loop.drawn = renderer.wants
    if progress:
        from learning.progress import progress_bar

        bar = progress_bar(total=n_ctrl, desc=f"trial {trial.trial_id}", unit="step", leave=False)

    wall0, cpu0 = time.perf_counter(), time.process_time()
    for k in range(n_ctrl):
        loop.control_step(k)
        if renderer is not None and renderer.wants(k):
            renderer.maybe_capture(loop.world.data, k, loop.caption(k))
        loop.physics_period(k)
        if bar is not None:
            bar.update(1)
    loop.check_recording()
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    if bar is not None:
        bar.close()

    info = loop.info(seed, wall, cpu)
    if renderer is not None:
        video, message = renderer.close()
        info["video"], info["render_message"] = (str(video) if video else None), message
        if message:
            warnings.warn(f"no video: {message}" if video is None else message, RuntimeWarning, stacklevel=2)
    return loop.episode(info)
