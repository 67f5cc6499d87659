"""Exact point-wise Lipschitz quotients (is the output y predictable from x?).

    q_i = max_{j ≠ i, g_j = g_i} ‖y_i − y_j‖ / ‖x_i − x_j‖      [units of y per unit of x]

Euclidean norms; pairs identical in both x and y are skipped; identical x with different y give
``inf``; a point with no partner gets 0. The result equals a float64 direct-difference computation:
conservative float32 screens (``_bounds``) discard pairs against lower bounds of the points'
quotients (from time neighbours and a warm-up, ``_search``), and every pair that can be a maximum
is recomputed exactly by a compiled loop (``_compiled``). Many labelings of the same points share
one pass: :func:`pointwise_quotients_multi` (``_multi``).

Memory O(N·(d + block)): a float32 and a float64 copy of X, Y in pass order, a few (tile × chunk)
screening matrices per thread. Time: N²/2 short float32 products plus the exact recomputation of
the survivors (few on windowed time series; about half a blocked brute force on i.i.d. data, where
no bound prunes; figures: docs/results.md, "Benchmarks"). Inputs that are empty, not 1-D or 2-D,
not real, not finite, of unequal rows, or bad ``groups`` raise ``ValueError``; options that are not
a :class:`SearchOptions` raise ``TypeError``.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from contextlib import nullcontext
from dataclasses import asdict, dataclass
from typing import Literal, NamedTuple

import numpy as np
from threadpoolctl import threadpool_limits

from learning.torch_threads import torch_threads

from ._bounds import F32_UNIT_ROUNDOFF, build_features
from ._exact import dense_exact, pair_ratios, update_best
from ._kernel import NumpyKernel
from ._search import (
    LeafContext,
    PairCounters,
    nearest_leaves,
    search_leaf,
    spread_sample,
    symmetric_pass,
    warm_leaf,
)

__all__ = ["QuotientResult", "SearchOptions", "SearchStats", "check_inputs", "default_jobs", "pointwise_quotients"]


@dataclass(frozen=True)
class SearchOptions:
    """Tuning of the exact search. Every setting gives the same quotients and partners
    (the bounds are conservative); they only change the work done.

    Attributes:
        search: "symmetric" — every unordered pair of a group screened once and both
            points credited (``_search.symmetric_pass``, after a warm-up that raises
            the lower bounds from each leaf's ``warmup_leaves`` nearest leaves); or
            "per_leaf" — each k-d leaf searches its candidate leaves one-sidedly
            (``_search.search_leaf``), about twice the screening work; the reference
            the symmetric pass is tested against.
        small_group: groups up to this size are done densely (all pairs, exactly).
        time_neighbours: initial bounds from rows k±1 … k±time_neighbours of a group.
        warmup_leaves: leaves in the warm-up of the symmetric pass (1 = own leaf; with the
            spread sample below, more leaves cost more screens than they save).
        multi_warmup_leaves: the same for the shared pass of many labelings
            (:func:`pointwise_quotients_multi`), whose bounds serve every labeling at once.
            Both defaults are measured: docs/results.md, "Benchmarks".
        warmup_sample: points spread over the group that every leaf is also bounded
            against in the warm-up (``_search.spread_sample``: maximisers are often far away).
        tile: rows per tile of the symmetric pass.
        chunk: columns per screened chunk of the symmetric pass.
    """

    search: Literal["symmetric", "per_leaf"] = "symmetric"
    small_group: int = 512
    time_neighbours: int = 2
    warmup_leaves: int = 1
    multi_warmup_leaves: int = 4
    warmup_sample: int = 512
    tile: int = 256
    chunk: int = 4096

    def __post_init__(self) -> None:
        if self.search not in ("symmetric", "per_leaf"):
            raise ValueError(f"search must be 'symmetric' or 'per_leaf', got {self.search!r}")
        for name in ("small_group", "warmup_leaves", "multi_warmup_leaves", "tile", "chunk"):
            if int(getattr(self, name)) < 1:
                raise ValueError(f"{name} must be a positive integer, got {getattr(self, name)!r}")
        if int(self.warmup_sample) < 0:
            raise ValueError(f"warmup_sample must be >= 0, got {self.warmup_sample!r}")
        if int(self.time_neighbours) < 0:
            raise ValueError(f"time_neighbours must be >= 0, got {self.time_neighbours!r}")


@dataclass(frozen=True)
class SearchStats:
    """Work counters of one :func:`pointwise_quotients` call.

    Attributes:
        n_pairs: unordered pairs within groups (what a brute force evaluates).
        pairs_screened: ordered pairs screened with the low-dimensional float32 bound.
        pairs_full_screened: ordered pairs screened with the full-dimensional float32 product.
        pairs_exact: ordered pairs recomputed exactly in float64.
    """

    n_pairs: int
    pairs_screened: int
    pairs_full_screened: int
    pairs_exact: int

    def to_dict(self) -> dict[str, int]:
        return asdict(self)


class QuotientResult(NamedTuple):
    """What :func:`pointwise_quotients` returns with ``return_stats=True``."""

    q: np.ndarray
    """(N,) float64 quotients."""
    partner: np.ndarray
    """(N,) int64 index attaining q_i (smallest such; -1 where q_i = 0)."""
    stats: SearchStats
    """work counters of this call."""


def _check_array(A, name: str) -> np.ndarray:
    A = np.asarray(A)
    if A.ndim == 1:
        A = A[:, None]
    if A.ndim != 2:
        raise ValueError(f"{name} must be 1-D or 2-D (samples × features), got ndim={A.ndim}")
    if A.shape[0] == 0:
        raise ValueError(f"{name} is empty (0 rows)")
    if A.shape[1] == 0:
        raise ValueError(f"{name} has no columns")
    if not (np.issubdtype(A.dtype, np.number) or A.dtype == bool) or np.iscomplexobj(A):
        raise ValueError(f"{name} must be real numeric, got dtype {A.dtype}")
    A = np.ascontiguousarray(A, dtype=np.float64)
    step = max(1, (1 << 22) // A.shape[1])
    for s in range(0, A.shape[0], step):
        ok = np.isfinite(A[s:s + step]).all(axis=1)
        if not ok.all():
            row = s + int(np.argmin(ok))
            raise ValueError(f"{name} contains NaN or inf at row {row}")
    return A


def check_inputs(X, Y, groups=None) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Validate and convert: float64 C-contiguous (N, d) X and (N, d_y) Y, (N,) groups.

    Raises ``ValueError`` naming the array (and the first bad row) for wrong
    ndim, empty input, NaN/inf, or mismatched lengths.
    """
    X = _check_array(X, "X")
    Y = _check_array(Y, "Y")
    if len(X) != len(Y):
        raise ValueError(f"X has {len(X)} rows but Y has {len(Y)}")
    if groups is not None:
        groups = np.asarray(groups)
        if groups.ndim != 1:
            raise ValueError(f"groups must be 1-D, got ndim={groups.ndim}")
        if len(groups) != len(X):
            raise ValueError(f"groups has {len(groups)} entries but X has {len(X)} rows")
        if groups.dtype.kind == "f":
            bad = ~np.isfinite(groups)
            if bad.any():
                raise ValueError(f"groups contains NaN or inf at row {int(np.argmax(bad))}")
    return X, Y, groups


def default_jobs() -> int:
    """Threads a call uses by default: the cores this process may run on."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - non-Linux
        return max(1, os.cpu_count() or 1)


def _blas_single_thread():
    """Context limiting BLAS to one thread while our own threads run (no oversubscription)."""
    return threadpool_limits(limits=1, user_api="blas")


def _time_neighbour_init(X, Y, idx, q, partner, lags: int) -> None:
    """Exact quotients of rows k and k+s (s = 1..lags) of a group: cheap, strong initial bounds.

    On windowed time series the nearest neighbours of a sample in x are
    usually its neighbours in time, which often give the maximum.
    """
    for s in range(1, min(lags, len(idx) - 1) + 1):
        i, j = idx[:-s], idx[s:]
        r = pair_ratios(X, Y, i, j)
        update_best(q, partner, np.concatenate([i, j]), np.concatenate([j, i]),
                    np.concatenate([r, r]))


def _make_kernel(backend: str, device, f, X, Y):
    if backend == "numpy":
        return NumpyKernel(f, X, Y)
    from ._torch import TorchKernel
    return TorchKernel(f, X, Y, device=device)


def _may_have_gpu() -> bool:
    """False only when, on Linux, no NVIDIA or ROCm device node exists (CUDA cannot work)."""
    import sys
    if "torch" in sys.modules or not sys.platform.startswith("linux"):
        return True
    return any(os.path.exists(p) for p in ("/dev/nvidiactl", "/dev/nvidia0", "/proc/driver/nvidia",
                                            "/dev/kfd", "/dev/dxg"))


def _resolve_backend(backend: str, device) -> tuple[str, object, float]:
    """(backend, device, unit roundoff of its float32 products)."""
    if backend not in ("auto", "numpy", "torch"):
        raise ValueError(f"backend must be 'auto', 'numpy' or 'torch', got {backend!r}")
    if backend == "auto":
        if device is not None and str(device) != "cpu":
            backend = "torch"
        elif not _may_have_gpu():
            backend = "numpy"  # no GPU device node: skip importing torch (about a second)
        else:
            try:
                import torch
                backend = "torch" if torch.cuda.is_available() else "numpy"
            except ImportError:  # pragma: no cover
                backend = "numpy"
    if backend == "numpy":
        return "numpy", None, F32_UNIT_ROUNDOFF
    from ._torch import resolve_device, torch_unit_roundoff
    dev = resolve_device(device)
    return "torch", dev, torch_unit_roundoff(dev)


def pointwise_quotients(X, Y, groups=None, *, return_partner: bool = False, block: int = 256,
                        n_jobs: int | None = None,
                        backend: Literal["auto", "numpy", "torch"] = "auto", device=None,
                        progress: bool = False, n_components: int | None = None,
                        options: SearchOptions | None = None, return_stats: bool = False):
    """Exact point-wise Lipschitz quotients q_i (see module doc for the definition).

    Args:
        X: (N, d) inputs (1-D is taken as one feature).
        Y: (N, d_y) outputs.
        groups: optional (N,) labels; pairs are formed only within a label.
        return_partner: also return, per point, the index j attaining q_i
            (smallest such j; -1 where q_i = 0, i.e. no partner or all quotients 0).
        block: leaf size of the k-d split (rows screened together).
        n_jobs: threads (default: all available cores; forced to 1 on a GPU).
        backend: "numpy", "torch" (CPU or CUDA), or "auto" (torch if CUDA is available).
        device: torch device for the torch backend (default: CUDA if available).
        progress: show a tqdm progress bar (pairs done; ``leave=False``, so it
            disappears when done and does not clutter an outer bar).
        n_components: principal components in the lower bound (default ≤ 12).
        options: tuning of the search (:class:`SearchOptions`; default: the measured best).
        return_stats: return a :class:`QuotientResult` ``(q, partner, stats)`` with the
            work counters of this call (:class:`SearchStats`).

    Returns:
        q (N,) float64; or (q, partner) with partner (N,) int64; or a
        :class:`QuotientResult` when ``return_stats``.
    """
    options = SearchOptions() if options is None else options
    if not isinstance(options, SearchOptions):
        raise TypeError(f"options must be a SearchOptions, got {type(options).__name__}")
    X, Y, groups = check_inputs(X, Y, groups)
    N = len(X)
    backend, dev, u = _resolve_backend(backend, device)
    if n_jobs is None:
        n_jobs = default_jobs()
    n_jobs = max(1, int(n_jobs))
    if backend == "torch" and str(dev) != "cpu":
        n_jobs = 1
    block = max(8, int(block))
    q = np.zeros(N)
    partner = np.full(N, -1, dtype=np.int64)
    if groups is None:
        group_idx = [np.arange(N)]
    else:
        order = np.argsort(groups, kind="stable")
        _, starts = np.unique(groups[order], return_index=True)
        group_idx = np.split(order, starts[1:])
    stats = PairCounters()
    n_pairs = sum(len(g) * (len(g) - 1) // 2 for g in group_idx)

    bar = None
    if progress:
        from learning.progress import progress_bar
        bar = progress_bar(total=n_pairs, unit="pair", unit_scale=True, desc="Lipschitz quotients",
                   leave=False)
    pool = ThreadPoolExecutor(max_workers=n_jobs) if n_jobs > 1 else None
    limit = _blas_single_thread() if backend == "numpy" else nullcontext()
    # torch on the CPU runs inside our threads: one intra-op thread each.
    tlimit = torch_threads(1) if backend == "torch" and str(dev) == "cpu" else nullcontext()
    try:
        with limit, tlimit:
            for idx in group_idx:
                _one_group(X, Y, idx, q, partner, options=options, block=block, n_components=n_components,
                           backend=backend, device=dev, u=u, pool=pool, bar=bar, stats=stats)
    finally:
        if pool is not None:
            pool.shutdown(wait=True)
        if bar is not None:
            bar.close()
    if return_stats:
        return QuotientResult(q, partner, SearchStats(
            n_pairs=n_pairs, pairs_screened=stats.pairs_screened,
            pairs_full_screened=stats.pairs_full_screened, pairs_exact=stats.pairs_exact))
    return (q, partner) if return_partner else q


def _one_group(X, Y, idx, q, partner, *, options: SearchOptions, block, n_components, backend,
               device, u, pool, bar,
               stats: PairCounters) -> None:
    n = len(idx)
    n_pairs = n * (n - 1) // 2
    if n <= options.small_group:
        dense_exact(X, Y, idx, q, partner)
        stats.pairs_exact += n * (n - 1)
        if bar is not None:
            bar.update(n_pairs)
        return
    if (Y[idx] == Y[idx[0]]).all():  # constant output: every quotient is 0 or skipped
        if bar is not None:
            bar.update(n_pairs)
        return
    _time_neighbour_init(X, Y, idx, q, partner, options.time_neighbours)
    f = build_features(X, Y, idx, leaf_size=block, n_components=n_components,
                       full_screen=True, unit_roundoff=u)
    qp = q[f.perm]
    pp = partner[f.perm]
    ctx = LeafContext(f=f, kernel=_make_kernel(backend, device, f, X, Y), q=qp, partner=pp)
    n_leaves = len(f.leaf_start) - 1
    sizes = np.diff(f.leaf_start)
    run = map if pool is None else pool.map

    if options.search == "symmetric":
        # 1. warm-up: each leaf against its nearest leaves (one-sided) raises the bounds;
        # 2. every unordered pair screened once against those bounds.
        ctx.lb = qp.copy()
        m = options.warmup_leaves
        far = spread_sample(n, options.warmup_sample)
        warm = (lambda a: warm_leaf(ctx, a, m, far)) if f.xs is not None else \
            (lambda a: search_leaf(ctx, a, nearest_leaves(ctx, a, m)))
        for st in run(warm, range(n_leaves)):
            stats.add(st)
        stats.add(symmetric_pass(ctx, pool, bar, tile=options.tile, chunk=options.chunk))
    else:
        for a, st in enumerate(run(lambda a: search_leaf(ctx, a), range(n_leaves))):
            stats.add(st)
            if bar is not None:
                bar.update(int(sizes[a]) * (n - 1) // 2)
    q[f.perm] = qp
    partner[f.perm] = pp
