"""Where the diagnosis's fits run: in this process, or on worker processes.

A fit (``fit.fit``) is a pure function of its inputs, so the selection (``select.py``,
``horizon.py``) submits every fit one step of it needs at once — all folds of all effects —
and collects them in its own order: the outcome is the same bit for bit whatever the number
of workers (a test holds it). With one job nothing is submitted anywhere: a fit runs when its
result is first asked for, in the order the selection asks, as it always did.

Workers are forked (``multiprocessing`` "fork" start method), so they see what this process
has: effects registered at run time (``effects.register``) included. Where fork is not
available (Windows), or with ``jobs=1``, fits run in this process. A fit's inputs are pickled
here, when it is submitted: inputs that do not pickle (a registered effect whose parameter
class is defined inside a function) run that fit here, with a warning. Pickled later, in the
executor's feeder thread, such a failure can leave Python 3.11's executor waiting forever at
shutdown.

Inside a :class:`Workers` context the BLAS libraries (numpy's and scipy's OpenBLAS) run on one
thread, in this process and in the workers (``threadpoolctl``): a fit's matrices are small,
so threads buy little and cost much (two OpenBLAS threads per process made a 5-minute log's
diagnosis slower, and several processes each with its own threads, contending for the same
cores, slower still; README), and how a threaded BLAS splits a sum depends on the machine's
core count, which would make the standard errors differ in their last digits from machine to
machine.
"""

from __future__ import annotations

import multiprocessing
import os
import pickle
import warnings
from collections.abc import Mapping
from concurrent.futures import Future, ProcessPoolExecutor

import numpy as np
from threadpoolctl import threadpool_limits

from slipenv.diagnose.effects import Term
from slipenv.diagnose.fit import Fit, Problem, fit


def available_cores() -> int:
    """Cores this process may run on (its CPU affinity where the OS has one)."""
    if hasattr(os, "sched_getaffinity"):
        return max(len(os.sched_getaffinity(0)), 1)
    return max(os.cpu_count() or 1, 1)


def check_jobs(jobs: object, option: str = "jobs") -> int:
    """``jobs`` as a count of worker processes, or a ``ValueError`` naming ``option``."""
    if isinstance(jobs, bool) or not isinstance(jobs, (int, np.integer)) or jobs < 1:
        raise ValueError(f"{option} must be a whole number of processes >= 1, got {jobs!r}")
    return int(jobs)


class _Later:
    """A fit run in this process when its result is first asked for (then kept)."""

    def __init__(self, *args) -> None:
        self._args: tuple | None = args
        self._value: Fit | None = None
        self._error: BaseException | None = None

    def result(self) -> Fit:
        if self._args is not None:
            args, self._args = self._args, None
            try:
                self._value = fit(*args)
            except Exception as exc:  # raised again to every caller, as a future does
                self._error = exc
        if self._error is not None:
            raise self._error
        assert self._value is not None  # fit() returned it, or raised above
        return self._value


def _fit_pickled(blob: bytes) -> Fit:
    """A worker's task: ``fit`` of the pickled arguments."""
    return fit(*pickle.loads(blob))


def one_blas_thread() -> threadpool_limits:
    """BLAS on one thread until the returned context ends (module doc)."""
    return threadpool_limits(1, user_api="blas")


class Workers:
    """Runs fits: here (``jobs=1``) or on ``jobs`` forked worker processes.

    Use as a context manager: inside it BLAS runs on one thread (module doc); the worker
    processes exist only inside it, so none outlives it. Outside a context, fits run here,
    with BLAS as the caller has it.
    """

    def __init__(self, jobs: int = 1) -> None:
        self.jobs = check_jobs(jobs)
        self._pool: ProcessPoolExecutor | None = None
        self._limits = None

    def fit(self, problem: Problem, effects: tuple[str, ...], index: np.ndarray | None = None,
            start: Mapping[str, Term] | None = None) -> Future | _Later:
        """``fit.fit(problem, effects, index, start)``, submitted: ``.result()`` gives it."""
        args = (problem, effects, index, start)
        if self._pool is None:
            return _Later(*args)
        try:
            blob = pickle.dumps(args, protocol=pickle.HIGHEST_PROTOCOL)
        except (pickle.PicklingError, AttributeError, TypeError) as exc:
            warnings.warn(f"a fit of {'+'.join(effects)} runs in this process: its inputs "
                          f"cannot be sent to a worker ({exc})", RuntimeWarning, stacklevel=2)
            return _Later(*args)
        return self._pool.submit(_fit_pickled, blob)

    def __enter__(self) -> Workers:
        self._limits = one_blas_thread()
        if self.jobs > 1 and "fork" in multiprocessing.get_all_start_methods():
            self._pool = ProcessPoolExecutor(self.jobs,
                                             mp_context=multiprocessing.get_context("fork"),
                                             initializer=one_blas_thread)
        return self

    def __exit__(self, *exc) -> None:
        """End the worker processes (fits not started are cancelled), restore BLAS."""
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None
        if self._limits is not None:
            self._limits.restore_original_limits()
            self._limits = None


INLINE = Workers(1)  # outside a context: every fit here, when asked for
