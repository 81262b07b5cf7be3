/* The PIHysteresis unit (unit 1): the PI operator y = sum p_i play_{r_i}(v) (pim_pi.c); input v
 * (in1), output y (out1).  Its hooks (fmi/pim_unit.h), included after the unit struct. */
#include "play_state_hooks.h"
#include "plays.h"

static int model_check_parameters(pim_unit *u) { return plays_check(u, PLAYS_POSITIVE); }

static int model_setup(pim_unit *u)
{
    plays_at_z0(u);
    return 0;
}

static void model_sample(pim_unit *u)
{
    u->out1 = pim_pi_step((size_t)u->n, u->p, u->r, u->z, u->in1);
}
