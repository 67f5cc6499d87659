"""comparison.md: the findings in words, the task sentence, who leads per mode."""

from __future__ import annotations

from mpcshare.evaluation import Comparison
from mpcshare.reports.comparison import comparison_findings, comparison_markdown, task_sentence
from mpcshare.run_table import RUN_NAMES


def _metrics(rms_mm: float, **extra) -> dict:
    base = {"tracking_rmse_m": rms_mm / 1e3, "tracking_p95_m": 2 * rms_mm / 1e3, "voluntary_effort": 0.05,
            "reactive_share": 0.8, "handovers": 4, "conflict_share": 0.02, "limit_violations": 0,
            "step_p50_ms": 0.5, "step_p99_ms": 1.5, "realtime_factor": 8.0, "lag_s": 0.1, "rms_at_lag_m": 0.01,
            "saw_amplitude_ratio": None, "saw_correlation": None, "stroke_share": None}
    return {**base, **extra}


def test_task_sentence_says_whether_the_knife_cut():
    cut = task_sentence("gate", {"lag_s": 0.11, "saw_amplitude_ratio": 0.89, "saw_correlation": 0.82,
                                 "stroke_share": 0.87})
    assert "110 ms late" in cut and "the knife SAWED" in cut and "87%" in cut
    assert "at least 0.7" in cut and "at least 0.6" in cut  # the task's criterion, in its words
    ahead = task_sentence("gate", {"lag_s": -0.02, "saw_amplitude_ratio": 0.89, "saw_correlation": 0.82})
    assert "20 ms ahead" in ahead and "-20" not in ahead
    no = task_sentence("gate", {"lag_s": 0.4, "saw_amplitude_ratio": 0.27, "saw_correlation": 0.02})
    assert "did NOT saw" in no
    assert "no cutting" in task_sentence("gate", {"lag_s": 0.1})


def test_findings_compare_the_mpc_and_name_the_upper_bound():
    s = {"voluntary": _metrics(13.0, voluntary_effort=0.08), "reactive": _metrics(16.0), "gate": _metrics(15.0),
         "gate_mpc": _metrics(16.5, step_p99_ms=3.0), "oracle_preview": _metrics(2.4)}
    text = " ".join(comparison_findings(s))
    assert "the MPC hurts" in text
    assert "2.4 mm" in text and "6.7×" in text  # reactive against the oracle
    s["gate_mpc"] = _metrics(15.05)
    assert "makes no measurable difference" in " ".join(comparison_findings(s))


def test_who_leads_per_mode_sits_beside_the_offline_share():
    gate = _metrics(15.0, wearer_share_by_mode={"cutting": 0.86, "collecting": 0.08})
    comp = Comparison(strategies={"gate": gate}, per_trial={}, trials=[2], duration_s=30.0, runs=[],
                      offline_wearer_share_by_mode={"cutting": 0.76, "collecting": 0.045})
    md = comparison_markdown(comp, plot_name=None)
    assert "| cutting | 86% | 76% |" in md.replace(" %", "%")
    assert "| collecting | 8% | 4% |" in md.replace(" %", "%") or "| collecting | 8% | 5% |" in md.replace(" %", "%")
    no_modes = Comparison(strategies={"gate": _metrics(15.0)}, per_trial={}, trials=[2], duration_s=30.0, runs=[])
    assert "Who leads" not in comparison_markdown(no_modes, plot_name=None)


def test_who_leads_has_a_column_per_shared_strategy_of_the_registry(monkeypatch):
    """The columns are the registry's ``shared`` strategies that ran, in its order; the others have none."""
    import mpcshare.reports.comparison as report

    shares = {"cutting": 0.5}
    runs = {name: _metrics(15.0, wearer_share_by_mode=shares) for name in ("reactive", "blend", "paper_gate", "gate")}
    comp = Comparison(strategies=runs, per_trial={}, trials=[2], duration_s=30.0, runs=[])
    head = next(line for line in comparison_markdown(comp, plot_name=None).splitlines() if "wearer leads" in line)
    assert head == ("| mode | wearer leads, `gate` | wearer leads, `paper_gate` | wearer leads, `blend` | "
                    "offline voluntary share |")
    monkeypatch.setattr(report, "by_role", lambda role: ("blend", "probe") if role == "shared" else ())
    head = next(line for line in comparison_markdown(comp, plot_name=None).splitlines() if "wearer leads" in line)
    assert head == "| mode | wearer leads, `blend` | offline voluntary share |"


def test_findings_state_the_line_ratio_and_when_the_wearer_alone_is_better():
    s = {"voluntary": _metrics(13.0, voluntary_effort=0.08, line_ratio=1.0), "reactive": _metrics(16.0, line_ratio=1.0),
         "gate": _metrics(15.0, line_ratio=1.07), "blend": _metrics(12.0, line_ratio=0.85)}
    text = " ".join(comparison_findings(s))
    assert "`gate` 1.07" in text and "below the line: `blend`" in text and "wearer alone tracks better" in text
    s["blend"]["line_ratio"] = 1.01
    assert "NONE is below the straight line" in " ".join(comparison_findings(s))


def test_the_effort_error_plot_fits_under_the_headline_on_a_laptop_screen(tmp_path):
    """990 × 385 px: with the four headline lines it stays above the fold at 1280 × 800."""
    from PIL import Image

    from mpcshare.reports.comparison import plot_effort_error

    s = {n: _metrics(10.0 + i, voluntary_effort=0.01 * (i + 1)) for i, n in enumerate(RUN_NAMES)}
    with Image.open(plot_effort_error(s, tmp_path / "e.png")) as im:
        assert im.size[0] <= 1000 and im.size[1] <= 400
