"""The efforts `mpcshare run` sends (mpcshare/runtime/effort_command.py), on the SuperLimb's model."""

from __future__ import annotations

import numpy as np
import pytest

from mpcshare.runtime.effort_command import EffortCommand
from robot.default_arm import as_description


def test_the_driver_s_gravity_is_taken_out_of_every_effort_the_stop_s_included():
    robot = as_description(None)
    plain, comp = (EffortCommand(robot, 0.01, 3, compensated=c) for c in (False, True))
    q, tau = np.array([0.1, 0.4, -0.3]), np.array([1.0, 2.0, 3.0])
    g = plain.holding.gravity(q)
    assert np.array_equal(plain.command(tau, q, None), tau)
    np.testing.assert_allclose(comp.command(tau, np.full(3, np.nan), q), tau - g)  # at the last measured q
    assert np.isnan(comp.command(tau, np.full(3, np.nan), None)).all()  # no q at all: NaN, the loop stops
    np.testing.assert_allclose(plain.stop(q, np.zeros(3), q), g, atol=1e-12)
    np.testing.assert_allclose(comp.stop(q, np.zeros(3), q), 0.0, atol=1e-12)
    moving = np.array([0.3, -0.2, 0.1])
    np.testing.assert_allclose(comp.stop(q, moving, q), plain.stop(q, moving, q) - g, atol=1e-12)
    values: dict[str, object] = {}
    assert plain.stop(q, None, q) is not None and "gravity alone" in plain.note(values)
    assert values == {"stop_torque": "gravity"}


def test_without_a_model_the_stop_is_zeros_and_compensation_is_refused():
    bare = EffortCommand(None, 0.01, 3)
    assert np.array_equal(bare.stop(np.zeros(3), np.zeros(3), None), np.zeros(3)) and bare.source == "zero"
    with pytest.raises(ValueError, match=r"cfg.toml, \[outputs.command\] driver_compensates_gravity: needs"):
        EffortCommand(None, 0.01, 3, compensated=True, where="cfg.toml, [outputs.command]")
