/*
 * FMI 2.0 Co-Simulation glue for the pimodel units, one source for the three models; the
 * including file defines PIM_MODEL (1 PIHysteresis, 2 RadiusEstimator, 3 InversePI) and
 * PIM_MODEL_GUID.  The numerics are the shared C core (pim_pi.c, pim_estimator.c, pim_loops.c).
 *
 * Sampling rule: internal sample k happens at time k*Ts.  doStep(t, h) processes every sample
 * with k*Ts in [t, t+h) (tolerance 1e-9*Ts), each with the inputs set before the call (held
 * over the step); outputs are those of the last processed sample and hold between samples.
 * A step shorter than Ts that contains no sample instant changes nothing.
 *
 * Value references: 0 Ts, 1 n, 2 z0 (initial play state), 3 adaptive (InversePI), 4 gain,
 * 5 known_linear, 6 guard, 7 slope_window, 10 main input, 11 main output, 12 second input (y of
 * the estimator), 13 second output (e), 100+i p[i+1], 200+i r[i+1] (initial radii for the
 * estimator), 300+i r_hat[i+1] (inputs of the adaptive InversePI, outputs of the estimator).
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "pim_core.h"
#include "pim_estimator.h"
#include "pim_loops.h"

#ifndef PIM_MODEL
#error "define PIM_MODEL (1 PIHysteresis, 2 RadiusEstimator, 3 InversePI)"
#endif

#define NMAX 16 /* declared array variables p[1..16], r[1..16], r_hat[1..16] */

typedef struct {
    fmi2CallbackFunctions cb;
    char name[128];
    int initialized;
    int failed;
    /* parameters */
    double Ts, z0, gain, guard;
    int n, adaptive, known_linear, slope_window;
    double p[NMAX], r[NMAX];
    /* inputs and outputs */
    double in1, in2, out1, out2;
    double rhat_in[NMAX], rhat_out[NMAX];
    /* states */
    double z[PIM_MAX_PLAYS];
    double pinv[PIM_MAX_PLAYS], rinv[PIM_MAX_PLAYS];
    pim_estimator est;
} Inst;

static void logmsg(Inst *c, fmi2Status st, const char *cat, const char *fmt, ...)
{
    char buf[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    /* pass the formatted text itself as the message (hosts such as fmpy's Python callback do not
     * expand printf arguments), with '%' removed so that it is a safe format string too */
    for (char *q = buf; *q; ++q)
        if (*q == '%') *q = ' ';
    if (c && c->cb.logger) c->cb.logger(c->cb.componentEnvironment, c->name, st, cat, buf);
}

static fmi2Status fail(Inst *c, const char *fmt, const char *detail)
{
    logmsg(c, fmi2Error, "logStatusError", fmt, detail);
    return fmi2Error;
}

static void set_defaults(Inst *c)
{
    c->Ts = 1e-3;
    c->z0 = 0.0;
    c->gain = 10.0;
    c->guard = 0.0;
    c->n = 1;
    c->adaptive = 0;
    c->known_linear = 0;
    c->slope_window = 8;
    for (int i = 0; i < NMAX; ++i) {
        c->p[i] = 1.0;
        c->r[i] = 0.0;
        c->rhat_in[i] = 0.0;
        c->rhat_out[i] = 0.0;
    }
    c->in1 = c->in2 = c->out1 = c->out2 = 0.0;
    c->initialized = 0;
    c->failed = 0;
}

/* Checks parameters and sets up the states; returns fmi2OK or fmi2Error with a logged reason. */
static fmi2Status setup(Inst *c)
{
    if (c->n < 1 || c->n > NMAX) {
        logmsg(c, fmi2Error, "logStatusError", "parameter n = %d out of range: 1 <= n <= %d",
               c->n, NMAX);
        return fmi2Error;
    }
    if (!(c->Ts > 0.0) || !isfinite(c->Ts)) {
        logmsg(c, fmi2Error, "logStatusError", "parameter Ts = %g: the sample time must be > 0",
               c->Ts);
        return fmi2Error;
    }
    if (!isfinite(c->z0)) return fail(c, "parameter z0: %s", "must be finite");
    const size_t n = (size_t)c->n;
    const char *msg = pim_pi_check(n, c->p, c->r, 0);
#if PIM_MODEL == 2
    if (msg) return fail(c, "bad parameters: %s", msg);
    {
        double g[NMAX];
        for (size_t i = 0; i < n; ++i) g[i] = c->gain;
        if (!(c->gain >= 0.0) || !isfinite(c->gain))
            return fail(c, "parameter gain: %s", "must be finite and >= 0");
        msg = pim_est_init(&c->est, n, c->p, g, c->r, c->Ts, c->z0, 0.0, 0.0, 0.0, c->guard,
                           c->known_linear);
        if (msg) return fail(c, "bad parameters: %s", msg);
        msg = pim_est_set_slope_check(&c->est, c->slope_window, 0.5);
        if (msg) return fail(c, "bad parameters: %s", msg);
        for (size_t i = 0; i < n; ++i) c->rhat_out[i] = c->est.rhat[i];
    }
#else
    if (msg) return fail(c, "bad parameters: %s", msg);
    for (size_t i = 0; i < n; ++i) c->z[i] = c->z0;
#endif
#if PIM_MODEL == 3
    if (!c->adaptive) {
        double zinv[PIM_MAX_PLAYS];
        if (pim_pi_inverse(n, c->p, c->r, c->z, c->pinv, c->rinv, zinv) != 0)
            return fail(c, "bad parameters: %s",
                        "not invertible (r[1] must be 0 with a positive weight p[1])");
        memcpy(c->z, zinv, n * sizeof(double));
    } else if (c->r[0] != 0.0 && c->known_linear) {
        return fail(c, "bad parameters: %s", "r[1] must be 0");
    }
#endif
    return fmi2OK;
}

/* One internal sample at the held inputs. */
static fmi2Status sample(Inst *c)
{
    const size_t n = (size_t)c->n;
    if (!isfinite(c->in1) || !isfinite(c->in2)) {
        logmsg(c, fmi2Error, "logStatusError", "input is not finite (NaN or Inf): %g, %g",
               c->in1, c->in2);
        return fmi2Error;
    }
#if PIM_MODEL == 1
    c->out1 = pim_pi_step(n, c->p, c->r, c->z, c->in1);
#elif PIM_MODEL == 2
    double yh, e, ed;
    (void)pim_est_step(&c->est, c->in1, c->in2, NULL, &yh, &e, &ed);
    c->out1 = yh;
    c->out2 = e;
    for (size_t i = 0; i < n; ++i) c->rhat_out[i] = c->est.rhat[i];
#else
    if (c->adaptive) {
        for (size_t i = 0; i < n; ++i) {
            if (!isfinite(c->rhat_in[i]) || c->rhat_in[i] < 0.0 ||
                (i > 0 && c->rhat_in[i] < c->rhat_in[i - 1])) {
                logmsg(c, fmi2Error, "logStatusError",
                       "input r_hat[%d] = %g: radii must be finite, >= 0 and sorted", (int)i + 1,
                       c->rhat_in[i]);
                return fmi2Error;
            }
        }
        double v = pim_adaptive_inverse_step(n, c->p, c->rhat_in, c->z, c->in1);
        if (isnan(v)) {
            logmsg(c, fmi2Error, "logStatusError", "%s",
                   "input r_hat: not invertible (r_hat[1] must be 0)");
            return fmi2Error;
        }
        c->out1 = v;
    } else {
        c->out1 = pim_pi_step(n, c->pinv, c->rinv, c->z, c->in1);
    }
#endif
    return fmi2OK;
}

/* ---- FMI functions -------------------------------------------------------------------- */

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cats[])
{
    (void)c; (void)on; (void)n; (void)cats;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid,
                              fmi2String resources, const fmi2CallbackFunctions *cb,
                              fmi2Boolean visible, fmi2Boolean logging)
{
    (void)resources; (void)visible; (void)logging;
    if (!cb || type != fmi2CoSimulation) return NULL;
    if (guid && strcmp(guid, PIM_MODEL_GUID) != 0) {
        if (cb->logger)
            cb->logger(cb->componentEnvironment, name, fmi2Error, "logStatusError",
                       "GUID mismatch: the FMU was built for another model description");
        return NULL;
    }
    Inst *c = (Inst *)calloc(1, sizeof(Inst));
    if (!c) return NULL;
    c->cb = *cb;
    snprintf(c->name, sizeof c->name, "%s", name ? name : "pimodel");
    set_defaults(c);
    return c;
}

void fmi2FreeInstance(fmi2Component c) { free(c); }

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tolDef, fmi2Real tol, fmi2Real t0,
                               fmi2Boolean stopDef, fmi2Real tStop)
{
    (void)c; (void)tolDef; (void)tol; (void)t0; (void)stopDef; (void)tStop;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) { (void)c; return fmi2OK; }

fmi2Status fmi2ExitInitializationMode(fmi2Component comp)
{
    Inst *c = (Inst *)comp;
    fmi2Status st = setup(c);
    c->failed = st != fmi2OK;
    c->initialized = st == fmi2OK;
    return st;
}

fmi2Status fmi2Terminate(fmi2Component c) { (void)c; return fmi2OK; }

fmi2Status fmi2Reset(fmi2Component comp)
{
    Inst *c = (Inst *)comp;
    set_defaults(c);
    return fmi2OK;
}

static double *real_ref(Inst *c, fmi2ValueReference vr)
{
    switch (vr) {
    case 0: return &c->Ts;
    case 2: return &c->z0;
    case 4: return &c->gain;
    case 6: return &c->guard;
    case 10: return &c->in1;
    case 11: return &c->out1;
    case 12: return &c->in2;
    case 13: return &c->out2;
    default: break;
    }
    if (vr >= 100 && vr < 100 + NMAX) return &c->p[vr - 100];
    if (vr >= 200 && vr < 200 + NMAX) return &c->r[vr - 200];
#if PIM_MODEL == 2
    if (vr >= 300 && vr < 300 + NMAX) return &c->rhat_out[vr - 300];
#else
    if (vr >= 300 && vr < 300 + NMAX) return &c->rhat_in[vr - 300];
#endif
    return NULL;
}

fmi2Status fmi2GetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[])
{
    Inst *c = (Inst *)comp;
    for (size_t i = 0; i < nvr; ++i) {
        double *x = real_ref(c, vr[i]);
        if (!x) {
            logmsg(c, fmi2Error, "logStatusError", "no Real variable with reference %u", vr[i]);
            return fmi2Error;
        }
        value[i] = *x;
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[])
{
    Inst *c = (Inst *)comp;
    for (size_t i = 0; i < nvr; ++i) {
        double *x = real_ref(c, vr[i]);
        if (!x || vr[i] == 11 || vr[i] == 13 || (PIM_MODEL == 2 && vr[i] >= 300)) {
            logmsg(c, fmi2Error, "logStatusError", "cannot set Real variable %u", vr[i]);
            return fmi2Error;
        }
        if (c->initialized && vr[i] < 10) {
            logmsg(c, fmi2Error, "logStatusError", "parameter %u is fixed after initialization",
                   vr[i]);
            return fmi2Error;
        }
        *x = value[i];
    }
    return fmi2OK;
}

static int *int_ref(Inst *c, fmi2ValueReference vr)
{
    if (vr == 1) return &c->n;
    if (vr == 7) return &c->slope_window;
    return NULL;
}

fmi2Status fmi2GetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[])
{
    Inst *c = (Inst *)comp;
    for (size_t i = 0; i < nvr; ++i) {
        int *x = int_ref(c, vr[i]);
        if (!x) return fail(c, "no Integer variable %s", "with this reference");
        value[i] = *x;
    }
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[])
{
    Inst *c = (Inst *)comp;
    for (size_t i = 0; i < nvr; ++i) {
        int *x = int_ref(c, vr[i]);
        if (!x) return fail(c, "no Integer variable %s", "with this reference");
        if (c->initialized) return fail(c, "parameter %s is fixed after initialization", "n");
        *x = value[i];
    }
    return fmi2OK;
}

static int *bool_ref(Inst *c, fmi2ValueReference vr)
{
    if (vr == 3) return &c->adaptive;
    if (vr == 5) return &c->known_linear;
    return NULL;
}

fmi2Status fmi2GetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[])
{
    Inst *c = (Inst *)comp;
    for (size_t i = 0; i < nvr; ++i) {
        int *x = bool_ref(c, vr[i]);
        if (!x) return fail(c, "no Boolean variable %s", "with this reference");
        value[i] = *x ? fmi2True : fmi2False;
    }
    return fmi2OK;
}

fmi2Status fmi2SetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[])
{
    Inst *c = (Inst *)comp;
    for (size_t i = 0; i < nvr; ++i) {
        int *x = bool_ref(c, vr[i]);
        if (!x) return fail(c, "no Boolean variable %s", "with this reference");
        if (c->initialized) return fail(c, "parameter %s is fixed after initialization", "flag");
        *x = value[i] ? 1 : 0;
    }
    return fmi2OK;
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[])
{
    (void)vr; (void)value;
    return nvr ? fail((Inst *)c, "no String variables %s", "") : fmi2OK;
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[])
{
    (void)vr; (void)value;
    return nvr ? fail((Inst *)c, "no String variables %s", "") : fmi2OK;
}

fmi2Status fmi2GetFMUstate(fmi2Component comp, fmi2FMUstate *state)
{
    Inst *c = (Inst *)comp;
    Inst *copy = *state ? (Inst *)*state : (Inst *)malloc(sizeof(Inst));
    if (!copy) return fail(c, "%s", "out of memory");
    memcpy(copy, c, sizeof(Inst));
    *state = copy;
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component comp, fmi2FMUstate state)
{
    Inst *c = (Inst *)comp;
    if (!state) return fail(c, "%s", "null FMU state");
    fmi2CallbackFunctions cb = c->cb;
    memcpy(c, state, sizeof(Inst));
    c->cb = cb;
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state)
{
    (void)c;
    if (state && *state) {
        free(*state);
        *state = NULL;
    }
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *size)
{
    (void)c; (void)s;
    *size = sizeof(Inst);
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte bytes[], size_t size)
{
    if (size < sizeof(Inst)) return fail((Inst *)c, "%s", "serialization buffer too small");
    memcpy(bytes, s, sizeof(Inst));
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size,
                                   fmi2FMUstate *s)
{
    if (size != sizeof(Inst)) return fail((Inst *)c, "%s", "serialized state has a wrong size");
    Inst *copy = (Inst *)malloc(sizeof(Inst));
    if (!copy) return fail((Inst *)c, "%s", "out of memory");
    memcpy(copy, bytes, sizeof(Inst));
    *s = copy;
    return fmi2OK;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu,
                                        const fmi2ValueReference z[], size_t nz,
                                        const fmi2Real dv[], fmi2Real dz[])
{
    (void)u; (void)nu; (void)z; (void)nz; (void)dv; (void)dz;
    return fail((Inst *)c, "%s", "directional derivatives are not provided");
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                       const fmi2Integer order[], const fmi2Real value[])
{
    (void)vr; (void)n; (void)order; (void)value;
    return fail((Inst *)c, "%s", "input derivatives are not supported");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                        const fmi2Integer order[], fmi2Real value[])
{
    (void)vr; (void)n; (void)order; (void)value;
    return fail((Inst *)c, "%s", "output derivatives are not provided");
}

fmi2Status fmi2DoStep(fmi2Component comp, fmi2Real t, fmi2Real h, fmi2Boolean noSetPrior)
{
    Inst *c = (Inst *)comp;
    (void)noSetPrior;
    if (!c->initialized) return fail(c, "%s", "doStep before a successful initialization");
    if (!(h >= 0.0) || !isfinite(t)) return fail(c, "%s", "invalid communication step");
    const double tol = 1e-9;
    const double k0 = ceil(t / c->Ts - tol), k1 = ceil((t + h) / c->Ts - tol);
    for (double k = k0; k < k1; k += 1.0) {
        fmi2Status st = sample(c);
        if (st != fmi2OK) return st;
    }
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component c) { (void)c; return fmi2Error; }

static fmi2Status no_status(fmi2Component c)
{
    return fail((Inst *)c, "%s", "asynchronous status is not supported");
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *v)
{
    (void)s; (void)v;
    return no_status(c);
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *v)
{
    (void)s; (void)v;
    return no_status(c);
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *v)
{
    (void)s; (void)v;
    return no_status(c);
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *v)
{
    (void)s; (void)v;
    return no_status(c);
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *v)
{
    (void)s; (void)v;
    return no_status(c);
}
