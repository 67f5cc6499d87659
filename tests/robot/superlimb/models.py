"""The SuperLimb's MuJoCo model and Pinocchio's full mass matrix, shared by the SuperLimb tests."""

from __future__ import annotations

import mujoco
import numpy as np
import pinocchio as pin

from robot.model_files import to_mjcf
from robot.superlimb import SuperLimbParams


def mj(params: SuperLimbParams, extra: str = "") -> tuple[mujoco.MjModel, mujoco.MjData]:
    """The MuJoCo model of ``params`` (with ``extra`` world bodies) and its data."""
    m = mujoco.MjModel.from_xml_string(to_mjcf(params, extra_worldbody_xml=extra))
    return m, mujoco.MjData(m)


def full_m(model, data, q) -> np.ndarray:
    """Pinocchio's joint-space mass matrix at ``q``, both triangles filled."""
    m = pin.crba(model, data, q)
    return np.triu(m) + np.triu(m, 1).T
