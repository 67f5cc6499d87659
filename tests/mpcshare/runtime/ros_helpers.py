"""Shared by the `mpcshare run` tests: a DDS domain of this test process, configs written from the examples."""

from __future__ import annotations

import os
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
SUPERLIMB = ROOT / "examples" / "ros2" / "superlimb.toml"
PANDA = ROOT / "examples" / "ros2" / "panda.toml"
#: a domain of its own per test process (loopback only), so parallel runs do not hear each other
DOMAIN = 100 + os.getpid() % 100


def write_config(folder: Path, source: Path = SUPERLIMB, replace: dict[str, str] | None = None,
                 append: str = "") -> Path:
    """``source`` with the test's domain, each regular expression of ``replace`` substituted once
    (it must match), and ``append`` added; written to ``folder`` (relative robot files made absolute)."""
    text = source.read_text().replace("domain_id = 0", f"domain_id = {DOMAIN}")
    if "domain_id" not in text:
        text = text.replace("[network]\n", f"[network]\ndomain_id = {DOMAIN}\n", 1)
    for pattern, new in (replace or {}).items():
        text, n = re.subn(pattern, new, text, count=1, flags=re.M)
        assert n == 1, pattern
    path = folder / source.name
    path.write_text(text + append)
    return path
