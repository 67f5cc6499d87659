"""The predictability analysis of Song & Asada, end to end, on any data set.

- :mod:`learning.analysis.pipeline` — :func:`analyze` and its result;
- :mod:`learning.analysis.config` — :class:`AnalysisConfig`, every setting with its default;
- :mod:`learning.analysis.predictability` — thresholds K, voluntary shares, paired tests;
- :mod:`learning.analysis.reference` — the time-free reference grouping, random groupings and
  the calibrated segmentation test (``mode_evidence``);
- :mod:`learning.analysis.search` — the search over window lengths and numbers of modes;
- :mod:`learning.analysis.report` — the report's records (``AnalysisReport``).
"""

from learning.analysis.config import HELP_EFFECT, MIN_EFFECT, SIGNIFICANCE, AnalysisConfig, AnalysisError

__all__ = ["HELP_EFFECT", "MIN_EFFECT", "SIGNIFICANCE", "AnalysisConfig", "AnalysisError", "AnalysisResult", "analyze"]


def __getattr__(name: str):
    # the pipeline imports the quotient engine (numba): loaded on first use, so that reading the
    # settings (the command line's defaults) stays light
    if name in ("AnalysisResult", "analyze"):
        from learning.analysis import pipeline

        return getattr(pipeline, name)
    raise AttributeError(f"module 'learning.analysis' has no attribute {name!r}")
