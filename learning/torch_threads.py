"""Torch's intra-op thread count, set for one call and restored after it.

``torch.set_num_threads`` acts on the whole process; :func:`torch_threads` scopes it to a
``with`` block, the way ``threadpoolctl.threadpool_limits`` scopes BLAS threads, so that a
training call or a quotient pass leaves the process as it found it, also when it raises.
"""

from __future__ import annotations

from contextlib import contextmanager
from typing import Iterator

__all__ = ["torch_threads"]


@contextmanager
def torch_threads(n: int | None) -> Iterator[None]:
    """Run the block with ``n`` torch threads (``None``: leave the count as it is), then restore it."""
    import torch

    if n is None:
        yield
        return
    if int(n) < 1:
        raise ValueError(f"the number of torch threads must be >= 1, got {n}")
    before = torch.get_num_threads()
    torch.set_num_threads(int(n))
    try:
        yield
    finally:
        torch.set_num_threads(before)
