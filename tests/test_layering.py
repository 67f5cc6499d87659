"""The layering table of docs/design.md ("Layout and layering"), checked on the source.

Every import counts, also those inside functions (the lazy ones), because a lazy import
that goes upward is still a dependency. A test failure names the file, the line and the rule.
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
FIRST_PARTY = ("learning", "robot", "sim", "mpcshare")

#: package → the first-party packages it may import (besides itself)
MAY_IMPORT = {
    "learning": set(),
    "robot": set(),
    "sim": {"learning", "robot"},
    "mpcshare": {"learning", "robot", "sim"},
}
#: package → the third-party libraries it may import (mpcshare: anything the distribution installs)
THIRD_PARTY = {
    "learning": {"numpy", "scipy", "sklearn", "hmmlearn", "torch", "numba", "threadpoolctl", "tqdm", "rosbags",
                 "tomli"},
    "robot": {"numpy", "scipy", "pinocchio", "qpsolvers", "osqp", "daqp", "ruckig", "casadi", "example_robot_data"},
    "sim": {"numpy", "scipy", "mujoco", "tqdm", "PIL", "imageio", "imageio_ffmpeg", "mcap"},
}
#: inside mpcshare: the online controller never imports training, reports or the command line
CONTROL_NEVER = ("mpcshare.training", "mpcshare.reports", "mpcshare.commands", "mpcshare.cli")


def _imports(path: Path) -> list[tuple[int, str]]:
    """(line, absolute module name) of every import in ``path``; relative ones resolved."""
    package = list(path.relative_to(ROOT).with_suffix("").parts[:-1])
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[:len(package) - node.level + 1]
                name = ".".join(base + ([node.module] if node.module else []))
            else:
                name = node.module or ""
            found.append((node.lineno, name))
    return found


def _sources(package: str) -> list[Path]:
    return sorted((ROOT / package).rglob("*.py"))


@pytest.mark.parametrize("package", FIRST_PARTY)
def test_each_package_imports_only_what_its_row_allows(package):
    stdlib = set(sys.stdlib_module_names)
    bad = []
    for path in _sources(package):
        for line, name in _imports(path):
            top = name.split(".")[0]
            where = f"{path.relative_to(ROOT)}:{line} imports {name}"
            if top in FIRST_PARTY and top != package and top not in MAY_IMPORT[package]:
                bad.append(f"{where} ({package}/ may import {sorted(MAY_IMPORT[package]) or 'no other package'})")
            elif top not in FIRST_PARTY and top not in stdlib and package in THIRD_PARTY \
                    and top not in THIRD_PARTY[package]:
                bad.append(f"{where} (third-party libraries of {package}/: {sorted(THIRD_PARTY[package])})")
    assert not bad, "\n".join(bad)


def test_the_controller_never_imports_training_reports_or_the_command_line():
    bad = [f"{p.relative_to(ROOT)}:{line} imports {name}"
           for p in _sources("mpcshare/control") for line, name in _imports(p)
           if any(name == m or name.startswith(m + ".") for m in CONTROL_NEVER)]
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("folder", [*FIRST_PARTY, "benchmarks", "examples"])
def test_no_private_module_or_name_of_another_package(folder):
    bad = []
    for path in sorted((ROOT / folder).rglob("*.py")):
        own = path.relative_to(ROOT).parts[0]
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if not isinstance(node, ast.ImportFrom) or node.level or not node.module:
                continue
            top = node.module.split(".")[0]
            if top not in FIRST_PARTY or top == own:
                continue
            private_module = any(part.startswith("_") for part in node.module.split("."))
            private_names = [a.name for a in node.names if a.name.startswith("_")]
            if private_module or private_names:
                bad.append(f"{path.relative_to(ROOT)}:{node.lineno} from {node.module} import "
                           f"{', '.join(a.name for a in node.names)}")
    assert not bad, "\n".join(bad)


def test_the_checker_sees_a_violation(tmp_path, monkeypatch):
    """The rules above can fail: a planted upward import is found."""
    planted = ROOT / "learning" / "_planted_for_test.py"
    assert not planted.exists()
    planted.write_text("def f():\n    from mpcshare.bundle import load_bundle\n    return load_bundle\n")
    try:
        with pytest.raises(AssertionError, match="_planted_for_test.py:2 imports mpcshare.bundle"):
            test_each_package_imports_only_what_its_row_allows("learning")
    finally:
        planted.unlink()


def _design_rows() -> dict[str, tuple[str, str]]:
    """folder → (what lives there, may import) of the table in docs/design.md, "Layout and layering"."""
    text = (ROOT / "docs" / "design.md").read_text()
    section = text[text.index("## Layout and layering"):]
    section = section[:section.index("\n## ", 1)]
    rows = {}
    for line in section.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 3 and cells[0].startswith("`") and cells[0].endswith("/`"):
            rows[cells[0].strip("`/")] = (cells[1], cells[2])
    return rows


def test_the_design_table_states_these_rules():
    """docs/design.md's "may import" column names exactly the packages and libraries above (in backticks),
    and each package's row names every subpackage (``name/``)."""
    import re

    rows = _design_rows()
    assert set(FIRST_PARTY) <= set(rows), f"the design table has no row for {set(FIRST_PARTY) - set(rows)}"
    bad = []
    for package in FIRST_PARTY:
        what, may = rows[package]
        named = set(re.findall(r"`([A-Za-z_][\w.]*)`", may))
        if named & set(FIRST_PARTY) != MAY_IMPORT[package]:
            bad.append(f"{package}: the table's packages {sorted(named & set(FIRST_PARTY))}, "
                       f"the test's {sorted(MAY_IMPORT[package])}")
        if package in THIRD_PARTY and named - set(FIRST_PARTY) != THIRD_PARTY[package]:
            bad.append(f"{package}: the table's libraries {sorted(named - set(FIRST_PARTY))}, "
                       f"the test's {sorted(THIRD_PARTY[package])}")
        if package not in THIRD_PARTY and "any library" not in may:
            bad.append(f"{package}: the test allows any library; the table says {may!r}")
        for sub in sorted(p.parent.name for p in (ROOT / package).glob("*/__init__.py")):
            if f"`{sub}/`" not in what:
                bad.append(f"{package}: subpackage {sub}/ not named in its row")
    assert not bad, "\n".join(bad)
