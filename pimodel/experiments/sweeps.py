"""Monte Carlo sweeps: one function mapped over a list of cases, serially or on Dask.

A sweep is a list of *cases*, each a plain dict of JSON values (str, int, float, bool, None,
lists and dicts of these) that carries everything the case needs, its seed included, and one
*case function* ``f(params) -> result`` (a JSON-able dict or list). The case function seeds its
own generators from ``params`` and never reads shared state, so a case gives the same numbers
wherever it runs: in this process (``workers=0``, Dask not imported), on a local cluster of
worker processes (``workers=N``) or on an existing cluster (``scheduler=ADDRESS``, e.g. one
started by dask-jobqueue or dask-kubernetes).

Every case runs with one BLAS/OpenMP thread (threadpoolctl), in every mode, so that a worker
process uses one core and the floating-point sums do not depend on the thread count. Workers
are processes, not threads: the compiled core releases the GIL only inside its ctypes calls,
while the estimator and diagnosis spend much of their time in Python and NumPy glue.

With ``cache_dir`` each finished case is written to ``cache_dir/<key>.json`` (``key`` a hash of
its params) as soon as it finishes; a rerun loads those and computes only the missing cases,
so a sweep killed halfway resumes; a file that is unreadable or not the case's is computed
again, never trusted. Ctrl-C (SIGINT) stops the workers (they ignore SIGINT themselves, so they
print nothing) and raises :class:`Interrupted`, which says how many cases are kept. Results
are JSON round-tripped whether computed or loaded, so both give identical values, and they come
back in case order.
"""

from __future__ import annotations

import gc
import hashlib
import json
import os
import random
import threading
import time
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager, nullcontext
from functools import partial
from itertools import product
from pathlib import Path

import numpy as np

from ..cores import available_cores, thread_budget

# Per-worker memory limit of the local cluster. A case keeps its records chunked (the long
# estimator records are made and consumed in chunks of a few MB); the largest study case
# (sim_to_real, two 2.5 s records at 10 kHz and the diagnosis' fits) peaks well under 0.5 GiB
# of worker memory, so 2 GiB leaves room for users' larger records. Dask pauses a worker at
# 80 % and restarts it at 95 %; a case that keeps exceeding it fails with KilledWorker.
DEFAULT_MEMORY_LIMIT = "2GiB"

# Dask's nanny sets MALLOC_TRIM_THRESHOLD_=65536 in its workers, which also switches off glibc's
# dynamic mmap threshold: every array above 128 KiB is then mmap'd and unmapped afresh. A
# sim_to_real case then spends about as much CPU in the kernel (page faults) as in user code:
# 71 M minor faults and stime/utime = 0.8 in a worker, measured. Larger thresholds keep the
# case's working arrays (up to 16 MiB) on the heap; memory still returns to the system above
# 64 MiB of free heap top. glibc reads them once, at process start, so they must go into the
# nanny's *pre-spawn* environment (``distributed.nanny.pre-spawn-environ``); LocalCluster's
# ``env=`` is applied after the worker started and has no effect on them. The nanny also prefers
# a variable already in the parent's ``os.environ`` to that config, and writes its pre-spawn
# environment into the parent's ``os.environ`` for good: after any earlier Dask cluster in the
# process (Dask's default 65536 is then in ``os.environ``) the config alone is ignored. So the
# local cluster is started with WORKER_ENV in ``os.environ`` too, and the parent's own values
# are put back afterwards.
WORKER_ENV = {"MALLOC_MMAP_THRESHOLD_": str(16 * 2**20), "MALLOC_TRIM_THRESHOLD_": str(64 * 2**20)}

__all__ = [
    "DEFAULT_MEMORY_LIMIT",
    "WORKER_ENV",
    "CaseFailed",
    "Interrupted",
    "available_cores",
    "case_key",
    "grid",
    "plain",
    "random_cases",
    "run_cases",
    "tidy_rows",
    "write_table",
]


class CaseFailed(RuntimeError):
    """A case function raised; the message names the case, its params and the kept results.

    Parameters
    ----------
    message : str
        What failed, which case, and how many finished cases were kept.
    index : int
        Position of the failing case in the case list.
    params : dict
        The failing case's parameters.

    Attributes
    ----------
    index : int
        Position of the failing case in the case list.
    params : dict
        The failing case's parameters.

    Examples
    --------
    >>> err = CaseFailed("case 2 of 5 failed", 1, {"seed": 1})
    >>> err.index, err.params
    (1, {'seed': 1})
    """

    def __init__(self, message: str, index: int, params: dict):
        super().__init__(message)
        self.index = index
        self.params = params


class Interrupted(KeyboardInterrupt):
    """Ctrl-C stopped a sweep; ``str()`` is one line with the cases kept and how to resume.

    Parameters
    ----------
    kept : int
        Cases finished (computed or reused) and kept in ``folder``.
    total : int
        Cases of the sweep.
    folder : path or None
        The cache folder (None: nothing kept).

    Examples
    --------
    >>> print(Interrupted(5, 12, "out/cases"))
    interrupted: 5 of 12 cases kept in out/cases; rerun the same command to resume
    """

    def __init__(self, kept: int, total: int, folder):
        self.kept, self.total, self.folder = kept, total, folder
        where = (f"kept in {folder}; rerun the same command to resume" if folder is not None
                 else "finished, none kept (no cache folder)")
        super().__init__(f"interrupted: {kept} of {total} cases {where}")


def plain(x):
    """``x`` with NumPy scalars/arrays, tuples and paths turned into JSON values.

    Parameters
    ----------
    x : object
        Nested dicts, lists, tuples, NumPy arrays and scalars, paths and JSON values.

    Returns
    -------
    object
        The same structure made of dicts (string keys), lists, str, int, float, bool, None.

    Examples
    --------
    >>> plain({"a": np.arange(2), 1: (np.float64(0.5),)})
    {'a': [0, 1], '1': [0.5]}
    """
    if isinstance(x, Mapping):
        return {str(k): plain(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [plain(v) for v in x]
    if isinstance(x, np.ndarray):
        return plain(x.tolist())
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, Path):
        return str(x)
    return x


def case_key(params: Mapping) -> str:
    """A 16-hex-digit hash of the case's params (key order does not matter).

    Parameters
    ----------
    params : dict
        The case's parameters (JSON values).

    Returns
    -------
    str
        The name of the case's file in the cache folder, without ``.json``.

    Examples
    --------
    >>> case_key({"seed": 1, "snr": 20}) == case_key({"snr": 20, "seed": 1})
    True
    """
    text = json.dumps(params, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _check_cases(cases) -> list[dict]:
    if isinstance(cases, Mapping) or not isinstance(cases, Iterable):
        raise ValueError(f"cases: expected a list of parameter dicts, got {type(cases).__name__}")
    cases = list(cases)
    seen: dict[str, int] = {}
    for i, p in enumerate(cases):
        if not isinstance(p, Mapping):
            raise ValueError(f"cases[{i}]: expected a dict of parameters, got "
                             f"{type(p).__name__}")
        try:
            same = json.loads(json.dumps(p)) == p
        except (TypeError, ValueError) as exc:
            raise ValueError(f"cases[{i}]: parameters must be plain JSON values (str, int, "
                             f"float, bool, None, lists, dicts): {exc}") from None
        if not same:
            raise ValueError(f"cases[{i}]: parameters must be plain JSON values (lists, not "
                             f"tuples; str keys), got {p!r}")
        key = case_key(p)
        if key in seen:
            raise ValueError(f"cases[{i}] repeats cases[{seen[key]}] ({p!r}); give each case "
                             f"its own seed")
        seen[key] = i
    return [dict(p) for p in cases]


def _call_case(func: Callable, params: dict, threads: int | None = None):
    """Run one case with one BLAS thread; the result as JSON values (runs on the worker).

    ``threads``: the case's thread budget (:func:`pimodel.cores.thread_budget`; what the
    library's own thread pools, such as the diagnosis', default to); 1 on Dask workers, which
    run one case per core; None in the serial path (the process' cores).

    The garbage of the case is collected before the next one: reference cycles (closures over
    their caches, caught exceptions' frames) can hold a case's arrays, and Python's collector
    counts objects, not bytes, so it ran too rarely for a worker that does many cases in a row
    (``sim_to_real`` workers grew to 2 GiB and Dask paused them; with the collection a worker
    stays at a case's own peak, a few hundred MB).
    """
    from threadpoolctl import threadpool_limits

    try:
        with threadpool_limits(limits=1), (nullcontext() if threads is None
                                           else thread_budget(threads)):
            result = func(dict(params))
        return json.loads(json.dumps(plain(result)))
    finally:
        gc.collect()


class _Cache:
    """The finished cases of a sweep, one JSON file each (``None``: keep nothing)."""

    def __init__(self, folder, fresh: bool):
        self.folder = None if folder is None else Path(folder)
        self.fresh = fresh
        if self.folder is not None:
            self.folder.mkdir(parents=True, exist_ok=True)

    def load(self, params: dict):
        """The stored result of ``params``, or ``None`` when absent, unreadable or other."""
        if self.folder is None or self.fresh:
            return None
        path = self.folder / f"{case_key(params)}.json"
        try:
            data = json.loads(path.read_text())
        except (OSError, ValueError):
            return None
        if not isinstance(data, dict) or data.get("params") != params or "result" not in data:
            return None
        return (data["result"],)

    def store(self, params: dict, result) -> None:
        if self.folder is None:
            return
        path = self.folder / f"{case_key(params)}.json"
        tmp = path.with_suffix(f".tmp{os.getpid()}")
        tmp.write_text(json.dumps({"params": params, "result": result}, indent=1))
        os.replace(tmp, path)  # atomic: a killed sweep never leaves half a file


def _failure(i: int, params: dict, n: int, exc: BaseException, cache: _Cache, done: int):
    kept = (f"; {done} finished cases kept in {cache.folder}, a rerun computes only the rest"
            if cache.folder is not None else "")
    return CaseFailed(f"case {i} of {n} failed with {type(exc).__name__}: {exc}; params: "
                      f"{json.dumps(params)}{kept}", i, params)


def _progress(total: int, initial: int, desc: str, show: bool):
    from tqdm import tqdm

    return tqdm(total=total, initial=initial, desc=desc, unit="case",
                disable=None if show else True)


def run_cases(func: Callable[[dict], object], cases: Sequence[dict], *,
              workers: int | None = None, scheduler: str | None = None, cache_dir=None,
              fresh: bool = False, memory_limit: str | None = DEFAULT_MEMORY_LIMIT,
              progress: bool = True, desc: str = "cases", counts: dict | None = None) -> list:
    """Compute ``func(params)`` for every case; results in case order.

    Parameters
    ----------
    func : callable
        The case function, ``func(params) -> result``. It must seed its own generators from
        ``params``. On Dask it is pickled to the workers (by reference when importable, else
        by value with cloudpickle); ``result`` must be JSON-able after :func:`plain`.
    cases : list of dict
        The cases, plain JSON values, each distinct (vary the seed).
    workers : int or None
        ``0``: run here, serially, without importing Dask. ``N > 0``: start a local cluster of
        ``N`` single-threaded worker processes. ``None``: the number of usable cores.
    scheduler : str or None
        Address of a running Dask scheduler (``tcp://host:8786``); used instead of a local
        cluster. Give either ``scheduler`` or ``workers``, not both.
    cache_dir : path or None
        Folder for the finished cases (``<key>.json``, see :func:`case_key`). Cases found
        there are loaded, not recomputed.
    fresh : bool
        Recompute every case even when the cache has it (and overwrite it).
    memory_limit : str or None
        Memory limit per local worker process (Dask syntax, ``"2GiB"``); ``None``: the
        machine's memory divided by the workers.
    progress : bool
        Show a progress bar over the cases (on a terminal).
    desc : str
        Label of the progress bar.
    counts : dict, optional
        Filled with ``"reused"`` (loaded from ``cache_dir``) and ``"computed"`` (run now)
        case counts, also when the sweep fails or is interrupted.

    Returns
    -------
    list
        ``[func(cases[0]), func(cases[1]), ...]`` as JSON values.

    Raises
    ------
    ValueError
        Bad ``cases``, ``workers`` or both ``workers`` and ``scheduler``.
    CaseFailed
        A case raised; the message names it and its params. Finished cases stay in
        ``cache_dir``; the remaining ones are cancelled.
    Interrupted
        Ctrl-C (a ``KeyboardInterrupt``): the workers are stopped, finished cases kept.

    Examples
    --------
    >>> def square(p):
    ...     return {"y": p["x"] ** 2}
    >>> run_cases(square, [{"x": 1}, {"x": 3}], workers=0, progress=False)
    [{'y': 1}, {'y': 9}]
    """
    if not callable(func):
        raise ValueError(f"func: expected a callable case function, got {type(func).__name__}")
    cases = _check_cases(cases)
    if scheduler is not None and workers is not None:
        raise ValueError(f"workers={workers} and scheduler={scheduler!r}: give one of them")
    if workers is None and scheduler is None:
        workers = available_cores()
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or workers < 0):
        raise ValueError(f"workers: expected an integer >= 0, got {workers!r}")
    cache = _Cache(cache_dir, fresh)
    results: list = [None] * len(cases)
    todo = []
    for i, p in enumerate(cases):
        hit = cache.load(p)
        if hit is None:
            todo.append(i)
        else:
            results[i] = hit[0]
    reused = len(cases) - len(todo)
    counts = {} if counts is None else counts
    counts.update(reused=reused, computed=0)
    bar = _progress(len(cases), reused, desc, progress)
    try:
        if not todo:
            pass
        elif workers == 0:
            _run_serial(func, cases, todo, results, cache, bar, counts)
        else:
            _run_dask(func, cases, todo, results, cache, bar, workers, scheduler, memory_limit,
                      counts)
    except KeyboardInterrupt:
        bar.close()
        raise Interrupted(reused + counts["computed"], len(cases), cache.folder) from None
    finally:
        bar.close()
    return results


def _run_serial(func, cases, todo, results, cache, bar, counts) -> None:
    for done, i in enumerate(todo):
        try:
            results[i] = _call_case(func, cases[i])
        except Exception as exc:
            raise _failure(i, cases[i], len(cases), exc, cache, len(cases) - len(todo) + done) \
                from exc
        cache.store(cases[i], results[i])
        counts["computed"] += 1
        bar.update()


def _start_local_cluster(workers: int, memory_limit):
    """A LocalCluster of single-threaded worker processes that ignore SIGINT (Ctrl-C stops
    them through this process, without their tracebacks)."""
    import logging
    import signal
    import threading

    import dask
    from dask.distributed import LocalCluster

    # processes, one thread each: the Python glue of a case holds the GIL
    spawn_env = {**dask.config.get("distributed.nanny.pre-spawn-environ", {}), **WORKER_ENV}
    saved = {k: os.environ.get(k) for k in WORKER_ENV}
    os.environ.update(WORKER_ENV)
    main = threading.current_thread() is threading.main_thread()
    handler = signal.signal(signal.SIGINT, signal.SIG_IGN) if main else None
    try:  # the nannies and workers inherit the ignored SIGINT
        with dask.config.set({"distributed.nanny.pre-spawn-environ": spawn_env}):
            # no dashboard; the scheduler's own HTTP server (health, metrics) on a free
            # local port, not 8787: a second sweep at once would warn "Port 8787 is in use"
            return LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                memory_limit=memory_limit, dashboard_address=None,
                                scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
                                silence_logs=logging.ERROR)
    finally:
        if main:
            signal.signal(signal.SIGINT, handler)
        for k, old in saved.items():
            if old is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = old


def _quiet_close(client, cluster, interrupted: bool) -> None:
    """Close the client and the local cluster; after Ctrl-C without Dask's log lines and
    without a second Ctrl-C cutting the shutdown short."""
    import contextlib
    import logging
    import signal
    import threading

    main = interrupted and threading.current_thread() is threading.main_thread()
    handler = signal.signal(signal.SIGINT, signal.SIG_IGN) if main else None
    log = logging.getLogger("distributed")
    level = log.level
    if interrupted:
        log.setLevel(logging.CRITICAL + 1)
    try:
        with contextlib.suppress(Exception) if interrupted else contextlib.nullcontext():
            client.close()
            if cluster is not None:
                cluster.close()
    finally:
        log.setLevel(level)
        if main:
            signal.signal(signal.SIGINT, handler)


def _run_dask(func, cases, todo, results, cache, bar, workers, scheduler, memory_limit,
              counts) -> None:
    from dask.distributed import Client

    cluster = _start_local_cluster(workers, memory_limit) if scheduler is None else None
    client = Client(cluster if cluster is not None else scheduler)
    interrupted = False
    try:
        run = partial(_call_case, func, threads=1)
        keys = [f"case-{i}-{case_key(cases[i])}" for i in todo]
        futures = client.map(run, [cases[i] for i in todo], key=keys, pure=False)
        index = dict(zip(keys, todo, strict=True))
        done = len(cases) - len(todo)
        with _deferred_sigint() as stop:
            for fut in _completed(futures, stop):
                i = index[fut.key]
                try:
                    results[i] = fut.result()
                except Exception as exc:
                    client.cancel(futures)
                    raise _failure(i, cases[i], len(cases), exc, cache, done) from exc
                cache.store(cases[i], results[i])
                counts["computed"] += 1
                done += 1
                bar.update()
    except KeyboardInterrupt:
        interrupted = True
        raise
    finally:
        _quiet_close(client, cluster, interrupted)


@contextmanager
def _deferred_sigint() -> Iterator[threading.Event]:
    """On the main thread, the first SIGINT only sets the event yielded (a second one gets the
    previous handler, which by default raises at once); elsewhere, or with SIGINT ignored or
    not handled in Python, an event never set.

    A ``KeyboardInterrupt`` raised inside Dask's own wait (a ``threading.Condition``) can leave
    its lock half released (``RuntimeError: cannot release un-acquired lock``), so the Dask loop
    polls this event between waits instead."""
    import signal

    stop = threading.Event()
    previous = signal.getsignal(signal.SIGINT)
    if threading.current_thread() is not threading.main_thread() or not callable(previous):
        yield stop
        return

    def on_sigint(signum, frame):
        stop.set()
        signal.signal(signal.SIGINT, previous)

    signal.signal(signal.SIGINT, on_sigint)
    try:
        yield stop
    finally:
        signal.signal(signal.SIGINT, previous)


def _completed(futures: list, stop: threading.Event) -> Iterator:
    """The futures as they finish, polled every 50 ms; ``KeyboardInterrupt`` once ``stop`` is
    set."""
    from dask.distributed import as_completed

    pending = as_completed(futures)
    while not pending.is_empty():
        if stop.is_set():
            raise KeyboardInterrupt
        batch = pending.next_batch(block=False)
        if not batch:
            time.sleep(0.05)  # not stop.wait: a second SIGINT may raise inside it
        yield from batch


def grid(**axes: Sequence) -> list[dict]:
    """All combinations of the given values (a full factorial grid), last axis fastest.

    Parameters
    ----------
    **axes : sequence
        ``name=[values...]`` for each swept parameter (JSON values).

    Returns
    -------
    list of dict
        One dict per combination.

    Raises
    ------
    ValueError
        An axis is not a non-empty sequence.

    Examples
    --------
    >>> grid(snr=[10, 20], seed=[0, 1])
    [{'snr': 10, 'seed': 0}, {'snr': 10, 'seed': 1}, {'snr': 20, 'seed': 0}, {'snr': 20, 'seed': 1}]
    """
    for name, values in axes.items():
        if isinstance(values, str | bytes) or not isinstance(values, Sequence) or not values:
            raise ValueError(f"{name}: expected a non-empty list of values, got {values!r}")
    names = list(axes)
    return [dict(zip(names, plain(list(combo)), strict=True))
            for combo in product(*axes.values())]


def random_cases(n: int, *, seed: int = 0, **ranges: tuple[float, float]) -> list[dict]:
    """``n`` cases drawn uniformly from ``name=(low, high)`` ranges, each with its own seed.

    Parameters
    ----------
    n : int
        Number of cases.
    seed : int
        Seed of the draw; case ``i`` gets ``"seed": seed + i`` for its own simulation.
    **ranges : (float, float)
        ``name=(low, high)`` with ``low <= high``.

    Returns
    -------
    list of dict
        ``n`` dicts with the drawn values and a ``"seed"``.

    Raises
    ------
    ValueError
        ``n < 1`` or a range that is not two numbers ``low <= high``.

    Examples
    --------
    >>> [sorted(c) for c in random_cases(2, noise_um=(0.003, 0.01))]
    [['noise_um', 'seed'], ['noise_um', 'seed']]
    """
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise ValueError(f"n: expected an integer >= 1, got {n!r}")
    for name, r in ranges.items():
        ok = isinstance(r, Sequence) and len(r) == 2 and all(
            isinstance(x, int | float) and not isinstance(x, bool) for x in r)
        if not ok or r[0] > r[1]:
            raise ValueError(f"{name}: expected a range (low, high) with low <= high, got {r!r}")
    rng = random.Random(seed)
    return [{**{name: rng.uniform(float(lo), float(hi)) for name, (lo, hi) in ranges.items()},
             "seed": seed + i} for i in range(n)]


def _flatten(prefix: str, x, row: dict) -> None:
    if isinstance(x, Mapping):
        for k, v in x.items():
            _flatten(f"{prefix}.{k}" if prefix else str(k), v, row)
    elif isinstance(x, list) and x and all(isinstance(v, int | float) for v in x):
        for j, v in enumerate(x, start=1):  # 1-based like r_hat[1]..r_hat[n]
            row[f"{prefix}[{j}]"] = v
    else:
        row[prefix] = x


def _cell_text(x) -> str:
    """``x`` as text for a table cell: strings as they are, other values as JSON."""
    return x if isinstance(x, str) else json.dumps(x)


def tidy_rows(cases: Sequence[dict], results: Sequence) -> list[dict]:
    """One flat row per case: its params, then its result (nested keys joined by ``.``).

    Parameters
    ----------
    cases : list of dict
        The cases.
    results : list
        Their results, in case order (dicts; other values go to a ``result`` column).

    Returns
    -------
    list of dict
        Flat rows; lists of numbers become columns ``name[1]``, ``name[2]``, ... and other
        lists (text, empty) a ``+``-joined text in column ``name``.

    Examples
    --------
    >>> tidy_rows([{"seed": 0}], [{"radii": [0.4, 1.0], "fit": {"rms": 0.1}}])
    [{'seed': 0, 'radii[1]': 0.4, 'radii[2]': 1.0, 'fit.rms': 0.1}]
    """
    rows = []
    for p, r in zip(cases, results, strict=True):
        row: dict = {}
        _flatten("", plain(p), row)
        _flatten("" if isinstance(r, Mapping) else "result", plain(r), row)
        rows.append({k: "+".join(map(_cell_text, v)) if isinstance(v, list) else v
                     for k, v in row.items()})
    return rows


def write_table(rows: Sequence[dict], path) -> Path:
    """Write tidy rows as CSV (``.csv``) or Parquet (``.parquet``, needs pyarrow).

    Parameters
    ----------
    rows : list of dict
        Flat rows, e.g. from :func:`tidy_rows`; columns are the union of their keys, in order
        of first appearance; missing values are left empty.
    path : path
        Output file; its suffix picks the format. ``pandas.read_csv(path)`` reads it back.

    Returns
    -------
    Path
        The written file.

    Raises
    ------
    ValueError
        Another suffix, or Parquet without pyarrow installed.

    Examples
    --------
    >>> import tempfile
    >>> p = write_table([{"seed": 0, "rms": 0.1}], Path(tempfile.mkdtemp()) / "t.csv")
    >>> p.read_text().splitlines()
    ['seed,rms', '0,0.1']
    """
    import csv

    path = Path(path)
    columns: dict[str, None] = {}
    for row in rows:
        columns.update(dict.fromkeys(row))
    path.parent.mkdir(parents=True, exist_ok=True)
    if path.suffix == ".csv":
        with path.open("w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(columns), restval="")
            w.writeheader()
            w.writerows(rows)
    elif path.suffix == ".parquet":
        try:
            import pyarrow as pa
            import pyarrow.parquet as pq
        except ImportError:
            raise ValueError(f"{path}: Parquet needs pyarrow (pip install pyarrow); "
                             f"write a .csv instead") from None
        pq.write_table(pa.Table.from_pylist(list(rows)), path)
    else:
        raise ValueError(f"{path}: expected a .csv or .parquet file name")
    return path
