"""Closed-loop episode: controller at 100 Hz, joint servo and MuJoCo at 1 kHz, simulated wearer.

Per control step k (t_k = k·T, T = 10 ms):

1. the torso is put at its sway pose, ``mj_step1`` gives the kinematics of the
   state (q, v); the knife tip p(t_k) and the base pose ``T_plate_torso`` are read;
2. the fork (mocap) is put at the demonstration's fork pose of sample k;
3. the wearer turns the delayed tip error against the intent into shoulder angles;
4. ``controller.step(t_k, obs_k, voluntary, q, v, base_pose)`` (timed);
   a command that is not finite or not of shape (3,) makes the servo hold (status
   ``invalid_command``), an exception inside ``step`` likewise (``controller_error``):
   the loop never stops for the controller;
5. ten physics steps: servo torque (:mod:`sim.servo`), ``mj_step2``; the realized
   q, v and the applied actuator force are recorded and checked against the
   limits (positions and velocities at 1e-6, torques at 1e-9 N·m).

The controller object needs only ``step`` (the interface of
``mpcshare.control.controller.SharedController``); ``reset()`` is called first if it has one.
``obs`` rows go to the controller in the trial's column order: reorder the trial
to the controller's channel order first if they differ.

Typical use::

    ep = run_episode(controller, trial, duration_s=60.0, seed=0, render="trial.mp4")
    ep.save("run.npz")
    figures = sim.metrics.episode_metrics(ep)   # the comparison.json keys
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

import mujoco
import numpy as np

from learning.atomic import atomic_open
from learning.data import Trial
from robot.kinematics import ArmGeometry, nearest_reachable_q
from sim.scene import EatingScene, SceneConfig
from sim.servo import JointServo, ServoConfig
from sim.wearer import SimulatedWearer, WearerConfig

__all__ = ["FORK_CHANNELS", "LIMIT_TOL", "TIP_CHANNELS", "TORQUE_TOL", "Controller", "Episode", "run_episode"]

LIMIT_TOL = 1e-6  # [rad, rad/s] tolerance of the position and velocity limit checks
TORQUE_TOL = 1e-9  # [N·m] rounding allowance of the torque check
TIP_CHANNELS = ("knife_x", "knife_y", "knife_z")
FORK_CHANNELS = ("fork_x", "fork_y", "fork_z", "fork_roll", "fork_pitch", "fork_yaw")


class Controller(Protocol):
    """What the loop needs: ``SharedController.step``'s signature."""

    def step(self, t: float, obs: np.ndarray, voluntary: np.ndarray, q: np.ndarray, v: np.ndarray,
             base_pose: np.ndarray | None = None) -> Any: ...


#: run-file arrays: physics rate, then control rate (the keys of issue 12, plus base_pose and novelty)
PHYSICS_KEYS = ("t_physics", "q", "v", "tau")
CONTROL_KEYS = ("t", "alpha", "beta", "mode", "tip", "tip_reference", "tip_intent", "voluntary", "status",
                "step_time", "base_pose", "novelty")


@dataclass
class Episode:
    """The record of one closed-loop run.

    Physics rate (1 kHz): ``t_physics`` (Np,) [s] (time after each step), ``q``,
    ``v`` (Np, 3) realized [rad, rad/s], ``tau`` (Np, 3) applied [N·m].
    Control rate (100 Hz): ``t`` (Nc,) [s], ``alpha``, ``beta`` (Nc,), ``mode`` (Nc,)
    int (argmax of ``mode_proba``, −1 if none), ``tip``, ``tip_reference``,
    ``tip_intent`` (Nc, 3) [m] plate frame, ``voluntary`` (Nc, 3) [rad], ``status``
    (Nc,) str, ``step_time`` (Nc,) [s], ``base_pose`` (Nc, 4, 4), ``novelty`` (Nc,)
    (the command's ``novelty`` where it has one, else NaN).
    ``info``: scalars — limit_violations (physics steps with any limit exceeded),
    the largest excesses, servo counters, wall_time_s, shoulder gain/deadband, the
    trial id, render result.
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

    def save(self, path: str | Path) -> Path:
        """Write the run file (NPZ, atomic): every array above plus ``info_<name>`` scalars."""
        path = Path(path)
        if path.suffix != ".npz":
            raise ValueError(f"run file must end in .npz, got {path.name!r}")
        arrays = {k: getattr(self, k) for k in PHYSICS_KEYS + CONTROL_KEYS}
        arrays["status"] = np.asarray(self.status, dtype=str)
        for k, v in self.info.items():
            arrays[f"info_{k}"] = np.asarray("" if v is None else v)
        with atomic_open(path, "wb") as fh:
            np.savez_compressed(fh, **arrays)
        return path

    @classmethod
    def load(cls, path: str | Path) -> Episode:
        """Read a run file written by :meth:`save`."""
        with np.load(path, allow_pickle=False) as z:
            missing = [k for k in PHYSICS_KEYS + CONTROL_KEYS if k not in z.files]
            if missing:
                raise ValueError(f"{path}: not a run file, missing {missing}")
            arrays = {k: z[k] for k in PHYSICS_KEYS + CONTROL_KEYS}
            info = {k[5:]: z[k].item() for k in z.files if k.startswith("info_")}
        return cls(**arrays, info=info)


def _columns(names: list[str] | None, wanted: tuple[str, ...], where: str) -> list[int]:
    if names is None:
        raise ValueError(f"{where}: channel names are needed to find {wanted}")
    missing = [w for w in wanted if w not in names]
    if missing:
        raise ValueError(f"{where} has no channel(s) {missing}; it has {list(names)}")
    return [names.index(w) for w in wanted]


def _vec3(x: Any) -> np.ndarray | None:
    try:
        a = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        return None
    return a if a.shape == (3,) and np.isfinite(a).all() else None


def _scalar(x: Any) -> float:
    try:
        return float(x)
    except (TypeError, ValueError):
        return float("nan")


def run_episode(controller: Controller, trial: Trial, *, scene: SceneConfig | None = None,
                wearer: WearerConfig | None = None, duration_s: float | None = None, seed: int = 0,
                record: bool = True, render: str | Path | None = None, progress: bool = False,
                obs_names: list[str] | None = None, act_names: list[str] | None = None,
                servo: ServoConfig | None = None) -> Episode:
    """Run ``controller`` beside a simulated wearer whose intent is ``trial``'s knife (module docstring).

    Args:
        controller: any object with ``step(t, obs, voluntary, q, v, base_pose)``.
        trial: raw 100 Hz demonstration; ``trial.obs`` rows are given to the controller as
            they are; the knife channels (``knife_x/y/z`` in ``act_names``, default the
            generator's) are the intent, the fork pose channels drive the fork.
        scene, wearer, servo: settings (defaults if None).
        duration_s: simulated time [s] (default: the whole trial).
        seed: torso sway phases and the wearer's noise.
        record: keep the physics-rate arrays (False: empty arrays, metrics still work).
        render: path of a video (.mp4 if ffmpeg is available, else a .gif beside it).
        progress: show a tqdm bar.
    """
    from sim.demonstrator import ACT_NAMES, OBS_NAMES

    sc = scene or SceneConfig()
    wc = wearer or WearerConfig()
    obs_names = list(OBS_NAMES) if obs_names is None else list(obs_names)
    act_names = list(ACT_NAMES) if act_names is None else list(act_names)
    if not callable(getattr(controller, "step", None)):
        raise TypeError(f"controller must have a step(t, obs, voluntary, q, v, base_pose) method, "
                        f"got {type(controller).__name__}")
    tip_cols = _columns(act_names, TIP_CHANNELS, "trial act")
    fork_cols = _columns(obs_names, FORK_CHANNELS, "trial obs")
    if trial.obs.shape[1] != len(obs_names) or trial.act.shape[1] != len(act_names):
        raise ValueError(f"trial {trial.trial_id}: obs/act have {trial.obs.shape[1]}/{trial.act.shape[1]} "
                         f"columns, names give {len(obs_names)}/{len(act_names)}")
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

    world = EatingScene(sc, seed=seed)
    m, d = world.model, world.data
    person = SimulatedWearer(intent_raw, 1.0 / sc.control_period, wc, seed=seed)
    intent = person.intent
    geom = ArmGeometry.from_params(sc.params)
    base0 = world.base_pose(0.0)
    q0 = nearest_reachable_q(geom, world.plate_to_torso(base0, intent[0][None])[0])
    world.set_state(q0, np.zeros(3), 0.0)
    world.set_fork(trial.obs[0, fork_cols])
    srv = JointServo(m, d, sc.params, servo)
    if callable(getattr(controller, "reset", None)):
        controller.reset()

    n_sub, h = sc.substeps, sc.timestep
    n_phys = n_ctrl * n_sub if record else 0
    rec_t, rec_q = np.zeros(n_phys), np.zeros((n_phys, 3))
    rec_v, rec_tau = np.zeros((n_phys, 3)), np.zeros((n_phys, 3))
    out = {k: np.full((n_ctrl, 3), np.nan) for k in ("tip", "tip_reference", "voluntary")}
    alpha, beta, novelty = np.full(n_ctrl, np.nan), np.full(n_ctrl, np.nan), np.full(n_ctrl, np.nan)
    mode = np.full(n_ctrl, -1, dtype=int)
    status = np.empty(n_ctrl, dtype=object)
    step_time = np.zeros(n_ctrl)
    base_poses = np.zeros((n_ctrl, 4, 4))
    q_lo, q_hi = sc.params.lower - LIMIT_TOL, sc.params.upper + LIMIT_TOL
    v_lim, tau_lim = sc.params.velocity_limit + LIMIT_TOL, sc.params.torque_limit + TORQUE_TOL
    buf_t, buf_q, buf_v, buf_f = np.zeros(n_sub), np.zeros((n_sub, 3)), np.zeros((n_sub, 3)), np.zeros((n_sub, 3))
    violations, worst = 0, {"q": 0.0, "v": 0.0, "tau": 0.0}
    renderer = None
    if render is not None:
        from sim.render import VideoRecorder

        renderer = VideoRecorder(m, render, fps=25, control_rate_hz=1.0 / sc.control_period)
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=n_ctrl, desc=f"trial {trial.trial_id}", unit="step", leave=False)

    wall0, cpu0 = time.perf_counter(), time.process_time()
    for k in range(n_ctrl):
        t_k = k * sc.control_period
        world.set_time(t_k)
        world.set_fork(trial.obs[k, fork_cols])
        mujoco.mj_step1(m, d)
        tip = world.tip_in_plate().copy()
        base = world.base_pose(t_k)
        theta = person.step(k, tip)
        q, v = d.qpos[:3].copy(), d.qvel[:3].copy()
        t0 = time.perf_counter()
        try:
            cmd = controller.step(t_k, trial.obs[k].copy(), theta.copy(), q, v, base)
            err = None
        except Exception as exc:  # noqa: BLE001  (the loop must go on: hold, and say why)
            cmd, err = None, f"controller_error: {type(exc).__name__}: {exc}"
        step_time[k] = time.perf_counter() - t0
        seg = None if cmd is None else [_vec3(getattr(cmd, a, None)) for a in ("q_cmd", "v_cmd", "a_cmd")]
        if seg is not None and all(x is not None for x in seg):
            srv.set_segment(seg[0], seg[1], seg[2], t_k + sc.control_period)
            status[k] = str(getattr(cmd, "status", "ok"))
        else:
            srv.hold()
            status[k] = err or "invalid_command"
        if cmd is not None:
            alpha[k], beta[k] = _scalar(getattr(cmd, "alpha", np.nan)), _scalar(getattr(cmd, "beta", np.nan))
            novelty[k] = _scalar(getattr(cmd, "novelty", np.nan))
            ref = _vec3(getattr(cmd, "tip_reference", None))
            if ref is not None:
                out["tip_reference"][k] = ref
            proba = np.asarray(getattr(cmd, "mode_proba", ()), dtype=float).reshape(-1)
            if proba.size and np.isfinite(proba).all():
                mode[k] = int(np.argmax(proba))
        out["tip"][k], out["voluntary"][k], base_poses[k] = tip, theta, base
        if renderer is not None:
            renderer.maybe_capture(d, k)

        if record:
            blk = slice(k * n_sub, (k + 1) * n_sub)
            bt, bq, bv, bf = rec_t[blk], rec_q[blk], rec_v[blk], rec_tau[blk]
        else:
            bt, bq, bv, bf = buf_t, buf_q, buf_v, buf_f
        for j in range(n_sub):
            if j:  # the first sub-step's kinematics were computed above
                world.set_time(t_k + j * h)
                mujoco.mj_step1(m, d)
            d.ctrl = srv.torque()
            mujoco.mj_step2(m, d)
            bt[j] = d.time
            bq[j], bv[j], bf[j] = d.qpos, d.qvel, d.actuator_force  # the arm is the whole state
        # the limits, checked on every physics step of the period (vectorised once per period)
        eq = np.maximum(q_lo - bq, bq - q_hi).max(axis=1)
        ev = (np.abs(bv) - v_lim).max(axis=1)
        et = (np.abs(bf) - tau_lim).max(axis=1)
        bad = (eq > 0.0) | (ev > 0.0) | (et > 0.0)
        if bad.any():
            violations += int(bad.sum())
            worst["q"], worst["v"] = max(worst["q"], float(eq.max())), max(worst["v"], float(ev.max()))
            worst["tau"] = max(worst["tau"], float(et.max()))
        if bar is not None:
            bar.update(1)
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    if bar is not None:
        bar.close()

    info: dict[str, Any] = {
        "trial_id": trial.trial_id, "seed": seed, "duration_s": n_ctrl * sc.control_period,
        "control_period_s": sc.control_period, "physics_dt_s": h, "wall_time_s": wall,
        "cpu_time_s": cpu,
        "limit_violations": violations, "max_q_excess_rad": worst["q"], "max_v_excess_rad_s": worst["v"],
        "max_tau_excess_nm": worst["tau"], "servo_qp_steps": srv.qp_steps,
        "servo_fallback_steps": srv.fallback_steps, "brake_infeasible_steps": srv.brake_infeasible,
        "shoulder_gain": wc.shoulder.gain, "shoulder_deadband_rad": wc.shoulder.deadband_rad,
        "wearer_deadband_m": wc.deadband_m, "video": None, "render_message": None,
    }
    if renderer is not None:
        video, message = renderer.close()
        info["video"], info["render_message"] = (str(video) if video else None), message
        if message:
            warnings.warn(message, RuntimeWarning, stacklevel=2)
    return Episode(rec_t, rec_q, rec_v, rec_tau, np.arange(n_ctrl) * sc.control_period, alpha, beta, mode,
                   out["tip"], out["tip_reference"], intent.copy(), out["voluntary"], status.astype(str),
                   step_time, base_poses, novelty, info)
