"""The candidates' least-squares fits are made once per grid point
(:func:`pimodel.diagnosis.effects._fit_memo`): a point fitted again gives the same coefficients
and RSS to the bit without a pass over the records, and any other point, column count, nominal
or record is fitted anew."""

from __future__ import annotations

import numpy as np

from pimodel.diagnosis.effects import (
    TrainRecords,
    _combo_features,
    _fit,
    fit_nominal,
    make_segment,
)
from pimodel.stages.pi_stage import excitation, random_truth


def _segments(seed: int = 1):
    truth = random_truth(["dynamics"], 0)
    t, v = excitation("train", seed=seed)
    rec = truth.record(t, v, seed)
    return [make_segment(rec.t, rec.v, rec.y, np.linspace(0.0, np.ptp(v) / 2, 20))]


def _counted(effects, p, nominal, static, ncols=None):
    """The regressors of :func:`_combo_features` and a count of the passes that build them."""
    feats = _combo_features(effects, p, nominal, static, ncols)
    calls = [0]
    rows = feats.parts

    def parts(s):
        calls[0] += 1
        return rows(s)

    feats.parts = parts
    return feats, calls


def test_a_point_fitted_again_is_taken_from_the_memo_to_the_bit():
    train = _segments()
    nominal = fit_nominal(train)
    p = {"fn": 800.0, "zeta": 0.1}
    first, calls1 = _counted(("dynamics",), dict(p), nominal, {"train": TrainRecords(train)})
    m1, rss1 = _fit("dynamics", 2, first, train, dict(p))
    again, calls2 = _counted(("dynamics",), dict(p), nominal, {"train": TrainRecords(train)})
    m2, rss2 = _fit("dynamics", 2, again, train, dict(p))
    assert calls1[0] >= 1 and calls2[0] == 0  # the second fit made no pass
    assert rss2 == rss1 and np.array_equal(m2.coef, m1.coef)
    assert m2.coef is not m1.coef and m2.params == p and m2.features is again


def test_other_points_columns_nominals_and_records_are_fitted_anew():
    train = _segments()
    nominal = fit_nominal(train)
    static = {"train": TrainRecords(train)}
    p = {"fn": 800.0, "zeta": 0.1}
    _fit("dynamics", 2, _counted(("dynamics",), p, nominal, static)[0], train, p)
    q_next = {"fn": float(np.nextafter(800.0, 1e9)), "zeta": 0.1}  # one bit off
    for q, ncols, nom, segs in ((q_next, None, nominal, train),
                                (p, 12, nominal, train),
                                (p, None, fit_nominal(train), train),
                                (p, None, nominal, _segments())):
        feats, calls = _counted(("dynamics",), dict(q), nom,
                                {"train": TrainRecords(segs)}, ncols)
        m, rss = _fit("dynamics", 2, feats, segs, dict(q))
        plain = _fit("dynamics", 2, _combo_features(("dynamics",), dict(q), nom,
                                                    {"train": TrainRecords(segs)}, ncols),
                     segs, dict(q))[1]
        assert calls[0] >= 1 and rss == plain


def test_a_delay_search_forms_the_play_rows_gram_once(monkeypatch):
    # the Gram of play rows delayed by a whole d is that of the undelayed rows on the window d
    # samples earlier (effects._delayed_grams): one Gram of the play rows for the search, and
    # the fits equal those that form each delayed Gram anew, to rounding
    from pimodel.diagnosis import effects

    train = _segments()
    nominal, other = fit_nominal(train), fit_nominal(train)
    big = []
    square = effects._square
    monkeypatch.setattr(effects, "_square",
                        lambda X: (big.append(X.shape) if X.shape[1] > 1024 else None,
                                   square(X))[1])

    def search(nominal, train):  # a nominal and records of its own: no fit taken from the
        # other's memo, no terms from the other's records (_stored_grams)
        static = {"train": TrainRecords(train)}
        return [_fit("delay", 1, _combo_features(("delay",), {"d": d}, nominal, static),
                     train, {"d": d}) for d in (1, 2, 5, 40, 2.5)]

    fast = search(nominal, train)
    n_fast = len(big)
    monkeypatch.setattr(effects, "DELAYED_GRAM_MAX", 0)  # every delayed Gram formed anew
    plain = search(other, _segments())
    cuts = len(list(effects.chunks(train[0].y.size)))
    # the undelayed rows' Gram once, the fractional delay's anew; without: one per delay
    assert n_fast == 2 * cuts and len(big) - n_fast == 5 * cuts
    for (m1, rss1), (m2, rss2) in zip(fast, plain, strict=True):
        assert abs(rss1 - rss2) <= 1e-9 * rss2
        out1, out2 = m1.predict(train[0]), m2.predict(train[0])
        assert np.max(np.abs(out1 - out2)) <= 1e-7 * np.ptp(train[0].y)


def test_the_play_rows_terms_are_kept_by_what_the_rows_are(monkeypatch):
    # effects._stored_grams: the mode-filtered play rows are built anew for each combination
    # and drift variant around one mode; their terms are formed once per (rows, mode) and the
    # fits equal those that form them anew, to the bit
    from pimodel.diagnosis import effects

    train = _segments()
    nominals = [fit_nominal(train), fit_nominal(train)]
    formed = []
    first_terms = effects._first_terms
    monkeypatch.setattr(effects, "_first_terms",
                        lambda *a: (formed.append(1), first_terms(*a))[1])
    p = {"fn": 800.0, "zeta": 0.1}
    combos = [("dynamics",), ("creep", "dynamics"), ("dynamics", "asymmetry")]

    def fits(nominal):  # a nominal of its own each: no fit taken from _fit's memo
        return [_fit("+".join(e), 3, _combo_features(e, dict(p), nominal,
                                                     {"train": TrainRecords(train)}),
                     train, dict(p)) for e in combos]

    kept = fits(nominals[0])
    n_kept = len(formed)
    cuts = len(list(effects.chunks(train[0].y.size)))
    monkeypatch.setattr(effects, "_stored_grams", lambda s, key, make: make())
    plain = fits(nominals[1])
    assert n_kept == cuts and len(formed) - n_kept == len(combos) * cuts
    for (m1, rss1), (m2, rss2) in zip(kept, plain, strict=True):
        assert rss1 == rss2 and np.array_equal(m1.coef, m2.coef)


def test_the_kept_terms_are_bounded_per_record(monkeypatch):
    from pimodel.diagnosis import effects

    train = _segments()
    nominal = fit_nominal(train)
    monkeypatch.setattr(effects, "GRAM_STORE_BYTES", 3 * 20 * 21 * 8)  # about three keys
    for fn in np.linspace(700.0, 900.0, 12):
        q = {"fn": float(fn), "zeta": 0.1}
        _fit("dynamics", 2, _combo_features(("dynamics",), q, nominal,
                                            {"train": TrainRecords(train)}), train, q)
    store = train[0].__dict__["_gram_store"]
    assert 1 <= len(store) <= 3
    assert train[0].__dict__["_gram_bytes"] == sum(size for size, _ in store.values())
    assert train[0].__dict__["_gram_bytes"] <= effects.GRAM_STORE_BYTES
