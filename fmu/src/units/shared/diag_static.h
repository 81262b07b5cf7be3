/* The static part shared by the DiagnosedModel (8) and DiagnosedInverse (9) units (fields in
 * diag_fields.h): start values, the plays' arrays joined and their parameter rules, written
 * once for both. */
#ifndef PIM_DIAG_STATIC_H
#define PIM_DIAG_STATIC_H

/* The highest creep_start a unit takes and its words in the range message: 0 at rest at h0[0],
 * 1 at a common rest; a unit that also counts the creep from the record's start (DiagnosedModel:
 * 2) defines both before including this file. */
#ifndef PIM_CREEP_START_MAX
#define PIM_CREEP_START_MAX 1
#define PIM_CREEP_START_MORE ""
#endif


/* Start values of the static part's parameters (the spec's). */
static void unit_diag_defaults(pim_unit *u)
{
    for (int i = 0; i < PIM_NMAX; ++i) {
        u->w0[i] = u->w0_hi[i] = u->p_hi[i] = 1.0;
        u->creep_tau[i] = 1.0;
    }
    u->half_range = u->rate_scale = u->input_range = 1.0;
}

/* The plays' arrays joined: plays 1..64 from p, r, w0, rate_band_gain, 65..128 from the _hi
 * arrays (derived, recomputed for every restored state). */
static void unit_diag_join(pim_unit *u)
{
    for (int i = 0; i < PIM_DIAG_MAX_PLAYS; ++i) {
        const int lo = i < PIM_NMAX, j = lo ? i : i - PIM_NMAX;
        u->dw[i] = lo ? u->p[j] : u->p_hi[j];
        u->dr[i] = lo ? u->r[j] : u->r_hi[j];
        u->dw0[i] = lo ? u->w0[j] : u->w0_hi[j];
        u->drb[i] = lo ? u->rate_band_gain[j] : u->rate_band_gain_hi[j];
    }
}

/* The derived quantities of the static part: the creep poles and the joined arrays. */
static void unit_diag_derive(pim_unit *u)
{
    for (int j = 0; j < u->n_lags; ++j) u->a[j] = exp(-u->Ts / u->creep_tau[j]);
    unit_diag_join(u);
}

/* The flat state (dstate) a step changes, for its rollback: model_save saves its first size
 * values (pim_diag's or pim_dinv's state size) with unit_diag_save. */
typedef struct {
    size_t size;
    double x[PIM_DIAG_STATE_MAX];
} model_saved;

static void unit_diag_save(const pim_unit *u, model_saved *s, size_t size)
{
    s->size = size;
    memcpy(s->x, u->dstate, size * sizeof(double));
}

static void model_restore(pim_unit *u, const model_saved *s)
{
    memcpy(u->dstate, s->x, s->size * sizeof(double));
}

/* "p[3]" or "p_hi[2]" for play i (0-based) of array `name`. */
static const char *unit_play_name(const char *name, int i, char *buf, size_t size)
{
    if (i < PIM_NMAX)
        snprintf(buf, size, "%s[%d]", name, i + 1);
    else
        snprintf(buf, size, "%s_hi[%d] (play %d)", name, i - PIM_NMAX + 1, i + 1);
    return buf;
}

/* The rules of the static part's parameters (units 8 and 9), with the variable, index and
 * value in the message. */
static int unit_check_diag_static(pim_unit *u)
{
    unit_diag_join(u);
    char a[48], b[48];
    for (int i = 0; i < u->n; ++i) {
        if (!isfinite(u->dw[i]))
            return unit_error(u, "weight %s = %g is not finite (weights may have any sign)",
                              unit_play_name("p", i, a, sizeof a), u->dw[i]);
        if (!isfinite(u->dw0[i]))
            return unit_error(u, "reference weight %s = %g is not finite",
                              unit_play_name("w0", i, a, sizeof a), u->dw0[i]);
        if (!isfinite(u->dr[i]))
            return unit_error(u, "radius %s = %g is not finite",
                              unit_play_name("r", i, a, sizeof a), u->dr[i]);
        if (u->dr[i] < 0.0)
            return unit_error(u, "radius %s = %g is negative (radii must be >= 0)",
                              unit_play_name("r", i, a, sizeof a), u->dr[i]);
        if (i > 0 && u->dr[i] < u->dr[i - 1])
            return unit_error(u, "radii not sorted: %s = %g < %s = %g (need r[1] <= ... <= "
                                 "r[n])", unit_play_name("r", i, a, sizeof a), u->dr[i],
                              unit_play_name("r", i - 1, b, sizeof b), u->dr[i - 1]);
        if (!isfinite(u->drb[i]))
            return unit_error(u, "rate gain %s = %g is not finite",
                              unit_play_name("rate_band_gain", i, a, sizeof a), u->drb[i]);
    }
    if (!isfinite(u->offset) || !isfinite(u->reference_offset))
        return unit_error(u, "parameters offset = %g, reference_offset = %g: must be finite",
                          u->offset, u->reference_offset);
    if (u->n_lags < 0 || u->n_lags > PIM_NMAX)
        return unit_error(u, "parameter n_lags = %d out of range: 0 <= n_lags <= %d", u->n_lags,
                          PIM_NMAX);
    for (int j = 0; j < u->n_lags; ++j) {
        if (!isfinite(u->creep_gain[j]))
            return unit_error(u, "creep gain creep_gain[%d] = %g is not finite", j + 1,
                              u->creep_gain[j]);
        if (!isfinite(u->creep_tau[j]) || !(u->creep_tau[j] > 0.0))
            return unit_error(u, "time constant creep_tau[%d] = %g is not positive (must be "
                                 "finite and > 0 s)", j + 1, u->creep_tau[j]);
        u->a[j] = exp(-u->Ts / u->creep_tau[j]); /* derived; checked below */
    }
    if (u->creep_start < 0 || u->creep_start > PIM_CREEP_START_MAX)
        return unit_error(u, "parameter creep_start = %d out of range: 0 at rest at h0[0], 1 at "
                             "rest at creep_start_level" PIM_CREEP_START_MORE, u->creep_start);
    for (int j = 0; u->creep_start == 1 && j < u->n_lags; ++j)
        if (!isfinite(u->creep_start_level[j]))
            return unit_error(u, "creep start level creep_start_level[%d] = %g is not finite",
                              j + 1, u->creep_start_level[j]);
    if (!isfinite(u->asym_q) || !isfinite(u->asym_c3) || !isfinite(u->center))
        return unit_error(u, "parameters asymmetry_quadratic, asymmetry_cubic, center = (%g, %g, "
                             "%g): must be finite", u->asym_q, u->asym_c3, u->center);
    if (!isfinite(u->half_range) || !(u->half_range > 0.0))
        return unit_error(u, "parameter half_range = %g: must be finite and > 0", u->half_range);
    if (!isfinite(u->rate_scale) || !(u->rate_scale > 0.0))
        return unit_error(u, "parameter rate_scale = %g: must be finite and > 0", u->rate_scale);
    if (u->rate_family != PIM_DIAG_RATE_RADIUS && u->rate_family != PIM_DIAG_RATE_WEIGHT &&
        u->rate_family != PIM_DIAG_RATE_SCALED)
        return unit_error(u, "parameter rate_family = %d out of range: 0 radius, 1 weight, "
                             "2 scaled", u->rate_family);
    if (!isfinite(u->rate_growth))
        return unit_error(u, "parameter rate_growth = %g: must be finite", u->rate_growth);
    if (u->rate_family == PIM_DIAG_RATE_SCALED && !(u->rate_tau > 0.0))
        return unit_error(u, "parameter rate_tau = %g: the scaled rate family (rate_family 2) "
                             "needs rate_tau > 0 s", u->rate_tau);
    if (!isfinite(u->rate_tau) || u->rate_tau < 0.0)
        return unit_error(u, "parameter rate_tau = %g: must be finite and >= 0 s",
                          u->rate_tau);
    if (!isfinite(u->rate_saturation) || u->rate_saturation < 0.0)
        return unit_error(u, "parameter rate_saturation = %g: must be finite and >= 0 (0: no "
                             "saturation)", u->rate_saturation);
    if (!isfinite(u->input_range) || !(u->input_range > 0.0))
        return unit_error(u, "parameter input_range = %g: must be finite and > 0",
                          u->input_range);
    return 0;
}

/* The static part's fields of a pim_diag (unit 8) or pim_dinv (unit 9) d, which share their
 * names, from the unit's checked parameters u (pointers into u). */
#define PIM_FILL_STATIC(d, u)                                                                 \
    do {                                                                                        \
        int rate_ = 0;                                                                          \
        for (int i_ = 0; i_ < (u)->n; ++i_) rate_ |= (u)->drb[i_] != 0.0;                       \
        (d)->n = (size_t)(u)->n;                                                                \
        (d)->w = (u)->dw;                                                                       \
        (d)->r = (u)->dr;                                                                       \
        (d)->w0 = (u)->dw0;                                                                     \
        (d)->c = (u)->offset;                                                                   \
        (d)->c0 = (u)->reference_offset;                                                        \
        (d)->m = (u)->n_lags > 0 ? (size_t)(u)->n_lags : 0;                                     \
        (d)->lag_a = (u)->a;                                                                    \
        (d)->lag_g = (u)->creep_gain;                                                           \
        (d)->lag_start = (u)->creep_start == 1 ? (u)->creep_start_level : NULL;                 \
        (d)->asym = (u)->asym_q != 0.0 || (u)->asym_c3 != 0.0;                                  \
        (d)->q = (u)->asym_q;                                                                   \
        (d)->c3 = (u)->asym_c3;                                                                 \
        (d)->center = (u)->center;                                                              \
        (d)->half = (u)->half_range;                                                            \
        (d)->rate_w = rate_ ? (u)->drb : NULL;                                                  \
        (d)->dt = (u)->Ts;                                                                      \
        (d)->rate_scale = (u)->rate_scale;                                                      \
        (d)->input_range = (u)->input_range;                                                    \
        (d)->rate_family = (u)->rate_family;                                                    \
        (d)->rate_tau = (u)->rate_tau;                                                          \
        (d)->rate_saturation = (u)->rate_saturation;                                            \
        (d)->rate_growth = (u)->rate_growth;                                                    \
    } while (0)

#endif /* PIM_DIAG_STATIC_H */
