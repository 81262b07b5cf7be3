"""The model descriptions of the FMU units, one writer for FMI 2.0 and FMI 3.0.

Both versions come from the same spec (:mod:`pimodel.fmu.spec`), as FMPy reads both with one
``ModelDescription``: FMI 2.0 lists every array element as a scalar (``p[1]..p[64]``, element
``p[i]`` at reference ``vr(p) + i - 1``); FMI 3.0 turns them into arrays and adds the
independent variable ``time`` and the structural parameter ``n_plays``, which sizes the
per-play arrays ``p``, ``r``, ``r_hat``, ... (``PER_PLAY``: ``<Dimension valueReference>``, the
first ``n`` used); the other arrays have ``NMAX`` elements.
"""

from __future__ import annotations

from xml.sax.saxutils import escape

from .sources import CORE_SOURCES
from .spec import N_PLAYS, NMAX, PER_PLAY, TIME, check_fmi_version, guid, spec_of, token, unit_of
from .units import unit_definitions, variable_unit

__all__ = ["LOG_CATEGORIES", "PLATFORM", "TYPES", "default_experiment", "model_description",
           "model_description3"]

TYPES = {"Real": "Float64", "Integer": "Int32", "Boolean": "Boolean",
         "UInt64": "UInt64"}  # FMI 2 -> FMI 3 type
PLATFORM = {"2.0": "linux64", "3.0": "x86_64-linux"}  # binaries/<platform>/ per FMI version
LOG_CATEGORIES = ('  <LogCategories><Category name="logStatusWarning" description="warnings (the '
                  'radius estimate\'s health)"/><Category name="logStatusError" '
                  'description="errors"/></LogCategories>')


def _variables3(name: str) -> list[tuple[str, int, str, str, str, str, bool]]:
    """(name, vr, type, causality, start, description, is_array), arrays merged (FMI 3)."""
    out, seen = [], set()
    variables = spec_of(name)["vars"]
    for v in variables:
        if "[" in v.name:
            if v.base in seen:
                continue
            seen.add(v.base)
            what = v.description.rsplit(",", 1)[0]
            starts = [w.start for w in variables if w.base == v.base]
            per = ("per play (first n of n_plays used)" if v.base in PER_PLAY
                   else f"{NMAX} elements")
            out.append((v.base, v.vr, TYPES[v.kind], v.causality, " ".join(starts),
                        f"{what}, {per}", True))
        else:
            out.append((v.name, v.vr, TYPES[v.kind], v.causality, v.start, v.description,
                        False))
    return out


def _header(name: str, fmi_version: str) -> list[str]:
    spec = spec_of(name)
    description = escape(spec["description"])
    if fmi_version == "3.0":
        return [
            f'<fmiModelDescription fmiVersion="3.0" modelName="{name}" '
            f'instantiationToken="{token(name)}" description="{description}" '
            'generationTool="pimodel" variableNamingConvention="structured">',
            f'  <CoSimulation modelIdentifier="{name}" '
            'canHandleVariableCommunicationStepSize="true" canGetAndSetFMUState="true" '
            'canSerializeFMUState="true" hasEventMode="false" providesIntermediateUpdate="false" '
            'canReturnEarlyAfterIntermediateUpdate="false"/>',
        ]
    return [
        f'<fmiModelDescription fmiVersion="2.0" modelName="{name}" guid="{guid(name)}" '
        f'description="{description}" generationTool="pimodel" '
        'variableNamingConvention="structured" numberOfEventIndicators="0">',
        f'  <CoSimulation modelIdentifier="{name}" canHandleVariableCommunicationStepSize="true"'
        ' canGetAndSetFMUstate="true" canSerializeFMUstate="true"'
        ' canNotUseMemoryManagementFunctions="true" canInterpolateInputs="false">',
        "    <SourceFiles>",
        '      <File name="model.c"/>',
        *[f'      <File name="{s}"/>' for s in CORE_SOURCES],
        "    </SourceFiles>",
        "  </CoSimulation>",
    ]


def _attributes(causality: str, fmi_version: str) -> str:
    if causality == "parameter":
        initial = ' initial="exact"' if fmi_version == "2.0" else ""
        return f'causality="parameter" variability="fixed"{initial}'
    if causality == "input":
        return 'causality="input" variability="discrete"'
    return 'causality="output" variability="discrete" initial="exact"'


def _unit_attr(unit: str, name: str) -> str:
    u = variable_unit(unit, name)
    return f' unit="{u}"' if u else ""


def default_experiment(name: str) -> tuple[float, float]:
    """``(stopTime, stepSize)`` of a unit's ``DefaultExperiment``: one sample time ``Ts`` per
    step (the start value of ``Ts``) until the spec's ``stop_time`` (a model's FMU: the length
    of the record it was made from), else 1000 samples.

    Parameters
    ----------
    name : str
        The unit's model identifier.

    Returns
    -------
    tuple of float
        Stop time [s] and step size [s].

    Examples
    --------
    >>> default_experiment("PIHysteresis")
    (1.0, 0.001)
    """
    spec = spec_of(name)
    ts = float(next(v.start for v in spec["vars"] if v.name == "Ts"))
    stop = spec.get("stop_time")
    return (float(stop) if stop else 1000 * ts), ts


def _variables_xml(name: str, fmi_version: str) -> tuple[list[str], list[int]]:
    """The ModelVariables lines and the outputs (FMI 2: 1-based indices; FMI 3: references)."""
    lines, outputs = [], []
    unit = unit_of(name)
    if fmi_version == "3.0":
        lines.append(f'    <Float64 name="{TIME.name}" valueReference="{TIME.vr}" '
                     f'causality="{TIME.causality}" variability="continuous" '
                     f'description="{TIME.description}" unit="s"/>')
        lines.append(f'    <{N_PLAYS.kind} name="{N_PLAYS.name}" valueReference="{N_PLAYS.vr}" '
                     f'causality="{N_PLAYS.causality}" variability="fixed" '
                     f'description="{escape(N_PLAYS.description)}" start="{N_PLAYS.start}" '
                     f'min="1" max="{NMAX}"/>')
        for vname, vr, kind, causality, start, desc, is_array in _variables3(name):
            if causality == "output":
                outputs.append(vr)
            head = (f'    <{kind} name="{vname}" valueReference="{vr}" '
                    f'{_attributes(causality, fmi_version)} description="{escape(desc)}"'
                    f'{_unit_attr(unit, vname)} start="{start}"')
            dim = (f'valueReference="{N_PLAYS.vr}"' if vname in PER_PLAY
                   else f'start="{NMAX}"')
            lines.append(f'{head}><Dimension {dim}/></{kind}>' if is_array else f"{head}/>")
        return lines, outputs
    for idx, v in enumerate(spec_of(name)["vars"], start=1):
        if v.causality == "output":
            outputs.append(idx)
        lines.append(f'    <ScalarVariable name="{v.name}" valueReference="{v.vr}" '
                     f'{_attributes(v.causality, fmi_version)} '
                     f'description="{escape(v.description)}"><{v.kind}'
                     f'{_unit_attr(unit, v.name)} start="{v.start}"/></ScalarVariable>')
    return lines, outputs


def model_description(name: str, fmi_version: str = "2.0") -> str:
    """The ``modelDescription.xml`` of a unit (Co-Simulation) for FMI 2.0 or FMI 3.0.

    Parameters
    ----------
    name : str
        The unit's model identifier.
    fmi_version : {"2.0", "3.0"}, optional
        ``"2.0"`` (scalar variables, ``p[1]..p[64]``) or ``"3.0"`` (arrays ``p``, the
        independent variable ``time``). Default ``"2.0"``.

    Returns
    -------
    str
        The XML text.

    Raises
    ------
    KeyError
        An unknown unit.
    ValueError
        An unsupported ``fmi_version``.

    Examples
    --------
    >>> xml = model_description("PIHysteresis")
    >>> 'fmiVersion="2.0" modelName="PIHysteresis"' in xml, 'name="r[64]"' in xml
    (True, True)
    >>> '<Float64 name="p"' in model_description("PIHysteresis", "3.0")
    True
    """
    check_fmi_version(fmi_version)
    variables, outputs = _variables_xml(name, fmi_version)
    unit = unit_of(name)
    units = unit_definitions({variable_unit(unit, v.name) for v in spec_of(name)["vars"]}
                             | ({"s"} if fmi_version == "3.0" else set()))
    stop, step = default_experiment(name)
    lines = ['<?xml version="1.0" encoding="UTF-8"?>', *_header(name, fmi_version),
             *([units] if units else []), LOG_CATEGORIES,
             f'  <DefaultExperiment startTime="0" stopTime="{stop!r}" stepSize="{step!r}"/>',
             "  <ModelVariables>", *variables, "  </ModelVariables>", "  <ModelStructure>"]
    if fmi_version == "3.0":
        lines += [f'    <Output valueReference="{vr}"/>' for vr in outputs]
    else:
        lines += ["    <Outputs>", *[f'      <Unknown index="{i}"/>' for i in outputs],
                  "    </Outputs>"]
    lines += ["  </ModelStructure>", "</fmiModelDescription>", ""]
    return "\n".join(lines)


def model_description3(name: str) -> str:
    """The FMI 3.0 ``modelDescription.xml`` of a unit: ``model_description(name, "3.0")``.

    Parameters
    ----------
    name : str
        The unit's model identifier.

    Returns
    -------
    str
        The XML text.

    Examples
    --------
    >>> model_description3("PIHysteresis") == model_description("PIHysteresis", "3.0")
    True
    """
    return model_description(name, "3.0")
