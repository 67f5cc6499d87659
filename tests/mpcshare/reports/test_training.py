"""training.md (mpcshare.reports.training): the skill tables of the control-rate forecast."""

from __future__ import annotations

import numpy as np

from mpcshare.reports.training import skill_lines, training_markdown
from mpcshare.training.fast import skill_table
from tests.mpcshare.training.fast_rows import fast_rows as _rows


def test_training_md_has_the_skill_tables():
    F, rows = _rows()
    fast = skill_table(F, rows, np.ones(3), 2, 0.1)
    lines = skill_lines(fast)
    assert any(line.startswith("| 0.1 |") for line in lines) and any(line.startswith("| 1 |") for line in lines)
    metrics = {"training": {"K": 2.0, "percentile": 90.0, "reactive_share_train": 0.9, "total_s": 12.0},
               "heldout_reactive_share": 0.88, "predictor": {"rmse_reactive": 0.1, "rmse_all": 0.2},
               "gate": {"overall": {"accuracy": 0.9, "f1": 0.9, "brier": 0.1}}, "fast_forecast": fast}
    md = training_markdown(metrics)
    assert "skill vs hold" in md and "Skill per mode" in md
    assert "not trained" in training_markdown({**metrics, "fast_forecast": None})
