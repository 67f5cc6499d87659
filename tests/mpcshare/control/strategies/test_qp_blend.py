"""``qp_blend``: the gate's α rule with the wearer's weight 1 − α, fusion declared inside the QP, the gate's
calibrated rule read, its settings checked."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from mpcshare.control.arbitration import Arbiter
from mpcshare.control.bundle_inputs import rule_settings
from mpcshare.control.strategies import REGISTRY
from mpcshare.control.strategies.base import ModeFigures
from mpcshare.control.strategies.qp_blend import QPBlendSettings

FIGURES = ModeFigures(np.array([0.05, 0.7, 0.0]), np.array([[0.8, 0.2, 0.0], [0.0, 0.9, 0.1], [0.1, 0.0, 0.9]]), 0.1)


def _pair(**options):
    return [Arbiter(s, beta=0.5, min_dwell_s=0.0, handover_s=0.5, figures=FIGURES, settings=options)
            for s in ("gate", "qp_blend")]


def test_the_gates_alpha_with_the_wearers_weight_one_minus_alpha():
    gate, blend = _pair(lead_s=0.0, hold_s=0.0)
    modes = [0] * 20 + [1] * 30 + [2] * 30
    for k, j in enumerate(modes):
        g = gate.decide(0.1 * k, 0.9, mode_proba=np.eye(3)[j])
        b = blend.decide(0.1 * k, 0.9, mode_proba=np.eye(3)[j])
        assert b.alpha == pytest.approx(g.alpha, abs=1e-12)  # the same ramp
        assert b.beta == 1.0 - b.alpha  # the gate's β at α = 1 is the user's 0.5: the QP's weights are convex
    assert [h.t for h in blend.handovers] == [h.t for h in gate.handovers] and len(blend.handovers) == 3
    assert blend.decide(9.0, None, mode_proba=np.eye(3)[0]).alpha == 0.0  # the gate's overrides apply


def test_spec_settings_and_the_bundles_gate_rule():
    spec = REGISTRY["qp_blend"]
    assert (spec.fusion, spec.rule_of, spec.role, spec.tunable) == ("qp", "gate", "shared", False)
    assert REGISTRY["gate"].fusion == "velocity"
    bundle = SimpleNamespace(rule=SimpleNamespace(strategy="gate", settings={"share_on": 0.4}))
    assert rule_settings(bundle, "qp_blend") == {"share_on": 0.4} == rule_settings(bundle, "gate")
    assert rule_settings(bundle, "blend") is None
    assert Arbiter("qp_blend", settings={"share_on": 0.4}).settings == QPBlendSettings(share_on=0.4)
    with pytest.raises(ValueError, match="wearer_offset_m must be finite and > 0"):
        Arbiter("qp_blend", settings={"wearer_offset_m": 0.0})
    with pytest.raises(ValueError, match="share_off <= share_on"):
        QPBlendSettings(share_on=0.1, share_off=0.2)
