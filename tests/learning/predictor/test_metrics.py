"""RMSE per channel group (learning.predictor.metrics): units and other channel names."""

from __future__ import annotations

import numpy as np
import pytest

from learning.predictor.metrics import channel_group, rmse_by_channel, rmse_by_group


def test_rmse_by_group_units_and_other_names():
    names = ["knife_x", "knife_y", "knife_z", "knife_roll", "knife_pitch", "knife_yaw",
             "knife_fx", "knife_fy", "knife_fz", "torque"]
    rng = np.random.default_rng(8)
    y = rng.standard_normal((50, 10))
    p = y + rng.standard_normal((50, 10)) * np.arange(1, 11)
    r = rmse_by_group(y, p, names)
    e2 = (p - y) ** 2
    assert set(r) == {"position_m", "orientation_rad", "force_N", "other"}
    assert r["position_m"] == pytest.approx(np.sqrt(e2[:, :3].mean()))
    assert r["orientation_rad"] == pytest.approx(np.sqrt(e2[:, 3:6].mean()))
    assert r["force_N"] == pytest.approx(np.sqrt(e2[:, 6:9].mean()))
    assert r["other"] == pytest.approx(np.sqrt(e2[:, 9].mean()))
    assert channel_group("knife_fx") == "force_N" and channel_group("ch0") == "other"
    assert rmse_by_group(y[:, :2], p[:, :2], ["a", "b"]) == {"other": pytest.approx(np.sqrt(e2[:, :2].mean()))}
    assert rmse_by_channel(y, p, names)["torque"] == pytest.approx(np.sqrt(e2[:, 9].mean()))
    with pytest.raises(ValueError, match="9 channel names for 10 channels"):
        rmse_by_group(y, p, names[:9])
    with pytest.raises(ValueError, match="same shape"):
        rmse_by_group(y, p[:, :3], names)
