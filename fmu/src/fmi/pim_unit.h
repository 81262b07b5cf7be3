/*
 * The pimodel FMU units, independent of the FMI version: variables, modes, the parameter check,
 * one internal sample, the sub-stepping rule and the checked FMU state format.  Included (static
 * functions) by the FMI 2 and FMI 3 glue after PIM_MODEL (1 PIHysteresis, 2 RadiusEstimator,
 * 3 InversePI, 4 GeneralizedPI, 5 AsymmetricPI, 6 RateDependentPI, 7 CreepOperator,
 * 8 DiagnosedModel, 9 DiagnosedInverse) is defined.  Units 4-7 have a Boolean parameter `inverse`: false runs the operator (input u = v,
 * output y), true its exact inverse (input u = y_d, output y = v) with the same parameters,
 * started from the forward operator's initial state (as InversePI).  The numerics are the shared
 * C core (pim_pi.c, pim_estimator.c, pim_loops.c, pim_generalized.c, pim_asymmetric.c,
 * pim_rate_dependent.c, pim_creep.c, pim_diagnosed.c).  Unit 8 (DiagnosedModel) runs the model a
 * diagnosis chose (pim_diagnosed.h): signed play weights and the effect terms in parallel.  Unit 9
 * (DiagnosedInverse) runs its causal feedforward (pim_diag_inverse.h): input y_d, output v, the
 * static part's variables as unit 8's (same names and references), plus the prefilter sections
 * (n_sections, section), the post sections of a Wiener model's filter inverse (n_post_sections,
 * post_section), latency, delay_fraction and reference_range.  An optional PIM_MODEL_DEFAULTS(u) (defined by a
 * model-specific model.c, `pimodel fmu build --model`) sets the parameters' start values.
 * Functions return 0 on success, or -1 with the reason in u->msg.
 *
 * RadiusEstimator: Integer parameter `law` (PIM_LAW_DATA 0, the default, or PIM_LAW_PAPER 1,
 * pim_estimator.h) and Integer output `health`, the bit mask of the checks of pim_est_health.h
 * on the samples processed so far (0 before the first one), evaluated after every doStep; the
 * glue logs the report in words (unit_health_report) once at terminate when it is not 0.
 *
 * Sampling rule: internal sample k (an int64 counter) happens at time k*Ts.  A step from t over
 * h processes every sample with k*Ts in [t, t+h) (tolerance 1e-9*Ts), each with the inputs set
 * before the call (held over the step); outputs are those of the last processed sample and hold
 * between samples.  A step shorter than Ts that contains no sample instant changes nothing.
 *
 * Limits (each breach is an error with a logged reason, never a crash or a hang):
 *   n in 1..PIM_NMAX (64) plays (DiagnosedModel: 1..128); Ts finite and >= PIM_TS_MIN; start time finite and >= 0;
 *   at most PIM_MAX_SUBSTEPS (10^7) samples per doStep; sample index (t+h)/Ts below
 *   PIM_MAX_SAMPLE_INDEX (2^52, where k*Ts is still exact in double); doStep needs
 *   t == the FMU's time (the end of the last step) within min(1e-9 max(1, |t|), 1e-3 Ts),
 *   h finite and > 0, and t + h > t.
 *
 * Value references: the enum ValueReference and, per unit, the table unit_vars (name, reference,
 * type, causality, size) are the one source of truth in C; tests/test_fmu3.py holds every
 * built modelDescription.xml (FMI 2 and 3) equal to unit_vars.  In FMI 2 array element
 * p[i+1] has reference 100 + i (r 200 + i, r_hat 300 + i; DiagnosedModel: w0 400 + i,
 * creep_gain 500 + i, creep_tau 600 + i, rate_band_gain 700 + i (per play the gain of its
 * rate band; the rate term is on when one is non-zero), lti_b 800 + i,
 * lti_a 900 + i, and for plays 65..128 p_hi 1000 + i, r_hi 1100 + i, w0_hi 1200 + i,
 * rate_band_gain_hi 1300 + i; the linear part's further elements lti_gain 1400 + i,
 * lti_element_b 1500 + i, lti_element_a 1600 + i; a Wiener model's filter before the plays
 * wiener_element_b 1700 + i, wiener_element_a 1800 + i; DiagnosedInverse: the prefilter's
 * sections section 1900 + i, the post sections post_section 2000 + i); in FMI 3 an array is
 * one variable.
 */
#ifndef PIM_UNIT_H
#define PIM_UNIT_H

#include <math.h>
#include <stddef.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pim_asymmetric.h"
#include "pim_core.h"
#include "pim_creep.h"
#include "pim_diag_inverse.h"
#include "pim_diagnosed.h"
#include "pim_est_health.h"
#include "pim_estimator.h"
#include "pim_generalized.h"
#include "pim_loops.h"
#include "pim_rate_dependent.h"

#include "config.h" /* generated: MODEL_IDENTIFIER, PIM_MODEL, ValueReference, PIM_UNIT_VARIABLES */

#if !defined(PIM_MODEL) || PIM_MODEL < 1 || PIM_MODEL > 9
#error "define PIM_MODEL (1 PIHysteresis, 2 RadiusEstimator, 3 InversePI, 4 GeneralizedPI, \
5 AsymmetricPI, 6 RateDependentPI, 7 CreepOperator, 8 DiagnosedModel, 9 DiagnosedInverse)"
#endif
#define PIM_HAS_INVERSE_FLAG (PIM_MODEL >= 4 && PIM_MODEL <= 7)
#define PIM_DIAG_UNIT (PIM_MODEL == 8 || PIM_MODEL == 9) /* the diagnosed model's units */

#define PIM_NMAX PIM_MAX_PLAYS            /* declared array size: p[1..64], r[..], r_hat[..] */
#define NMAX PIM_NMAX
#if PIM_DIAG_UNIT
#define PIM_UNIT_NMAX PIM_DIAG_MAX_PLAYS  /* plays 1..64 in p, r, ...; 65..128 in p_hi, r_hi, ... */
#else
#define PIM_UNIT_NMAX PIM_NMAX            /* largest n */
#endif


typedef enum { PIM_PARAMETER, PIM_INPUT, PIM_OUTPUT, PIM_INDEPENDENT } pim_causality;

typedef struct {
    const char *name;
    unsigned vr;
    char type; /* 'R' Real/Float64, 'I' Integer/Int32, 'B' Boolean */
    pim_causality causality;
    int size;      /* 1, or PIM_NMAX for an array */
    size_t offset; /* of the value(s) in pim_unit */
} pim_var;


/* Life cycle (FMI 2 and 3 Co-Simulation): instantiated -> initialization mode -> step mode
 * (after a successful exitInitializationMode) -> terminated; reset goes back to instantiated. */
enum { PIM_INSTANTIATED = 1, PIM_INIT_MODE, PIM_STEP_MODE, PIM_TERMINATED };

typedef struct {
    /* parameters */
    double Ts, z0, gain, guard;
    int n, adaptive, linear_play, slope_window;
    double p[PIM_NMAX], r[PIM_NMAX];
    /* inputs and outputs */
    double in1, in2, out1, out2;
    double rhat_in[PIM_NMAX], rhat_out[PIM_NMAX];
    /* mode, time and sample counter */
    int mode;
    double time;    /* the end of the last communication step (the start time before any) */
    int64_t k_next; /* index of the next sample to process */
    /* states */
    double z[PIM_MAX_PLAYS];
    double pinv[PIM_MAX_PLAYS], rinv[PIM_MAX_PLAYS];
    pim_estimator est;
    /* parameters of units 4-7 (GeneralizedPI, AsymmetricPI, RateDependentPI, CreepOperator;
     * the creep's gains c and time constants tau are stored in p and r) */
    int inverse, kind_in, kind_out;
    double c_in[4], c_out[4];
    double p0, a_l, d_l, a_r, d_r;
    double rate_gain, rate_tc, v0;
    /* derived from the parameters (recomputed, never read from an FMU state) */
    double lam, a[PIM_NMAX];
    pim_asym asym;
    /* rate-dependent state: v[k-1], rate[k] */
    double hist[2];
    /* RadiusEstimator: law (PIM_LAW_DATA 0, PIM_LAW_PAPER 1, a parameter) and the health bit
     * mask of the estimate so far (an output, 0 before the first sample) */
    int law, health;
#if PIM_MODEL == 2
    pim_est_health est_health; /* rows v[k], rhat[k], y[k], e[k] of the samples processed */
#elif PIM_DIAG_UNIT
    /* DiagnosedModel parameters (pim_diagnosed.h; weights w of plays 1..64 in p, radii in r,
     * plays 65..128 in p_hi, r_hi, w0_hi, rate_band_gain_hi; the creep poles exp(-Ts /
     * creep_tau) derived into a), the plays' arrays joined (derived) and the flat state */
    double w0[PIM_NMAX], creep_gain[PIM_NMAX], creep_tau[PIM_NMAX], rate_band_gain[PIM_NMAX];
    double lti_b[PIM_NMAX], lti_a[PIM_NMAX];
    double p_hi[PIM_NMAX], r_hi[PIM_NMAX], w0_hi[PIM_NMAX], rate_band_gain_hi[PIM_NMAX];
    double dw[PIM_DIAG_MAX_PLAYS], dr[PIM_DIAG_MAX_PLAYS], dw0[PIM_DIAG_MAX_PLAYS],
        drb[PIM_DIAG_MAX_PLAYS];
    double offset, reference_offset, asym_q, asym_c3, center, half_range, rate_scale,
        input_range, drift_per_s, delay_samples;
    int n_lags, lti_order, drift_clock, rate_family;
    double rate_tau;
    /* the linear part's further elements (pim_diagnosed.h): n_lti_elements sections E_j with
     * gains lti_gain[j], and section 0 the base mode M_1 on h0, PIM_DIAG_SECTION coefficients
     * each in lti_element_b, lti_element_a */
    int n_lti_elements;
    double lti_gain[PIM_NMAX], lti_element_b[PIM_NMAX], lti_element_a[PIM_NMAX];
    /* a Wiener model's filter before the plays (pim_diagnosed.h): n_wiener_elements sections
     * F_j in series on v, PIM_DIAG_SECTION coefficients each in wiener_element_b, _a */
    int n_wiener_elements;
    double wiener_element_b[PIM_NMAX], wiener_element_a[PIM_NMAX];
    /* DiagnosedInverse (pim_diag_inverse.h): the root rule's scale, latency A, the delay's
     * fraction and the prefilter's sections (6 coefficients each: b0 b1 b2 a0 a1 a2) */
    double reference_range, delay_fraction;
    int latency, n_sections, n_post_sections;
    double section[PIM_NMAX], post_section[PIM_NMAX];
    double dstate[PIM_DIAG_STATE_MAX]; /* unit 8: pim_diag's state, unit 9: pim_dinv's */
#endif
    char msg[256]; /* reason of the last failure */
} pim_unit;

#define PIM_AT(field) offsetof(pim_unit, field)

/* The variables of the unit: the table PIM_UNIT_VARIABLES of config.h, generated from the
 * Python spec (pimodel.fmu.spec) like the model description; inputs and outputs first, as the
 * accessors scan it on every call. */
#define PIM_VAR_ROW(name, vr, type, causality, size, member) \
    {name, vr, type, causality, size, PIM_AT(member)},
static const pim_var unit_vars[] = {PIM_UNIT_VARIABLES(PIM_VAR_ROW)};
#undef PIM_VAR_ROW
#define PIM_NVARS (sizeof unit_vars / sizeof unit_vars[0])

/* The name of the variable stored at offset (e.g. the main input's, "v", "y_d" or "u"). */
static const char *unit_name_of(size_t offset)
{
    for (size_t i = 0; i < PIM_NVARS; ++i)
        if (unit_vars[i].offset == offset) return unit_vars[i].name;
    return "?";
}

static int unit_error(pim_unit *u, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(u->msg, sizeof u->msg, fmt, ap);
    va_end(ap);
    /* hosts may pass the message on as a format string: no '%' in it */
    for (char *q = u->msg; *q; ++q)
        if (*q == '%') *q = ' ';
    return -1;
}

static const char *unit_mode_name(int mode)
{
    switch (mode) {
    case PIM_INSTANTIATED: return "instantiated";
    case PIM_INIT_MODE: return "in initialization mode";
    case PIM_STEP_MODE: return "in step mode";
    case PIM_TERMINATED: return "terminated";
    default: return "in an unknown mode";
    }
}

/* 0 if the unit's mode is one of the bits in `allowed` (1 << mode), else -1 naming the call. */
static int unit_require_mode(pim_unit *u, unsigned allowed, const char *call)
{
    if (u->mode >= PIM_INSTANTIATED && u->mode <= PIM_TERMINATED && (allowed & (1u << u->mode)))
        return 0;
    return unit_error(u, "%s is not allowed now: the FMU is %s", call, unit_mode_name(u->mode));
}
#define PIM_IN(m) (1u << (m))

static void unit_defaults(pim_unit *u)
{
    memset(u, 0, sizeof *u);
    u->Ts = 1e-3;
    u->gain = 10.0;
    u->n = 1;
    u->slope_window = 8;
    u->mode = PIM_INSTANTIATED;
    for (int i = 0; i < PIM_NMAX; ++i) u->p[i] = 1.0;
    u->c_in[1] = u->c_out[1] = 1.0; /* identity envelopes */
    u->p0 = u->a_l = u->a_r = 1.0;
#if PIM_MODEL == 7
    for (int i = 0; i < PIM_NMAX; ++i) {
        u->p[i] = 0.05; /* creep gain c */
        u->r[i] = 1.0;  /* time constant tau [s] */
    }
#endif
#if PIM_DIAG_UNIT
    for (int i = 0; i < PIM_NMAX; ++i) {
        u->w0[i] = u->w0_hi[i] = u->p_hi[i] = 1.0;
        u->creep_tau[i] = 1.0;
    }
    u->lti_a[0] = 1.0; /* lti_order 0: no LTI */
    for (int j = 0; j <= PIM_DIAG_MAX_ELEMENTS; ++j) /* each section's a[0] = 1 */
        u->lti_element_a[PIM_DIAG_SECTION * j] = 1.0;
    for (int j = 0; j < PIM_DIAG_MAX_ELEMENTS; ++j)
        u->wiener_element_a[PIM_DIAG_SECTION * j] = 1.0;
    u->half_range = u->rate_scale = u->input_range = 1.0;
    for (int j = 0; j < PIM_DINV_FMU_SECTIONS; ++j) /* a0 = 1 */
        u->section[6 * j + 3] = u->post_section[6 * j + 3] = 1.0;
#endif
#ifdef PIM_MODEL_DEFAULTS
    PIM_MODEL_DEFAULTS(u);
#endif
}

/* Start time (setupExperiment / enterInitializationMode): finite and >= 0. */
static int unit_start(pim_unit *u, double t0, int stop_defined, double t_stop)
{
    if (!isfinite(t0) || t0 < 0.0)
        return unit_error(u, "start time = %g: must be finite and >= 0", t0);
    if (stop_defined && (!isfinite(t_stop) || t_stop < t0))
        return unit_error(u, "stop time = %g: must be finite and >= the start time %g", t_stop,
                          t0);
    u->time = t0;
    return 0;
}

#if PIM_MODEL == 4 || PIM_MODEL == 5
/* An envelope's kind (0..3, pim_generalized.h) and coefficients <prefix>_kind, <prefix>_c0.. */
static int unit_check_envelope(pim_unit *u, const char *prefix, int kind, const double *c)
{
    if (kind < PIM_ENV_POLY2 || kind > PIM_ENV_TANH_INV)
        return unit_error(u, "parameter %s_kind = %d out of range: 0 poly2, 1 tanh, 2 poly2_inv, "
                             "3 tanh_inv", prefix, kind);
    const char *msg = pim_envelope_check(kind, c);
    if (msg)
        return unit_error(u, "parameters %s_c0..%s_c3 = (%g, %g, %g, %g): %s", prefix, prefix,
                          c[0], c[1], c[2], c[3], msg);
    return 0;
}
#endif

/* The unit's own code (fmu/src/units/<unit>/unit.h: its parameter rules and helpers). */
#if PIM_DIAG_UNIT
#include "diag_static.h" /* units 8 and 9: the static part's rules */
#endif
#include "unit.h"


/* Quantities derived from checked parameters (inverse PI, envelope struct, rate filter, creep
 * poles); at setup and for every restored FMU state.  0, or -1 with the reason. */
static int unit_derive(pim_unit *u)
{
    const size_t n = (size_t)u->n;
#if PIM_MODEL == 3
    if (!u->adaptive && pim_pi_inverse(n, u->p, u->r, NULL, u->pinv, u->rinv, NULL) != 0)
        return unit_error(u, "bad parameters: not invertible (r[1] must be 0 with a positive "
                             "weight p[1])");
#elif PIM_MODEL == 4
    if (u->inverse && pim_pi_inverse(n, u->p, u->r, NULL, u->pinv, u->rinv, NULL) != 0)
        return unit_error(u, "bad parameters: not invertible (r[1] must be 0)");
#elif PIM_MODEL == 5
    const pim_asym a = {u->p0, u->a_l, u->d_l, u->a_r, u->d_r, u->kind_in,
                        {u->c_in[0], u->c_in[1], u->c_in[2], u->c_in[3]}, u->kind_in ^ 2};
    u->asym = a;
#elif PIM_MODEL == 6
    u->lam = u->rate_tc > 0.0 ? exp(-u->Ts / u->rate_tc) : 0.0;
#elif PIM_MODEL == 7
    for (size_t i = 0; i < n; ++i) u->a[i] = exp(-u->Ts / u->r[i]);
#elif PIM_DIAG_UNIT
    for (int j = 0; j < u->n_lags; ++j) u->a[j] = exp(-u->Ts / u->creep_tau[j]);
    unit_diag_join(u);
#endif
    (void)n;
    return 0;
}

/* The parameter rules, shared by initialization and by every FMU state that is restored. */
static int unit_check_parameters(pim_unit *u)
{
    if (u->n < 1 || u->n > PIM_UNIT_NMAX)
        return unit_error(u, "parameter n = %d out of range: 1 <= n <= %d", u->n, PIM_UNIT_NMAX);
    if (!isfinite(u->Ts) || !(u->Ts >= PIM_TS_MIN))
        return unit_error(u, "parameter Ts = %g: the sample time must be > 0 (finite, >= %g)",
                          u->Ts, PIM_TS_MIN);
    if (!isfinite(u->z0)) return unit_error(u, "parameter z0 = %g: must be finite", u->z0);
#if PIM_HAS_INVERSE_FLAG
    if (u->inverse != 0 && u->inverse != 1)
        return unit_error(u, "parameter inverse = %d: must be a Boolean", u->inverse);
#endif
#if PIM_MODEL == 7
    return unit_check_creep(u);
#elif PIM_MODEL == 8
    return unit_check_diag(u);
#elif PIM_MODEL == 9
    return unit_check_dinv(u);
#else
    for (int i = 0; i < u->n; ++i) {
#if PIM_MODEL == 5
        if (!isfinite(u->p[i]))
            return unit_error(u, "weight p[%d] = %g is not finite", i + 1, u->p[i]);
        if (u->p[i] < 0.0)
            return unit_error(u, "weight p[%d] = %g is negative (weights must be >= 0)", i + 1,
                              u->p[i]);
#else
        if (!isfinite(u->p[i]))
            return unit_error(u, "weight p[%d] = %g is not finite", i + 1, u->p[i]);
        if (!(u->p[i] > 0.0))
            return unit_error(u, "weight p[%d] = %g is not positive (weights must be > 0)",
                              i + 1, u->p[i]);
#endif
        if (!isfinite(u->r[i]))
            return unit_error(u, "radius r[%d] = %g is not finite", i + 1, u->r[i]);
        if (u->r[i] < 0.0)
            return unit_error(u, "radius r[%d] = %g is negative (radii must be >= 0)", i + 1,
                              u->r[i]);
        if (i > 0 && u->r[i] < u->r[i - 1])
            return unit_error(u, "radii not sorted: r[%d] = %g < r[%d] = %g (need r[1] <= ... "
                                 "<= r[n])", i + 1, u->r[i], i, u->r[i - 1]);
    }
#if PIM_MODEL != 5
    const char *msg = pim_pi_check((size_t)u->n, u->p, u->r, 0);
    if (msg) return unit_error(u, "bad parameters: %s", msg);
#endif
#if PIM_MODEL == 2
    if (!(u->gain >= 0.0) || !isfinite(u->gain))
        return unit_error(u, "parameter gain = %g: must be finite and >= 0", u->gain);
    if (!(u->guard >= 0.0) || !isfinite(u->guard))
        return unit_error(u, "parameter guard = %g: must be finite and >= 0", u->guard);
    if (u->slope_window < 0 || u->slope_window >= PIM_EST_WIN)
        return unit_error(u, "parameter slope_window = %d out of range: 0 <= slope_window <= %d",
                          u->slope_window, PIM_EST_WIN - 1);
    if (u->linear_play != 0 && u->linear_play != 1)
        return unit_error(u, "parameter linear_play = %d: must be a Boolean", u->linear_play);
    if (u->law != PIM_LAW_DATA && u->law != PIM_LAW_PAPER)
        return unit_error(u, "parameter law = %d out of range: 0 data (principal case from the "
                             "measured branches, default), 1 paper (from the estimate)", u->law);
#elif PIM_MODEL == 3
    if (u->adaptive != 0 && u->adaptive != 1)
        return unit_error(u, "parameter adaptive = %d: must be a Boolean", u->adaptive);
    if (!u->adaptive && u->r[0] != 0.0)
        return unit_error(u, "bad parameters: not invertible (r[1] = %g must be 0 with a "
                             "positive weight p[1])", u->r[0]);
#elif PIM_MODEL == 4
    if (unit_check_envelope(u, "in", u->kind_in, u->c_in) != 0 ||
        unit_check_envelope(u, "out", u->kind_out, u->c_out) != 0)
        return -1;
    if (u->inverse && u->r[0] != 0.0)
        return unit_error(u, "bad parameters: inverse = true needs a linear play (r[1] = %g "
                             "must be 0)", u->r[0]);
#elif PIM_MODEL == 5
    if (!isfinite(u->p0) || !(u->p0 > 0.0))
        return unit_error(u, "parameter p0 = %g: the direct weight must be finite and > 0",
                          u->p0);
    if (!isfinite(u->a_l) || !(u->a_l > 0.0))
        return unit_error(u, "parameter a_l = %g: the ascending slope must be finite and > 0",
                          u->a_l);
    if (!isfinite(u->a_r) || !(u->a_r > 0.0))
        return unit_error(u, "parameter a_r = %g: the descending slope must be finite and > 0",
                          u->a_r);
    if (!isfinite(u->d_l)) return unit_error(u, "parameter d_l = %g: must be finite", u->d_l);
    if (!isfinite(u->d_r)) return unit_error(u, "parameter d_r = %g: must be finite", u->d_r);
    if (unit_check_envelope(u, "shape", u->kind_in, u->c_in) != 0) return -1;
#elif PIM_MODEL == 6
    if (!isfinite(u->rate_gain) || u->rate_gain < 0.0)
        return unit_error(u, "parameter rate_gain = %g: must be finite and >= 0", u->rate_gain);
    if (!isfinite(u->rate_tc) || u->rate_tc < 0.0)
        return unit_error(u, "parameter rate_time_constant = %g: must be finite and >= 0",
                          u->rate_tc);
    if (!isfinite(u->v0)) return unit_error(u, "parameter v0 = %g: must be finite", u->v0);
    if (u->inverse && u->r[0] != 0.0)
        return unit_error(u, "bad parameters: inverse = true needs a linear play (r[1] = %g "
                             "must be 0)", u->r[0]);
#endif
    return 0;
#endif /* PIM_MODEL != 7, 8, 9 */
}


/* Index of the first sample at or after time t. */
static double unit_first_sample(const pim_unit *u, double t)
{
    return ceil(t / u->Ts - PIM_SAMPLE_TOL);
}

/* Checks the parameters and sets up the states (exitInitializationMode). */
static int unit_setup(pim_unit *u)
{
    if (unit_check_parameters(u) != 0) return -1;
    const double k0 = unit_first_sample(u, u->time);
    if (!(k0 < PIM_MAX_SAMPLE_INDEX))
        return unit_error(u, "start time %g is beyond the sample counter's range (2^52 samples "
                             "of Ts = %g)", u->time, u->Ts);
    u->k_next = (int64_t)k0;
    const size_t n = (size_t)u->n;
#if PIM_MODEL == 2
    if (unit_init_estimator(u, &u->est) != 0) return -1;
    for (size_t i = 0; i < n; ++i) u->rhat_out[i] = u->est.rhat[i];
    (void)pim_health_init(&u->est_health, n, 1);
    u->health = 0;
#elif PIM_MODEL == 8
    memset(u->dstate, 0, sizeof u->dstate); /* not started; plays (and a prefilter's) at z0 */
    {
        pim_diag d;
        unit_diag(u, &d);
        pim_diag_initial_state(&d, u->dstate, u->z0);
    }
    (void)n;
#elif PIM_MODEL == 9
    memset(u->dstate, 0, sizeof u->dstate); /* not started; plays (and the rate source's) at z0 */
    {
        double z0[PIM_DINV_MAX_PLAYS];
        for (size_t i = 0; i < n; ++i) z0[i] = u->z0;
        pim_dinv d;
        unit_diag_join(u); /* the joined arrays for d (unit_derive below recomputes them) */
        unit_dinv(u, &d);
        pim_dinv_initial_state(&d, u->dstate, z0);
    }
#else
    for (size_t i = 0; i < n; ++i) u->z[i] = u->z0;
#endif
    if (unit_derive(u) != 0) return -1;
#if PIM_MODEL == 3 || PIM_MODEL == 4
#if PIM_MODEL == 3
    const int inverse_pi = !u->adaptive;
#else
    const int inverse_pi = u->inverse;
#endif
    if (inverse_pi) { /* the inverse's play states consistent with the forward ones */
        double zinv[PIM_MAX_PLAYS], pinv[PIM_MAX_PLAYS], rinv[PIM_MAX_PLAYS];
        if (pim_pi_inverse(n, u->p, u->r, u->z, pinv, rinv, zinv) != 0)
            return unit_error(u, "bad parameters: not invertible (r[1] must be 0 with a "
                                 "positive weight p[1])");
        memcpy(u->z, zinv, n * sizeof(double));
    }
#elif PIM_MODEL == 6
    u->hist[0] = u->v0;
    u->hist[1] = 0.0;
#endif
    return 0;
}

/* The inputs held over a step: finite (and admissible radii for the adaptive inverse). */
static int unit_check_inputs(pim_unit *u)
{
    if (!isfinite(u->in1))
        return unit_error(u, "input %s = %g is not finite (NaN or Inf)",
                          unit_name_of(PIM_AT(in1)), u->in1);
#if PIM_MODEL == 2
    if (!isfinite(u->in2)) return unit_error(u, "input y = %g is not finite (NaN or Inf)", u->in2);
#elif PIM_MODEL == 3
    if (u->adaptive) {
        for (int i = 0; i < u->n; ++i) {
            const double x = u->rhat_in[i];
            if (!isfinite(x) || x < 0.0 || (i > 0 && x < u->rhat_in[i - 1]))
                return unit_error(u, "input r_hat[%d] = %g: radii must be finite, >= 0 and "
                                     "sorted", i + 1, x);
        }
        if (u->rhat_in[0] != 0.0)
            return unit_error(u, "input r_hat[1] = %g: not invertible (r_hat[1] must be 0)",
                              u->rhat_in[0]);
    }
#endif
    return 0;
}

/* One internal sample at the held inputs (checked by unit_check_inputs). */
static void unit_sample(pim_unit *u)
{
    const size_t n = (size_t)u->n;
#if PIM_MODEL == 1
    u->out1 = pim_pi_step(n, u->p, u->r, u->z, u->in1);
#elif PIM_MODEL == 2
    double yh, e, ed, rhat[PIM_MAX_PLAYS];
    memcpy(rhat, u->est.rhat, n * sizeof(double)); /* rhat[k], the estimate used at k */
    (void)pim_est_step(&u->est, u->in1, u->in2, NULL, &yh, &e, &ed);
    pim_health_add(&u->est_health, 1, &u->in1, rhat, &u->in2, &e);
    u->out1 = yh;
    u->out2 = e;
    for (size_t i = 0; i < n; ++i) u->rhat_out[i] = u->est.rhat[i];
#elif PIM_MODEL == 3
    if (u->adaptive)
        u->out1 = pim_adaptive_inverse_step(n, u->p, u->rhat_in, u->z, u->in1);
    else
        u->out1 = pim_pi_step(n, u->pinv, u->rinv, u->z, u->in1);
#elif PIM_MODEL == 4
    /* the inverse envelope kinds: kind ^ 2 (poly2 <-> poly2_inv, tanh <-> tanh_inv) */
    if (u->inverse)
        (void)pim_gpi_run(1, n, u->pinv, u->rinv, u->z, u->kind_out ^ 2, u->c_out,
                          u->kind_in ^ 2, u->c_in, &u->in1, &u->out1);
    else
        (void)pim_gpi_run(1, n, u->p, u->r, u->z, u->kind_in, u->c_in, u->kind_out, u->c_out,
                          &u->in1, &u->out1);
#elif PIM_MODEL == 5
    if (u->inverse)
        (void)pim_asym_inverse_run(&u->asym, 1, n, u->p, u->r, u->z, &u->in1, &u->out1);
    else
        (void)pim_asym_run(&u->asym, 1, n, u->p, u->r, u->z, &u->in1, &u->out1);
#elif PIM_MODEL == 6
    if (u->inverse)
        (void)pim_rdpi_inverse_run(1, n, u->p, u->r, u->rate_gain, u->lam, u->Ts, u->z, u->hist,
                                   &u->in1, &u->out1);
    else
        pim_rdpi_run(1, n, u->p, u->r, u->rate_gain, u->lam, u->Ts, u->z, u->hist, &u->in1,
                     &u->out1);
#elif PIM_MODEL == 7
    if (u->inverse)
        pim_creep_inverse_run(1, n, u->a, u->p, u->z, &u->in1, &u->out1);
    else
        pim_creep_run(1, n, u->a, u->p, u->z, &u->in1, &u->out1);
#elif PIM_MODEL == 8
    pim_diag d;
    unit_diag(u, &d);
    u->out1 = pim_diag_step(&d, u->dstate, u->in1, (double)u->k_next * u->Ts);
    (void)n;
#else
    pim_dinv d;
    unit_dinv(u, &d);
    u->out1 = pim_dinv_step(&d, u->dstate, u->in1);
    (void)n;
#endif
}

/* Whether the outputs (and the estimator's radii) are finite. */
static int unit_outputs_finite(const pim_unit *u)
{
    if (!isfinite(u->out1) || !isfinite(u->out2)) return 0;
#if PIM_MODEL == 2
    for (int i = 0; i < u->n; ++i)
        if (!isfinite(u->rhat_out[i])) return 0;
#endif
    return 1;
}

#if PIM_DIAG_UNIT
/* Length of the flat state in dstate (unit 8: pim_diag's, unit 9: pim_dinv's). */
static size_t unit_flat_state_size(const pim_unit *u)
{
#if PIM_MODEL == 8
    pim_diag d;
    unit_diag(u, &d);
    return pim_diag_state_size(&d);
#else
    pim_dinv d;
    unit_dinv(u, &d);
    return pim_dinv_state_size(&d);
#endif
}
#endif

/* doStep(t, h): processes the samples k*Ts in [t, t+h) (the sampling rule above). */
static int unit_do_step(pim_unit *u, double t, double h)
{
    if (u->mode != PIM_STEP_MODE) return unit_require_mode(u, PIM_IN(PIM_STEP_MODE), "doStep");
    if (!isfinite(t) || t < 0.0)
        return unit_error(u, "communication point t = %g: must be finite and >= 0", t);
    if (!isfinite(h) || !(h > 0.0))
        return unit_error(u, "communication step size h = %g: must be finite and > 0", h);
    const double scale = fabs(u->time) > 1.0 ? fabs(u->time) : 1.0;
    const double tol = 1e-9 * scale < 1e-3 * u->Ts ? 1e-9 * scale : 1e-3 * u->Ts;
    if (t != u->time && fabs(t - u->time) > tol)
        return unit_error(u, "communication point t = %.17g does not match the FMU's time "
                             "%.17g (the end of the last step)", t, u->time);
    const double t_end = t + h;
    if (!(t_end > t))
        return unit_error(u, "no progress: t + h == t at t = %g, h = %g (h is below the time "
                             "resolution at t)", t, h);
    const double k_end = unit_first_sample(u, t_end);
    if (!(k_end < PIM_MAX_SAMPLE_INDEX))
        return unit_error(u, "time t + h = %g is beyond the sample counter's range (2^52 "
                             "samples of Ts = %g)", t_end, u->Ts);
    const int64_t k1 = (int64_t)k_end;
    if (k1 - u->k_next > PIM_MAX_SUBSTEPS)
        return unit_error(u, "step h = %g spans %lld samples of Ts = %g; at most %lld per doStep "
                             "(use shorter communication steps)", h,
                          (long long)(k1 - u->k_next), u->Ts, PIM_MAX_SUBSTEPS);
    if (k1 <= u->k_next) {
        u->time = t_end;
        return 0;
    }
    if (unit_check_inputs(u) != 0) return -1;
    /* a step that overflows is not taken: the states it changes are restored */
    const int64_t k_saved = u->k_next;
    const double out_saved[2] = {u->out1, u->out2};
#if PIM_MODEL == 2
    const pim_estimator est_saved = u->est;
    const pim_est_health health_saved = u->est_health;
#elif !PIM_DIAG_UNIT
    double z_saved[PIM_MAX_PLAYS];
    for (int i = 0; i < u->n; ++i) z_saved[i] = u->z[i];
    const double hist_saved[2] = {u->hist[0], u->hist[1]};
#else
    const size_t dsize = unit_flat_state_size(u);
    double dsaved[PIM_DIAG_STATE_MAX];
    memcpy(dsaved, u->dstate, dsize * sizeof(double));
#endif
    for (; u->k_next < k1; ++u->k_next) {
        unit_sample(u);
        if (!unit_outputs_finite(u)) {
            const double y1 = u->out1, y2 = u->out2;
            u->k_next = k_saved;
            u->out1 = out_saved[0];
            u->out2 = out_saved[1];
#if PIM_MODEL == 2
            u->est = est_saved;
            u->est_health = health_saved;
            for (int i = 0; i < u->n; ++i) u->rhat_out[i] = u->est.rhat[i];
#elif !PIM_DIAG_UNIT
            memcpy(u->z, z_saved, (size_t)u->n * sizeof(double));
            u->hist[0] = hist_saved[0];
            u->hist[1] = hist_saved[1];
#else
            memcpy(u->dstate, dsaved, dsize * sizeof(double));
#endif
            return unit_error(u, "the outputs overflowed or are undefined (%g, %g) at sample "
                                 "%lld with the inputs held over this step (an input beyond an "
                                 "envelope's domain or range, or a numeric overflow); the step "
                                 "was not taken", y1, y2,
                              (long long)u->k_next);
        }
    }
#if PIM_MODEL == 2
    u->health = unit_health(u, NULL, NULL, NULL, NULL, NULL);
#endif
    u->time = t_end;
    return 0;
}

/* ---- variables by value reference --------------------------------------------------------- */

/* The variable with reference vr, or NULL.  With elements (FMI 2) an array is addressed by
 * element (reference base + i, *elem = i); without (FMI 3) as a whole (*elem = -1). */
static const pim_var *unit_var(unsigned vr, int elements, int *elem)
{
    for (size_t i = 0; i < PIM_NVARS; ++i) {
        const pim_var *v = &unit_vars[i];
        if (v->size > 1 && elements) { /* FMI 2 array elements: v->vr + 0 .. v->vr + size - 1 */
            if (vr < v->vr || vr - v->vr >= (unsigned)v->size) continue;
            *elem = (int)(vr - v->vr);
        } else {
            if (vr != v->vr) continue;
            if (elements && v->causality == PIM_INDEPENDENT) return NULL; /* FMI 2: no time */
            *elem = -1;
        }
        return v;
    }
    return NULL;
}

/* "p[3]" or "Ts" into buf. */
static const char *unit_label(const pim_var *v, int elem, char *buf, size_t size)
{
    if (elem >= 0)
        snprintf(buf, size, "%s[%d]", v->name, elem + 1);
    else
        snprintf(buf, size, "%s", v->name);
    return buf;
}

/* Whether variable v may be set now: parameters before initialization, inputs until
 * terminate, never outputs or time. */
static int unit_settable(const pim_unit *u, const pim_var *v)
{
    if (v->causality == PIM_OUTPUT || v->causality == PIM_INDEPENDENT) return 0;
    if (v->causality == PIM_PARAMETER)
        return u->mode == PIM_INSTANTIATED || u->mode == PIM_INIT_MODE;
    return u->mode != PIM_TERMINATED;
}

/* Error paths out of line, so that the accessors stay small (they run on every get/set). */
#if defined(__GNUC__)
#define PIM_COLD __attribute__((noinline, cold))
#else
#define PIM_COLD
#endif

/* The reason why unit_ref refused vr (v: its variable or NULL), into u->msg; returns NULL. */
PIM_COLD static void *unit_ref_refused(pim_unit *u, const pim_var *v, int elem, unsigned vr, char type)
{
    const char *tname = type == 'R' ? "Real" : type == 'I' ? "Integer" : "Boolean";
    char name[40];
    if (!v)
        unit_error(u, "no %s variable with value reference %u in the model description", tname,
                   vr);
    else if (v->type != type)
        unit_error(u, "variable %s (value reference %u) is not a %s",
                   unit_label(v, elem, name, sizeof name), vr, tname);
    else if (v->causality == PIM_OUTPUT || v->causality == PIM_INDEPENDENT)
        unit_error(u, "variable %s (value reference %u) is %s and cannot be set",
                   unit_label(v, elem, name, sizeof name), vr,
                   v->causality == PIM_OUTPUT ? "an output" : "the independent variable");
    else if (v->causality == PIM_PARAMETER)
        unit_error(u, "cannot set parameter %s (value reference %u) after initialization",
                   unit_label(v, elem, name, sizeof name), vr);
    else
        unit_error(u, "cannot set input %s (value reference %u) after terminate",
                   unit_label(v, elem, name, sizeof name), vr);
    return NULL;
}

/*
 * Storage of the variable with reference vr, checked against the model description (exists,
 * has type `type`) and, for set != 0, against the mode (unit_settable).  *count: values it
 * holds (1, or PIM_NMAX for an FMI 3 array).  NULL with the reason in u->msg on failure.
 */
static void *unit_ref(pim_unit *u, unsigned vr, char type, int elements, int set, size_t *count)
{
    int elem = -1;
    const pim_var *v = unit_var(vr, elements, &elem);
    if (!v || v->type != type || (set && !unit_settable(u, v)))
        return unit_ref_refused(u, v, elem, vr, type);
    *count = elem >= 0 ? 1 : (size_t)v->size;
    return (char *)u + v->offset + (elem > 0 ? (size_t)elem * sizeof(double) : 0);
}

/* ---- FMU state: a checked, versioned byte format ------------------------------------------ */

/*
 * Layout (native byte order), PIM_STATE_SIZE bytes:
 *   header  magic "PIMSTATE", format version, byte-order mark 0x01020304, unit (PIM_MODEL),
 *           FMI major version, PIM_NMAX, PIM_EST_WIN, sizeof(pim_unit), sizeof(pim_estimator),
 *           GUID / instantiation token (64 bytes, NUL padded)
 *   payload the pim_unit struct (parameters, inputs, outputs, mode, time, counter, states)
 *   check   FNV-1a 64 of header and payload
 * Loading checks every header field, the checksum, the mode, time and counter, every parameter
 * (unit_check_parameters, as at initialization) and that every state is finite; derived
 * quantities (inverse parameters, estimator settings, r_hat outputs) are recomputed, not read.
 * The in-memory FMU state (get/set) is the same byte block, checked again when set.
 */
#define PIM_STATE_MAGIC "PIMSTATE"
#define PIM_STATE_VERSION 5u /* 2: units 4-7 fields; 3: law, health; 4: DiagnosedModel
                                prefilter (Wiener); 5: DiagnosedInverse fields, post sections */
#define PIM_STATE_TOKEN 64

typedef struct {
    char magic[8];
    uint32_t version, byte_order, model, fmi, nmax, est_win;
    uint64_t unit_size, est_size;
    char token[PIM_STATE_TOKEN];
} pim_state_header;

#define PIM_STATE_SIZE (sizeof(pim_state_header) + sizeof(pim_unit) + sizeof(uint64_t))

static uint64_t unit_fnv1a(const unsigned char *b, size_t n)
{
    uint64_t h = 0xcbf29ce484222325ULL;
    for (size_t i = 0; i < n; ++i) {
        h ^= b[i];
        h *= 0x100000001b3ULL;
    }
    return h;
}

static void unit_state_header(pim_state_header *h, const char *token, unsigned fmi)
{
    memset(h, 0, sizeof *h);
    memcpy(h->magic, PIM_STATE_MAGIC, 8);
    h->version = PIM_STATE_VERSION;
    h->byte_order = 0x01020304u;
    h->model = PIM_MODEL;
    h->fmi = fmi;
    h->nmax = PIM_NMAX;
    h->est_win = PIM_EST_WIN;
    h->unit_size = sizeof(pim_unit);
    h->est_size = sizeof(pim_estimator);
    snprintf(h->token, sizeof h->token, "%s", token);
}

/* Writes the unit's state into buf (PIM_STATE_SIZE bytes). */
static void unit_state_write(const pim_unit *u, unsigned char *buf, const char *token,
                             unsigned fmi)
{
    pim_state_header h;
    unit_state_header(&h, token, fmi);
    memcpy(buf, &h, sizeof h);
    memcpy(buf + sizeof h, u, sizeof *u);
    const uint64_t sum = unit_fnv1a(buf, sizeof h + sizeof *u);
    memcpy(buf + sizeof h + sizeof *u, &sum, sizeof sum);
}

#if PIM_MODEL != 2
static int unit_all_finite(const double *x, size_t n)
{
    for (size_t i = 0; i < n; ++i)
        if (!isfinite(x[i])) return 0;
    return 1;
}
#endif

/* Checks the states of a loaded unit s (parameters already checked) and recomputes what derives
 * from the parameters; on failure the reason goes to u->msg. */
static int unit_check_states(pim_unit *u, pim_unit *s)
{
    const size_t n = (size_t)s->n;
    const double k = unit_first_sample(s, s->time);
    if (!(k < PIM_MAX_SAMPLE_INDEX) || s->k_next != (int64_t)k)
        return unit_error(u, "FMU state rejected: sample counter %lld does not match time %g "
                             "and Ts = %g", (long long)s->k_next, s->time, s->Ts);
#if PIM_MODEL == 2
    if (s->est.n != n)
        return unit_error(u, "FMU state rejected: estimator has n = %llu plays, the unit %d",
                          (unsigned long long)s->est.n, s->n);
    double flat[PIM_EST_STATE_SIZE(PIM_MAX_PLAYS)];
    pim_est_get_state(&s->est, flat);
    pim_estimator fresh;
    if (unit_init_estimator(s, &fresh) != 0) return unit_error(u, "FMU state rejected: %s",
                                                               s->msg);
    const char *msg = pim_est_set_state(&fresh, flat);
    if (msg) return unit_error(u, "FMU state rejected: estimator %s", msg);
    s->est = fresh;
    for (size_t i = 0; i < n; ++i) s->rhat_out[i] = s->est.rhat[i];
    msg = pim_health_check(&s->est_health, n);
    if (msg) return unit_error(u, "FMU state rejected: %s", msg);
    s->health = s->est_health.count > 0.0 ? unit_health(s, NULL, NULL, NULL, NULL, NULL) : 0;
#elif !PIM_DIAG_UNIT
    if (!unit_all_finite(s->z, n))
        return unit_error(u, "FMU state rejected: a play state z is not finite");
#endif
#if PIM_MODEL == 8
    (void)n; /* the plays' states are in dstate */
    {
        pim_diag d;
        unit_diag(s, &d);
        const size_t size = pim_diag_state_size(&d), nbuf = pim_diag_delay_length(d.delay);
        const double *x = s->dstate;
        if (!unit_all_finite(x, size))
            return unit_error(u, "FMU state rejected: a model state is not finite");
        if ((x[0] != 0.0 && x[0] != 1.0) || x[3] < 0.0 || x[3] != floor(x[3]) ||
            (nbuf ? x[3] >= (double)nbuf : x[3] != 0.0))
            return unit_error(u, "FMU state rejected: model state started = %g, head = %g "
                                 "(expected 0 or 1, and 0 <= head < %llu)", x[0], x[3],
                              (unsigned long long)(nbuf ? nbuf : 1));
        if (pim_diag_rate_size(&d) && x[PIM_DIAG_HEADER + d.n] < 0.0)
            return unit_error(u, "FMU state rejected: the filtered rate rho_f = %g must be "
                                 ">= 0", x[PIM_DIAG_HEADER + d.n]);
    }
#endif
#if PIM_MODEL == 9
    (void)n; /* the plays' states are in dstate */
    {
        pim_dinv d;
        unit_diag_join(s);
        unit_dinv(s, &d);
        const double *x = s->dstate, *solver = x + PIM_DINV_HEAD + 2 * d.ns;
        if (!unit_all_finite(x, pim_dinv_state_size(&d)))
            return unit_error(u, "FMU state rejected: a feedforward state is not finite");
        if ((x[0] != 0.0 && x[0] != 1.0) || x[1] < 0.0 || x[1] != floor(x[1]) ||
            x[1] > (double)d.latency || (solver[0] != 0.0 && solver[0] != 1.0))
            return unit_error(u, "FMU state rejected: feedforward state started = %g, seen = %g, "
                                 "solver started = %g (expected 0 or 1, 0 <= seen <= latency "
                                 "%llu)", x[0], x[1], solver[0],
                              (unsigned long long)d.latency);
        if (d.rate_w && solver[3 + d.n + d.m] < 0.0)
            return unit_error(u, "FMU state rejected: the filtered rate rho_f = %g must be "
                                 ">= 0", solver[3 + d.n + d.m]);
    }
#endif
#if PIM_MODEL == 6
    if (!unit_all_finite(s->hist, 2) || s->hist[1] < 0.0)
        return unit_error(u, "FMU state rejected: the rate state (v[k-1], rate[k]) = (%g, %g) "
                             "must be finite with rate >= 0", s->hist[0], s->hist[1]);
#endif
    if (unit_derive(s) != 0) return unit_error(u, "FMU state rejected: %s", s->msg);
    return 0;
}

/*
 * Checks a serialized state (bytes, size) for this unit and token and, when out != NULL,
 * loads it into *out.  Returns 0, or -1 with the reason in u->msg (u and out unchanged).
 */
static int unit_state_read(pim_unit *u, const unsigned char *bytes, size_t size,
                           const char *token, unsigned fmi, pim_unit *out)
{
    if (!bytes) return unit_error(u, "FMU state rejected: null state");
    if (size != PIM_STATE_SIZE)
        return unit_error(u, "FMU state rejected: %llu bytes, expected %llu (another FMU or "
                             "version)", (unsigned long long)size,
                          (unsigned long long)PIM_STATE_SIZE);
    pim_state_header h, want;
    memcpy(&h, bytes, sizeof h);
    unit_state_header(&want, token, fmi);
    if (memcmp(h.magic, want.magic, 8) != 0)
        return unit_error(u, "FMU state rejected: not a pimodel FMU state (bad magic)");
    if (h.version != want.version)
        return unit_error(u, "FMU state rejected: format version %u, expected %u", h.version,
                          want.version);
    if (h.byte_order != want.byte_order)
        return unit_error(u, "FMU state rejected: written on a machine of another byte order");
    if (h.model != want.model || h.fmi != want.fmi || memcmp(h.token, want.token,
                                                             PIM_STATE_TOKEN) != 0)
        return unit_error(u, "FMU state rejected: written by another model (unit %u, FMI %u); "
                             "the GUID / instantiation token does not match", h.model, h.fmi);
    if (h.nmax != want.nmax || h.est_win != want.est_win || h.unit_size != want.unit_size ||
        h.est_size != want.est_size)
        return unit_error(u, "FMU state rejected: sizes differ (written by another build of "
                             "this FMU)");
    uint64_t sum;
    memcpy(&sum, bytes + sizeof h + sizeof(pim_unit), sizeof sum);
    if (sum != unit_fnv1a(bytes, sizeof h + sizeof(pim_unit)))
        return unit_error(u, "FMU state rejected: checksum mismatch (corrupted bytes)");
    pim_unit *s = (pim_unit *)malloc(sizeof *s);
    if (!s) return unit_error(u, "FMU state rejected: out of memory");
    memcpy(s, bytes + sizeof h, sizeof *s);
    s->msg[0] = '\0';
    int rc = 0;
    if (s->mode < PIM_INSTANTIATED || s->mode > PIM_TERMINATED)
        rc = unit_error(u, "FMU state rejected: unknown mode %d", s->mode);
    else if (!isfinite(s->time) || s->time < 0.0)
        rc = unit_error(u, "FMU state rejected: time %g must be finite and >= 0", s->time);
    else if (!isfinite(s->out1) || !isfinite(s->out2))
        rc = unit_error(u, "FMU state rejected: an output is not finite");
    else if (s->mode >= PIM_STEP_MODE) {
        if (unit_check_parameters(s) != 0)
            rc = unit_error(u, "FMU state rejected: %s", s->msg);
        else
            rc = unit_check_states(u, s);
    }
    if (rc == 0 && out) {
        s->msg[0] = '\0';
        *out = *s;
    }
    free(s);
    return rc;
}

#endif /* PIM_UNIT_H */
