/*
 * The pimodel FMU units, independent of the FMI version: parameters, inputs, outputs, states,
 * the parameter check, one internal sample and the sub-stepping rule.  Included (static
 * functions) by the FMI 2 and FMI 3 glue after PIM_MODEL (1 PIHysteresis, 2 RadiusEstimator,
 * 3 InversePI) is defined.  The numerics are the shared C core (pim_pi.c, pim_estimator.c,
 * pim_loops.c).  Functions return 0 on success, or -1 with the reason in u->msg.
 *
 * Sampling rule: internal sample k happens at time k*Ts.  A step from t over h processes every
 * sample with k*Ts in [t, t+h) (tolerance 1e-9*Ts), each with the inputs set before the call
 * (held over the step); outputs are those of the last processed sample and hold between
 * samples.  A step shorter than Ts that contains no sample instant changes nothing.
 *
 * Value references: 0 Ts, 1 n, 2 z0 (initial play state), 3 adaptive (InversePI), 4 gain,
 * 5 known_linear, 6 guard, 7 slope_window, 10 main input, 11 main output, 12 second input (y of
 * the estimator), 13 second output (e); arrays p (100), r (200; initial radii for the
 * estimator), r_hat (300; inputs of the adaptive InversePI, outputs of the estimator): in FMI 2
 * element i (0-based) has reference base + i, in FMI 3 the array is one variable.
 */
#ifndef PIM_UNIT_H
#define PIM_UNIT_H

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "pim_core.h"
#include "pim_estimator.h"
#include "pim_loops.h"

#ifndef PIM_MODEL
#error "define PIM_MODEL (1 PIHysteresis, 2 RadiusEstimator, 3 InversePI)"
#endif

#define NMAX 16 /* declared array size: p[1..16], r[1..16], r_hat[1..16] */

typedef struct {
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
    char msg[256]; /* reason of the last failure */
} pim_unit;

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

static void unit_defaults(pim_unit *u)
{
    memset(u, 0, sizeof *u);
    u->Ts = 1e-3;
    u->gain = 10.0;
    u->n = 1;
    u->slope_window = 8;
    for (int i = 0; i < NMAX; ++i) u->p[i] = 1.0;
}

/* Checks the parameters and sets up the states. */
static int unit_setup(pim_unit *u)
{
    if (u->n < 1 || u->n > NMAX)
        return unit_error(u, "parameter n = %d out of range: 1 <= n <= %d", u->n, NMAX);
    if (!(u->Ts > 0.0) || !isfinite(u->Ts))
        return unit_error(u, "parameter Ts = %g: the sample time must be > 0", u->Ts);
    if (!isfinite(u->z0)) return unit_error(u, "parameter z0: must be finite");
    const size_t n = (size_t)u->n;
    const char *msg = pim_pi_check(n, u->p, u->r, 0);
    if (msg) return unit_error(u, "bad parameters: %s", msg);
#if PIM_MODEL == 2
    if (!(u->gain >= 0.0) || !isfinite(u->gain))
        return unit_error(u, "parameter gain = %g: must be finite and >= 0", u->gain);
    double g[NMAX];
    for (size_t i = 0; i < n; ++i) g[i] = u->gain;
    msg = pim_est_init(&u->est, n, u->p, g, u->r, u->Ts, u->z0, 0.0, 0.0, 0.0, u->guard,
                       u->known_linear);
    if (msg) return unit_error(u, "bad parameters: %s", msg);
    msg = pim_est_set_slope_check(&u->est, u->slope_window, 0.5);
    if (msg) return unit_error(u, "bad parameters: %s", msg);
    for (size_t i = 0; i < n; ++i) u->rhat_out[i] = u->est.rhat[i];
#else
    for (size_t i = 0; i < n; ++i) u->z[i] = u->z0;
#endif
#if PIM_MODEL == 3
    if (!u->adaptive) {
        double zinv[PIM_MAX_PLAYS];
        if (pim_pi_inverse(n, u->p, u->r, u->z, u->pinv, u->rinv, zinv) != 0)
            return unit_error(u, "bad parameters: not invertible (r[1] must be 0 with a "
                                 "positive weight p[1])");
        memcpy(u->z, zinv, n * sizeof(double));
    } else if (u->r[0] != 0.0 && u->known_linear) {
        return unit_error(u, "bad parameters: r[1] must be 0");
    }
#endif
    return 0;
}

/* One internal sample at the held inputs. */
static int unit_sample(pim_unit *u)
{
    const size_t n = (size_t)u->n;
    if (!isfinite(u->in1) || !isfinite(u->in2))
        return unit_error(u, "input is not finite (NaN or Inf): %g, %g", u->in1, u->in2);
#if PIM_MODEL == 1
    (void)n;
    u->out1 = pim_pi_step(n, u->p, u->r, u->z, u->in1);
#elif PIM_MODEL == 2
    double yh, e, ed;
    (void)pim_est_step(&u->est, u->in1, u->in2, NULL, &yh, &e, &ed);
    u->out1 = yh;
    u->out2 = e;
    for (size_t i = 0; i < n; ++i) u->rhat_out[i] = u->est.rhat[i];
#else
    if (u->adaptive) {
        for (size_t i = 0; i < n; ++i) {
            if (!isfinite(u->rhat_in[i]) || u->rhat_in[i] < 0.0 ||
                (i > 0 && u->rhat_in[i] < u->rhat_in[i - 1]))
                return unit_error(u, "input r_hat[%d] = %g: radii must be finite, >= 0 and "
                                     "sorted", (int)i + 1, u->rhat_in[i]);
        }
        double v = pim_adaptive_inverse_step(n, u->p, u->rhat_in, u->z, u->in1);
        if (isnan(v)) return unit_error(u, "input r_hat: not invertible (r_hat[1] must be 0)");
        u->out1 = v;
    } else {
        u->out1 = pim_pi_step(n, u->pinv, u->rinv, u->z, u->in1);
    }
#endif
    return 0;
}

/* Processes the samples k*Ts in [t, t+h) (the sampling rule above). */
static int unit_do_step(pim_unit *u, double t, double h)
{
    if (!(h >= 0.0) || !isfinite(t) || !isfinite(h))
        return unit_error(u, "invalid communication step: t = %g, h = %g", t, h);
    const double tol = 1e-9;
    const double k0 = ceil(t / u->Ts - tol), k1 = ceil((t + h) / u->Ts - tol);
    for (double k = k0; k < k1; k += 1.0)
        if (unit_sample(u) != 0) return -1;
    return 0;
}

/* Scalar Float64 variables by value reference (NULL if none). */
static double *unit_scalar(pim_unit *u, unsigned vr)
{
    switch (vr) {
    case 0: return &u->Ts;
    case 2: return &u->z0;
    case 4: return &u->gain;
    case 6: return &u->guard;
    case 10: return &u->in1;
    case 11: return &u->out1;
    case 12: return &u->in2;
    case 13: return &u->out2;
    default: return NULL;
    }
}

/* Array variable (p, r, r_hat) with base reference 100, 200 or 300 (NULL if none). */
static double *unit_array(pim_unit *u, unsigned base)
{
    switch (base) {
    case 100: return u->p;
    case 200: return u->r;
#if PIM_MODEL == 2
    case 300: return u->rhat_out;
#else
    case 300: return u->rhat_in;
#endif
    default: return NULL;
    }
}

/* Whether a Float64 variable may be set: parameters before initialization, inputs always. */
static int unit_settable(unsigned vr, int initialized)
{
    if (vr == 11 || vr == 13 || (PIM_MODEL == 2 && vr >= 300)) return 0;
    if (initialized && (vr < 10 || (vr >= 100 && vr < 300))) return 0;
    return 1;
}

static int *unit_int(pim_unit *u, unsigned vr)
{
    if (vr == 1) return &u->n;
    if (vr == 7) return &u->slope_window;
    return NULL;
}

static int *unit_bool(pim_unit *u, unsigned vr)
{
    if (vr == 3) return &u->adaptive;
    if (vr == 5) return &u->known_linear;
    return NULL;
}

#endif /* PIM_UNIT_H */
