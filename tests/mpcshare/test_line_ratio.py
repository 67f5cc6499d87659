"""The line ratio: RMS over the voluntary–reactive line at the same effort."""

from __future__ import annotations

import pytest

from mpcshare.line_ratio import add_line_ratios, line_ratio, line_rms

VOL, REAC = (0.06, 0.008), (0.01, 0.010)  # (effort [rad], RMS [m])


def test_the_line_between_the_parties_and_its_ends():
    assert line_rms(0.01, VOL, REAC) == pytest.approx(0.010)
    assert line_rms(0.06, VOL, REAC) == pytest.approx(0.008)
    assert line_rms(0.035, VOL, REAC) == pytest.approx(0.009)  # half way
    assert line_rms(0.0, VOL, REAC) == pytest.approx(0.010)  # less effort than reactive: held at reactive
    assert line_rms(0.2, VOL, REAC) == pytest.approx(0.008)  # more than voluntary: held at voluntary
    assert line_rms(0.03, (0.02, 0.008), (0.02, 0.010)) == pytest.approx(0.008)  # equal efforts: the better
    # one party better on both (here the wearer: less effort and less error than the robot)
    dominant, poor = (0.08, 0.003), (0.11, 0.036)
    assert line_rms(0.095, dominant, poor) == pytest.approx(0.0195)  # on the segment: the line itself
    assert line_rms(0.12, dominant, poor) == pytest.approx(0.003)  # beyond both efforts: the better party
    assert line_rms(0.05, dominant, poor) == pytest.approx(0.003)  # below both: the end of least effort
    assert line_rms(0.11, dominant, poor) == pytest.approx(0.036)  # each party is on its own line
    assert line_ratio(0.0045, 0.035, VOL, REAC) == pytest.approx(0.5)
    assert line_ratio(None, 0.035, VOL, REAC) is None
    assert line_ratio(0.01, float("nan"), VOL, REAC) is None


def test_add_line_ratios_puts_the_parties_at_one():
    runs = {"voluntary": {"voluntary_effort": VOL[0], "tracking_rmse_m": VOL[1]},
            "reactive": {"voluntary_effort": REAC[0], "tracking_rmse_m": REAC[1]},
            "mix50": {"voluntary_effort": 0.035, "tracking_rmse_m": 0.0099}}
    add_line_ratios(runs)
    assert runs["voluntary"]["line_ratio"] == pytest.approx(1.0)
    assert runs["reactive"]["line_ratio"] == pytest.approx(1.0)
    assert runs["mix50"]["line_ratio"] == pytest.approx(1.1)
    alone = add_line_ratios({"gate": {"voluntary_effort": 0.02, "tracking_rmse_m": 0.01}})
    assert alone["gate"]["line_ratio"] is None
