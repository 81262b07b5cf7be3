/*
 * Creep operator: a sum of first-order lags acting on a signal u (typically the hysteresis
 * output), discretised with a zero-order hold, and its exact causal inverse.
 *
 * Discrete-time semantics, sample time Ts, lag i with time constant tau_i and gain c_i,
 * a_i = exp(-Ts / tau_i):
 *
 *     y[k]      = u[k] + sum_i c_i x_i[k]                     feedthrough 1
 *     x_i[k+1]  = a_i x_i[k] + (1 - a_i) u[k]                 x_i[0] = state
 *
 * i.e. G(z) = 1 + sum_i c_i (1 - a_i) / (z - a_i): a step of u of height h gives h at once and
 * creeps to (1 + sum c_i) h.  The states x_i[k] depend on u[0..k-1] only, so the inverse is
 *
 *     u[k] = y[k] - sum_i c_i x_i[k],   x_i[k+1] = a_i x_i[k] + (1 - a_i) u[k]
 *
 * exact and causal; its poles are the zeros of G (eigenvalues of diag(a) - (1 - a) c^T), so it
 * is stable iff G is minimum phase.  y and u share a unit; c is dimensionless.
 * Arrays are caller-owned; x (m lag states) is updated in place; nothing allocates.
 */
#ifndef PIM_CREEP_H
#define PIM_CREEP_H

#include "pim_core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Forward run: y[k] from u[0..k]; x updated in place. */
PIM_API void pim_creep_run(size_t N, size_t m, const double *a, const double *c, double *x,
                           const double *u, double *y);

/* Inverse run: u[k] from y[0..k] (the forward operator's states x, updated in place). */
PIM_API void pim_creep_inverse_run(size_t N, size_t m, const double *a, const double *c,
                                   double *x, const double *y, double *u);

#ifdef __cplusplus
}
#endif

#endif /* PIM_CREEP_H */
