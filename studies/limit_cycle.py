"""Study: limit cycles of the piezo-like stage (PI hysteresis + 1 kHz mode) under PI feedback,
predicted by the PI operator's describing function and checked in closed-loop simulation.

Loop (compiled, 50 kHz): ``u = PI-controller(y_d - y)``, ``h = H[u]``, ``y = G(z) h`` with the
stage's mode ``G`` (1 kHz, damping 0.05). The hysteresis ``H`` the controller sees is the stage
itself (no compensation, input in V) or, with inverse compensation, the residual
``stage o model^-1`` of an inverse built from a model whose radii are 20 % too small (input in
um; again a PI operator, with signed weights). Two integral-dominated PI controllers are scaled
to the nominal gain (the stage's chord gain at +-1 V, or 1 with compensation): a moderate one
(the linearised loop would go unstable at twice the nominal gain) and a high-gain one (at 0.97
times the nominal gain). For each case: the sector (Lemma 1) and the circle criterion, the
harmonic balance ``1 + N(A) L(e^{jw dt}) = 0`` (amplitude, frequency, stability by Loeb's
criterion), and the simulation: a small reference step (a stable limit cycle is reached, or the
loop settles) and, for an unstable limit cycle, the threshold amplitude found by bisection on a
burst injected at the nonlinearity's input. ``--quick`` runs 1 s instead of 2 s of step response
and 14 instead of 30 bisection steps.
"""

from __future__ import annotations

import sys
from pathlib import Path

import control
import numpy as np

from pimodel.experiments.compensation import STAGE
from pimodel.experiments.studies import StudyResult, Table, study_main
from pimodel.loops.actuators import stage_dynamics
from pimodel.loops.compiled import PID, run_loop
from pimodel.loops.describing import (
    circle_criterion,
    harmonic_balance,
    residual_hysteresis,
    sector,
    static_gain,
)
from pimodel.operators.pi import PIOperator
from pimodel.plotting import new_figure, save_figure

FS = 50_000.0  # Hz: 50 samples per period of the 1 kHz mode
DT = 1.0 / FS
FN_HZ, DAMPING = 1000.0, 0.05
PI_ZERO_HZ = 3300.0  # integral-dominated PI: kp = ki / (2 pi PI_ZERO_HZ)
CRITICAL_GAINS = {"moderate": 2.0, "high-gain": 0.97}  # gain (x nominal) where the linear loop
MODEL = PIOperator(STAGE.weights, 0.8 * STAGE.radii)  # the wrong model: radii 20 % low
STEP_UM = 1.0  # reference step that starts each run


def pid_tf(pid: PID, dt: float) -> control.TransferFunction:
    """The compiled loops' PID as a discrete transfer function from ``e`` to ``u``.

    ``I[k] = I[k-1] + dt e[k]``, ``D[k] = (tf D[k-1] + kd (e[k] - e[k-1])) / (tf + dt)``,
    ``u[k] = kp e[k] + ki I[k] + D[k]`` (``fmu/src/pim_loops.c``)::

        C(z) = kp + ki dt z / (z - 1) + kd / (tf + dt) (z - 1) / (z - tf / (tf + dt))
    """
    z = control.tf([1.0, 0.0], [1.0], dt)
    C = pid.kp + pid.ki * dt * z / (z - 1)
    if pid.kd:
        tf = 10 * dt if pid.tf is None else pid.tf
        C = C + pid.kd / (tf + dt) * (z - 1) / (z - tf / (tf + dt))
    return C


def controller(critical_gain: float, nominal_gain: float, G) -> PID:
    """PI (zero at PI_ZERO_HZ) scaled so that the loop ``C G`` closed with the static gain
    ``g`` loses stability at ``g = critical_gain * nominal_gain``."""
    ki = 1.0
    shape = PID(ki / (2 * np.pi * PI_ZERO_HZ), ki)
    L = pid_tf(shape, DT) * G
    w = np.linspace(0.5, 1.5, 200_001) * 2 * np.pi * FN_HZ
    H = np.asarray(L(np.exp(1j * w * DT))).ravel()
    k = np.flatnonzero((np.diff(np.sign(H.imag)) != 0) & (H[:-1].real < 0))[0]
    g_unit = -1.0 / H[k].real  # critical static gain for ki = 1
    s = g_unit / (critical_gain * nominal_gain)
    return PID(shape.kp * s, shape.ki * s)


def first_harmonic(v: np.ndarray, fs: float) -> tuple[float, float]:
    """Amplitude (least-squares sine fit) and frequency [Hz] (interpolated upward zero
    crossings) of the oscillation in ``v`` about its mean."""
    x = v - v.mean()
    i = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))
    if i.size < 3:
        return 0.0, float("nan")
    tc = i + x[i] / (x[i] - x[i + 1])
    f = fs * (tc.size - 1) / (tc[-1] - tc[0])
    t = np.arange(x.size) / fs
    M = np.column_stack([np.sin(2 * np.pi * f * t), np.cos(2 * np.pi * f * t), np.ones_like(t)])
    c = np.linalg.lstsq(M, x, rcond=None)[0]
    return float(np.hypot(c[0], c[1])), float(f)


def _burst_outcome(op, pid, G, amp, f_hz, periods=10, settle=0.15):
    """Amplitude of ``u`` just after a burst of ``amp`` at ``f_hz`` injected at the
    nonlinearity's input (via the feedforward path), and at the end of the run."""
    n = int(settle * FS)
    t = np.arange(n) * DT
    tb = periods / f_hz
    scale = 1e3  # inject through ff_gain so the reference (and the error) stay ~0
    ref = np.where(t < tb, amp * np.sin(2 * np.pi * f_hz * t), 0.0) / scale
    r = run_loop(ref, op, DT, dynamics=G, feedforward="none", ff_gain=scale, pid=pid)
    per = int(round(3 * FS / f_hz))
    i0 = int(tb * FS) + per // 3
    a0 = first_harmonic(r.v[i0:i0 + per], FS)[0]
    a1 = first_harmonic(r.v[-per:], FS)[0]
    return a0, a1, r


def threshold(op, pid, G, f_hz, iters):
    """Bisection on the burst amplitude: the oscillation amplitude that separates decay from
    growth (the simulated unstable limit cycle), and its frequency."""
    lo, hi = 1e-3, 1e3
    grows_hi = _burst_outcome(op, pid, G, hi, f_hz)
    if not grows_hi[1] > grows_hi[0]:
        return float("nan"), float("nan"), None
    for _ in range(iters):
        mid = np.sqrt(lo * hi)
        a0, a1, _ = _burst_outcome(op, pid, G, mid, f_hz)
        if a1 > a0:
            hi = mid
        else:
            lo = mid
    a0, a1, r = _burst_outcome(op, pid, G, hi, f_hz)
    i0 = int(10 / f_hz * FS)
    amp, f = first_harmonic(r.v[i0 + int(FS / f_hz):i0 + int(6 * FS / f_hz)], FS)
    return a0, f, r


def run(out: Path, quick: bool = False) -> StudyResult:
    res = StudyResult("limit_cycle")
    G = stage_dynamics(DT, fn_hz=FN_HZ, damping=DAMPING)
    k_nom = static_gain(STAGE, 1.0)
    residual = residual_hysteresis(STAGE, MODEL)
    plants = {
        "no compensation": (STAGE, k_nom, "V"),
        "inverse (radii 20 % low)": (residual, 1.0, "um"),
    }
    cases, runs, loops, rows = {}, {}, {}, []
    for pname, (op, gnom, unit) in plants.items():
        F = op.describing_function()
        amps = _search_amplitudes(unit)
        for cname, kc in CRITICAL_GAINS.items():
            pid = controller(kc, gnom, G)
            L = pid_tf(pid, DT) * G
            sec = sector(op)
            cc = circle_criterion(L, sec)
            cycles = harmonic_balance(L, F, amps)
            n = int((1.0 if quick else 2.0) * FS)
            step = run_loop(np.full(n, STEP_UM), op, DT, dynamics=G, feedforward="none",
                            ff_gain=0.0, pid=pid)
            win = int(0.1 * FS)
            a_end, f_end = first_harmonic(step.v[-win:], FS)
            a_prev, _ = first_harmonic(step.v[-2 * win:-win], FS)
            swing = float(np.ptp(step.v[-win:]) / 2)
            sim = {"final_amplitude": a_end, "final_frequency_hz": f_end,
                   "final_half_range": swing,
                   "converged": bool(abs(a_end - a_prev) <= 0.01 * max(a_end, 1e-12))}
            stable = [c for c in cycles if c.stable]
            unstable = [c for c in cycles if not c.stable]
            key = f"{pname}, {cname}"
            d = {"sector": sec, "pid": {"kp": pid.kp, "ki": pid.ki}, "unit": unit,
                 "circle_criterion": {"holds": cc.holds, "margin": cc.margin},
                 "limit_cycles": [{"amplitude": c.amplitude, "frequency_hz": c.frequency_hz,
                                   "stable": c.stable} for c in cycles],
                 "step": sim}
            if stable:
                p = stable[0]
                d["compare"] = {"kind": "stable", "predicted_amplitude": p.amplitude,
                                "predicted_frequency_hz": p.frequency_hz,
                                "simulated_amplitude": a_end, "simulated_frequency_hz": f_end}
            elif unstable:
                p = unstable[0]
                a_thr, f_thr, burst = threshold(op, pid, G, p.frequency_hz, 14 if quick else 30)
                d["compare"] = {"kind": "unstable (threshold)", "predicted_amplitude": p.amplitude,
                                "predicted_frequency_hz": p.frequency_hz,
                                "simulated_amplitude": a_thr, "simulated_frequency_hz": f_thr}
                runs[key + " (burst at threshold)"] = burst
            if "compare" in d:
                c = d["compare"]
                c["amplitude_error"] = c["simulated_amplitude"] / c["predicted_amplitude"] - 1
                c["frequency_error"] = (c["simulated_frequency_hz"] / c["predicted_frequency_hz"]
                                        - 1)
            cases[key] = d
            runs[key] = step
            loops[key] = (L, cycles)
            pred = "; ".join(f"{c.amplitude:.3g} {unit} @ {c.frequency_hz:.1f} Hz "
                             f"({'stable' if c.stable else 'unstable'})" for c in cycles) or "none"
            if "compare" in d:
                c = d["compare"]
                simtxt = (f"{c['simulated_amplitude']:.3g} {unit} @ "
                          f"{c['simulated_frequency_hz']:.1f} Hz ({c['kind']})")
                errs = (f"{100 * c['amplitude_error']:+.2f} % / "
                        f"{100 * c['frequency_error']:+.2f} %")
            else:
                size = "< 1e-12" if swing < 1e-12 else f"{swing:.1e}"
                simtxt = f"settles (final half range {size} {unit})"
                errs = "-"
            rows.append([pname, cname, f"[{sec[0]:.4g}, {sec[1]:.4g}]",
                         f"{'holds' if cc.holds else 'fails'} ({cc.margin:.3g})", pred, simtxt,
                         errs])
    res.tables.append(Table(
        "Limit cycles: circle criterion, describing-function prediction, simulation "
        "(amplitude of the hysteresis input u)",
        ["hysteresis seen", "loop", "sector [min, max] slope", "circle criterion (margin)",
         "DF prediction", "simulation", "error amplitude / frequency"], rows))
    res.numbers = dict(cases)
    res.numbers["k_nominal_um_per_V"] = k_nom
    res.numbers["residual"] = {"weights": residual.weights, "radii": residual.radii}
    res.notes += [
        f"Stage: the paper's piezo-like PI operator (weights {STAGE.weights.tolist()} um/V, radii "
        f"{STAGE.radii.tolist()} V), mode {FN_HZ:.0f} Hz with damping {DAMPING}, loop at "
        f"{FS / 1000:.0f} kHz; nominal gain {k_nom:.4g} um/V (chord of the +-1 V loop).",
        f"Wrong model: radii x 0.8; the residual hysteresis stage o model^-1 is the PI operator "
        f"with weights {np.round(residual.weights, 4).tolist()} and radii "
        f"{np.round(residual.radii, 4).tolist()} um.",
        "Circle criterion on the differenced loop with the Lemma 1 sector: 'holds' proves "
        "that no limit cycle exists; 'fails' proves nothing.",
        "A stable predicted limit cycle is compared with the end of a 1 um step response; an "
        "unstable one with the decay/growth threshold found by bisection on an injected burst.",
    ]
    res.figures.append(_nyquist_figure(out, plants, loops))
    res.figures.append(_time_figure(out, runs, cases))
    return res


def _search_amplitudes(unit: str) -> np.ndarray:
    """Amplitudes searched for limit cycles: 1 mV to 50 V, or the same range in um."""
    return np.geomspace(1e-3, 50.0, 500) * (1.0 if unit == "V" else static_gain(STAGE, 1.0))


def _nyquist_figure(out, plants, loops) -> Path:
    fig, ax = new_figure(3, 1, size=(5.6, 5.0))
    w = np.geomspace(2 * np.pi * 300, 2 * np.pi * 3000, 4000)
    panels = [(ax[0, 0], "no compensation", None),
              (ax[0, 1], "inverse (radii 20 % low)", None),
              (ax[0, 2], "inverse (radii 20 % low)", "zoom")]
    for a, pname, zoom in panels:
        op, _, unit = plants[pname]
        F = op.describing_function()
        loc = -1.0 / F.describing_function(_search_amplitudes(unit))
        for i, cname in enumerate(CRITICAL_GAINS):
            L, cycles = loops[f"{pname}, {cname}"]
            H = np.asarray(L(np.exp(1j * w * DT))).ravel()
            a.plot(H.real, H.imag, lw=1.0, color=f"C{i}", label=f"L(e^jw dt), {cname} PI")
            for c in cycles:
                p = complex(-1.0 / F.describing_function(c.amplitude))
                a.plot(p.real, p.imag, "o" if c.stable else "x", ms=7, mfc="none", color="k",
                       label=f"{'stable' if c.stable else 'unstable'} LC {c.amplitude:.3g} "
                             f"{unit} @ {c.frequency_hz:.0f} Hz")
        a.plot(loc.real, loc.imag, lw=2.0, color="C3", label="-1/N(A)")
        s = sector(op)
        a.axvspan(-1 / s[0], -1 / s[1], color="C3", alpha=0.12, label="[-1/min, -1/max] slope")
        a.axhline(0, color="0.6", lw=0.5)
        if zoom:
            a.set(xlim=(-1.3, -0.9), ylim=(-0.06, 0.06))
        else:
            span = 1.6 / s[0]
            a.set(xlim=(-span, 0.3 * span), ylim=(-0.8 * span, 0.8 * span))
        a.set(xlabel="real part", ylabel="imaginary part",
              title=f"{pname}{' (zoom)' if zoom else ''}: L and -1/N(A)")
        handles, labels = a.get_legend_handles_labels()
        uniq = dict(zip(labels, handles, strict=True))
        a.legend(uniq.values(), uniq.keys(), fontsize=6.5, loc="lower left")
    return save_figure(fig, out / "nyquist.png")


def _time_figure(out, runs, cases) -> Path:
    fig, ax = new_figure(3, 1, size=(5.6, 4.2))
    key = "inverse (radii 20 % low), high-gain"
    r, c = runs[key], cases[key].get("compare")
    ax[0, 0].plot(r.t, r.v, lw=0.5, label="u (hysteresis input)")
    if c:
        for sgn in (1, -1):
            ax[0, 0].axhline(r.v[-5000:].mean() + sgn * c["predicted_amplitude"], color="k",
                             ls="--", lw=0.8,
                             label="DF prediction" if sgn == 1 else None)
    ax[0, 0].set(xlabel="time t [s]", ylabel="u [um]",
                 title="With inverse (radii 20 % low), high-gain PI: a limit cycle")
    ax[0, 0].legend(fontsize=8)
    if c:
        n = int(5e-3 * FS)
        t, v = r.t[-n:], r.v[-n:]
        amp, f = c["predicted_amplitude"], c["predicted_frequency_hz"]
        ax[0, 2].plot(1e3 * t, v, ".", ms=3, label="simulated u (50 kHz samples)")
        # sine of the predicted amplitude and frequency, phase fitted to the samples
        M = np.column_stack([np.sin(2 * np.pi * f * t), np.cos(2 * np.pi * f * t)])
        cs = np.linalg.lstsq(M, v - v.mean(), rcond=None)[0]
        ax[0, 2].plot(1e3 * t, v.mean() + amp * M @ (cs / np.hypot(*cs)), lw=1.0,
                      label=f"DF: {amp:.3g} um at {f:.0f} Hz")
        ax[0, 2].set(xlabel="time t [ms]", ylabel="u [um]", title="Last 5 ms of the limit cycle")
        ax[0, 2].legend(fontsize=8, loc="lower left")
    key = "no compensation, high-gain (burst at threshold)"
    if key in runs and runs[key] is not None:
        rb = runs[key]
        c = cases["no compensation, high-gain"]["compare"]
        ax[0, 1].plot(rb.t, rb.v, lw=0.5, label="u after a burst at the threshold")
        for sgn in (1, -1):
            ax[0, 1].axhline(sgn * c["predicted_amplitude"], color="k", ls="--", lw=0.8,
                             label="DF unstable limit cycle" if sgn == 1 else None)
        ax[0, 1].set(xlabel="time t [s]", ylabel="u [V]",
                     title="No compensation, high-gain PI: threshold between decay and growth")
        ax[0, 1].legend(fontsize=8)
    return save_figure(fig, out / "time_response.png")


if __name__ == "__main__":
    sys.exit(study_main("limit_cycle"))
