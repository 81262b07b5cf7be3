"""Each formerly silent case of issue 14 (Python side) now warns or raises, naming the
parameter and the expected range: passes, n_plays, a record without a loop, an ill-conditioned
inverse, an overflowing input, diagnose with nothing held out."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from pimodel import PIOperator, Record, identify
from pimodel.cli import main
from pimodel.identification.chain import MAX_REPEATED_SAMPLES
from pimodel.records import save_record
from pimodel.signals import sinusoid


@pytest.fixture(scope="module")
def two_play():
    _, v = sinusoid(5, 1, fs=1000, duration=3)
    return v, PIOperator([1.0, 0.5], [0.5, 1.5]).simulate(v)


@pytest.mark.parametrize("passes", [0, -1, 2.0, True, MAX_REPEATED_SAMPLES])
def test_passes_out_of_range(two_play, passes):
    v, y = two_play
    with pytest.raises(ValueError, match=r"passes: expected an integer from 1 to \d+"):
        identify(v, y, dt=1e-3, passes=passes)


@pytest.mark.parametrize("n_plays", [4.0, 0, 65, True, "4", np.float64(2)])
def test_n_plays_must_be_an_integer(two_play, n_plays):
    v, y = two_play
    with pytest.raises(ValueError, match="n_plays: expected an integer from 1 to 64"):
        identify(v, y, dt=1e-3, n_plays=n_plays, method="joint")


def test_n_plays_float_message_says_what_to_write(two_play):
    with pytest.raises(ValueError, match=r"got 4.0 \(a float; write 4\)"):
        identify(*two_play, dt=1e-3, n_plays=4.0)


def test_n_plays_numpy_integer_accepted(two_play):
    idn = identify(*two_play, dt=1e-3, n_plays=np.int64(2), method="joint")
    assert idn.operator.n == 2


def test_no_loop_in_pure_noise_warns_with_the_evidence(two_play):
    v, _ = two_play
    noise = np.random.default_rng(0).normal(size=v.size)
    with pytest.warns(RuntimeWarning, match=r"no hysteresis loop found.*R\^2 = 0\.0"):
        identify(v, noise, dt=1e-3, n_plays=2, method="joint")


def test_a_clear_loop_does_not_warn(two_play):
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        identify(*two_play, dt=1e-3, n_plays=2, method="joint")


def test_ill_conditioned_inverse():
    with pytest.raises(ValueError, match=r"ill-conditioned.*1e\+15.*p_1 = 1e-15"):
        PIOperator([1e-15, 1], [0, 0.2]).inverse()
    with pytest.warns(RuntimeWarning, match=r"ill-conditioned, max P_i / min P_i = 1e\+09"):
        PIOperator([1e-9, 1], [0, 0.2]).inverse()
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        PIOperator([1e-3, 1], [0, 0.2]).inverse()


@pytest.mark.parametrize("value", [1e308, -1e308])
def test_overflowing_input_raises(value):
    op = PIOperator([1.0, 1.0], [0.0, 0.2])
    with pytest.raises(ValueError, match="v: sample 1 .* overflow"):
        op.simulate([0.0, value])
    with pytest.raises(ValueError, match="overflow"):
        op.step(value)


def test_diagnose_warns_when_nothing_is_held_out(tmp_path, capsys):
    t = np.arange(2000) * 1e-3
    v = 3 * np.sin(2 * np.pi * 2 * t)
    path = tmp_path / "a.csv"
    save_record(Record(t, v, PIOperator([1.0, 0.5], [0.0, 0.5]).simulate(v)), path)
    main(["diagnose", "--train", str(path), "--validate", str(path), "--json",
          str(tmp_path / "r.json")])
    err = capsys.readouterr().err.splitlines()  # the CLI prints each warning once
    assert sum("warning: UserWarning: " in e and "nothing is held out" in e for e in err) == 1


def test_cli_passes_bound_exits_2(tmp_path, capsys, two_play):
    v, y = two_play
    path = tmp_path / "d.csv"
    save_record(Record(np.arange(v.size) * 1e-3, v, y), path)
    assert main(["identify", str(path), "--json", str(tmp_path / "o.json"), "--passes",
                 "100000000"]) == 2
    assert "passes: expected an integer from 1 to" in capsys.readouterr().err
