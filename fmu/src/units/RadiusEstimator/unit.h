/* The RadiusEstimator unit (unit 2): the online radius estimator (pim_estimator.h) on inputs v
 * (in1) and y (in2), outputs y_hat (out1), e (out2), r_hat and health.  Integer parameter `law`
 * (PIM_LAW_DATA 0, the default, or PIM_LAW_PAPER 1, pim_estimator.h) and Integer output
 * `health`, the bit mask of the checks of pim_est_health.h on the samples processed so far (0
 * before the first one), evaluated after every doStep; the report in words (model_report) is
 * logged once at terminate when it is not 0.  Its hooks (fmi/pim_unit.h), included after the
 * unit struct. */
#include "plays.h"
#define HAS_MODEL_DEFAULTS
#define HAS_MODEL_CHECK_INPUTS
#define HAS_MODEL_OUTPUTS_FINITE
#define HAS_MODEL_STEP_DONE
#define HAS_MODEL_REPORT

typedef struct {
    pim_estimator est;
    pim_est_health health;
} model_saved;

/* A freshly initialised estimator for the unit's (checked) parameters. */
static int unit_init_estimator(pim_unit *u, pim_estimator *est)
{
    double g[PIM_NMAX];
    for (int i = 0; i < u->n; ++i) g[i] = u->gain;
    const char *msg = pim_est_init(est, (size_t)u->n, u->p, g, u->r, u->Ts, u->z0, u->threshold,
                                   0.0, 0.0, u->guard, u->linear_play);
    if (!msg) msg = pim_est_set_slope_check(est, u->slope_window, 0.5);
    if (!msg) msg = pim_est_set_law(est, u->law);
    return msg ? unit_error(u, "bad parameters: %s", msg) : 0;
}

/* The checks of pim_est_health.h on the samples processed so far (reversals: the estimator's
 * rule); merged and pinned (nullable) get the per-play flags. */
static int unit_health(const pim_unit *u, double *drift, double *range, double *fit,
                       int *merged, int *pinned)
{
    return pim_health_eval(&u->est_health, u->p, u->linear_play, u->est.have_rev > 0.0,
                           drift, range, fit, merged, pinned);
}

/*
 * The health report in words (no '%', hosts may use it as a format string) into buf; returns
 * the bit mask of the failed checks (0: healthy or no sample yet, buf empty).
 */
static int unit_health_report(const pim_unit *u, char *buf, size_t size)
{
    int merged[PIM_NMAX], pinned[PIM_NMAX];
    double drift, range, fit[2];
    const int n = u->n;
    buf[0] = '\0';
    if (u->est_health.count == 0.0) return 0;
    const int flags = unit_health(u, &drift, &range, fit, merged, pinned);
    if (!flags) return 0;
    const double *r = u->est_health.last;
    double sp = 0.0, spr = 0.0;
    for (int j = 0; j < n; ++j) {
        sp += u->p[j];
        spr += u->p[j] * r[j];
    }
    size_t len = 0;
#define PIM_ADD(...) \
    do { if (len < size) len += (size_t)snprintf(buf + len, size - len, __VA_ARGS__); } while (0)
    PIM_ADD("radius estimate health after %.0f samples (health = %d):", u->est_health.count,
            flags);
    if (flags & PIM_HEALTH_EXCITATION)
        PIM_ADD(" the record cannot excite every play (Lemma 2, Prop. 2): input range %g, "
                "2 r_hat[%d] = %g, loop width rho = %g, %s;", range, n, 2.0 * r[n - 1],
                2.0 * spr / sp, u->est.have_rev > 0.0 ? "reversals seen" : "no reversal");
    if (flags & PIM_HEALTH_MERGED) {
        PIM_ADD(" plays merged (equal estimates, the ordering constraint is active):");
        for (int j = 0; j + 1 < n; ++j)
            if (merged[j]) PIM_ADD(" r_hat[%d] = r_hat[%d]", j + 1, j + 2);
        PIM_ADD(";");
    }
    if (flags & PIM_HEALTH_PINNED) {
        PIM_ADD(" radius pinned at the projection bound 0:");
        for (int j = 0; j < n; ++j)
            if (pinned[j]) PIM_ADD(" r_hat[%d]", j + 1);
        PIM_ADD(";");
    }
    if (flags & PIM_HEALTH_MOVING)
        PIM_ADD(" estimate still moving at the end: drift %g between the last two quarters of "
                "the record (above 1 percent of max r_hat = %g); use a longer record or larger "
                "gains;", drift, r[n - 1]);
    if (flags & PIM_HEALTH_FIT)
        PIM_ADD(" the model does not fit the data: RMS error %g over the last quarter exceeds "
                "the noise bound %g (a wrong fixed point, e.g. law = 1 from below, weights "
                "that do not match the data, or dynamics the PI model lacks);", fit[0], fit[1]);
#undef PIM_ADD
    for (char *q = buf; *q; ++q)
        if (*q == '%') *q = ' ';
    return flags;
}

static void model_defaults(pim_unit *u)
{
    u->gain = 10.0;
    u->slope_window = 8;
}

static int model_check_parameters(pim_unit *u)
{
    if (plays_check(u, PLAYS_POSITIVE) != 0) return -1;
    if (!(u->gain >= 0.0) || !isfinite(u->gain))
        return unit_error(u, "parameter gain = %g: must be finite and >= 0", u->gain);
    if (!(u->guard >= 0.0) || !isfinite(u->guard))
        return unit_error(u, "parameter guard = %g: must be finite and >= 0", u->guard);
    if (!(u->threshold >= 0.0) || !isfinite(u->threshold))
        return unit_error(u, "parameter threshold = %g: must be finite and >= 0", u->threshold);
    if (u->slope_window < 0 || u->slope_window >= PIM_EST_WIN)
        return unit_error(u, "parameter slope_window = %d out of range: 0 <= slope_window <= %d",
                          u->slope_window, PIM_EST_WIN - 1);
    if (u->linear_play != 0 && u->linear_play != 1)
        return unit_error(u, "parameter linear_play = %d: must be a Boolean", u->linear_play);
    if (u->law != PIM_LAW_DATA && u->law != PIM_LAW_PAPER)
        return unit_error(u, "parameter law = %d out of range: 0 data (principal case from the "
                             "measured branches, default), 1 paper (from the estimate)", u->law);
    return 0;
}

static int model_setup(pim_unit *u)
{
    if (unit_init_estimator(u, &u->est) != 0) return -1;
    for (int i = 0; i < u->n; ++i) u->rhat_out[i] = u->est.rhat[i];
    (void)pim_health_init(&u->est_health, (size_t)u->n, 1);
    u->health = 0;
    return 0;
}

static int model_check_inputs(pim_unit *u)
{
    if (!isfinite(u->in2)) return unit_error(u, "input y = %g is not finite (NaN or Inf)", u->in2);
    return 0;
}

static void model_sample(pim_unit *u)
{
    const size_t n = (size_t)u->n;
    double yh, e, ed, rhat[PIM_MAX_PLAYS];
    memcpy(rhat, u->est.rhat, n * sizeof(double)); /* rhat[k], the estimate used at k */
    (void)pim_est_step(&u->est, u->in1, u->in2, NULL, &yh, &e, &ed);
    pim_health_add(&u->est_health, 1, &u->in1, rhat, &u->in2, &e);
    u->out1 = yh;
    u->out2 = e;
    for (size_t i = 0; i < n; ++i) u->rhat_out[i] = u->est.rhat[i];
}

/* The radii r_hat are outputs too. */
static int model_outputs_finite(const pim_unit *u)
{
    for (int i = 0; i < u->n; ++i)
        if (!isfinite(u->rhat_out[i])) return 0;
    return 1;
}

static void model_save(const pim_unit *u, model_saved *s)
{
    s->est = u->est;
    s->health = u->est_health;
}

static void model_restore(pim_unit *u, const model_saved *s)
{
    u->est = s->est;
    u->est_health = s->health;
    for (int i = 0; i < u->n; ++i) u->rhat_out[i] = u->est.rhat[i];
}

static void model_step_done(pim_unit *u)
{
    u->health = unit_health(u, NULL, NULL, NULL, NULL, NULL);
}

/* The estimator's state re-checked through a fresh estimator (pim_est_set_state), r_hat and the
 * health output recomputed. */
static int model_check_states(pim_unit *u, pim_unit *s)
{
    const size_t n = (size_t)s->n;
    if (s->est.n != n)
        return unit_error(u, "FMU state rejected: estimator has n = %llu plays, the unit %d",
                          (unsigned long long)s->est.n, s->n);
    double flat[PIM_EST_STATE_SIZE(PIM_MAX_PLAYS)];
    pim_est_get_state(&s->est, flat);
    pim_estimator fresh;
    if (unit_init_estimator(s, &fresh) != 0) return unit_error(u, "FMU state rejected: %s",
                                                               s->msg);
    const char *msg = pim_est_set_state(&fresh, flat);
    if (msg) return unit_error(u, "FMU state rejected: estimator %s", msg);
    s->est = fresh;
    for (size_t i = 0; i < n; ++i) s->rhat_out[i] = s->est.rhat[i];
    msg = pim_health_check(&s->est_health, n);
    if (msg) return unit_error(u, "FMU state rejected: %s", msg);
    s->health = s->est_health.count > 0.0 ? unit_health(s, NULL, NULL, NULL, NULL, NULL) : 0;
    return 0;
}

static int model_report(const pim_unit *u, char *buf, size_t size)
{
    return unit_health_report(u, buf, size);
}
