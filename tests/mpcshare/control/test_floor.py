"""The knife stays above the plate: a command below the table never takes the tip through it.

Issue 30's follow-up: under ``sweep`` the reactive run drove the tip ~8 cm below the plate top
while its reference sat on the workspace box's floor. These tests reproduce that in the
controller alone (arm integrated from its commands) and check the fix: the reference stays in
the box and the reach at once, the smoother is not aimed through the floor, and the QP holds
the tip above the plate (:class:`robot.floor.FloorLimit`).
"""

from __future__ import annotations

import numpy as np

from mpcshare.control.controller import SharedController
from robot.superlimb import SuperLimbParams
from sim.task import EATING
from tests.mpcshare.control.controller_doubles import MOUNT, demos_and_bundle

P = SuperLimbParams()
Q0 = 0.5 * (P.lower + P.upper)
DOWN = EATING.shoulder_map().angles_for(np.array([0.0, 0.0, -0.5]))  # the wearer commands 0.5 m/s down


def _lowest_tip(ctl: SharedController, n: int = 300) -> tuple[float, list]:
    """Lowest tip z [m] (plate frame, default base pose) over n steps of a downward shoulder command."""
    demos, _ = demos_and_bundle(0)
    trial = demos.trials[0]
    q, v = Q0.copy(), np.zeros(3)
    low, cmds = np.inf, []
    for k in range(n):
        c = ctl.step(trial.t[k], trial.obs[k], DOWN, q, v)
        q, v = c.q_cmd, c.v_cmd
        low = min(low, float(ctl._to_plate(ctl.tip.position(q))[2]))
        cmds.append(c)
    return low, cmds


def test_a_command_below_the_table_stops_the_tip_at_the_plate():
    _, bundle = demos_and_bundle(0)
    ctl = SharedController.from_bundle(bundle, strategy="voluntary", base_pose=MOUNT)
    low, cmds = _lowest_tip(ctl)
    floor = ctl.config.floor_z
    assert floor is not None and -0.01 <= floor <= 0.0
    assert low >= floor - 1e-3, f"tip {low * 1e3:.1f} mm, floor {floor * 1e3:.1f} mm"
    assert low <= floor + 0.01  # it did go down to the plate
    assert cmds[-1].tip_reference[2] >= floor - 1e-9
    assert cmds[-1].status == "reference_unreachable"
