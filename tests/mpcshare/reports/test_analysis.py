"""Report writing: atomic JSON, formatting, plots of demonstrations."""

import json

import pytest

from mpcshare.reports.analysis import (
    fmt,
    fmt_p,
    fmt_p_value,
    plot_demonstrations,
)
from sim.demonstrator import generate_demonstrations
from sim.task.eating import MODE_NAMES


def test_json_is_atomic_and_strict(tmp_path):
    from learning.atomic import write_json

    path = tmp_path / "r.json"
    write_json({"a": 1}, path, non_finite="raise")
    with pytest.raises(ValueError):
        write_json({"a": float("inf")}, path, non_finite="raise")  # not JSON: refused
    assert json.loads(path.read_text()) == {"a": 1}  # the old file is intact
    assert [p.name for p in tmp_path.iterdir()] == ["r.json"]  # no temporary left behind


def test_fmt():
    assert fmt(None) == "inf" and fmt(3.14159) == "3.14"


def test_fmt_p_does_not_print_an_underflowed_zero():
    assert fmt_p(0.0) == "p < 1e-300"
    assert fmt_p(3.14e-5) == "p = 3.1e-05"
    assert fmt_p(0.5, 3) == "p = 0.5"
    assert fmt_p_value(0.0) == "< 1e-300" and fmt_p_value(3.14e-5) == "3.1e-05"


def test_plot_demonstrations(tmp_path):
    d = generate_demonstrations(1, 0.5, seed=0)
    plot_demonstrations(d, tmp_path / "t.png", mode_names=MODE_NAMES)
    assert (tmp_path / "t.png").stat().st_size > 10_000


def test_importing_the_report_module_leaves_the_matplotlib_backend_alone():
    import os
    import subprocess
    import sys

    env = {**os.environ, "MPLBACKEND": "svg"}
    code = "import mpcshare.reports.analysis, matplotlib; print(matplotlib.get_backend())"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env).stdout
    assert out.strip() == "svg"
