"""The cores a computation of this process may use: the CPUs the process may run on, within
the thread budget of the work that runs it (:func:`thread_budget`: a sweep gives each case on a
Dask worker one thread, as it gives it one BLAS thread, so the workers do not oversubscribe the
machine)."""

from __future__ import annotations

import contextvars
import os
from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["available_cores", "thread_budget"]

_BUDGET: contextvars.ContextVar[int | None] = contextvars.ContextVar("pimodel_thread_budget",
                                                                     default=None)


def available_cores() -> int:
    """Cores this process may use: ``len(os.sched_getaffinity(0))`` where available, else
    ``os.cpu_count()``, at most the budget of an enclosing :func:`thread_budget`; at least 1.

    Examples
    --------
    >>> available_cores() >= 1
    True
    >>> with thread_budget(1):
    ...     available_cores()
    1
    """
    try:
        n = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):  # pragma: no cover - not on Linux
        n = os.cpu_count() or 1
    budget = _BUDGET.get()
    return max(1, n if budget is None else min(n, budget))


@contextmanager
def thread_budget(threads: int) -> Iterator[None]:
    """Within the block (this thread or task's context), :func:`available_cores` is at most
    ``threads``: what the library's own thread pools default to (e.g.
    :func:`pimodel.diagnosis.diagnose`'s ``workers``).

    Parameters
    ----------
    threads : int
        Threads the work in the block may use, at least 1.

    Raises
    ------
    ValueError
        ``threads`` not an integer >= 1.

    Examples
    --------
    >>> with thread_budget(1):
    ...     with thread_budget(3):
    ...         available_cores() <= 3
    True
    """
    if isinstance(threads, bool) or not isinstance(threads, int) or threads < 1:
        raise ValueError(f"threads: expected an integer >= 1, got {threads!r}")
    token = _BUDGET.set(threads)
    try:
        yield
    finally:
        _BUDGET.reset(token)
