"""A new strategy is one module: dropped into the strategies package, it reaches the Arbiter (with its typed
settings), the command line (``sim --runs``, ``tune --strategies``), the run table, the Pareto set, the colours
and, declared ``shared``, the headline."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

import pytest

PROBE = textwrap.dedent('''
    """A probe strategy for the test: the robot leads at α = share (0.7 by default)."""
    from dataclasses import dataclass

    from mpcshare.control.strategies.base import StrategySpec
    from mpcshare.control.strategies.fixed import Fixed


    @dataclass(frozen=True)
    class ProbeSettings:
        share: float = 0.7

        def __post_init__(self):
            if not 0.0 <= self.share <= 1.0:
                raise ValueError(f"share must be in [0, 1], got {self.share!r}")


    SPECS = (StrategySpec("probe70", "A probe strategy for the registry test.", tunable=True, color="#123456",
                          factory=lambda ctx: Fixed(ctx.settings.share, 1 - ctx.settings.share, "probe"), order=4.5,
                          role="shared", settings=ProbeSettings),)
''')

# run in a fresh interpreter whose import system gives the strategies package the probe's folder as a
# second path before the package (and its registry) is first imported: nothing is written into the tree
CHECK = textwrap.dedent('''
    import importlib.machinery, json, sys

    class ExtraStrategyPath:
        @staticmethod
        def find_spec(name, path=None, target=None):
            if name != "mpcshare.control.strategies":
                return None
            spec = importlib.machinery.PathFinder.find_spec(name, path)
            spec.submodule_search_locations.append(sys.argv[1])
            return spec

    sys.meta_path.insert(0, ExtraStrategyPath)
    import mpcshare.control.strategies as module
    from mpcshare import run_table
    from mpcshare.cli import build_parser
    from mpcshare.control.arbitration import Arbiter
    from mpcshare.reports.headline import shared_strategy
    parser = build_parser()
    sim = parser.parse_args(["sim", "--model", "b", "--out", "o", "--runs", "probe70"])
    tune = parser.parse_args(["tune", "d", "--out", "o", "--strategies", "probe70"])
    d = Arbiter("probe70").decide(0.0, 0.9)
    mine = Arbiter("probe70", settings={"share": 0.6}).decide(0.0, 0.9)
    try:
        Arbiter("probe70", settings={"share": 2.0})
        refused = None
    except ValueError as exc:
        refused = str(exc)
    print(json.dumps({"registry": list(module.REGISTRY), "runs": list(run_table.RUN_NAMES),
                      "tunable": list(run_table.TUNABLE), "pareto": list(run_table.REALISABLE),
                      "color": run_table.RUN_COLORS.get("probe70"), "sim": sim.runs, "tune": tune.strategies,
                      "decision": [d.alpha, d.beta], "mine": mine.alpha, "refused": refused,
                      "headline": shared_strategy({"paper_gate": {}, "probe70": {}, "blend": {}})}))
''')


def test_a_strategy_module_reaches_every_command_and_table(tmp_path):
    (tmp_path / "probe70.py").write_text(PROBE)
    out = subprocess.run([sys.executable, "-c", CHECK, str(tmp_path)], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    seen = json.loads(out.stdout.strip().splitlines()[-1])
    assert seen["registry"].index("probe70") == seen["registry"].index("gate") + 1  # placed by its order
    assert "probe70" in seen["runs"] and "probe70" in seen["tunable"] and "probe70" in seen["pareto"]
    assert seen["color"] == "#123456" and seen["sim"] == ["probe70"] and seen["tune"] == ["probe70"]
    assert seen["decision"] == pytest.approx([0.7, 0.3]) and seen["mine"] == 0.6
    assert seen["refused"] == "strategy 'probe70': probe70 settings: share must be in [0, 1], got 2.0"
    assert seen["headline"] == "probe70"  # shared, and before paper_gate in the registry
