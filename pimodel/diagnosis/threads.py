"""Threads for the diagnosis: its independent fits on a pool of threads in one process, the
results taken in the serial order (issue 31, the wall-time goal).

The heavy work of a fit is NumPy (BLAS and ufuncs release the GIL on large arrays) and the C
core through ctypes (``ctypes.CDLL`` releases it during each call), so two threads can keep two
cores busy. What a fit memoises on objects that the threads share is kept per thread
(:func:`per_thread`), so no thread sees another's half-built memo and each thread's
``release()`` drops its own. :class:`Pool` with one worker runs everything inline, in the
caller's order: the serial path, unchanged.

A fit that runs while a thread of the pool is idle lends it small pieces of its own work
(:func:`lend`): the points of a search (:func:`helped_map`) and the next chunk of a pass over a
record (:func:`read_ahead`). Either is a call queued on the pool that the caller cancels and
does itself when no thread has started it, so the caller never waits for work that has not
begun, and the results are taken in the caller's order: the same values as on one thread.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from contextlib import contextmanager

from ..cores import available_cores

__all__ = ["Pool", "OnceCache", "per_thread", "default_workers", "lend", "helped_map",
           "read_ahead"]

MAX_DEFAULT_WORKERS = 2  # the default pool: the cores, at most this many


def default_workers() -> int:
    """The default number of threads of a diagnosis: the cores this process may use
    (:func:`pimodel.cores.available_cores`: within a sweep's case on a Dask worker, one), at
    most ``MAX_DEFAULT_WORKERS``.

    Examples
    --------
    >>> 1 <= default_workers() <= MAX_DEFAULT_WORKERS
    True
    """
    return min(MAX_DEFAULT_WORKERS, available_cores())


def per_thread(name: str, factory: Callable[[], object]) -> property:
    """A property whose value is kept per thread (in the instance's ``_threads``, a
    ``threading.local`` created on first use), starting at ``factory()`` in each thread.

    Examples
    --------
    >>> class Memo:
    ...     cache = per_thread("cache", dict)
    >>> m = Memo(); m.cache["a"] = 1
    >>> out = []
    >>> t = threading.Thread(target=lambda: out.append(dict(m.cache))); t.start(); t.join()
    >>> m.cache, out
    ({'a': 1}, [{}])
    """
    def local(self) -> threading.local:
        loc = self.__dict__.get("_threads")
        if loc is None:
            loc = self.__dict__.setdefault("_threads", threading.local())
        return loc

    def get(self):
        loc = local(self)
        try:
            return getattr(loc, name)
        except AttributeError:
            value = factory()
            setattr(loc, name, value)
            return value

    def set_(self, value) -> None:
        setattr(local(self), name, value)

    return property(get, set_)


def drop_threads(state: dict) -> dict:
    """``state`` (an instance's ``__dict__``) without its per-thread memos, for pickling and
    copying (a ``threading.local`` is neither; the memos are rebuilt on use)."""
    return {k: x for k, x in state.items() if k != "_threads"}


class Pool:
    """``workers`` threads for independent calls; one worker: every call inline, in order.

    Examples
    --------
    >>> with Pool(2) as pool:
    ...     pool.map(lambda x: x * x, [1, 2, 3]), pool.submit(sum, [1, 2]).result()
    ([1, 4, 9], 3)
    """

    def __init__(self, workers: int):
        self.workers = int(workers)
        self._executor = self._threads()

    def map(self, fn: Callable, items: Iterable) -> list:
        """``[fn(x) for x in items]``, the calls spread over the threads, results in order."""
        if self._executor is None:
            return [fn(x) for x in items]
        return list(self._executor.map(fn, items))

    def submit(self, fn: Callable, *args) -> Future:
        """``fn(*args)`` on a thread (one worker: called now); its Future."""
        if self._executor is not None:
            return self._executor.submit(fn, *args)
        f: Future = Future()
        f.set_result(fn(*args))
        return f

    def close(self) -> None:
        """Wait for the calls under way and end the threads."""
        if self._executor is not None:
            self._executor.shutdown(wait=True, cancel_futures=True)

    def renew(self) -> None:
        """End the threads, and with them what they memoised per thread (:func:`per_thread`),
        then start fresh ones.

        Examples
        --------
        >>> with Pool(2) as pool:
        ...     pool.renew(); pool.map(abs, [-1, 2])
        [1, 2]
        """
        self.close()
        self._executor = self._threads()

    def _threads(self) -> ThreadPoolExecutor | None:
        return ThreadPoolExecutor(self.workers, thread_name_prefix="pimodel-diagnose") \
            if self.workers > 1 else None

    def __enter__(self) -> Pool:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


_LENT = threading.local()  # the pool lent to this thread's calls (lend)


@contextmanager
def lend(pool: Pool) -> Iterator[None]:
    """Within the block, :func:`helped_map` and :func:`read_ahead` on this thread may hand
    work to ``pool``'s idle threads (the pool of the diagnosis that makes this call; restored
    on exit).

    Examples
    --------
    >>> with Pool(2) as pool, lend(pool):
    ...     helped_map(lambda x: x + 1, [1, 2, 3])
    [2, 3, 4]
    """
    before = getattr(_LENT, "pool", None)
    _LENT.pool = pool
    try:
        yield
    finally:
        _LENT.pool = before


def helped_map(fn: Callable, items: Iterable) -> list:
    """``[fn(x) for x in items]``, results in order, the calling thread taking the items one by
    one while the threads of the pool lent to it (:func:`lend`) that are idle take some too.

    The caller never waits for a helper that has not started: a helper is a call queued on the
    pool behind the batch under way, so it starts only when a thread has nothing else to do
    (the tail of a batch, a long fit alone); once the caller has taken the last item, the
    helpers not yet started are cancelled and it waits only for the items helpers are
    computing. So no deadlock with :class:`OnceCache` (a thread waiting for this very call is
    never needed to finish it), and without a lent pool, or with one worker, this is the plain
    loop. ``fn`` must give the same result on any thread (no per-thread state in its result)."""
    items = list(items)
    pool = _lent_pool()
    if pool is None or len(items) < 2:
        return [fn(x) for x in items]
    results: list = [None] * len(items)
    lock = threading.Lock()
    state = {"next": 0, "stop": False}
    # what the helpers reach, dropped once the map is done: a cancelled helper stays queued
    # on the pool until a thread takes it, and would keep the results alive until then
    job = {"fn": fn, "items": items, "results": results}
    n = len(items)

    def take() -> int | None:
        with lock:
            i = state["next"]
            if state["stop"] or i >= n:
                return None
            state["next"] = i + 1
            return i

    def work() -> None:
        while (i := take()) is not None:
            job["results"][i] = job["fn"](job["items"][i])

    helpers = [h for h in (_queued(pool, work) for _ in range(pool.workers - 1)) if h]
    try:
        work()
    finally:
        with lock:
            state["stop"] = True
        try:
            for h in helpers:
                if not h.cancel():
                    h.result()  # running: it ends with the item it holds
        finally:
            job.clear()
    return results


def read_ahead(items: Iterable) -> Iterator:
    """The items of ``items`` in order, each next item made on an idle thread of the pool lent
    to this thread (:func:`lend`) while the caller works on the one before: a pass over a long
    record whose chunks of play outputs (the C core) are made beside the caller's sums over the
    chunk before.

    The item ahead is a call queued on the pool; when the caller wants it and no thread has
    started it, the caller cancels it and makes the item itself, so it never waits for a call
    that has not started (no deadlock with :class:`OnceCache`), and ``items`` is never advanced
    by two threads at once. Without a lent pool, or with one worker, the plain iteration. The
    pool is the one lent when this is called. ``items`` must give the same items on any thread.

    Examples
    --------
    >>> with Pool(2) as pool, lend(pool):
    ...     list(read_ahead(x * x for x in range(4)))
    [0, 1, 4, 9]
    """
    pool = _lent_pool()
    it = iter(items)
    return it if pool is None else _ahead(it, pool)


def _lent_pool() -> Pool | None:
    """The pool lent to this thread (:func:`lend`) when it has threads of its own, else None."""
    pool = getattr(_LENT, "pool", None)
    return None if pool is None or pool._executor is None else pool


def _queued(pool: Pool, fn: Callable) -> Future | None:
    """``fn()`` queued on the pool's threads; None when the pool is closing (no thread will
    take it: the caller does the work alone)."""
    try:
        return pool._executor.submit(fn)
    except RuntimeError:
        return None


def _ahead(it: Iterator, pool: Pool) -> Iterator:
    done = object()
    # the items reached through a cell emptied at the end: a cancelled read stays queued on
    # the pool until a thread takes it, and would keep the iterator (its last item) alive
    cell = [it]

    def next_item():
        return next(cell[0], done)

    def submit() -> Future | None:
        return _queued(pool, next_item)

    ahead = submit()
    try:
        while True:
            item = next_item() if ahead is None or ahead.cancel() else ahead.result()
            ahead = None
            if item is done:
                return
            ahead = submit()
            yield item
    finally:
        if ahead is not None and not ahead.cancel():
            ahead.exception()  # running: wait for it to end before the items are dropped
        cell.clear()


class OnceCache:
    """A memo whose every key is computed once: a thread asking for a key another thread is
    computing waits for that result (no fit made twice, none with a half-filled memo).

    Examples
    --------
    >>> c = OnceCache(); calls = []
    >>> c.get("k", lambda: calls.append(1) or 7), c.get("k", lambda: 0), calls
    (7, 7, [1])
    """

    def __init__(self):
        self._lock = threading.Lock()
        self._entries: dict = {}

    def __contains__(self, key) -> bool:
        return key in self._entries

    def get(self, key, compute: Callable[[], object]):
        """The value of ``key``, from ``compute()`` the first time (exceptions not kept)."""
        with self._lock:
            entry = self._entries.get(key)
            mine = entry is None
            if mine:
                entry = self._entries[key] = Future()
        if mine:
            try:
                entry.set_result(compute())
            except BaseException as exc:
                with self._lock:
                    del self._entries[key]
                entry.set_exception(exc)
                raise
        return entry.result()
