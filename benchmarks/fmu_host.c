/* Minimal FMI 2.0 host: loads an FMU binary, runs N doStep calls of one sample each (n plays)
 * and prints the time per sample in ns (wall clock, then the process's CPU time, which a loaded
 * machine inflates less) and a checksum of the outputs.  Every call's status is checked (a
 * failing call ends the run with exit status 1, so no failing call is timed).  Value
 * references: the enum ValueReference of the unit's generated config.h.
 * Usage: fmu_host BINARY.so GUID N n */
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "fmi2Functions.h"

#include "config.h" /* PIHysteresis: vr_Ts, vr_n, vr_p, vr_r, vr_v, vr_y */

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status st, fmi2String cat,
                   fmi2String msg, ...)
{
    (void)env; (void)st; (void)cat;
    fprintf(stderr, "%s: %s\n", name, msg);
}

#define LOAD(T, name) T *name = (T *)dlsym(h, #name); if (!name) { fprintf(stderr, "missing %s\n", #name); return 1; }

int main(int argc, char **argv)
{
    if (argc != 5) { fprintf(stderr, "usage: fmu_host BINARY GUID N n\n"); return 2; }
    void *h = dlopen(argv[1], RTLD_NOW);
    if (!h) { fprintf(stderr, "%s\n", dlerror()); return 1; }
    LOAD(fmi2InstantiateTYPE, fmi2Instantiate)
    LOAD(fmi2SetRealTYPE, fmi2SetReal)
    LOAD(fmi2SetIntegerTYPE, fmi2SetInteger)
    LOAD(fmi2GetRealTYPE, fmi2GetReal)
    LOAD(fmi2EnterInitializationModeTYPE, fmi2EnterInitializationMode)
    LOAD(fmi2ExitInitializationModeTYPE, fmi2ExitInitializationMode)
    LOAD(fmi2DoStepTYPE, fmi2DoStep)
    LOAD(fmi2FreeInstanceTYPE, fmi2FreeInstance)
    const long N = atol(argv[3]);
    const int n = atoi(argv[4]);
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    fmi2Component c = fmi2Instantiate("bench", fmi2CoSimulation, argv[2], "", &cb, 0, 0);
    if (!c) return 1;
    LOAD(fmi2SetupExperimentTYPE, fmi2SetupExperiment)
    if (fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK ||
        fmi2EnterInitializationMode(c) != fmi2OK) return 1;
    const fmi2ValueReference vr_n_ = vr_n, vr_ts = vr_Ts, vr_v_ = vr_v, vr_y_ = vr_y;
    fmi2Integer nn = n;
    double ts = 1e-4;
    if (fmi2SetInteger(c, &vr_n_, 1, &nn) != fmi2OK || fmi2SetReal(c, &vr_ts, 1, &ts) != fmi2OK)
        return 1;
    for (int i = 0; i < n; ++i) {
        const fmi2ValueReference vp = vr_p + i, vrr = vr_r + i;
        double p = 1.0 / (i + 1), r = 0.2 * i;
        if (fmi2SetReal(c, &vp, 1, &p) != fmi2OK || fmi2SetReal(c, &vrr, 1, &r) != fmi2OK)
            return 1;
    }
    if (fmi2ExitInitializationMode(c) != fmi2OK) return 1;
    struct timespec t0, t1, c0, c1;
    double acc = 0.0;
    int failed = 0;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c0);
    for (long k = 0; k < N; ++k) {
        double v = 3.0 * ((k % 2000) < 1000 ? (k % 1000) / 1000.0 : 1.0 - (k % 1000) / 1000.0);
        double y = 0.0;
        failed |= fmi2SetReal(c, &vr_v_, 1, &v) != fmi2OK;
        failed |= fmi2DoStep(c, k * ts, ts, fmi2True) != fmi2OK;
        failed |= fmi2GetReal(c, &vr_y_, 1, &y) != fmi2OK;
        acc += y;
    }
    clock_gettime(CLOCK_MONOTONIC, &t1);
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c1);
    if (failed) {
        fprintf(stderr, "a setReal, doStep or getReal call failed\n");
        return 1;
    }
    double ns = ((t1.tv_sec - t0.tv_sec) * 1e9 + (t1.tv_nsec - t0.tv_nsec)) / (double)N;
    double ns_cpu = ((c1.tv_sec - c0.tv_sec) * 1e9 + (c1.tv_nsec - c0.tv_nsec)) / (double)N;
    printf("%.2f %.2f %g\n", ns, ns_cpu, acc);
    fmi2FreeInstance(c);
    dlclose(h);
    return 0;
}
