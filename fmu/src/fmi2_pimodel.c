/*
 * FMI 2.0 Co-Simulation glue for the pimodel units (pim_unit.h), one source for the three
 * models; the including file defines PIM_MODEL (1 PIHysteresis, 2 RadiusEstimator,
 * 3 InversePI) and PIM_MODEL_GUID.  Sampling rule and value references: pim_unit.h (array
 * element p[i+1] has reference 100 + i, r[i+1] 200 + i, r_hat[i+1] 300 + i).
 */
#include <stdlib.h>

#include "fmi2Functions.h"
#include "pim_unit.h"

typedef struct {
    pim_unit u;
    fmi2CallbackFunctions cb;
    char name[128];
    int initialized;
} Inst;

static void logmsg(Inst *c, fmi2Status st, const char *msg)
{
    /* the message is passed as is (hosts such as fmpy's Python callback do not expand printf
     * arguments); pim_unit removes '%' so that it is a safe format string too */
    if (c && c->cb.logger) c->cb.logger(c->cb.componentEnvironment, c->name, st,
                                        "logStatusError", msg);
}

static fmi2Status fail(Inst *c, const char *fmt, const char *detail)
{
    unit_error(&c->u, fmt, detail);
    logmsg(c, fmi2Error, c->u.msg);
    return fmi2Error;
}

/* Logs the unit's failure reason when rc != 0. */
static fmi2Status status(Inst *c, int rc)
{
    if (rc == 0) return fmi2OK;
    logmsg(c, fmi2Error, c->u.msg);
    return fmi2Error;
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
    unit_defaults(&c->u);
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
    fmi2Status st = status(c, unit_setup(&c->u));
    c->initialized = st == fmi2OK;
    return st;
}

fmi2Status fmi2Terminate(fmi2Component c) { (void)c; return fmi2OK; }

fmi2Status fmi2Reset(fmi2Component comp)
{
    Inst *c = (Inst *)comp;
    unit_defaults(&c->u);
    c->initialized = 0;
    return fmi2OK;
}

static double *real_ref(Inst *c, fmi2ValueReference vr)
{
    double *x = unit_scalar(&c->u, vr);
    if (x) return x;
    for (unsigned base = 100; base <= 300; base += 100)
        if (vr >= base && vr < base + NMAX) return unit_array(&c->u, base) + (vr - base);
    return NULL;
}

fmi2Status fmi2GetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[])
{
    Inst *c = (Inst *)comp;
    for (size_t i = 0; i < nvr; ++i) {
        double *x = real_ref(c, vr[i]);
        if (!x) return status(c, unit_error(&c->u, "no Real variable with reference %u", vr[i]));
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
        if (!x || !unit_settable(vr[i], c->initialized))
            return status(c, unit_error(&c->u, "cannot set Real variable %u (an output, or a "
                                               "parameter after initialization)", vr[i]));
        *x = value[i];
    }
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[])
{
    Inst *c = (Inst *)comp;
    for (size_t i = 0; i < nvr; ++i) {
        int *x = unit_int(&c->u, vr[i]);
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
        int *x = unit_int(&c->u, vr[i]);
        if (!x) return fail(c, "no Integer variable %s", "with this reference");
        if (c->initialized) return fail(c, "parameter %s is fixed after initialization", "n");
        *x = value[i];
    }
    return fmi2OK;
}

fmi2Status fmi2GetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[])
{
    Inst *c = (Inst *)comp;
    for (size_t i = 0; i < nvr; ++i) {
        int *x = unit_bool(&c->u, vr[i]);
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
        int *x = unit_bool(&c->u, vr[i]);
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
    return status(c, unit_do_step(&c->u, t, h));
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
