"""The four answers a person reads first: the task, sharing (against each party and the line), effort, keep-out."""

from __future__ import annotations

import pytest

from mpcshare.reports.headline import headline_lines, headlines, line_ratio


def _m(rms_mm: float, effort: float, **extra) -> dict:
    return {"tracking_rmse_m": rms_mm / 1e3, "voluntary_effort": effort, "lag_s": 0.12,
            "saw_amplitude_ratio": 0.9, "saw_correlation": 0.85, **extra}


def _runs(gate_mm: float, gate_effort: float = 0.03, **gate_extra) -> dict:
    return {"voluntary": _m(6.7, 0.06), "reactive": _m(18.4, 0.0), "gate": _m(gate_mm, gate_effort, **gate_extra)}


def test_line_ratio_is_the_rms_over_the_straight_line_at_the_same_effort():
    s = _runs(10.0, gate_effort=0.03)  # half way in effort: the line is at (6.7 + 18.4) / 2 = 12.55 mm
    assert line_ratio(s, "gate") == pytest.approx(10.0 / 12.55)
    s["gate"]["line_ratio"] = 0.5  # the comparison's own figure wins where it has one
    assert line_ratio(s, "gate") == 0.5
    del s["reactive"]
    assert line_ratio({"gate": _m(10.0, 0.03)}, "gate") is None


def test_sharing_says_when_it_loses_to_the_wearer_alone():
    h = {x.topic: x for x in headlines(_runs(15.7, gate_effort=0.048))}
    assert h["Sharing"].verdict.startswith("NO, it loses to the wearer alone")
    assert "15.7 mm" in h["Sharing"].text and "6.7 mm" in h["Sharing"].text and "18.4 mm" in h["Sharing"].text
    good = {x.topic: x for x in headlines(_runs(5.0))}
    assert good["Sharing"].verdict == "yes, it beats the wearer alone, the robot alone, mixing them"


def test_effort_task_and_keepout_each_have_a_figure_and_a_verdict():
    h = {x.topic: x for x in headlines(_runs(5.0, gate_effort=0.012))}
    assert h["Effort"].verdict == "80% saved" and "20%" in h["Effort"].text
    assert h["The task"].verdict == "yes, it cut" and "0.85" in h["The task"].text
    assert h["Keep-out"].verdict == "not measured"  # no clearance figures in these runs
    weak = {x.topic: x for x in headlines(_runs(5.0, gate_effort=0.05, saw_correlation=0.2))}
    assert weak["Effort"].verdict == "only 17% saved" and weak["The task"].verdict.startswith("NO")
    zones = {x.topic: x for x in headlines(_runs(5.0, min_clearance_m=0.031, steps_driven_in=0))}
    assert zones["Keep-out"].verdict == "yes, it kept out" and "31 mm" in zones["Keep-out"].text
    bad = {x.topic: x for x in headlines(_runs(5.0, steps_driven_in=3))}
    assert bad["Keep-out"].verdict == "NO" and "3 control step" in bad["Keep-out"].text


def test_the_four_lines_come_in_order_and_nothing_without_a_shared_run():
    lines = headline_lines(_runs(15.7), markdown=False)
    assert [ln.split(":")[0] for ln in lines] == ["The task", "Sharing", "Effort", "Keep-out"]
    assert headline_lines({"voluntary": _m(6.7, 0.06)}) == []
