"""FMI 3.0 model descriptions of the pimodel units: the same variables as FMI 2.0, with the
``p[i]``, ``r[i]`` and ``r_hat[i]`` scalars turned into real arrays ``p``, ``r``, ``r_hat`` of
``NMAX`` elements (the first ``n`` used)."""

from __future__ import annotations

import uuid
from xml.sax.saxutils import escape

from .build import LOG_CATEGORIES, MODEL_UNITS, NMAX, spec_of

__all__ = [
    "model_description3",
    "token",
]

TYPES = {"Real": "Float64", "Integer": "Int32", "Boolean": "Boolean"}
PLATFORM = "x86_64-linux"


def token(name: str) -> str:
    """Fixed instantiation token of a unit (changes with the interface version).

    Parameters
    ----------
    name : str
        The unit's model identifier.

    Returns
    -------
    str
        A braced name-based UUID (uuid5), the same on every build, different from the FMI 2
        GUID.

    Examples
    --------
    >>> from pimodel.fmu.build import guid
    >>> t = token("PIHysteresis")
    >>> t == token("PIHysteresis"), t != guid("PIHysteresis"), len(t)
    (True, True, 38)
    """
    salt = MODEL_UNITS[name]["salt"] if name in MODEL_UNITS else ""
    return "{" + str(uuid.uuid5(uuid.NAMESPACE_URL, f"pimodel/fmi3/{name}/v2{salt}")) + "}"


def _variables(name: str) -> list[tuple[str, int, str, str, str, str, bool]]:
    """(name, vr, type, causality, start, description, is_array), arrays merged."""
    out, seen = [], set()
    variables = spec_of(name)["vars"]
    for v in variables:
        if "[" in v.name:
            base = v.name.split("[")[0]
            if base in seen:
                continue
            seen.add(base)
            what = v.description.rsplit(",", 1)[0]
            starts = [w.start for w in variables if w.name.split("[")[0] == base]
            out.append((base, v.vr, TYPES[v.kind], v.causality, " ".join(starts),
                        f"{what}, per play (first n of {NMAX} used)", True))
        else:
            out.append((v.name, v.vr, TYPES[v.kind], v.causality, v.start, v.description,
                        False))
    return out


def model_description3(name: str) -> str:
    """The FMI 3.0 ``modelDescription.xml`` of a unit (Co-Simulation, array variables).

    Parameters
    ----------
    name : str
        The unit's model identifier.

    Returns
    -------
    str
        The XML text.

    Raises
    ------
    KeyError
        An unknown unit.

    Examples
    --------
    >>> xml = model_description3("PIHysteresis")
    >>> 'fmiVersion="3.0" modelName="PIHysteresis"' in xml, '<Float64 name="p"' in xml
    (True, True)
    """
    spec = spec_of(name)
    lines = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<fmiModelDescription fmiVersion="3.0" modelName="{name}" '
        f'instantiationToken="{token(name)}" description="{escape(spec["description"])}" '
        'generationTool="pimodel" variableNamingConvention="structured">',
        f'  <CoSimulation modelIdentifier="{name}" canHandleVariableCommunicationStepSize="true"'
        ' canGetAndSetFMUState="true" canSerializeFMUState="true" hasEventMode="false"'
        ' providesIntermediateUpdate="false" canReturnEarlyAfterIntermediateUpdate="false"/>',
        LOG_CATEGORIES,
        '  <DefaultExperiment startTime="0" stopTime="1" stepSize="0.001"/>',
        "  <ModelVariables>",
        '    <Float64 name="time" valueReference="9" causality="independent" '
        'variability="continuous" description="simulation time [s]"/>',
    ]
    outputs = []
    for vname, vr, kind, causality, start, desc, is_array in _variables(name):
        if causality == "parameter":
            attrs = 'causality="parameter" variability="fixed"'
        elif causality == "input":
            attrs = 'causality="input" variability="discrete"'
        else:
            attrs = 'causality="output" variability="discrete" initial="exact"'
            outputs.append(vr)
        head = (f'    <{kind} name="{vname}" valueReference="{vr}" {attrs} '
                f'description="{escape(desc)}" start="{start}"')
        lines.append(f'{head}><Dimension start="{NMAX}"/></{kind}>' if is_array else f"{head}/>")
    lines += ["  </ModelVariables>", "  <ModelStructure>"]
    lines += [f'    <Output valueReference="{vr}"/>' for vr in outputs]
    lines += ["  </ModelStructure>", "</fmiModelDescription>", ""]
    return "\n".join(lines)
