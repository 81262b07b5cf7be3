/* The PIHysteresis unit (unit 1): the PI operator y = sum p_i play_{r_i}(v) (pim_pi.c); input v
 * (in1), output y (out1).  Its hooks (fmi/pim_unit.h), included after the unit struct. */
#include "play_state_hooks.h"
#include "plays.h"
#define HAS_MODEL_DERIVE
#define HAS_MODEL_STEP_SAFE

static int model_check_parameters(pim_unit *u) { return plays_check(u, PLAYS_POSITIVE); }

/* The input bound v_safe of model_step_safe: a sample clamps every play state into
 * [v - r_i, v + r_i] whatever it was, so |z_i| <= |v| + r_n and |y| <= P (|v| + r_n) with
 * P = sum p_i (> 0); |v| <= 1e300 / max(P, 1) - r_n keeps every sum far below DBL_MAX.
 * -1 (never safe) when no input is. */
static int model_derive(pim_unit *u)
{
    double P = 0.0;
    for (int i = 0; i < u->n; ++i) P += u->p[i];
    const double v = 1e300 / (P > 1.0 ? P : 1.0) - u->r[u->n - 1];
    u->v_safe = isfinite(P) && v > 0.0 ? v : -1.0;
    return 0;
}

static int model_setup(pim_unit *u)
{
    plays_at_z0(u);
    return model_derive(u);
}

/* v_safe is finite, so a safe v is finite too (a NaN compares false). */
static int model_step_safe(const pim_unit *u) { return fabs(u->in1) <= u->v_safe; }

static PIM_HOT_INLINE void model_sample(pim_unit *u)
{
    u->out1 = pim_pi_step_small((size_t)u->n, u->p, u->r, u->z, u->in1);
}
