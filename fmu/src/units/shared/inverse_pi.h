/* The inverse PI operator of the plays (p, r) (pim_pi_inverse), for InversePI (adaptive = false)
 * and GeneralizedPI (inverse = true): fields `double pinv[PIM_MAX_PLAYS], rinv[PIM_MAX_PLAYS]`
 * and the play states z in the unit's fields.h. */
#ifndef PIM_SHARED_INVERSE_PI_H
#define PIM_SHARED_INVERSE_PI_H

/* The inverse's weights pinv and radii rinv (derived). */
static inline int inverse_pi_derive(pim_unit *u)
{
    if (pim_pi_inverse((size_t)u->n, u->p, u->r, NULL, u->pinv, u->rinv, NULL) != 0)
        return unit_error(u, "bad parameters: not invertible (r[1] must be 0 with a positive "
                             "weight p[1])");
    return 0;
}

/* The inverse's play states, consistent with the forward ones in z (setup). */
static inline int inverse_pi_start(pim_unit *u)
{
    const size_t n = (size_t)u->n;
    double zinv[PIM_MAX_PLAYS], pinv[PIM_MAX_PLAYS], rinv[PIM_MAX_PLAYS];
    if (pim_pi_inverse(n, u->p, u->r, u->z, pinv, rinv, zinv) != 0)
        return unit_error(u, "bad parameters: not invertible (r[1] must be 0 with a "
                             "positive weight p[1])");
    memcpy(u->z, zinv, n * sizeof(double));
    return 0;
}

#endif /* PIM_SHARED_INVERSE_PI_H */
