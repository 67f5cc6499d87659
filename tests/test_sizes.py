"""Small modules with one purpose: no module of the four packages over 400 lines, no function over 80.

Tests and benchmarks are held to the same module size (their functions are not limited).
A failure names the file, the function and its length, so that the one that grew is split
where it grew.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("learning", "robot", "sim", "mpcshare")
#: folders held to the module size only (a test or a benchmark may have long functions)
SCRIPT_FOLDERS = ("tests", "benchmarks")
MAX_MODULE_LINES = 400
MAX_FUNCTION_LINES = 80


def _sources() -> list[Path]:
    return sorted(p for pkg in PACKAGES for p in (ROOT / pkg).rglob("*.py"))


def test_the_packages_have_sources():
    assert len(_sources()) > 100  # the check below looks at the real tree


@pytest.mark.parametrize("package", PACKAGES)
def test_no_module_over_400_lines(package):
    long = [f"{p.relative_to(ROOT)}: {n} lines" for p in sorted((ROOT / package).rglob("*.py"))
            if (n := len(p.read_text().splitlines())) > MAX_MODULE_LINES]
    assert not long, f"modules over {MAX_MODULE_LINES} lines (split them by purpose): {long}"


@pytest.mark.parametrize("folder", SCRIPT_FOLDERS)
def test_no_test_or_benchmark_module_over_400_lines(folder):
    sources = sorted((ROOT / folder).rglob("*.py"))
    assert len(sources) > 5  # the check looks at the real tree
    long = [f"{p.relative_to(ROOT)}: {n} lines" for p in sources
            if (n := len(p.read_text().splitlines())) > MAX_MODULE_LINES]
    assert not long, f"modules over {MAX_MODULE_LINES} lines (split them by purpose): {long}"


@pytest.mark.parametrize("package", PACKAGES)
def test_no_function_over_80_lines(package):
    long = []
    for p in sorted((ROOT / package).rglob("*.py")):
        for node in ast.walk(ast.parse(p.read_text(), str(p))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = node.end_lineno - node.lineno + 1
                if n > MAX_FUNCTION_LINES:
                    long.append(f"{p.relative_to(ROOT)}:{node.lineno} {node.name}: {n} lines")
    assert not long, f"functions over {MAX_FUNCTION_LINES} lines (split them): {long}"
