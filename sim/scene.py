"""The MuJoCo eating scene: a swaying torso wearing an arm (the SuperLimb by default), a table, a plate, food, the fork.

Frames (right-handed, metres): **world** — the seat under the wearer's sternum at the neutral posture, x forward,
y to the wearer's left, z up; **torso** (a mocap body) — the model world frame of the arm's
:class:`robot.description.RobotDescription`, its subtree (``RobotDescription.mjcf_body``) mounted at the
description's mount; **plate** — origin at the plate's centre on its top surface, z up, x away from the wearer
(``SceneConfig.plate_position``).

The torso sways kinematically (:meth:`SceneConfig.torso_pose`):

    p_torso(t) = Σ_k A_k · sin(2π f_k t + φ_k)  [m],   pitch(t) = P · sin(2π f_posture t + φ_posture)  [rad]

f = 0.25 Hz (breathing, a few mm: De Groote et al. 1997, J Appl Physiol 83:1531) and 0.05 Hz (postural drift,
about a centimetre: Kuo 2005); mocap motion is no inertial load (≈ 0.01 m/s²). The controller's base pose is
``T_plate_torso = T_world_plate⁻¹ · T_world_torso`` (``p_plate = R p_model + t``), as the paper's motion capture.
Physics: 1 kHz, semi-implicit ``Euler`` (which :mod:`sim.servo` predicts exactly), contacts disabled (the
demonstration's forces are logged, not simulated).

Headless rendering needs ``MUJOCO_GL=egl`` before MuJoCo's first import; importing ``sim`` sets it when unset
and there is no display (:mod:`sim.offscreen_gl`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import mujoco
import numpy as np

from robot.default_arm import as_description
from robot.description import RobotDescription
from robot.keepout import BLADE_LENGTH
from robot.superlimb import rpy_to_matrix, superlimb_description
from robot.wearer_body import WearerBody, body_zones
from sim.task import EATING

__all__ = ["EatingScene", "SceneConfig", "build_scene_xml", "pose_matrix"]


_EYE4 = np.eye(4)


def pose_matrix(R: np.ndarray, p: np.ndarray) -> np.ndarray:
    """4×4 homogeneous transform [[R, p], [0, 1]]."""
    T = _EYE4.copy()
    T[:3, :3] = R
    T[:3, 3] = p
    return T


def _v(x) -> str:
    return " ".join(repr(float(e)) for e in x)


def _rot_y(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


@dataclass(frozen=True)
class SceneConfig:
    """Settings of the scene (lengths [m], frequencies [Hz], angles [rad]).

    Attributes:
        robot: the arm (a :class:`robot.description.RobotDescription`; a ``SuperLimbParams`` is
            turned into one); default the SuperLimb, mounted on the right side of the chest.
            A mount given in the plate frame is ``plate_position`` + that position in the torso
            frame (the torso at rest is the world; plate axes = world axes).
        plate_position: plate frame origin in the world (= torso at rest): 0.40 m in
            front of the sternum, 0.10 m to the right (the knife side), 0.21 m above
            the seat; chosen so that every knife tip of the default demonstrations
            is reachable by the SuperLimb
            (tests/robot/test_kinematics.py::test_demonstrated_knife_tips_reachable_and_on_or_above_the_plate).
        plate_radius, plate_height: plate geometry.
        table_height: table top above the seat (below the plate).
        breathing_hz, breathing_amplitude_m: breathing sway (x, y, z) of the torso.
        posture_hz, posture_amplitude_m, posture_pitch_rad: slow postural sway.
        timestep: physics step [s] (1 kHz).
        control_period: controller period [s] (100 Hz), a multiple of ``timestep``.
        body: the wearer's body zones (:mod:`robot.wearer_body`): the trunk, head, fork hand and
            forearm are drawn from it (skin coloured; the forearm is a mocap body that
            :meth:`EatingScene.set_fork` moves with the hand).
        blade_length: the knife's blade [m], tip to heel along the tool frame's −x.
    """

    robot: RobotDescription = field(default_factory=superlimb_description)
    plate_position: tuple[float, float, float] = (0.40, -0.10, 0.21)
    plate_radius: float = 0.12
    plate_height: float = 0.015
    table_height: float = 0.195
    breathing_hz: float = 0.25
    breathing_amplitude_m: tuple[float, float, float] = (0.004, 0.0, 0.003)
    posture_hz: float = 0.05
    posture_amplitude_m: tuple[float, float, float] = (0.010, 0.006, 0.0)
    posture_pitch_rad: float = 0.015
    timestep: float = 0.001
    control_period: float = 0.01
    body: WearerBody = field(default_factory=lambda: EATING.body)
    blade_length: float = BLADE_LENGTH

    def __post_init__(self) -> None:
        object.__setattr__(self, "robot", as_description(self.robot))
        if not (self.timestep > 0 and self.control_period > 0):
            raise ValueError(f"timestep and control_period must be > 0, got {self.timestep}, {self.control_period}")
        ratio = self.control_period / self.timestep
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            raise ValueError(f"control_period {self.control_period} s must be a multiple of timestep {self.timestep} s")
        for name in ("breathing_hz", "posture_hz", "plate_radius", "plate_height"):
            if not getattr(self, name) >= 0:
                raise ValueError(f"SceneConfig.{name} must be >= 0, got {getattr(self, name)}")

    @property
    def params(self):
        """The SuperLimb's parameters (old name; only for the SuperLimb)."""
        params = getattr(self.robot, "params", None)
        if params is None:
            raise AttributeError(f"SceneConfig.params: the arm {self.robot.name!r} is not a SuperLimb; use .robot")
        return params

    def mount_in_torso(self, mount_plate: tuple[float, float, float]) -> tuple[float, float, float]:
        """A mount position [m] given in the plate frame, in the torso frame (module docstring frames)."""
        return tuple(float(m + p) for m, p in zip(mount_plate, self.plate_position))  # type: ignore[return-value]

    @property
    def substeps(self) -> int:
        """Physics steps per control period."""
        return round(self.control_period / self.timestep)

    def torso_pose(self, t: float, phases: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Torso position (3,) [m] and rotation (3, 3) in the world at time t [s] (module equation).

        ``phases`` (2,) [rad]: breathing and posture phase (drawn from the episode seed).
        """
        wb = 2.0 * math.pi * self.breathing_hz * t + phases[0]
        wp = 2.0 * math.pi * self.posture_hz * t + phases[1]
        sb, sp = math.sin(wb), math.sin(wp)
        ab, ap = self.breathing_amplitude_m, self.posture_amplitude_m
        p = np.array([ab[0] * sb + ap[0] * sp, ab[1] * sb + ap[1] * sp, ab[2] * sb + ap[2] * sp])
        return p, _rot_y(self.posture_pitch_rad * sp)


_FOOD = ((-0.03, 0.03), (0.04, -0.02), (0.0, -0.05), (0.05, 0.05))  # piece centres on the plate [m]


def build_scene_xml(config: SceneConfig | None = None) -> str:
    """The scene's MJCF (see module docstring): torso (mocap) with the arm, table, plate, food, fork (mocap)."""
    c = config or SceneConfig()
    robot, b = c.robot, c.body
    px, py, pz = c.plate_position
    food = "".join(
        f'      <geom name="food{i}" type="box" size="0.012 0.012 0.008" pos="{x} {y} 0.008" rgba="0.8 0.55 0.3 1"/>\n'
        for i, (x, y) in enumerate(_FOOD))
    arm = robot.mjcf_body(indent=6)
    return f"""<mujoco model="superlimb_eating">
  <compiler angle="radian" inertiafromgeom="false" autolimits="true"/>
  <option timestep="{c.timestep!r}" gravity="0 0 {-robot.gravity!r}" integrator="Euler">
    <flag contact="disable"/>
  </option>
  <visual><global offwidth="640" offheight="480"/><quality offsamples="0"/></visual>
  <worldbody>
    <light pos="0.4 0 1.5" dir="0 0 -1" directional="true"/>
    <camera name="side" pos="{px + 0.35} {py - 0.75} {pz + 0.45}" xyaxes="0.9 0.44 0 -0.2 0.4 0.9"/>
    <camera name="front" pos="{px + 0.9} {py} {pz + 0.5}" xyaxes="0 1 0 -0.45 0 0.9"/>
    <geom name="floor" type="plane" size="2 2 0.1" pos="0 0 -0.47" rgba="0.5 0.5 0.5 1"/>
    <geom name="table" type="box" size="0.35 0.5 {(c.table_height + 0.47) / 2!r}"
          pos="{px + 0.1!r} {py!r} {(c.table_height - 0.47) / 2!r}" rgba="0.55 0.4 0.25 1"/>
    <geom name="seat" type="box" size="0.2 0.2 0.02" pos="-0.05 0 -0.02" rgba="0.3 0.3 0.35 1"/>
    <body name="plate" pos="{px!r} {py!r} {pz!r}">
      <geom name="plate_geom" type="cylinder" size="{c.plate_radius!r} {c.plate_height / 2!r}"
            pos="0 0 {-c.plate_height / 2!r}" rgba="0.95 0.95 0.95 1"/>
      <site name="plate_frame" pos="0 0 0" size="0.005" rgba="0 0 1 1"/>
{food}    </body>
    <body name="torso" mocap="true" pos="0 0 0">
      <geom name="trunk" type="capsule" fromto="{_v(b.torso_a)} {_v(b.torso_b)}" size="{b.torso_radius!r}"
            rgba="0.4 0.5 0.7 0.6"/>
      <geom name="head" type="sphere" size="{b.head_radius!r}" pos="{_v(b.head_center)}" rgba="0.9 0.75 0.65 0.6"/>
      <geom name="upper_arm" type="capsule" fromto="-0.05 0.2 0.5 {_v(b.elbow)}" size="0.045"
            rgba="0.9 0.75 0.65 0.6"/>
{arm}    </body>
    <body name="forearm" mocap="true" pos="0 0 0">
      <geom name="forearm" type="capsule" fromto="0 0 0 0 0 {b.forearm_length!r}" size="{b.forearm_radius!r}"
            rgba="0.9 0.75 0.65 0.6"/>
    </body>
    <body name="fork" mocap="true" pos="{px} {py} {pz}">
      <geom name="fork_handle" type="capsule" fromto="-0.04 0.07 0.13 -0.008 0.014 0.026" size="0.006"
            rgba="0.3 0.3 0.3 1"/>
      <geom name="fork_tines" type="box" size="0.012 0.01 0.002" pos="-0.004 0.007 0.013" rgba="0.8 0.8 0.85 1"/>
      <site name="fork_tip" pos="0 0 0" size="0.004" rgba="0 1 0 1"/>
      <geom name="hand" type="sphere" size="{b.hand_radius!r}" pos="{_v(b.hand_offset)}" rgba="0.9 0.75 0.65 0.6"/>
    </body>
  </worldbody>
  <actuator>
{robot.mjcf_actuators(indent=4)}  </actuator>
</mujoco>
"""


class EatingScene:
    """The compiled scene with handles to its bodies, joints and sites.

    ``model``, ``data``: MuJoCo objects; ``qadr``/``dofadr``: the arm's joint
    addresses in qpos/qvel; ``phases``: the torso sway phases of this episode.
    """

    def __init__(self, config: SceneConfig | None = None, seed: int = 0) -> None:
        self.config = c = config or SceneConfig()
        self.model = mujoco.MjModel.from_xml_string(build_scene_xml(c))
        self.data = mujoco.MjData(self.model)
        m = self.model
        names = c.robot.joint_names
        jids = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, n) for n in names]
        self.qadr = np.array([m.jnt_qposadr[j] for j in jids])
        self.dofadr = np.array([m.jnt_dofadr[j] for j in jids])
        n = len(names)
        if m.nv != n or m.nq != n or list(self.dofadr) != list(range(n)) or list(self.qadr) != list(range(n)):
            raise RuntimeError(f"the scene's state must be exactly the arm's {n} joints {names} in the model's "
                               f"order, got nq={m.nq}, nv={m.nv}, DOF addresses {list(self.dofadr)}")
        self.torso_body = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "torso")
        self.fork_body = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "fork")
        self.plate_body = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "plate")
        self.torso_mocap = int(m.body_mocapid[self.torso_body])
        self.fork_mocap = int(m.body_mocapid[self.fork_body])
        self.forearm_mocap = int(m.body_mocapid[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "forearm")])
        self.fork_pose = np.full(6, np.nan)
        self.tip_site = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, c.robot.tip_frame)
        self.plate_p = np.array(c.plate_position, dtype=float)  # plate frame = world axes, shifted
        self.phases = np.random.default_rng(seed).uniform(0.0, 2.0 * math.pi, 2)
        self._ph0, self._ph1 = float(self.phases[0]), float(self.phases[1])
        self._quat = np.zeros(4)
        # the torso's mocap rows as views (set at every physics step)
        self._torso_pos = self.data.mocap_pos[self.torso_mocap]
        self._torso_quat = self.data.mocap_quat[self.torso_mocap]
        c0 = self.config
        self._sway = (2.0 * math.pi * c0.breathing_hz, 2.0 * math.pi * c0.posture_hz, *c0.breathing_amplitude_m,
                      *c0.posture_amplitude_m, 0.5 * c0.posture_pitch_rad)

    # ------------------------------------------------------------------ poses
    def base_pose(self, t: float) -> np.ndarray:
        """4×4 T_plate_torso at time t [s]: ``p_plate = R p_model + t`` (the controller's ``base_pose``)."""
        p, R = self.config.torso_pose(t, self.phases)
        return pose_matrix(R, p - self.plate_p)

    def set_time(self, t: float) -> None:
        """Move the torso mocap body to its sway pose at time t [s] (takes effect at the next kinematics).

        Same pose as :meth:`SceneConfig.torso_pose` (pitch about y: quaternion
        (cos θ/2, 0, sin θ/2, 0)), in plain floats: it runs at every physics step.
        """
        wb, wp, ab0, ab1, ab2, ap0, ap1, ap2, half_pitch = self._sway
        sb = math.sin(wb * t + self._ph0)
        sp = math.sin(wp * t + self._ph1)
        self._torso_pos[:] = (ab0 * sb + ap0 * sp, ab1 * sb + ap1 * sp, ab2 * sb + ap2 * sp)
        half = half_pitch * sp
        self._torso_quat[:] = (math.cos(half), 0.0, math.sin(half), 0.0)

    def set_fork(self, pose: np.ndarray, t: float | None = None) -> None:
        """Place the fork tip at ``pose`` = (x, y, z [m], roll, pitch, yaw [rad]) in the plate frame,
        and, with the time t [s] (the torso's pose), the forearm from the hand toward the elbow.

        Non-finite entries (a lost marker) leave the fork where it was; :attr:`fork_pose` is
        the pose shown.
        """
        pose = np.asarray(pose, dtype=float)
        if pose.shape != (6,):
            return
        values = pose.tolist()
        if not all(map(math.isfinite, values)):
            return
        self.fork_pose = pose.copy()
        mujoco.mju_mat2Quat(self._quat, rpy_to_matrix(values[3:]).reshape(-1))
        self.data.mocap_pos[self.fork_mocap] = pose[:3] + self.plate_p
        self.data.mocap_quat[self.fork_mocap] = self._quat
        if t is not None:
            self._place_forearm(pose, t)

    def _place_forearm(self, pose: np.ndarray, t: float) -> None:
        """The forearm mocap body: its local z along the forearm zone's axis (hand → elbow)."""
        base = self.base_pose(t)
        zone = body_zones(self.config.body, pose, base, parts=("forearm",))[0]
        a = base[:3, :3] @ zone.a + base[:3, 3] + self.plate_p
        b = base[:3, :3] @ zone.b + base[:3, 3] + self.plate_p
        axis = b - a
        length = float(np.linalg.norm(axis))
        if length < 1e-9:
            return
        z = axis / length
        quat = np.zeros(4)
        mujoco.mju_quatZ2Vec(quat, z)
        self.data.mocap_pos[self.forearm_mocap] = a
        self.data.mocap_quat[self.forearm_mocap] = quat

    def knife_heel_in_plate(self) -> np.ndarray:
        """The blade's heel [m] in the plate frame: ``blade_length`` back from the tip along the
        tool frame's x (valid after mj_step1 / mj_forward)."""
        R = self.data.site_xmat[self.tip_site].reshape(3, 3)
        return self.data.site_xpos[self.tip_site] - self.config.blade_length * R[:, 0] - self.plate_p

    def tip_in_plate(self) -> np.ndarray:
        """Knife tip [m] in the plate frame from MuJoCo's kinematics (valid after mj_step1 / mj_forward)."""
        return self.data.site_xpos[self.tip_site] - self.plate_p

    def torso_to_plate(self, base_pose: np.ndarray, points_model: np.ndarray) -> np.ndarray:
        """Points (N, 3) in the torso (model world) frame → plate frame with ``base_pose``."""
        return points_model @ base_pose[:3, :3].T + base_pose[:3, 3]

    def plate_to_torso(self, base_pose: np.ndarray, points_plate: np.ndarray) -> np.ndarray:
        """Points (N, 3) in the plate frame → torso (model world) frame: R⁻¹(p − t)."""
        return (points_plate - base_pose[:3, 3]) @ base_pose[:3, :3]

    def set_state(self, q: np.ndarray, v: np.ndarray, t: float = 0.0) -> None:
        """Arm state (q [rad], v [rad/s]) and the torso at time t; recomputes the kinematics."""
        self.data.time = t
        self.data.qpos[self.qadr] = q
        self.data.qvel[self.dofadr] = v
        self.set_time(t)
        mujoco.mj_forward(self.model, self.data)
