/*
 * FMI 3.0 Co-Simulation glue for the pimodel units (pim_unit.h), one source for the three
 * models; the including file defines PIM_MODEL (1 PIHysteresis, 2 RadiusEstimator,
 * 3 InversePI) and PIM_MODEL_TOKEN (the instantiation token).  Sampling rule and value
 * references: pim_unit.h.  Here p (100), r (200) and r_hat (300) are real arrays of NMAX
 * elements (the first n are used): getting or setting one moves NMAX values.  Reference 9 is
 * the independent variable time (the end of the last communication step).
 */
#include <stdlib.h>

#include "fmi3Functions.h"
#include "pim_unit.h"

typedef struct {
    pim_unit u;
    fmi3InstanceEnvironment env;
    fmi3LogMessageCallback log;
    int initialized;
    double time;
} Inst;

static fmi3Status status(Inst *c, int rc)
{
    if (rc == 0) return fmi3OK;
    if (c->log) c->log(c->env, fmi3Error, "logStatusError", c->u.msg);
    return fmi3Error;
}

static fmi3Status fail(Inst *c, const char *msg)
{
    return status(c, unit_error(&c->u, "%s", msg));
}

/* ---- creation, modes ------------------------------------------------------------------- */

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance c, fmi3Boolean on, size_t n, const fmi3String cats[])
{
    (void)c; (void)on; (void)n; (void)cats;
    return fmi3OK;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String name, fmi3String token, fmi3String res,
                                          fmi3Boolean visible, fmi3Boolean logging,
                                          fmi3InstanceEnvironment env, fmi3LogMessageCallback log)
{
    (void)name; (void)token; (void)res; (void)visible; (void)logging;
    if (log) log(env, fmi3Error, "logStatusError", "only Co-Simulation is provided");
    return NULL;
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String name, fmi3String token, fmi3String res,
                                         fmi3Boolean visible, fmi3Boolean logging,
                                         fmi3Boolean eventModeUsed, fmi3Boolean earlyReturn,
                                         const fmi3ValueReference required[], size_t nRequired,
                                         fmi3InstanceEnvironment env, fmi3LogMessageCallback log,
                                         fmi3IntermediateUpdateCallback update)
{
    (void)name; (void)res; (void)visible; (void)logging; (void)earlyReturn; (void)required;
    (void)nRequired; (void)update;
    if (token && strcmp(token, PIM_MODEL_TOKEN) != 0) {
        if (log) log(env, fmi3Error, "logStatusError",
                     "instantiation token mismatch: the FMU was built for another model "
                     "description");
        return NULL;
    }
    if (eventModeUsed) {
        if (log) log(env, fmi3Error, "logStatusError", "event mode is not supported");
        return NULL;
    }
    Inst *c = (Inst *)calloc(1, sizeof(Inst));
    if (!c) return NULL;
    c->env = env;
    c->log = log;
    unit_defaults(&c->u);
    return c;
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String name, fmi3String token, fmi3String res,
                                               fmi3Boolean visible, fmi3Boolean logging,
                                               fmi3InstanceEnvironment env,
                                               fmi3LogMessageCallback log,
                                               fmi3ClockUpdateCallback clock,
                                               fmi3LockPreemptionCallback lock,
                                               fmi3UnlockPreemptionCallback unlock)
{
    (void)name; (void)token; (void)res; (void)visible; (void)logging; (void)clock; (void)lock;
    (void)unlock;
    if (log) log(env, fmi3Error, "logStatusError", "only Co-Simulation is provided");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance c) { free(c); }

fmi3Status fmi3EnterInitializationMode(fmi3Instance c, fmi3Boolean tolDef, fmi3Float64 tol,
                                       fmi3Float64 t0, fmi3Boolean stopDef, fmi3Float64 tStop)
{
    (void)tolDef; (void)tol; (void)stopDef; (void)tStop;
    ((Inst *)c)->time = t0;
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance inst)
{
    Inst *c = (Inst *)inst;
    fmi3Status st = status(c, unit_setup(&c->u));
    c->initialized = st == fmi3OK;
    return st;
}

fmi3Status fmi3EnterEventMode(fmi3Instance c) { return fail((Inst *)c, "no event mode"); }
fmi3Status fmi3Terminate(fmi3Instance c) { (void)c; return fmi3OK; }

fmi3Status fmi3Reset(fmi3Instance inst)
{
    Inst *c = (Inst *)inst;
    unit_defaults(&c->u);
    c->initialized = 0;
    return fmi3OK;
}

fmi3Status fmi3EnterStepMode(fmi3Instance c) { (void)c; return fmi3OK; }

fmi3Status fmi3DoStep(fmi3Instance inst, fmi3Float64 t, fmi3Float64 h, fmi3Boolean noSetPrior,
                      fmi3Boolean *eventNeeded, fmi3Boolean *terminate, fmi3Boolean *earlyReturn,
                      fmi3Float64 *lastTime)
{
    Inst *c = (Inst *)inst;
    (void)noSetPrior;
    if (eventNeeded) *eventNeeded = fmi3False;
    if (terminate) *terminate = fmi3False;
    if (earlyReturn) *earlyReturn = fmi3False;
    if (lastTime) *lastTime = t;
    if (!c->initialized) return fail(c, "doStep before a successful initialization");
    fmi3Status st = status(c, unit_do_step(&c->u, t, h));
    if (st == fmi3OK) {
        c->time = t + h;
        if (lastTime) *lastTime = t + h;
    }
    return st;
}

/* ---- variables --------------------------------------------------------------------------- */

fmi3Status fmi3GetFloat64(fmi3Instance inst, const fmi3ValueReference vr[], size_t nvr,
                          fmi3Float64 values[], size_t nValues)
{
    Inst *c = (Inst *)inst;
    size_t k = 0;
    for (size_t i = 0; i < nvr; ++i) {
        double *x = vr[i] == 9 ? &c->time : unit_scalar(&c->u, vr[i]);
        double *a = x ? NULL : unit_array(&c->u, vr[i]);
        size_t m = x ? 1 : NMAX;
        if (!x && !a) return status(c, unit_error(&c->u, "no Float64 variable %u", vr[i]));
        if (k + m > nValues) return fail(c, "GetFloat64: nValues too small for the variables");
        memcpy(values + k, x ? x : a, m * sizeof(double));
        k += m;
    }
    return fmi3OK;
}

fmi3Status fmi3SetFloat64(fmi3Instance inst, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Float64 values[], size_t nValues)
{
    Inst *c = (Inst *)inst;
    size_t k = 0;
    for (size_t i = 0; i < nvr; ++i) {
        double *x = unit_scalar(&c->u, vr[i]);
        double *a = x ? NULL : unit_array(&c->u, vr[i]);
        size_t m = x ? 1 : NMAX;
        if ((!x && !a) || !unit_settable(vr[i], c->initialized))
            return status(c, unit_error(&c->u, "cannot set Float64 variable %u (an output, or "
                                               "a parameter after initialization)", vr[i]));
        if (k + m > nValues) return fail(c, "SetFloat64: nValues too small for the variables");
        memcpy(x ? x : a, values + k, m * sizeof(double));
        k += m;
    }
    return fmi3OK;
}

fmi3Status fmi3GetInt32(fmi3Instance inst, const fmi3ValueReference vr[], size_t nvr,
                        fmi3Int32 values[], size_t nValues)
{
    Inst *c = (Inst *)inst;
    if (nValues < nvr) return fail(c, "GetInt32: nValues too small");
    for (size_t i = 0; i < nvr; ++i) {
        int *x = unit_int(&c->u, vr[i]);
        if (!x) return status(c, unit_error(&c->u, "no Int32 variable %u", vr[i]));
        values[i] = *x;
    }
    return fmi3OK;
}

fmi3Status fmi3SetInt32(fmi3Instance inst, const fmi3ValueReference vr[], size_t nvr,
                        const fmi3Int32 values[], size_t nValues)
{
    Inst *c = (Inst *)inst;
    if (nValues < nvr) return fail(c, "SetInt32: nValues too small");
    for (size_t i = 0; i < nvr; ++i) {
        int *x = unit_int(&c->u, vr[i]);
        if (!x) return status(c, unit_error(&c->u, "no Int32 variable %u", vr[i]));
        if (c->initialized) return fail(c, "Int32 parameters are fixed after initialization");
        *x = values[i];
    }
    return fmi3OK;
}

fmi3Status fmi3GetBoolean(fmi3Instance inst, const fmi3ValueReference vr[], size_t nvr,
                          fmi3Boolean values[], size_t nValues)
{
    Inst *c = (Inst *)inst;
    if (nValues < nvr) return fail(c, "GetBoolean: nValues too small");
    for (size_t i = 0; i < nvr; ++i) {
        int *x = unit_bool(&c->u, vr[i]);
        if (!x) return status(c, unit_error(&c->u, "no Boolean variable %u", vr[i]));
        values[i] = *x ? fmi3True : fmi3False;
    }
    return fmi3OK;
}

fmi3Status fmi3SetBoolean(fmi3Instance inst, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Boolean values[], size_t nValues)
{
    Inst *c = (Inst *)inst;
    if (nValues < nvr) return fail(c, "SetBoolean: nValues too small");
    for (size_t i = 0; i < nvr; ++i) {
        int *x = unit_bool(&c->u, vr[i]);
        if (!x) return status(c, unit_error(&c->u, "no Boolean variable %u", vr[i]));
        if (c->initialized) return fail(c, "Boolean parameters are fixed after initialization");
        *x = values[i] ? 1 : 0;
    }
    return fmi3OK;
}

/* Types the units do not use: any access is an error (an empty access is fine). */
#define PIM_NO_TYPE(NAME, T, CONST)                                                           \
    fmi3Status fmi3Get##NAME(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,      \
                             T values[], size_t nValues)                                     \
    {                                                                                         \
        (void)vr; (void)values; (void)nValues;                                                \
        return nvr ? fail((Inst *)c, "no " #NAME " variables") : fmi3OK;                      \
    }                                                                                         \
    fmi3Status fmi3Set##NAME(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,      \
                             CONST T values[], size_t nValues)                               \
    {                                                                                         \
        (void)vr; (void)values; (void)nValues;                                                \
        return nvr ? fail((Inst *)c, "no " #NAME " variables") : fmi3OK;                      \
    }

PIM_NO_TYPE(Float32, fmi3Float32, const)
PIM_NO_TYPE(Int8, fmi3Int8, const)
PIM_NO_TYPE(UInt8, fmi3UInt8, const)
PIM_NO_TYPE(Int16, fmi3Int16, const)
PIM_NO_TYPE(UInt16, fmi3UInt16, const)
PIM_NO_TYPE(UInt32, fmi3UInt32, const)
PIM_NO_TYPE(Int64, fmi3Int64, const)
PIM_NO_TYPE(UInt64, fmi3UInt64, const)
PIM_NO_TYPE(String, fmi3String, const)

fmi3Status fmi3GetBinary(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                         size_t sizes[], fmi3Binary values[], size_t nValues)
{
    (void)vr; (void)sizes; (void)values; (void)nValues;
    return nvr ? fail((Inst *)c, "no Binary variables") : fmi3OK;
}

fmi3Status fmi3SetBinary(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                         const size_t sizes[], const fmi3Binary values[], size_t nValues)
{
    (void)vr; (void)sizes; (void)values; (void)nValues;
    return nvr ? fail((Inst *)c, "no Binary variables") : fmi3OK;
}

fmi3Status fmi3GetClock(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                        fmi3Clock values[])
{
    (void)vr; (void)values;
    return nvr ? fail((Inst *)c, "no Clock variables") : fmi3OK;
}

fmi3Status fmi3SetClock(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                        const fmi3Clock values[])
{
    (void)vr; (void)values;
    return nvr ? fail((Inst *)c, "no Clock variables") : fmi3OK;
}

/* ---- FMU state (rollback) ------------------------------------------------------------- */

fmi3Status fmi3GetFMUState(fmi3Instance inst, fmi3FMUState *state)
{
    Inst *c = (Inst *)inst;
    Inst *copy = *state ? (Inst *)*state : (Inst *)malloc(sizeof(Inst));
    if (!copy) return fail(c, "out of memory");
    memcpy(copy, c, sizeof(Inst));
    *state = copy;
    return fmi3OK;
}

fmi3Status fmi3SetFMUState(fmi3Instance inst, fmi3FMUState state)
{
    Inst *c = (Inst *)inst;
    if (!state) return fail(c, "null FMU state");
    const Inst *s = (const Inst *)state;
    c->u = s->u;
    c->initialized = s->initialized;
    return fmi3OK;
}

fmi3Status fmi3FreeFMUState(fmi3Instance c, fmi3FMUState *state)
{
    (void)c;
    if (state && *state) {
        free(*state);
        *state = NULL;
    }
    return fmi3OK;
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance c, fmi3FMUState s, size_t *size)
{
    (void)c; (void)s;
    *size = sizeof(Inst);
    return fmi3OK;
}

fmi3Status fmi3SerializeFMUState(fmi3Instance c, fmi3FMUState s, fmi3Byte bytes[], size_t size)
{
    if (size < sizeof(Inst)) return fail((Inst *)c, "serialization buffer too small");
    memcpy(bytes, s, sizeof(Inst));
    return fmi3OK;
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance c, const fmi3Byte bytes[], size_t size,
                                   fmi3FMUState *s)
{
    if (size != sizeof(Inst)) return fail((Inst *)c, "serialized state has a wrong size");
    Inst *copy = (Inst *)malloc(sizeof(Inst));
    if (!copy) return fail((Inst *)c, "out of memory");
    memcpy(copy, bytes, sizeof(Inst));
    *s = copy;
    return fmi3OK;
}

/* ---- not provided ------------------------------------------------------------------------ */

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance c, fmi3ValueReference vr, size_t *n)
{
    (void)vr; (void)n;
    return fail((Inst *)c, "variable dependencies are not provided");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance c, fmi3ValueReference dep, size_t ed[],
                                       fmi3ValueReference ind[], size_t ei[],
                                       fmi3DependencyKind kinds[], size_t n)
{
    (void)dep; (void)ed; (void)ind; (void)ei; (void)kinds; (void)n;
    return fail((Inst *)c, "variable dependencies are not provided");
}

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance c, const fmi3ValueReference u[], size_t nu,
                                        const fmi3ValueReference k[], size_t nk,
                                        const fmi3Float64 seed[], size_t ns,
                                        fmi3Float64 sens[], size_t nsens)
{
    (void)u; (void)nu; (void)k; (void)nk; (void)seed; (void)ns; (void)sens; (void)nsens;
    return fail((Inst *)c, "directional derivatives are not provided");
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance c, const fmi3ValueReference u[], size_t nu,
                                    const fmi3ValueReference k[], size_t nk,
                                    const fmi3Float64 seed[], size_t ns, fmi3Float64 sens[],
                                    size_t nsens)
{
    (void)u; (void)nu; (void)k; (void)nk; (void)seed; (void)ns; (void)sens; (void)nsens;
    return fail((Inst *)c, "adjoint derivatives are not provided");
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance c)
{
    return fail((Inst *)c, "no structural parameters");
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance c)
{
    return fail((Inst *)c, "no structural parameters");
}

fmi3Status fmi3GetIntervalDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t n,
                                  fmi3Float64 iv[], fmi3IntervalQualifier q[])
{
    (void)vr; (void)n; (void)iv; (void)q;
    return fail((Inst *)c, "no clocks");
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t n,
                                   fmi3UInt64 cnt[], fmi3UInt64 res[], fmi3IntervalQualifier q[])
{
    (void)vr; (void)n; (void)cnt; (void)res; (void)q;
    return fail((Inst *)c, "no clocks");
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t n,
                               fmi3Float64 s[])
{
    (void)vr; (void)n; (void)s;
    return fail((Inst *)c, "no clocks");
}

fmi3Status fmi3GetShiftFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t n,
                                fmi3UInt64 cnt[], fmi3UInt64 res[])
{
    (void)vr; (void)n; (void)cnt; (void)res;
    return fail((Inst *)c, "no clocks");
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t n,
                                  const fmi3Float64 iv[])
{
    (void)vr; (void)n; (void)iv;
    return fail((Inst *)c, "no clocks");
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t n,
                                   const fmi3UInt64 cnt[], const fmi3UInt64 res[])
{
    (void)vr; (void)n; (void)cnt; (void)res;
    return fail((Inst *)c, "no clocks");
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t n,
                               const fmi3Float64 s[])
{
    (void)vr; (void)n; (void)s;
    return fail((Inst *)c, "no clocks");
}

fmi3Status fmi3SetShiftFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t n,
                                const fmi3UInt64 cnt[], const fmi3UInt64 res[])
{
    (void)vr; (void)n; (void)cnt; (void)res;
    return fail((Inst *)c, "no clocks");
}

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance c) { (void)c; return fmi3OK; }

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance c, fmi3Boolean *needUpdate,
                                    fmi3Boolean *terminate, fmi3Boolean *nominalsChanged,
                                    fmi3Boolean *valuesChanged, fmi3Boolean *nextDefined,
                                    fmi3Float64 *nextTime)
{
    (void)c;
    *needUpdate = fmi3False;
    *terminate = fmi3False;
    *nominalsChanged = fmi3False;
    *valuesChanged = fmi3False;
    *nextDefined = fmi3False;
    *nextTime = 0.0;
    return fmi3OK;
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                    const fmi3Int32 orders[], fmi3Float64 values[],
                                    size_t nValues)
{
    (void)vr; (void)nvr; (void)orders; (void)values; (void)nValues;
    return fail((Inst *)c, "output derivatives are not provided");
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance c, fmi3ValueReference clock, fmi3Float64 t)
{
    (void)clock; (void)t;
    return fail((Inst *)c, "only Co-Simulation is provided");
}

/* Model Exchange is not provided; the functions exist for hosts that load every symbol. */
static fmi3Status no_me(fmi3Instance c) { return fail((Inst *)c, "no Model Exchange"); }

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance c) { return no_me(c); }

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance c, fmi3Boolean noSetPrior,
                                       fmi3Boolean *enterEvent, fmi3Boolean *terminate)
{
    (void)noSetPrior; (void)enterEvent; (void)terminate;
    return no_me(c);
}

fmi3Status fmi3SetTime(fmi3Instance c, fmi3Float64 t)
{
    (void)t;
    return no_me(c);
}

fmi3Status fmi3SetContinuousStates(fmi3Instance c, const fmi3Float64 x[], size_t n)
{
    (void)x; (void)n;
    return no_me(c);
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance c, fmi3Float64 dx[], size_t n)
{
    (void)dx; (void)n;
    return no_me(c);
}

fmi3Status fmi3GetEventIndicators(fmi3Instance c, fmi3Float64 ind[], size_t n)
{
    (void)ind; (void)n;
    return no_me(c);
}

fmi3Status fmi3GetContinuousStates(fmi3Instance c, fmi3Float64 x[], size_t n)
{
    (void)x; (void)n;
    return no_me(c);
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance c, fmi3Float64 nom[], size_t n)
{
    (void)nom; (void)n;
    return no_me(c);
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance c, size_t *n)
{
    (void)c;
    *n = 0;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance c, size_t *n)
{
    (void)c;
    *n = 0;
    return fmi3OK;
}
