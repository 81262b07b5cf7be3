/* The InversePI unit (unit 3): the exact inverse of a PI operator, input y_d (in1), output v
 * (out1); adaptive = true takes the radii from the input r_hat (a RadiusEstimator's output)
 * every sample (pim_adaptive_inverse_step), else the inverse's plays are derived from (p, r)
 * once and start consistent with the forward plays at z0.  Its hooks (fmi/pim_unit.h), included
 * after the unit struct. */
#include "inverse_pi.h"
#include "play_state_hooks.h"
#include "plays.h"
#define HAS_MODEL_DERIVE
#define HAS_MODEL_CHECK_INPUTS

static int model_check_parameters(pim_unit *u)
{
    if (plays_check(u, PLAYS_POSITIVE) != 0) return -1;
    if (u->adaptive != 0 && u->adaptive != 1)
        return unit_error(u, "parameter adaptive = %d: must be a Boolean", u->adaptive);
    if (!u->adaptive && u->r[0] != 0.0)
        return unit_error(u, "bad parameters: not invertible (r[1] = %g must be 0 with a "
                             "positive weight p[1])", u->r[0]);
    return 0;
}

static int model_derive(pim_unit *u) { return u->adaptive ? 0 : inverse_pi_derive(u); }

static int model_setup(pim_unit *u)
{
    plays_at_z0(u);
    if (model_derive(u) != 0) return -1;
    return u->adaptive ? 0 : inverse_pi_start(u);
}

/* The adaptive inverse's radii r_hat: finite, >= 0, sorted, r_hat[1] = 0. */
static int model_check_inputs(pim_unit *u)
{
    if (!u->adaptive) return 0;
    for (int i = 0; i < u->n; ++i) {
        const double x = u->rhat_in[i];
        if (!isfinite(x) || x < 0.0 || (i > 0 && x < u->rhat_in[i - 1]))
            return unit_error(u, "input r_hat[%d] = %g: radii must be finite, >= 0 and "
                                 "sorted", i + 1, x);
    }
    if (u->rhat_in[0] != 0.0)
        return unit_error(u, "input r_hat[1] = %g: not invertible (r_hat[1] must be 0)",
                          u->rhat_in[0]);
    return 0;
}

static void model_sample(pim_unit *u)
{
    const size_t n = (size_t)u->n;
    if (u->adaptive)
        u->out1 = pim_adaptive_inverse_step(n, u->p, u->rhat_in, u->z, u->in1);
    else
        u->out1 = pim_pi_step_inline(n, u->pinv, u->rinv, u->z, u->in1);
}
