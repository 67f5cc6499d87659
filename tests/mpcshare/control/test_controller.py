"""SharedController: a closed run on a recorded trial, every fault path, construction misuse."""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace

import numpy as np
import pytest

from mpcshare.control.controller import STATUSES, SharedController
from mpcshare.control.strategies import user_strategies
from robot.superlimb import SuperLimbParams
from tests.mpcshare.control.controller_doubles import MOUNT, demos_and_bundle, real_model_bundle

P = SuperLimbParams()
Q0 = 0.5 * (P.lower + P.upper)


def _controller(strategy="gate", beta=0.5, seed=0, **kw):
    demos, bundle = demos_and_bundle(seed)
    return demos, SharedController.from_bundle(bundle, strategy=strategy, beta=beta, use_mpc=False,
                                               **{"base_pose": MOUNT, **kw})


def _run(ctl, trial, n, q=Q0, v=None, modify=None):
    """Step the controller over the first n samples, integrating the arm from the commands."""
    q, v = np.array(q, dtype=float), np.zeros(3) if v is None else np.array(v, dtype=float)
    cmds = []
    for k in range(n):
        args = [trial.t[k], trial.obs[k], trial.voluntary[k], q, v, None]
        if modify is not None:
            args = modify(k, args)
        c = ctl.step(*args)
        cmds.append(c)
        q, v = c.q_cmd, c.v_cmd
    return cmds


def _safe(c, q_prev=None):
    for x in (c.tau, c.q_cmd, c.v_cmd, c.a_cmd):
        assert x.shape == (3,) and np.all(np.isfinite(x))
    assert np.all(c.q_cmd >= P.lower - 1e-9) and np.all(c.q_cmd <= P.upper + 1e-9)
    assert np.all(np.abs(c.v_cmd) <= P.velocity_limit + 1e-9)
    assert np.all(np.abs(c.tau) <= P.torque_limit + 1e-6)
    assert c.status in STATUSES


@pytest.mark.parametrize("strategy,seconds", [("gate", 30), ("blend", 10), ("voluntary", 10), ("reactive", 10)])
def test_run_on_a_recorded_trial(strategy, seconds):
    demos, ctl = _controller(strategy, seed=0)
    trial = demos.trials[-1]
    assert trial.duration_s >= 29.9
    cmds = _run(ctl, trial, 100 * seconds)  # the arm integrated from the commands
    for c in cmds:
        _safe(c)
        assert np.all(np.isfinite(c.tip_reference))
    assert [c.status for c in cmds if c.status != "ok"] == []
    alpha = np.array([c.alpha for c in cmds])
    if strategy == "gate":
        # α ramps between 0 and 1 over ControllerConfig.handover_s, at most one step's share per step
        assert alpha.min() == 0.0 and alpha.max() == 1.0 and 0 < len(ctl.handovers) < 60
        assert np.abs(np.diff(alpha)).max() <= 0.01 / ctl.config.handover_s + 1e-9
        assert np.all(np.diff([h.t for h in ctl.handovers]) > 0)
        assert np.all(np.array([c.beta for c in cmds])[alpha == 1.0] == 0.5)
    if strategy == "reactive":
        # the tip follows π̂: the reference ends near the last prediction
        assert np.linalg.norm(cmds[-1].tip_reference - cmds[-1].predicted_tip) < 0.03
    assert {"frontend", "models", "arbitration", "smoothing", "qp", "total"} <= set(cmds[-1].timings)
    assert cmds[-1].mode_proba.shape == (3,) and np.isclose(cmds[-1].mode_proba.sum(), 1.0)


class _AlternatingGate:
    """Gate probability 0.45, 0.55, 0.45, … on successive calls (a gate undecided around 0.5)."""

    def __init__(self):
        self.n = 0

    def proba_one(self, window, mode):
        self.n += 1
        return 0.45 if self.n % 2 else 0.55


def test_undecided_gate_does_not_toggle_alpha_in_the_loop():
    demos, bundle = demos_and_bundle(0)
    gate = _AlternatingGate()
    undecided = SimpleNamespace(**{**vars(bundle), "gates": gate})
    ctl = SharedController.from_bundle(undecided, strategy="gate", use_mpc=False, base_pose=MOUNT)
    cmds = _run(ctl, demos.trials[0], 500)
    assert gate.n > 40 and ctl.handovers == [] and {c.alpha for c in cmds} == {0.0}


def test_torso_sway_moves_the_arm_not_the_plate_frame_reference():
    """A swaying base pose: the reference stays put in the plate frame, the arm compensates."""
    import pinocchio as pin

    demos, ctl = _controller("voluntary")
    trial = demos.trials[0]
    pose = MOUNT.copy()

    def sway(k, a):
        T = pose.copy()
        T[:3, 3] += 0.02 * np.sin(2 * np.pi * 0.5 * trial.t[k]) * np.array([1.0, 0.5, 0.3])
        return [*a[:2], np.zeros(3), *a[3:5], T]

    cmds = _run(ctl, trial, 400, modify=sway)
    refs = np.array([c.tip_reference for c in cmds])
    assert np.abs(refs - refs[0]).max() < 1e-12
    model, data = ctl.qp.model, ctl.qp.model.createData()
    fid = model.getFrameId("knife_tip")
    errs = []
    for k in range(200, 400):
        pin.framesForwardKinematics(model, data, cmds[k].q_cmd)
        T = sway(k, [None] * 6)[5]
        errs.append(np.linalg.norm(T[:3, :3] @ data.oMf[fid].translation + T[:3, 3] - refs[0]))
    assert max(errs) < 0.01  # the tip stays within 1 cm of the plate-frame reference under 2 cm sway


def test_missing_and_stale_fork_sensor():
    demos, ctl = _controller("reactive")
    trial = demos.trials[0]

    def drop(k, args):
        if 300 <= k < 380:  # one NaN channel for 0.8 s, the first 0.5 s bridged by the KF
            o = args[1].copy()
            o[:] = np.nan
            args[1] = o
        if 500 <= k < 520:
            args[1] = None
        return args

    cmds = _run(ctl, trial, 600, modify=drop)
    for c in cmds:
        _safe(c)
    st = [c.status for c in cmds]
    assert st[299] == "ok" and st[300] == "missing_observation" and st[349] == "missing_observation"
    assert set(st[351:380]) == {"stale_fork_sensor"}
    assert all((c.alpha, c.beta) == (0.0, 1.0) for c in cmds[351:380])
    assert any("Kalman" in r for r in cmds[300].reasons)
    assert st[385] == "ok" and st[505] == "missing_observation"


def test_nan_shoulder_holds_reference():
    demos, ctl = _controller("voluntary")
    trial = demos.trials[0]
    cmds = _run(ctl, trial, 100, modify=lambda k, a: a if k < 50 else [*a[:2], np.full(3, np.nan), *a[3:]])
    assert cmds[49].status == "ok" and all(c.status == "invalid_shoulder" for c in cmds[50:])
    for c in cmds:
        _safe(c)
        np.testing.assert_array_equal(cmds[60].tip_reference, cmds[49].tip_reference)


def test_time_backwards_wrong_shape_and_nan_joint_state():
    demos, ctl = _controller()
    trial = demos.trials[0]
    cmds = _run(ctl, trial, 50)
    q, v = cmds[-1].q_cmd, cmds[-1].v_cmd
    c = ctl.step(trial.t[48], trial.obs[49], trial.voluntary[49], q, v)
    assert c.status == "time_went_backwards" and "holding" in c.reasons[0]
    _safe(c)
    c = ctl.step(trial.t[50], trial.obs[50][:5], trial.voluntary[50], q, v)
    assert c.status == "invalid_observation_shape"
    _safe(c)
    c2 = ctl.step(trial.t[51], trial.obs[51], trial.voluntary[51], np.array([np.nan, 0, 0]), v)
    assert c2.status == "invalid_joint_state"
    np.testing.assert_array_equal(c2.q_cmd, c.q_cmd)  # holds the last valid command
    c3 = ctl.step(trial.t[52], trial.obs[52], trial.voluntary[52], q[:2], v)
    assert c3.status == "invalid_joint_state"
    c4 = ctl.step(trial.t[53], trial.obs[53], trial.voluntary[53], q, v, base_pose=np.full((4, 4), np.nan))
    assert c4.status == "invalid_base_pose"
    _safe(c4)


def test_no_observation_yet_holds():
    _, ctl = _controller()
    c = ctl.step(0.0, np.full(9, np.nan), np.zeros(3), Q0, np.zeros(3))
    assert c.status == "no_observation"
    _safe(c)
    np.testing.assert_allclose(c.q_cmd, Q0, atol=1e-6)


def test_unreachable_reference_is_clamped():
    demos, ctl = _controller("voluntary")
    trial = demos.trials[0]
    def push(k, a):  # protraction: +x, 0.25 m/s
        return [*a[:2], np.array([0.0, 0.5, 0.0]), *a[3:]]

    cmds = _run(ctl, trial, 300, modify=push)
    assert cmds[-1].status == "reference_unreachable"
    assert cmds[-1].tip_reference[0] == pytest.approx(0.30)  # the workspace box
    far = np.eye(4)
    far[:3, 3] = (-1.5, 0.0, 0.0)  # torso 1.5 m behind the plate: the plate is out of reach
    _, ctl2 = _controller("voluntary")
    c = _run(ctl2, trial, 20, modify=lambda k, a: [*a[:5], far])[-1]
    assert c.status == "reference_unreachable" and any("reach" in r for r in c.reasons)
    _safe(c)


class _FakeMPC:
    """MPC double: plans the tip at the reference (ok) or fails / runs late."""

    horizon = 5

    def __init__(self, mode):
        self.mode, self.calls = mode, 0

    def reset(self):
        pass

    def solve(self, q, v, p_ref, deadline_s=None):
        self.calls += 1
        if self.mode == "raise":
            raise RuntimeError("boom")
        ok = self.mode in ("ok", "late")
        return SimpleNamespace(a=np.zeros(3), q_plan=None, v_plan=None, tip_plan=np.array(p_ref), ok=ok,
                               status="solved" if ok else "infeasible",
                               solve_time=0.1 if self.mode == "late" else 1e-4, iterations=1)


@pytest.mark.parametrize("mode,status", [("ok", "ok"), ("fail", "mpc_failed"), ("late", "mpc_timeout"),
                                         ("raise", "mpc_failed")])
def test_mpc_paths(mode, status):
    demos, bundle = demos_and_bundle(0)
    from mpcshare.control.controller import ControllerConfig

    mpc = _FakeMPC(mode)
    ctl = SharedController.from_bundle(bundle, strategy="gate", mpc=mpc, config=ControllerConfig(mpc_every=1),
                                       base_pose=MOUNT)
    cmds = _run(ctl, demos.trials[0], 60)
    assert mpc.calls == 60 and cmds[-1].status == status and "mpc" in cmds[-1].timings
    for c in cmds:
        _safe(c)


def test_mpc_at_its_own_rate():
    from mpcshare.control.controller import ControllerConfig

    demos, bundle = demos_and_bundle(0)
    mpc = _FakeMPC("ok")
    ctl = SharedController.from_bundle(bundle, mpc=mpc, config=ControllerConfig(mpc_every=3), base_pose=MOUNT)
    cmds = _run(ctl, demos.trials[0], 60)
    assert mpc.calls == 20 and all(c.status == "ok" for c in cmds)


def test_with_the_real_mpc():
    """TipMPC in the loop (a generous deadline: no timing dependence); the QP gets its plan."""
    from mpcshare.control.controller import ControllerConfig

    demos, bundle = demos_and_bundle(0)
    ctl = SharedController.from_bundle(bundle, use_mpc=True, config=ControllerConfig(mpc_deadline_s=1.0),
                                       base_pose=MOUNT)
    cmds = _run(ctl, demos.trials[0], 300)
    for c in cmds:
        _safe(c)
    assert all(c.status == "ok" for c in cmds) and "mpc" in cmds[-1].timings


def test_qp_failure_brakes_within_limits():
    demos, ctl = _controller()
    trial = demos.trials[0]
    cmds = _run(ctl, trial, 30)
    def fail(*a, **k):
        return SimpleNamespace(x=None, status="forced failure", infeasible=False, iterations=0)

    ctl.qp._primary.solve = fail
    ctl.qp._relaxed.solve = fail
    c = ctl.step(trial.t[30], trial.obs[30], trial.voluntary[30], cmds[-1].q_cmd, np.array([1.0, -1.0, 1.0]))
    assert c.status == "qp_failed"
    _safe(c)
    assert np.all(np.abs(c.v_cmd) < 1.0)  # braking


def test_learned_part_failure_is_reported_not_raised():
    demos, bundle = demos_and_bundle(0)
    ctl = SharedController.from_bundle(bundle, use_mpc=False, base_pose=MOUNT)

    def broken(x):
        raise FloatingPointError("bad weights")

    ctl.state.stream.step = broken
    cmds = _run(ctl, demos.trials[0], 120)
    assert cmds[0].status == "internal_error" and "bad weights" in cmds[0].reasons[0]
    assert all(c.alpha == 0.0 for c in cmds)  # π̂ not finite → α = 0
    for c in cmds:
        _safe(c)


def test_from_a_saved_bundle_folder(tmp_path):
    """The real learned parts (gates, LSTM stream) through save_bundle / load_bundle."""
    from mpcshare.bundle import save_bundle

    demos, bundle = real_model_bundle(0)
    save_bundle(bundle, tmp_path / "bundle")
    ctl = SharedController.from_bundle(str(tmp_path / "bundle"), strategy="gate", use_mpc=False, base_pose=MOUNT)
    cmds = _run(ctl, demos.trials[1], 400)
    for c in cmds:
        _safe(c)
    assert all(c.status == "ok" for c in cmds)
    assert np.all(np.isfinite(cmds[-1].predicted_tip)) and np.all(np.isfinite(cmds[-1].tip_reference))
    with pytest.raises(ValueError, match="tip_channels"):
        SharedController.from_bundle(str(tmp_path / "bundle"), use_mpc=False, tip_channels=("a", "b", "c"))


def test_construction_misuse():
    _, bundle = demos_and_bundle(0)
    with pytest.raises(ValueError, match="valid choices: " + ", ".join(user_strategies())):
        SharedController.from_bundle(bundle, strategy="nope", use_mpc=False)
    with pytest.raises(ValueError, match="beta must be in"):
        SharedController.from_bundle(bundle, beta=1.2, use_mpc=False)
    renamed = SimpleNamespace(**{**vars(bundle), "act_names": tuple(n.replace("knife", "blade")
                                                                        for n in bundle.act_names)})
    with pytest.raises(ValueError, match=r"no channel\(s\) \['knife_x'.*tip_channels"):
        SharedController.from_bundle(renamed, use_mpc=False)
    ctl = SharedController.from_bundle(renamed, use_mpc=False, tip_channels=("blade_x", "blade_y", "blade_z"))
    assert ctl.layout.tip_index.tolist() == [0, 1, 2]
    no_fork = SimpleNamespace(**{**vars(bundle), "obs_names": tuple(f"o{j}" for j in range(9))})
    with pytest.raises(ValueError, match="fork_channels"):
        SharedController.from_bundle(no_fork, use_mpc=False)
    short = SimpleNamespace(**{**vars(bundle), "obs_names": bundle.obs_names[:8]})
    with pytest.raises(ValueError, match="preprocessor.obs was fitted on 9 channels"):
        SharedController.from_bundle(short, use_mpc=False)
    with pytest.raises(ValueError, match="lacks field"):
        SharedController.from_bundle(SimpleNamespace(obs_names=()), use_mpc=False)
    with pytest.raises(TypeError, match="robot must be"):
        SharedController.from_bundle(bundle, robot="ur5", use_mpc=False)
    assert dataclasses.is_dataclass(SharedController.from_bundle(bundle, use_mpc=False).config)


def test_without_a_mount_the_controller_holds_until_a_step_gives_one():
    demos, ctl = _controller("voluntary", base_pose=None)
    trial = demos.trials[0]
    first = ctl.step(trial.t[0], trial.obs[0], trial.voluntary[0], Q0, np.zeros(3))
    _safe(first)
    assert first.status == "invalid_base_pose" and "no base pose yet" in first.reasons[0]
    assert np.allclose(first.v_cmd, 0.0, atol=0.02)  # held (from rest)
    given = ctl.step(trial.t[1], trial.obs[1], trial.voluntary[1], first.q_cmd, first.v_cmd, MOUNT)
    assert given.status == "ok"
    kept = ctl.step(trial.t[2], trial.obs[2], trial.voluntary[2], given.q_cmd, given.v_cmd)  # the last one kept
    assert kept.status == "ok"
    _, bundle = demos_and_bundle(0)
    with pytest.raises(ValueError, match="base_pose has non-finite entries"):
        SharedController.from_bundle(bundle, base_pose=np.full((4, 4), np.nan))


@pytest.mark.parametrize("share", [0.0, 0.9])
def test_the_default_gate_reads_the_modes_and_the_bundles_per_mode_figures(share):
    """Every mode of the bundle's held-out figures unpredictable: the wearer keeps the lead; none: the robot
    leads once the window is full. The decision needs the mode probabilities the controller passes."""
    demos, b = demos_and_bundle(0)
    per_mode = {str(j): {"n": 100, "n_positive": round(100 * (1 - share))} for j in range(3)}
    bundle = SimpleNamespace(**vars(b), metrics={"gate": {"per_mode": per_mode}})
    ctl = SharedController.from_bundle(bundle, strategy="gate", use_mpc=False, base_pose=MOUNT)
    cmds = _run(ctl, demos.trials[0], 300)
    for c in cmds:
        _safe(c)
    alphas = np.array([c.alpha for c in cmds])
    if share:
        assert np.all(alphas == 0.0) and ctl.handovers == []
    else:
        assert alphas[-1] == 1.0 and len(ctl.handovers) == 1 and "robot leads" in ctl.handovers[0].reason


def test_the_strategy_runs_with_the_bundles_rule_unless_the_config_names_its_settings():
    from mpcshare.bundle import CalibratedRule
    from mpcshare.control.strategies.gate import GateSettings
    from mpcshare.control.types import ControllerConfig
    from mpcshare.errors import ControllerSetupError

    _, plain = demos_and_bundle(0)
    bundle = SimpleNamespace(**{**vars(plain), "rule": CalibratedRule("gate", {"wearer_modes": [1], "lead_s": 1.0})})
    ctl = SharedController.from_bundle(bundle, strategy="gate")
    assert ctl.arbiter.settings == GateSettings(wearer_modes=(1,), lead_s=1.0)
    mine = ControllerConfig(strategy_settings={"share_on": 0.5, "share_off": 0.4})
    assert SharedController(bundle, config=mine).arbiter.settings == GateSettings(share_on=0.5, share_off=0.4)
    assert SharedController(bundle, strategy="paper_gate").arbiter.settings.on_threshold == 0.6  # not its rule
    with pytest.raises(ControllerSetupError, match="strategy 'gate': unknown gate setting.*'lead'"):
        SharedController(bundle, config=ControllerConfig(strategy_settings={"lead": 1.0}))
