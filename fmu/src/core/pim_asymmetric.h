/*
 * Asymmetric generalized PI operator: generalized plays with distinct loading and unloading
 * envelopes gamma_l, gamma_r (Al Janaideh, Rakheja & Su 2011), both affine in one strictly
 * increasing shape function phi, plus a direct term, and its exact inverse.
 *
 * Discrete-time semantics, input v[k] (input unit):
 *
 *     s[k]   = phi(v[k])                                      shape (pim_envelope kinds)
 *     L_i[k] = al s[k] + dl - r_i        gamma_l(v) - r_i     ascending envelope
 *     U_i[k] = ar s[k] + dr + r_i        gamma_r(v) + r_i     descending envelope
 *     z_i[k] = max(L_i[k], min(U_i[k], z_i[k-1])),  z_i[-1] = state
 *     y[k]   = p0 s[k] + sum_i p_i z_i[k]
 *
 * with al, ar > 0, p0 > 0, p_i >= 0.  y[k] is a continuous, strictly increasing function of
 * s[k] that is piecewise linear in s (kinks where L_i = z_i, U_i = z_i or L_i = U_i), so the
 * inverse solves it exactly per sample by interpolating between the sorted kinks and returns
 * v[k] = phi^-1(s[k]).  Units: s, z, r, dl, dr and y / p in the output-side unit of phi.
 * Arrays are caller-owned; z is updated in place; nothing allocates.
 */
#ifndef PIM_ASYMMETRIC_H
#define PIM_ASYMMETRIC_H

#include "pim_core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Envelope parameters of the asymmetric operator (ascending: al, dl; descending: ar, dr). */
typedef struct {
    double p0, al, dl, ar, dr;
    int kind;        /* phi: a PIM_ENV_* kind (pim_generalized.h) */
    double c[4];     /* phi's coefficients */
    int kind_inv;    /* phi^-1's kind */
} pim_asym;

/*
 * The s that gives y at one step from play states z (z untouched): piecewise-linear solve
 * between the sorted kinks, no iteration; n <= PIM_MAX_PLAYS.  Internal (also used by
 * pim_play_solve), not exported from the library.
 */
double pim_asym_solve(const pim_asym *a, size_t n, const double *p, const double *r,
                      const double *z, double y);

/* Forward run; returns 0, or k + 1 when phi is undefined at v[k] (the run stops there). */
PIM_API size_t pim_asym_run(const pim_asym *a, size_t N, size_t n, const double *p,
                            const double *r, double *z, const double *v, double *y);

/*
 * Exact inverse run: v[k] with the forward operator (state z) giving yd[k]; z advances.
 * Returns 0, k + 1 when the solution s[k] lies outside the range of phi (e.g. beyond a tanh
 * saturation level), or N + 1 when n > PIM_MAX_PLAYS.
 */
PIM_API size_t pim_asym_inverse_run(const pim_asym *a, size_t N, size_t n, const double *p,
                                    const double *r, double *z, const double *yd, double *v);

#ifdef __cplusplus
}
#endif

#endif /* PIM_ASYMMETRIC_H */
