/* The Boolean parameter `inverse` of GeneralizedPI, AsymmetricPI, RateDependentPI and
 * CreepOperator: false runs the operator (input u = v, output y), true its exact inverse (input
 * u = y_d, output y = v) with the same parameters, started from the forward operator's initial
 * state (as InversePI).  A field `int inverse` in the unit's fields.h. */
#ifndef PIM_SHARED_INVERSE_FLAG_H
#define PIM_SHARED_INVERSE_FLAG_H

/* inverse is a Boolean (0 or 1). */
static inline int inverse_flag_check(pim_unit *u)
{
    if (u->inverse != 0 && u->inverse != 1)
        return unit_error(u, "parameter inverse = %d: must be a Boolean", u->inverse);
    return 0;
}

/* inverse = true needs a linear play (r[1] = 0): the inverse of a PI operator's plays. */
static inline int inverse_flag_needs_linear_play(pim_unit *u)
{
    if (u->inverse && u->r[0] != 0.0)
        return unit_error(u, "bad parameters: inverse = true needs a linear play (r[1] = %g "
                             "must be 0)", u->r[0]);
    return 0;
}

#endif /* PIM_SHARED_INVERSE_FLAG_H */
