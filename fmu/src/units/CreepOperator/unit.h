/* The CreepOperator unit (unit 7): y = G(z) u with G = 1 + sum_i c_i (1 - a_i) / (z - a_i)
 * (pim_creep.h), or with inverse = true its exact inverse (units/shared/inverse_flag.h).  Its
 * hooks (fmi/pim_unit.h), included after the unit struct. */
#include "inverse_flag.h"
#include "play_state_hooks.h"
#define HAS_MODEL_DEFAULTS
#define HAS_MODEL_DERIVE

static void model_defaults(pim_unit *u)
{
    for (int i = 0; i < PIM_NMAX; ++i) {
        u->p[i] = 0.05; /* creep gain c */
        u->r[i] = 1.0;  /* time constant tau [s] */
    }
}

/* Creep: gains c[i] (stored in p) finite and > 0, time constants tau[i] (in r) finite and > 0,
 * and G minimum phase (sum_i c_i (1 - a_i) / (1 + a_i) < 1, exact for c_i > 0; pim_creep.h). */
static int unit_check_creep(pim_unit *u)
{
    double s = 0.0;
    for (int i = 0; i < u->n; ++i) {
        if (!isfinite(u->p[i]) || !(u->p[i] > 0.0))
            return unit_error(u, "gain c[%d] = %g is not positive (creep gains must be finite "
                                 "and > 0)", i + 1, u->p[i]);
        if (!isfinite(u->r[i]) || !(u->r[i] > 0.0))
            return unit_error(u, "time constant tau[%d] = %g is not positive (must be finite "
                                 "and > 0 s)", i + 1, u->r[i]);
        const double a = exp(-u->Ts / u->r[i]);
        s += u->p[i] * (1.0 - a) / (1.0 + a);
    }
    if (!(s < 1.0))
        return unit_error(u, "bad parameters: the creep G(z) is not minimum phase (sum c_i "
                             "(1 - a_i) / (1 + a_i) = %g >= 1), its inverse would be unstable",
                          s);
    return 0;
}

static int model_check_parameters(pim_unit *u)
{
    if (inverse_flag_check(u) != 0) return -1;
    return unit_check_creep(u);
}

static int model_derive(pim_unit *u)
{
    for (int i = 0; i < u->n; ++i) u->a[i] = exp(-u->Ts / u->r[i]);
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
        pim_creep_inverse_run(1, n, u->a, u->p, u->z, &u->in1, &u->out1);
    else
        pim_creep_run(1, n, u->a, u->p, u->z, &u->in1, &u->out1);
}
