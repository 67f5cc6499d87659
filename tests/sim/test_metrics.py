"""Episode metrics on episodes written for the test (known answers)."""

import numpy as np
import pytest

from sim.episode import Episode
from sim.metrics import conflict_mask, episode_metrics
from sim.task import EATING


def _episode(n=100, **over):
    t = np.arange(n) * 0.01
    base = {
        "t_physics": np.zeros(0), "q": np.zeros((0, 3)), "v": np.zeros((0, 3)), "tau": np.zeros((0, 3)),
        "t": t, "alpha": np.zeros(n), "beta": np.ones(n), "mode": np.zeros(n, int),
        "tip": np.zeros((n, 3)), "tip_reference": np.zeros((n, 3)), "tip_intent": np.zeros((n, 3)),
        "voluntary": np.zeros((n, 3)), "status": np.array(["ok"] * n), "step_time": np.full(n, 0.001),
        "base_pose": np.tile(np.eye(4), (n, 1, 1)), "novelty": np.full(n, np.nan),
        "info": {"wall_time_s": 0.1, "duration_s": n * 0.01, "control_period_s": 0.01, "limit_violations": 0,
                 "shoulder_gain": 0.5, "shoulder_deadband_rad": 0.01},
    }
    base.update(over)
    return Episode(**base)


def test_tracking_effort_shares_and_timing():
    n = 100
    err = np.zeros((n, 3))
    err[:, 0] = np.linspace(0, 0.02, n)
    vol = np.zeros((n, 3))
    vol[:, 1] = 0.03
    vol[:, 2] = 0.04  # ‖θ‖ = 0.05 rad
    alpha = np.where((np.arange(n) // 25) % 2 == 1, 1.0, 0.0)  # 0,1,0,1 blocks: 3 crossings
    m = episode_metrics(_episode(tip=err, voluntary=vol, alpha=alpha, beta=np.zeros(n),
                                 step_time=np.linspace(0.001, 0.002, n)))
    e = np.linspace(0, 0.02, n)
    assert m["tracking_rmse_m"] == pytest.approx(np.sqrt(np.mean(e**2)))
    assert m["tracking_p95_m"] == pytest.approx(np.percentile(e, 95))
    assert m["voluntary_effort"] == pytest.approx(0.05)
    assert m["reactive_share"] == 0.5 and m["handovers"] == 3
    assert m["step_p50_ms"] == pytest.approx(1.5) and m["step_p99_ms"] == pytest.approx(1.99)
    assert m["realtime_factor"] == pytest.approx(10.0)
    assert m["limit_violations"] == 0 and m["conflict_share"] == 0.0


def test_conflict_when_wearer_and_robot_push_opposite_ways():
    n = 50
    shoulder = EATING.shoulder_map()
    u_v = np.array([-0.05, 0.0, 0.0])  # the wearer pulls the tip toward −x at 5 cm/s
    theta = np.tile(shoulder.angles_for(u_v), (n, 1))
    beta = np.full(n, 0.5)
    # the reference moves at ṙ = β·û_v + û_r with the robot's own û_r = +0.1 m/s along x
    r_dot = 0.5 * u_v + np.array([0.1, 0.0, 0.0])
    ref = np.cumsum(np.tile(r_dot * 0.01, (n, 1)), axis=0)
    ep = _episode(n, voluntary=theta, beta=beta, tip_reference=ref, alpha=np.ones(n))
    mask = conflict_mask(ep)
    assert not mask[0] and mask[1:].all()
    assert episode_metrics(ep)["conflict_share"] == pytest.approx((n - 1) / n)
    # the robot going the same way as the wearer: no conflict
    ref_same = np.cumsum(np.tile((0.5 * u_v + np.array([-0.1, 0, 0])) * 0.01, (n, 1)), axis=0)
    assert not conflict_mask(_episode(n, voluntary=theta, beta=beta, tip_reference=ref_same)).any()
    # below the speed deadband: no conflict
    slow = np.cumsum(np.tile((0.5 * u_v + np.array([0.005, 0, 0])) * 0.01, (n, 1)), axis=0)
    assert not conflict_mask(_episode(n, voluntary=theta, beta=beta, tip_reference=slow)).any()


def test_missing_values_give_none_not_errors():
    n = 10
    m = episode_metrics(_episode(n, alpha=np.full(n, np.nan), tip=np.full((n, 3), np.nan),
                                 tip_reference=np.full((n, 3), np.nan)))
    assert m["tracking_rmse_m"] is None and m["reactive_share"] is None and m["handovers"] == 0
    assert m["conflict_share"] == 0.0
