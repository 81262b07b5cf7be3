"""The blind generator's creep-bearing cases (drift50; docs/notes/drift50.md): one JSON line per
case and variant appended to ``OUT``.

Generator variants (how ``stage48``'s creep starts; ``h[k]`` the plays' output before the
sensor gain, ``L_i`` the lag of time constant ``tau_i`` driven by ``h``, ``gamma`` each lag's
gain, 9 lags):

``asis``
    As coded: ``h + gamma sum_i lag_i(h - h[0])`` from 0, i.e. every ``L_i`` at rest at
    ``h[0]`` and a level ``-9 gamma h[0]`` that differs from record to record.
``settled``
    ``h + gamma sum_i L_i``, every ``L_i`` at rest at ``h[0]`` (the stage sat at ``v[0]``).
``park``
    ``h + gamma sum_i (L_i - h_b)``, every ``L_i`` at rest at ``h_b``, the output at rest at
    the park level ``v_bias`` (what the generator's docstring says: the stage sat at
    ``v_bias`` and was stepped to ``v[0]``; the lags settle from that step through the record).

Diagnosis variant ``--common`` (an experiment, not in the package): the creep candidate's lags
at rest, before every record, at one level per lag common to all records (where the stage
rested between records) in place of each record's first model output: the columns
``lag_i(h0) - h0`` with the lags at rest at 0 and ``a_i^(k+1) = exp(-(k + 1) dt / tau_i)``
(restarting with each record, one coefficient shared by the records), ``2 n_lags`` parameters.

Diagnosis variant ``--variant`` (an experiment, not in the package): both starts, the lags at
rest at each record's first output (``main``) and at a common rest (``--common``), scored as
the creep's two variants on validate by BIC for every combination (as the drift's variants);
``creep_start`` ``"common"`` in the model's grid when chosen. Records of at most
``effects.SCREEN_SAMPLES`` samples; the reported asymmetry and rate coefficients are read from
the wrong columns beside a common-rest creep (report only: the predictions are the fit's).

Usage: python tests/blind/drift50.py OUT VARIANT [--common | --variant] NAME SEED [NAME SEED ...]
"""

from __future__ import annotations

import inspect
import json
import os
import sys
import textwrap
import time

import numpy as np
from scipy import signal

sys.path.insert(0, os.path.dirname(__file__))

import run48 as R  # noqa: E402
import stage48 as S  # noqa: E402

import pimodel.diagnosis.effects as E  # noqa: E402
from pimodel import diagnose  # noqa: E402

_CLEAN = S.Stage.clean
VARIANTS = ("asis", "settled", "park")


def _clean(variant: str):
    """``Stage.clean`` with the creep started as ``variant`` (module docstring)."""

    def clean(self, t, v, t_clock0):
        if "creep" not in self.effects or variant == "asis":
            return _CLEAN(self, t, v, t_clock0)
        gamma, taus = self.effects["creep"]
        fs = 1.0 / (t[1] - t[0])
        h = self._plays(self._amplifier(v, fs), fs)
        h_b = float((self.weights.sum() + self.a0) * self.v_bias)  # at rest at v_bias
        start, ref = (h[0], 0.0) if variant == "settled" else (h_b, h_b)
        c = np.zeros_like(h)
        for tau in taus:
            a = np.exp(-1.0 / (tau * fs))
            c += signal.lfilter([1 - a], [1, -a], h, zi=[a * start])[0] - ref
        eff, plays = self.effects, self._plays
        self.effects = {k: x for k, x in eff.items() if k != "creep"}
        self._plays = lambda u, fs_: plays(u, fs_) + gamma * c  # creep before the rest
        try:
            return _CLEAN(self, t, v, t_clock0)
        finally:
            del self._plays
            self.effects = eff

    return clean


def common_rest() -> None:
    """Patch the creep candidate to the common-rest columns (module docstring). Records of at
    most ``effects.SCREEN_SAMPLES`` samples only (the streamed columns are not patched)."""
    src = textwrap.dedent(inspect.getsource(E._combo_features))
    old = 'out += [lag(h0, tau, s.dt, y0) - h0 for tau in nominal.params["creep_taus"]]'
    new = ('out += [lag(h0, tau, s.dt, 0.0 if y0 is None else y0) - h0\n'
           '                        for tau in nominal.params["creep_taus"]]\n'
           '                out += [np.exp(-(np.arange(h0.size) + 1) * s.dt / tau)\n'
           '                        for tau in nominal.params["creep_taus"]]')
    if old not in src:
        raise RuntimeError("effects._combo_features changed: the patch no longer applies")
    exec(compile(src.replace(old, new), E.__file__, "exec"), E.__dict__)  # noqa: S102
    k = E._combo_k
    E._combo_k = lambda effects, nominal: k(effects, nominal) + (
        len(nominal.params["creep_taus"]) if "creep" in effects else 0)


def common_variant() -> None:
    """Patch the creep candidate to two starts chosen on validate (module docstring)."""
    D = sys.modules["pimodel.diagnosis.diagnose"]  # the module (the package exports the function)

    src = textwrap.dedent(inspect.getsource(E._combo_features))
    old = "            if \"asymmetry\" in effects:\n                u = "
    new = ("            if \"creep\" in effects and p.get(\"creep_start\") == \"common\":\n"
           "                out[1:1 + len(nominal.params[\"creep_taus\"])] = [\n"
           "                    lag(h0, tau, s.dt, 0.0) - h0\n"
           "                    for tau in nominal.params[\"creep_taus\"]]\n"
           "                tail = [np.exp(-(np.arange(h0.size) + 1) * s.dt / tau)\n"
           "                        for tau in nominal.params[\"creep_taus\"]]\n"
           "            else:\n"
           "                tail = []\n" + old)
    if old not in src:
        raise RuntimeError("effects._combo_features changed: the patch no longer applies")
    src = src.replace(old, new)
    old2 = "            static[key] = (s, np.vstack(out))"
    if old2 not in src:
        raise RuntimeError("effects._combo_features changed: the patch no longer applies")
    src = src.replace(old2, "            static[key] = (s, np.vstack(out + tail))")
    exec(compile(src, E.__file__, "exec"), E.__dict__)  # noqa: S102
    src = textwrap.dedent(inspect.getsource(E._fit_combo))
    old3 = ("    k = _combo_k(effects, nominal) + "
            "(drift_k(fixed) - 1 if \"drift\" in effects else 0)\n")
    old4 = "        elif e == \"delay\":\n"
    if old3 not in src or old4 not in src:
        raise RuntimeError("effects._fit_combo changed: the patch no longer applies")
    src = src.replace(old3, old3 + (
        "    common = \"creep\" in effects and fixed.get(\"creep_start\") == \"common\"\n"
        "    k += len(nominal.params[\"creep_taus\"]) if common else 0\n"))
    src = src.replace(old4, "        elif e == \"creep\":\n"
                      "            grids.append([{\"creep_start\": \"common\"}]\n"
                      "                         if common else [{}])\n"
                      + old4)
    exec(compile(src, E.__file__, "exec"), E.__dict__)  # noqa: S102
    shapes = D.rate_shapes

    def rate_and_creep(effects, fixed):
        starts = [{"creep_start": "rest"}, {"creep_start": "common"}] if "creep" in effects \
            else [{}]
        return [{**r, **c} for r in shapes(effects, fixed) for c in starts]

    D.rate_shapes = rate_and_creep
    D.fit_effect = E.fit_effect


def run(out: str, variant: str, name: str, seed: int, common: str | bool) -> None:
    case = next(c for c in R.cases([seed]) if c.name == name)
    rt, rv, st, info = S.make_records(case)
    gamma, taus = st.effects.get("creep", (0.0, ()))
    h0 = [float(st._plays(st._amplifier(r.v[:3], case.fs), case.fs)[0]) for r in (rt, rv)]
    t0 = time.process_time()
    rep = diagnose([rt], [rv], workers=1)
    v = rep.verdict
    nf = v["noise_floor"]
    m = v.get("model", {})
    row = {"variant": variant, "common": common, "name": name, "seed": seed,
           "kind": case.kind, "fs": case.fs, "effects": v["effects"],
           "right": R.judge(case.effects, v["effects"]), "noise_floor": nf,
           "gap_before_nf": v["gap_before"] / nf, "gap_after_nf": v["gap_after"] / nf,
           "alone_nf": {c["effect"]: c["validate"]["rms"] / nf for c in rep.candidates},
           "creep_alone": next((c["params"] for c in rep.candidates
                                if c["effect"] == "creep"), None),
           # the start of each record's plays' output moved by the sensor gain [um], and the
           # level per validate record the generator as coded adds (-9 gamma dh0) [noise floors]
           "dh0_um": st.gain * (h0[1] - h0[0]),
           "coded_level_nf": -len(taus) * gamma * st.gain * (h0[1] - h0[0]) / nf,
           "drift": {k: x for k, x in m.items() if k.startswith("drift")}
           if "drift" in v["effects"] else None,
           "cpu": time.process_time() - t0, **info}
    if common == "variant":
        row["creep_start"] = rep.fitted["model"].grid.get("creep_start")
    with open(out, "a") as f:
        f.write(json.dumps(row, default=lambda o: o.tolist() if hasattr(o, "tolist")
                           else str(o)) + "\n")
    print(variant, common or "rest", name, seed, v["effects"], row.get("creep_start"),
          flush=True)


def main() -> None:
    out, variant, *rest = sys.argv[1:]
    if variant not in VARIANTS:
        raise SystemExit(f"variant: one of {VARIANTS}, got {variant!r}")
    mode = rest[0] if rest and rest[0] in ("--common", "--variant") else ""
    rest = rest[1:] if mode else rest
    S.Stage.clean = _clean(variant)
    if mode == "--common":
        common_rest()
    elif mode == "--variant":
        common_variant()
    common = mode[2:] or False
    for name, seed in zip(rest[::2], rest[1::2], strict=True):
        run(out, variant, name, int(seed), common)


if __name__ == "__main__":
    main()
