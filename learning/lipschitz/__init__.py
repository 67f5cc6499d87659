"""Exact point-wise Lipschitz quotients (is the output y predictable from x?).

    q_i = max_{j ≠ i, g_j = g_i} ‖y_i − y_j‖ / ‖x_i − x_j‖      [units of y per unit of x]

Public API
----------
- :func:`pointwise_quotients` — the exact quotients of every point (optionally the
  partner attaining each, and the work counters as a :class:`QuotientResult`).
- :class:`SearchOptions` — tuning of the search (never changes the result);
  :class:`SearchStats` — work counters of one call.
- :func:`check_inputs` — the input validation ``pointwise_quotients`` applies.
- Building blocks, float64 by direct differences: :func:`pair_ratios` (quotients of
  explicit pairs, with the conventions for duplicates), :func:`pair_norms`; and
  :func:`survivors` (positions of the entries ≥ 0 of a float32 screen).

The engine lives in private modules: ``_bounds`` (conservative float32 bounds),
``_exact`` (float64 pairs), ``_kernel`` (numpy screening), ``_search`` (branch and
bound, symmetric pass),
``_torch`` (the torch kernel), ``_quotients`` (the driver).
"""

from ._exact import pair_norms, pair_ratios
from ._kernel import survivors
from ._quotients import (
                         QuotientResult,
                         SearchOptions,
                         SearchStats,
                         check_inputs,
                         pointwise_quotients,
)

__all__ = [
                         "QuotientResult",
                         "SearchOptions",
                         "SearchStats",
                         "check_inputs",
                         "pair_norms",
                         "pair_ratios",
                         "pointwise_quotients",
                         "survivors",
]
