"""The diagnosis on several threads (``diagnose(workers=N)``, module
``pimodel.diagnosis.threads``): the same report to the bit as on one thread, and the memos
the threads share kept per thread."""

from __future__ import annotations

import json
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from pimodel.diagnosis import diagnose
from pimodel.diagnosis.rate import RateBasis
from pimodel.diagnosis.threads import OnceCache, Pool, helped_map, lend, read_ahead

sys.path.insert(0, str(Path(__file__).parent))
from test_diagnosis import records  # noqa: E402 (train and validate records, one each)


def _everything(rep) -> tuple:
    """The whole report: its JSON (verdict, candidates, nominal, where, the model's
    parameters), the validate predictions and the exported model's output, as bytes."""
    text = json.dumps(rep.to_json(), sort_keys=True, default=lambda x: np.asarray(x).tolist())
    arrays = [np.asarray(a).tobytes() for a in (*rep.before, *rep.after)]
    v = rep.validate[0].v
    return text, arrays, rep.model().simulate(v).tobytes()


@pytest.mark.slow  # two diagnoses of about 5-10 s each
def test_the_same_report_to_the_bit_on_one_and_two_threads():
    """Creep + dynamics: the candidates, two greedy rounds, the refined dynamics, the lag's
    re-search and the revision, each batch of fits on two threads."""
    train, validate = records(("creep", "dynamics"), 0)
    one = diagnose(train, validate, workers=1)
    two = diagnose(train, validate, workers=2)
    assert one.verdict["effects"] == two.verdict["effects"]
    assert _everything(one) == _everything(two)


def test_workers_must_be_a_positive_integer():
    train, validate = records([], 4)
    for bad in (0, -1, 1.5, True):
        with pytest.raises(ValueError, match="workers"):
            diagnose(train, validate, workers=bad)


def test_a_rate_basis_keeps_its_columns_per_thread():
    """Two threads asking one basis for different filters at once each get their own columns
    (one thread's memo of the latest filter never replaces what the other is using)."""
    v = np.sin(np.linspace(0.0, 20.0, 4000)) + 0.1 * np.sin(np.linspace(0.0, 400.0, 4000))
    basis = RateBasis(None, np.linspace(0.0, 0.8, 8), v, 1e-3, 1.0, np.ones(8),
                      at_rest=True)
    taus = (1e-3, 3e-2)
    want = {tau: RateBasis(None, np.linspace(0.0, 0.8, 8), v, 1e-3, 1.0, np.ones(8),
                           at_rest=True).columns(tau, "radius").copy() for tau in taus}
    errors, barrier = [], threading.Barrier(2)

    def work(tau):
        barrier.wait()
        for _ in range(30):
            try:
                cols = basis.columns(tau, "radius")
                basis.columns(tau, "weight")
                if not np.array_equal(cols, want[tau]):
                    errors.append(tau)
                basis.release()
            except Exception as exc:  # another thread's release or memo under this one
                errors.append(repr(exc))

    threads = [threading.Thread(target=work, args=(tau,)) for tau in taus]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors == []


def test_once_cache_computes_each_key_once_across_threads():
    cache, calls, gate = OnceCache(), [], threading.Event()

    def slow():
        calls.append(1)
        gate.wait(5.0)
        return 42

    with Pool(2) as pool:
        first = pool.submit(cache.get, "k", slow)
        while not calls:
            pass
        second = pool.submit(cache.get, "k", lambda: 0)
        gate.set()
        assert (first.result(), second.result(), len(calls)) == (42, 42, 1)


def test_helped_map_gives_the_results_in_order_and_lets_an_idle_thread_help():
    """A search's points (module effects) on the pool lent to the calling thread: the
    results in the points' order whichever thread made each, and the pool's idle threads
    take some; without a lent pool (or on one worker) the caller makes them all."""
    def square(x):
        names.add(threading.current_thread().name)
        for _ in range(200):  # long enough for the helper to start
            np.linalg.norm(np.ones(2000))
        return x * x

    items = list(range(40))
    names: set = set()
    assert helped_map(square, items) == [x * x for x in items]
    assert names == {threading.current_thread().name}
    with Pool(2) as pool:
        names.clear()
        got = pool.submit(lambda: _lent(pool, square, items)).result(timeout=60)
    assert got == [x * x for x in items]
    assert len(names) == 2  # the caller (a pool thread) and the idle one
    with Pool(1) as pool, lend(pool):
        names.clear()
        assert helped_map(square, items) == [x * x for x in items]
        assert names == {threading.current_thread().name}


def _lent(pool, fn, items):
    with lend(pool):
        return helped_map(fn, items)


def test_helped_map_never_waits_for_a_helper_that_has_not_started():
    """The pool's other thread blocked on the caller's own result (a fit waiting in
    ``OnceCache`` for the one being made): the caller makes every point itself, no deadlock."""
    cache, inside, started = OnceCache(), threading.Event(), threading.Event()

    def fit():
        inside.set()
        started.wait(10.0)  # the other thread now waits on this key
        with lend(pool):
            return helped_map(lambda x: x + 1, range(10))

    with Pool(2) as pool:
        first = pool.submit(cache.get, "k", fit)
        inside.wait(10.0)
        second = pool.submit(lambda: started.set() or cache.get("k", lambda: None))
        assert first.result(timeout=30) == second.result(timeout=30) == list(range(1, 11))


def _chunks(names: list, n: int = 30):
    """A pass's chunks (module effects: play_chunks), noting the thread that made each."""
    for j in range(n):
        names.append(threading.current_thread().name)
        time.sleep(0.002)  # the C core's plays (the GIL released)
        yield j, np.full(3, float(j))


def test_read_ahead_gives_the_items_in_order_and_makes_the_next_on_an_idle_thread():
    """The items as the plain iteration gives them, each made once; with a lent pool whose
    other thread is idle that thread makes some while the caller works on the one before;
    without a lent pool, or with one worker, the caller makes them all."""
    want = [(j, [float(j)] * 3) for j in range(30)]
    names: list = []
    assert [(j, x.tolist()) for j, x in read_ahead(_chunks(names))] == want
    assert set(names) == {threading.current_thread().name}

    def consume():
        caller.append(threading.current_thread().name)
        with lend(pool):
            out = []
            for j, x in read_ahead(_chunks(names)):
                time.sleep(0.01)  # the caller's sums over the chunk (BLAS: the GIL released)
                deadline = time.monotonic() + 10.0  # on a busy machine: time for the thread
                while j == 0 and all(n == caller[0] for n in names) and \
                        time.monotonic() < deadline:  # to start on the read of item 1
                    time.sleep(0.01)
                out.append((j, x.tolist()))
            return out

    caller: list = []
    with Pool(2) as pool:
        names.clear()
        assert pool.submit(consume).result(timeout=60) == want
    assert len(names) == 30  # each item made once
    assert any(name != caller[0] for name in names)  # the idle thread made some
    with Pool(1) as pool, lend(pool):
        names.clear()
        assert [(j, x.tolist()) for j, x in read_ahead(_chunks(names))] == want
        assert set(names) == {threading.current_thread().name}


def test_read_ahead_never_waits_for_a_read_that_has_not_started():
    """Every thread of the lent pool blocked until the caller's pass has ended (fits waiting in
    ``OnceCache`` for the one reading): the caller makes every item itself, no deadlock; a
    pass left early waits for the read under way, and an error in the items reaches it."""
    release = threading.Event()
    with Pool(2) as pool:
        blocked = [pool.submit(release.wait, 30.0) for _ in range(2)]
        names: list = []
        got: list = []

        def one_pass():
            with lend(pool):
                got.extend(j for j, _ in read_ahead(_chunks(names, 10)))

        reader = threading.Thread(target=one_pass, daemon=True)
        reader.start()
        reader.join(30.0)  # a read-ahead waiting for a queued read would never end
        finished = not reader.is_alive()
        release.set()
        assert finished and got == list(range(10))
        assert set(names) == {reader.name}
        assert all(b.result(timeout=30) for b in blocked)

    def failing():
        yield 1
        raise RuntimeError("chunk 2")

    with Pool(2) as pool, lend(pool):
        for j, _ in read_ahead(_chunks([], 10)):
            if j == 2:
                break
        it = read_ahead(failing())
        assert next(it) == 1
        with pytest.raises(RuntimeError, match="chunk 2"):
            next(it)


class _Item:
    """A result that can be watched by a weak reference."""


def test_a_cancelled_helper_or_read_keeps_nothing_alive():
    """Every thread of the lent pool busy: ``helped_map``'s helpers and ``read_ahead``'s reads
    are cancelled but stay queued until a thread takes them; they must not keep the results,
    the items or the iterator alive meanwhile (a long fit beside another made hundreds of such
    maps: 0.65 GB of the linear part's columns held at 2 x 1M)."""
    import gc
    import weakref

    release = threading.Event()
    with Pool(2) as pool:
        blocked = [pool.submit(release.wait, 30.0) for _ in range(2)]
        with lend(pool):
            out = helped_map(lambda x: _Item(), range(5))
            watched = [weakref.ref(x) for x in out]

            def items():
                for _ in range(5):
                    item = _Item()
                    watched.append(weakref.ref(item))
                    yield item

            reads = read_ahead(items())
            for _ in range(3):
                next(reads)
            reads.close()  # a pass left early
        del out, reads
        gc.collect()
        alive = sum(w() is not None for w in watched)
        release.set()
        assert all(b.result(timeout=30) for b in blocked)
    assert alive == 0


@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
def test_cli_workers_option(tmp_path, capsys):
    """``pimodel diagnose --workers N``: N >= 1 runs (the clean stage: ``none``), 0 is refused."""
    from pimodel import save_record
    from pimodel.cli import main

    train, validate = records([], 4)
    save_record(train[0], tmp_path / "a.csv")
    save_record(validate[0], tmp_path / "b.csv")
    args = ["diagnose", "--train", str(tmp_path / "a.csv"), "--validate",
            str(tmp_path / "b.csv"), "--json", str(tmp_path / "d.json"), "--quiet"]
    assert main([*args, "--workers", "2"]) == 0
    assert json.loads((tmp_path / "d.json").read_text())["verdict"]["effects"] == ["none"]
    with pytest.raises(SystemExit):
        main([*args[:-3], "--json", str(tmp_path / "e.json"), "--workers", "0"])
    assert ">= 1" in capsys.readouterr().err


def test_a_fits_variants_run_on_the_pool_each_on_its_own(monkeypatch):
    """The rate candidate's two shapes (first order and exact) are two fits the pool makes
    at once: each waits at a barrier for the other. When the variants of one ``fit`` ran one
    after the other on one thread, the first waited alone and the barrier broke."""
    import importlib
    diagnose_module = importlib.import_module("pimodel.diagnosis.diagnose")
    real = diagnose_module.fit_effect
    barrier = threading.Barrier(2, timeout=120)
    met = []

    def fit_effect(name, train, combo, fixed, nominal):
        if name == "rate" and not combo:  # the candidate alone: its two shapes
            met.append(barrier.wait())
        return real(name, train, combo, fixed, nominal)

    monkeypatch.setattr(diagnose_module, "fit_effect", fit_effect)
    train, validate = records(("rate",), 0)
    rep = diagnose(train, validate, workers=2, max_effects=1)
    assert sorted(met) == [0, 1]  # both shapes passed the barrier together
    assert "rate" in [c["effect"] for c in rep.candidates]


class _StoresMeet(dict):
    """A fit's memo whose stores of a segment's latest rate filter wait until both threads of
    the test have stored theirs (the order in which two points of one search interleave)."""

    def __init__(self, barrier: threading.Barrier):
        super().__init__()
        self.barrier = barrier

    def __setitem__(self, key, value):
        super().__setitem__(key, value)
        if isinstance(key, tuple) and key[0] == "rate":
            self.barrier.wait(timeout=30)


def test_two_points_of_one_search_on_two_threads_each_get_their_own_rate_filter():
    """Two points of a rate search (two filters) built at once on one segment, as when an idle
    thread takes a search's point (``threads.helped_map``): each point's rows are those of its
    own filter, also when the other thread stores its filter as the segment's latest between
    this thread's store and its read (forced here by a barrier after each store)."""
    from pimodel.diagnosis.effects import _combo_features, fit_nominal, make_segment

    rng = np.random.default_rng(46)
    t = np.arange(4000) * 1e-3
    v = np.cumsum(rng.normal(0.0, 0.05, t.size))
    radii = np.linspace(0.0, 0.8, 8)
    seg = make_segment(t, v, np.zeros_like(v), radii)
    nominal = fit_nominal([seg])
    seg.rate_basis = RateBasis(None, radii, v, 1e-3, 1.0, np.ones(8), at_rest=True)
    points = [{"rate_family": "radius", "rate_tau": tau, "rate_saturation": None}
              for tau in (3e-3, 30e-3)]
    want = [_combo_features(("rate",), p, nominal, {}).parts(seg)[1] for p in points]
    assert not np.array_equal(want[0], want[1])  # two filters, two sets of columns
    static = _StoresMeet(threading.Barrier(2))
    with Pool(2) as pool:
        got = pool.map(lambda p: _combo_features(("rate",), p, nominal, static).parts(seg)[1],
                       points)
    for g, w in zip(got, want, strict=True):
        assert np.array_equal(g, w)
