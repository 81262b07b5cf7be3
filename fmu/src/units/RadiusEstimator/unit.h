/* The RadiusEstimator unit (unit 2): its own rules and helpers, included by the framework
 * fmu/src/fmi/pim_unit.h after the unit struct and unit_error. */

/* A freshly initialised estimator for the unit's (checked) parameters. */
static int unit_init_estimator(pim_unit *u, pim_estimator *est)
{
    double g[PIM_NMAX];
    for (int i = 0; i < u->n; ++i) g[i] = u->gain;
    const char *msg = pim_est_init(est, (size_t)u->n, u->p, g, u->r, u->Ts, u->z0, 0.0, 0.0, 0.0,
                                   u->guard, u->linear_play);
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
