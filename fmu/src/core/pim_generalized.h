/*
 * Generalized Prandtl-Ishlinskii operator: a PI operator between two strictly increasing
 * envelope functions (Al Janaideh, Rakheja & Su 2011, with identical loading and unloading
 * envelopes, which is the case with an analytic inverse; Kuhnen 2003 for the output function).
 *
 * Discrete-time semantics, input v[k] (input unit), output y[k] (output unit):
 *
 *     u[k]   = h(v[k])                                            input envelope
 *     z_i[k] = max(u[k] - r_i, min(u[k] + r_i, z_i[k-1]))          play i, z_i[-1] = state
 *     y[k]   = g(sum_i p_i z_i[k])                                 output envelope
 *
 * so y[k] depends on v[0..k] only.  Radii r_i and play states are in envelope units (the unit
 * of h(v)).  The exact inverse has the same form: input envelope g^-1, the Krejci-Kuhnen inverse
 * PI (pim_pi_inverse, signed weights), output envelope h^-1.
 *
 * Envelope kinds (coefficients c[0..3]; each is strictly increasing on its domain):
 *     PIM_ENV_POLY2  f(x) = c0 + c1 x + c2 x^2   domain c1 + 2 c2 x > 0 (c1 > 0 if c2 == 0)
 *     PIM_ENV_TANH   f(x) = c0 tanh(c1 x + c2) + c3           c0 > 0, c1 > 0, all x
 *     PIM_ENV_POLY2_INV  inverse of POLY2 with the same c:
 *                    f(x) = 2 (x - c0) / (c1 + sqrt(c1^2 + 4 c2 (x - c0)))
 *                    domain c1^2 + 4 c2 (x - c0) > 0
 *     PIM_ENV_TANH_INV   inverse of TANH with the same c:
 *                    f(x) = (atanh((x - c3) / c0) - c2) / c1,   domain |x - c3| < c0
 * Outside its domain an envelope returns NAN.  Arrays are caller-owned; nothing allocates.
 */
#ifndef PIM_GENERALIZED_H
#define PIM_GENERALIZED_H

#include "pim_core.h"

#ifdef __cplusplus
extern "C" {
#endif

#define PIM_ENV_POLY2 0
#define PIM_ENV_TANH 1
#define PIM_ENV_POLY2_INV 2
#define PIM_ENV_TANH_INV 3

/* Envelope value f(x) of the given kind, NAN outside the domain or for an unknown kind. */
PIM_API double pim_envelope(int kind, const double *c, double x);

/*
 * Parameter check of an envelope: NULL when the coefficients are finite and give a strictly
 * increasing function, else a static message naming the offending coefficient.
 */
PIM_API const char *pim_envelope_check(int kind, const double *c);

/*
 * Runs the generalized PI operator over v[0..N-1] (semantics above); z (n play states) is
 * updated in place.  Returns 0, or k + 1 when an envelope is undefined at sample k (y[k] is
 * then NAN, the run stops there and z is not meaningful).
 */
PIM_API size_t pim_gpi_run(size_t N, size_t n, const double *p, const double *r, double *z,
                           int kind_in, const double *c_in, int kind_out, const double *c_out,
                           const double *v, double *y);

#ifdef __cplusplus
}
#endif

#endif /* PIM_GENERALIZED_H */
