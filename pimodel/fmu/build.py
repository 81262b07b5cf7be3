"""Build the pimodel FMUs (FMI 2.0 Co-Simulation, Linux binary + sources) with a C compiler.

Each FMU holds ``modelDescription.xml``, ``binaries/linux64/<id>.so``, ``sources/`` (our C core
and FMI glue plus a one-line ``model.c`` selecting the unit, listed in the model description
and in ``sources/buildDescription.xml`` so that ``fmpy compile`` rebuilds it elsewhere) and
``documentation/index.html``. The FMI headers come from the installed fmpy (``fmpy/c-code``).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
import zipfile
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import escape

__all__ = [
    "build_description",
    "build_fmus",
    "check_fmi_version",
    "find_compiler",
    "fmi_headers",
    "fmu_filename",
    "guid",
    "model_description",
    "source_dir",
    "spec_of",
    "Var",
]

NMAX = 64  # declared array size per FMU (p[1..64] ...); PIM_NMAX in fmu/src/pim_unit.h
MAX_SUBSTEPS = 10_000_000  # samples per doStep; PIM_MAX_SUBSTEPS in fmu/src/pim_unit.h
MAX_LTI_ELEMENTS = 8  # further elements of a DiagnosedModel's linear part; PIM_DIAG_MAX_ELEMENTS
# in fmu/src/pim_diagnosed.h
CORE_SOURCES = ("pim_pi.c", "pim_estimator.c", "pim_est_health.c", "pim_loops.c",
                "pim_generalized.c", "pim_asymmetric.c", "pim_rate_dependent.c", "pim_creep.c",
                "pim_diagnosed.c", "pim_diag_inverse.c")
HEADERS = ("pim_core.h", "pim_estimator.h", "pim_est_health.h", "pim_loops.h",
           "pim_generalized.h", "pim_asymmetric.h", "pim_rate_dependent.h", "pim_creep.h",
           "pim_diagnosed.h", "pim_diag_inverse.h",
           "pim_unit.h")
GLUE = {"2.0": "fmi2_pimodel.c", "3.0": "fmi3_pimodel.c"}
FMI_VERSIONS = tuple(GLUE)
SUFFIX = {"2.0": "", "3.0": "_fmi3"}  # file NAME{suffix}.fmu per FMI version


def check_fmi_version(fmi_version: str) -> str:
    """``fmi_version`` if supported, else ValueError naming the supported ones.

    Parameters
    ----------
    fmi_version : str
        ``"2.0"`` or ``"3.0"``.

    Returns
    -------
    str
        ``fmi_version``.

    Raises
    ------
    ValueError
        If it is not one of :data:`FMI_VERSIONS`.

    Examples
    --------
    >>> check_fmi_version("3.0")
    '3.0'
    >>> check_fmi_version("1.0")
    Traceback (most recent call last):
    ...
    ValueError: fmi_version: expected one of ('2.0', '3.0'), got '1.0'
    """
    if fmi_version not in GLUE:
        raise ValueError(f"fmi_version: expected one of {FMI_VERSIONS}, got {fmi_version!r}")
    return fmi_version


def fmu_filename(name: str, fmi_version: str = "2.0") -> str:
    """File name of a unit's FMU as :func:`build_fmus` writes it (``NAME.fmu``,
    ``NAME_fmi3.fmu``).

    Parameters
    ----------
    name : str
        The unit (model identifier), e.g. ``"PIHysteresis"``.
    fmi_version : {"2.0", "3.0"}, optional
        The FMI version. Default ``"2.0"``.

    Returns
    -------
    str
        The file name.

    Raises
    ------
    ValueError
        An unsupported ``fmi_version``.

    Examples
    --------
    >>> fmu_filename("PIHysteresis"), fmu_filename("PIHysteresis", "3.0")
    ('PIHysteresis.fmu', 'PIHysteresis_fmi3.fmu')
    """
    return f"{name}{SUFFIX[check_fmi_version(fmi_version)]}.fmu"
CFLAGS = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-fvisibility=hidden", "-O2", "-fPIC",
          "-shared"]

SAMPLING = ("Internal sample k at time k*Ts; doStep(t, h) processes every sample with k*Ts in "
            "[t, t+h) using the inputs set before the call; outputs hold the last sample's "
            "values.")


@dataclass(frozen=True)
class Var:
    """One scalar variable of a unit's FMI interface (a row of its model description).

    Parameters
    ----------
    name : str
        Variable name; arrays are 1-based scalars ``p[1]..p[64]``.
    vr : int
        Value reference.
    kind : {"Real", "Integer", "Boolean"}
        FMI 2 type.
    causality : {"parameter", "input", "output"}
        FMI causality.
    start : str
        Start value as written in the XML.
    description : str
        Meaning and unit.

    Examples
    --------
    >>> ts = spec_of("PIHysteresis")["vars"][0]
    >>> ts.name, ts.causality, ts.start
    ('Ts', 'parameter', '0.001')
    """

    name: str
    vr: int
    kind: str  # Real, Integer, Boolean
    causality: str  # parameter, input, output
    start: str
    description: str


def _arrays(prefix: str, base: int, causality: str, start: str, what: str) -> list[Var]:
    return [Var(f"{prefix}[{i + 1}]", base + i, "Real", causality, start, f"{what} {i + 1}")
            for i in range(NMAX)]


def _common(*, elements: str = "plays", z0: str = "initial play state (input unit)",
            weights: tuple[str, str, str] = ("p", "1", "weight p (> 0), play"),
            n_max: int = NMAX) -> list[Var]:
    """Ts, n, z0 and the weight array (name, start, description) of a unit."""
    return [
        Var("Ts", 0, "Real", "parameter", "0.001", "sample time [s] (>= 1e-12)"),
        Var("n", 1, "Integer", "parameter", "1", f"number of {elements}, 1 <= n <= {n_max}"),
        Var("z0", 2, "Real", "parameter", "0", z0),
        *_arrays(weights[0], 100, "parameter", weights[1], weights[2]),
    ]


def _inverse_flag(forward: str, inverse: str) -> Var:
    return Var("inverse", 8, "Boolean", "parameter", "false",
               f"false: u = {forward}; true: the exact inverse, u = {inverse}")


ENVELOPE_KINDS = {"poly2": 0, "tanh": 1, "poly2_inv": 2, "tanh_inv": 3}  # PIM_ENV_* codes


def _envelope_vars(prefix: str, base: int, what: str) -> list[Var]:
    """kind and c0..c3 of an envelope (pim_generalized.h); the default is the identity."""
    return [Var(f"{prefix}_kind", base, "Integer", "parameter", "0",
                f"{what}: 0 poly2, 1 tanh, 2 poly2_inv, 3 tanh_inv"),
            *[Var(f"{prefix}_c{j}", base + 1 + j, "Real", "parameter", "1" if j == 1 else "0",
                  f"{what}: coefficient c{j}") for j in range(4)]]


def _io(inp: str, out: str) -> list[Var]:
    return [Var("u", 10, "Real", "input", "0", inp), Var("y", 11, "Real", "output", "0", out)]


# The RadiusEstimator's health output (PIM_HEALTH_* in fmu/src/pim_est_health.h); the report in
# words goes to the FMU log (category logStatusWarning) at terminate.
HEALTH_BITS = ("health of the estimate so far, a bit mask: 1 the record cannot excite every "
               "play (Lemma 2), 2 plays merged, 4 a radius pinned at 0, 8 still moving, "
               "16 the model does not fit the data; 0 healthy (and before the first sample)")
LOG_CATEGORIES = ('  <LogCategories><Category name="logStatusWarning" description="warnings (the '
                  'radius estimate\'s health)"/><Category name="logStatusError" '
                  'description="errors"/></LogCategories>')

MODELS: dict[str, dict] = {
    "PIHysteresis": {
        "id": 1,
        "description": "Prandtl-Ishlinskii operator y = sum p_i Gamma_{r_i}[v] (pimodel C core)",
        "vars": [*_common(), *_arrays("r", 200, "parameter", "0", "radius r (>= 0, sorted), play"),
                 Var("v", 10, "Real", "input", "0", "input v (e.g. V)"),
                 Var("y", 11, "Real", "output", "0", "output y (e.g. um)")],
    },
    "RadiusEstimator": {
        "id": 2,
        "description": "Adaptive estimation of the play radii (gradient law with projection)",
        "vars": [*_common(), *_arrays("r", 200, "parameter", "0", "initial radius estimate, play"),
                 Var("gain", 4, "Real", "parameter", "10", "adaptation gain (>= 0)"),
                 Var("linear_play", 5, "Boolean", "parameter", "false",
                     "the model has a linear play: hold r_hat[1] = 0"),
                 Var("guard", 6, "Real", "parameter", "0", "breakpoint guard band (input unit)"),
                 Var("slope_window", 7, "Integer", "parameter", "8",
                     "slope check window in samples (0: off; law = 1 only)"),
                 Var("law", 14, "Integer", "parameter", "0",
                     "principal case: 0 data (from the measured branches, the default), "
                     "1 paper (from the estimate, the paper's rule)"),
                 Var("v", 10, "Real", "input", "0", "actuator input v"),
                 Var("y", 12, "Real", "input", "0", "measured output y"),
                 Var("y_hat", 11, "Real", "output", "0", "model output"),
                 Var("e", 13, "Real", "output", "0", "estimation error y_hat - y"),
                 *_arrays("r_hat", 300, "output", "0", "radius estimate, play"),
                 Var("health", 15, "Integer", "output", "0", HEALTH_BITS)],
    },
    "InversePI": {
        "id": 3,
        "description": "Exact inverse PI compensator, fixed radii or adaptive (r_hat inputs)",
        "vars": [*_common(), *_arrays("r", 200, "parameter", "0", "radius (fixed mode), play"),
                 Var("adaptive", 3, "Boolean", "parameter", "false",
                     "take the radii from the r_hat inputs at every sample"),
                 Var("y_d", 10, "Real", "input", "0", "desired output"),
                 Var("v", 11, "Real", "output", "0", "compensator output (actuator input)"),
                 *_arrays("r_hat", 300, "input", "0", "radius input (adaptive mode), play")],
    },
    "GeneralizedPI": {
        "id": 4,
        "description": "Generalized PI y = g(sum p_i Gamma_{r_i}[h(v)]) or its exact inverse "
                       "(pimodel.operators.generalized.GeneralizedPI)",
        "vars": [*_common(), *_arrays("r", 200, "parameter", "0",
                                      "radius r (>= 0, sorted, envelope units), play"),
                 _inverse_flag("v, y = y", "y_d, y = v"),
                 *_envelope_vars("in", 20, "input envelope h"),
                 *_envelope_vars("out", 25, "output envelope g"),
                 *_io("input (v, or y_d when inverse)", "output (y, or v when inverse)")],
    },
    "AsymmetricPI": {
        "id": 5,
        "description": "Asymmetric generalized PI (ascending/descending envelopes a phi + d) or "
                       "its exact inverse (pimodel.operators.asymmetric.AsymmetricPI)",
        "vars": [*_common(z0="initial play state (unit of phi)",
                          weights=("p", "1", "weight p (>= 0), play")),
                 *_arrays("r", 200, "parameter", "0", "radius r (>= 0, sorted), play"),
                 _inverse_flag("v, y = y", "y_d, y = v"),
                 Var("p0", 30, "Real", "parameter", "1", "direct weight of phi(v) (> 0)"),
                 Var("a_l", 31, "Real", "parameter", "1", "ascending envelope slope (> 0)"),
                 Var("d_l", 32, "Real", "parameter", "0", "ascending envelope offset"),
                 Var("a_r", 33, "Real", "parameter", "1", "descending envelope slope (> 0)"),
                 Var("d_r", 34, "Real", "parameter", "0", "descending envelope offset"),
                 *_envelope_vars("shape", 20, "shape function phi"),
                 *_io("input (v, or y_d when inverse)", "output (y, or v when inverse)")],
    },
    "RateDependentPI": {
        "id": 6,
        "description": "Rate-dependent PI, radii alpha_i (1 + beta rate), or its exact inverse "
                       "(pimodel.operators.rate_dependent.RateDependentPI, dt = Ts)",
        "vars": [*_common(), *_arrays("r", 200, "parameter", "0",
                                      "base radius alpha (>= 0, sorted), play"),
                 _inverse_flag("v, y = y", "y_d, y = v"),
                 Var("rate_gain", 40, "Real", "parameter", "0",
                     "beta [s per input unit] (>= 0)"),
                 Var("rate_time_constant", 41, "Real", "parameter", "0",
                     "rate filter time constant [s] (>= 0; 0: last interval)"),
                 Var("v0", 42, "Real", "parameter", "0", "input before the first sample v[-1]"),
                 *_io("input (v, or y_d when inverse)", "output (y, or v when inverse)")],
    },
    "CreepOperator": {
        "id": 7,
        "description": "Creep: sum of ZOH first-order lags with feedthrough 1, or its exact "
                       "inverse (pimodel.operators.creep.CreepOperator, dt = Ts)",
        "vars": [*_common(elements="lags", z0="initial lag state x_i[0]",
                          weights=("c", "0.05", "gain c (> 0), lag")),
                 *_arrays("tau", 200, "parameter", "1", "time constant tau [s] (> 0), lag"),
                 _inverse_flag("u, y = G[u]", "y, y = G^-1[y]"),
                 *_io("input (u, or y when inverse)", "output (G[u], or u when inverse)")],
    },
    "DiagnosedModel": {
        "id": 8,
        "description": "The model a diagnosis chose: PI hysteresis with signed weights and the "
                       "effect terms in parallel, creep, asymmetry, rate, drift, an LTI (b, a) "
                       "with further elements on h0 or a filter before the plays (Wiener), "
                       "and a delay "
                       "(pimodel.diagnosis.model.DiagnosedModel, dt = Ts)",
        "vars": [*_common(z0="initial play state (input unit; a diagnosis starts at 0)",
                          weights=("p", "1", "weight w (any sign), play"),
                          n_max=2 * NMAX),
                 *_arrays("r", 200, "parameter", "0", "radius r (>= 0, sorted), play"),
                 *_arrays("w0", 400, "parameter", "1",
                          "reference weight w0 of h0 (effect terms), play"),
                 Var("offset", 50, "Real", "parameter", "0", "offset c (output unit)"),
                 Var("reference_offset", 51, "Real", "parameter", "0", "offset c0 of h0"),
                 Var("n_lags", 52, "Integer", "parameter", "0",
                     f"creep lags, 0 <= n_lags <= {NMAX}"),
                 *_arrays("creep_gain", 500, "parameter", "0", "creep gain g, lag"),
                 *_arrays("creep_tau", 600, "parameter", "1",
                          "creep time constant tau [s] (> 0), lag"),
                 Var("asymmetry_quadratic", 53, "Real", "parameter", "0",
                     "asymmetry q of u^2, u = (h0 - center) / half_range"),
                 Var("asymmetry_cubic", 54, "Real", "parameter", "0", "asymmetry c3 of u^3"),
                 Var("center", 55, "Real", "parameter", "0", "asymmetry center (output unit)"),
                 Var("half_range", 56, "Real", "parameter", "1", "asymmetry half range (> 0)"),
                 *_arrays("rate_band_gain", 700, "parameter", "0",
                          "rate gain of the play's band (all 0: no rate term), play"),
                 Var("rate_scale", 57, "Real", "parameter", "1",
                     "input rate [input unit / s] of rho = 1 (> 0)"),
                 Var("rate_family", 63, "Integer", "parameter", "0",
                     "rate family: 0 radius (terms held from each play's last contact), "
                     "1 weight (rho_f times the band's sum of w0 z)"),
                 Var("rate_tau", 64, "Real", "parameter", "0",
                     "low-pass time constant of the normalised input rate [s] (>= 0; "
                     "0: none, with the step rule)"),
                 Var("input_range", 58, "Real", "parameter", "1",
                     "input range of the step rule (rate_tau = 0): a jump above 5 % of it "
                     "has no rate (> 0)"),
                 Var("drift_per_s", 59, "Real", "parameter", "0", "drift [output unit / s]"),
                 Var("drift_clock", 60, "Integer", "parameter", "0",
                     "drift clock: 0 none, 1 record (t - t_start), 2 absolute (t = k Ts)"),
                 Var("lti_order", 61, "Integer", "parameter", "0",
                     "order of the LTI b(z^-1) / a(z^-1) on the hysteresis (0: none, <= 63)"),
                 *_arrays("lti_b", 800, "parameter", "0",
                          "LTI numerator, coefficient of z^-(i-1), element"),
                 *[Var(f"lti_a[{i + 1}]", 900 + i, "Real", "parameter", "1" if i == 0 else "0",
                       f"LTI denominator (lti_a[1] = 1), coefficient of z^-(i-1), element "
                       f"{i + 1}") for i in range(NMAX)],
                 Var("delay_samples", 62, "Real", "parameter", "0",
                     "delay of the hysteresis term [samples] (0 <= d <= 4094, fractional: "
                     "linear interpolation)"),
                 Var("n_lti_elements", 65, "Integer", "parameter", "0",
                     f"further elements E_j of the linear part on h0, 0 <= n_lti_elements <= "
                     f"{MAX_LTI_ELEMENTS} (0: none)"),
                 *_arrays("lti_gain", 1400, "parameter", "0",
                          "gain g_j of the term g_j (E_j - M_1)[h0], element"),
                 *_arrays("lti_element_b", 1500, "parameter", "0",
                          "second-order sections, 3 numerator coefficients each (z^0, z^-1, "
                          "z^-2): M_1 in 1..3, E_j in 3j+1..3j+3, element"),
                 *[Var(f"lti_element_a[{i + 1}]", 1600 + i, "Real", "parameter",
                       "1" if i % 3 == 0 and i <= 3 * MAX_LTI_ELEMENTS else "0",
                       "second-order sections, 3 denominator coefficients each (the first 1), "
                       f"element {i + 1}") for i in range(NMAX)],
                 Var("n_wiener_elements", 66, "Integer", "parameter", "0",
                     f"sections F_j of a Wiener model's filter before the plays, in series on "
                     f"v, 0 <= n_wiener_elements <= {MAX_LTI_ELEMENTS} (0: none)"),
                 *_arrays("wiener_element_b", 1700, "parameter", "0",
                          "filter before the plays: second-order sections, 3 numerator "
                          "coefficients each (z^0, z^-1, z^-2): F_j in 3j-2..3j, element"),
                 *[Var(f"wiener_element_a[{i + 1}]", 1800 + i, "Real", "parameter",
                       "1" if i % 3 == 0 and i < 3 * MAX_LTI_ELEMENTS else "0",
                       "filter before the plays: second-order sections, 3 denominator "
                       f"coefficients each (the first 1), element {i + 1}") for i in range(NMAX)],
                 *_arrays("p_hi", 1000, "parameter", "1",
                          "weight w of play 64 + i (used when n > 64), element"),
                 *_arrays("r_hi", 1100, "parameter", "0",
                          "radius of play 64 + i (used when n > 64), element"),
                 *_arrays("w0_hi", 1200, "parameter", "1",
                          "reference weight of play 64 + i (used when n > 64), element"),
                 *_arrays("rate_band_gain_hi", 1300, "parameter", "0",
                          "rate band gain of play 64 + i (used when n > 64), element"),
                 Var("v", 10, "Real", "input", "0", "input v"),
                 Var("y", 11, "Real", "output", "0", "output y")],
    },
}


# The DiagnosedInverse unit (9): the causal feedforward of a DiagnosedModel
# (pimodel.diagnosis.inverse_native, fmu/src/pim_diag_inverse.h). The static part's variables
# are the DiagnosedModel unit's (same names and references, the weights projected monotone).
MAX_INVERSE_SECTIONS = 10  # prefilter sections in section[1..60]; PIM_DINV_FMU_SECTIONS
_INVERSE_SHARED = {"Ts", "n", "z0", "p", "r", "w0", "offset", "reference_offset", "n_lags",
                   "creep_gain", "creep_tau", "asymmetry_quadratic", "asymmetry_cubic",
                   "center", "half_range", "rate_band_gain", "rate_scale", "rate_family",
                   "rate_tau", "input_range", "p_hi", "r_hi", "w0_hi", "rate_band_gain_hi"}
MODELS["DiagnosedInverse"] = {
    "id": 9,
    "description": "The causal feedforward of a diagnosed model: the prefilter (the dynamics' "
                   "approximate inverse), the delay's fraction, the exact per-sample root "
                   "of the static part (creep, asymmetry, rate) and the post sections (the "
                   "approximate inverse of a filter before the hysteresis), its output delayed "
                   "by the latency (pimodel.diagnosis.model.DiagnosedInverse.block, dt = Ts)",
    "vars": [*[v for v in MODELS["DiagnosedModel"]["vars"]
               if v.name.split("[")[0] in _INVERSE_SHARED],
             Var("reference_range", 67, "Real", "parameter", "0",
                 "range of the (prefiltered) reference, the root rule's scale: span = max(2 "
                 "r_n, reference_range / |sum w|, 1) (>= 0)"),
             Var("latency", 68, "Integer", "parameter", "0",
                 "samples A by which v is delayed (the prefilter's advance and the delay's "
                 "whole samples, one more for a fraction); v = v_rest before"),
             Var("delay_fraction", 69, "Real", "parameter", "0",
                 "the delay's fractional part f (0 <= f < 1): the reference interpolated "
                 "between the last two prefilter outputs"),
             Var("n_sections", 70, "Integer", "parameter", "0",
                 f"prefilter sections (the dynamics' approximate inverse), 0 <= n_sections "
                 f"<= {MAX_INVERSE_SECTIONS}"),
             *[Var(f"section[{i + 1}]", 1900 + i, "Real", "parameter",
                   "1" if i % 6 == 3 and i < 6 * MAX_INVERSE_SECTIONS else "0",
                   "prefilter second-order sections, 6 coefficients each (b0 b1 b2 a0 a1 a2, "
                   f"a0 = 1, as scipy.signal.sosfilt), element {i + 1}") for i in range(NMAX)],
             Var("n_post_sections", 71, "Integer", "parameter", "0",
                 f"sections after the solve (a Wiener model's filter inverse, latency >= 1), "
                 f"0 <= n_post_sections <= {MAX_INVERSE_SECTIONS}"),
             *[Var(f"post_section[{i + 1}]", 2000 + i, "Real", "parameter",
                   "1" if i % 6 == 3 and i < 6 * MAX_INVERSE_SECTIONS else "0",
                   "post second-order sections on the solved input (the approximate inverse of a "
                   "filter before the hysteresis), 6 coefficients each (b0 b1 b2 a0 a1 a2, a0 = "
                   f"1), element {i + 1}") for i in range(NMAX)],
             Var("y_d", 10, "Real", "input", "0", "reference y_d (the model's output unit)"),
             Var("v", 11, "Real", "output", "0", "feedforward input v (the model's input "
                 "unit)")],
}


# FMUs of one model's operators (pimodel.fmu.model_fmu): identifier -> spec as in MODELS, plus
# "salt" (in the GUID) and "defaults" (C statements setting the parameters' start values).
MODEL_UNITS: dict[str, dict] = {}


def spec_of(name: str) -> dict:
    """The spec of a unit (``MODELS``) or of a model's operator FMU (``MODEL_UNITS``).

    Parameters
    ----------
    name : str
        The unit's model identifier.

    Returns
    -------
    dict
        ``id`` (unit code in the C glue), ``description`` and ``vars`` (list of :class:`Var`);
        a model's operator FMU also has ``salt`` and ``defaults``.

    Raises
    ------
    KeyError
        An unknown unit.

    Examples
    --------
    >>> spec = spec_of("PIHysteresis")
    >>> spec["id"], [v.name for v in spec["vars"]][:4]
    (1, ['Ts', 'n', 'z0', 'p[1]'])
    """
    return MODEL_UNITS[name] if name in MODEL_UNITS else MODELS[name]


def guid(name: str) -> str:
    """Fixed GUID of a unit (changes with the interface version: v2 has 64 plays, linear_play;
    a model's operator FMU also with its parameter values).

    Parameters
    ----------
    name : str
        The unit's model identifier.

    Returns
    -------
    str
        A braced name-based UUID (uuid5), the same on every build.

    Examples
    --------
    >>> g = guid("PIHysteresis")
    >>> g == guid("PIHysteresis"), g[0] + g[-1], len(g)
    (True, '{}', 38)
    """
    import uuid

    salt = MODEL_UNITS[name]["salt"] if name in MODEL_UNITS else ""
    return "{" + str(uuid.uuid5(uuid.NAMESPACE_URL, f"pimodel/fmi2/{name}/v2{salt}")) + "}"


def source_dir() -> Path:
    """The C sources: ``fmu/src`` beside the package (editable install) or packaged copy.

    Returns
    -------
    pathlib.Path
        The folder holding the FMI glue and the C core.

    Raises
    ------
    FileNotFoundError
        When neither location holds the sources.

    Examples
    --------
    >>> (source_dir() / "pim_pi.c").is_file()
    True
    """
    here = Path(__file__).resolve()
    for cand in (here.parents[2] / "fmu" / "src", here.parent / "src"):
        if (cand / GLUE["2.0"]).exists():
            return cand
    raise FileNotFoundError("pimodel FMU sources (fmu/src) not found; install pimodel from a "
                            "source checkout ('pip install -e .')")


def fmi_headers() -> Path:
    """The FMI headers shipped with the installed fmpy (``fmpy/c-code``).

    Returns
    -------
    pathlib.Path
        The folder holding ``fmi2Functions.h`` (and the FMI 3 headers).

    Raises
    ------
    FileNotFoundError
        When the fmpy installation has no FMI 2 headers.

    Examples
    --------
    >>> (fmi_headers() / "fmi2Functions.h").is_file()
    True
    """
    import fmpy

    path = Path(fmpy.__file__).parent / "c-code"
    if not (path / "fmi2Functions.h").exists():
        raise FileNotFoundError(f"FMI 2 headers not found in {path} (fmpy installation)")
    return path


def find_compiler() -> str:
    """A C compiler on PATH ($CC, cc, gcc or clang); RuntimeError naming them when none.

    Returns
    -------
    str
        The first of ``$CC``, ``cc``, ``gcc``, ``clang`` found on PATH.

    Raises
    ------
    RuntimeError
        When none is found.

    Examples
    --------
    >>> import os
    >>> find_compiler() in (os.environ.get("CC"), "cc", "gcc", "clang")
    True
    """
    for cand in (os.environ.get("CC"), "cc", "gcc", "clang"):
        if cand and shutil.which(cand):
            return cand
    raise RuntimeError("no C compiler found: set CC or put cc, gcc or clang on PATH")


def model_description(name: str) -> str:
    """The FMI 2.0 ``modelDescription.xml`` of a unit (Co-Simulation, scalar variables).

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
    >>> xml = model_description("PIHysteresis")
    >>> 'fmiVersion="2.0" modelName="PIHysteresis"' in xml, 'name="r[64]"' in xml
    (True, True)
    """
    spec = spec_of(name)
    lines = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<fmiModelDescription fmiVersion="2.0" modelName="{name}" guid="{guid(name)}" '
        f'description="{escape(spec["description"])}" generationTool="pimodel" '
        'variableNamingConvention="structured" numberOfEventIndicators="0">',
        f'  <CoSimulation modelIdentifier="{name}" canHandleVariableCommunicationStepSize="true"'
        ' canGetAndSetFMUstate="true" canSerializeFMUstate="true"'
        ' canNotUseMemoryManagementFunctions="true" canInterpolateInputs="false">',
        "    <SourceFiles>",
        '      <File name="model.c"/>',
        *[f'      <File name="{s}"/>' for s in CORE_SOURCES],
        "    </SourceFiles>",
        "  </CoSimulation>",
        LOG_CATEGORIES,
        '  <DefaultExperiment startTime="0" stopTime="1" stepSize="0.001"/>',
        "  <ModelVariables>",
    ]
    outputs = []
    for idx, v in enumerate(spec["vars"], start=1):
        if v.causality == "parameter":
            attrs = 'causality="parameter" variability="fixed" initial="exact"'
        elif v.causality == "input":
            attrs = 'causality="input" variability="discrete"'
        else:
            attrs = 'causality="output" variability="discrete" initial="exact"'
            outputs.append(idx)
        lines.append(f'    <ScalarVariable name="{v.name}" valueReference="{v.vr}" {attrs} '
                     f'description="{escape(v.description)}"><{v.kind} start="{v.start}"/>'
                     "</ScalarVariable>")
    lines += ["  </ModelVariables>", "  <ModelStructure>", "    <Outputs>"]
    lines += [f'      <Unknown index="{i}"/>' for i in outputs]
    lines += ["    </Outputs>", "  </ModelStructure>", "</fmiModelDescription>", ""]
    return "\n".join(lines)


def build_description(name: str) -> str:
    """``sources/buildDescription.xml``: the C files ``fmpy compile`` needs to rebuild the unit.

    Parameters
    ----------
    name : str
        The unit's model identifier.

    Returns
    -------
    str
        The XML text (FMI 3 build description, also read for FMI 2 by fmpy).

    Examples
    --------
    >>> build_description("PIHysteresis").splitlines()[2]
    '  <BuildConfiguration modelIdentifier="PIHysteresis">'
    """
    files = "\n".join(f'        <SourceFile name="{s}"/>' for s in ("model.c", *CORE_SOURCES))
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n<fmiBuildDescription fmiVersion="3.0">\n'
        f'  <BuildConfiguration modelIdentifier="{name}">\n'
        '    <SourceFileSet language="C99">\n'
        f"{files}\n"
        "    </SourceFileSet>\n  </BuildConfiguration>\n</fmiBuildDescription>\n"
    )


def _model_c(name: str, fmi_version: str) -> str:
    if fmi_version == "3.0":
        from .fmi3 import token

        ident = f'#define PIM_MODEL_TOKEN "{token(name)}"\n'
    else:
        ident = f'#define PIM_MODEL_GUID "{guid(name)}"\n'
    spec = spec_of(name)
    if "defaults" in spec:
        ident += f"#define PIM_MODEL_DEFAULTS(u) do {{ {spec['defaults']} }} while (0)\n"
    return (f"/* {name}: selects the unit in the shared FMI {fmi_version} glue. */\n"
            f"#define PIM_MODEL {spec['id']}\n{ident}"
            f'#include "{GLUE[fmi_version]}"\n')


def _documentation(name: str) -> str:
    spec = spec_of(name)
    rows = "".join(f"<tr><td>{v.name}</td><td>{v.causality}</td><td>{escape(v.description)}"
                   "</td></tr>" for v in spec["vars"] if "[" not in v.name or "[1]" in v.name)
    return (f"<html><body><h1>{name}</h1><p>{escape(spec['description'])}.</p>"
            f"<p>{escape(SAMPLING)} Arrays are declared up to index {NMAX}; the first n are "
            "used. Bad parameters or non-finite inputs return an error status (fmi2Error, "
            "fmi3Error) with a logged message, as do a call in the wrong state, an unknown "
            "value reference, a doStep whose t is not the FMU's time, a step of more than "
            f"{MAX_SUBSTEPS:,} samples, and an FMU state that fails its checks (format, "
            "checksum, parameters, finite states)."
            f"</p><table>{rows}</table></body></html>\n")


def build_fmus(out_dir, which=None, *, compiler: str | None = None,
               fmi_version: str = "2.0") -> list[Path]:
    """Compile and package the FMUs named in ``which`` (default all) into ``out_dir``.

    Parameters
    ----------
    out_dir : str or Path
        Folder of the FMUs (created; existing files overwritten).
    which : iterable of str, optional
        Units to build (names of ``MODELS`` or ``MODEL_UNITS``); default all of ``MODELS``.
    compiler : str, optional
        C compiler; default :func:`find_compiler`.
    fmi_version : {"2.0", "3.0"}, optional
        ``"2.0"`` (files ``NAME.fmu``) or ``"3.0"`` (files ``NAME_fmi3.fmu``, arrays as FMI 3
        arrays); the model identifier is ``NAME`` in both. Default ``"2.0"``.

    Returns
    -------
    list of pathlib.Path
        The FMU files, in the order of ``which``.

    Raises
    ------
    ValueError
        An unknown unit or FMI version.
    RuntimeError
        No compiler found, or compiling failed (the message holds the compiler's output).
    FileNotFoundError
        The C sources or the FMI headers are missing.

    Examples
    --------
    Compiling takes about a second per unit, hence skipped here:

    >>> import tempfile
    >>> build_fmus(tempfile.mkdtemp(), ["PIHysteresis"])[0].name  # doctest: +SKIP
    'PIHysteresis.fmu'
    """
    names = list(MODELS) if which is None else list(which)
    unknown = [n for n in names if n not in MODELS and n not in MODEL_UNITS]
    if unknown:
        raise ValueError(f"which: unknown FMU(s) {unknown}; available: {list(MODELS)}")
    check_fmi_version(fmi_version)
    cc = compiler or find_compiler()
    src, inc = source_dir(), fmi_headers()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    glue = GLUE[fmi_version]
    if fmi_version == "3.0":
        from .fmi3 import PLATFORM
        from .fmi3 import model_description3 as describe

        platform = PLATFORM
    else:
        describe, platform = model_description, "linux64"
    paths = []
    for name in names:
        with tempfile.TemporaryDirectory() as tmp:
            tmp = Path(tmp)
            (tmp / "model.c").write_text(_model_c(name, fmi_version))
            for f in (glue, *CORE_SOURCES, *HEADERS):
                shutil.copy(src / f, tmp / f)
            so = tmp / f"{name}.so"
            cmd = [cc, *CFLAGS, "-I", str(tmp), "-I", str(inc), str(tmp / "model.c"),
                   *[str(tmp / s) for s in CORE_SOURCES], "-o", str(so), "-lm"]
            proc = subprocess.run(cmd, capture_output=True, text=True)
            if proc.returncode != 0:
                raise RuntimeError(f"compiling {name} (FMI {fmi_version}) failed:\n"
                                   f"{proc.stderr}")
            fmu = out / fmu_filename(name, fmi_version)
            with zipfile.ZipFile(fmu, "w", zipfile.ZIP_DEFLATED) as z:
                z.writestr("modelDescription.xml", describe(name))
                z.write(so, f"binaries/{platform}/{name}.so")
                for f in ("model.c", glue, *CORE_SOURCES, *HEADERS):
                    z.write(tmp / f, f"sources/{f}")
                z.writestr("sources/buildDescription.xml", build_description(name))
                z.writestr("documentation/index.html", _documentation(name))
            paths.append(fmu)
    return paths
