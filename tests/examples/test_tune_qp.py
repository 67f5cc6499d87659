"""examples/tune_qp.py writes its table into the folder it names, with every column explained."""

import importlib.util
import json
from pathlib import Path

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "tune_qp.py"


def test_tune_qp_writes_its_explained_table_into_out(tmp_path, capsys):
    spec = importlib.util.spec_from_file_location("tune_qp", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    rows = module.main(["--out", str(tmp_path / "qp"), "--seconds", "0.6"])
    printed = capsys.readouterr().out
    assert len(rows) == 18 and all(r["rms_mm"] >= 0 and r["not_ok"] >= 0 for r in rows)
    for _, head, meaning in module.COLUMNS:  # every printed column is explained, on screen and in the file
        assert f"{head}: {meaning}" in printed
    saved = json.loads((tmp_path / "qp" / "tune_qp.json").read_text())
    assert saved["rows"] == rows
    md = (tmp_path / "qp" / "tune_qp.md").read_text()
    assert md.count("\n| ") == 19 and "m_tau: smallest torque margin" in md
