/*
 * The pimodel FMU framework, independent of the FMI version and of the unit: variables, modes,
 * the common parameter check, the sampling rule, the step and its rollback, and the checked FMU
 * state format.  Included (static functions) by the FMI 2 and FMI 3 glue after config.h
 * (generated from pimodel.fmu.spec: MODEL_IDENTIFIER, PIM_MODEL, ValueReference,
 * PIM_UNIT_VARIABLES).
 * Functions return 0 on success, or -1 with the reason in u->msg.
 *
 * One folder per unit (units/<Unit>/, as the Modelica Reference-FMUs): fields.h declares the
 * unit's own fields of pim_unit (included inside the struct) and unit.h its hooks, which this
 * framework calls and which are the only unit-specific code (those marked * are optional: a
 * unit that defines one says so with HAS_MODEL_<NAME>, e.g. HAS_MODEL_DERIVE):
 *
 *   model_defaults(u) *        start values of the unit's own parameters
 *   model_check_parameters(u)  the unit's parameter rules (after n, Ts, z0 here)
 *   model_derive(u) *          quantities derived from checked parameters (setup, restored state)
 *   model_setup(u)             initial states at exitInitializationMode (and model_derive)
 *   model_check_inputs(u) *    the inputs held over a step, besides the main input (in1)
 *   model_sample(u)            one internal sample at the held inputs
 *   model_outputs_finite(u) *  the unit's further outputs are finite (out1, out2 checked here)
 *   model_saved, model_save(u, s), model_restore(u, s)   the states a step changes, for the
 *                              rollback of a step that overflows (once per doStep, not per sample)
 *   model_step_safe(u) *       1 when no sample at the held inputs can overflow (a bound from the
 *                              checked parameters, derived once; 1 implies a finite main input):
 *                              the step then runs without the rollback copy and without the
 *                              per-sample output checks, a one-sample step on unit_one_sample's
 *                              fast path
 *   model_step_done(u) *       after a step's samples (e.g. the RadiusEstimator's health output)
 *   model_check_states(u, s)   the states of a loaded FMU state s (parameters already checked)
 *   model_report(u, buf, size) * a report in words logged once at terminate (0: none)
 *
 * Code shared by some units is in units/shared/ (plays.h, play_states.h, play_state_hooks.h,
 * inverse_flag.h, inverse_pi.h, envelope_check.h, sections.h, diag_fields.h, diag_static.h).
 * The numerics are the shared C core (core/pim_*.c).  An optional PIM_MODEL_DEFAULTS(u)
 * (config.h of a model's operator FMU, `pimodel fmu build --model`) sets the parameters' start
 * values after model_defaults.
 *
 * Sampling rule: internal sample k (an int64 counter) happens at time k*Ts.  A step from t over
 * h processes every sample with k*Ts in [t, t+h) (up to a master's rounding of the grid:
 * unit_first_sample), each with the inputs set before the call (held over the step); outputs are
 * those of the last processed sample and hold between samples, and after initialization those of
 * the first sample for the inputs set so far (unit_start_outputs).  A step shorter than Ts that
 * contains no sample instant changes nothing.
 *
 * Limits (each breach is an error with a logged reason, never a crash or a hang):
 *   n in 1..PIM_UNIT_NMAX (64; DiagnosedModel, DiagnosedInverse: 128) plays; Ts finite and
 *   >= PIM_TS_MIN; start time finite and >= 0; at most PIM_MAX_SUBSTEPS (10^7) samples per
 *   doStep; sample index (t+h)/Ts below PIM_MAX_SAMPLE_INDEX (2^52, where k*Ts is still exact in
 *   double); doStep needs t == the FMU's time (the end of the last step) within
 *   min(1e-9 max(1, |t|), 1e-3 Ts), h finite and > 0, and t + h > t.
 *
 * Value references: config.h's enum ValueReference and table PIM_UNIT_VARIABLES (name,
 * reference, type, causality, size, member of pim_unit), generated from the Python spec like
 * the model description, are the one source of truth; tests/test_fmu3.py holds every built
 * modelDescription.xml (FMI 2 and 3) equal to it.  In FMI 2 array element x[i+1] has reference
 * base + i (p 100, r 200, r_hat 300, ...: pimodel.fmu.spec); in FMI 3 an array is one variable,
 * a per-play one (size PIM_PER_PLAY) of n_plays elements: the UInt64 structural parameter
 * (reference 18, FMI 3 only), set in configuration mode, 1..PIM_NMAX, default PIM_NMAX, and
 * n <= n_plays (n > PIM_NMAX, the Diagnosed units' plays in the _hi arrays: n_plays = PIM_NMAX).
 */
#ifndef PIM_UNIT_H
#define PIM_UNIT_H

#include <float.h>
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

#define PIM_NMAX PIM_MAX_PLAYS            /* declared array size: p[1..64], r[..], r_hat[..] */
#define NMAX PIM_NMAX


/* Error paths out of line, so that the accessors and doStep stay small (they run every sample);
 * the per-sample code inline (the framework's fast path and a unit's model_sample). */
#if defined(__GNUC__)
#define PIM_COLD __attribute__((noinline, cold))
#define PIM_NOINLINE __attribute__((noinline))
#define PIM_HOT_INLINE __attribute__((always_inline)) inline
#else
#define PIM_COLD
#define PIM_NOINLINE
#define PIM_HOT_INLINE inline
#endif

typedef enum {
    PIM_PARAMETER, PIM_INPUT, PIM_OUTPUT, PIM_INDEPENDENT, PIM_STRUCTURAL
} pim_causality;

/* The size of an FMI 3 array sized by the structural parameter n_plays (the per-play arrays p,
 * r, r_hat, ...: <Dimension valueReference="n_plays"/>); the C storage stays PIM_NMAX wide. */
#define PIM_PER_PLAY (-1)

typedef struct {
    const char *name;
    unsigned vr;
    char type; /* 'R' Real/Float64, 'I' Integer/Int32, 'B' Boolean, 'U' UInt64 (FMI 3) */
    pim_causality causality;
    int size;      /* 1, PIM_NMAX for an array, or PIM_PER_PLAY (FMI 3: n_plays elements) */
    size_t offset; /* of the value(s) in pim_unit */
} pim_var;


/* Life cycle (FMI 2 and 3 Co-Simulation): instantiated -> initialization mode -> step mode
 * (after a successful exitInitializationMode) -> terminated; reset goes back to instantiated.
 * FMI 3 also: instantiated <-> configuration mode (the structural parameter n_plays). */
enum { PIM_INSTANTIATED = 1, PIM_INIT_MODE, PIM_STEP_MODE, PIM_TERMINATED, PIM_CONFIG_MODE };

/* 16-byte alignment of the unit (its arrays at offsets that are multiples of 16, so the play
 * loop reads them as aligned vectors) */
#if defined(__GNUC__)
#define PIM_ALIGNED16 __attribute__((aligned(16))) /* pim_unit: allocated by unit_alloc */
#define PIM_UNIT_ALIGNED(u) ((pim_unit *)__builtin_assume_aligned((u), 16))
#else
#define PIM_ALIGNED16
#define PIM_UNIT_ALIGNED(u) (u)
#endif

/* The unit: the common part (the same layout in every unit, mirrored by tests/fmu_driver.py),
 * then the unit's own fields (units/<Unit>/fields.h). */
typedef struct {
    /* common parameters: sample time, initial play state, plays 1..64 (weights p, radii r;
     * CreepOperator: gains c in p, time constants tau in r; 16-byte aligned as the arrays
     * the core's loops run over) */
    double Ts PIM_ALIGNED16, z0;
    double p[PIM_NMAX], r[PIM_NMAX];
    /* inputs and outputs (the spec's names: in1 is v, y_d or u; in2 and out2 the
     * RadiusEstimator's y and e) */
    double in1, in2, out1, out2;
    /* time and sample counter; the number of plays (a parameter) and the mode */
    double time;    /* the end of the last communication step (the start time before any) */
    int64_t k_next; /* index of the next sample to process */
    int n, mode;
    /* FMI 3's structural parameter: the size of the per-play arrays (FMI 2: PIM_NMAX) */
    uint64_t n_plays;
    /* derived from Ts (unit_derive_time): 1 / Ts, so that a doStep counts its samples without
     * a division, and the tolerance of a doStep's t that needs no further check */
    double inv_Ts, t_tol;
    /* derived from the mode, the time, t_tol and k_next (unit_fast), for the per-sample fast
     * paths: the tolerance of doStep's t (t_tol in step mode once time > t_tol, else -1: no t
     * passes), the main input's value reference while an input may be set (else 2^32, no
     * value reference), and k_next + PIM_ONE_MID, the centre of doStep's one-sample window */
    double fast_t_tol;
    uint64_t fast_in_vr;
    double x_next;
    /* the unit's own parameters, states and derived quantities */
#include "fields.h"
    char msg[256]; /* reason of the last failure */
} pim_unit;

#ifndef PIM_UNIT_NMAX
#define PIM_UNIT_NMAX PIM_NMAX /* largest n (a unit's fields.h may raise it) */
#endif

#define PIM_AT(field) offsetof(pim_unit, field)

/* The variables of the unit: the table PIM_UNIT_VARIABLES of config.h, generated from the
 * Python spec (pimodel.fmu.spec) like the model description; inputs and outputs first, as the
 * accessors scan it on every call. */
#define PIM_VAR_ROW(name, vr, type, causality, size, member) \
    {name, vr, type, causality, size, PIM_AT(member)},
static const pim_var unit_vars[] = {PIM_UNIT_VARIABLES(PIM_VAR_ROW)};
#undef PIM_VAR_ROW
#define PIM_NVARS (sizeof unit_vars / sizeof unit_vars[0])

/* Zeroed memory of `size` bytes for a pim_unit or a struct that starts with one, or NULL when
 * out of memory or not 16-byte aligned (PIM_UNIT_ALIGNED; what the allocators of 64-bit
 * platforms return). */
static void *unit_alloc(size_t size)
{
    void *m = calloc(1, size);
    if (m && ((uintptr_t)m & 15u) != 0) {
        free(m);
        return NULL;
    }
    return m;
}

/* The name of the variable stored at offset (e.g. the main input's, "v", "y_d" or "u"). */
static const char *unit_name_of(size_t offset)
{
    for (size_t i = 0; i < PIM_NVARS; ++i)
        if (unit_vars[i].offset == offset) return unit_vars[i].name;
    return "?";
}

/* The value reference of the scalar Real variable stored at `offset` (the main input in1 of
 * causality input, the main output out1), or -1; from the constant table, so that the
 * compiler folds it to a number. */
static PIM_HOT_INLINE long unit_main_vr(size_t offset, pim_causality causality)
{
    for (size_t i = 0; i < PIM_NVARS; ++i)
        if (unit_vars[i].offset == offset && unit_vars[i].type == 'R' && unit_vars[i].size == 1 &&
            unit_vars[i].causality == causality)
            return (long)unit_vars[i].vr;
    return -1;
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
    case PIM_CONFIG_MODE: return "in configuration mode";
    default: return "in an unknown mode";
    }
}

/* 0 if the unit's mode is one of the bits in `allowed` (1 << mode), else -1 naming the call. */
static int unit_require_mode(pim_unit *u, unsigned allowed, const char *call)
{
    if (u->mode >= PIM_INSTANTIATED && u->mode <= PIM_CONFIG_MODE && (allowed & (1u << u->mode)))
        return 0;
    return unit_error(u, "%s is not allowed now: the FMU is %s", call, unit_mode_name(u->mode));
}
#define PIM_IN(m) (1u << (m))

/* Whether x[0..n) are all finite (for the units' state checks). */
static inline int unit_all_finite(const double *x, size_t n)
{
    for (size_t i = 0; i < n; ++i)
        if (!isfinite(x[i])) return 0;
    return 1;
}

/* The unit's own code: its hooks (model_*, above), after the struct and unit_error.  A unit
 * declares the optional hooks it defines (HAS_MODEL_DEFAULTS, ...), as the Reference-FMUs'
 * config.h declares its capabilities; the others do nothing: */
#include "unit.h"

#ifndef HAS_MODEL_DEFAULTS
static void model_defaults(pim_unit *u) { (void)u; }
#endif
#ifndef HAS_MODEL_DERIVE
static int model_derive(pim_unit *u) { (void)u; return 0; }
#endif
#ifndef HAS_MODEL_CHECK_INPUTS
static int model_check_inputs(pim_unit *u) { (void)u; return 0; }
#endif
#ifndef HAS_MODEL_OUTPUTS_FINITE
static int model_outputs_finite(const pim_unit *u) { (void)u; return 1; }
#endif
#ifndef HAS_MODEL_STEP_SAFE
static int model_step_safe(const pim_unit *u) { (void)u; return 0; }
#endif
#ifndef HAS_MODEL_STEP_DONE
static void model_step_done(pim_unit *u) { (void)u; }
#endif
#ifndef HAS_MODEL_REPORT
static int model_report(const pim_unit *u, char *buf, size_t size)
{
    (void)u, (void)buf, (void)size;
    return 0;
}
#endif

/* The sampling rule's tolerance at sample x, in samples (unit_first_sample). */
static double unit_sample_tol(double x)
{
    const double tol = PIM_SAMPLE_TOL + x * x * 2.220446049250313e-16;
    return tol < 1e-3 ? tol : 1e-3;
}

/* Index of the first sample at or after time t: ceil(t / Ts) up to the rounding of a time
 * computed by a master (PIM_SAMPLE_TOL plus x^2 eps samples at sample x, what a clock that adds
 * its step x times accumulates; at most 1e-3 samples), so that a communication grid that
 * differs from k*Ts by floating-point rounding never shifts a sample. */
static double unit_first_sample(const pim_unit *u, double t)
{
    const double x = t / u->Ts;
    return ceil(x - unit_sample_tol(x));
}

/*
 * The end sample k1 of a doStep ending at t > 0 (unit_first_sample(u, t)), or -1 when it is
 * beyond the counter's range, with the reciprocal u->inv_Ts (unit_derive_time) instead of a
 * division.  x = t * inv_Ts is within 3.4e-16 x of the rule's t / Ts (three roundings) and the
 * rule's tolerance within a relative 1e-15 of unit_sample_tol(x), so for x < 2^32 the result
 * is the rule's whenever x lies at least 1e-15 x + 1e-6 tol below (result k) or above (result
 * k + 1) an integer k plus the tolerance (a margin that also covers the rounding of the rule's
 * x - tol).  Most steps end within half the smallest tolerance (1e-9 / 2) above an integer, or
 * beyond the largest (1e-3) plus the error: two comparisons decide them without the
 * tolerance.  Only a step end within that margin of the tolerance, or beyond 2^32 samples,
 * asks unit_first_sample.
 */
static int64_t unit_end_sample(const pim_unit *u, double t)
{
    const double x = t * u->inv_Ts;
    if (x < 4294967296.0) {
        const int64_t k = (int64_t)x; /* floor: x > 0 */
        const double frac = x - (double)k;
        if (frac <= 0.5 * PIM_SAMPLE_TOL) return k;
        if (frac >= 1.01e-3) return k + 1;
        const double tol = unit_sample_tol(x), margin = 1e-15 * x;
        if (frac <= tol * (1.0 - 1e-6) - margin) return k;
        if (frac > tol * (1.0 + 1e-6) + margin) return k + 1;
    }
    const double k = unit_first_sample(u, t);
    return k < PIM_MAX_SAMPLE_INDEX ? (int64_t)k : -1;
}

/* What the sampling rule derives from Ts (setup, restored FMU states): the reciprocal of
 * unit_end_sample and the tolerance within which a doStep's t matches the FMU's time without
 * further checks (the smallest of the rule's tolerances: 1e-9 s, or 1e-3 Ts). */
static void unit_derive_time(pim_unit *u)
{
    u->inv_Ts = 1.0 / u->Ts;
    u->t_tol = u->Ts < 1e-6 ? 1e-3 * u->Ts : 1e-9;
}

/* The one-sample window of doStep's fast path (unit_one_sample): a step ending at x = t_end /
 * Ts samples (x as unit_end_sample computes it) below 2^32 with x - k_next in [PIM_ONE_LO,
 * PIM_ONE_HI] ends at sample k_next + 1, so it processes exactly sample k_next.  Proof:
 * x - k_next is within 2^-52 of its exact value (|x - k_next| <= 2), so either
 * x >= k_next + 1 with x - (k_next + 1) <= 0.4e-9 + 2^-52 < 0.5 PIM_SAMPLE_TOL
 * (unit_end_sample's first case: k_next + 1), or x < k_next + 1 with x - k_next >= 1.02e-3 -
 * 2^-52 >= 1.01e-3 (its second case: k_next + 1); x < 2^32 as those cases need.
 * The fast path tests |x - x_next| <= PIM_ONE_HALF with x_next = k_next + PIM_ONE_MID (exact:
 * PIM_ONE_MID = 1/2 + 2^-9 has 10 bits, k_next < 2^43), a window [2 PIM_ONE_MID - PIM_ONE_HI
 * + 1e-15, PIM_ONE_HI - 1e-15] (3.9e-3 .. 1 + 4e-10 samples) within [PIM_ONE_LO, PIM_ONE_HI]
 * despite the subtraction's rounding (at most 2^-54). */
#define PIM_ONE_LO 1.02e-3
#define PIM_ONE_HI (1.0 + 0.4 * PIM_SAMPLE_TOL)
#define PIM_ONE_MID (0.5 + 1.0 / 512.0)
#define PIM_ONE_HALF (PIM_ONE_HI - PIM_ONE_MID - 1e-15)
#define PIM_ONE_XMAX 4294967296.0

/* The fast paths' fields (pim_unit) from the mode, the time, t_tol and k_next: after every
 * change of the mode (unit_set_mode), after the general doStep, and for a restored state.  The
 * one-sample fast path keeps them right: it moves the time forward only, and x_next with
 * k_next. */
static void unit_fast(pim_unit *u)
{
    const long in_vr = unit_main_vr(PIM_AT(in1), PIM_INPUT);
    u->fast_t_tol = u->mode == PIM_STEP_MODE && u->time > u->t_tol ? u->t_tol : -1.0;
    u->x_next = (double)u->k_next + PIM_ONE_MID;
    u->fast_in_vr = in_vr >= 0 && u->mode != PIM_TERMINATED && u->mode != PIM_CONFIG_MODE
                        ? (uint64_t)in_vr
                        : (uint64_t)1 << 32;
}

static void unit_set_mode(pim_unit *u, int mode)
{
    u->mode = mode;
    unit_fast(u);
}

static void unit_defaults(pim_unit *u)
{
    memset(u, 0, sizeof *u);
    u->Ts = 1e-3;
    u->n = 1;
    u->n_plays = PIM_NMAX;
    for (int i = 0; i < PIM_NMAX; ++i) u->p[i] = 1.0;
    model_defaults(u);
#ifdef PIM_MODEL_DEFAULTS
    PIM_MODEL_DEFAULTS(u);
#endif
    unit_set_mode(u, PIM_INSTANTIATED);
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

/* Quantities derived from checked parameters; at setup and for every restored FMU state. */
static int unit_derive(pim_unit *u)
{
    unit_derive_time(u);
    return model_derive(u);
}

/* The structural parameter n_plays (fmi3ExitConfigurationMode, restored states). */
static int unit_check_n_plays(pim_unit *u)
{
    if (u->n_plays < 1 || u->n_plays > PIM_NMAX)
        return unit_error(u, "structural parameter n_plays = %llu out of range: 1 <= n_plays "
                             "<= %d", (unsigned long long)u->n_plays, PIM_NMAX);
    return 0;
}

/* The parameter rules, shared by initialization and by every FMU state that is restored. */
static int unit_check_parameters(pim_unit *u)
{
    if (u->n < 1 || u->n > PIM_UNIT_NMAX)
        return unit_error(u, "parameter n = %d out of range: 1 <= n <= %d", u->n, PIM_UNIT_NMAX);
    if (unit_check_n_plays(u) != 0) return -1;
    if ((uint64_t)(u->n < PIM_NMAX ? u->n : PIM_NMAX) > u->n_plays)
        return unit_error(u, "parameter n = %d exceeds n_plays = %llu, the size of the per-play "
                             "arrays (set n_plays in configuration mode%s)", u->n,
                          (unsigned long long)u->n_plays,
                          u->n > PIM_NMAX ? "; plays beyond 64 need n_plays = 64" : "");
    if (!isfinite(u->Ts) || !(u->Ts >= PIM_TS_MIN))
        return unit_error(u, "parameter Ts = %g: the sample time must be > 0 (finite, >= %g)",
                          u->Ts, PIM_TS_MIN);
    if (!isfinite(u->z0)) return unit_error(u, "parameter z0 = %g: must be finite", u->z0);
    return model_check_parameters(u);
}

/* The outputs at the start time (FMI: after initialization the outputs are those of the
 * inputs set so far): the response of sample k_next to the inputs held now, computed on a copy
 * so that the states stay those before that sample, which the first doStep processes.  Inputs
 * that a step would refuse, or outputs that overflow, leave the start values. */
static void unit_start_outputs(pim_unit *u)
{
    pim_unit *c = (pim_unit *)unit_alloc(sizeof *c);
    if (!c) return;
    *c = *u;
    if (isfinite(c->in1) && model_check_inputs(c) == 0) {
        model_sample(c);
        if (isfinite(c->out1) && isfinite(c->out2) && model_outputs_finite(c)) {
            u->out1 = c->out1;
            u->out2 = c->out2;
        }
    }
    free(c);
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
    unit_derive_time(u);
    if (model_setup(u) != 0) return -1;
    unit_start_outputs(u);
    return 0;
}

/* The inputs held over a step: finite (and the unit's further inputs admissible). */
static int unit_check_inputs(pim_unit *u)
{
    if (!isfinite(u->in1))
        return unit_error(u, "input %s = %g is not finite (NaN or Inf)",
                          unit_name_of(PIM_AT(in1)), u->in1);
    return model_check_inputs(u);
}

/* Samples k_next .. k1-1 with the outputs checked after each; a step that overflows is not
 * taken: the states it changes are restored (a copy per step, for the units whose step can
 * fail: model_step_safe). */
static int unit_samples_checked(pim_unit *u, int64_t k1)
{
    const int64_t k_saved = u->k_next;
    const double out_saved[2] = {u->out1, u->out2};
    model_saved saved;
    model_save(u, &saved);
    for (; u->k_next < k1; ++u->k_next) {
        model_sample(u);
        if (!isfinite(u->out1) || !isfinite(u->out2) || !model_outputs_finite(u)) {
            const double y1 = u->out1, y2 = u->out2;
            const long long k_bad = (long long)u->k_next;
            u->k_next = k_saved;
            u->out1 = out_saved[0];
            u->out2 = out_saved[1];
            model_restore(u, &saved);
            return unit_error(u, "the outputs overflowed or are undefined (%g, %g) at sample "
                                 "%lld with the inputs held over this step (an input beyond an "
                                 "envelope's domain or range, or a numeric overflow); the step "
                                 "was not taken", y1, y2, k_bad);
        }
    }
    return 0;
}

/* doStep(t, h) in general (unit_do_step): processes the samples k*Ts in [t, t+h) (the sampling
 * rule above), with every check. */
PIM_NOINLINE static int unit_do_step_general(pim_unit *u, double t, double h)
{
    if (u->mode != PIM_STEP_MODE) return unit_require_mode(u, PIM_IN(PIM_STEP_MODE), "doStep");
    if (!(h > 0.0 && h <= DBL_MAX))
        return unit_error(u, "communication step size h = %g: must be finite and > 0", h);
    /* u->time is finite and >= 0: only a t further away needs the scale of the time */
    if (!(fabs(t - u->time) <= u->t_tol && t >= 0.0)) {
        if (!isfinite(t) || t < 0.0)
            return unit_error(u, "communication point t = %g: must be finite and >= 0", t);
        const double scale = fabs(u->time) > 1.0 ? fabs(u->time) : 1.0;
        const double tol = 1e-9 * scale < 1e-3 * u->Ts ? 1e-9 * scale : 1e-3 * u->Ts;
        if (fabs(t - u->time) > tol)
            return unit_error(u, "communication point t = %.17g does not match the FMU's time "
                                 "%.17g (the end of the last step)", t, u->time);
    }
    const double t_end = t + h;
    if (!(t_end > t))
        return unit_error(u, "no progress: t + h == t at t = %g, h = %g (h is below the time "
                             "resolution at t)", t, h);
    const int64_t k1 = unit_end_sample(u, t_end);
    if (k1 < 0)
        return unit_error(u, "time t + h = %g is beyond the sample counter's range (2^52 "
                             "samples of Ts = %g)", t_end, u->Ts);
    if (k1 - u->k_next > PIM_MAX_SUBSTEPS)
        return unit_error(u, "step h = %g spans %lld samples of Ts = %g; at most %lld per doStep "
                             "(use shorter communication steps)", h,
                          (long long)(k1 - u->k_next), u->Ts, PIM_MAX_SUBSTEPS);
    if (k1 > u->k_next) {
        if (unit_check_inputs(u) != 0) return -1;
        if (model_step_safe(u)) { /* no sample can overflow: a tight loop, nothing to roll back */
            int64_t k = u->k_next;
            do model_sample(u);
            while (++k < k1);
            u->k_next = k1;
        } else if (unit_samples_checked(u, k1) != 0) {
            return -1;
        }
        model_step_done(u);
    }
    u->time = t_end;
    unit_fast(u);
    return 0;
}

/*
 * The fast path of doStep(t, h) for the usual step, one sample on the FMU's grid (h == Ts up to
 * rounding) at inputs that cannot overflow it (model_step_safe): |t - time| <= fast_t_tol
 * (unit_fast: -1 outside step mode, so no t passes; else t_tol, and time > t_tol, so a t that
 * passes is >= 0: the general path's first test), the end in the one-sample window (so t + h,
 * and h, are finite) and the inputs admissible (unit_check_inputs: the main input is finite as
 * model_step_safe implies).  Then also t + h > t (so h > 0, the general path's other tests):
 * k_next is the rule's sample of time, so time <= (k_next + 1e-3 + 2e-6) Ts, and t <= time +
 * t_tol (1 + 2^-52) <= (k_next + 2.01e-3) Ts, while the window puts t + h at >= (k_next + 3.9e-3
 * - 1e-6) Ts.  The general path would take the same checks, find k1 = k_next + 1 and run its
 * loop once: this runs that sample and returns 1.  Any other step returns 0 with nothing
 * changed, for unit_do_step_general (which also gives a failing step's reason).
 */
static PIM_HOT_INLINE int unit_one_sample(pim_unit *u0, double t, double h)
{
    pim_unit *u = PIM_UNIT_ALIGNED(u0);
    const double t_end = t + h, x = t_end * u->inv_Ts;
    /* a NaN t or h gives a NaN x, which fails the window's test; so the tests before it may
     * let NaN through: !(a > b), which compares with b in memory */
    if (!(!(fabs(t - u->time) > u->fast_t_tol) && !(x >= PIM_ONE_XMAX) &&
          fabs(x - u->x_next) <= PIM_ONE_HALF && model_step_safe(u) &&
          model_check_inputs(u) == 0))
        return 0;
    model_sample(u);
    ++u->k_next;
    u->x_next += 1.0;
    model_step_done(u);
    u->time = t_end;
    return 1;
}

/* doStep(t, h): the one-sample fast path, else the general path; 0, or -1 with the reason. */
static PIM_HOT_INLINE int unit_do_step(pim_unit *u, double t, double h)
{
    return unit_one_sample(u, t, h) ? 0 : unit_do_step_general(u, t, h);
}

/* The unit's report in words (no '%') into buf at terminate, after a run in step mode;
 * returns 0 when there is nothing to report. */
static int unit_terminate_report(const pim_unit *u, char *buf, size_t size)
{
    buf[0] = '\0';
    return u->mode == PIM_STEP_MODE ? model_report(u, buf, size) : 0;
}

/* ---- variables by value reference --------------------------------------------------------- */

/* The variable with reference vr, or NULL.  With elements (FMI 2) an array is addressed by
 * element (reference base + i, *elem = i); without (FMI 3) as a whole (*elem = -1). */
static const pim_var *unit_var(unsigned vr, int elements, int *elem)
{
    for (size_t i = 0; i < PIM_NVARS; ++i) {
        const pim_var *v = &unit_vars[i];
        const unsigned d = vr - v->vr; /* wraps for vr < v->vr */
        if (v->size > 1 && elements) { /* FMI 2 array elements: v->vr + 0 .. v->vr + size - 1 */
            if (d >= (unsigned)v->size) continue;
            *elem = (int)d;
        } else {
            if (d != 0) continue;
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

/* Whether variable v may be set now: the structural parameter in configuration mode,
 * parameters before initialization, inputs until terminate, never outputs or time. */
static int unit_settable(const pim_unit *u, const pim_var *v)
{
    if (v->causality == PIM_OUTPUT || v->causality == PIM_INDEPENDENT) return 0;
    if (v->causality == PIM_STRUCTURAL) return u->mode == PIM_CONFIG_MODE;
    if (v->causality == PIM_PARAMETER)
        return u->mode == PIM_INSTANTIATED || u->mode == PIM_INIT_MODE;
    return u->mode != PIM_TERMINATED && u->mode != PIM_CONFIG_MODE;
}

/* The reason why unit_ref refused vr (v: its variable or NULL), into u->msg; returns NULL. */
PIM_COLD static void *unit_ref_refused(pim_unit *u, const pim_var *v, int elem, unsigned vr, char type)
{
    const char *tname = type == 'R' ? "Real" : type == 'I' ? "Integer" : type == 'U' ? "UInt64"
                                                                        : "Boolean";
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
    else if (v->causality == PIM_STRUCTURAL)
        unit_error(u, "structural parameter %s (value reference %u) can be set in configuration "
                      "mode only (fmi3EnterConfigurationMode after instantiation)",
                   unit_label(v, elem, name, sizeof name), vr);
    else if (v->causality == PIM_PARAMETER)
        unit_error(u, "cannot set parameter %s (value reference %u) after initialization",
                   unit_label(v, elem, name, sizeof name), vr);
    else if (u->mode == PIM_CONFIG_MODE)
        unit_error(u, "cannot set input %s (value reference %u) in configuration mode (only "
                      "n_plays)", unit_label(v, elem, name, sizeof name), vr);
    else
        unit_error(u, "cannot set input %s (value reference %u) after terminate",
                   unit_label(v, elem, name, sizeof name), vr);
    return NULL;
}

/*
 * Storage of the variable with reference vr, checked against the model description (exists,
 * has type `type`) and, for set != 0, against the mode (unit_settable).  *count: values it
 * holds (1; an FMI 3 array's PIM_NMAX, or n_plays for a per-play array).  NULL with the
 * reason in u->msg on failure.
 */
static PIM_HOT_INLINE void *unit_ref(pim_unit *u, unsigned vr, char type, int elements, int set,
                                     size_t *count)
{
    int elem = -1;
    const pim_var *v = unit_var(vr, elements, &elem);
    if (!v || v->type != type || (set && !unit_settable(u, v)))
        return unit_ref_refused(u, v, elem, vr, type);
    *count = elem >= 0 ? 1 : v->size == PIM_PER_PLAY ? (size_t)u->n_plays : (size_t)v->size;
    return (char *)u + v->offset + (elem > 0 ? (size_t)elem * sizeof(double) : 0);
}

/*
 * The accessors' fast path for what a master moves every step: the storage of the main input
 * in1 (set != 0, in a mode where unit_settable allows an input: u->fast_in_vr) or of the
 * main output out1
 * (set == 0); NULL for any other variable or mode, which then takes unit_ref (the same rules,
 * and the reasons of a refusal).
 */
static PIM_HOT_INLINE double *unit_main_real(pim_unit *u, unsigned vr, int set)
{
    if (set) return vr == u->fast_in_vr ? &u->in1 : NULL;
    return (long)vr == unit_main_vr(PIM_AT(out1), PIM_OUTPUT) ? &u->out1 : NULL;
}

/* *to = *from bit for bit through an integer register (a shorter path from the master's store
 * to the unit's load than through a floating-point register). */
static PIM_HOT_INLINE void unit_copy_real(double *to, const double *from)
{
    uint64_t b;
    memcpy(&b, from, sizeof b);
    memcpy(to, &b, sizeof b);
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
#define PIM_STATE_VERSION 10u /* 2: units 4-7 fields; 3: law, health; 4: DiagnosedModel
                                 prefilter (Wiener); 5: DiagnosedInverse fields, post sections;
                                 6: the common part, then the unit's own fields; 7: n_plays;
                                 8: inv_Ts, t_tol (derived, recomputed on load);
                                 9: rate_growth, the scaled rate family's state;
                                 10: fast_t_tol, fast_in_vr, x_next (derived, recomputed
                                 on load),
                                 the unit 16-byte aligned */
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


/* Checks the states of a loaded unit s (parameters already checked) and recomputes what derives
 * from the parameters; on failure the reason goes to u->msg. */
static int unit_check_states(pim_unit *u, pim_unit *s)
{
    const double k = unit_first_sample(s, s->time);
    if (!(k < PIM_MAX_SAMPLE_INDEX) || s->k_next != (int64_t)k)
        return unit_error(u, "FMU state rejected: sample counter %lld does not match time %g "
                             "and Ts = %g", (long long)s->k_next, s->time, s->Ts);
    if (model_check_states(u, s) != 0) return -1;
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
    pim_unit *s = (pim_unit *)unit_alloc(sizeof *s);
    if (!s) return unit_error(u, "FMU state rejected: out of memory");
    memcpy(s, bytes + sizeof h, sizeof *s);
    s->msg[0] = '\0';
    int rc = 0;
    if (s->mode < PIM_INSTANTIATED || s->mode > PIM_TERMINATED) /* none in configuration mode */
        rc = unit_error(u, "FMU state rejected: unknown mode %d", s->mode);
    else if (!isfinite(s->time) || s->time < 0.0)
        rc = unit_error(u, "FMU state rejected: time %g must be finite and >= 0", s->time);
    else if (!isfinite(s->out1) || !isfinite(s->out2))
        rc = unit_error(u, "FMU state rejected: an output is not finite");
    else if (unit_check_n_plays(s) != 0)
        rc = unit_error(u, "FMU state rejected: %s", s->msg);
    else if (s->mode == PIM_STEP_MODE || s->mode == PIM_TERMINATED) {
        if (unit_check_parameters(s) != 0)
            rc = unit_error(u, "FMU state rejected: %s", s->msg);
        else
            rc = unit_check_states(u, s);
    }
    if (rc == 0 && out) {
        s->msg[0] = '\0';
        unit_fast(s);
        *out = *s;
    }
    free(s);
    return rc;
}

#endif /* PIM_UNIT_H */
