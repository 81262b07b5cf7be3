"""Study: identification of the shared real piezo record (chandratue/SmartHysteresis, 1 Hz,
+-150 V): adaptive (slopes + radii) against conventional, trained on the first half of the sine
cycles after the initial hold and scored on the held-out second half. Skipped with a message
when ../shared is absent. ``--quick`` is the same size (about 10 s)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from pimodel import identify, load_record  # noqa: E402
from pimodel.experiments.studies import StudyResult, Table, study_main  # noqa: E402
from pimodel.plotting import new_figure, save_figure  # noqa: E402

REAL = Path(__file__).resolve().parents[2] / "shared" / "data" / "real" / \
    "smarthysteresis-piezo-1hz" / "piezo_1hz.csv"


def run(out: Path, quick: bool = False) -> StudyResult:
    res = StudyResult("real_data")
    if not REAL.exists():
        res.notes.append(f"skipped: the shared real record is not at {REAL}")
        res.numbers = {"skipped": True}
        return res
    rec = load_record(REAL)
    k0 = int(np.argmax(np.abs(rec.v) > 1))
    mid = k0 + (len(rec) - k0) // 2
    models = {"adaptive (BIC)": identify(rec.v[k0:mid], rec.y[k0:mid], dt=rec.dt),
              "adaptive n=4": identify(rec.v[k0:mid], rec.y[k0:mid], dt=rec.dt, n_plays=4),
              "joint (BIC)": identify(rec.v[k0:mid], rec.y[k0:mid], dt=rec.dt, method="joint"),
              "joint n=4": identify(rec.v[k0:mid], rec.y[k0:mid], dt=rec.dt, n_plays=4,
                                    method="joint")}
    for n in (4, 10, 20):
        models[f"conventional n={n}"] = identify(rec.v[k0:mid], rec.y[k0:mid], dt=rec.dt,
                                                 method="conventional", n_plays=n)
    rows, numbers = [], {}
    span = float(np.ptp(rec.y))
    for name, idn in models.items():
        r = idn.predict(rec.v[k0:])[mid - k0:] - rec.y[mid:]
        rms, mx = float(np.sqrt(np.mean(r**2))), float(np.max(np.abs(r)))
        rows.append([name, idn.operator.n, idn.rms_error, rms, 100 * rms / span, mx])
        numbers[name] = {"n": idn.operator.n, "held_out_rms": rms, "held_out_max": mx}
    res.tables.append(Table("Real record: train on the first half, score on the held-out half",
                            ["model", "n", "train RMS [um]", "held-out RMS [um]",
                             "held-out RMS [% span]", "held-out max [um]"], rows))
    best = models["adaptive (BIC)"]
    fig, ax = new_figure(2, 1)
    ax[0, 0].plot(rec.v[mid:], rec.y[mid:], ".", ms=1, alpha=0.4, label="measured (held out)")
    ax[0, 0].plot(rec.v[mid:], best.predict(rec.v[k0:])[mid - k0:], lw=0.8,
                  label=f"adaptive, n = {best.operator.n}")
    ax[0, 0].set(xlabel="input voltage v [V]", ylabel="displacement y [um]",
                 title="Real piezo record, held-out half")
    ax[0, 0].legend(markerscale=8)
    ax[0, 1].plot(rec.t[mid:], best.predict(rec.v[k0:])[mid - k0:] - rec.y[mid:], lw=0.6,
                  label="model - measured")
    ax[0, 1].set(xlabel="time t [s]", ylabel="residual [um]", title="Held-out residual")
    ax[0, 1].legend()
    res.figures.append(save_figure(fig, out / "real_data.png"))
    res.numbers = numbers
    return res


if __name__ == "__main__":
    sys.exit(study_main("real_data"))
