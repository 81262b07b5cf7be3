"""Identification chain: slopes, conventional baseline, the paper's comparison, CLI, errors."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

from pimodel import PIOperator, Record, check_excitation, identify, identify_slopes, save_record
from pimodel.cli import main
from pimodel.identification.conventional import fit_conventional
from pimodel.signals import add_noise_snr, major_minor_loops, triangle

STAGE = PIOperator([6.3460, 1.6735, 1.1552, 0.4477], [0.0, 0.1945, 0.4826, 0.5707])


def random_operator(seed: int, n: int) -> PIOperator:
    rng = np.random.default_rng(seed)
    return PIOperator(rng.uniform(0.3, 1.0, n), np.cumsum(rng.uniform(0.4, 0.8, n)))


@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
@pytest.mark.parametrize("n", [2, 3, 4, 5, 6])
def test_slopes_recover_random_operators_noise_free(n):
    op = random_operator(100 + n, n)
    t, v = triangle(2 * op.radii[-1] + 1, 1, fs=2000, duration=3)
    s = identify_slopes(v, op.simulate(v))
    assert s.n_plays == n
    assert not s.linear_play
    np.testing.assert_allclose(s.weights, op.weights, rtol=0.01)
    np.testing.assert_allclose(s.radii_guess, op.radii, rtol=0.01)


@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
@pytest.mark.parametrize("n", [2, 3, 4, 5, 6])
def test_slopes_recover_random_operators_snr30(n):
    """SNR 30 dB, 200 triangle periods at 2 kHz (400k samples): n exact, weights within 5 %."""
    op = random_operator(200 + n, n)
    t, v = triangle(2 * op.radii[-1] + 1, 1, fs=2000, duration=200)
    y = add_noise_snr(op.simulate(v), 30, np.random.default_rng(n))
    s = identify_slopes(v, y)
    assert s.n_plays == n
    np.testing.assert_allclose(s.weights, op.weights, rtol=0.05)


@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
def test_slopes_detect_linear_play_on_stage():
    t, v = triangle(2, 1, fs=1000, duration=3)
    s = identify_slopes(v, STAGE.simulate(v))
    assert s.linear_play and s.n_plays == 4
    np.testing.assert_allclose(s.weights, STAGE.weights, rtol=1e-3)
    assert s.bic[4] < s.bic[3] and s.bic[4] < s.bic[6]


def paper_comparison_errors(snr_db=None):
    """1 Hz triangle of 2 V peak to peak (the paper's 17 um range) for identification; a
    record with major and minor loops for validation."""
    t, v = triangle(1, 1, fs=1000, duration=3)
    y = STAGE.simulate(v)
    if snr_db is not None:
        y = add_noise_snr(y, snr_db, np.random.default_rng(0))
    tv, vv = major_minor_loops(1, 1, fs=1000, minor_fractions=(0.6, 0.3, 0.15))
    yv = STAGE.simulate(vv)
    proposed = identify(v, y, dt=1e-3, n_plays=4)
    errs = {"proposed n=4": float(np.max(np.abs(proposed.predict(vv) - yv)))}
    for n in (4, 7, 10):
        conv = identify(v, y, dt=1e-3, method="conventional", n_plays=n)
        errs[f"conventional n={n}"] = float(np.max(np.abs(conv.predict(vv) - yv)))
    return errs


@pytest.mark.parametrize("snr_db", [None, 40])
def test_paper_comparison_proposed_beats_conventional_on_minor_loops(snr_db):
    errs = paper_comparison_errors(snr_db)
    best = errs.pop("proposed n=4")
    for name, e in errs.items():
        assert best < e, f"proposed {best:.4f} um not below {name} {e:.4f} um"


def test_conventional_preset_radii_and_positive_weights():
    t, v = triangle(2, 1, fs=1000, duration=3)
    fit = fit_conventional(v, STAGE.simulate(v) + 1.5, 5)
    grid = np.linspace(0, 2.0, 5)  # span = half the 4 V input range
    assert np.all(np.min(np.abs(fit.operator.radii[:, None] - grid[None, :]), axis=1) < 1e-12)
    assert np.all(fit.operator.weights > 0)
    assert fit.operator.is_invertible
    assert abs(fit.offset - 1.5) < 0.5


def test_excitation_check_warns():
    with pytest.warns(UserWarning, match="no reversal"):
        rep = check_excitation(np.linspace(0, 1, 100))
    assert not rep.ok
    t, v = triangle(0.1, 1, fs=500, duration=2)  # range 0.2 V < rho = 0.237 V
    with pytest.warns(UserWarning, match="below the loop width"):
        rep = check_excitation(v, STAGE.weights, STAGE.radii)
    assert not rep.ok
    t, v = triangle(2, 1, fs=500, duration=2)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert check_excitation(v, STAGE.weights, STAGE.radii).ok


@pytest.mark.parametrize(
    ("v", "y", "match"),
    [
        (np.linspace(0, 1, 50), np.linspace(0, 1, 50), "no input reversal"),
        (np.ones(50), np.linspace(0, 1, 50), "the input is constant"),
        (np.sin(np.arange(5.0)), np.sin(np.arange(5.0)), "at least 10 sample"),
        (np.r_[np.sin(np.arange(20.0)), np.nan], np.sin(np.arange(21.0)), "v: sample 20 is nan"),
        (np.sin(np.arange(20.0)), np.sin(np.arange(21.0)), "equal lengths"),
    ],
)
def test_identify_bad_input(v, y, match):
    with pytest.raises(ValueError, match=match):
        identify(v, y, dt=1e-3)


def test_identify_constant_output_and_bad_method():
    t, v = triangle(2, 1, fs=500, duration=2)
    with pytest.raises(ValueError, match="output is constant"):
        identify(v, np.zeros_like(v), dt=2e-3)
    with pytest.raises(ValueError, match="method: expected one of"):
        identify(v, v, dt=2e-3, method="magic")
    with pytest.raises(ValueError, match="n_plays: expected an integer >= 1"):
        fit_conventional(v, v, 0)


@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
def test_cli_identify_writes_json_and_plots(tmp_path):
    t, v = triangle(2, 1, fs=1000, duration=3)
    save_record(Record(t, v, STAGE.simulate(v)), tmp_path / "rec.csv")
    out = tmp_path / "id.json"
    assert main(["identify", str(tmp_path / "rec.csv"), "--json", str(out),
                 "--plots", str(tmp_path / "plots")]) == 0
    data = json.loads(out.read_text())  # a model file: the operator, offset, report
    assert data["type"] == "PIOperator" and data["provenance"]["method"] == "adaptive"
    np.testing.assert_allclose(data["weights"], STAGE.weights, rtol=1e-3)
    np.testing.assert_allclose(data["radii"], STAGE.radii, atol=2e-3)
    assert data["report"]["fit"]["rms_error_percent"] < 0.1
    assert data["report"]["excitation"]["ok"] is True
    assert (tmp_path / "plots" / "identify_adaptive.png").exists()
    assert main(["identify", str(tmp_path / "rec.csv"), "--json", str(out), "--method",
                 "conventional", "--plays", "7"]) == 0
    assert json.loads(out.read_text())["report"]["n_plays"] <= 7
    assert main(["identify", str(tmp_path / "rec.csv"), "--json", str(out), "--method",
                 "joint", "--plots", str(tmp_path / "plots")]) == 0
    data = json.loads(out.read_text())
    assert data["report"]["method"] == "joint" and data["report"]["settings"]["updates"] >= 1
    np.testing.assert_allclose(data["weights"], STAGE.weights, rtol=1e-3)
    np.testing.assert_allclose(data["radii"], STAGE.radii, atol=2e-3)
    assert (tmp_path / "plots" / "identify_joint.png").exists()


@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
def test_real_record_identification(real_record_path):
    from pimodel import load_record

    rec = load_record(real_record_path)
    k0 = int(np.argmax(np.abs(rec.v) > 1))  # skip the initial hold at 0 V
    mid = k0 + (rec.t.size - k0) // 2
    adaptive = identify(rec.v[k0:mid], rec.y[k0:mid], dt=rec.dt)
    conv = identify(rec.v[k0:mid], rec.y[k0:mid], dt=rec.dt, method="conventional", n_plays=10)

    def held_out_rms(idn):
        r = idn.predict(rec.v[k0:])[mid - k0:] - rec.y[mid:]
        return float(np.sqrt(np.mean(r**2)))

    # held-out RMS below 0.5 % of the 39.5 um span, and no worse than the conventional n = 10
    assert held_out_rms(adaptive) < 0.005 * np.ptp(rec.y)
    assert held_out_rms(adaptive) <= held_out_rms(conv)


@pytest.mark.filterwarnings("ignore:identify. radius estimate health")  # the final mean only
def test_identify_reports_progress_on_a_long_record(monkeypatch):
    # a record beyond HISTORY_LIMIT runs the estimator in chunks, each announced with the
    # share done; the progress changes nothing in the result
    from pimodel.identification import chain

    rng = np.random.default_rng(21)
    op = random_operator(22, 3)
    _, v = triangle(amplitude=1.0 + rng.uniform(), freq=1.0, fs=500.0, duration=4.0)
    y = op.simulate(v)
    monkeypatch.setattr(chain, "HISTORY_LIMIT", 1000)
    monkeypatch.setattr(chain, "PROGRESS_CHUNK", int(rng.integers(300, 700)))
    messages: list[str] = []
    ident = identify(v, y, dt=2e-3, n_plays=3, passes=2, progress=messages.append)
    shares = [float(m.rsplit(": ", 1)[1].rstrip(" %")) for m in messages if m.endswith("%")]
    assert messages[0].startswith("loop slopes") and messages[-1] == "errors on the record"
    samples = ident.settings["passes"] * v.size
    assert len(shares) >= -(-v.size // chain.PROGRESS_CHUNK) >= 3  # one per chunk
    assert len(shares) <= -(-samples // chain.PROGRESS_CHUNK)
    assert shares[0] == 0.0 and all(b > a for a, b in zip(shares, shares[1:], strict=False))
    assert shares[-1] < 100.0
    quiet = identify(v, y, dt=2e-3, n_plays=3, passes=2)
    assert np.array_equal(quiet.radii, ident.radii) and np.array_equal(quiet.weights,
                                                                       ident.weights)


def test_identify_runs_blas_on_one_thread_and_restores_the_callers_setting(monkeypatch):
    """Within ``identify`` NumPy's BLAS runs on one thread (its small least squares; a thread
    per core spins on a busy machine, docs/identification.md); the caller's setting is back
    when it returns."""
    from threadpoolctl import threadpool_info, threadpool_limits

    import pimodel.identification.chain as chain

    def blas_threads() -> list[int]:
        return [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]

    seen: list = []
    slopes = chain.identify_slopes

    def watched(*args, **kwargs):
        seen.append(blas_threads())
        return slopes(*args, **kwargs)

    monkeypatch.setattr(chain, "identify_slopes", watched)
    t, v = triangle(2.0, 1.0, fs=1000, duration=6.0)
    y = PIOperator([1.0, 0.5], [0.0, 0.4]).simulate(v)
    with threadpool_limits(2, user_api="blas"):  # the caller's own setting (the tests run one)
        before = blas_threads()
        identify(v, y, dt=1e-3, n_plays=2, passes=2)
        after = blas_threads()
    assert before and seen and all(n == 1 for n in seen[0])
    assert after == before
