"""The layering table of docs/design.md ("Layout and layering"), checked on the source.

Every import counts, also those inside functions (the lazy ones) and under ``TYPE_CHECKING``, because a
lazy import that goes upward is still a dependency. The rules: each package's row of the table; folders
that never import some packages (the controller, training, the product against ``research``, the
benchmarks against the tests); no cycle between the subpackages and modules of ``mpcshare``; no cycle
between files anywhere in the packages and ``research``. A failure names the file, the line and the rule;
each rule is shown to fail on a planted file.
"""

from __future__ import annotations

import ast
import functools
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
#: folder → the modules it never imports (a name or anything below it): the online controller nothing of
#: training, calibration, evaluation, reports or the command line; training neither its calibration nor the
#: simulator; the distribution's packages never ``research``; benchmarks no test module
NEVER = {
    "mpcshare/control": ("mpcshare.training", "mpcshare.calibration", "mpcshare.evaluation", "mpcshare.reports",
                         "mpcshare.commands", "mpcshare.cli"),
    "mpcshare/training": ("mpcshare.calibration", "mpcshare.evaluation", "mpcshare.commands", "mpcshare.cli",
                          "sim"),
    **{package: ("research",) for package in FIRST_PARTY},
    "benchmarks": ("tests",),
}
#: the folders whose files may form no import cycle
ACYCLIC = (*FIRST_PARTY, "research")


def _imports(path: Path, with_names: bool = False) -> list[tuple[int, str]]:
    """(line, absolute module name) of every import in ``path``; relative ones resolved. ``with_names``: also
    ``a.b`` for each ``from a import b`` (``b`` may be a module). Parsed once per file version (its modification
    time and size), as every rule reads every file."""
    stat = path.stat()
    return list(_parsed_imports(path, with_names, stat.st_mtime_ns, stat.st_size))


@functools.lru_cache(maxsize=None)
def _parsed_imports(path: Path, with_names: bool, _mtime_ns: int, _size: int) -> tuple[tuple[int, str], ...]:
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
            if with_names:
                found += [(node.lineno, f"{name}.{a.name}") for a in node.names if a.name != "*"]
    return tuple(found)


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


@pytest.mark.parametrize("folder", NEVER)
def test_folder_never_imports_what_its_rule_forbids(folder):
    bad = [f"{p.relative_to(ROOT)}:{line} imports {name} ({folder}/ never imports {', '.join(NEVER[folder])})"
           for p in _sources(folder) for line, name in _imports(p)
           if any(name == m or name.startswith(m + ".") for m in NEVER[folder])]
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


def test_the_task_imports_nothing_else_of_sim():
    """``sim/task/`` (what is specific to the task) imports ``learning`` and ``robot``, of ``sim`` only itself."""
    bad = [f"{p.relative_to(ROOT)}:{line} imports {name} (sim/task/ imports of sim only sim.task)"
           for p in _sources("sim/task") for line, name in _imports(p)
           if name.split(".")[0] == "sim" and name != "sim.task" and not name.startswith("sim.task.")]
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


def _module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _module_graph(folders: tuple[str, ...]) -> dict[str, dict[str, int]]:
    """module → {module it imports: first line}, over the files of ``folders``. ``from a import b`` is an edge to
    the module ``a.b`` where there is one, else to ``a``; ``import a.b.c`` to the longest module prefix."""
    paths = {_module_name(p): p for folder in folders for p in _sources(folder)}
    graph: dict[str, dict[str, int]] = {}
    for module, path in paths.items():
        edges = graph.setdefault(module, {})
        for line, name in _imports(path, with_names=True):
            while name and name not in paths:
                name = name.rpartition(".")[0]
            if name and name != module:
                edges.setdefault(name, line)
    return graph


def _cycles(graph: dict[str, dict[str, int]]) -> list[list[str]]:
    """The strongly connected components of more than one node (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in graph.get(v, {}):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def _describe(cycle: list[str], graph: dict[str, dict[str, int]], where: dict[str, str]) -> str:
    """One cycle with the edges that close it: ``a -> b (file:line)``."""
    members = set(cycle)
    edges = [f"{a} -> {b} ({where[a]}:{line})" for a in cycle for b, line in sorted(graph[a].items()) if b in members]
    return "cycle " + " / ".join(cycle) + ": " + "; ".join(edges)


def _file_cycles() -> list[str]:
    graph = _module_graph(ACYCLIC)
    where = {_module_name(p): str(p.relative_to(ROOT)) for folder in ACYCLIC for p in _sources(folder)}
    return [_describe(c, graph, where) for c in _cycles(graph)]


def _mpcshare_part(module: str) -> str | None:
    """The child of ``mpcshare`` (subpackage or module) that ``module`` belongs to; None outside it or for
    the package itself."""
    parts = module.split(".")
    return parts[1] if parts[0] == "mpcshare" and len(parts) > 1 else None


def _package_cycles() -> list[str]:
    files = _module_graph(("mpcshare",))
    where = {_module_name(p): str(p.relative_to(ROOT)) for p in _sources("mpcshare")}
    graph: dict[str, dict[str, int]] = {}
    first: dict[tuple[str, str], str] = {}
    for module, edges in files.items():
        a = _mpcshare_part(module)
        for target, line in edges.items():
            b = _mpcshare_part(target)
            if a and b and a != b:
                graph.setdefault(a, {}).setdefault(b, line)
                first.setdefault((a, b), f"{where[module]}:{line} imports {target}")
    return ["cycle " + " / ".join(c) + ": " + "; ".join(first[(a, b)] for a in c for b in c if (a, b) in first)
            for c in _cycles(graph)]


def test_no_import_cycle_between_files():
    bad = _file_cycles()
    assert not bad, "\n".join(bad)


def test_no_import_cycle_between_the_parts_of_mpcshare():
    bad = _package_cycles()
    assert not bad, "\n".join(bad)


@pytest.fixture
def plant():
    """``plant(relative path, source)`` writes a file into the real tree for one test; removed afterwards."""
    planted: list[Path] = []

    def write(relative: str, source: str) -> None:
        path = ROOT / relative
        assert not path.exists()
        path.write_text(source)
        planted.append(path)

    yield write
    for path in planted:
        path.unlink()


def test_the_folder_rules_see_a_planted_import(plant):
    plant("mpcshare/training/_planted_for_test.py", "def f():\n    from sim.scene import SceneConfig\n")
    plant("sim/_planted_for_test.py", "import research.splice_bound\n")
    plant("benchmarks/_planted_for_test.py", "from tests.sim.controllers import IdleController\n")
    for folder, needle in [("mpcshare/training", "_planted_for_test.py:2 imports sim.scene"),
                           ("sim", "_planted_for_test.py:1 imports research.splice_bound"),
                           ("benchmarks", "_planted_for_test.py:1 imports tests.sim.controllers")]:
        with pytest.raises(AssertionError, match=needle):
            test_folder_never_imports_what_its_rule_forbids(folder)


def test_the_cycle_checks_see_planted_cycles(plant):
    """A lazy import back and forth between two files, and a module of ``bundle/`` that imports the command
    line (which imports ``bundle``), are both found."""
    plant("learning/_planted_a.py", "from learning import _planted_b\n")
    plant("learning/_planted_b.py", "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
                                    "    from learning._planted_a import x\n")
    plant("mpcshare/bundle/_planted_for_test.py", "def f():\n    import mpcshare.commands.train\n")
    with pytest.raises(AssertionError, match=r"cycle learning\._planted_a / learning\._planted_b"):
        test_no_import_cycle_between_files()
    with pytest.raises(AssertionError, match=r"cycle .*bundle / .*commands .*bundle/_planted_for_test\.py:2 imports "
                                             r"mpcshare\.commands\.train"):
        test_no_import_cycle_between_the_parts_of_mpcshare()


def test_the_cycle_finder_on_small_graphs():
    assert _cycles({"a": {"b": 1}, "b": {"c": 1}, "c": {"a": 1}, "d": {"a": 1}}) == [["a", "b", "c"]]
    assert _cycles({"a": {"b": 1}, "b": {}}) == []


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
