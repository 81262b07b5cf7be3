"""``pimodel demo``: the headline chain on the embedded piezo-like stage, in under a minute.

1. **identify**: a noisy 1 Hz triangle record of the stage (the paper's identified Nano-OP65
   values, 5 nm sensor noise); plays and weights from the loop slopes, radii from the adaptive
   estimator, against the conventional method; errors on a held-out record of nested loops;
2. **compensate**: each model's exact inverse as feedforward on the stage with a 1 kHz mode,
   open loop and with a PID loop;
3. **FMU**: build the three C FMUs and run the adaptive compensation loop in a co-simulation
   master, checked against the native compiled loop;
4. **diagnose**: a stage with creep the model does not know; the diagnosis names the effect
   from train/validate records and says how far the gap shrinks;

and a one-page Markdown report with the figures. Every number in the report is computed here.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from ..diagnosis.summary import markdown_table
from ..identification.chain import identify
from ..loops.actuators import stage_dynamics
from ..loops.compiled import PID, run_loop
from ..plotting import new_figure, save_figure
from ..signals import major_minor_loops, triangle
from .compensation import STAGE, chord_gain

__all__ = [
    "run_demo",
    "step_compensate",
    "step_diagnose",
    "step_fmu",
    "step_identify",
]

FS_ID = 1000.0  # Hz, identification record
FS_LOOP = 10_000.0  # Hz, compensation loops
NOISE_UM = 0.005
GAIN = 50.0  # estimator gain in the co-simulated loop


def step_identify(out: Path) -> tuple[dict, str]:
    """Identify adaptive (n by BIC) and conventional (n = 4, 10) models; held-out errors.

    Parameters
    ----------
    out : pathlib.Path
        Output directory for the figures.

    Returns
    -------
    results : dict
        ``{"identify": numbers, "models": {name: operator}}``.
    text : str
        The report section (Markdown).

    Examples
    --------
    >>> from pathlib import Path
    >>> FS_ID  # identification sample rate [Hz]
    1000.0
    >>> r, text = step_identify(Path("pimodel-demo"))  # doctest: +SKIP
    """
    rng = np.random.default_rng(0)
    t, v = triangle(1.0, 1, fs=FS_ID, duration=3)
    y = STAGE.simulate(v) + rng.normal(0, NOISE_UM, v.size)
    th, vh = major_minor_loops(1.0, 1, fs=FS_ID, minor_fractions=(0.6, 0.3, 0.15))
    yh = STAGE.simulate(vh)
    fits = {"adaptive (slopes + radii)": identify(v, y, dt=1 / FS_ID)}
    for n in (4, 10):
        fits[f"conventional n={n}"] = identify(v, y, dt=1 / FS_ID, method="conventional",
                                               n_plays=n)
    rows, models = [], {}
    for name, idn in fits.items():
        e = yh - idn.predict(vh)
        rows.append([name, idn.operator.n, 100 * idn.rms_error / idn.output_range,
                     100 * float(np.sqrt(np.mean(e**2))) / float(np.ptp(yh)),
                     100 * float(np.max(np.abs(e))) / float(np.ptp(yh))])
        models[name] = idn
    adaptive = fits["adaptive (slopes + radii)"]
    fig, ax = new_figure(2, 1)
    ax[0, 0].plot(v, y, ".", ms=1.5, color="0.6", label="measured (5 nm noise)")
    ax[0, 0].plot(v, adaptive.predict(v), lw=1.0, label=f"adaptive, n={adaptive.operator.n}")
    ax[0, 0].set(xlabel="input voltage v [V]", ylabel="displacement y [um]",
                 title="Identification record: 1 Hz triangle")
    ax[0, 0].legend(loc="upper left", fontsize=8)
    for name, idn in fits.items():
        ax[0, 1].plot(th, yh - idn.predict(vh), lw=0.8, label=name)
    ax[0, 1].set(xlabel="time t [s]", ylabel="held-out error y - model [um]",
                 title="Held-out record: major and nested minor loops")
    ax[0, 1].legend(fontsize=8)
    save_figure(fig, out / "identify.png")
    text = (
        "## 1. Identify\n\n"
        f"Record: 3 periods of a 1 Hz triangle, +-1 V, {FS_ID:.0f} Hz, {1000 * NOISE_UM:.0f} nm "
        "noise. The slopes give the number of plays (BIC) and the weights; the adaptive "
        "estimator gives the radii.\n\n"
        f"Adaptive model: weights {np.round(adaptive.weights, 4).tolist()} um/V, radii "
        f"{np.round(adaptive.radii, 4).tolist()} V (truth {STAGE.weights.tolist()}, "
        f"{STAGE.radii.tolist()}).\n\n"
        + markdown_table(["model", "plays (nonzero weight)", "fit RMS [%]",
                          "held-out RMS [%]", "held-out max [%]"], rows)
        + "\n![identification](identify.png)\n\n"
    )
    nums = {r[0]: {"n": r[1], "fit_rms_percent": r[2], "heldout_rms_percent": r[3],
                   "heldout_max_percent": r[4]} for r in rows}
    nums["adaptive_radii"] = adaptive.radii.tolist()
    return {"identify": nums, "models": models}, text


def step_compensate(out: Path, models: dict) -> tuple[dict, str]:
    """Feedforward with each identified model's inverse, on the stage with a 1 kHz mode.

    Parameters
    ----------
    out : pathlib.Path
        Output directory for the figures.
    models : dict
        The identified operators, ``step_identify(out)[0]["models"]``.

    Returns
    -------
    results : dict
        ``{"compensate": numbers}``.
    text : str
        The report section (Markdown).

    Examples
    --------
    >>> from pathlib import Path
    >>> FS_LOOP  # compensation loop sample rate [Hz]
    10000.0
    >>> r, _ = step_identify(Path("pimodel-demo"))  # doctest: +SKIP
    >>> r2, text = step_compensate(Path("pimodel-demo"), r["models"])  # doctest: +SKIP
    """
    dt = 1 / FS_LOOP
    t, vr = major_minor_loops(1.0, 1, fs=FS_LOOP, minor_fractions=(0.6, 0.3, 0.15))
    yd = STAGE.simulate(vr) - STAGE.simulate(vr).mean()
    G = stage_dynamics(dt, fn_hz=1000, damping=0.05)
    ffs = {"none (static gain)": "none", "exact inverse (true model)": STAGE}
    ffs.update({name: idn.operator for name, idn in models.items()})
    gain = chord_gain()
    rows, nums, runs = [], {}, {}
    for name, ff in ffs.items():
        ol = run_loop(yd, STAGE, dt, dynamics=G, feedforward=ff, ff_gain=gain)
        cl = run_loop(yd, STAGE, dt, dynamics=G, feedforward=ff, ff_gain=gain, pid=PID(0, 20))
        a, b = ol.tracking(), cl.tracking()
        rows.append([name, a["max_percent"], a["rms_percent"], b["max_percent"],
                     b["rms_percent"]])
        nums[name] = {"open_loop": a, "with_pid": b}
        runs[name] = ol
    fig, ax = new_figure(2, 1)
    ax[0, 0].plot(t, yd, lw=2, color="0.7", label="desired y_d")
    for name in ("none (static gain)", "adaptive (slopes + radii)"):
        ax[0, 0].plot(t, runs[name].y, lw=0.8, label=f"y, feedforward: {name}")
        ax[0, 1].plot(t, runs[name].error, lw=0.8, label=name)
    ax[0, 0].set(xlabel="time t [s]", ylabel="displacement [um]",
                 title="Open-loop tracking, stage with 1 kHz mode")
    ax[0, 0].legend(fontsize=7, loc="lower left")
    ax[0, 1].set(xlabel="time t [s]", ylabel="tracking error y_d - y [um]",
                 title="Tracking error without and with inverse feedforward")
    ax[0, 1].legend(fontsize=8)
    save_figure(fig, out / "compensate.png")
    text = (
        "## 2. Compensate\n\n"
        "Reference: the stage's own major and nested minor 1 Hz loops (17 um range), "
        f"{FS_LOOP:.0f} Hz loop, 1 kHz mode (damping 0.05) after the hysteresis. Feedforward "
        "`v = PI_model^-1[y_d]`; the PID loop adds integral action (ki = 20 V/(um s)). Errors "
        "in % of the reference range.\n\n"
        + markdown_table(["feedforward", "open loop max", "open loop RMS", "with PID max",
                          "with PID RMS"], rows)
        + "\n![compensation](compensate.png)\n\n"
    )
    return {"compensate": nums}, text


def step_fmu(out: Path, weights) -> tuple[dict, str]:
    """Build the FMUs and co-simulate the adaptive compensation loop; compare with native.

    Parameters
    ----------
    out : pathlib.Path
        Output directory (the FMUs go to ``out / "fmus"``).
    weights : array_like
        Play weights of the adaptive model (from step 1).

    Returns
    -------
    results : dict
        ``{"fmu": numbers}``.
    text : str
        The report section (Markdown).

    Examples
    --------
    >>> from pathlib import Path
    >>> GAIN  # estimator gain in the co-simulated loop
    50.0
    >>> r, text = step_fmu(Path("pimodel-demo"), [1.0, 0.5, 0.3, 0.2])  # doctest: +SKIP
    """
    from ..fmu import build_fmus
    from ..fmu.cosim import LOOP_UNITS
    from .fmu_comparison import compare_with_native, plot_comparison

    fmu_dir = out / "fmus"
    t0 = time.perf_counter()
    paths = build_fmus(fmu_dir, LOOP_UNITS)
    t_build = time.perf_counter() - t0
    n = len(weights)
    r0 = [0.0, *np.linspace(0.3, 0.8, n - 1).round(3).tolist()]  # deliberately wrong start
    cmp = compare_with_native(fmu_dir, duration=1.0, weights=weights, initial_radii=r0,
                              gain=GAIN)
    plot_comparison(cmp, out / "fmu_cosimulation.png")
    co, steps = cmp.cosim, cmp.cosim.t.size
    nums = {"fmus": [p.name for p in paths], "build_s": t_build, "steps": steps,
            "cosim_steps_per_s": cmp.cosim_steps_per_s,
            "max_abs_difference_um": cmp.max_difference, "final_radii": co.radii[-1].tolist(),
            "tracking_last_20_percent": co.tracking(int(0.8 * steps))}
    text = (
        "## 3. FMU co-simulation\n\n"
        f"Built {', '.join(nums['fmus'])} (FMI 2.0 co-simulation, C) into `fmus/` in "
        f"{t_build:.1f} s. A fixed-step master runs plant FMU + 1 kHz mode + RadiusEstimator "
        "FMU + adaptive InversePI FMU (weights from step 1) on a 5 Hz triangle, the estimator "
        f"starting from wrong radii {r0}: {steps} steps at "
        f"{nums['cosim_steps_per_s']:.0f} steps/s; largest difference "
        f"from the native compiled loop {cmp.max_difference:.1e} um; final radii "
        f"{np.round(co.radii[-1], 4).tolist()} V (truth {STAGE.radii.tolist()}); tracking "
        f"error over the last 20 %: max {nums['tracking_last_20_percent']['max_percent']:.2f} % "
        "of range.\n\n![FMU co-simulation](fmu_cosimulation.png)\n\n"
    )
    return {"fmu": nums}, text


def step_diagnose(out: Path) -> tuple[dict, str]:
    """A stage with creep (1.5 %/decade) the PI model lacks: where, which effect, how far.

    Parameters
    ----------
    out : pathlib.Path
        Output directory for the figures.

    Returns
    -------
    results : dict
        ``{"diagnose": verdict}``.
    text : str
        The report section (Markdown).

    Examples
    --------
    >>> from pathlib import Path
    >>> NOISE_UM  # sensor noise of the identification record [um]
    0.005
    >>> r, text = step_diagnose(Path("pimodel-demo"))  # doctest: +SKIP
    """
    from ..diagnosis import diagnose
    from ..diagnosis.plots import plot_diagnosis
    from ..stages.pi_stage import Truth, excitation

    truth = Truth(creep_percent_per_decade=1.5)
    tt, vt = excitation("train", seed=1)
    tv, vv = excitation("validate", seed=2)
    rep = diagnose([truth.record(tt, vt, 1, "train")], [truth.record(tv, vv, 2, "validate")])
    figs = plot_diagnosis(rep, out, prefix="diagnose_")
    v = rep.verdict
    top = rep.where["regions"][:3]
    rows = [[c["effect"], c["validate"]["rms"], c.get("delta_bic", float("nan"))]
            for c in rep.candidates]
    text = (
        "## 4. Diagnose the sim-to-real gap\n\n"
        "The 'real' stage here has creep (1.5 % of the last move per decade, simulated); the "
        "diagnosis is not told. Train: triangles, minor loops, steps with holds; validate: sines, "
        "minor loops, other steps.\n\n"
        f"**Verdict: {', '.join(v['effects'])}**; validate RMS {v['gap_before']:.4f} um -> "
        f"{v['gap_after']:.4f} um (shrink {100 * v['shrink']:.0f} %).\n\n"
        + "Where the residual concentrates (energy share / sample share): "
        + "; ".join(f"{r['region']} ({100 * r['energy_share']:.0f} % of the energy in "
                    f"{100 * r['sample_share']:.0f} % of the samples)" for r in top)
        + ".\n\n"
        + markdown_table(["candidate alone", "validate RMS [um]", "delta BIC"], rows)
        + "\n" + "\n".join(f"![{p.stem}]({p.name})" for p in figs) + "\n"
    )
    return {"diagnose": v}, text


def run_demo(out_dir="pimodel-demo") -> Path:
    """Run the chain; write ``report.md``, ``results.json`` and figures into ``out_dir``.

    Parameters
    ----------
    out_dir : str or pathlib.Path, optional
        Output directory (created if missing).

    Returns
    -------
    pathlib.Path
        The path of ``report.md``.

    Examples
    --------
    >>> import inspect
    >>> inspect.signature(run_demo).parameters["out_dir"].default
    'pimodel-demo'
    >>> run_demo("pimodel-demo")  # doctest: +SKIP
    PosixPath('.../pimodel-demo/report.md')
    """
    out = Path(out_dir).resolve()
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    res, parts = {}, []
    r, text = step_identify(out)
    models = r.pop("models")
    res.update(r)
    parts.append(text)
    for step in (lambda: step_compensate(out, models),
                 lambda: step_fmu(out, models["adaptive (slopes + radii)"].weights),
                 lambda: step_diagnose(out)):
        r, text = step()
        res.update(r)
        parts.append(text)
    res["elapsed_s"] = time.perf_counter() - t0
    (out / "results.json").write_text(json.dumps(res, indent=2, default=float))
    report = out / "report.md"
    report.write_text(
        "# pimodel demo: identify, compensate, co-simulate, diagnose\n\n"
        "Stage: the paper's identified piezo stage (Nano-OP65, 4 plays, voltage [V] to "
        f"displacement [um]). Whole chain: {res['elapsed_s']:.0f} s.\n\n" + "".join(parts))
    return report
