"""The one builder: the QP made once with its whole constraint list, the parts reached by name."""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace

import pytest

import mpcshare.control.builder as builder
from mpcshare.control.builder import ControllerParts, build_qp
from mpcshare.control.controller import SharedController
from mpcshare.control.keepout import KeepOutSettings
from mpcshare.control.types import ControllerConfig
from robot.default_arm import as_description
from sim.task import EATING
from tests.mpcshare.control.controller_doubles import demos_and_bundle


def test_the_qp_is_built_once_with_its_whole_constraint_list(monkeypatch):
    made = []
    real = builder.QPController

    def counting(*args, **kw):
        made.append(kw.get("constraints"))
        return real(*args, **kw)

    monkeypatch.setattr(builder, "QPController", counting)
    _, bundle = demos_and_bundle(0)
    ctl = SharedController(bundle)
    assert len(made) == 1 and [type(c).__name__ for c in made[0]] == ["TorqueLimit", "FloorLimit", "KeepOutLimit"]
    assert ctl.qp is ctl.parts.qp and ctl.keepout.limit is made[0][2] and ctl.floor is made[0][1]
    made.clear()
    plain = SharedController(bundle, config=ControllerConfig(keepout=None, floor_z=None))
    assert len(made) == 1 and made[0] is None and plain.keepout is None and plain.floor is None


def test_the_qp_runs_at_the_bundles_period_from_the_arms_home_posture():
    robot = as_description(None)
    qp, keepout, floor = build_qp(robot, ControllerConfig(floor_z=None, keepout=KeepOutSettings(body=EATING.body)),
                                  0.02)
    assert qp.dt == 0.02 and (qp.config.q_posture == robot.q_home).all() and floor is None and keepout is not None
    with pytest.raises(ValueError, match="KeepOut needs KeepOutSettings.body"):  # no body: no keep-out
        build_qp(robot, ControllerConfig(floor_z=None), 0.02)


def test_the_keepout_holds_the_body_zones_of_the_bundles_task(monkeypatch):
    import tests.sim.task.test_protocol as protocol

    monkeypatch.setattr(protocol, "POURING", protocol.Pouring(), raising=False)  # a task of the user's own
    _, bundle = demos_and_bundle(0)
    assert SharedController(bundle).keepout.settings.body == EATING.body  # none recorded: the default task's
    other = dataclasses.replace(EATING.body, head_speed_cap=0.03)  # Pouring's
    pouring = SimpleNamespace(**{**vars(bundle), "config": {"task": "tests.sim.task.test_protocol:POURING"}})
    assert SharedController(pouring).keepout.settings.body == other
    given = SharedController(bundle, config=ControllerConfig(keepout=KeepOutSettings(body=other)))
    assert given.keepout.settings.body == other  # a given body stands


def test_the_parts_are_the_controllers_by_name_and_built_once():
    _, bundle = demos_and_bundle(0)
    ctl = SharedController(bundle, strategy="paper_gate", beta=0.3)
    for f in dataclasses.fields(ControllerParts):
        assert getattr(ctl, f.name) is getattr(ctl.parts, f.name), f.name
    assert (ctl.strategy, ctl.beta_user, ctl.dt) == ("paper_gate", 0.3, 0.01)
    with pytest.raises(dataclasses.FrozenInstanceError):
        ctl.parts.qp = None
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        _ = ctl.nothing
