"""The README as a new user meets it: short, and every code block runs as written.

- the PyTorch line is PyTorch's own CPU install (it reaches a host this machine cannot: checked, not run);
- the quickstart block is what ``.ci/run`` runs, line for line (it installs the project and runs this suite);
- every other block runs, in the README's order, in one folder: a TOML block is written to the file its
  first comment names; a bash block runs line by line (``bash -e``) with this environment's ``mpcshare``;
  a Python block runs in a fresh interpreter. The folder holds the bags the README imports, recorded
  from synthetic demonstrations (:func:`tests.learning.bags.write_trial_bag`), and ``mpcshare-out/model``
  is the model the README's own-data block trains (the demo's is the quickstart's, run by ``.ci/run``).
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
BLOCK = re.compile(r"^```(\w*)\n(.*?)^```", re.S | re.M)
TORCH_CPU = "pip install torch --index-url https://download.pytorch.org/whl/cpu"
MAX_LINES = 150
TRIAL_SECONDS = 8.0  # each bag one trial: long enough for every block, short for the closed loops


def _blocks() -> list[tuple[str, str]]:
    return [(lang, body) for lang, body in BLOCK.findall(README.read_text(encoding="utf-8"))]


def _commands(body: str) -> list[str]:
    """The shell lines of a block, continuation lines joined, comments and blanks dropped."""
    lines, cur = [], ""
    for raw in body.splitlines():
        line = raw.split(" #")[0].rstrip() if not raw.lstrip().startswith("#") else ""
        if line.endswith("\\"):
            cur += line[:-1] + " "
            continue
        cur += line
        if cur.strip():
            lines.append(cur.strip())
        cur = ""
    return lines


def _is_install(body: str) -> bool:
    return any(c.startswith("pip install") for c in _commands(body))


def test_the_readme_is_short():
    n = len(README.read_text(encoding="utf-8").splitlines())
    assert n <= MAX_LINES, f"README.md has {n} lines, at most {MAX_LINES}"


def test_torch_line_is_pytorchs_cpu_install_and_ci_installs_torch_first():
    torch_blocks = [b for lang, b in _blocks() if lang == "bash" and "torch" in b]
    assert [_commands(b) for b in torch_blocks] == [[TORCH_CPU]]
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    torch_at, project_at = ci.find("pip install torch"), ci.find('pip install -e ".[test]"')
    assert 0 <= torch_at < project_at, ".ci/run must install torch's CPU build before the project"


def test_the_quickstart_is_what_ci_runs():
    quick = [b for lang, b in _blocks() if lang == "bash" and 'pip install -e ".[test]"' in b]
    assert len(quick) == 1, "one quickstart block"
    assert _commands(quick[0]) == ['pip install -e ".[test]" && mpcshare demo', "pytest"]
    ci_lines = [line.strip() for line in (ROOT / ".ci" / "run").read_text(encoding="utf-8").splitlines()]
    for command in _commands(quick[0]):
        assert command in ci_lines, f".ci/run does not run the README's {command!r}"


def _toml_target(body: str) -> str:
    first = body.splitlines()[0]
    m = re.match(r"#\s*(\S+\.toml)\b", first)
    assert m, f"a TOML block's first line names its file (# NAME.toml: ...), got {first!r}"
    return m.group(1)


@pytest.fixture(scope="module")
def workdir(tmp_path_factory) -> Path:
    """A folder with the bags the README's import line names, one synthetic trial each."""
    from sim.demonstrator import generate_demonstrations
    from tests.learning.bags import write_trial_bag

    work = tmp_path_factory.mktemp("readme")
    imports = [c for lang, b in _blocks() if lang == "bash" for c in _commands(b) if c.startswith("mpcshare import")]
    assert len(imports) == 1, "the README imports bags once"
    args = shlex.split(imports[0])[2:]
    bags = args[:args.index("--mapping")]
    demos = generate_demonstrations(len(bags), TRIAL_SECONDS / 60.0, seed=0)
    for name, trial in zip(bags, demos.trials):
        write_trial_bag(work / name, trial, demos.obs_names, demos.act_names, demos.vol_names)
    return work


def _run(cmd: list[str], cwd: Path, what: str) -> subprocess.CompletedProcess:
    env = dict(os.environ)
    env["PATH"] = os.pathsep.join([str(Path(sys.executable).parent), env.get("PATH", "")])
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")])
    run = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True, timeout=900)
    tail = f"{run.stdout[-3000:]}\n{run.stderr[-3000:]}"
    assert run.returncode == 0, f"README {what} failed (exit {run.returncode}):\n{tail}"
    return run


def test_every_other_block_runs_as_written(workdir):
    ran = []
    for k, (lang, body) in enumerate(_blocks()):
        if lang == "bash" and _is_install(body):
            continue  # the two tests above
        if lang == "toml":
            (workdir / _toml_target(body)).write_text(body, encoding="utf-8")
        elif lang == "bash":
            for command in _commands(body):
                if "mpcshare-out/model" in command and not (workdir / "mpcshare-out" / "model").exists():
                    (workdir / "mpcshare-out").mkdir(exist_ok=True)
                    (workdir / "mpcshare-out" / "model").symlink_to(workdir / "model", target_is_directory=True)
                _run(["bash", "-e", "-c", command], workdir, f"block {k + 1}: {command}")
        elif lang == "python":
            (workdir / f"block{k + 1}.py").write_text(body, encoding="utf-8")
            run = _run([sys.executable, f"block{k + 1}.py"], workdir, f"block {k + 1} (python)")
            if "ctrl.step(" in body:  # the own-loop block: the controller tracks, it does not hold on a fault
                assert run.stdout.split()[:1] == ["ok"], f"README block {k + 1} printed {run.stdout!r}"
        else:
            pytest.fail(f"README block {k + 1} has no runner for language {lang!r}")
        ran.append(lang)
    assert ran.count("bash") >= 2 and "python" in ran and "toml" in ran
