"""Benchmark: exact point-wise Lipschitz quotients vs a blocked NumPy float32 brute force.

    python benchmarks/bench_lipschitz.py --n 50000 --d 90 [--data windowed|windowed-other|iid|demos]
        [--block 256] [--floor] [--certify ROWS] [--compile-time]

Prints one JSON object: the project's time, the brute force's time on the same
data in the same process (its block size tuned over 256–2,048 rows in the same run, the
fastest used and reported: the baseline is the best simple blocked brute force; for large
N measured on a subset of rows and
extrapolated linearly in the number of rows, flagged in the JSON), their ratio,
the fraction of pairs the project evaluated exactly, peak memory (ru_maxrss of the process after the data and after
the project's run, and the process RSS sampled every 20 ms during the project's run, input
data included; tracemalloc is not used, its hooks slow the search several-fold), and the
largest relative difference to a float64 direct-difference reference on a
sample of rows.

``--floor`` adds the time below which no exact method that screens every pair once can go
on this machine: the bare float32 products of the screen (inner length dy + 12 + 3, the
engine's smallest; tiles of 256 × 4096 on every core, nothing else) timed for about 2 s and
extrapolated to the N(N − 1)/2 pairs (``screen_floor_s``), and the engine's time over it.

``--certify ROWS`` adds the share of points that a bound on a group of partners using the
outputs' spread (balls or boxes in x and y: trees, dual trees, block pruning) cannot rule
out for a row
(``certification_share``): the part of the pairs such pruning must still screen one by one.
On data whose outputs have a part independent of x it stays a sizeable share of N, so the
screen's N² floor is also the floor of those methods (issue 21).

``--compile-time`` adds the numba compile time of the compiled loops (``_compiled``),
measured in a fresh interpreter with an empty cache directory, and the time to load them
from that cache in a second one.

Data: ``windowed`` = smooth multichannel time series (sums of random sinusoids
plus low-pass filtered noise, ⌈d/10⌉ channels) in trials of 600 samples (60 s at
10 Hz), turned into causal windows of 10 lags that never cross a trial, with
outputs that are partly a smooth function of the window and partly an
independent smooth "voluntary" signal — like the demonstrations; ``iid`` =
Gaussian inputs and outputs, the hard case where no bound prunes; ``demos`` = the
synthetic eating demonstrations themselves, preprocessed as ``mpcshare analyze``
does (dense and confounded: many close pairs, so pruning is harder than on
``windowed``); ``windowed-other`` = the windowed generator with another structure
(20 lags of 2 min trials, 6 latent motions, 4× the sensor noise). On ``iid`` data no
bound prunes (every point's maximiser is anywhere): the engine screens all pairs with
the full-dimensional float32 bound and its ratio to the brute force stays near 1–2×.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import sys
import threading
import time
from pathlib import Path

import numpy as np
from typing_extensions import Self

from learning.lipschitz import pair_ratios, pointwise_quotients

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _lipschitz_data import demo_data, iid_data, windowed_data  # noqa: E402


class RssPeak:
    """Peak resident set size [MB] of this process while the context is open (sampled).

    ru_maxrss is a lifetime peak (it includes the data generation); this samples
    /proc/self/statm every ``dt`` seconds in a thread.
    """

    def __init__(self, dt: float = 0.02) -> None:
        self.dt, self.peak_mb = dt, 0.0
        self._stop = threading.Event()
        self._page = os.sysconf("SC_PAGE_SIZE")

    def _sample(self) -> None:
        try:
            with open("/proc/self/statm") as fh:
                rss = int(fh.read().split()[1]) * self._page / 2 ** 20
            self.peak_mb = max(self.peak_mb, rss)
        except OSError:  # pragma: no cover - not Linux
            pass

    def _run(self) -> None:
        while not self._stop.wait(self.dt):
            self._sample()

    def __enter__(self) -> Self:
        self._sample()
        self._t = threading.Thread(target=self._run, daemon=True)
        self._t.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._t.join()
        self._sample()


def brute_force_f32(X: np.ndarray, Y: np.ndarray, rows: np.ndarray, block: int | None = None
                    ) -> np.ndarray:
    """Plain blocked float32 brute force: q_i for the given rows against all points.

    ‖a−b‖² = ‖a‖² + ‖b‖² − 2a·b in float32 (fast, inexact for close pairs).
    Blocks of 512 rows by default, fewer for large N so a (block × N) matrix stays ≤ 256 MB
    (``tune_brute_block`` picks the fastest block size on this machine).
    """
    if block is None:
        block = min(512, brute_block_cap(len(X)))
    X32 = X.astype(np.float32)
    Y32 = Y.astype(np.float32)
    nx = (X32 * X32).sum(1)
    ny = (Y32 * Y32).sum(1)
    out = np.empty(len(rows))
    for s in range(0, len(rows), block):
        r = rows[s:s + block]
        dx2 = nx[r, None] + nx[None, :] - 2.0 * (X32[r] @ X32.T)
        dy2 = ny[r, None] + ny[None, :] - 2.0 * (Y32[r] @ Y32.T)
        np.maximum(dx2, 0, out=dx2)
        np.maximum(dy2, 0, out=dy2)
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = dy2 / dx2
        ratio[np.arange(len(r)), r] = 0.0
        ratio[np.isnan(ratio)] = 0.0
        out[s:s + block] = np.sqrt(ratio.max(1))
    return out


def brute_block_cap(n: int) -> int:
    """Largest block of the brute force whose (block × n) float32 matrices stay ≤ 256 MB."""
    return int(max(16, (1 << 26) // n))


def tune_brute_block(X: np.ndarray, Y: np.ndarray, rng: np.random.Generator,
                     sizes: tuple[int, ...] = (256, 512, 1024, 2048), rows: int = 2048
                     ) -> tuple[int, dict[str, float]]:
    """The fastest block size of ``brute_force_f32`` on this data and machine: each size
    within the memory cap timed on the same random rows (at least two blocks), best of two.
    Returns (block, µs a row per size)."""
    cap = brute_block_cap(len(X))
    cands = [b for b in sizes if b <= cap] or [cap]
    per_row: dict[str, float] = {}
    for b in cands:
        r = np.sort(rng.choice(len(X), size=min(len(X), max(rows, 2 * b)), replace=False))
        best = np.inf
        for _ in range(2):
            t0 = time.perf_counter()
            brute_force_f32(X, Y, r, block=b)
            best = min(best, (time.perf_counter() - t0) / len(r))
        per_row[str(b)] = round(best * 1e6, 2)
    block = int(min(cands, key=lambda b: per_row[str(b)]))
    return block, per_row


def certification_share(X: np.ndarray, Y: np.ndarray, q: np.ndarray, rows: np.ndarray
                        ) -> dict[str, float]:
    """Share of the points that a group bound using the outputs' spread cannot rule out.

    For a row i with quotient q_i > 0, a group of partners whose outputs may lie anywhere
    within D_i = max_k ‖y_i − y_k‖ of y_i can only be excluded unscreened when it lies at
    least D_i / q_i from x_i: inside that radius some output could still give a quotient
    above q_i. Where the outputs have a part independent of x (the voluntary part), groups
    of partners near x_i do hold outputs from the whole spread, so tree or block pruning
    (ball or box bounds in x and y, e.g. a dual tree) gains little over this share (a tree
    split in the joint (x, y) space changed its leaf checks by −13 % to +70 %, issue 21).
    The share is the part of the N² pairs such pruning must still screen pair by pair.
    float64, direct differences."""
    shares = []
    for i in rows:
        if not q[i] > 0 or not np.isfinite(q[i]):
            continue
        dy_max = float(np.sqrt(((Y - Y[i]) ** 2).sum(1)).max())
        dx = np.sqrt(((X - X[i]) ** 2).sum(1))
        shares.append((np.count_nonzero(dx < dy_max / q[i]) - 1) / (len(X) - 1))
    if not shares:
        return {"certification_rows": 0}
    sh = np.asarray(shares)
    return {"certification_rows": len(sh), "certification_share_median": round(float(np.median(sh)), 4),
            "certification_share_mean": round(float(sh.mean()), 4),
            "certification_share_p10": round(float(np.quantile(sh, 0.1)), 4)}


def reference_rows(X: np.ndarray, Y: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """float64 direct-difference q_i for the given rows (the definition, no shortcuts)."""
    N = len(X)
    ref = np.zeros(len(rows))
    for k, i in enumerate(rows):
        j = np.arange(N)
        r = pair_ratios(X, Y, np.full(N, i), j)
        r = r[~np.isnan(r)]
        ref[k] = max(0.0, r.max()) if len(r) else 0.0
    return ref


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=50000)
    ap.add_argument("--d", type=int, default=90)
    ap.add_argument("--dy", type=int, default=3)
    ap.add_argument("--data", choices=["windowed", "windowed-other", "iid", "demos"], default="windowed",
                    help="windowed: smooth synthetic windows; iid: Gaussian; demos: the synthetic "
                         "eating demonstrations preprocessed as `mpcshare analyze` (d=90, dy=9; "
                         "--d/--dy ignored)")
    ap.add_argument("--block", type=int, default=256)
    ap.add_argument("--n-jobs", type=int, default=None)
    ap.add_argument("--n-components", type=int, default=None)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--brute-rows", type=int, default=None,
                    help="rows timed for the brute force (default: all up to 20,000)")
    ap.add_argument("--ref-rows", type=int, default=None, help="rows checked in float64")
    ap.add_argument("--latent", type=int, default=3,
                    help="windowed data: number of latent motions driving the channels")
    ap.add_argument("--noise", type=float, default=0.05,
                    help="windowed data: relative low-pass sensor noise")
    ap.add_argument("--progress", action="store_true")
    ap.add_argument("--floor", action="store_true",
                    help="also time the bare float32 screen products over all pairs (the floor)")
    ap.add_argument("--certify", type=int, default=0, metavar="ROWS",
                    help="also measure, on ROWS of the float64-checked rows, the share of points "
                         "a group bound using the outputs' spread cannot rule out (certification_share)")
    ap.add_argument("--compile-time", action="store_true",
                    help="also measure the numba compile time (fresh interpreter, empty cache)")
    a = ap.parse_args(argv)

    if a.data == "iid":
        X, Y = iid_data(a.n, a.d, a.dy, a.seed)
    elif a.data == "demos":
        X, Y = demo_data(a.n, a.seed)
    elif a.data == "windowed-other":
        X, Y = windowed_data(a.n, a.d, a.dy, a.seed, trial_len=1200, lags=20, latent=6, noise=0.2)
    else:
        X, Y = windowed_data(a.n, a.d, a.dy, a.seed, latent=a.latent, noise=a.noise)
    rss_data = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024

    # One small call first: loads the compiled loops (numba's disk cache) and imports, a
    # fixed cost per process that is not the search (reported; see --compile-time).
    t0 = time.perf_counter()
    pointwise_quotients(X[:1000], Y[:1000], n_jobs=a.n_jobs)
    t_first = time.perf_counter() - t0

    rss_before = RssPeak()
    rss_before._sample()
    rss_before = rss_before.peak_mb
    with RssPeak() as rss_run:
        t0 = time.perf_counter()
        c0 = time.process_time()
        q, _, search_stats = pointwise_quotients(X, Y, block=a.block, n_jobs=a.n_jobs,
                                                 progress=a.progress, n_components=a.n_components,
                                                 return_stats=True)
        t_project = time.perf_counter() - t0
        cpu_project = time.process_time() - c0
    stats = search_stats.to_dict()
    rss_project = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024

    rng = np.random.default_rng(a.seed + 1)
    brute_block, brute_tuning = tune_brute_block(X, Y, np.random.default_rng(a.seed + 2))
    n_brute = a.brute_rows or min(a.n, 20000 if a.n <= 200000 else 2000)
    brute_rows = np.sort(rng.choice(a.n, size=n_brute, replace=False))
    t0 = time.perf_counter()
    c0 = time.process_time()
    q32 = brute_force_f32(X, Y, brute_rows, block=brute_block)
    t_brute_sub = time.perf_counter() - t0
    cpu_brute = (time.process_time() - c0) * a.n / n_brute
    t_brute = t_brute_sub * a.n / n_brute

    n_ref = a.ref_rows or (200 if a.n <= 200000 else 30)
    ref_rows = np.sort(rng.choice(a.n, size=min(n_ref, a.n), replace=False))
    ref = reference_rows(X, Y, ref_rows)
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.abs(q[ref_rows] - ref) / np.abs(ref)
    rel = np.where(q[ref_rows] == ref, 0.0, rel)
    common = np.intersect1d(ref_rows, brute_rows)
    rel32 = None
    if len(common):
        pos_b = np.searchsorted(brute_rows, common)
        pos_r = np.searchsorted(ref_rows, common)
        rel32 = float(np.max(np.abs(q32[pos_b] - ref[pos_r]) / np.abs(ref[pos_r])))

    n_pairs = stats["n_pairs"]
    out = {
        "data": a.data, "n": a.n, "d": int(X.shape[1]), "dy": int(Y.shape[1]), "block": a.block,
        "cores": len(os.sched_getaffinity(0)),
        "project_s": round(t_project, 3),
        "project_first_small_call_s": round(t_first, 3),
        "brute_force_f32_s": round(t_brute, 3),
        "brute_force_extrapolated": n_brute < a.n,
        "brute_force_rows_timed": int(n_brute),
        "brute_force_timed_s": round(t_brute_sub, 3),
        "brute_force_block": brute_block,
        "brute_force_us_per_row_by_block": brute_tuning,
        "speedup": round(t_brute / t_project, 2),
        "project_cpu_s": round(cpu_project, 3),
        "brute_force_cpu_s": round(cpu_brute, 3),
        "speedup_cpu_time": round(cpu_brute / cpu_project, 2),
        "fraction_pairs_exact": stats["pairs_exact"] / (2 * n_pairs),
        "fraction_pairs_screened_lowdim": stats["pairs_screened"] / (2 * n_pairs),
        "fraction_pairs_screened_full_d": stats["pairs_full_screened"] / (2 * n_pairs),
        "pairs_screened": stats["pairs_screened"],
        "peak_rss_mb_after_data": round(rss_data, 1),
        "peak_rss_mb_after_project": round(rss_project, 1),
        "peak_rss_mb_during_project": round(rss_run.peak_mb, 1),
        "rss_mb_before_project": round(rss_before, 1),
        "ref_rows": len(ref_rows),
        "max_rel_diff_vs_float64": float(np.max(rel)),
        "max_rel_diff_bruteforce_f32_vs_float64": rel32,
        "q_median": float(np.median(q)),
    }
    if a.certify:
        out.update(certification_share(X, Y, q, ref_rows[: a.certify]))
    if a.floor:
        floor = screen_floor(a.n, int(Y.shape[1]), a.n_jobs)
        out["project_over_floor"] = round(t_project / floor.pop("floor_exact_s"), 2)
        out.update(floor)
    if a.compile_time:
        out.update(numba_compile_times())
    print(json.dumps(out, indent=1))
    return out


def screen_floor(n: int, dy: int, n_jobs: int | None = None, seconds: float = 2.0,
                 tile: int = 256, chunk: int = 4096) -> dict[str, float]:
    """Time of the bare screen over all n(n − 1)/2 pairs: float32 products of (tile × K')
    row features by (K' × chunk) column features, K' = dy + 12 + 3 (the engine's smallest
    z screen), on every core for ``seconds``; no bound, no survivor, no exact pair."""
    from threadpoolctl import threadpool_limits

    jobs = n_jobs or len(os.sched_getaffinity(0))
    k = dy + 12 + 3
    rng = np.random.default_rng(0)
    R = rng.standard_normal((tile, k)).astype(np.float32)
    C = rng.standard_normal((k, chunk)).astype(np.float32)
    done = [0] * jobs

    def work(slot: int) -> None:
        out = np.empty((tile, chunk), np.float32)
        end = time.perf_counter() + seconds
        while time.perf_counter() < end:
            np.matmul(R, C, out=out)
            done[slot] += tile * chunk

    with threadpool_limits(limits=1, user_api="blas"):
        t0 = time.perf_counter()
        threads = [threading.Thread(target=work, args=(i,)) for i in range(jobs)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        elapsed = time.perf_counter() - t0
    rate = sum(done) / elapsed
    return {"floor_exact_s": n * (n - 1) / 2 / rate, "screen_floor_s": round(n * (n - 1) / 2 / rate, 3),
            "screen_floor_ns_per_pair_per_core": round(jobs / rate * 1e9, 3), "screen_floor_inner_length": k}


def numba_compile_times() -> dict[str, float]:
    """Seconds to compile the engine's numba loops (fresh interpreter, empty cache) and
    to load them from that cache in a second interpreter (what every later run pays)."""
    import subprocess
    import tempfile

    code = ("import time, numpy as np; t0 = time.perf_counter(); "
            "from learning.lipschitz import pointwise_quotients, pointwise_quotients_multi; "
            "rng = np.random.default_rng(0); X = rng.normal(size=(1200, 6)); Y = rng.normal(size=(1200, 2)); "
            "pointwise_quotients(X, Y, backend='numpy', n_jobs=1); "
            "pointwise_quotients_multi(X, Y, rng.integers(0, 3, (2, 1200)), n_jobs=1); "
            "print(time.perf_counter() - t0)")
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        times = [float(subprocess.run([sys.executable, "-c", code], env=env, check=True, capture_output=True,
                                      text=True).stdout.split()[-1]) for _ in range(2)]
    return {"numba_first_run_empty_cache_s": round(times[0], 2), "numba_first_run_cached_s": round(times[1], 2),
            "numba_compile_s": round(times[0] - times[1], 2)}


if __name__ == "__main__":
    main(sys.argv[1:])
