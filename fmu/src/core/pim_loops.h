/*
 * Compiled closed-loop paths: PI hysteresis plant (Hammerstein: PI operator then linear
 * discrete dynamics), inverse feedforward (none, fixed exact inverse, or adaptive inverse driven
 * by the radius estimator) and optional PID feedback.  Per sample k (sample time dt):
 *
 *   ff[k]  = feedforward of the reference r[k]:
 *              none:     ff = ff_gain * r[k]
 *              fixed:    ff = PI_inv[r][k]                (exact inverse, state zinv)
 *              adaptive: ff = pim_adaptive_inverse_step(p, rhat[k], zm, r[k])
 *   y[k]   = C xd[k] + D h[k] (measured output; D must be 0 when PID is on: no algebraic loop)
 *   e[k]   = r[k] - y[k] with y[k] = C xd[k] (PID on)           -> u[k] = PID(e)[k]
 *   v[k]   = ff[k] + u[k],   h[k] = PI_plant[v][k],   xd[k+1] = A xd[k] + B h[k]
 *   adaptive: the estimator takes (v[k], y[k]) and gives rhat[k+1].
 *
 * PID (backward Euler, filtered derivative):  I[k] = I[k-1] + dt e[k],
 *   Df[k] = (Tf Df[k-1] + Kd (e[k] - e[k-1])) / (Tf + dt),  u[k] = Kp e[k] + Ki I[k] + Df[k],
 *   with e[-1] = 0, I[-1] = 0, Df[-1] = 0.
 */
#ifndef PIM_LOOPS_H
#define PIM_LOOPS_H

#include "pim_core.h"
#include "pim_estimator.h"

#ifdef __cplusplus
extern "C" {
#endif


/*
 * Adaptive inverse step: forward model with weights p and current radii r (sorted, r[0] == 0),
 * forward play states zm (updated).  Builds the exact inverse of (p, r) with the state consistent
 * with zm, steps it with the desired output yd and returns v; then advances zm with v.
 * Returns NAN if (p, r) is not invertible.
 */
PIM_API double pim_adaptive_inverse_step(size_t n, const double *p, const double *r, double *zm,
                                         double yd);

typedef struct {
    /* plant */
    size_t n;
    double p[PIM_MAX_PLAYS], r[PIM_MAX_PLAYS], z[PIM_MAX_PLAYS];
    size_t nx; /* dynamics order, 0: y = h */
    double A[PIM_MAX_DYN * PIM_MAX_DYN], B[PIM_MAX_DYN], C[PIM_MAX_DYN], D;
    double xd[PIM_MAX_DYN];
    /* feedforward: 0 none (ff_gain), 1 fixed inverse, 2 adaptive */
    int ff_mode;
    double ff_gain;
    size_t ni;
    double pinv[PIM_MAX_PLAYS], rinv[PIM_MAX_PLAYS], zinv[PIM_MAX_PLAYS];
    size_t nm;
    double pm[PIM_MAX_PLAYS], zm[PIM_MAX_PLAYS];
    pim_estimator est;
    /* PID */
    int pid_on;
    double kp, ki, kd, tf, dt;
    double integ, dfilt, e_prev;
} pim_loop;

PIM_API size_t pim_loop_sizeof(void);

/* Runs N samples of reference ref; writes y, v (nullable), e (nullable) and, in adaptive mode,
 * R (nullable, N*nm: rhat[k] row by row).  Returns 0, or -1 if the adaptive inverse failed. */
PIM_API int pim_loop_run(pim_loop *L, size_t N, const double *ref, double *y, double *v,
                         double *e, double *R);

#ifdef __cplusplus
}
#endif

#endif /* PIM_LOOPS_H */
