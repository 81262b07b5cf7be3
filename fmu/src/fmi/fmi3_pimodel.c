/*
 * FMI 3.0 Co-Simulation glue for the pimodel units (pim_unit.h), one source for every unit,
 * without unit-specific code; the including model.c includes the unit's config.h first
 * (PIM_MODEL, PIM_MODEL_TOKEN the instantiation token, the variables).  Sampling rule and value
 * references, limits, modes and the FMU state format: pim_unit.h.  Here the per-play arrays
 * (p 100, r 200, r_hat 300, ...) have n_plays elements, the UInt64 structural parameter set in
 * configuration mode (default PIM_NMAX; the first n are used), the others PIM_NMAX: getting or
 * setting one moves all its values.  Reference 9 is the independent variable time (the end of
 * the last communication step).  Every failure returns fmi3Error and logs the reason.
 */
#include <stdlib.h>

#include "fmi3Functions.h"
#include "pim_unit.h"

typedef struct {
    pim_unit u;
    fmi3InstanceEnvironment env;
    fmi3LogMessageCallback log;
} Inst;

static fmi3Status status(Inst *c, int rc)
{
    if (rc == 0) return fmi3OK;
    if (c->log) c->log(c->env, fmi3Error, "logStatusError", c->u.msg);
    return fmi3Error;
}

static fmi3Status fail(Inst *c, const char *msg)
{
    if (!c) return fmi3Error;
    return status(c, unit_error(&c->u, "%s", msg));
}

#define INST(inst) Inst *c = (Inst *)(inst); if (!c) return fmi3Error
#define IN_MODES(mask, call) \
    if (unit_require_mode(&c->u, (mask), (call)) != 0) return status(c, -1)

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
    Inst *c = (Inst *)unit_alloc(sizeof(Inst));
    if (!c) {
        if (log) log(env, fmi3Error, "logStatusError",
                     "out of memory (or memory not 16-byte aligned)");
        return NULL;
    }
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

fmi3Status fmi3EnterInitializationMode(fmi3Instance inst, fmi3Boolean tolDef, fmi3Float64 tol,
                                       fmi3Float64 t0, fmi3Boolean stopDef, fmi3Float64 tStop)
{
    INST(inst);
    (void)tolDef; (void)tol;
    IN_MODES(PIM_IN(PIM_INSTANTIATED), "fmi3EnterInitializationMode");
    if (unit_start(&c->u, t0, stopDef, tStop) != 0) return status(c, -1);
    unit_set_mode(&c->u, PIM_INIT_MODE);
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance inst)
{
    INST(inst);
    IN_MODES(PIM_IN(PIM_INIT_MODE), "fmi3ExitInitializationMode");
    fmi3Status st = status(c, unit_setup(&c->u));
    if (st == fmi3OK) unit_set_mode(&c->u, PIM_STEP_MODE);
    return st;
}

fmi3Status fmi3EnterEventMode(fmi3Instance c) { return fail((Inst *)c, "no event mode"); }

fmi3Status fmi3Terminate(fmi3Instance inst)
{
    INST(inst);
    IN_MODES(PIM_IN(PIM_INIT_MODE) | PIM_IN(PIM_STEP_MODE) | PIM_IN(PIM_TERMINATED),
             "fmi3Terminate");
    /* the unit's report (RadiusEstimator: the estimate's health), once, as a warning
     * (category logStatusWarning) */
    char report[4096];
    if (unit_terminate_report(&c->u, report, sizeof report) && c->log)
        c->log(c->env, fmi3Warning, "logStatusWarning", report);
    unit_set_mode(&c->u, PIM_TERMINATED);
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance inst)
{
    INST(inst);
    unit_defaults(&c->u);
    return fmi3OK;
}

fmi3Status fmi3EnterStepMode(fmi3Instance inst)
{
    INST(inst);
    IN_MODES(PIM_IN(PIM_STEP_MODE), "fmi3EnterStepMode");
    return fmi3OK;
}

fmi3Status fmi3DoStep(fmi3Instance inst, fmi3Float64 t, fmi3Float64 h, fmi3Boolean noSetPrior,
                      fmi3Boolean *eventNeeded, fmi3Boolean *terminate, fmi3Boolean *earlyReturn,
                      fmi3Float64 *lastTime)
{
    INST(inst);
    (void)noSetPrior;
    if (eventNeeded) *eventNeeded = fmi3False;
    if (terminate) *terminate = fmi3False;
    if (earlyReturn) *earlyReturn = fmi3False;
    fmi3Status st = status(c, unit_do_step(&c->u, t, h));
    if (lastTime) *lastTime = c->u.time;
    return st;
}

/* ---- variables --------------------------------------------------------------------------- */

/* Get (SET 0) or set (SET 1) values of one type through unit_ref; an FMI 3 array moves all
 * its values (n_plays or PIM_NMAX). */
#define PIM_ACCESS(TYPE_CHAR, CTYPE, SET, FROM_UNIT, TO_UNIT)                                  \
    INST(inst);                                                                               \
    size_t k = 0;                                                                             \
    for (size_t i = 0; i < nvr; ++i) {                                                        \
        size_t cnt = 0;                                                                       \
        CTYPE *x = (CTYPE *)unit_ref(&c->u, vr[i], TYPE_CHAR, 0, SET, &cnt);                  \
        if (!x) return status(c, -1);                                                         \
        if (k + cnt > nValues)                                                                \
            return status(c, unit_error(&c->u, "nValues = %llu is too small: at least %llu " \
                                        "values needed (an array moves all its values)",      \
                                        (unsigned long long)nValues,                          \
                                        (unsigned long long)(k + cnt)));                      \
        for (size_t j = 0; j < cnt; ++j, ++k) {                                               \
            if (SET) { TO_UNIT; } else { FROM_UNIT; }                                         \
        }                                                                                     \
    }                                                                                         \
    return fmi3OK

/* The Float64 accessors: one value of the main input or output (unit_main_real, what a master
 * moves every step) straight to its storage, all else through unit_ref, out of line so that
 * the fast path saves no registers. */
PIM_NOINLINE static fmi3Status get_float64s(fmi3Instance inst, const fmi3ValueReference vr[],
                                            size_t nvr, fmi3Float64 values[], size_t nValues)
{
    PIM_ACCESS('R', double, 0, values[k] = x[j], (void)0);
}

PIM_NOINLINE static fmi3Status set_float64s(fmi3Instance inst, const fmi3ValueReference vr[],
                                            size_t nvr, const fmi3Float64 values[],
                                            size_t nValues)
{
    PIM_ACCESS('R', double, 1, (void)0, x[j] = values[k]);
}

fmi3Status fmi3GetFloat64(fmi3Instance inst, const fmi3ValueReference vr[], size_t nvr,
                          fmi3Float64 values[], size_t nValues)
{
    const double *x = inst && nvr == 1 && nValues >= 1
                          ? unit_main_real(&((Inst *)inst)->u, vr[0], 0)
                          : NULL;
    if (!x) return get_float64s(inst, vr, nvr, values, nValues);
    unit_copy_real(values, x);
    return fmi3OK;
}

fmi3Status fmi3SetFloat64(fmi3Instance inst, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Float64 values[], size_t nValues)
{
    double *x = inst && nvr == 1 && nValues >= 1 ? unit_main_real(&((Inst *)inst)->u, vr[0], 1)
                                                 : NULL;
    if (!x) return set_float64s(inst, vr, nvr, values, nValues);
    unit_copy_real(x, values);
    return fmi3OK;
}

fmi3Status fmi3GetInt32(fmi3Instance inst, const fmi3ValueReference vr[], size_t nvr,
                        fmi3Int32 values[], size_t nValues)
{
    PIM_ACCESS('I', int, 0, values[k] = x[j], (void)0);
}

fmi3Status fmi3SetInt32(fmi3Instance inst, const fmi3ValueReference vr[], size_t nvr,
                        const fmi3Int32 values[], size_t nValues)
{
    PIM_ACCESS('I', int, 1, (void)0, x[j] = values[k]);
}

fmi3Status fmi3GetBoolean(fmi3Instance inst, const fmi3ValueReference vr[], size_t nvr,
                          fmi3Boolean values[], size_t nValues)
{
    PIM_ACCESS('B', int, 0, values[k] = x[j] ? fmi3True : fmi3False, (void)0);
}

fmi3Status fmi3SetBoolean(fmi3Instance inst, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Boolean values[], size_t nValues)
{
    PIM_ACCESS('B', int, 1, (void)0, x[j] = values[k] ? 1 : 0);
}

fmi3Status fmi3GetUInt64(fmi3Instance inst, const fmi3ValueReference vr[], size_t nvr,
                         fmi3UInt64 values[], size_t nValues)
{
    PIM_ACCESS('U', uint64_t, 0, values[k] = x[j], (void)0);
}

fmi3Status fmi3SetUInt64(fmi3Instance inst, const fmi3ValueReference vr[], size_t nvr,
                         const fmi3UInt64 values[], size_t nValues)
{
    PIM_ACCESS('U', uint64_t, 1, (void)0, x[j] = values[k]);
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

/* ---- FMU state: the checked byte block of pim_unit.h, in memory and serialized ------------ */

fmi3Status fmi3GetFMUState(fmi3Instance inst, fmi3FMUState *state)
{
    INST(inst);
    IN_MODES(PIM_IN(PIM_INSTANTIATED) | PIM_IN(PIM_INIT_MODE) | PIM_IN(PIM_STEP_MODE) |
             PIM_IN(PIM_TERMINATED), "fmi3GetFMUState");
    if (!state) return fail(c, "fmi3GetFMUState: null state pointer");
    unsigned char *buf = *state ? (unsigned char *)*state : (unsigned char *)malloc(PIM_STATE_SIZE);
    if (!buf) return fail(c, "fmi3GetFMUState: out of memory");
    unit_state_write(&c->u, buf, PIM_MODEL_TOKEN, 3);
    *state = buf;
    return fmi3OK;
}

fmi3Status fmi3SetFMUState(fmi3Instance inst, fmi3FMUState state)
{
    INST(inst);
    IN_MODES(PIM_IN(PIM_INSTANTIATED) | PIM_IN(PIM_INIT_MODE) | PIM_IN(PIM_STEP_MODE) |
             PIM_IN(PIM_TERMINATED), "fmi3SetFMUState");
    return status(c, unit_state_read(&c->u, (const unsigned char *)state, PIM_STATE_SIZE,
                                     PIM_MODEL_TOKEN, 3, &c->u));
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

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance inst, fmi3FMUState s, size_t *size)
{
    INST(inst);
    (void)s;
    if (!size) return fail(c, "fmi3SerializedFMUStateSize: null size pointer");
    *size = PIM_STATE_SIZE;
    return fmi3OK;
}

fmi3Status fmi3SerializeFMUState(fmi3Instance inst, fmi3FMUState s, fmi3Byte bytes[],
                                 size_t size)
{
    INST(inst);
    if (!s || !bytes) return fail(c, "fmi3SerializeFMUState: null state or buffer");
    if (size < PIM_STATE_SIZE) return fail(c, "fmi3SerializeFMUState: buffer too small");
    memcpy(bytes, s, PIM_STATE_SIZE);
    return fmi3OK;
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance inst, const fmi3Byte bytes[], size_t size,
                                   fmi3FMUState *s)
{
    INST(inst);
    if (!s) return fail(c, "fmi3DeserializeFMUState: null state pointer");
    if (unit_state_read(&c->u, (const unsigned char *)bytes, size, PIM_MODEL_TOKEN, 3, NULL))
        return status(c, -1);
    unsigned char *copy = (unsigned char *)malloc(PIM_STATE_SIZE);
    if (!copy) return fail(c, "fmi3DeserializeFMUState: out of memory");
    memcpy(copy, bytes, PIM_STATE_SIZE);
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

/* Configuration mode: the structural parameter n_plays (the per-play arrays' size) can be set,
 * and is checked when the mode is left. */
fmi3Status fmi3EnterConfigurationMode(fmi3Instance inst)
{
    INST(inst);
    IN_MODES(PIM_IN(PIM_INSTANTIATED), "fmi3EnterConfigurationMode");
    unit_set_mode(&c->u, PIM_CONFIG_MODE);
    return fmi3OK;
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance inst)
{
    INST(inst);
    IN_MODES(PIM_IN(PIM_CONFIG_MODE), "fmi3ExitConfigurationMode");
    if (unit_check_n_plays(&c->u) != 0) return status(c, -1);
    unit_set_mode(&c->u, PIM_INSTANTIATED);
    return fmi3OK;
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
