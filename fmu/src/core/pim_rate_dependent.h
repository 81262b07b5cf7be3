/*
 * Rate-dependent Prandtl-Ishlinskii operator: play radii that grow with the input rate
 * (Al Janaideh, Su & Rakheja 2008; Al Janaideh & Krejci 2013), and its exact inverse.
 *
 * Discrete-time semantics, input v[k] (input unit) sampled every Ts seconds:
 *
 *     rate[k] = lam rate[k-1] + (1 - lam) |v[k-1] - v[k-2]| / Ts     input unit / s
 *     r_i[k]  = alpha_i (1 + beta rate[k])        beta in s per input unit
 *     z_i[k]  = max(v[k] - r_i[k], min(v[k] + r_i[k], z_i[k-1]))
 *     y[k]    = sum_i p_i z_i[k]
 *
 * lam = exp(-Ts / tau) in [0, 1) filters the rate (lam = 0: the rate of the last interval).
 * The state holds hist[0] = v[k-1] and hist[1] = rate[k].  The rate uses the inputs before
 * v[k] only, so the radii at step k are fixed before v[k] is known:
 * y[k] is then a continuous, non-decreasing, piecewise-linear function of v[k] (slope
 * sum of p_i over the plays on their envelope), strictly increasing when alpha_1 = 0 and
 * p_1 > 0.  That makes the inverse exact: pim_rdpi_inverse_run solves that function for v[k]
 * in closed form (pim_play_solve) and advances the same forward state with it.
 * Arrays are caller-owned, states are updated in place; nothing allocates.
 */
#ifndef PIM_RATE_DEPENDENT_H
#define PIM_RATE_DEPENDENT_H

#include "pim_core.h"

#ifdef __cplusplus
extern "C" {
#endif

/*
 * Exact solution v of  sum_i p_i clamp(z_i, v - r_i, v + r_i) = y  (p_i > 0, r_i >= 0, at
 * least one r_i == 0 for uniqueness; on a flat stretch the smallest solution is returned),
 * then one play step with v: z is updated in place.  Piecewise-linear interpolation between
 * the sorted breakpoints z_i -+ r_i, O(n^2).  Returns v, or NAN (z untouched) when
 * n > PIM_MAX_PLAYS.
 */
PIM_API double pim_play_solve(size_t n, const double *p, const double *r, double *z, double y);

/* Forward run (semantics above); z (n) and hist (2) are updated in place. */
PIM_API void pim_rdpi_run(size_t N, size_t n, const double *p, const double *alpha, double beta,
                          double lam, double Ts, double *z, double *hist, const double *v, double *y);

/*
 * Forward run with a saturating radius growth: r_i[k] = alpha_i (1 + beta rate[k] / (1 +
 * rate[k] / sat)) (sat in input unit / s; sat <= 0: no saturation, pim_rdpi_run), the
 * other semantics as above (rate[k] from v[..k-1] only).  The diagnosis' "scaled" rate
 * shape (pimodel.diagnosis.rate) runs its bands of plays through it.
 */
PIM_API void pim_rdpi_sat_run(size_t N, size_t n, const double *p, const double *alpha,
                              double beta, double sat, double lam, double Ts, double *z,
                              double *hist, const double *v, double *y);

/*
 * The play outputs of pim_rdpi_sat_run instead of their weighted sum: zs[k n + i] = z_i[k]
 * (row-major N x n), every play on the one rate (computed once per sample); z (n) and hist
 * (2) are updated in place.  The same steps as pim_rdpi_sat_run with p_i = 1, one play at a
 * time (tests/test_native_equals_reference.py holds them equal).
 */
PIM_API void pim_rdpi_sat_plays(size_t N, size_t n, const double *alpha, double beta,
                                double sat, double lam, double Ts, double *z, double *hist,
                                const double *v, double *zs);

/*
 * pim_rdpi_sat_plays writing z_i[k] to zs[k ks + i is]: (ks, is) = (n, 1) is its row-major
 * N x n, (1, N) the plays as rows (n x N, the layout the diagnosis' fits take; no transpose).
 */
PIM_API void pim_rdpi_sat_plays_strided(size_t N, size_t n, const double *alpha, double beta,
                                        double sat, double lam, double Ts, double *z,
                                        double *hist, const double *v, double *zs, size_t ks,
                                        size_t is);

/*
 * Exact inverse run: v[k] such that the forward operator with state (z, hist) outputs yd[k];
 * z and hist are the *forward* operator's state and are advanced with v[k].  Returns 0, or
 * -1 when n > PIM_MAX_PLAYS.
 */
PIM_API int pim_rdpi_inverse_run(size_t N, size_t n, const double *p, const double *alpha,
                                 double beta, double lam, double Ts, double *z, double *hist,
                                 const double *yd, double *v);

#ifdef __cplusplus
}
#endif

#endif /* PIM_RATE_DEPENDENT_H */
