"""`mpcshare/runtime/` may import the controller and the bundle, never training, reports or the command line."""

from __future__ import annotations

from tests.test_layering import ROOT, _imports, _sources

NEVER = ("mpcshare.training", "mpcshare.reports", "mpcshare.commands", "mpcshare.cli", "mpcshare.evaluation")


def test_the_runtime_never_imports_training_reports_or_the_command_line():
    sources = _sources("mpcshare/runtime")
    assert len(sources) >= 8
    bad = [f"{p.relative_to(ROOT)}:{line} imports {name}" for p in sources for line, name in _imports(p)
           if any(name == m or name.startswith(m + ".") for m in NEVER)]
    assert not bad, "\n".join(bad)
