"""The one schema of every model file: :func:`check_model_dict`.

Each type's keys with their kind (number, list of numbers, bool, envelope, nested model, ...),
whether they are required, and their ranges; the keys every file may carry at its top level
(``offset``, ``dt``, ``units``, ``provenance``, ``report``, ``format_version``). The check refuses,
naming the key and what was expected: a wrong JSON type (``"false"`` for a bool), a number that is
NaN, infinite or beyond float64 (``10**400``), a value out of range (a negative time constant,
``dt = inf``), a missing or unknown key (with a "did you mean" for a near miss), and lists whose
lengths do not match (creep gains and time constants). ``load_model`` and
``pimodel fmu build --model`` run it before any operator is built.
"""

from __future__ import annotations

import difflib
import math

__all__ = ["FORMAT_VERSION", "META_KEYS", "check_model_dict"]

FORMAT_VERSION = 2
"""The model file format written by :func:`pimodel.model_files.save_model` (1: no metadata)."""

META_KEYS = ("offset", "dt", "units", "provenance", "report", "format_version")
"""Keys every model file may carry at its top level, besides its type's own."""

UNIT_KEYS = ("time", "input", "output")
PROVENANCE_KEYS = ("record", "columns", "method", "date", "pimodel_version", "source")

# kind, required; kinds: num (finite float), num+ (> 0), num0 (>= 0), nums (non-empty list of
# finite floats), nums0 (... >= 0), nums+ (... > 0), state (number or list), bool, env, pair,
# model, models, str, strs, obj
_STATE = ("state", False)
SPECS: dict[str, dict[str, tuple[str, bool]]] = {
    "PIOperator": {"weights": ("nums", True), "radii": ("nums0", True), "initial_state": _STATE},
    "GeneralizedPI": {"weights": ("nums", True), "radii": ("nums0", True),
                      "input_envelope": ("env", True), "output_envelope": ("env", True),
                      "initial_state": _STATE, "signed_weights": ("bool", False)},
    "AsymmetricPI": {"direct_weight": ("num", True), "weights": ("nums", True),
                     "radii": ("nums0", True), "ascending": ("pair", False),
                     "descending": ("pair", False), "shape": ("env", False),
                     "initial_state": _STATE},
    "RateDependentPI": {"weights": ("nums", True), "base_radii": ("nums0", True),
                        "rate_gain": ("num", True), "dt": ("num+", True),
                        "rate_time_constant": ("num0", False), "initial_state": _STATE,
                        "initial_input": ("num", False)},
    "CreepOperator": {"gains": ("nums", True), "time_constants": ("nums+", True),
                      "dt": ("num+", True), "initial_state": _STATE, "inverted": ("bool", False)},
    "Inverse": {"operator": ("model", True)},
    "Cascade": {"stages": ("models", True)},
    "DiagnosedModel": {"radii": ("nums0", True), "weights": ("nums", True),
                       "offset": ("num", True), "dt": ("num+", True), "effects": ("strs", True),
                       "reference_weights": ("nums", True), "reference_offset": ("num", True),
                       "params": ("obj", True), "initial_state": ("str", False),
                       "plays_start": ("str", False)},
}
TYPES = tuple(SPECS)
# lists that must have equal lengths, per type
SAME_LENGTH = {"PIOperator": ("weights", "radii"), "GeneralizedPI": ("weights", "radii"),
               "AsymmetricPI": ("weights", "radii"), "RateDependentPI": ("weights", "base_radii"),
               "CreepOperator": ("gains", "time_constants"),
               "DiagnosedModel": ("weights", "radii", "reference_weights")}
# the parameters each effect of a DiagnosedModel needs (kind as above)
EFFECT_PARAMS = {"creep": {"creep_lag_gains": "nums", "creep_time_constants_s": "nums+"},
                 "asymmetry": {"asymmetry_quadratic": "num", "asymmetry_cubic": "num",
                               "center": "num", "half_range": "num+"},
                 "delay": {"delay_samples": "num0"},
                 "drift": {"drift_clock": "str", "drift_per_s": "num"}}
# and those a settling drift (params["drift_variant"] "settle" or "settle_levels") needs
SETTLE_PARAMS = {"drift_settling": "num", "drift_settling_time_s": "num+",
                 "drift_settling_start_s": "num"}
# a DiagnosedModel's params that record what the diagnosis tried (not used to simulate): not
# held to the finiteness check
TRACE_PARAMS = ("dynamics_structures_tried", "dynamics_positions_tried")
_EXPECT = {"num": "a finite number", "num+": "a finite number > 0", "num0": "a finite number >= 0",
           "nums": "a non-empty list of finite numbers",
           "nums0": "a non-empty list of finite numbers >= 0",
           "nums+": "a non-empty list of finite numbers > 0",
           "state": "a finite number or a list of finite numbers", "bool": "true or false",
           "env": "{'kind': ..., 'coefficients': [...]}", "pair": "a list of two finite numbers",
           "model": "a model object with a 'type'", "models": "a non-empty list of model objects",
           "str": "a string", "strs": "a list of strings", "obj": "a JSON object"}


def _fail(where: str, kind: str, value) -> ValueError:
    return ValueError(f"{where}: expected {_EXPECT.get(kind, kind)}, got {_show(value)}")


def _show(value) -> str:
    text = repr(value)
    return text if len(text) <= 60 else f"{text[:40]}... ({len(text)} characters)"


def _number(value, where: str, kind: str = "num") -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise _fail(where, kind, value)
    try:
        x = float(value)
    except OverflowError:
        raise ValueError(f"{where}: expected {_EXPECT[kind]}, got an integer of "
                         f"{len(str(abs(value)))} digits, beyond the float64 range") from None
    if not math.isfinite(x):
        raise _fail(where, kind, value)
    if (kind.endswith("+") and x <= 0) or (kind.endswith("0") and x < 0):
        raise _fail(where, kind, value)
    return x


def _numbers(value, where: str, kind: str) -> list:
    if not isinstance(value, list) or not value:
        raise _fail(where, kind, value)
    return [_number(x, f"{where}[{i}]", "num" + kind[4:]) for i, x in enumerate(value)]


def _unknown(keys, allowed, where: str) -> None:
    for key in keys:
        if key not in allowed:
            near = difflib.get_close_matches(str(key), list(allowed), n=1, cutoff=0.6)
            hint = f"; did you mean {near[0]!r}?" if near else \
                f"; expected one of {sorted(allowed)}"
            raise ValueError(f"{where}.{key}: unknown key{hint}")


def _value(value, where: str, kind: str):
    if kind.startswith("num") and kind[3:] in ("", "+", "0"):
        _number(value, where, kind)
    elif kind.startswith("nums"):
        _numbers(value, where, kind)
    elif kind == "state":
        if isinstance(value, list):
            _numbers(value, where, "nums")
        else:
            _number(value, where, "state")
    elif kind == "bool":
        if not isinstance(value, bool):
            raise _fail(where, kind, value)
    elif kind == "pair":
        if not isinstance(value, list) or len(value) != 2:
            raise _fail(where, kind, value)
        _numbers(value, where, "nums")
    elif kind == "env":
        if not isinstance(value, dict):
            raise _fail(where, kind, value)
        _unknown(value, ("kind", "coefficients"), where)
        for key in ("kind", "coefficients"):
            if key not in value:
                raise ValueError(f"{where}.{key}: missing key; expected {_EXPECT['env']}")
        if not isinstance(value["kind"], str):
            raise _fail(f"{where}.kind", "str", value["kind"])
        _numbers(value["coefficients"], f"{where}.coefficients", "nums")
    elif kind == "model":
        _check(value, where, top=False)
    elif kind == "models":
        if not isinstance(value, list) or not value:
            raise _fail(where, kind, value)
        for i, stage in enumerate(value):
            _check(stage, f"{where}[{i}]", top=False)
    elif kind == "str":
        if not isinstance(value, str):
            raise _fail(where, kind, value)
    elif kind == "strs":
        if not isinstance(value, list) or not all(isinstance(s, str) for s in value):
            raise _fail(where, kind, value)
    elif kind == "obj" and not isinstance(value, dict):
        raise _fail(where, kind, value)


def _finite_leaves(value, where: str) -> None:
    """Every number inside ``value`` (lists and objects, any depth) is a finite float64."""
    if isinstance(value, dict):
        for key, item in value.items():
            _finite_leaves(item, f"{where}.{key}")
    elif isinstance(value, list):
        for i, item in enumerate(value):
            _finite_leaves(item, f"{where}[{i}]")
    elif isinstance(value, (int, float)) and not isinstance(value, bool):
        _number(value, where)


def _diagnosed_params(d: dict, where: str) -> None:
    params = d["params"]
    _finite_leaves({k: v for k, v in params.items() if k not in TRACE_PARAMS}, f"{where}.params")
    needs = [(effect, EFFECT_PARAMS.get(effect, {})) for effect in d["effects"]]
    if "drift" in d["effects"] and params.get("drift_variant") in ("settle", "settle_levels"):
        needs.append(("drift", SETTLE_PARAMS))
    for effect, keys in needs:
        for key, kind in keys.items():
            if key not in params:
                raise ValueError(f"{where}.params.{key}: missing key; the effect {effect!r} "
                                 f"needs it ({_EXPECT[kind]})")
            _value(params[key], f"{where}.params.{key}", kind)
    if "creep" in d["effects"]:
        _same_length(params, ("creep_lag_gains", "creep_time_constants_s"), f"{where}.params")


def _same_length(d: dict, keys, where: str) -> None:
    present = [k for k in keys if isinstance(d.get(k), list)]
    sizes = {k: len(d[k]) for k in present}
    if len(set(sizes.values())) > 1:
        first = present[0]
        for key in present[1:]:
            if sizes[key] != sizes[first]:
                raise ValueError(f"{where}.{key}: expected {sizes[first]} values, one per entry "
                                 f"of {first}, got {sizes[key]}")


def _check(d, where: str, *, top: bool) -> None:
    if not isinstance(d, dict):
        raise ValueError(f"{where}: expected a JSON object with a 'type', got {_show(d)}")
    kind = d.get("type")
    if kind is None:
        raise ValueError(f"{where}.type: missing key; expected one of {list(TYPES)}")
    if not isinstance(kind, str) or kind not in SPECS:
        near = difflib.get_close_matches(str(kind), TYPES, n=1, cutoff=0.6)
        hint = f" (did you mean {near[0]!r}?)" if near else ""
        raise ValueError(f"{where}.type: unknown model type {kind!r}{hint}; expected one of "
                         f"{list(TYPES)}")
    spec = SPECS[kind]
    allowed = {"type", *spec, *(META_KEYS if top else ())}
    _unknown(d, allowed, where)
    for key, (k, required) in spec.items():
        if key not in d:
            if required:
                raise ValueError(f"{where}.{key}: missing key for type {kind!r}; expected "
                                 f"{_EXPECT[k]}")
            continue
        _value(d[key], f"{where}.{key}", k)
    _same_length(d, SAME_LENGTH.get(kind, ()), where)
    for key in ("weights", "radii", "base_radii", "gains"):
        state = d.get("initial_state")
        if key in spec and isinstance(state, list) and isinstance(d.get(key), list) \
                and len(state) not in (1, len(d[key])):
            raise ValueError(f"{where}.initial_state: expected one value or {len(d[key])} (one "
                             f"per entry of {key}), got {len(state)}")
    if kind == "DiagnosedModel":
        _diagnosed_params(d, where)
    if top:
        _meta(d, where, own=spec)


def _meta(d: dict, where: str, own: dict) -> None:
    if "offset" in d and "offset" not in own:
        _number(d["offset"], f"{where}.offset")
    if "dt" in d and "dt" not in own:
        _number(d["dt"], f"{where}.dt", "num+")
    for key, names in (("units", UNIT_KEYS), ("provenance", PROVENANCE_KEYS)):
        if key in d:
            if not isinstance(d[key], dict):
                raise _fail(f"{where}.{key}", "obj", d[key])
            _unknown(d[key], names, f"{where}.{key}")
            for name, value in d[key].items():
                ok = isinstance(value, str) or (name == "columns" and isinstance(value, list)
                                                and all(isinstance(s, str) for s in value))
                if not ok:
                    raise _fail(f"{where}.{key}.{name}", "str", value)
    if "report" in d and not isinstance(d["report"], dict):
        raise _fail(f"{where}.report", "obj", d["report"])
    if "format_version" in d and d["format_version"] not in (1, FORMAT_VERSION):
        raise ValueError(f"{where}.format_version: expected 1 or {FORMAT_VERSION}, got "
                         f"{_show(d['format_version'])} (a newer pimodel wrote it?)")


def check_model_dict(d, *, where: str = "model") -> None:
    """Check a model file's JSON object against the schema (module docstring).

    Parameters
    ----------
    d : object
        The parsed JSON.
    where : str
        Name of ``d`` in error messages (``load_model`` passes ``"model"`` and prefixes the
        file).

    Raises
    ------
    ValueError
        The first problem, naming the key (``model.stages[1].gains[0]``) and what was expected.

    Examples
    --------
    >>> check_model_dict({"type": "CreepOperator", "gains": [0.05], "time_constants": [0.1],
    ...                   "dt": 1e-3, "inverted": "false"})
    Traceback (most recent call last):
    ...
    ValueError: model.inverted: expected true or false, got 'false'
    """
    _check(d, where, top=True)
