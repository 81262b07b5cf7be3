/* The AsymmetricPI unit (unit 5): the asymmetric generalized PI operator (pim_asymmetric.h),
 * weights p >= 0, or with inverse = true its exact inverse (units/shared/inverse_flag.h).  Its
 * hooks (fmi/pim_unit.h), included after the unit struct. */
#include "envelope_check.h"
#include "inverse_flag.h"
#include "play_state_hooks.h"
#include "plays.h"
#define HAS_MODEL_DEFAULTS
#define HAS_MODEL_DERIVE

static void model_defaults(pim_unit *u)
{
    u->c_in[1] = 1.0; /* identity shape */
    u->p0 = u->a_l = u->a_r = 1.0;
}

static int model_check_parameters(pim_unit *u)
{
    if (inverse_flag_check(u) != 0 || plays_check(u, PLAYS_NONNEGATIVE) != 0) return -1;
    if (!isfinite(u->p0) || !(u->p0 > 0.0))
        return unit_error(u, "parameter p0 = %g: the direct weight must be finite and > 0",
                          u->p0);
    if (!isfinite(u->a_l) || !(u->a_l > 0.0))
        return unit_error(u, "parameter a_l = %g: the ascending slope must be finite and > 0",
                          u->a_l);
    if (!isfinite(u->a_r) || !(u->a_r > 0.0))
        return unit_error(u, "parameter a_r = %g: the descending slope must be finite and > 0",
                          u->a_r);
    if (!isfinite(u->d_l)) return unit_error(u, "parameter d_l = %g: must be finite", u->d_l);
    if (!isfinite(u->d_r)) return unit_error(u, "parameter d_r = %g: must be finite", u->d_r);
    return envelope_check(u, "shape", u->kind_in, u->c_in);
}

static int model_derive(pim_unit *u)
{
    const pim_asym a = {u->p0, u->a_l, u->d_l, u->a_r, u->d_r, u->kind_in,
                        {u->c_in[0], u->c_in[1], u->c_in[2], u->c_in[3]}, u->kind_in ^ 2};
    u->asym = a;
    return 0;
}

static int model_setup(pim_unit *u)
{
    plays_at_z0(u);
    return model_derive(u);
}

static void model_sample(pim_unit *u)
{
    const size_t n = (size_t)u->n;
    if (u->inverse)
        (void)pim_asym_inverse_run(&u->asym, 1, n, u->p, u->r, u->z, &u->in1, &u->out1);
    else
        (void)pim_asym_run(&u->asym, 1, n, u->p, u->r, u->z, &u->in1, &u->out1);
}
