"""Docstrings name things that exist: every Sphinx-role reference to a first-party name
(``:mod:``, ``:class:``, ``:func:``, ``:meth:``, ``:data:``, ``:attr:``, ``:exc:``) resolves, and every
file of the repository a docstring names (``tests/….py``, ``docs/….md``, ``benchmarks/….py``,
``examples/….py``) is there. No module cites an issue number: docstrings and comments are contracts,
the history is in ``docs/``. Module docstrings of every module of :data:`PACKAGES` are contracts of at most
:data:`MAX_MODULE_DOC_LINES` lines."""

from __future__ import annotations

import ast
import importlib
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("learning", "robot", "sim", "mpcshare")
ROLE = re.compile(r":(?:mod|class|func|meth|data|attr|exc):`~?((?:learning|robot|sim|mpcshare)(?:\.\w+)+)`")
FILE = re.compile(r"\b((?:tests|docs|benchmarks|examples)/[\w/.-]+\.(?:py|md))\b")
ISSUE = re.compile(r"\bissues?[\s-]+#?\d+", re.IGNORECASE)
MAX_MODULE_DOC_LINES = 20


def _resolves(name: str) -> bool:
    """``name`` is a module, or an attribute path from the longest importable module prefix."""
    parts = name.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        try:
            for part in parts[i:]:
                obj = getattr(obj, part)
        except AttributeError:
            return False
        return True
    return False


def _sources() -> list[Path]:
    return [p for package in PACKAGES for p in sorted((ROOT / package).rglob("*.py"))]


def _issue_numbers(paths: list[Path]) -> list[str]:
    """``file:line: text`` of each line that mentions an issue by number."""
    return [f"{p.name}:{i}: {line.strip()}" for p in paths
            for i, line in enumerate(p.read_text().splitlines(), 1) if ISSUE.search(line)]


def _module_doc_lines(source: str) -> int:
    """Lines of the module docstring of ``source`` (0 without one); the closing quotes on a
    line of their own do not count."""
    doc = ast.get_docstring(ast.parse(source), clean=False)
    return len(doc.splitlines()) if doc else 0


def _long_module_docstrings(sources: dict[str, str], limit: int = MAX_MODULE_DOC_LINES) -> list[str]:
    """``name: N lines`` of each source (name → text) whose module docstring exceeds ``limit`` lines."""
    return [f"{name}: {n} lines" for name, text in sources.items() if (n := _module_doc_lines(text)) > limit]


def _capped_sources() -> dict[str, str]:
    """Path → text of every module of :data:`PACKAGES`, the modules whose docstrings are capped."""
    return {str(p.relative_to(ROOT)): p.read_text() for p in _sources()}


def test_references_in_docstrings_resolve():
    bad = [f"{p.relative_to(ROOT)} names {m.group(1)}"
           for p in _sources() for m in ROLE.finditer(p.read_text()) if not _resolves(m.group(1))]
    assert not bad, "\n".join(bad)


def test_files_named_in_docstrings_exist():
    bad = [f"{p.relative_to(ROOT)} names {m.group(1)}"
           for p in _sources() for m in FILE.finditer(p.read_text()) if not (ROOT / m.group(1)).exists()]
    assert not bad, "\n".join(bad)


def test_no_module_cites_an_issue_number():
    bad = _issue_numbers(_sources())
    assert not bad, "say what the code does; the history goes to docs/:\n" + "\n".join(bad)


def test_the_issue_check_sees_a_planted_mention(tmp_path):
    planted = 'X = 1  # the keys of Issue 12\n"""issue-7, issues #8"""\nI = "issues"  # 3 of them\n'
    (tmp_path / "planted.py").write_text(planted)
    assert _issue_numbers([tmp_path / "planted.py"]) == ["planted.py:1: X = 1  # the keys of Issue 12",
                                                        'planted.py:2: """issue-7, issues #8"""']


def test_module_docstrings_are_short_contracts():
    long = [row for row in _long_module_docstrings(_capped_sources())]
    assert not long, (f"module docstrings over {MAX_MODULE_DOC_LINES} lines: say what the module computes, the "
                      "equation, units and errors; evidence goes to docs/results.md, rationale to docs/design.md:\n"
                      + "\n".join(long))


def test_the_length_check_sees_a_planted_long_docstring():
    body = "\n".join(f"line {i}" for i in range(1, MAX_MODULE_DOC_LINES + 1))
    at_cap = f'"""{body}\n"""\nX = 1\n'
    over = f'"""{body}\none more\n"""\nX = 1\n'
    assert _module_doc_lines(at_cap) == MAX_MODULE_DOC_LINES
    assert _long_module_docstrings({"at_cap.py": at_cap, "over.py": over, "none.py": "X = 1\n"}) == [
        f"over.py: {MAX_MODULE_DOC_LINES + 1} lines"]
    capped = _capped_sources()
    assert {"mpcshare/runtime/loop.py", "sim/task/metrics.py", "mpcshare/control/strategies/gate.py",
            "mpcshare/cli.py", "mpcshare/__init__.py", "mpcshare/calibration/rule_choice.py",
            "mpcshare/evaluation/tuning/stats.py", "learning/__init__.py", "robot/__init__.py"} <= set(capped)
    assert {str(p.relative_to(ROOT)) for p in (ROOT / "mpcshare").rglob("*.py")} <= set(capped)


def test_the_checks_see_a_missing_name():
    assert _resolves("sim.wearer_protocol.Wearer") and _resolves("learning.modes.ModeFilter")
    assert not _resolves("learning.modes_online.ModeFilter") and not _resolves("robot.superlimb.mjcf_arm_body")
    assert FILE.findall("see tests/sim/test_reach.py.") == ["tests/sim/test_reach.py"]


def test_the_package_docstrings_list_their_modules_and_commands():
    import mpcshare
    import sim
    from mpcshare.cli import COMMANDS

    missing = [f"sim.{p.stem}" for p in sorted((ROOT / "sim").glob("*.py"))
               if p.stem != "__init__" and f":mod:`sim.{p.stem}`" not in sim.__doc__]
    missing += [f"mpcshare.{p.stem if p.suffix else p.name}" for p in sorted((ROOT / "mpcshare").iterdir())
                if (p.suffix == ".py" and p.stem not in ("__init__", "__main__")) or (p / "__init__.py").exists()
                if f":mod:`mpcshare.{p.stem if p.suffix else p.name}`" not in mpcshare.__doc__]
    missing += [f"command {c.name}" for c in COMMANDS if f"``{c.name}``" not in mpcshare.__doc__]
    assert not missing, f"not in the package docstrings: {missing}"
