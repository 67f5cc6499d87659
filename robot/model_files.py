"""Old import path of :mod:`robot.superlimb.model_files` (the SuperLimb's URDF, MJCF and Pinocchio model)."""

from robot.superlimb.model_files import (
    PinocchioModel,
    build_pinocchio_model,
    mjcf_actuators,
    mjcf_arm_body,
    to_mjcf,
    to_urdf,
    write_assets,
)

__all__ = ["PinocchioModel", "build_pinocchio_model", "mjcf_actuators", "mjcf_arm_body", "to_mjcf", "to_urdf",
           "write_assets"]
