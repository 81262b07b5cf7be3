"""A diagnosis in words: the verdict, how sure it is, where the gap sits and the next thing to
try (:func:`summarize`, :func:`hints`), and the Markdown report with its figures
(:func:`write_report`). Reads a :class:`~pimodel.diagnosis.diagnose.DiagnosisReport` (one
rebuilt from JSON too: the figures then are left out); computes nothing new.
"""

from __future__ import annotations

from pathlib import Path

__all__ = [
    "confidence",
    "drift_words",
    "hints",
    "markdown_table",
    "next_step",
    "summarize",
    "write_report",
]

STARTUP = "start-up"  # the start of the start-up region's name (pimodel.diagnosis.where)
DOMINANT = 1.5  # a region dominates when its concentration is at least this
STARTUP_MAJORITY = 0.5  # the start-up dominates outside the top two with this energy share
NOTES = ("the noise floor is estimated", "each validate record sits")  # hints, not next steps
NEAR_NOISE = 2.0  # the gap after is "at the noise" within this factor of the noise floor
MEANING = {
    "none": "the nominal PI model explains the validate records to the noise",
    "creep": "slow creep after moves (a memory of the input history over seconds)",
    "drift": "a slow drift or a level of each record's own, independent of the input",
    "dynamics": "linear dynamics (a mode or a lag) beside the hysteresis",
    "delay": "a pure time delay between input and output",
    "asymmetry": "an asymmetric output map (the loop differs at the two ends)",
    "rate": "hysteresis that widens with the input rate",
    "unexplained": "a gap no candidate effect explains",
}


def _ratio(v: dict) -> float:
    return float(v.get("gap_after_over_noise", v["gap_after"] / max(v["noise_floor"], 1e-300)))


def _extrapolated(rep) -> list[dict]:
    """The validate records (``nominal["coverage"]["records"]``, :mod:`.coverage`) that drive
    plays above half the train input's range on loops, when the verdict is not ``none``; a
    report without ``coverage`` (older JSON) gives none."""
    if rep.verdict["effects"] == ["none"]:
        return []
    cov = (getattr(rep, "nominal", None) or {}).get("coverage") or {}
    return [dict(r, source=r["source"] or f"validate record {k}")
            for k, r in enumerate(cov.get("records", [])) if r["loops_above"] > 0]


def confidence(rep) -> tuple[str, str]:
    """How sure the verdict is: ``("sure" | "fairly sure" | "unsure", reason)``.

    ``sure``: the gap after the chosen model is within ``NEAR_NOISE`` times the noise floor
    and no other effect explains the gap as well (``verdict["alternatives"]`` empty) nor
    stands in for a named one (``verdict["interchangeable"]`` empty);
    ``fairly sure``: at the noise but with alternatives or stand-ins, or a named effect with a
    residual above the noise that is not ``unexplained``; ``unsure``: part of the gap is
    unexplained, or (the verdict not ``none``) a validate record drives plays on loops that
    train moved only in its start-up or never (``nominal["coverage"]``, :mod:`.coverage`):
    the gap may be the nominal's extrapolation.

    Parameters
    ----------
    rep : DiagnosisReport
        Uses ``verdict`` only.

    Returns
    -------
    tuple of str
        The level and a sentence giving the figures behind it.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> rep = SimpleNamespace(verdict={"effects": ["creep"], "gap_after": 0.011,
    ...     "noise_floor": 0.01, "alternatives": [], "unexplained": {"share": 0.0}})
    >>> confidence(rep)[0]
    'sure'
    """
    v = rep.verdict
    ratio = _ratio(v)
    alts = v.get("alternatives") or []
    at = f"the gap left is {ratio:.1f} times the noise floor"
    if _extrapolated(rep):
        return "unsure", f"{at}; validate drives plays train did not identify (see the hints)"
    if "unexplained" in v["effects"]:
        share = 100 * v["unexplained"].get("share", 0.0)
        return "unsure", f"{at}; {share:.0f} % of the gap's energy is unexplained"
    if alts:
        verb = "explains" if len(alts) == 1 else "explain"
        return "fairly sure", f"{at}, but {' and '.join(alts)} {verb} it about as well " \
                              "(the records cannot tell them apart)"
    swaps = v.get("interchangeable") or []
    if swaps:
        return "fairly sure", f"{at}, but " + " and ".join(
            f"{s['instead']} in place of {s['effect']} fits validate about as well (RMS "
            f"{s['ratio']:.2f} times the verdict's)" for s in swaps) + \
            ": the records cannot tell them apart"
    if ratio <= NEAR_NOISE:
        return "sure", f"{at} and no other effect explains it as well"
    return "fairly sure", at


def _regions(where: dict, n: int = 3) -> list[dict]:
    return [r for r in where.get("regions", []) if r["concentration"] > 1.0][:n]


def hints(rep) -> list[str]:
    """What the data suggests trying, one sentence each, most useful first.

    Parameters
    ----------
    rep : DiagnosisReport
        Uses ``verdict`` (``closed_loop_records`` among it, when present), ``where``,
        ``nominal["initial_state"]`` and ``nominal["coverage"]`` (when present).

    Returns
    -------
    list of str
        Possibly empty.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> rep = SimpleNamespace(verdict={"effects": ["none"], "gap_after": 0.01,
    ...     "noise_floor": 0.01, "alternatives": [], "unexplained": {"share": 0.0},
    ...     "noise_floor_method": "repeated periods", "model": {}},
    ...     where={"regions": [{"region": "start-up (until ...)", "concentration": 3.0,
    ...     "energy_share": 0.6, "sample_share": 0.2}]}, nominal={"initial_state": "rest"})
    >>> hints(rep)[0][:30]
    'the start-up region dominates '
    """
    v, out = rep.verdict, []
    ext = _extrapolated(rep)
    if ext:
        cov = rep.nominal["coverage"]
        a, b = cov["train_range"]
        recs = "; ".join(f"{r['source']} (input {r['range'][0]:.4g} to "
                         f"{r['range'][1]:.4g}) at {100 * r['loops_above']:.1f} % of its samples"
                         f" from {r['first_loop_s']:.3g} s, plays train never moved at "
                         f"{100 * r['beyond_reach']:.1f} %" for r in ext[:2])
        out.append(f"validate drives plays of radius above half the train input's range "
                   f"({cov['half_range']:.4g}; train input {a:.4g} to {b:.4g}) on loops: "
                   f"{recs}; train identifies those plays by its start-up alone or not at all, "
                   "so no model fitted on train is checked there and the gap may be the "
                   "nominal's extrapolation, not an effect: record train over at least the "
                   "validate input's range")
    top = _regions(rep.where, 2)
    # the start-up dominates when it is among the two most concentrated regions, or when it
    # holds most of the residual (STARTUP_MAJORITY): regions inside it (fast input, ascending
    # branches of its first sweep) can be more concentrated and rank above it (issue 28)
    start = [r for r in rep.where.get("regions", []) if r["region"].startswith(STARTUP) and
             r["concentration"] >= DOMINANT and
             (r in top or r.get("energy_share", 0.0) >= STARTUP_MAJORITY)]
    choice = rep.nominal.get("initial_state_choice") or {}
    if choice.get("chosen") == "unknown":  # initial_state "auto" left the start-ups out
        over = {k: (choice.get(k) or 0.0) > lim for k, lim in choice["limits"].items()}
        why = [f"{choice['post_startup_ratio']:.3g} times the mean squared misfit after "
               "validate's start-up of a nominal fitted without it"
               if over["post_startup_ratio"] else "",
               f"{choice['startup_ratio']:.3g} times as much misfit in validate's start-up as "
               "after it" if over["startup_ratio"] else ""]
        why = [w for w in why if w]
        second = choice.get("second_look")
        if second is not None:  # decided by the two diagnoses (diagnose._final_start)
            rest = ", ".join(second.get("rest_effects", []))
            ratio = second["post_startup_ratio"]
            if ratio > second["limits"]["post_startup_ratio"] or second.get("other_effects"):
                than = (f"{ratio:.3g} times worse (mean square) than the one without the "
                        "start-ups" + (", which names other effects, no more of them"
                                       if second.get("other_effects") else ""))
            else:
                than = "no better than the one without the start-ups, which names fewer effects"
            why = [f"the diagnosis from rest ({rest}) predicts validate after its start-up "
                   + than]
        out.append("the records do not all start at rest: "
                   f"{'fitted from rest, the nominal left ' if second is None else ''}"
                   f"{' and '.join(why)}, so "
                   "each record's start-up region was left out (initial_state 'auto' chose "
                   "'unknown'); to model the start too, record from a known rest (a hold, then "
                   "a ramp from it)")
    if start and rep.nominal.get("initial_state", "rest") == "rest":
        r = start[0]
        out.append(f"the start-up region dominates ({100 * r['energy_share']:.0f} % of the "
                   f"nominal residual in {100 * r['sample_share']:.0f} % of the samples); the "
                   "record may start mid-motion: try --initial-state unknown")
    swaps = v.get("interchangeable") or []
    # an alternative that stands in for the first named effect: said once, by its stand-in hint
    alts = [a for a in v.get("alternatives") or []
            if not any(w["effect"] == v["effects"][0] and w["instead"] == a for w in swaps)]
    if alts and v["effects"] != ["none"]:
        out.append(f"{v['effects'][0]} and {' and '.join(alts)} explain the gap about as well: "
                   "add a record at other input frequencies or with holds after steps to "
                   "tell them apart")
    for sw in swaps:
        pair = {sw["effect"], sw["instead"]}
        how = ("a delay and a mode or pole above the input's band act alike on it: add a "
               "record with faster input (a chirp or steps up to the band you control) "
               if pair == {"delay", "dynamics"} else
               "creep follows the input history, a drift the clock: add a record with holds "
               "at other levels after steps both ways, or repeat a record later, ")
        out.append(f"{sw['instead']} in place of {sw['effect']} fits validate within "
                   f"{abs(100 * (sw['ratio'] - 1)):.0f} % (RMS): {how}to tell them apart")
    closed = v.get("closed_loop_records") or []
    if closed:  # the noise floor's check (noise.py): the input follows the measured noise
        out.append(f"{', '.join(closed[:3])}{' ...' if len(closed) > 3 else ''} look taken in "
                   "closed loop (the input follows the measured noise one sample later): a "
                   "loop keeps the input slow, so an effect faster than it (a mode, a delay, a "
                   "rate dependence) is barely excited and may go unnamed; a record in open "
                   "loop, or with a faster reference, shows such effects")
    un = v.get("unexplained") or {}
    if "unexplained" in v["effects"]:
        where = "; ".join(un.get("where", [])[:2]) or "no one region"
        out.append(f"the unexplained residual sits at {where} (strongest band "
                   f"{un.get('band', '?')}); effects outside the candidates look like this: "
                   "output clipping or a sensor range, an input the records do not hold, a "
                   "sensor gain that changes between records; check the setup there")
    if un.get("note"):  # a gain per validate record explains the gap (diagnosis.gain)
        out.append(un["note"])
    model = v.get("model") or {}
    if "drift" in v["effects"] and model.get("drift_variant") == "levels":
        out.append("each validate record sits at a level of its own: was the sensor zeroed "
                   "anew between records?")
    if "repeated" not in str(v.get("noise_floor_method", "")):
        out.append("the noise floor is estimated from a local model, not measured: repeat one "
                   "input period a few times in a record to measure it")
    return out


def next_step(rep) -> str:
    """The one next thing to try, as a sentence.

    Parameters
    ----------
    rep : DiagnosisReport
        Uses ``verdict``, ``where`` and ``nominal``.

    Returns
    -------
    str
        The first hint that asks for another setting or record when there is one, else what to
        do with the verdict.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> v = dict(effects=["none"], gap_after=0.01, noise_floor=0.01, alternatives=[],
    ...          unexplained={"share": 0.0}, noise_floor_method="repeated periods")
    >>> rep = SimpleNamespace(verdict=v, where={}, nominal={})
    >>> next_step(rep)[:26]
    'use the nominal PI model: '
    """
    h = [x for x in hints(rep) if not x.startswith(NOTES)]
    if h:
        return h[0]
    if rep.verdict["effects"] == ["none"]:
        return "use the nominal PI model: pimodel diagnose ... --export DIR writes it"
    return ("use the augmented model: pimodel diagnose ... --export DIR writes it and its "
            "feedforward as JSON and FMUs")


def summarize(rep) -> str:
    """A short summary in words: verdict, how sure, where the gap sits, next step.

    Parameters
    ----------
    rep : DiagnosisReport
        Result of :func:`pimodel.diagnosis.diagnose` (or rebuilt from its JSON).

    Returns
    -------
    str
        Four lines (five with a drift: :func:`drift_words`), output units as in the records
        (um for pimodel's stages). With
        ``initial_state="unknown"`` the start-up region (left out of fitting and scoring) is
        not named among the regions.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> rep = SimpleNamespace(verdict={"effects": ["creep"], "gap_before": 0.05,
    ...     "gap_after": 0.011, "shrink": 0.78, "noise_floor": 0.01, "alternatives": [],
    ...     "unexplained": {"share": 0.0}, "noise_floor_method": "repeated periods",
    ...     "model": {}}, where={"regions": [{"region": "hold after a step (after 50 ms)",
    ...     "concentration": 3.0, "energy_share": 0.6, "sample_share": 0.2}],
    ...     "spectrum": [{"band": "< 1 Hz", "energy_share": 0.7}]},
    ...     nominal={"initial_state": "rest"})
    >>> print(summarize(rep).splitlines()[0])
    Verdict: creep - slow creep after moves (a memory of the input history over seconds).
    """
    v = rep.verdict
    effects = v["effects"]
    named = ", ".join(effects)
    what = "; ".join(MEANING.get(e, e) for e in effects)
    level, why = confidence(rep)
    lines = [f"Verdict: {named} - {what}."]
    if "drift" in effects and drift_words(v.get("model") or {}):
        lines.append(f"Drift: {drift_words(v['model'])}.")
    lines.append(f"How sure: {level}: validate gap {v['gap_before']:.3g} -> "
                 f"{v['gap_after']:.3g} (shrink {100 * v['shrink']:.0f} %), noise floor "
                 f"{v['noise_floor']:.3g} ({v.get('noise_floor_method', '?')}); {why}.")
    regs = _regions(rep.where, 4)
    if rep.nominal.get("initial_state", "rest") == "unknown":  # left out of fit and score
        regs = [r for r in regs if not r["region"].startswith(STARTUP)]
    regs = regs[:3]
    spectrum = rep.where.get("spectrum") or []
    band = max(spectrum, key=lambda b: b["energy_share"]) if spectrum else None
    where = "; ".join(f"{r['region']}: {100 * r['energy_share']:.0f} % of the residual in "
                      f"{100 * r['sample_share']:.0f} % of the samples" for r in regs) \
        or "spread evenly over the records"
    if band is not None:
        where += f"; {100 * band['energy_share']:.0f} % of it at {band['band']}"
    lines.append(f"Where the gap sits (nominal model): {where}.")
    lines.append(f"Next: {next_step(rep)}.")
    return "\n".join(lines)


def drift_words(model: dict) -> str:
    """The fitted drift in words, or ``""`` when ``model`` holds none.

    Parameters
    ----------
    model : dict
        ``verdict["model"]`` (``drift_variant``, ``drift_per_s``, ``drift_clock`` and, for a
        settling, ``drift_settling``, ``drift_settling_time_s``, ``drift_settling_start_s``).

    Returns
    -------
    str
        One sentence, output units as in the records (um for pimodel's stages).

    Examples
    --------
    >>> drift_words({"drift_variant": "settle", "drift_settling": -0.42,
    ...              "drift_settling_time_s": 4.4, "drift_settling_start_s": 1.5})
    'settles by -0.42 um with time constant 4.4 s (from t = 1.5 s on the clock the records share)'
    >>> drift_words({"drift_variant": "trend", "drift_per_s": 0.05, "drift_clock": "record"})
    "moves 0.05 um/s on each record's own clock"
    """
    variant = model.get("drift_variant")
    if variant is None:
        return ""
    levels = ", with a level of each record's own" if "levels" in variant else ""
    if variant.startswith("settle"):
        return (f"settles by {model['drift_settling']:.3g} um with time constant "
                f"{model['drift_settling_time_s']:.3g} s (from t = "
                f"{model['drift_settling_start_s']:.3g} s on the clock the records share)"
                f"{levels}")
    clock = ("each record's own clock" if model["drift_clock"] == "record" else
             "the clock the records share")
    return f"moves {model['drift_per_s']:.3g} um/s on {clock}{levels}"


def markdown_table(header: list[str], rows: list[list]) -> str:
    """A Markdown table (the reports' and the demo's): one row per list, floats to 4
    significant digits, other cells as ``str``, a ``|`` inside a cell escaped.

    Examples
    --------
    >>> print(markdown_table(["a", "b"], [[0.123456, "x|y"]]), end="")
    | a | b |
    |---|---|
    | 0.1235 | x\\|y |
    """
    def cell(x) -> str:
        return (f"{x:.4g}" if isinstance(x, float) else str(x)).replace("|", "\\|")

    out = ["| " + " | ".join(cell(c) for c in header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(cell(x) for x in r) + " |" for r in rows]
    return "\n".join(out) + "\n"


def write_report(rep, out_dir, *, title: str = "Diagnosis", units=("V", "um")) -> Path:
    """Write ``report.md`` (the summary, the figures, the numbers, the effects tried, where the
    gap sits, the hints) and its figures into ``out_dir``.

    Parameters
    ----------
    rep : DiagnosisReport
        Result of :func:`pimodel.diagnosis.diagnose`. A report without validate records
        (rebuilt from JSON) gets no figures.
    out_dir : str or pathlib.Path
        Directory (created if missing).
    title : str
        The report's heading.
    units : tuple of str
        Input and output units.

    Returns
    -------
    pathlib.Path
        ``out_dir / "report.md"``.

    Examples
    --------
    >>> import tempfile
    >>> from types import SimpleNamespace
    >>> rep = SimpleNamespace(verdict={"effects": ["none"], "gap_before": 0.01,
    ...     "gap_after": 0.01, "shrink": 0.0, "noise_floor": 0.01, "alternatives": [],
    ...     "unexplained": {"share": 0.0}, "noise_floor_method": "repeated periods",
    ...     "model": {}}, where={"regions": [], "spectrum": []},
    ...     nominal={"initial_state": "rest"}, candidates=[], validate=[])
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     write_report(rep, tmp).name
    'report.md'
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    v, uy = rep.verdict, units[1]
    figs = []
    if getattr(rep, "validate", None):
        from .plots import plot_diagnosis

        figs = plot_diagnosis(rep, out, units=units)
    parts = [f"# {title}\n", "## Summary\n", "\n\n".join(summarize(rep).splitlines()) + "\n"]
    if figs:
        parts += ["## Figures\n", "\n\n".join(f"![{p.stem}]({p.name})" for p in figs) + "\n",
                  "Left above: the validate residual of the nominal PI model and of the model "
                  "with the named effects over time; right: against the input. Below: the "
                  "loops of the first validate record, and where the nominal residual "
                  "concentrates (1 is uniform).\n"]
    parts += ["## Numbers\n", markdown_table(
        ["", "value"],
        [["verdict", ", ".join(v["effects"])],
         [f"validate gap before (RMS) [{uy}]", f"{v['gap_before']:.4g}"],
         [f"validate gap after (RMS) [{uy}]", f"{v['gap_after']:.4g}"],
         ["shrink", f"{100 * v['shrink']:.0f} %"],
         [f"noise floor [{uy}]", f"{v['noise_floor']:.4g} ({v.get('noise_floor_method')})"],
         ["gap after / noise floor", f"{_ratio(v):.2f}"],
         ["unexplained share of the gap energy", f"{100 * v['unexplained']['share']:.0f} %"],
         ["alternatives", ", ".join(v.get("alternatives") or []) or "-"],
         ["stand-ins fitting as well", ", ".join(
             f"{w['instead']} for {w['effect']} ({w['ratio']:.2f}x RMS)"
             for w in v.get("interchangeable") or []) or "-"],
         ["initial state", rep.nominal.get("initial_state", "rest")]])]
    cands = getattr(rep, "candidates", None) or []
    if cands:
        parts += ["## Each effect alone\n",
                  "Each candidate fitted alone on the train records, scored on validate "
                  "(negative delta BIC: better than the nominal).\n",
                  markdown_table(["effect", f"validate RMS [{uy}]", "delta BIC"],
                                 [[c["effect"], f"{c['validate']['rms']:.4g}",
                                   f"{c['delta_bic']:.0f}"] for c in cands])]
    regs = rep.where.get("regions") or []
    if regs:
        parts += ["## Where the nominal residual lies\n", markdown_table(
            ["region", "energy share", "sample share", "concentration"],
            [[r["region"], f"{100 * r['energy_share']:.0f} %",
              f"{100 * r['sample_share']:.0f} %", f"{r['concentration']:.2f}"]
             for r in regs])]
    h = hints(rep)
    parts += ["## Hints\n", "\n".join(f"- {x}" for x in h) + "\n" if h else
              "None: nothing in the data points to another setting.\n"]
    path = out / "report.md"
    path.write_text("\n".join(parts))
    return path
