"""Each module of the four packages has its test at the mirrored path, or an exemption that says why.

The mirrored path of ``pkg/sub/mod.py`` is ``tests/pkg/sub/test_mod.py`` (of a private ``_mod.py``
too); a package's ``__init__.py`` is tested as if the package were a module (``pkg/sub/__init__.py``
→ ``tests/pkg/test_sub.py``), and one that only imports and lists names needs no test. ``EXEMPT``
may only shrink: an entry whose module gained its test, or is gone, fails until it is removed, and
``EXEMPT_CEILING`` is lowered with it. ``python -m tests.test_layout`` lists the modules without one.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("learning", "robot", "sim", "mpcshare")

#: module (repository path) → why it has no test at its mirrored path
EXEMPT: dict[str, str] = {
    "learning/analysis/__init__.py": "`__init__` lazy re-exports",
    "learning/analysis/report.py": "no test yet",
    "learning/analysis/result.py": "no test yet",
    "learning/errors.py": "error root: tests/mpcshare/test_errors.py",
    "learning/lipschitz/_bounds.py": "no test yet",
    "learning/lipschitz/_search.py": "no test yet",
    "learning/predictor/__init__.py": "`__init__` lazy re-exports",
    "learning/predictor/defaults.py": "pure data: tests/mpcshare/test_defaults.py checks who reads it",
    "learning/predictor/stream.py": "exercised by tests/learning/predictor/test_lstm.py",
    "mpcshare/__init__.py": "`__init__` lazy re-exports",
    "mpcshare/__main__.py": "`__main__`: `python -m mpcshare`, run by tests/mpcshare/test_cli.py",
    "mpcshare/bundle/manifest.py": "exercised by tests/mpcshare/bundle/test_bundle.py",
    "mpcshare/commands/robot_options.py": "no test yet",
    "mpcshare/commands/sim_serve.py": "no test yet",
    "mpcshare/control/mpc_follow.py": "no test yet",
    "mpcshare/control/preview.py": "exercised by tests/mpcshare/control/test_fastpath.py",
    "mpcshare/control/records.py": "exercised by tests/mpcshare/control/test_sensing.py",
    "mpcshare/control/strategies/blend.py": "exercised by tests/mpcshare/control/strategies/test_base.py",
    "mpcshare/control/strategies/fixed.py": "no test yet",
    "mpcshare/control/strategies/mix.py": "no test yet",
    "mpcshare/control/strategies/paper_gate.py": "exercised by tests/mpcshare/test_defaults.py",
    "mpcshare/control/strategies/replay.py": "no test yet",
    "mpcshare/control/types.py": "exercised by tests/mpcshare/control/test_builder.py",
    "mpcshare/evaluation/distinct.py": "exercised by tests/mpcshare/evaluation/test_frontend_replay.py",
    "mpcshare/evaluation/episode.py": "exercised by tests/mpcshare/evaluation/test_frontend_replay.py",
    "mpcshare/evaluation/pooling.py": "exercised by tests/mpcshare/commands/test_sim.py",
    "mpcshare/evaluation/runs.py": "exercised by tests/mpcshare/evaluation/test_episode_pool.py",
    "mpcshare/evaluation/tuning/runner.py": "exercised by tests/mpcshare/evaluation/test_tune.py",
    "mpcshare/reports/demo.py": "exercised by tests/mpcshare/training/test_modes_from.py",
    "mpcshare/runtime/config_reader.py": "exercised by tests/mpcshare/runtime/test_config.py",
    "mpcshare/runtime/convert.py": "exercised by tests/mpcshare/runtime/test_messages.py",
    "mpcshare/runtime/setup.py": "exercised by tests/mpcshare/runtime/test_config.py",
    "mpcshare/runtime/stand_in_command.py": "no test yet",
    "mpcshare/training/__init__.py": "`__init__` lazy re-exports",
    "mpcshare/training/evaluation.py": "exercised by tests/mpcshare/training/test_train.py",
    "robot/__main__.py": "`__main__`: writes the files tests/robot/superlimb/test_model_files.py checks",
    "robot/errors.py": "error root: tests/mpcshare/test_errors.py",
    "robot/mpc/codegen.py": "exercised by tests/robot/mpc/test_tip_mpc.py",
    "robot/mpc/nlp.py": "no test yet",
    "robot/mpc/problem.py": "no test yet",
    "robot/mpc/qp.py": "no test yet",
    "robot/qp_types.py": "exercised by tests/robot/test_floor.py",
    "robot/wearer_body.py": "exercised by tests/mpcshare/control/test_keepout.py",
    "sim/__init__.py": "`__init__` chooses offscreen GL: tests/sim/test_offscreen_gl.py",
    "sim/arm_mounts.py": "tested in tests/mpcshare/test_arms.py, the path arm_mounts.py cites",
    "sim/episode.py": "exercised by tests/sim/test_closed_loop.py",
    "sim/errors.py": "error root: tests/mpcshare/test_errors.py",
    "sim/task/__init__.py": "the task registry: tested in tests/sim/task/test_protocol.py",
}
#: len(EXEMPT) may only fall: lower this with each entry removed, never raise it
EXEMPT_CEILING = 48


def mirrored_test(module: str) -> str:
    """The test file of ``module`` (a repository path such as ``sim/task/eating.py``), as a repository path."""
    path = Path(module)
    if path.parts[0] not in PACKAGES or path.suffix != ".py":
        raise ValueError(f"{module}: not a module of the packages {PACKAGES}")
    if path.name == "__init__.py":
        return str(Path("tests", *path.parts[:-2], f"test_{path.parent.name}.py"))
    return str(Path("tests", *path.parts[:-1], f"test_{path.stem.removeprefix('_')}.py"))


def _reexports_only(path: Path) -> bool:
    """True when ``path`` holds only its docstring, imports and ``__all__`` (nothing to test)."""
    for node in ast.parse(path.read_text(), str(path)).body:
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            continue
        if isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant) and isinstance(node.value.value, str):
            continue
        if isinstance(node, (ast.Assign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            if all(isinstance(t, ast.Name) and t.id == "__all__" for t in targets):
                continue
        return False
    return True


def modules() -> list[str]:
    """Every module of the four packages, as repository paths."""
    return sorted(str(p.relative_to(ROOT)) for pkg in PACKAGES for p in (ROOT / pkg).rglob("*.py"))


def untested() -> list[str]:
    """The modules with something to test and no file at their mirrored path."""
    return [m for m in modules()
            if not (ROOT / mirrored_test(m)).exists() and not _reexports_only(ROOT / m)]


def test_the_mirrored_path_of_a_module_a_private_module_and_a_package():
    assert mirrored_test("mpcshare/commands/sim.py") == "tests/mpcshare/commands/test_sim.py"
    assert mirrored_test("learning/lipschitz/_quotients.py") == "tests/learning/lipschitz/test_quotients.py"
    assert mirrored_test("mpcshare/control/strategies/__init__.py") == "tests/mpcshare/control/test_strategies.py"
    assert mirrored_test("sim/__init__.py") == "tests/test_sim.py"


def test_the_check_looks_at_the_real_tree():
    assert len(modules()) > 150
    assert _reexports_only(ROOT / "learning/gates/__init__.py")
    assert not _reexports_only(ROOT / "mpcshare/control/strategies/__init__.py")


def test_no_two_modules_share_a_test():
    seen: dict[str, str] = {}
    for m in modules():
        other = seen.setdefault(mirrored_test(m), m)
        assert other == m, f"{other} and {m} would share {mirrored_test(m)}: rename one"


def test_every_module_has_its_test_at_the_mirrored_path_or_an_exemption():
    missing = [f"{m}: create {mirrored_test(m)}" for m in untested() if m not in EXEMPT]
    assert not missing, f"modules without their test at the mirrored path: {missing}"


def test_the_exemptions_only_shrink():
    need = set(untested())
    stale = [f"{m}: {'has ' + mirrored_test(m) if (ROOT / m).exists() else 'is gone'}; remove it from EXEMPT"
             for m in EXEMPT if m not in need]
    assert not stale, f"exemptions no longer needed (lower EXEMPT_CEILING too): {stale}"
    assert len(EXEMPT) <= EXEMPT_CEILING, f"EXEMPT grew to {len(EXEMPT)} (ceiling {EXEMPT_CEILING}): write the test"
    assert len(EXEMPT) == EXEMPT_CEILING, f"EXEMPT shrank to {len(EXEMPT)}: set EXEMPT_CEILING = {len(EXEMPT)}"


def test_each_exemption_says_why_in_a_phrase():
    bad = [m for m, why in EXEMPT.items() if not why.strip() or len(why) > 100]
    assert not bad, f"exemptions without a one-phrase reason: {bad}"


if __name__ == "__main__":
    for m in untested():
        print(f"{m}\t{mirrored_test(m)}\t{EXEMPT.get(m, 'NOT EXEMPT')}")
