/* The GeneralizedPI unit (unit 4): y = g(PI(h(v))) with envelopes h, g (pim_generalized.h), or
 * with inverse = true its exact inverse (units/shared/inverse_flag.h).  Its hooks
 * (fmi/pim_unit.h), included after the unit struct. */
#include "envelope_check.h"
#include "inverse_flag.h"
#include "inverse_pi.h"
#include "play_state_hooks.h"
#include "plays.h"
#define HAS_MODEL_DEFAULTS
#define HAS_MODEL_DERIVE

static void model_defaults(pim_unit *u)
{
    u->c_in[1] = u->c_out[1] = 1.0; /* identity envelopes */
}

static int model_check_parameters(pim_unit *u)
{
    if (inverse_flag_check(u) != 0 || plays_check(u, PLAYS_POSITIVE) != 0 ||
        envelope_check(u, "in", u->kind_in, u->c_in) != 0 ||
        envelope_check(u, "out", u->kind_out, u->c_out) != 0)
        return -1;
    return inverse_flag_needs_linear_play(u);
}

static int model_derive(pim_unit *u) { return u->inverse ? inverse_pi_derive(u) : 0; }

static int model_setup(pim_unit *u)
{
    plays_at_z0(u);
    if (model_derive(u) != 0) return -1;
    return u->inverse ? inverse_pi_start(u) : 0;
}

static void model_sample(pim_unit *u)
{
    const size_t n = (size_t)u->n;
    /* the inverse envelope kinds: kind ^ 2 (poly2 <-> poly2_inv, tanh <-> tanh_inv) */
    if (u->inverse)
        (void)pim_gpi_run(1, n, u->pinv, u->rinv, u->z, u->kind_out ^ 2, u->c_out,
                          u->kind_in ^ 2, u->c_in, &u->in1, &u->out1);
    else
        (void)pim_gpi_run(1, n, u->p, u->r, u->z, u->kind_in, u->c_in, u->kind_out, u->c_out,
                          &u->in1, &u->out1);
}
