"""The controller keeps the knife out of the wearer: commands into the hand, the hand onto the knife,
a lost marker, and the fault table that says whose doing an intrusion is."""

from __future__ import annotations

import numpy as np
import pytest

from mpcshare.control.controller import SharedController
from mpcshare.control.keepout import KeepOutSettings
from mpcshare.control.types import ControllerConfig
from robot.keepout import segment_zone_clearance
from robot.superlimb import SuperLimbParams
from robot.wearer_body import body_zones, hand_center
from sim.task import EATING
from tests.mpcshare.control.controller_doubles import MOUNT, demos_and_bundle

P = SuperLimbParams()
Q0 = 0.5 * (P.lower + P.upper)
FORK = slice(0, 6)  # fork_x … fork_yaw are the first obs channels of the generator


def _controller(config=None):
    demos, bundle = demos_and_bundle(0)
    ctl = SharedController.from_bundle(bundle, strategy="voluntary", beta=1.0, use_mpc=False, config=config,
                                       base_pose=MOUNT)
    return demos.trials[0], ctl


def _blade(ctl, q):
    tip, heel = ctl.keepout.limit.knife(q)
    return tip.p, heel.p


def _hand_clearance(ctl, q, fork_pose):
    """Clearance [m] of the blade to the true hand (model frame; base pose at rest)."""
    zone = body_zones(EATING.body, fork_pose, ctl.state.pose, parts=("hand",))[0]
    tip, heel = _blade(ctl, q)
    return segment_zone_clearance(tip, heel, zone).distance


def _run(ctl, trial, n, fork, theta):
    q, v = Q0.copy(), np.zeros(3)
    out = []
    for k in range(n):
        obs = trial.obs[k].copy()
        obs[FORK] = fork(k)
        c = ctl.step(trial.t[k], obs, theta(k, q), q, v, None)
        q, v = c.q_cmd, c.v_cmd
        out.append((c, q.copy(), _hand_clearance(ctl, q, fork(k))))
    return out


def _fork_near_knife(ctl, trial, offset):
    """A fork pose whose hand sits ``offset`` (plate frame) from the knife's tip at the start pose."""
    tip_plate = ctl._to_plate(ctl.tip.position(Q0))
    pose = trial.obs[0, FORK].copy()
    pose[:3] += tip_plate + offset - hand_center(EATING.body, pose)
    return pose


def test_a_command_into_the_hand_stops_at_the_margin():
    trial, ctl = _controller()
    fork = _fork_near_knife(ctl, trial, np.array([0.0, 0.12, 0.0]))
    shoulder = EATING.shoulder_map()
    push = shoulder.angles_for(np.array([0.0, 0.15, 0.0]))  # 0.15 m/s straight at the hand
    out = _run(ctl, trial, 150, lambda k: fork, lambda k, q: push)
    d = np.array([o[2] for o in out])
    print(f"least clearance to the hand {d.min() * 1e3:.1f} mm (margin 20 mm)")
    assert d.min() >= 0.02 - 2e-3
    assert not any(s.startswith("keepout_robot") for o in out for s in o[0].reasons)


def test_the_hand_moving_onto_a_still_knife_is_the_person_s_doing_and_the_knife_yields():
    trial, ctl = _controller()
    start = _fork_near_knife(ctl, trial, np.array([0.0, 0.15, 0.0]))

    def fork(k):  # the hand sweeps at 0.4 m/s toward the knife for 0.5 s, then stays
        pose = start.copy()
        pose[1] -= 0.004 * min(k, 50)
        return pose

    out = _run(ctl, trial, 120, fork, lambda k, q: np.zeros(3))
    d = np.array([o[2] for o in out])
    reasons = [s for o in out for s in o[0].reasons]
    print(f"least clearance to a sweeping hand {d.min() * 1e3:.1f} mm")
    assert d.min() > 0.0  # the knife got out of the way: never inside the hand
    assert not any(s.startswith("keepout_robot") for s in reasons)


def test_a_lost_marker_grows_the_zone_and_is_reported():
    trial, ctl = _controller()
    fork = _fork_near_knife(ctl, trial, np.array([0.0, 0.15, 0.0]))
    q, v = Q0.copy(), np.zeros(3)
    statuses = []
    for k in range(60):
        obs = trial.obs[k].copy()
        obs[FORK] = fork if k < 20 else np.nan
        c = ctl.step(trial.t[k], obs, np.zeros(3), q, v, None)
        q, v = c.q_cmd, c.v_cmd
        statuses += [s.split(":")[0] for s in c.reasons]
        assert np.all(np.isfinite(c.q_cmd))
    assert "keepout_stale_zone" in statuses
    hand = next(z for z in ctl.keepout.limit.zones if z.name == "hand")
    assert hand.uncertainty == pytest.approx(EATING.body.hand_top_speed * ctl.keepout.age_s)


def test_keepout_off_is_today_s_controller():
    trial, ctl = _controller(ControllerConfig(keepout=None, floor_z=None))
    assert ctl.keepout is None and len(ctl.qp.constraints) == 1
    _, floored = _controller(ControllerConfig(keepout=None))  # the knife's floor stays without the keep-out
    assert floored.keepout is None and [c.name for c in floored.qp.constraints] == ["torque", "floor"]
    c = ctl.step(0.0, trial.obs[0], np.zeros(3), Q0, np.zeros(3))
    assert c.status in ("ok", "missing_observation")


def test_settings_name_the_valid_parts():
    with pytest.raises(ValueError, match="valid choices"):
        KeepOutSettings(parts=("hand", "knee"))
