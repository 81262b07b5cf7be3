"""The one spec of the FMU units: their variables, value references and identity.

``MODELS`` (and ``MODEL_UNITS``, a model's operator FMUs) lists every unit's variables as
:class:`Var` rows; from it come both the model descriptions (:mod:`pimodel.fmu.description`)
and, at build time, each unit's C header ``config.h`` (:func:`config_h`: model identifier, unit
number, GUID or instantiation token, the ``ValueReference`` enum and the variable table the C
framework ``fmu/src/fmi/pim_unit.h`` serves every get/set from). No value reference is typed in
C. The limits come from the C core (``pimodel._native.LIMITS``, ``fmu/src/core/pim_limits.h``).
"""

from __future__ import annotations

import uuid
from dataclasses import dataclass

from .. import _native
from .._native import LIMITS

__all__ = ["FMI_VERSIONS", "MAX_INVERSE_SECTIONS", "MAX_LTI_ELEMENTS", "MAX_SUBSTEPS",
           "MODELS", "MODEL_UNITS", "NMAX", "N_PLAYS", "PER_PLAY", "TIME", "Var",
           "ENVELOPE_KINDS", "HEALTH_BITS",
           "c_variables", "check_fmi_version", "config_h", "guid", "spec_of", "token",
           "unit_of"]

NMAX = LIMITS["PIM_MAX_PLAYS"]  # declared array size per FMU (p[1..64] ...)
MAX_SUBSTEPS = LIMITS["PIM_MAX_SUBSTEPS"]  # samples per doStep
MAX_LTI_ELEMENTS = LIMITS["PIM_DIAG_MAX_ELEMENTS"]  # further elements of a DiagnosedModel's LTI
MAX_INVERSE_SECTIONS = LIMITS["PIM_DINV_FMU_SECTIONS"]  # DiagnosedInverse: sections in section[]
FMI_VERSIONS = ("2.0", "3.0")


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
    if fmi_version not in FMI_VERSIONS:
        raise ValueError(f"fmi_version: expected one of {FMI_VERSIONS}, got {fmi_version!r}")
    return fmi_version


@dataclass(frozen=True)
class Var:
    """One scalar variable of a unit's FMI interface (a row of its model description).

    Parameters
    ----------
    name : str
        Variable name; arrays are 1-based scalars ``p[1]..p[64]``.
    vr : int
        Value reference.
    kind : {"Real", "Integer", "Boolean", "UInt64"}
        FMI 2 type (``"UInt64"``: FMI 3 only, :data:`N_PLAYS`).
    causality : {"parameter", "input", "output", "independent", "structuralParameter"}
        FMI causality (the last two FMI 3 only: :data:`TIME`, :data:`N_PLAYS`).
    start : str
        Start value as written in the XML.
    description : str
        Meaning and unit.
    field : str, optional
        The C storage: member of the unit's struct ``pim_unit`` (``fmu/src/fmi/pim_unit.h``)
        that holds the value (an array's elements from its first); default the name (an array's:
        without the index).

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
    field: str = ""

    @property
    def base(self) -> str:
        """The name without an array index (``p`` of ``p[3]``)."""
        return self.name.split("[")[0]

    @property
    def storage(self) -> str:
        """The C member holding the value (:attr:`field`, default :attr:`base`)."""
        return self.field or self.base


def _arrays(prefix: str, base: int, causality: str, start: str, what: str,
            field: str = "") -> list[Var]:
    return [Var(f"{prefix}[{i + 1}]", base + i, "Real", causality, start, f"{what} {i + 1}",
                field) for i in range(NMAX)]


def _common(*, elements: str = "plays", z0: str = "initial play state (input unit)",
            weights: tuple[str, str, str] = ("p", "1", "weight p (> 0), play"),
            n_max: int = NMAX, weights_field: str = "") -> list[Var]:
    """Ts, n, z0 and the weight array (name, start, description) of a unit."""
    return [
        Var("Ts", 0, "Real", "parameter", "0.001", "sample time [s] (>= 1e-12)"),
        Var("n", 1, "Integer", "parameter", "1", f"number of {elements}, 1 <= n <= {n_max}"),
        Var("z0", 2, "Real", "parameter", "0", z0),
        *_arrays(weights[0], 100, "parameter", weights[1], weights[2], weights_field),
    ]


def _inverse_flag(forward: str, inverse: str) -> Var:
    return Var("inverse", 8, "Boolean", "parameter", "false",
               f"false: u = {forward}; true: the exact inverse, u = {inverse}")


ENVELOPE_KINDS = _native.ENVELOPE_KINDS


def _envelope_vars(prefix: str, base: int, what: str, field: str) -> list[Var]:
    """kind and c0..c3 of an envelope (pim_generalized.h), stored in kind_<field>,
    c_<field>[j]; the default is the identity."""
    return [Var(f"{prefix}_kind", base, "Integer", "parameter", "0",
                f"{what}: 0 poly2, 1 tanh, 2 poly2_inv, 3 tanh_inv", f"kind_{field}"),
            *[Var(f"{prefix}_c{j}", base + 1 + j, "Real", "parameter", "1" if j == 1 else "0",
                  f"{what}: coefficient c{j}", f"c_{field}[{j}]") for j in range(4)]]


def _io(inp: str, out: str) -> list[Var]:
    return [Var("u", 10, "Real", "input", "0", inp, "in1"),
            Var("y", 11, "Real", "output", "0", out, "out1")]


# The RadiusEstimator's health output (PIM_HEALTH_* in fmu/src/pim_est_health.h); the report in
# words goes to the FMU log (category logStatusWarning) at terminate.
HEALTH_BITS = ("health of the estimate so far, a bit mask: 1 the record cannot excite every "
               "play (Lemma 2), 2 plays merged, 4 a radius pinned at 0, 8 still moving, "
               "16 the model does not fit the data; 0 healthy (and before the first sample)")

MODELS: dict[str, dict] = {
    "PIHysteresis": {
        "id": 1,
        "description": "Prandtl-Ishlinskii operator y = sum p_i Gamma_{r_i}[v] (pimodel C core)",
        "vars": [*_common(), *_arrays("r", 200, "parameter", "0", "radius r (>= 0, sorted), play"),
                 Var("v", 10, "Real", "input", "0", "input v (e.g. V)", "in1"),
                 Var("y", 11, "Real", "output", "0", "output y (e.g. um)", "out1")],
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
                 Var("threshold", 16, "Real", "parameter", "0",
                     "reversal threshold (input unit; estimate_radii's default: 3 x the "
                     "input noise level)"),
                 Var("law", 14, "Integer", "parameter", "0",
                     "principal case: 0 data (from the measured branches, the default), "
                     "1 paper (from the estimate, the paper's rule)"),
                 Var("v", 10, "Real", "input", "0", "actuator input v", "in1"),
                 Var("y", 12, "Real", "input", "0", "measured output y", "in2"),
                 Var("y_hat", 11, "Real", "output", "0", "model output", "out1"),
                 Var("e", 13, "Real", "output", "0", "estimation error y_hat - y", "out2"),
                 *_arrays("r_hat", 300, "output", "0", "radius estimate, play", "rhat_out"),
                 Var("health", 15, "Integer", "output", "0", HEALTH_BITS)],
    },
    "InversePI": {
        "id": 3,
        "description": "Exact inverse PI compensator, fixed radii or adaptive (r_hat inputs)",
        "vars": [*_common(), *_arrays("r", 200, "parameter", "0", "radius (fixed mode), play"),
                 Var("adaptive", 3, "Boolean", "parameter", "false",
                     "take the radii from the r_hat inputs at every sample"),
                 Var("y_d", 10, "Real", "input", "0", "desired output", "in1"),
                 Var("v", 11, "Real", "output", "0", "compensator output (actuator input)",
                     "out1"),
                 *_arrays("r_hat", 300, "input", "0", "radius input (adaptive mode), play",
                          "rhat_in")],
    },
    "GeneralizedPI": {
        "id": 4,
        "description": "Generalized PI y = g(sum p_i Gamma_{r_i}[h(v)]) or its exact inverse "
                       "(pimodel.operators.generalized.GeneralizedPI)",
        "vars": [*_common(), *_arrays("r", 200, "parameter", "0",
                                      "radius r (>= 0, sorted, envelope units), play"),
                 _inverse_flag("v, y = y", "y_d, y = v"),
                 *_envelope_vars("in", 20, "input envelope h", "in"),
                 *_envelope_vars("out", 25, "output envelope g", "out"),
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
                 *_envelope_vars("shape", 20, "shape function phi", "in"),
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
                     "rate filter time constant [s] (>= 0; 0: last interval)", "rate_tc"),
                 Var("v0", 42, "Real", "parameter", "0", "input before the first sample v[-1]"),
                 *_io("input (v, or y_d when inverse)", "output (y, or v when inverse)")],
    },
    "CreepOperator": {
        "id": 7,
        "description": "Creep: sum of ZOH first-order lags with feedthrough 1, or its exact "
                       "inverse (pimodel.operators.creep.CreepOperator, dt = Ts)",
        "vars": [*_common(elements="lags", z0="initial lag state x_i[0]",
                          weights=("c", "0.05", "gain c (> 0), lag"), weights_field="p"),
                 *_arrays("tau", 200, "parameter", "1", "time constant tau [s] (> 0), lag", "r"),
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
        "vars": [*_common(z0="initial play state (input unit; used when plays_start = 0)",
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
                     "asymmetry q of u^2, u = (h0 - center) / half_range", "asym_q"),
                 Var("asymmetry_cubic", 54, "Real", "parameter", "0", "asymmetry c3 of u^3",
                     "asym_c3"),
                 Var("center", 55, "Real", "parameter", "0", "asymmetry center (output unit)"),
                 Var("half_range", 56, "Real", "parameter", "1", "asymmetry half range (> 0)"),
                 *_arrays("rate_band_gain", 700, "parameter", "0",
                          "rate gain of the play's band (all 0: no rate term), play"),
                 Var("rate_scale", 57, "Real", "parameter", "1",
                     "input rate [input unit / s] of rho = 1 (> 0)"),
                 Var("rate_family", 63, "Integer", "parameter", "0",
                     "rate family: 0 radius (terms held from each play's last contact), "
                     "1 weight (rho_f times the band's sum of w0 z), 2 scaled (plays whose "
                     "radii scale with the rate, minus the plays)"),
                 Var("rate_tau", 64, "Real", "parameter", "0",
                     "low-pass time constant of the normalised input rate [s] (>= 0; "
                     "0: none, with the step rule)"),
                 Var("rate_saturation", 76, "Real", "parameter", "0",
                     "saturation S of the filtered normalised rate rho_f: the terms follow "
                     "rho_f / (1 + rho_f / S), rho_f >= 0 (S >= 0; 0: linear in rho_f)"),
                 Var("rate_growth", 77, "Real", "parameter", "0",
                     "growth G of the scaled family (rate_family 2): plays of radii r (1 + G s "
                     "/ (1 + s / S)), s the strictly causal filtered normalised rate"),
                 Var("input_range", 58, "Real", "parameter", "1",
                     "input range of the step rule (rate_tau = 0): a jump above 5 % of it "
                     "has no rate (> 0)"),
                 Var("drift_per_s", 59, "Real", "parameter", "0", "drift [output unit / s]"),
                 Var("drift_clock", 60, "Integer", "parameter", "0",
                     "drift clock: 0 none, 1 record (t - t_start), 2 absolute (t = k Ts)"),
                 Var("drift_settling", 73, "Real", "parameter", "0",
                     "settling drift D of D (1 - exp(-(t - drift_settling_start) / "
                     "drift_settling_tau)), t = k Ts (output unit)"),
                 Var("drift_settling_tau", 74, "Real", "parameter", "0",
                     "settling time constant T [s] (>= 0; 0: no settling)"),
                 Var("drift_settling_start", 75, "Real", "parameter", "0",
                     "settling start t_s [s] on the FMU clock t = k Ts"),
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
                 Var("plays_start", 72, "Integer", "parameter", "0",
                     "plays before the first sample: 0 at z0, 1 at rest at the first input "
                     "v[0] (the diagnosis' nominal, DiagnosedModel.plays_start)"),
                 Var("creep_start", 78, "Integer", "parameter", "0",
                     "creep lags before the first sample: 0 at rest at h0[0], 1 at rest at "
                     "creep_start_level (a common rest, params creep_start 'common'), 2 at "
                     "rest at h0[0] and the creep counted from the record's start: less "
                     "sum_j g_j h0[0], y[0] un-crept (params creep_start 'record')"),
                 *_arrays("creep_start_level", 2100, "parameter", "0",
                          "rest level s of the creep lag before the first sample when "
                          "creep_start = 1 (output unit), lag"),
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
                 Var("v", 10, "Real", "input", "0", "input v", "in1"),
                 Var("y", 11, "Real", "output", "0", "output y", "out1")],
    },
}


# The DiagnosedInverse unit (9): the causal feedforward of a DiagnosedModel
# (pimodel.diagnosis.native_inverse, fmu/src/core/pim_diag_inverse.h). The static part's variables
# are the DiagnosedModel unit's (same names and references, the weights projected monotone).
_INVERSE_SHARED = {"Ts", "n", "z0", "p", "r", "w0", "offset", "reference_offset", "n_lags",
                   "creep_gain", "creep_tau", "creep_start", "creep_start_level",
                   "asymmetry_quadratic", "asymmetry_cubic",
                   "center", "half_range", "rate_band_gain", "rate_scale", "rate_family",
                   "rate_tau", "rate_saturation", "rate_growth", "input_range", "p_hi", "r_hi",
                   "w0_hi", "rate_band_gain_hi"}
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
             Var("y_d", 10, "Real", "input", "0", "reference y_d (the model's output unit)",
                 "in1"),
             Var("v", 11, "Real", "output", "0", "feedforward input v (the model's input "
                 "unit)", "out1")],
}


# The FMI 3 independent variable (every unit; FMI 2 has none): its storage is the FMU's time.
TIME = Var("time", 9, "Real", "independent", "", "simulation time [s]")

# The FMI 3 structural parameter (every unit; FMI 2 has none) that sizes the per-play arrays
# (<Dimension valueReference="18"/>), set in configuration mode; plays 1..n of n_plays are used.
N_PLAYS = Var("n_plays", 18, "UInt64", "structuralParameter", str(NMAX),
              f"size of the per-play arrays (p, r, r_hat, ...; CreepOperator: c, tau), "
              f"n <= n_plays <= {NMAX} (DiagnosedModel, DiagnosedInverse: n > {NMAX} needs "
              f"n_plays = {NMAX}, plays beyond in the _hi arrays); set in configuration mode",
              "n_plays")
# The FMI 3 arrays sized by N_PLAYS: one element per play (CreepOperator: per lag). The
# others (coefficients, lags of n_lags, the _hi plays 65..128) stay NMAX wide.
PER_PLAY = frozenset({"p", "r", "r_hat", "c", "tau", "w0", "rate_band_gain"})

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


def unit_of(name: str) -> str:
    """The unit (a ``MODELS`` name, its C folder ``fmu/src/units/<unit>``) of a unit or of a
    model's operator FMU.

    Parameters
    ----------
    name : str
        The model identifier (a ``MODELS`` or ``MODEL_UNITS`` name).

    Returns
    -------
    str
        The ``MODELS`` name with the same unit number.

    Raises
    ------
    KeyError
        An unknown unit.

    Examples
    --------
    >>> unit_of("PIHysteresis")
    'PIHysteresis'
    """
    unit_id = spec_of(name)["id"]
    return next(unit for unit, spec in MODELS.items() if spec["id"] == unit_id)


def _identity(name: str, fmi: str) -> str:
    """A braced uuid5 of the unit, its FMI version and (a model's operator FMU) its salt."""
    salt = MODEL_UNITS[name]["salt"] if name in MODEL_UNITS else ""
    return "{" + str(uuid.uuid5(uuid.NAMESPACE_URL, f"pimodel/{fmi}/{name}/v2{salt}")) + "}"


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
    return _identity(name, "fmi2")


def token(name: str) -> str:
    """Fixed FMI 3 instantiation token of a unit (changes with the interface version).

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
    >>> t = token("PIHysteresis")
    >>> t == token("PIHysteresis"), t != guid("PIHysteresis"), len(t)
    (True, True, 38)
    """
    return _identity(name, "fmi3")


_C_TYPES = {"Real": "'R'", "Integer": "'I'", "Boolean": "'B'", "UInt64": "'U'"}
_C_CAUSALITY = {"parameter": "PIM_PARAMETER", "input": "PIM_INPUT", "output": "PIM_OUTPUT",
                "independent": "PIM_INDEPENDENT", "structuralParameter": "PIM_STRUCTURAL"}


def _c_size(row: tuple, fmi_version: str) -> str:
    """The size column of a C table row: 1, PIM_NMAX, or PIM_PER_PLAY (FMI 3 per-play)."""
    if row[4] == 1:
        return "1"
    return "PIM_PER_PLAY" if fmi_version == "3.0" and row[0] in PER_PLAY else "PIM_NMAX"


def c_variables(name: str) -> list[tuple[str, int, str, str, int, str]]:
    """The rows of a unit's C variable table, arrays as one row: (name, value reference, FMI 2
    type, causality, size, C storage); inputs and outputs first (the accessors scan the table
    on every call), then the parameters, then ``time``.

    Parameters
    ----------
    name : str
        The unit's model identifier.

    Returns
    -------
    list of tuple
        One row per variable (an array's first element gives its reference).

    Raises
    ------
    ValueError
        A variable whose array size is not ``NMAX`` (the C arrays' size) or whose elements'
        references are not consecutive.

    Examples
    --------
    >>> c_variables("PIHysteresis")[:2]
    [('v', 10, 'Real', 'input', 1, 'in1'), ('y', 11, 'Real', 'output', 1, 'out1')]
    """
    rows: dict[str, list] = {}
    for v in spec_of(name)["vars"]:
        if v.base in rows:
            row = rows[v.base]
            if v.vr != row[1] + row[4]:
                raise ValueError(f"{name}: {v.name} has reference {v.vr}, not {row[1] + row[4]}")
            row[4] += 1
        else:
            rows[v.base] = [v.base, v.vr, v.kind, v.causality, 1, v.storage]
    for row in rows.values():
        if row[4] != 1 and row[4] != NMAX:
            raise ValueError(f"{name}: array {row[0]} has {row[4]} elements, the C arrays {NMAX}")
    ordered = sorted(rows.values(), key=lambda r: r[3] == "parameter")  # stable: io first
    return [tuple(r) for r in ordered] + [
        (TIME.name, TIME.vr, TIME.kind, TIME.causality, 1, "time")]


def config_h(name: str, fmi_version: str = "2.0") -> str:
    """The C header ``config.h`` of a unit, generated at build time into the FMU's ``sources/``:
    model identifier, unit number, GUID (FMI 2) or instantiation token (FMI 3), the
    ``ValueReference`` enum and the variable table ``PIM_UNIT_VARIABLES(X)`` that
    ``fmu/src/fmi/pim_unit.h`` expands into ``unit_vars`` (optionally ``PIM_MODEL_DEFAULTS``,
    the start values of a model's operator FMU).

    Parameters
    ----------
    name : str
        The unit's model identifier.
    fmi_version : {"2.0", "3.0"}, optional
        The FMI version. Default ``"2.0"``.

    Returns
    -------
    str
        The C text.

    Raises
    ------
    KeyError
        An unknown unit.
    ValueError
        An unsupported ``fmi_version``.

    Examples
    --------
    >>> text = config_h("PIHysteresis")
    >>> "#define MODEL_IDENTIFIER PIHysteresis" in text, "    vr_v = 10," in text
    (True, True)
    """
    check_fmi_version(fmi_version)
    spec = spec_of(name)
    rows = c_variables(name)
    if fmi_version == "3.0":
        rows.append((N_PLAYS.name, N_PLAYS.vr, N_PLAYS.kind, N_PLAYS.causality, 1,
                     N_PLAYS.storage))
    ident = (f'#define PIM_MODEL_TOKEN "{token(name)}"' if fmi_version == "3.0"
             else f'#define PIM_MODEL_GUID "{guid(name)}"')
    enum = ",\n".join(f"    vr_{r[0]} = {r[1]}" for r in sorted(rows, key=lambda r: r[1]))
    table = " \\\n".join(
        f'    X("{r[0]}", vr_{r[0]}, {_C_TYPES[r[2]]}, {_C_CAUSALITY[r[3]]}, '
        f'{_c_size(r, fmi_version)}, {r[5]})' for r in rows)
    lines = [
        f"/* config.h of the FMU unit {name} (FMI {fmi_version}), generated by",
        " * pimodel.fmu.spec.config_h from pimodel.fmu.spec: do not edit. */",
        "#ifndef PIM_CONFIG_H",
        "#define PIM_CONFIG_H",
        "",
        f"#define MODEL_IDENTIFIER {name}",
        f"#define PIM_MODEL {spec['id']} /* the unit (fmu/src/units/<unit>) */",
        f"#define PIM_FMI_MAJOR {fmi_version[0]}",
        ident,
    ]
    if "defaults" in spec:
        lines.append(f"#define PIM_MODEL_DEFAULTS(u) do {{ {spec['defaults']} }} while (0)")
    lines += ["", "typedef enum {", enum, "} ValueReference;", "",
              "/* X(name, value reference, type, causality, size, member of pim_unit) */",
              "#define PIM_UNIT_VARIABLES(X) \\", table, "", "#endif /* PIM_CONFIG_H */", ""]
    return "\n".join(lines)
