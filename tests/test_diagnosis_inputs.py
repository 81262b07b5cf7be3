"""Issue 28: the diagnosis on records unlike its other tests' (a logarithmic chirp, ramps to
held levels, band-limited random input, 500 Hz and 2 kHz), and creep reported as a law.

Stages and inputs are drawn in the tests (fixed seeds): a clean stage must come out ``none``;
a creep over tens of seconds must come out ``creep`` with its percent per decade.
"""

import numpy as np
import pytest
from scipy.signal import butter, lfilter

from pimodel.diagnosis import diagnose
from pimodel.diagnosis.creep import creep_law, creep_time_constants
from pimodel.operators.creep import CreepOperator
from pimodel.operators.pi import PIOperator
from pimodel.records import Record

NOISE = 0.005  # um


def _stage(rng):
    """4-8 plays, the first at radius 0, the others up to 3 (input units)."""
    n = int(rng.integers(4, 9))
    radii = np.sort(np.concatenate(([0.0], rng.uniform(0.2, 3.0, n - 1))))
    return rng.uniform(0.1, 1.0, n), radii


def _chirp(rng, fs, seconds=4.0):
    """A logarithmic chirp from 0.5 Hz to min(40 Hz, fs / 20) around 2, random phase."""
    t = np.arange(int(seconds * fs)) / fs
    f0, f1 = 0.5, min(40.0, fs / 20)
    phase = 2 * np.pi * f0 * t[-1] / np.log(f1 / f0) * ((f1 / f0) ** (t / t[-1]) - 1)
    return t, 2.0 + 3.0 * np.sin(phase + rng.uniform(0, 2 * np.pi))


def _held_ramps(rng, fs, seconds=4.0, levels=16):
    """Ramps of 50 ms to random levels in [-3, 4], each held until the next (random times)."""
    t = np.arange(int(seconds * fs)) / fs
    starts = np.sort(rng.uniform(0, t[-1] - 0.1, levels))
    lv = rng.uniform(-3, 4, levels)
    tk, vk = [0.0], [lv[0]]
    for k in range(1, levels):
        tk += [starts[k], starts[k] + 0.05]
        vk += [vk[-1], lv[k]]
    return t, np.interp(t, tk + [t[-1]], vk + [vk[-1]])


def _band_limited(rng, fs, seconds, cutoff):
    """Gaussian noise low-passed (3rd-order Butterworth, ``cutoff`` Hz), unit variance."""
    b, a = butter(3, cutoff / (fs / 2))
    n = int(seconds * fs)
    x = lfilter(b, a, rng.normal(0, 1, n + 3000))[3000:]
    return np.arange(n) / fs, x / np.std(x)


def _random_input(rng, fs, seconds=4.0):
    """Band-limited random input (:func:`_band_limited`, 8 Hz) around 1, standard deviation 1.5."""
    t, x = _band_limited(rng, fs, seconds, 8.0)
    return t, 1.0 + 1.5 * x


INPUTS = {"chirp": _chirp, "held_ramps": _held_ramps, "band_limited": _random_input}
SEEDS = {"chirp": 11, "held_ramps": 12, "band_limited": 4}  # band_limited 4: 500 Hz failed
# before issue 28's grid tops (nominal 3.5x the noise, `unexplained`; docs/diagnosis.md)


@pytest.mark.parametrize("fs", [500.0, 2000.0])
@pytest.mark.parametrize("kind", sorted(INPUTS))
def test_clean_stage_is_none_on_other_inputs_and_rates(kind, fs):
    """A clean stage (plays at rest at v[0], white noise) driven by a chirp, by ramps to held
    levels or by band-limited random input (4 s records), at 500 Hz or 2 kHz: the nominal
    reaches the noise (within 1.5x) and the verdict is ``none``."""
    rng = np.random.default_rng(SEEDS[kind])
    p, r = _stage(rng)
    recs = []
    for i in range(2):
        t, v = INPUTS[kind](rng, fs)
        y = PIOperator(p, r, initial_state=v[0]).simulate(v) + rng.normal(0, NOISE, v.size)
        recs.append(Record(t, v, y, source=f"{kind}{i}"))
    rep = diagnose([recs[0]], [recs[1]])
    assert rep.nominal["validate"]["rms"] <= 1.5 * NOISE, rep.nominal["validate"]
    assert rep.verdict["effects"] == ["none"], rep.verdict["effects"]


def test_few_samples_also_try_grids_topped_below_half_the_range():
    """The nominal's grids (issue 28): with fewer than ``FEW_SAMPLES_PER_PLAY`` train samples
    per play of the finest grid, grids topped at ``GRID_TOPS`` of half the train range are
    offered beside the half-range ones (those unchanged); with as many or more samples none. A
    stage with a play at 0.95 of half the range still gets a grid that reaches it."""
    import importlib

    dg = importlib.import_module("pimodel.diagnosis.diagnose")

    def record(v):
        return Record(np.arange(v.size) * 1e-3, v, v.copy())

    limit = dg.FEW_SAMPLES_PER_PLAY * max(dg.GRID_SIZES)
    assert all(0.5 < top < 1.0 for top in dg.GRID_TOPS)
    for n, tops in ((limit - 1, dg.GRID_TOPS), (limit, ()), (4 * limit, ())):
        v = np.sin(np.linspace(0.0, 6 * np.pi, n)) * np.linspace(1.0, 3.0, n) + 0.5
        train = [record(v[: n // 2]), record(v[n // 2:])]
        half = np.ptp(v) / 2
        assert [g.tolist() for g in dg._grids(train)[0]] == \
            [np.linspace(0.0, half, size).tolist() for size in dg.GRID_SIZES]
        topped = dg._topped_grids(train)
        assert len(topped) == len(tops) * len(dg.GRID_SIZES)
        for g, (top, size) in zip(topped, [(t, m) for t in tops for m in dg.GRID_SIZES],
                                  strict=True):
            assert np.allclose(g, np.linspace(0.0, top * half, size), rtol=0, atol=1e-12)
    for seed in range(3):
        rng = np.random.default_rng(seed)
        (t, v), (t2, v2) = _random_input(rng, 500.0), _random_input(rng, 500.0)
        half = np.ptp(v) / 2
        radii = np.sort(np.concatenate(([0.0], rng.uniform(0.1, 0.7, 4) * half, [0.95 * half])))
        w = rng.uniform(0.1, 1.0, radii.size)
        train, validate = (Record(tk, vk, PIOperator(w, radii, initial_state=vk[0]).simulate(vk)
                                  + rng.normal(0, NOISE, vk.size)) for tk, vk in ((t, v), (t2, v2)))
        assert len(train) < limit
        chosen, _, _ = dg._nominal([train], [validate], "rest")
        assert chosen[-1] >= radii[-1], (seed, chosen[-1] / half)


def test_creep_lags_follow_the_records():
    """One lag per decade from at least 10 samples to at most twice the longest record: the
    grid of the existing generators' records (10 kHz over 3 s, 5 kHz over 1.7 s, 2 kHz over
    5 s) is kept, a slow record gets longer lags, a fast one shorter ones, and no lag is so
    long that the record shows less than 39 % of its settling."""
    assert creep_time_constants(1e-4, 3.0 - 1e-4) == (0.003, 0.03, 0.3, 3.0)
    assert creep_time_constants(2e-4, 1.65) == (0.003, 0.03, 0.3, 3.0)
    assert creep_time_constants(5e-4, 5.0 - 5e-4) == (0.03, 0.3, 3.0)
    for dt, duration in ((5e-3, 100.0), (2e-3, 40.0), (1e-5, 0.2), (1e-3, 600.0),
                         (2e-4, 1.0 - 2e-4)):
        taus = np.array(creep_time_constants(dt, duration))
        assert taus[0] >= 10 * dt and taus[0] < 100 * dt
        assert taus[-1] <= 2 * duration and taus[-1] > duration / 5
        assert np.allclose(np.diff(np.log10(taus)), 1.0)
    with pytest.raises(ValueError, match="dt"):
        creep_time_constants(0.0, 1.0)
    with pytest.raises(ValueError, match="duration"):
        creep_time_constants(1e-3, float("nan"))


def test_creep_law_reads_a_log_law():
    """Lags one per decade of equal gain give a law of that gain per decade (to 10 %), and its
    total creep; gains that sum to 1 or more are refused."""
    rng = np.random.default_rng(4)
    for _ in range(5):
        c = rng.uniform(0.005, 0.03)
        taus = 0.01 * 10.0 ** np.arange(int(rng.integers(3, 6)))
        g = np.full(taus.size, c) / (1 + c * taus.size)  # the diagnosis' form (module creep)
        law = creep_law(g, taus)
        assert law["percent_per_decade"] == pytest.approx(100 * c, rel=0.1)
        assert law["total_percent"] == pytest.approx(100 * c * taus.size, rel=1e-9)
        assert law["lag_percent"] == pytest.approx([100 * c] * taus.size, rel=1e-9)
    with pytest.raises(ValueError, match="sum"):
        creep_law([0.6, 0.5], [0.1, 1.0])
    with pytest.raises(ValueError, match="one gain per time constant"):
        creep_law([0.1], [0.1, 1.0])


@pytest.mark.slow  # two 40 s records at 500 Hz (~15-30 s)
def test_slow_creep_on_long_band_limited_records_is_read_as_a_law():
    """Creep of 1-3 % per decade with lags of 0.2, 2 and 20 s under band-limited random motion
    and held levels (two 40 s records at 500 Hz): creep is the first effect named, its lags
    reach half the record and its percent per decade is the truth's within 25 %. (A second
    effect, ``rate``, is still added here: issue 28's "second effect only when it is real" is
    not met, docs/diagnosis.md.)"""
    rng = np.random.default_rng(0)
    fs, seconds = 500.0, 40.0
    p, r = _stage(rng)
    gamma = rng.uniform(0.01, 0.03)
    taus = np.array([0.2, 2.0, 20.0])
    recs = []
    for i in range(2):
        t, x = _band_limited(rng, fs, seconds, 1.5)
        levels = np.repeat(rng.uniform(-3, 3, 20), t.size // 20 + 1)[:t.size]
        v = 1.0 + 1.5 * x + np.convolve(levels, np.ones(50) / 50, mode="same")
        h = PIOperator(p, r, initial_state=v[0]).simulate(v)
        y = CreepOperator(np.full(3, gamma), taus, dt=1 / fs, initial_state=h[0]).simulate(h)
        recs.append(Record(t, v, y + rng.normal(0, NOISE, t.size), source=f"creep{i}"))
    rep = diagnose([recs[0]], [recs[1]])
    assert rep.verdict["effects"][0] == "creep", rep.verdict["effects"]
    law = rep.verdict["creep_law"]
    assert law["time_constants_s"][-1] >= seconds / 2
    assert law["time_constants_s"][0] >= 10 / fs
    truth = creep_law(np.full(3, gamma) / (1 + 3 * gamma), taus)
    assert law["percent_per_decade"] == pytest.approx(truth["percent_per_decade"], rel=0.25)


def test_held_ramps_whose_stage_has_plays_above_half_the_train_range_say_so():
    """Ramps to held levels at 500 Hz, 4 s records, seed 4 (issue 28): the stage's largest play
    (2.93) lies above half the train input's range (2.69) and beyond its travel from its start
    (2.92): train never moves it, so no PI model fitted on train predicts validate (refitted on
    the true radii it misses by 0.17 um, 34x the noise; docs/diagnosis.md). The verdict cannot be
    ``none``; the report says why: the confidence is ``unsure`` and the next step names the
    validate record that drives plays above half the train range and asks for train over
    validate's range (on clean47 the hint is not there)."""
    from pimodel.diagnosis.summary import confidence, next_step

    rng = np.random.default_rng(4)
    p, r = _stage(rng)
    recs = []
    for i in range(2):
        t, v = _held_ramps(rng, 500.0)
        y = PIOperator(p, r, initial_state=v[0]).simulate(v) + rng.normal(0, NOISE, v.size)
        recs.append(Record(t, v, y, source=f"held_ramps{i}"))
    rep = diagnose([recs[0]], [recs[1]], workers=1)
    cov = rep.nominal["coverage"]
    assert r[-1] > cov["reach"] > cov["half_range"]  # the premise: a play train never moves
    assert rep.nominal["validate"]["rms"] > 5 * rep.verdict["noise_floor"]
    assert rep.verdict["effects"] != ["none"]
    assert confidence(rep)[0] == "unsure"
    step = next_step(rep)
    assert "half the train input's range" in step and "held_ramps1" in step, step
    assert "record train over at least the validate input's range" in step


def _clean_records(seed, kind, fs=500.0, seconds=4.0, stage=None):
    """The clean-stage test's records (:func:`_stage` or ``stage``, white noise): train,
    validate, weights, radii."""
    rng = np.random.default_rng(seed)
    p, r = _stage(rng) if stage is None else stage
    recs = []
    for i in range(2):
        t, v = INPUTS[kind](rng, fs, seconds)
        y = PIOperator(p, r, initial_state=v[0]).simulate(v) + rng.normal(0, NOISE, v.size)
        recs.append(Record(t, v, y, source=f"{kind}{i}"))
    return [recs[0]], [recs[1]], p, r


def test_held_ramps_with_a_play_above_half_the_train_range_is_none():
    """Ramps to held levels at 500 Hz, 4 s records, seed 2 (issue 28): the stage's largest play
    (2.48) lies above half the train input's range (2.37) and below its travel from its start
    (3.25), so train moves it once, in its start-up. On clean47 every grid missed validate by
    0.09-0.12 um (`unexplained`, 21x the noise); one play above half the range at a searched
    radius reaches the noise and the verdict is ``none``."""
    train, validate, p, r = _clean_records(2, "held_ramps")
    h = np.ptp(train[0].v) / 2
    assert h < r[-1] < np.max(np.abs(train[0].v - train[0].v[0]))  # the premise
    rep = diagnose(train, validate, workers=1)
    assert rep.nominal["validate"]["rms"] < 1.5 * rep.verdict["noise_floor"]
    assert rep.verdict["effects"] == ["none"], rep.verdict["effects"]
    assert rep.nominal["model"]["grid_extended"]


def test_few_samples_try_one_play_above_half_the_range():
    """The rule (issue 28, ``_one_above``): with few train samples, one play above half the
    train range ``h`` at a radius searched in ``(h, reach]`` is added when it lowers the train
    BIC by ``ABOVE_MARGIN`` and validate agrees. A stage with such a play gets one within a
    search step of it; stages without one get none; with as many train samples as
    ``_topped_grids`` asks, it is not tried."""
    import importlib

    dg = importlib.import_module("pimodel.diagnosis.diagnose")
    assert dg.ABOVE_MARGIN > 0 and dg.ABOVE_POINTS >= 10
    for seed in (0, 5, 6, 8, 9):  # stages with no play above h: nothing added
        train, validate, _, r = _clean_records(seed, "held_ramps")
        assert r[-1] < np.ptp(train[0].v) / 2
        radii, _, _ = dg._nominal(train, validate, "rest")
        assert radii[-1] <= np.ptp(train[0].v) / 2 + 1e-12, seed
    for seed in (2, 3, 7):  # the train input of these seeds, a stage with one play above h
        rng = np.random.default_rng(seed)
        t, v = _held_ramps(rng, 500.0)
        h, reach = np.ptp(v) / 2, np.max(np.abs(v - v[0]))
        assert reach > 1.3 * h  # room above h for the play
        top = h + 0.37 * (reach - h)
        stage = (np.array([0.6, 0.3, 0.4, 0.5]), np.array([0.0, 0.3 * h, 0.7 * h, top]))
        train, validate, _, _ = _clean_records(seed, "held_ramps", stage=stage)
        half = dg._train_pick(train, [np.linspace(0.0, h, 40)], "rest", True,
                              dg._fitted_samples(train, "rest"))
        above = dg._one_above(train, validate, "rest", half, None,
                              dg._fitted_samples(train, "rest"))
        assert above is not None and above[1].size == 41, seed
        assert abs(above[1][-1] - top) <= (reach - h) / dg.ABOVE_POINTS + 1e-12, seed
        many = [Record(np.arange(4 * len(x)) * 2e-3, np.tile(x.v, 4), np.tile(x.y, 4))
                for x in train]
        assert dg._one_above(many, validate, "rest", half, None, 4 * len(train[0])) is None
