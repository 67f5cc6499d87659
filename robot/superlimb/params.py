"""SuperLimb description: one parametric source for URDF, MJCF and Pinocchio.

The arm of Song & Asada: a 3-DOF arm on a rigid base on a vest, worn on the right side of the
wearer's torso, holding a knife. Kinematic chain (lengths [m], angles [rad])::

    world ──mount (fixed)──▶ base_link
      base_link ──base_yaw (revolute z, right-angle drive)──▶ turret_link
      turret_link ──shoulder (revolute y, belt 1:3)──▶ upper_arm_link
      upper_arm_link ──elbow (revolute y, belt 1:2)──▶ forearm_link
      forearm_link ──knife_mount (fixed, pitched down)──▶ knife_link
      knife_link ──knife_tip_joint (fixed)──▶ knife_tip       (the tool frame)

``world`` is the wearer's torso frame (x forward, y to the wearer's left, z up); at q = 0 the arm
points forward (+x), a positive shoulder or elbow angle pitches it down (about +y). Every number
lives in :class:`SuperLimbParams`; joint position, velocity, acceleration and torque limits are
derived from the actuator and transmission figures (:meth:`JointParams.torque_limit` and friends)
unless a ``*_override`` field is set. :mod:`robot.superlimb.model_files` turns it into URDF, MJCF
and a Pinocchio model from the same object, so they cannot drift; ``python -m robot`` regenerates
``robot/assets/`` and a test checks the files are up to date. Inconsistent parameters (joint and
link counts, limits out of order or not positive, braking above the acceleration limit) raise ``ValueError``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Sequence

import numpy as np

Vec3 = tuple[float, float, float]
Inertia6 = tuple[float, float, float, float, float, float]

ASSETS_DIR = Path(__file__).resolve().parent.parent / "assets"
TOOL_FRAME = "knife_tip"
GRAVITY = 9.81  # [m/s²], also written into the MJCF <option>


# --------------------------------------------------------------------------
# building blocks
# --------------------------------------------------------------------------


@dataclass(frozen=True)
class Inertial:
    """Rigid-body inertia of one link.

    ``com`` [m] is in the link frame; ``inertia`` = (ixx, iyy, izz, ixy, ixz, iyz)
    [kg·m²] is about the centre of mass, expressed in axes parallel to the link
    frame (the URDF convention with ``<origin rpy="0 0 0"/>`` and MuJoCo's
    ``fullinertia``).
    """

    mass: float
    com: Vec3
    inertia: Inertia6


def rod_inertial(mass: float, length: float, radius: float, com_x: float | None = None,
                 point_mass: float = 0.0, point_x: float = 0.0) -> Inertial:
    """Thin-walled-tube-like link along +x plus an optional point mass on the axis.

    Tube (solid cylinder approximation) of ``mass`` [kg], ``length`` [m] and
    ``radius`` [m] from x = 0 to x = length: I_xx = m r²/2,
    I_yy = I_zz = m (3 r² + L²)/12 about its centre.  A point mass
    ``point_mass`` [kg] at x = ``point_x`` [m] (an actuator, a pulley) is
    combined by the parallel-axis theorem.  ``com_x`` overrides the tube centre.
    """
    xc = length / 2.0 if com_x is None else com_x
    m_total = mass + point_mass
    x_com = (mass * xc + point_mass * point_x) / m_total
    ixx = 0.5 * mass * radius**2
    iyy_tube = mass * (3.0 * radius**2 + length**2) / 12.0
    iyy = iyy_tube + mass * (xc - x_com) ** 2 + point_mass * (point_x - x_com) ** 2
    return Inertial(m_total, (x_com, 0.0, 0.0), (ixx, iyy, iyy, 0.0, 0.0, 0.0))


@dataclass(frozen=True)
class Actuator:
    """Harmonic-drive servo actuator, figures at the harmonic-drive *output*.

    Defaults are representative of a size-8 hollow-shaft harmonic-drive servo
    with ratio 50 (FHA-8C-50 class): replace them by the datasheet of the units
    actually fitted.
    """

    gear_ratio: float = 50.0  # [-] harmonic drive reduction (motor turns per output turn)
    rated_torque: float = 1.8  # [N·m] continuous (thermal) torque at the HD output
    peak_torque: float = 3.3  # [N·m] repeated peak torque at the HD output
    max_output_speed: float = 120.0 * 2.0 * math.pi / 60.0  # [rad/s] 120 rpm at the HD output
    # Motor rotor + wave generator at the motor shaft [kg·m²].  The datasheet
    # gives ≈ 0.0074 kg·m² at the output for ratio 50 → 0.0074 / 50² ≈ 2.96e-6.
    rotor_inertia: float = 2.96e-6


@dataclass(frozen=True)
class JointParams:
    """One actuated revolute joint and its drive train.

    Derived limits (each overridable by the ``*_override`` field):

    - torque  τ_max = η · N_t · τ_peak          [N·m]  (N_t: belt / right-angle ratio)
    - speed   v_max = min(ω_HD,max / N_t, cap)  [rad/s]
    - armature I_a = J_rotor · (N_HD · N_t)²    [kg·m²] (reflected rotor inertia)
    """

    name: str
    axis: Vec3
    origin_xyz: Vec3  # [m] parent link frame → joint frame, at q = 0
    origin_rpy: Vec3  # [rad] URDF roll-pitch-yaw (fixed axes X, Y, Z)
    lower: float  # [rad]
    upper: float  # [rad]
    transmission_ratio: float  # [-] belt or right-angle drive, joint side slower
    transmission_efficiency: float  # [-] applied to the torque limit
    speed_cap: float  # [rad/s] wearer-safety cap on joint speed (see SuperLimbParams)
    braking_acceleration: float  # [rad/s²] deceleration the QP relies on to stop (viability)
    acceleration_limit: float  # [rad/s²] box on commanded joint acceleration
    actuator: Actuator = field(default_factory=Actuator)
    torque_limit_override: float | None = None
    velocity_limit_override: float | None = None
    armature_override: float | None = None

    @property
    def torque_limit(self) -> float:
        """τ_max = η · N_t · τ_peak [N·m] (peak, not rated: eating motions are short bursts)."""
        if self.torque_limit_override is not None:
            return float(self.torque_limit_override)
        return self.transmission_efficiency * self.transmission_ratio * self.actuator.peak_torque

    @property
    def rated_joint_torque(self) -> float:
        """Continuous torque at the joint η · N_t · τ_rated [N·m] (for holding against gravity)."""
        return self.transmission_efficiency * self.transmission_ratio * self.actuator.rated_torque

    @property
    def velocity_limit(self) -> float:
        """v_max = min(ω_HD,max / N_t, speed_cap) [rad/s]."""
        if self.velocity_limit_override is not None:
            return float(self.velocity_limit_override)
        return min(self.actuator.max_output_speed / self.transmission_ratio, self.speed_cap)

    @property
    def armature(self) -> float:
        """Reflected rotor inertia I_a = J_rotor · (N_HD · N_t)² [kg·m²]."""
        if self.armature_override is not None:
            return float(self.armature_override)
        n = self.actuator.gear_ratio * self.transmission_ratio
        return self.actuator.rotor_inertia * n * n


@dataclass(frozen=True)
class LinkParams:
    """A link: its name, inertia and a visual capsule from ``geom_from`` to ``geom_to`` [m]."""

    name: str
    inertial: Inertial
    geom_from: Vec3
    geom_to: Vec3
    geom_radius: float  # [m]


# --------------------------------------------------------------------------
# the configuration: every number and the reasoning next to it
# --------------------------------------------------------------------------

UPPER_ARM_LENGTH = 0.26  # [m] shoulder axis → elbow axis
FOREARM_LENGTH = 0.22  # [m] elbow axis → knife holder
KNIFE_LENGTH = 0.14  # [m] knife holder → knife tip (handle stub + blade)
KNIFE_PITCH = math.pi / 4  # [rad] knife pitched 45° down from the forearm axis


def _default_joints() -> tuple[JointParams, ...]:
    # Torque limits (η · N_t · τ_peak with τ_peak = 3.3 N·m):
    #   base_yaw: bevel right-angle drive 1:1, η = 0.90  → 2.97 N·m
    #             (only inertia and Coriolis loads: the axis is vertical)
    #   shoulder: belt 1:3, η = 0.95                      → 9.405 N·m
    #             (gravity of the outstretched arm ≈ 2.3 N·m, ≈ 25 %)
    #   elbow:    belt 1:2, η = 0.95                      → 6.27 N·m
    #             (gravity of forearm + knife ≈ 0.7 N·m)
    # Speed limits: the HD output reaches 12.57 rad/s (120 rpm), i.e.
    #   12.57 / N_t = 12.57, 4.19, 6.28 rad/s.  A knife next to the wearer's
    #   face must not move that fast and, at those speeds, centrifugal and
    #   Coriolis loads alone would exceed the shoulder torque; the caps
    #   (2.0, 2.0, 2.5 rad/s) keep the knife tip below ≈ 1.5 m/s and the
    #   velocity-product torques below ≈ 30 % of the torque limits, so that the
    #   braking accelerations below stay available at every state.
    # Braking accelerations (viability: the QP guarantees the arm can stop
    #   before a position limit decelerating at this rate): chosen so that
    #   |M(q)·a + h(q, v)| ≤ τ_max for every a with |a_i| ≤ a_brake,i, every q
    #   in the limits and |v_i| ≤ v_max,i (checked by sampling in
    #   tests/robot/test_superlimb.py::test_braking_is_always_torque_feasible).
    #   (10, 15, 20) rad/s² need at worst ≈ 32 %, 46 %, 28 % of τ_max, which
    #   leaves the rest for gravity changes and tracking while braking.
    # Acceleration limits: a box on the commanded acceleration, ≈ τ_max over the
    #   smallest joint inertia seen by that joint (≈ 0.04, 0.07, 0.035 kg·m²):
    #   2.97/0.04 ≈ 75 → 60, 9.4/0.07 ≈ 135 → 100, 6.27/0.035 ≈ 180 → 150 rad/s²,
    #   so that the torque limit, not this box, is what saturates in fast motions.
    # Armature: J_rotor (N_HD N_t)² = 2.96e-6 · 50² · (1, 9, 4)
    #   = 0.0074, 0.0666, 0.0296 kg·m².
    return (
        JointParams(
            name="base_yaw", axis=(0.0, 0.0, 1.0), origin_xyz=(0.0, 0.0, 0.04), origin_rpy=(0.0, 0.0, 0.0),
            # −70° (outward, to the wearer's right) … +90° (across the front).
            lower=-1.22, upper=1.57,
            transmission_ratio=1.0, transmission_efficiency=0.90,
            speed_cap=2.0, braking_acceleration=10.0, acceleration_limit=60.0,
        ),
        JointParams(
            name="shoulder", axis=(0.0, 1.0, 0.0), origin_xyz=(0.0, 0.0, 0.06), origin_rpy=(0.0, 0.0, 0.0),
            # −45° (up) … +90° (straight down).
            lower=-0.79, upper=1.57,
            transmission_ratio=3.0, transmission_efficiency=0.95,
            speed_cap=2.0, braking_acceleration=15.0, acceleration_limit=100.0,
        ),
        JointParams(
            name="elbow", axis=(0.0, 1.0, 0.0), origin_xyz=(UPPER_ARM_LENGTH, 0.0, 0.0), origin_rpy=(0.0, 0.0, 0.0),
            # −30° … +137°; the outstretched (singular) pose, knife tip on the
            # upper-arm line, is at ≈ −0.30 rad, inside the range.
            lower=-0.52, upper=2.40,
            transmission_ratio=2.0, transmission_efficiency=0.95,
            speed_cap=2.5, braking_acceleration=20.0, acceleration_limit=150.0,
        ),
    )


def _default_links() -> tuple[LinkParams, ...]:
    return (
        # Vest plate, right-angle drive and base actuator: fixed to the wearer,
        # no effect on the arm dynamics (kept for the scene mass).
        LinkParams("base_link", Inertial(0.60, (0.0, 0.0, 0.02), (1.2e-3, 1.2e-3, 1.0e-3, 0.0, 0.0, 0.0)),
                   (0.0, 0.0, 0.0), (0.0, 0.0, 0.04), 0.035),
        # Turret: carries the shoulder actuator (0.40 kg) and its belt pulley.
        LinkParams("turret_link", Inertial(0.55, (0.0, 0.0, 0.03), (9.0e-4, 9.0e-4, 6.0e-4, 0.0, 0.0, 0.0)),
                   (0.0, 0.0, 0.0), (0.0, 0.0, 0.06), 0.03),
        # Upper arm: 0.15 kg carbon tube + 0.40 kg elbow actuator 0.05 m from the
        # shoulder (it drives the elbow through the 1:2 belt inside the tube).
        LinkParams("upper_arm_link", rod_inertial(0.15, UPPER_ARM_LENGTH, 0.02, point_mass=0.40, point_x=0.05),
                   (0.0, 0.0, 0.0), (UPPER_ARM_LENGTH, 0.0, 0.0), 0.022),
        # Forearm: 0.22 kg tube with the elbow pulley and the knife holder.
        LinkParams("forearm_link", rod_inertial(0.22, FOREARM_LENGTH, 0.018),
                   (0.0, 0.0, 0.0), (FOREARM_LENGTH, 0.0, 0.0), 0.018),
        # Knife with handle and quick-release holder, along the knife frame x.
        LinkParams("knife_link", rod_inertial(0.12, KNIFE_LENGTH, 0.008, com_x=0.04),
                   (0.0, 0.0, 0.0), (KNIFE_LENGTH, 0.0, 0.0), 0.006),
    )


@dataclass(frozen=True)
class SuperLimbParams:
    """All parameters of the SuperLimb; override with :func:`dataclasses.replace`."""

    name: str = "superlimb"
    # Mount of base_link in the torso frame: right side of the chest, 0.20 m to
    # the wearer's right of the sternum, 0.12 m forward, 0.40 m above the seat.
    mount_xyz: Vec3 = (0.12, -0.20, 0.40)  # [m]
    mount_rpy: Vec3 = (0.0, 0.0, 0.0)  # [rad]
    joints: tuple[JointParams, ...] = field(default_factory=_default_joints)
    links: tuple[LinkParams, ...] = field(default_factory=_default_links)
    forearm_length: float = FOREARM_LENGTH  # [m] elbow axis → knife holder
    knife_pitch: float = KNIFE_PITCH  # [rad] knife pitched down about the forearm y axis
    knife_length: float = KNIFE_LENGTH  # [m] holder → tip
    gravity: float = GRAVITY  # [m/s²]
    mj_timestep: float = 0.002  # [s] MuJoCo integration step written into the MJCF
    knife_contact: bool = True  # whether the knife geom collides in MuJoCo

    def __post_init__(self) -> None:
        if len(self.joints) != 3 or len(self.links) != 5:
            raise ValueError("SuperLimbParams needs 3 joints and 5 links (base, turret, upper arm, forearm, knife)")
        for j in self.joints:
            if not j.lower < j.upper:
                raise ValueError(f"joint {j.name}: lower limit {j.lower} must be < upper {j.upper}")
            if min(j.torque_limit, j.velocity_limit, j.braking_acceleration, j.acceleration_limit) <= 0:
                raise ValueError(f"joint {j.name}: limits must be positive")
            if j.braking_acceleration > j.acceleration_limit:
                raise ValueError(f"joint {j.name}: braking acceleration exceeds the acceleration limit")

    # vectors over the joints -------------------------------------------------
    @property
    def joint_names(self) -> list[str]:
        return [j.name for j in self.joints]

    @property
    def lower(self) -> np.ndarray:
        """Joint lower position limits [rad]."""
        return np.array([j.lower for j in self.joints])

    @property
    def upper(self) -> np.ndarray:
        """Joint upper position limits [rad]."""
        return np.array([j.upper for j in self.joints])

    @property
    def velocity_limit(self) -> np.ndarray:
        """Joint speed limits [rad/s]."""
        return np.array([j.velocity_limit for j in self.joints])

    @property
    def torque_limit(self) -> np.ndarray:
        """Joint torque limits [N·m]."""
        return np.array([j.torque_limit for j in self.joints])

    @property
    def acceleration_limit(self) -> np.ndarray:
        """Box on commanded joint acceleration [rad/s²]."""
        return np.array([j.acceleration_limit for j in self.joints])

    @property
    def braking_acceleration(self) -> np.ndarray:
        """Guaranteed braking deceleration [rad/s²]."""
        return np.array([j.braking_acceleration for j in self.joints])

    @property
    def armature(self) -> np.ndarray:
        """Reflected rotor inertia per joint [kg·m²]."""
        return np.array([j.armature for j in self.joints])

    def with_joint(self, name: str, **changes: object) -> "SuperLimbParams":
        """Copy with one joint's fields replaced, e.g. ``p.with_joint("elbow", upper=2.0)``."""
        if name not in self.joint_names:
            raise KeyError(f"no joint named {name!r}; joints are {self.joint_names}")
        joints = tuple(replace(j, **changes) if j.name == name else j for j in self.joints)  # type: ignore[arg-type]
        return replace(self, joints=joints)


# --------------------------------------------------------------------------
# geometry helpers
# --------------------------------------------------------------------------


def rpy_to_matrix(rpy: Sequence[float]) -> np.ndarray:
    """URDF roll-pitch-yaw → rotation matrix R = Rz(yaw) · Ry(pitch) · Rx(roll)."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return np.array([
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ])


def rpy_to_quat(rpy: Sequence[float]) -> np.ndarray:
    """URDF roll-pitch-yaw → unit quaternion (w, x, y, z) (MuJoCo's order)."""
    r, p, y = (0.5 * float(a) for a in rpy)
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return np.array([
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    ])

