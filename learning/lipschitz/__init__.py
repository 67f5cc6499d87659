"""Exact point-wise Lipschitz quotients (is the output y predictable from x?).

    q_i = max_{j ≠ i, g_j = g_i} ‖y_i − y_j‖ / ‖x_i − x_j‖      [units of y per unit of x]

- :func:`pointwise_quotients` — the exact quotients of every point (optionally the partner
  attaining each, and the work counters, as a :class:`QuotientResult`).
- :func:`pointwise_quotients_multi` — the quotients of many labelings (L × N labels) of the same
  points in one pass over the pairs, each equal to the single-labeling call.
- :class:`SearchOptions` — tuning of the search (never changes the result);
  :class:`SearchStats` — work counters of one call.
- :func:`check_inputs` — the input validation (``ValueError`` naming the input and row);
  :func:`default_jobs` — the threads a call uses by default.
- Building blocks, float64 by direct differences: :func:`pair_ratios` (quotients of explicit
  pairs, with the conventions for duplicates), :func:`pair_norms`; :func:`survivors` (positions
  of the entries ≥ 0 of a float32 screen).

Private modules: ``_bounds`` (conservative float32 bounds), ``_exact`` (float64 pairs),
``_compiled`` (numba loops), ``_kernel`` (numpy screening), ``_search`` (branch and bound),
``_multi`` (many labelings), ``_torch`` (the torch kernel), ``_quotients`` (the driver).
"""

from ._exact import pair_norms, pair_ratios
from ._kernel import survivors
from ._multi import pointwise_quotients_multi
from ._quotients import (
                         QuotientResult,
                         SearchOptions,
                         SearchStats,
                         check_inputs,
                         default_jobs,
                         pointwise_quotients,
)

__all__ = [
                         "QuotientResult",
                         "SearchOptions",
                         "SearchStats",
                         "check_inputs",
                         "default_jobs",
                         "pair_norms",
                         "pair_ratios",
                         "pointwise_quotients",
                         "pointwise_quotients_multi",
                         "survivors",
]
