"""What the controller reads of a bundle: the shoulder map of the task the bundle was trained for, the rule's
settings."""

from __future__ import annotations

import sys
from types import SimpleNamespace

import numpy as np
import pytest

from mpcshare.channel_map import bundle_wearer, simulator_gaps
from mpcshare.control.bundle_inputs import shoulder_map
from mpcshare.errors import ControllerSetupError
from sim.task import EATING
from sim.wearer import WearerConfig

#: a task of the user's own whose shoulder elevation moves the tip away from the wearer (eating's lifts it)
_REACHING = '''
import numpy as np

from tests.sim.task.test_protocol import Pouring


class Reaching(Pouring):
    name = "reaching"
    shoulder_to_plate = np.array([[1.0], [0.0], [0.0]])


TASK = Reaching()
'''


@pytest.fixture
def reaching(tmp_path, monkeypatch):
    (tmp_path / "reaching_for_test.py").write_text(_REACHING)
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, "reaching_for_test", raising=False)
    return "reaching_for_test:TASK"


def test_the_shoulder_map_is_the_recorded_tasks(reaching):
    vol = ["shoulder_elevation"]
    assert np.array_equal(shoulder_map(SimpleNamespace(vol_names=vol, config={"task": reaching})).matrix,
                          [[1.0], [0.0], [0.0]])
    eating = shoulder_map(SimpleNamespace(vol_names=vol, config={}))  # a bundle from before tasks were named
    assert np.array_equal(eating.matrix, EATING.shoulder_map(vol).matrix) and eating.matrix[2, 0] == 1.0
    with pytest.raises(ControllerSetupError, match="the bundle's task: task 'gone_x.tasks': cannot import"):
        shoulder_map(SimpleNamespace(vol_names=vol, config={"task": "gone_x.tasks"}))


def test_the_simulated_wearer_and_the_channel_check_use_the_tasks_roles(reaching):
    from sim.task import task_named

    bundle = SimpleNamespace(vol_names=["shoulder_elevation"], config={"task": reaching})
    wearer = bundle_wearer(bundle, WearerConfig())
    assert np.array_equal(wearer.shoulder.matrix, [[1.0], [0.0], [0.0]])  # the controller's map, the same task
    two = ["angle_a", "angle_b"]  # unnamed: taken by position, eating has 3 roles, reaching 1
    assert simulator_gaps(["fork_x", "fork_y", "fork_z"], ["knife_x", "knife_y", "knife_z"], two) == []
    gaps = simulator_gaps(["fork_x", "fork_y", "fork_z"], ["knife_x", "knife_y", "knife_z"], two,
                          task=task_named(reaching))
    assert len(gaps) == 1 and "takes at most 1 by position" in gaps[0]
    assert gaps[0].endswith("--map shoulder_elevation=CHANNEL ... names them")


def test_a_skipped_rule_leaves_the_strategy_its_defaults():
    from mpcshare.bundle.rule import CalibratedRule, skipped_rule
    from mpcshare.control.bundle_inputs import rule_settings

    assert rule_settings(SimpleNamespace(rule=skipped_rule("closed-loop choice was skipped: no knife")), "gate") is None
    ran = SimpleNamespace(rule=CalibratedRule("gate", {"share_on": 0.4}))
    assert rule_settings(ran, "gate") == {"share_on": 0.4} and rule_settings(ran, "gate", {"lead_s": 1.0}) == {
        "lead_s": 1.0}
