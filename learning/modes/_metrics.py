"""Agreement between decoded task modes and ground-truth labels.

HMM states are found without labels, so their numbering is arbitrary. When
labels exist, each predicted mode is matched to one true label so that the
number of agreeing samples is maximal (the Hungarian algorithm on the
contingency table, ``scipy.optimize.linear_sum_assignment``). True labels < 0
(``-1`` = unknown, see docs/design.md) are ignored everywhere.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment
from sklearn.metrics import adjusted_rand_score

__all__ = ["match_modes", "mode_agreement", "mode_ari", "relabel"]


def _labels(pred: np.ndarray, true: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    pred = np.asarray(pred)
    true = np.asarray(true)
    if pred.ndim != 1 or true.ndim != 1:
        raise ValueError(f"labels must be 1-D, got shapes {pred.shape} and {true.shape}")
    if pred.shape != true.shape:
        raise ValueError(f"pred has {pred.size} labels but true has {true.size}")
    for name, a in (("pred", pred), ("true", true)):
        if a.size and not np.issubdtype(a.dtype, np.integer) and (
                not np.all(np.isfinite(a)) or not np.all(a == np.round(a))):
            raise ValueError(f"{name} labels must be integers")
    return pred.astype(np.int64), true.astype(np.int64)


def match_modes(pred: np.ndarray, true: np.ndarray, one_to_one: bool = True) -> dict[int, int]:
    """Map predicted mode → true label that maximises agreement.

    Maximises Σ_p C[p, mapping[p]] over one-to-one mappings, C[p, l] = #{t: pred_t = p,
    true_t = l, true_t ≥ 0} (Hungarian algorithm). The numbers of labels may differ:
    predicted modes left without a partner (more modes than labels) map to -1, i.e. they
    count as wrong. With ``one_to_one=False`` each mode maps to its majority label instead
    (several modes may share a label: agreement of an over-segmentation). Every label
    occurring in ``pred`` is a key.
    """
    pred, true = _labels(pred, true)
    keep = true >= 0
    p_labels = np.unique(pred)
    t_labels = np.unique(true[keep])
    mapping = {int(p): -1 for p in p_labels}
    if t_labels.size == 0 or p_labels.size == 0:
        return mapping
    pi = np.searchsorted(p_labels, pred[keep])
    ti = np.searchsorted(t_labels, true[keep])
    counts = np.zeros((p_labels.size, t_labels.size), dtype=np.int64)
    np.add.at(counts, (pi, ti), 1)
    if not one_to_one:
        for r in range(p_labels.size):
            if counts[r].any():
                mapping[int(p_labels[r])] = int(t_labels[np.argmax(counts[r])])
        return mapping
    rows, cols = linear_sum_assignment(counts, maximize=True)
    for r, c in zip(rows, cols):
        mapping[int(p_labels[r])] = int(t_labels[c])
    return mapping


def relabel(pred: np.ndarray, mapping: dict[int, int]) -> np.ndarray:
    """``pred`` with each mode replaced by ``mapping[mode]`` (-1 where not in the mapping)."""
    pred = np.asarray(pred, dtype=np.int64)
    out = np.full(pred.shape, -1, dtype=np.int64)
    for p, t in mapping.items():
        out[pred == p] = t
    return out


def mode_agreement(pred: np.ndarray, true: np.ndarray, one_to_one: bool = True
                   ) -> tuple[float, dict[int, int]]:
    """Accuracy after the best matching (:func:`match_modes`), over samples with
    ``true ≥ 0``; and the matching. Raises ValueError when no sample is labelled.
    """
    pred, true = _labels(pred, true)
    keep = true >= 0
    if not keep.any():
        raise ValueError("no labelled samples: every true label is < 0 (unknown)")
    mapping = match_modes(pred, true, one_to_one)
    acc = float(np.mean(relabel(pred[keep], mapping) == true[keep]))
    return acc, mapping


def mode_ari(pred: np.ndarray, true: np.ndarray) -> float:
    """Adjusted Rand index (sklearn) between ``pred`` and ``true`` over samples with ``true ≥ 0``.

    Invariant to the numbering of modes; 1 = identical partitions, ≈0 = chance.
    """
    pred, true = _labels(pred, true)
    keep = true >= 0
    if not keep.any():
        raise ValueError("no labelled samples: every true label is < 0 (unknown)")
    return float(adjusted_rand_score(true[keep], pred[keep]))
