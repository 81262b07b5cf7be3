/* The plays' parameter rule of the PI-family units (PIHysteresis, RadiusEstimator, InversePI,
 * GeneralizedPI, AsymmetricPI, RateDependentPI): weights p and radii r. */
#ifndef PIM_SHARED_PLAYS_H
#define PIM_SHARED_PLAYS_H

enum { PLAYS_POSITIVE, PLAYS_NONNEGATIVE }; /* the weight rule of plays_check */

/* Weights p[1..n] finite and > 0 (PLAYS_NONNEGATIVE: >= 0, and no pim_pi_check), radii r
 * finite, >= 0 and sorted, with the variable, index and value in the message. */
static inline int plays_check(pim_unit *u, int weights)
{
    for (int i = 0; i < u->n; ++i) {
        if (!isfinite(u->p[i]))
            return unit_error(u, "weight p[%d] = %g is not finite", i + 1, u->p[i]);
        if (weights == PLAYS_NONNEGATIVE && u->p[i] < 0.0)
            return unit_error(u, "weight p[%d] = %g is negative (weights must be >= 0)", i + 1,
                              u->p[i]);
        if (weights == PLAYS_POSITIVE && !(u->p[i] > 0.0))
            return unit_error(u, "weight p[%d] = %g is not positive (weights must be > 0)",
                              i + 1, u->p[i]);
        if (!isfinite(u->r[i]))
            return unit_error(u, "radius r[%d] = %g is not finite", i + 1, u->r[i]);
        if (u->r[i] < 0.0)
            return unit_error(u, "radius r[%d] = %g is negative (radii must be >= 0)", i + 1,
                              u->r[i]);
        if (i > 0 && u->r[i] < u->r[i - 1])
            return unit_error(u, "radii not sorted: r[%d] = %g < r[%d] = %g (need r[1] <= ... "
                                 "<= r[n])", i + 1, u->r[i], i, u->r[i - 1]);
    }
    if (weights == PLAYS_POSITIVE) {
        const char *msg = pim_pi_check((size_t)u->n, u->p, u->r, 0);
        if (msg) return unit_error(u, "bad parameters: %s", msg);
    }
    return 0;
}

#endif /* PIM_SHARED_PLAYS_H */
