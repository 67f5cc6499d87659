"""Preprocessing: downsampling, standardisation, causal windows.

- :mod:`learning.preprocessing.preprocess` — zero-phase downsampling for the analysis,
  :class:`Standardizer`, :class:`Preprocessor`, causal windows that never cross a trial;
- :mod:`learning.preprocessing.resample` — causal anti-aliased downsampling, offline and
  streaming (what the online controller reproduces).
"""

from learning.preprocessing.preprocess import (
                                               Preprocessor,
                                               Standardizer,
                                               WindowedData,
                                               causal_windows,
                                               downsample,
                                               preprocess,
                                               window_lags,
)
from learning.preprocessing.resample import StreamingDecimator, causal_downsample, decimation_factor, lowpass_sos

__all__ = ["Preprocessor", "Standardizer", "WindowedData", "causal_windows", "downsample", "preprocess",
           "window_lags", "StreamingDecimator", "causal_downsample", "decimation_factor", "lowpass_sos"]
