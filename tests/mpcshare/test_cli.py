"""The command line itself: usage errors, help, added commands, `python -m mpcshare`, sim free of mpcshare."""

import pytest

from mpcshare.cli import main


def test_usage_error_exits_2():
    with pytest.raises(SystemExit) as e:
        main(["analyze"])
    assert e.value.code == 2


def test_help_lists_every_registered_subcommand(capsys):
    from mpcshare.cli import COMMANDS

    with pytest.raises(SystemExit) as e:
        main(["--help"])
    assert e.value.code == 0
    out = capsys.readouterr().out
    names = [c.name for c in COMMANDS]
    assert {"generate", "inspect", "analyze", "demo"} <= set(names)
    for c in COMMANDS:
        assert c.name in out and c.help[:30] in out, c.name


def test_extra_command_is_added_and_replaces_by_name(capsys):
    from mpcshare.cli import Command

    seen = []
    extra = Command("hello", "say hello", lambda p: p.add_argument("--who", default="x"),
                    lambda a: seen.append(a.who) or 3)
    assert main(["hello", "--who", "y"], commands=(extra,)) == 3 and seen == ["y"]
    shadow = Command("inspect", "replaced", lambda p: None, lambda a: 7)
    assert main(["inspect"], commands=(shadow,)) == 7


def test_python_dash_m_runs_the_command_line():
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-m", "mpcshare", "--help"], capture_output=True, text=True,
                         check=True).stdout
    assert "generate" in out and "analyze" in out and "demo" in out


def test_sim_imports_nothing_from_mpcshare():
    import ast
    from pathlib import Path

    for path in (Path(__file__).parents[2] / "sim").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import) else
                     [node.module or ""] if isinstance(node, ast.ImportFrom) and node.level == 0 else [])
            assert not any(n == "mpcshare" or n.startswith("mpcshare.") for n in names), path
