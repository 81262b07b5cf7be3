/* The RateDependentPI unit (unit 6): the PI operator with rate-dependent radii
 * (pim_rate_dependent.h), or with inverse = true its exact inverse
 * (units/shared/inverse_flag.h).  Its hooks (fmi/pim_unit.h), included after the unit struct. */
#include "inverse_flag.h"
#include "play_states.h"
#include "plays.h"
#define HAS_MODEL_DERIVE

typedef struct {
    plays_saved plays;
    double hist[2];
} model_saved;

static int model_check_parameters(pim_unit *u)
{
    if (inverse_flag_check(u) != 0 || plays_check(u, PLAYS_POSITIVE) != 0) return -1;
    if (!isfinite(u->rate_gain) || u->rate_gain < 0.0)
        return unit_error(u, "parameter rate_gain = %g: must be finite and >= 0", u->rate_gain);
    if (!isfinite(u->rate_tc) || u->rate_tc < 0.0)
        return unit_error(u, "parameter rate_time_constant = %g: must be finite and >= 0",
                          u->rate_tc);
    if (!isfinite(u->v0)) return unit_error(u, "parameter v0 = %g: must be finite", u->v0);
    return inverse_flag_needs_linear_play(u);
}

static int model_derive(pim_unit *u)
{
    u->lam = u->rate_tc > 0.0 ? exp(-u->Ts / u->rate_tc) : 0.0;
    return 0;
}

static int model_setup(pim_unit *u)
{
    plays_at_z0(u);
    if (model_derive(u) != 0) return -1;
    u->hist[0] = u->v0;
    u->hist[1] = 0.0;
    return 0;
}

static void model_sample(pim_unit *u)
{
    const size_t n = (size_t)u->n;
    if (u->inverse)
        (void)pim_rdpi_inverse_run(1, n, u->p, u->r, u->rate_gain, u->lam, u->Ts, u->z, u->hist,
                                   &u->in1, &u->out1);
    else
        pim_rdpi_run(1, n, u->p, u->r, u->rate_gain, u->lam, u->Ts, u->z, u->hist, &u->in1,
                     &u->out1);
}

static void model_save(const pim_unit *u, model_saved *s)
{
    plays_save(u, &s->plays);
    s->hist[0] = u->hist[0];
    s->hist[1] = u->hist[1];
}

static void model_restore(pim_unit *u, const model_saved *s)
{
    plays_restore(u, &s->plays);
    u->hist[0] = s->hist[0];
    u->hist[1] = s->hist[1];
}

static int model_check_states(pim_unit *u, pim_unit *s)
{
    if (plays_check_states(u, s) != 0) return -1;
    if (!unit_all_finite(s->hist, 2) || s->hist[1] < 0.0)
        return unit_error(u, "FMU state rejected: the rate state (v[k-1], rate[k]) = (%g, %g) "
                             "must be finite with rate >= 0", s->hist[0], s->hist[1]);
    return 0;
}
