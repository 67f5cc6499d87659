"""The K trade-off in words: the trend sentence."""

from mpcshare.reports.sweep import trend_sentence


def _rows(rmse, effort, ps=(100, 80, 60)):
    return [{"kind": "gate+predictor", "percentile": p, "rmse_reactive": r, "voluntary_effort": e}
            for p, r, e in zip(ps, rmse, effort)] + [{"kind": "ridge", "percentile": None}]


def test_trend_sentence_says_what_happened():
    assert "as the paper expects" in trend_sentence(_rows([0.3, 0.2, 0.1], [0.0, 0.1, 0.2]))
    s = trend_sentence(_rows([0.3, 0.35, 0.1], [0.0, 0.1, 0.2]))
    assert "not at every step" in s and "100th and 80th" in s and "as the paper expects" in s
    s = trend_sentence(_rows([0.1, 0.2, 0.3], [0.0, 0.1, 0.2]))
    assert "does not fall" in s and "NOT what the paper expects" in s
    assert "no trend" in trend_sentence(_rows([0.1], [0.0], ps=(100,)))
