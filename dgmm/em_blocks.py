"""Row blocks for EM over many primitives: bounded memory, several threads, sums in a fixed order.

Of the ``(n_components, n_prims)`` responsibilities an EM iteration needs only their product with the moment
table, ``resp · moments`` of shape ``(n_components, 10)``, and each primitive's log-normaliser.
:class:`BlockPass` computes such products block by block of primitives, so memory holds one
``(n_components, rows)`` block per thread, never the whole matrix.

An input whose responsibilities fit in the memory limit is one block, computed exactly as without blocks (every
fit of the paper sweep is). A larger one streams in blocks of :data:`CACHE_BLOCK_BYTES`: EM's passes over a
block then stay in the CPU cache, which makes them several times faster than over one large block, and each
block is enough work that the threads' hand-offs between blocks cost little beside it. Blocks depend only on
the input size, ``n_components`` and the memory limit, and their partial sums are added in block order, so
the thread count never changes a bit of the result.
"""
from __future__ import annotations

import os
import threading
from concurrent.futures import ThreadPoolExecutor
from contextlib import ExitStack

import numpy as np

DEFAULT_MEMORY_LIMIT = 128 * 2**20
"""Bytes of responsibilities (and their row features) that may be held at once: larger inputs stream."""
CACHE_BLOCK_BYTES = 8 * 2**20
"""Bytes of one streamed block: large enough that two threads gain nearly 2x over one (every block costs a few GIL
and futex hand-offs between the threads), small enough to stream (measured: docs/studies/odometry_constants.md)."""
ROW_FLOATS = 24
"""float64 per row beside the responsibilities in 3-D: E-step features (11), weighted moments (10), row sums; in
dimension d, 2 (d(d+1)/2 + d + 2) + 2."""

_controller = None


def _blas_controller():
    """A threadpoolctl controller, made once: ``controller.limit`` is then cheap enough to use per fit."""
    global _controller
    if _controller is None:
        from threadpoolctl import ThreadpoolController
        _controller = ThreadpoolController()
    return _controller


def block_rows(n_rows, n_components, memory_limit, row_floats=ROW_FLOATS):
    """Rows per block: all ``n_rows`` if they fit in ``memory_limit`` bytes, else as many as
    ``min(memory_limit, CACHE_BLOCK_BYTES)`` bytes hold (at least 1); a row holds ``n_components + row_floats``
    float64."""
    row_bytes = 8 * (n_components + row_floats)
    if n_rows * row_bytes <= memory_limit:
        return n_rows
    return int(max(1, min(memory_limit, CACHE_BLOCK_BYTES) // row_bytes))


def n_threads(n_jobs):
    """Threads for scikit-learn's ``n_jobs``: None is 1, -1 every CPU, -2 all but one, ..."""
    if n_jobs is None:
        return 1
    if n_jobs < 0:
        return max(1, (os.cpu_count() or 1) + 1 + n_jobs)
    return n_jobs


class BlockPass:
    """Runs a function over the row blocks of an input on ``n_jobs`` threads and sums its results in block order.

    Use as a context manager: inside it BLAS runs one thread per caller (the threads here are the parallelism),
    and ``run`` may be called once per EM iteration, reusing each thread's block buffer.

    Parameters
    ----------
    n_rows, n_components : int
    memory_limit : int
        Bytes of responsibilities that may be held at once; see :func:`block_rows`.
    n_jobs : int or None
        Threads, as scikit-learn's ``n_jobs``.
    row_floats : int, default=ROW_FLOATS
        float64 per row beside the responsibilities (:data:`ROW_FLOATS`).
    """

    def __init__(self, n_rows, n_components, memory_limit, n_jobs, row_floats=ROW_FLOATS):
        rows = block_rows(n_rows, n_components, memory_limit, row_floats)
        self.blocks = [slice(start, min(start + rows, n_rows)) for start in range(0, n_rows, rows)]
        self._shape = (n_components, min(rows, n_rows))
        self._threads = min(n_threads(n_jobs), len(self.blocks))
        self._local = threading.local()
        self._executor = None

    def __enter__(self):
        self._stack = ExitStack()
        self._stack.enter_context(_blas_controller().limit(limits=1, user_api="blas"))
        if self._threads > 1:
            self._executor = self._stack.enter_context(ThreadPoolExecutor(self._threads))
        return self

    def __exit__(self, *exc_info):
        self._executor = None
        return self._stack.__exit__(*exc_info)

    @property
    def threaded(self):
        """Whether :meth:`run` hands the blocks to threads (inside the context, with more than one)."""
        return self._executor is not None

    def _buffer(self, rows):
        """This thread's (n_components, rows) block buffer, contiguous, allocated once (fresh pages cost as much
        as the products written into them)."""
        buffer = getattr(self._local, "buffer", None)
        if buffer is None:
            buffer = self._local.buffer = np.empty(self._shape[0] * self._shape[1])
        return buffer[: self._shape[0] * (rows.stop - rows.start)].reshape(self._shape[0], -1)

    def run(self, function, threads=True):
        """``Σ_blocks function(rows, out)`` added in block order; ``out`` is a free, C-contiguous (n_components,
        n_rows_in_block) buffer. ``threads=False`` runs the blocks in order on the calling thread (for functions
        that draw from a random generator)."""
        call = lambda rows: function(rows, self._buffer(rows))  # noqa: E731
        if threads and self._executor is not None:
            parts = self._executor.map(call, self.blocks)
        else:
            parts = map(call, self.blocks)
        total = None
        for part in parts:
            total = part if total is None else total + part
        return total
