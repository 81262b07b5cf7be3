"""The physical units of the FMU variables: ``UnitDefinitions`` and each variable's ``unit``.

pimodel's convention (:mod:`pimodel.records`) is an input in volts and an output in
micrometres; times are in seconds. A variable has a unit when its meaning fixes one:
the input side (``v``, radii, ``z0``) in ``V``, the output side (``y``, offsets) in ``um``
(``m`` with factor 1e-6), times in ``s`` and rates in ``V/s`` or ``um/s``. Variables of the
units whose input and output swap with the ``inverse`` flag, envelope coefficients, weights
and counts have none.
"""

from __future__ import annotations

__all__ = ["UNITS", "unit_definitions", "variable_unit"]

# name -> (SI base exponents, factor) as in FMI's <BaseUnit>
UNITS: dict[str, tuple[dict[str, int], float]] = {
    "s": ({"s": 1}, 1.0),
    "V": ({"kg": 1, "m": 2, "s": -3, "A": -1}, 1.0),
    "um": ({"m": 1}, 1e-6),
    "V/s": ({"kg": 1, "m": 2, "s": -4, "A": -1}, 1.0),
    "um/s": ({"m": 1, "s": -1}, 1e-6),
    "s/V": ({"kg": -1, "m": -2, "s": 4, "A": 1}, 1.0),
}

_TIMES = ("Ts", "time", "tau", "creep_tau", "rate_tau", "rate_time_constant",
          "drift_settling_tau", "drift_settling_start")
_INPUT_SIDE = ("z0", "r", "r_hat", "guard", "v0", "input_range")
_OUTPUT_SIDE = ("y_hat", "e", "offset", "reference_offset", "center", "half_range",
                "reference_range", "drift_settling")
# the units whose input is v [V] and output y [um] (the others swap them with `inverse`)
_FIXED_IO = {"PIHysteresis": {"v": "V", "y": "um"},
             "RadiusEstimator": {"v": "V", "y": "um"},
             "InversePI": {"y_d": "um", "v": "V"},
             "DiagnosedModel": {"v": "V", "y": "um"},
             "DiagnosedInverse": {"y_d": "um", "v": "V"}}
_OTHER = {"rate_scale": "V/s", "drift_per_s": "um/s", "rate_gain": "s/V"}


def variable_unit(unit: str, name: str) -> str:
    """The unit of variable ``name`` (an array's base name) of FMU unit ``unit``, or ``""``.

    Parameters
    ----------
    unit : str
        The unit (a ``MODELS`` name).
    name : str
        The variable's name, ``p[3]`` or ``p``.

    Returns
    -------
    str
        A key of :data:`UNITS`, or ``""`` (no unit).

    Examples
    --------
    >>> variable_unit("PIHysteresis", "r[2]"), variable_unit("DiagnosedModel", "y")
    ('V', 'um')
    >>> variable_unit("GeneralizedPI", "u"), variable_unit("CreepOperator", "tau[1]")
    ('', 's')
    """
    base = name.split("[")[0]
    if base in _TIMES:
        return "s"
    io = _FIXED_IO.get(unit)
    if io is None:
        return "s/V" if base == "rate_gain" else ""
    if base in io:
        return io[base]
    if base in _INPUT_SIDE:
        return "V"
    if base in _OUTPUT_SIDE:
        return "um"
    return _OTHER.get(base, "")


def unit_definitions(used) -> str:
    """The ``<UnitDefinitions>`` element (FMI 2 and 3 alike) of the units in ``used``.

    Parameters
    ----------
    used : iterable of str
        Keys of :data:`UNITS` (``""`` ignored).

    Returns
    -------
    str
        The XML lines, or ``""`` when none is used.

    Examples
    --------
    >>> print(unit_definitions(["um"]))
      <UnitDefinitions>
        <Unit name="um"><BaseUnit m="1" factor="1e-06"/></Unit>
      </UnitDefinitions>
    """
    names = [u for u in UNITS if u in set(used)]
    if not names:
        return ""
    rows = []
    for name in names:
        exps, factor = UNITS[name]
        attrs = " ".join(f'{k}="{v}"' for k, v in exps.items())
        attrs += f' factor="{factor:g}"' if factor != 1.0 else ""
        rows.append(f'    <Unit name="{name}"><BaseUnit {attrs}/></Unit>')
    return "\n".join(["  <UnitDefinitions>", *rows, "  </UnitDefinitions>"])
