/*
 * FMI 2.0 Co-Simulation glue for the pimodel units (pim_unit.h), one source for every unit,
 * without unit-specific code; the including model.c includes the unit's config.h first
 * (PIM_MODEL, PIM_MODEL_GUID, the variables).  Sampling rule, limits, modes, value references
 * and the FMU state format: pim_unit.h (array element p[i+1] has reference 100 + i, r[i+1]
 * 200 + i, r_hat[i+1] 300 + i).  Every failure returns fmi2Error and logs the reason.
 */
#include <stdlib.h>

#include "fmi2Functions.h"
#include "pim_unit.h"

typedef struct {
    pim_unit u;
    fmi2CallbackFunctions cb;
    char name[128];
} Inst;

static void logmsg(Inst *c, fmi2Status st, const char *msg)
{
    /* the message is passed as is (hosts such as fmpy's Python callback do not expand printf
     * arguments); pim_unit removes '%' so that it is a safe format string too */
    if (c && c->cb.logger) c->cb.logger(c->cb.componentEnvironment, c->name, st,
                                        "logStatusError", msg);
}

/* Logs the unit's failure reason when rc != 0. */
static fmi2Status status(Inst *c, int rc)
{
    if (rc == 0) return fmi2OK;
    logmsg(c, fmi2Error, c->u.msg);
    return fmi2Error;
}

static fmi2Status fail(Inst *c, const char *msg)
{
    if (!c) return fmi2Error;
    return status(c, unit_error(&c->u, "%s", msg));
}

#define INST(comp) Inst *c = (Inst *)(comp); if (!c) return fmi2Error
#define IN_MODES(mask, call) \
    if (unit_require_mode(&c->u, (mask), (call)) != 0) return status(c, -1)

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
    Inst *c = (Inst *)unit_alloc(sizeof(Inst));
    if (!c) {
        if (cb->logger)
            cb->logger(cb->componentEnvironment, name, fmi2Error, "logStatusError",
                       "out of memory (or memory not 16-byte aligned)");
        return NULL;
    }
    c->cb = *cb;
    snprintf(c->name, sizeof c->name, "%s", name ? name : "pimodel");
    unit_defaults(&c->u);
    return c;
}

void fmi2FreeInstance(fmi2Component c) { free(c); }

fmi2Status fmi2SetupExperiment(fmi2Component comp, fmi2Boolean tolDef, fmi2Real tol,
                               fmi2Real t0, fmi2Boolean stopDef, fmi2Real tStop)
{
    INST(comp);
    (void)tolDef; (void)tol;
    IN_MODES(PIM_IN(PIM_INSTANTIATED), "fmi2SetupExperiment");
    return status(c, unit_start(&c->u, t0, stopDef, tStop));
}

fmi2Status fmi2EnterInitializationMode(fmi2Component comp)
{
    INST(comp);
    IN_MODES(PIM_IN(PIM_INSTANTIATED), "fmi2EnterInitializationMode");
    unit_set_mode(&c->u, PIM_INIT_MODE);
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component comp)
{
    INST(comp);
    IN_MODES(PIM_IN(PIM_INIT_MODE), "fmi2ExitInitializationMode");
    fmi2Status st = status(c, unit_setup(&c->u));
    if (st == fmi2OK) unit_set_mode(&c->u, PIM_STEP_MODE);
    return st;
}

fmi2Status fmi2Terminate(fmi2Component comp)
{
    INST(comp);
    IN_MODES(PIM_IN(PIM_INIT_MODE) | PIM_IN(PIM_STEP_MODE) | PIM_IN(PIM_TERMINATED),
             "fmi2Terminate");
    /* the unit's report (RadiusEstimator: the estimate's health), once, as a warning
     * (category logStatusWarning) */
    char report[4096];
    if (unit_terminate_report(&c->u, report, sizeof report) && c->cb.logger)
        c->cb.logger(c->cb.componentEnvironment, c->name, fmi2Warning, "logStatusWarning",
                     report);
    unit_set_mode(&c->u, PIM_TERMINATED);
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component comp)
{
    INST(comp);
    unit_defaults(&c->u);
    return fmi2OK;
}

/* Get (set = 0) or set values of one type through unit_ref (FMI 2: scalars and elements). */
#define PIM_ACCESS(TYPE_CHAR, CTYPE, SET, FROM_UNIT, TO_UNIT)                                  \
    INST(comp);                                                                               \
    for (size_t i = 0; i < nvr; ++i) {                                                        \
        size_t cnt = 0;                                                                       \
        CTYPE *x = (CTYPE *)unit_ref(&c->u, vr[i], TYPE_CHAR, 1, SET, &cnt);                  \
        if (!x) return status(c, -1);                                                         \
        if (SET) { TO_UNIT; } else { FROM_UNIT; }                                             \
    }                                                                                         \
    return fmi2OK

/* The Real accessors: one value of the main input or output (unit_main_real, what a master
 * moves every step) straight to its storage, all else through unit_ref, out of line so that
 * the fast path saves no registers. */
PIM_NOINLINE static fmi2Status get_reals(fmi2Component comp, const fmi2ValueReference vr[],
                                         size_t nvr, fmi2Real value[])
{
    PIM_ACCESS('R', double, 0, value[i] = *x, (void)0);
}

PIM_NOINLINE static fmi2Status set_reals(fmi2Component comp, const fmi2ValueReference vr[],
                                         size_t nvr, const fmi2Real value[])
{
    PIM_ACCESS('R', double, 1, (void)0, *x = value[i]);
}

fmi2Status fmi2GetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[])
{
    const double *x = comp && nvr == 1 ? unit_main_real(&((Inst *)comp)->u, vr[0], 0) : NULL;
    if (!x) return get_reals(comp, vr, nvr, value);
    unit_copy_real(value, x);
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[])
{
    double *x = comp && nvr == 1 ? unit_main_real(&((Inst *)comp)->u, vr[0], 1) : NULL;
    if (!x) return set_reals(comp, vr, nvr, value);
    unit_copy_real(x, value);
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[])
{
    PIM_ACCESS('I', int, 0, value[i] = *x, (void)0);
}

fmi2Status fmi2SetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[])
{
    PIM_ACCESS('I', int, 1, (void)0, *x = value[i]);
}

fmi2Status fmi2GetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[])
{
    PIM_ACCESS('B', int, 0, value[i] = *x ? fmi2True : fmi2False, (void)0);
}

fmi2Status fmi2SetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[])
{
    PIM_ACCESS('B', int, 1, (void)0, *x = value[i] ? 1 : 0);
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[])
{
    (void)vr; (void)value;
    return nvr ? fail((Inst *)c, "no String variables") : fmi2OK;
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[])
{
    (void)vr; (void)value;
    return nvr ? fail((Inst *)c, "no String variables") : fmi2OK;
}

/* ---- FMU state: the checked byte block of pim_unit.h, in memory and serialized ------------ */

fmi2Status fmi2GetFMUstate(fmi2Component comp, fmi2FMUstate *state)
{
    INST(comp);
    if (!state) return fail(c, "fmi2GetFMUstate: null state pointer");
    unsigned char *buf = *state ? (unsigned char *)*state : (unsigned char *)malloc(PIM_STATE_SIZE);
    if (!buf) return fail(c, "fmi2GetFMUstate: out of memory");
    unit_state_write(&c->u, buf, PIM_MODEL_GUID, 2);
    *state = buf;
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component comp, fmi2FMUstate state)
{
    INST(comp);
    return status(c, unit_state_read(&c->u, (const unsigned char *)state, PIM_STATE_SIZE,
                                     PIM_MODEL_GUID, 2, &c->u));
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

fmi2Status fmi2SerializedFMUstateSize(fmi2Component comp, fmi2FMUstate s, size_t *size)
{
    INST(comp);
    (void)s;
    if (!size) return fail(c, "fmi2SerializedFMUstateSize: null size pointer");
    *size = PIM_STATE_SIZE;
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component comp, fmi2FMUstate s, fmi2Byte bytes[],
                                 size_t size)
{
    INST(comp);
    if (!s || !bytes) return fail(c, "fmi2SerializeFMUstate: null state or buffer");
    if (size < PIM_STATE_SIZE) return fail(c, "fmi2SerializeFMUstate: buffer too small");
    memcpy(bytes, s, PIM_STATE_SIZE);
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component comp, const fmi2Byte bytes[], size_t size,
                                   fmi2FMUstate *s)
{
    INST(comp);
    if (!s) return fail(c, "fmi2DeSerializeFMUstate: null state pointer");
    if (unit_state_read(&c->u, (const unsigned char *)bytes, size, PIM_MODEL_GUID, 2, NULL))
        return status(c, -1);
    unsigned char *copy = (unsigned char *)malloc(PIM_STATE_SIZE);
    if (!copy) return fail(c, "fmi2DeSerializeFMUstate: out of memory");
    memcpy(copy, bytes, PIM_STATE_SIZE);
    *s = copy;
    return fmi2OK;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu,
                                        const fmi2ValueReference z[], size_t nz,
                                        const fmi2Real dv[], fmi2Real dz[])
{
    (void)u; (void)nu; (void)z; (void)nz; (void)dv; (void)dz;
    return fail((Inst *)c, "directional derivatives are not provided");
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                       const fmi2Integer order[], const fmi2Real value[])
{
    (void)vr; (void)n; (void)order; (void)value;
    return fail((Inst *)c, "input derivatives are not supported");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                        const fmi2Integer order[], fmi2Real value[])
{
    (void)vr; (void)n; (void)order; (void)value;
    return fail((Inst *)c, "output derivatives are not provided");
}

/* doStep's general path, out of line so that the one-sample fast path needs no stack frame. */
PIM_NOINLINE static fmi2Status do_step_general(Inst *c, fmi2Real t, fmi2Real h)
{
    return status(c, unit_do_step_general(&c->u, t, h));
}

fmi2Status fmi2DoStep(fmi2Component comp, fmi2Real t, fmi2Real h, fmi2Boolean noSetPrior)
{
    INST(comp);
    (void)noSetPrior;
    return unit_one_sample(&c->u, t, h) ? fmi2OK : do_step_general(c, t, h);
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
    return fail((Inst *)c, "fmi2CancelStep: steps are never asynchronous");
}

static fmi2Status no_status(fmi2Component c)
{
    return fail((Inst *)c, "asynchronous status is not supported");
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
