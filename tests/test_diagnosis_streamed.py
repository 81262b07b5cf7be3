"""The whole-record refit streamed chunk by chunk (issue 31; pimodel.diagnosis.streamed): a held
model fitted and predicted on streamed segments (play rows and every filter's state carried from
chunk to chunk) gives the coefficients, RSS, outputs and levels of the full-rows path to the bit,
for each effect alone and the usual pairs, with and without a masked start; a whole diagnosis
of records longer than SCREEN_SAMPLES gives the same report; and the refit holds a few columns
of the record, not the model's columns on the whole record."""

import importlib
import json
import sys
import tracemalloc
from pathlib import Path

import numpy as np
import pytest
from threadpoolctl import threadpool_limits

from pimodel.diagnosis import streamed
from pimodel.diagnosis.chunked import CHUNK
from pimodel.diagnosis.effects import (
    SCREEN_SAMPLES,
    Model,
    TrainRecords,
    _combo_features,
    _fit,
    base_features,
    fit_effect,
    nominal_params,
)
from pimodel.records import Record
from pimodel.stages.pi_stage import random_truth

sys.path.insert(0, str(Path(__file__).parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from bench_diagnosis import long_record as _long  # noqa: E402
from test_diagnosis import records as short_records  # noqa: E402

dg = importlib.import_module("pimodel.diagnosis.diagnose")  # not the function it exports

N = 2 * CHUNK + 5_003  # longer than two chunks, not a whole number of them


def test_chunks_hold_whole_groups_of_four_samples():
    # the bit-equality of streamed and full rows rests on the products' kernels seeing the same
    # groups of samples in each chunk as in the whole record
    assert CHUNK % 4 == 0


@pytest.fixture(scope="module")
def recs():
    truth = random_truth(["creep", "dynamics"], 0)
    train = [_long("train", N, truth, 1), _long("train", N - 777, truth, 7, 9.0)]
    validate = [_long("validate", N + 321, truth, 100, 20.0), _long("validate", N, truth, 3, 30.0)]
    return train, validate


def _segments(recs, initial_state: str, projected: bool):
    train, validate = recs
    radii = np.linspace(0.0, float(np.ptp(np.concatenate([r.v for r in train]))) / 2, 20)
    tr, ne = dg._plain_fit(train, radii, initial_state)
    coef = ne.solve()
    V = None
    if projected:  # the nominal's direction and the leading principal directions
        _, vecs = np.linalg.eigh(ne.G[:20, :20])
        w = coef[:20]
        V = np.column_stack((w / np.linalg.norm(w), vecs[:, ::-1][:, :8]))
    va = dg._bare(validate, initial_state)
    full = [[dg._with_rows(s, radii, V, True) for s in h] for h in (tr, va)]
    stream = [[dg._streamed(s, radii, V, True) for s in h] for h in (tr, va)]
    nominal = Model("nominal", 0, base_features, None)
    ne2 = dg.NormalEquations(full[0][0].Z.shape[1] + 1)
    for s in full[0]:
        X = s.play_rows(offset=True)[:, s.used]
        ne2.add_gram(X @ X.T, X @ s.y[s.used], X.shape[1])
    nominal.coef = ne2.solve()
    nominal.params = nominal_params(nominal.coef, [nominal.predict(s) for s in full[0]], full[0])
    return full, stream, nominal


LTI = (("mode", 2500.0, 0.05), ("lowpass", 3e-4), ("direct",))
CASES = [
    ("creep", (), {}),
    ("dynamics", (), {"fn": 900.0, "zeta": 0.08}),
    ("delay", (), {"d": 3}),
    ("delay", (), {"d": 2.375}),
    ("asymmetry", (), {}),
    ("drift", (), {"clock": "record"}),
    ("drift", (), {"clock": "absolute"}),
    ("drift", (), {"clock": "levels"}),
    ("drift", (), {"clock": "settle", "settle_tau": 0.4, "settle_t0": 0.0}),
    ("creep", ("dynamics",), {"fn": 900.0, "zeta": 0.08}),
    ("delay", ("creep",), {"d": 1.5}),
    ("dynamics", (), {"fn": 900.0, "zeta": 0.08, "lti": LTI}),
    ("delay", ("dynamics",), {"fn": 900.0, "zeta": 0.08, "lti": LTI[:2], "d": 2.5}),
    ("asymmetry", ("creep",), {}),
    ("creep", (), {"creep_start": "common"}),  # the lags at a common rest (module creep)
    ("asymmetry", ("creep",), {"creep_start": "common"}),
    ("delay", ("creep",), {"creep_start": "common", "d": 1.5}),
    ("creep", (), {"creep_start": "record", "creep_levels": 2}),  # from each record's start
    ("delay", ("creep",), {"creep_start": "record", "creep_levels": 2, "d": 1.5}),
    ("drift", ("creep",), {"creep_start": "record", "creep_levels": 2, "clock": "levels",
                           "levels": 2}),
]


@pytest.mark.parametrize("initial_state", ["rest", "unknown"])
@pytest.mark.parametrize("projected", [False, True])
def test_streamed_refit_equals_the_full_rows_refit_to_the_bit(recs, initial_state, projected):
    with threadpool_limits(1, user_api="blas"):  # as diagnose runs the fits (a product on
        # several threads splits a record's samples at other points than the chunks)
        _check_streamed_equals_full(recs, initial_state, projected)


def _check_streamed_equals_full(recs, initial_state, projected):
    full, stream, nominal = _segments(recs, initial_state, projected)
    assert all(streamed.is_streamed(s) for h in stream for s in h)
    assert all(s.Z is None for h in stream for s in h)  # no play rows held
    if initial_state == "unknown":
        assert all(s.mask is not None and not s.mask[0] for s in full[0])
    for name, combo, grid in CASES:
        fixed = {**grid, "held": True}
        a = fit_effect(name, full[0], combo, fixed, nominal)
        b = fit_effect(name, stream[0], combo, fixed, nominal)
        what = f"{'+'.join((*combo, name))} {grid}"
        assert np.array_equal(a.coef, b.coef), what
        assert repr(a.params) == repr(b.params), what
        for sa, sb in zip(full[1] + full[0], stream[1] + stream[0], strict=True):
            assert np.array_equal(a.predict(sa), b.predict(sb)), what
        if "drift" in (*combo, name):
            assert repr(dg.level_report(a, full[1], full[0])) == \
                repr(dg.level_report(b, stream[1], stream[0])), what
        # the RSS of the fit itself
        feats = {id(s): _combo_features((*combo, name), a.grid, nominal,
                                        {"train": TrainRecords(h)})
                 for h in (full[0], stream[0]) for s in h[:1]}
        ra = _fit("x", 0, feats[id(full[0][0])], full[0], a.grid)
        rb = _fit("x", 0, feats[id(stream[0][0])], stream[0], a.grid)
        assert ra[1] == rb[1] and np.array_equal(ra[0].coef, rb[0].coef), what


def test_rate_and_a_filter_before_the_hysteresis_are_not_streamed():
    assert not streamed.streamable(("rate",), {"rate_tau": 1e-3})
    assert not streamed.streamable(("dynamics",), {"wiener": (("lowpass", 1e-3),)})
    assert streamed.streamable(("dynamics", "creep", "delay", "asymmetry", "drift"),
                               {"fn": 1.0, "zeta": 0.1, "d": 1, "lti": LTI})


def _refit_peak(recs, stream_on: bool) -> tuple[float, Model, list]:
    """Peak traced memory [bytes] of the whole-record refit of dynamics + creep (held grid,
    projected plays) over what the records take, and its model and validate outputs."""
    train, validate = recs
    radii = np.linspace(0.0, float(np.ptp(train[0].v)) / 2, 40)
    tr, ne = dg._plain_fit(train, radii, "rest")
    coef = ne.solve()
    _, vecs = np.linalg.eigh(ne.G[:40, :40])
    V = np.column_stack((coef[:40] / np.linalg.norm(coef[:40]), vecs[:, ::-1][:, :16]))
    va = dg._bare(validate, "rest")
    nominal, _ = dg._projected_fit(tr, radii, V, True)
    nominal.params = nominal_params(nominal.coef, dg._plain_outputs(tr, radii, coef), tr)
    screened = Model("dynamics+creep", 0, None, None, {},
                     {"fn": 900.0, "zeta": 0.08, "lti": LTI[:1]})
    tracemalloc.start()
    base = tracemalloc.get_traced_memory()[0]
    with threadpool_limits(1, user_api="blas"):
        m, out = dg._whole_fit(("dynamics", "creep"), screened, tr, va, nominal,
                               lambda s: dg._with_rows(s, radii, V, True),
                               (lambda s: dg._streamed(s, radii, V, True)) if stream_on else None)
    peak = tracemalloc.get_traced_memory()[1] - base
    tracemalloc.stop()
    return peak, m, out


@pytest.mark.slow
def test_the_streamed_refit_holds_a_few_columns_not_the_models():
    truth = random_truth(["creep", "dynamics"], 0)
    n = 300_000
    recs = ([_long("train", n, truth, 1)], [_long("validate", n, truth, 100)])
    peak, m, out = _refit_peak(recs, True)
    column, chunk_row = 8 * n, 8 * CHUNK  # bytes of a column of the record, of a chunk's row
    # the validate output and a chunk of the model's rows with their temporaries (the plays,
    # the projected and filtered rows: about 200 rows of 16,384 samples), not the model's
    # ~35 rows on the whole record (the full rows' path: about 54 columns here)
    bound = 4 * column + 256 * chunk_row
    assert peak < bound, (peak / column, bound / column)
    peak_full, m_full, out_full = _refit_peak(recs, False)
    assert peak_full > 2 * bound, (peak_full / column, bound / column)  # the bound tells
    assert np.array_equal(m.coef, m_full.coef)
    assert all(np.array_equal(a, b) for a, b in zip(out, out_full, strict=True))


def _text_of(value) -> str:
    return json.dumps(value, sort_keys=True, default=lambda x: np.asarray(x).tolist())


def _longer(records_, n: int):
    """Each record repeated (its input and output; time continued) to ``n`` samples."""
    out = []
    for r in records_:
        k = -(-n // len(r))
        dt = float(r.t[1] - r.t[0])
        out.append(Record(r.t[0] + np.arange(k * len(r))[:n] * dt, np.tile(r.v, k)[:n],
                          np.tile(r.y, k)[:n], source=r.source))
    return out


@pytest.mark.slow
@pytest.mark.parametrize("effects,seed", [(("creep", "dynamics"), 0)])
def test_a_whole_diagnosis_is_the_same_with_the_streamed_refit(effects, seed, monkeypatch):
    """One diagnosis of records longer than SCREEN_SAMPLES (the choice made once); its
    whole-record refit (``_whole_fit``, called with what the diagnosis passes it) is run with
    the full rows, then streamed, and must give the same model and outputs to the bit."""
    train, validate = short_records(effects, seed)
    train, validate = (_longer(train, SCREEN_SAMPLES + 9_000),
                       _longer(validate, SCREEN_SAMPLES + 4_000))
    whole_fit, refits = dg._whole_fit, []

    def both(*args):
        full = whole_fit(*args[:-1], None)  # the last argument: the streamed rows
        got = whole_fit(*args)
        refits.append((got, full))
        return got

    monkeypatch.setattr(dg, "_whole_fit", both)
    rep = dg.diagnose(train, validate, workers=1, initial_state="rest")  # one diagnosis
    assert "screen" in rep.verdict
    assert refits, "the diagnosis made no whole-record refit"
    for (m, out), (m_full, out_full) in refits:
        assert m.name == m_full.name
        assert streamed.streamable(tuple(m.name.split("+")), m.grid)  # the refit streamed
        assert np.array_equal(m.coef, m_full.coef)
        assert _text_of(m.params) == _text_of(m_full.params)
        assert all(np.array_equal(x, y) for x, y in zip(out, out_full, strict=True))
    assert all(np.array_equal(x, y) for x, y in zip(rep.after, refits[-1][0][1], strict=True))


def _whole_refit(recs, chosen: tuple, grid: dict, stream_on: bool):
    """``_whole_fit`` of ``chosen`` (grid held) on whole records, as the diagnosis calls it
    (bare segments, the rows or streamed rows of a 40-play grid)."""
    train, validate = recs
    radii = np.linspace(0.0, float(np.ptp(train[0].v)) / 2, 40)
    tr, ne = dg._plain_fit(train, radii, "rest")
    coef = ne.solve()
    va = dg._bare(validate, "rest")
    nominal = Model("nominal", 0, base_features, coef,
                    nominal_params(coef, dg._plain_outputs(tr, radii, coef), tr))
    screened = Model("+".join(chosen), 0, None, None, {}, grid)
    with threadpool_limits(1, user_api="blas"):
        return dg._whole_fit(chosen, screened, tr, va, nominal,
                             lambda s: dg._with_rows(s, radii, None, True),
                             (lambda s: dg._streamed(s, radii, None, True)) if stream_on
                             else None)


@pytest.mark.parametrize("clock", ["record", "levels"])
def test_a_whole_refit_with_a_drift_reads_the_same_levels_streamed(clock):
    """The refit's drift branch (every validate record's rows at once, their levels read from
    all of them) on records longer than SCREEN_SAMPLES: streamed as with the full rows."""
    truth = random_truth(["delay", "drift"], 0)
    n = SCREEN_SAMPLES + 3_001
    recs = ([_long("train", n, truth, 1), _long("train", n - 500, truth, 5, 8.0)],
            [_long("validate", n + 77, truth, 100, 20.0), _long("validate", n, truth, 3, 30.0)])
    chosen, grid = ("delay", "drift"), {"d": 2.5, "clock": clock}
    m, out = _whole_refit(recs, chosen, grid, True)
    m_full, out_full = _whole_refit(recs, chosen, grid, False)
    assert np.array_equal(m.coef, m_full.coef)
    assert _text_of(m.params) == _text_of(m_full.params)
    assert all(np.array_equal(x, y) for x, y in zip(out, out_full, strict=True))
