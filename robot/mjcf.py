"""Any Pinocchio arm as an MJCF body subtree and its motors: the MuJoCo side of a robot description.

One body per joint, in Pinocchio's joint order (depth first, as MuJoCo numbers its
DOFs): ``pos``/``quat`` = the joint placement in its parent joint's frame (the mount
included for the first joints), one ``hinge`` (revolute) or ``slide`` (prismatic) joint
with its axis, range [rad or m] and armature [kg·m²], and the body's inertia exactly as
Pinocchio holds it (mass [kg], centre of mass in the joint frame [m], inertia about the
centre of mass [kg·m²]; links fixed to a joint are already lumped into its body). Visuals:
a capsule from each body's origin to every child joint and to the tool site (contacts
off); the tool frame is a ``site`` named as the frame. A body without mass gets 1e-6 kg
(MuJoCo refuses massless moving bodies), a difference far below anything measured.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
import pinocchio as pin

from robot.errors import UnsupportedModelError

__all__ = ["joint_axis", "mjcf_actuators", "mjcf_arm_body"]

_AXES = {"X": (1.0, 0.0, 0.0), "Y": (0.0, 1.0, 0.0), "Z": (0.0, 0.0, 1.0)}
_MIN_MASS = 1e-6  # [kg]


def _f(x: float) -> str:
    return repr(float(x))


def _v(xs: Sequence[float]) -> str:
    return " ".join(_f(x) for x in xs)


def joint_axis(joint) -> tuple[str, np.ndarray]:
    """("hinge" or "slide", unit axis (3,) in the joint frame) of a Pinocchio joint model."""
    name = joint.shortname()
    for prefix, kind in (("JointModelR", "hinge"), ("JointModelP", "slide")):
        if name in (prefix + "X", prefix + "Y", prefix + "Z"):
            return kind, np.array(_AXES[name[-1]])
    if name in ("JointModelRevoluteUnaligned", "JointModelPrismaticUnaligned"):
        axis = np.asarray(joint.extract().axis, dtype=float)
        if not np.linalg.norm(axis) > 0:
            raise UnsupportedModelError(f"joint axis must be non-zero, got {axis}")
        return ("hinge" if "Revolute" in name else "slide"), axis / np.linalg.norm(axis)
    raise UnsupportedModelError(f"joint type {name} is not supported; only revolute and prismatic joints "
                                "(RX, RY, RZ, PX, PY, PZ, RevoluteUnaligned, PrismaticUnaligned)")


def _quat(R: np.ndarray) -> np.ndarray:
    """Rotation matrix → unit quaternion (w, x, y, z), MuJoCo's order."""
    c = pin.Quaternion(np.asarray(R)).coeffs()  # (x, y, z, w)
    return np.array([c[3], c[0], c[1], c[2]])


def _inertial(inertia) -> str:
    mass = float(inertia.mass)
    I = np.asarray(inertia.inertia)
    if mass < _MIN_MASS:
        mass, I = _MIN_MASS, np.eye(3) * 1e-9
    full = (I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2])
    return f'<inertial pos="{_v(inertia.lever)}" mass="{_f(mass)}" fullinertia="{_v(full)}"/>'


def _capsule(name: str, end: np.ndarray) -> str:
    return (f'<geom name="{name}" type="capsule" fromto="0 0 0 {_v(end)}" size="0.02" '
            'rgba="0.7 0.7 0.75 1" contype="0" conaffinity="0"/>')


def mjcf_arm_body(model, tip_frame: str, q_min: np.ndarray, q_max: np.ndarray, tau_max: np.ndarray,
                  indent: int = 4) -> str:
    """The arm's bodies (module docstring) for insertion in a ``<worldbody>`` or a body (the mount's parent)."""
    children: dict[int, list[int]] = {i: [] for i in range(model.njoints)}
    for j in range(1, model.njoints):
        children[model.parents[j]].append(j)
    tip = model.frames[model.getFrameId(tip_frame)]
    lines: list[str] = []

    def add(depth: int, text: str) -> None:
        lines.append(" " * (indent + 2 * depth) + text)

    def body(j: int, depth: int) -> None:
        placement, name = model.jointPlacements[j], model.names[j]
        kind, axis = joint_axis(model.joints[j])
        iv = model.joints[j].idx_v
        pose = f'pos="{_v(placement.translation)}" quat="{_v(_quat(placement.rotation))}"'
        add(depth, f'<body name="{name}_body" {pose}>')
        add(depth + 1, f'<joint name="{name}" type="{kind}" axis="{_v(axis)}" range="{_f(q_min[iv])} {_f(q_max[iv])}" '
                       f'limited="true" armature="{_f(model.armature[iv])}" damping="0" frictionloss="0" '
                       f'actuatorfrcrange="{_f(-tau_max[iv])} {_f(tau_max[iv])}" actuatorfrclimited="true"/>')
        add(depth + 1, _inertial(model.inertias[j]))
        ends = [model.jointPlacements[c].translation for c in children[j]]
        if tip.parentJoint == j:
            ends.append(tip.placement.translation)
        for k, end in enumerate(e for e in ends if np.linalg.norm(e) > 1e-6):
            add(depth + 1, _capsule(f"{name}_geom{k}", np.asarray(end)))
        if tip.parentJoint == j:
            add(depth + 1, f'<site name="{tip_frame}" pos="{_v(tip.placement.translation)}" '
                           f'quat="{_v(_quat(tip.placement.rotation))}" size="0.004" rgba="1 0 0 1"/>')
        for c in children[j]:
            body(c, depth + 1)
        add(depth, "</body>")

    for root in children[0]:
        body(root, 0)
    return "\n".join(lines) + "\n"


def mjcf_actuators(model, tau_max: np.ndarray, indent: int = 4) -> str:
    """``<motor>`` elements, one per joint (joint order), control = joint torque [N·m] within ±τ_max."""
    return "".join(
        " " * indent + f'<motor name="{model.names[j]}_motor" joint="{model.names[j]}" gear="1" ctrllimited="true" '
        f'ctrlrange="{_f(-tau_max[model.joints[j].idx_v])} {_f(tau_max[model.joints[j].idx_v])}"/>\n'
        for j in range(1, model.njoints))
