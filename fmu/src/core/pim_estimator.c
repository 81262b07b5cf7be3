/* Adaptive radius estimator; the discrete-time law is documented in pim_estimator.h. */
#include "pim_estimator.h"

#include <math.h>
#include <string.h>

void pim_project_ordered(size_t n, double *x, const double *w, int fix_first)
{
    double val[PIM_MAX_PLAYS], wt[PIM_MAX_PLAYS];
    size_t cnt[PIM_MAX_PLAYS];
    size_t start = 0, nb = 0;
    if (fix_first && n > 0) {
        x[0] = 0.0;
        start = 1;
    }
    for (size_t i = start; i < n; ++i) { /* pool adjacent violators */
        val[nb] = x[i];
        wt[nb] = w[i];
        cnt[nb] = 1;
        ++nb;
        while (nb > 1 && val[nb - 2] > val[nb - 1]) {
            double ws = wt[nb - 2] + wt[nb - 1];
            val[nb - 2] = (wt[nb - 2] * val[nb - 2] + wt[nb - 1] * val[nb - 1]) / ws;
            wt[nb - 2] = ws;
            cnt[nb - 2] += cnt[nb - 1];
            --nb;
        }
    }
    size_t i = start;
    for (size_t b = 0; b < nb; ++b) {
        double v = val[b] > 0.0 ? val[b] : 0.0;
        for (size_t c = 0; c < cnt[b]; ++c) x[i++] = v;
    }
}

static void est_weights(const pim_estimator *est, double *w)
{
    for (size_t j = 0; j < est->n; ++j) w[j] = 1.0 / (est->gain[j] > 1e-300 ? est->gain[j] : 1e-300);
}

/* 1 if rhat already satisfies 0 <= rhat_1 <= ... <= rhat_n (and rhat_1 == 0 if known_linear). */
static int est_feasible(const pim_estimator *est)
{
    if (est->known_linear ? est->rhat[0] != 0.0 : est->rhat[0] < 0.0) return 0;
    for (size_t j = 1; j < est->n; ++j)
        if (est->rhat[j] < est->rhat[j - 1]) return 0;
    return 1;
}

size_t pim_est_sizeof(void) { return sizeof(pim_estimator); }

const char *pim_est_set_slope_check(pim_estimator *est, int window, double tol)
{
    if (window < 0 || window >= PIM_EST_WIN) return "slope_window: must be between 0 and 63";
    if (!(tol > 0.0) || !isfinite(tol)) return "slope_tol: must be finite and > 0";
    est->slope_window = window;
    est->slope_tol = tol;
    return NULL;
}

const char *pim_est_set_law(pim_estimator *est, int law)
{
    if (law != PIM_LAW_DATA && law != PIM_LAW_PAPER) return "law: must be 0 (data) or 1 (paper)";
    est->law = law;
    return NULL;
}

/* Band of the data law around a fitted breakpoint: at least one bin (the breakpoint lies
 * in the bin on either side of the fitted edge). */
static double est_data_guard(const pim_estimator *est)
{
    const double g = est->width;
    return est->guard > g ? est->guard : g;
}

/* Add the branch piece [x0, x1] (travel) with output change dy to the profile, spread over the
 * bins it covers in proportion to the overlap; bins are merged in pairs (width doubled) until
 * x1 fits. */
static void est_profile_add(pim_estimator *est, double x0, double x1, double dy)
{
    while (x1 >= PIM_EST_BINS * est->width) {
        for (int b = 0; b < PIM_EST_BINS / 2; ++b) {
            est->S[b] = est->S[2 * b] + est->S[2 * b + 1];
            est->C[b] = est->C[2 * b] + est->C[2 * b + 1];
        }
        for (int b = PIM_EST_BINS / 2; b < PIM_EST_BINS; ++b) est->S[b] = est->C[b] = 0.0;
        est->width *= 2.0;
        est->top = est->top >= 0.0 ? (double)((int)est->top / 2) : -1.0;
    }
    const double w = est->width, span = x1 - x0;
    int b0 = (int)(x0 / w), b1 = (int)(x1 / w);
    if (b1 > PIM_EST_BINS - 1) b1 = PIM_EST_BINS - 1;
    if (b0 > b1) b0 = b1;
    if (b0 == b1) { /* the usual case: one bin (dy * (span / span) == dy exactly) */
        est->S[b1] += dy;
        est->C[b1] += span;
        if ((double)b1 > est->top) est->top = (double)b1;
        return;
    }
    for (int b = b0; b <= b1; ++b) {
        double lo = b * w > x0 ? b * w : x0, hi = (b + 1) * w < x1 ? (b + 1) * w : x1;
        double part = b0 == b1 ? span : (hi > lo ? hi - lo : 0.0);
        est->S[b] += dy * (part / span);
        est->C[b] += part;
    }
    if ((double)b1 > est->top) est->top = (double)b1;
}

/* Fit the regime table: the non-decreasing count i_b of plays on their envelope in bin b that
 * minimises sum_b C_b (S_b / C_b - P_{i_b})^2 (dynamic programme over bins and counts), and
 * store its breakpoints edge_j (travel of the first bin with i_b >= j, -1 if none). */
static void est_fit_regimes(pim_estimator *est)
{
    const int n = (int)est->n, top = (int)est->top, imin = est->known_linear ? 1 : 0;
    if (top < 0) return;
    double P[PIM_MAX_PLAYS + 1], f[PIM_MAX_PLAYS + 1];
    static const double BIG = 1e300;
    unsigned char back[PIM_EST_BINS][PIM_MAX_PLAYS + 1];
    P[0] = 0.0;
    for (int i = 1; i <= n; ++i) P[i] = P[i - 1] + est->p[i - 1];
    for (int i = 0; i <= n; ++i)
        f[i] = i < imin ? BIG : est->C[0] * P[i] * P[i] - 2.0 * est->S[0] * P[i];
    for (int b = 1; b <= top; ++b) {
        double best = BIG;
        int arg = 0;
        for (int i = 0; i <= n; ++i) {
            if (f[i] < best) {
                best = f[i];
                arg = i;
            }
            back[b][i] = (unsigned char)arg;
            f[i] = i < imin ? BIG : best + est->C[b] * P[i] * P[i] - 2.0 * est->S[b] * P[i];
        }
    }
    int i = imin;
    for (int k = imin; k <= n; ++k)
        if (f[k] < f[i]) i = k;
    for (int j = 0; j < n; ++j) est->edge[j] = -1.0;
    for (int b = top; b >= 0; --b) {
        for (int j = 0; j < i; ++j) est->edge[j] = b * est->width;
        if (b > 0) i = back[b][i];
    }
    est->fitted = 1.0;
}

/* Regime of the data law at travel d: on[j] = 1 if play j is on its envelope.  Returns 0 if
 * the sample is not to be used.  Away from a fitted breakpoint edge_j (by the guard band g) the
 * table decides; within the band the estimate decides (d >= 2 rhat_j, the paper's rule, finer
 * than a bin) if 2 rhat_j itself lies in the band and d is at least `guard` from it, else the
 * sample is skipped.  While the profile does not yet cover the travel t_prev (the first
 * branches), a play whose breakpoint has not been profiled follows the paper's rule.
 * Skipped too: no table yet, a travel beyond the profiled one with plays
 * not yet on, an interior play whose fitted breakpoint (plus g) exceeds the travel t_prev of
 * the segment before the reversal (not surely saturated there). */
static int est_regime_data(const pim_estimator *est, double d, int *on)
{
    if (est->fitted == 0.0) return 0;
    const double g = est_data_guard(est);
    const int partial = (est->top + 1.0) * est->width < est->t_prev;
    int all_on = 1;
    for (size_t j = 0; j < est->n; ++j) {
        const double b = est->edge[j];
        if (b < 0.0 && partial) { /* breakpoint not profiled yet: the paper's rule */
            if (fabs(d - 2.0 * est->rhat[j]) < est->guard) return 0;
            on[j] = d >= 2.0 * est->rhat[j];
            if (!on[j] && est->sat[j] == 0.0) return 0;
            if (!on[j]) all_on = 0;
            continue;
        }
        if (b < 0.0) {
            on[j] = 0;
        } else if (fabs(d - b) >= g) {
            on[j] = d >= b;
        } else {
            const double b2 = 2.0 * est->rhat[j];
            if (fabs(b2 - b) >= g || fabs(d - b2) < est->guard) return 0;
            on[j] = d >= b2;
        }
        if (!on[j]) {
            all_on = 0;
            if (b < 0.0 || b + g > est->t_prev) return 0;
        }
    }
    if (!all_on && d >= (est->top + 1.0) * est->width) return 0;
    return 1;
}

/* Regime of the paper's law at travel d (from the estimate), or 0 if not to be used. */
static int est_regime_paper(const pim_estimator *est, double d, int *on)
{
    for (size_t j = 0; j < est->n; ++j) {
        if (fabs(d - 2.0 * est->rhat[j]) < est->guard) return 0;
        on[j] = d >= 2.0 * est->rhat[j];
        if (!on[j] && est->sat[j] == 0.0) return 0;
    }
    return 1;
}

/* Slope check: measured vs case-model output change over the window before this sample. */
static int est_slope_ok(const pim_estimator *est)
{
    const int m = est->slope_window;
    if (m == 0) return 1;
    if (est->nseg < (double)(m + 1)) return 0;
    const int hb = ((int)est->head + PIM_EST_WIN - 1) % PIM_EST_WIN;
    const int ha = ((int)est->head + PIM_EST_WIN - 1 - m) % PIM_EST_WIN;
    const double da = fabs(est->vbuf[ha] - est->v_rev), db = fabs(est->vbuf[hb] - est->v_rev);
    const double travel = db - da;
    if (travel <= 0.0) return 1; /* hold: nothing to compare */
    double model = 0.0, pmin = est->p[0];
    for (size_t j = 0; j < est->n; ++j) {
        double start = da > 2.0 * est->rhat[j] ? da : 2.0 * est->rhat[j];
        if (db > start) model += est->p[j] * (db - start);
        if (est->p[j] < pmin) pmin = est->p[j];
    }
    const double meas = est->dir * (est->ybuf[hb] - est->ybuf[ha]);
    return fabs(meas - model) <= est->slope_tol * pmin * travel;
}

const char *pim_est_init(pim_estimator *est, size_t n, const double *p, const double *gains,
                         const double *rhat0, double dt, double z0, double threshold,
                         double max_step, double anneal_time, double guard, int known_linear)
{
    if (n < 1 || n > PIM_MAX_PLAYS) return "n: the number of plays must be between 1 and 64";
    if (!(dt > 0.0) || !isfinite(dt)) return "dt: the sample time must be finite and > 0";
    if (!isfinite(z0)) return "initial state: must be finite";
    if (!(threshold >= 0.0) || !isfinite(threshold)) return "threshold: must be finite and >= 0";
    if (!isfinite(max_step)) return "max_step: must be finite";
    if (!isfinite(anneal_time)) return "anneal_time: must be finite";
    if (!(guard >= 0.0) || !isfinite(guard)) return "guard: must be finite and >= 0";
    for (size_t j = 0; j < n; ++j) {
        if (!isfinite(p[j]) || !(p[j] > 0.0)) return "weights: every weight must be finite and > 0";
        if (!isfinite(gains[j]) || gains[j] < 0.0) return "gains: every gain must be finite and >= 0";
        if (!isfinite(rhat0[j]) || rhat0[j] < 0.0)
            return "initial radii: every radius must be finite and >= 0";
    }
    memset(est, 0, sizeof(*est));
    est->n = n;
    est->dt = dt;
    est->threshold = threshold;
    est->max_step = max_step;
    est->anneal_time = anneal_time;
    est->guard = guard;
    est->known_linear = known_linear ? 1 : 0;
    est->slope_window = 8;
    est->slope_tol = 0.5;
    est->law = PIM_LAW_DATA;
    est->top = -1.0;
    for (size_t j = 0; j < n; ++j) {
        est->p[j] = p[j];
        est->gain[j] = gains[j];
        est->rhat[j] = rhat0[j];
        est->zhat[j] = z0;
    }
    double w[PIM_MAX_PLAYS];
    est_weights(est, w);
    pim_project_ordered(n, est->rhat, w, est->known_linear);
    return NULL;
}

/* sat_j = 1 iff a segment travel of `travel` surely saturated play j. */
static void est_saturation(pim_estimator *est, double travel)
{
    for (size_t j = 0; j < est->n; ++j)
        est->sat[j] = travel >= 2.0 * est->rhat[j] + est->guard ? 1.0 : 0.0;
}

int pim_est_step(pim_estimator *est, double v, double y, double *rhat_used, double *yhat,
                 double *e, double *e_delta)
{
    const size_t n = est->n;
    if (!isfinite(v) || !isfinite(y)) return -1;
    if (rhat_used) memcpy(rhat_used, est->rhat, n * sizeof(double));

    /* 1. time-dependent model */
    double yh = 0.0;
    for (size_t j = 0; j < n; ++j) {
        double lo = v - est->rhat[j], hi = v + est->rhat[j], z = est->zhat[j];
        z = z < hi ? z : hi;
        z = z > lo ? z : lo;
        est->zhat[j] = z;
        yh += est->p[j] * z;
    }
    *yhat = yh;
    *e = yh - y;
    *e_delta = 0.0;

    /* 2. segments and reversals */
    int usable = 0;
    if (!est->started) {
        est->started = 1.0;
        est->v_first = v;
        est->v_start = v;
        est->v_ext = v;
        est->y_ext = y;
    } else if (est->dir == 0.0) {
        if (fabs(v - est->v_first) > est->threshold) {
            est->dir = v > est->v_first ? 1.0 : -1.0;
            est->v_ext = v;
            est->y_ext = y;
        }
    } else if (est->dir * (v - est->v_ext) >= 0.0) {
        if (est->dir * (v - est->v_ext) > 0.0) {
            est->v_ext = v;
            est->y_ext = y;
        }
        usable = est->have_rev != 0.0;
    } else if (fabs(v - est->v_ext) > est->threshold) {
        est->t_prev = fabs(est->v_ext - est->v_start);
        est_saturation(est, est->t_prev);
        est->v_rev = est->v_ext;
        est->v_start = est->v_ext;
        est->have_rev = 1.0;
        est->dir = -est->dir;
        est->x_last = 0.0;
        est->y_last = est->y_ext;
        est->v_ext = v;
        est->y_ext = y;
        est->nseg = 0.0;
        usable = 1;
        if (est->law == PIM_LAW_DATA) {
            if (est->width == 0.0) est->width = 2.2 * est->t_prev / PIM_EST_BINS;
            est_fit_regimes(est);
        }
    }

    /* 3. principal case and modified error */
    int used = 0;
    if (usable) {
        const double s = est->dir, d = fabs(v - est->v_rev);
        int on[PIM_MAX_PLAYS], ok;
        if (est->law == PIM_LAW_DATA) {
            if (d > est->x_last) { /* the branch profile: F(x) holds for x <= t_prev */
                if (d <= est->t_prev) {
                    const double top = est->top;
                    est_profile_add(est, est->x_last, d, s * (y - est->y_last));
                    if (est->top > top) est_fit_regimes(est); /* the profile grew */
                }
                est->x_last = d;
                est->y_last = y;
            }
            ok = est_regime_data(est, d, on);
        } else {
            ok = est_slope_ok(est) && est_regime_paper(est, d, on);
        }
        if (ok) {
            double phi[PIM_MAX_PLAYS], ybar = 0.0;
            for (size_t j = 0; j < n; ++j) {
                if (on[j]) {
                    phi[j] = est->p[j];
                    ybar += est->p[j] * (v - s * est->rhat[j]);
                } else {
                    phi[j] = -est->p[j];
                    ybar += est->p[j] * (est->v_rev + s * est->rhat[j]);
                }
            }
            /* 4. gradient step with projection */
            const double ed = ybar - y;
            const double scale = est->anneal_time > 0.0 ? 1.0 / (1.0 + est->time / est->anneal_time) : 1.0;
            double w[PIM_MAX_PLAYS];
            for (size_t j = 0; j < n; ++j) {
                double step = est->dt * est->gain[j] * scale * ed * s * phi[j];
                if (est->max_step > 0.0) {
                    step = step > est->max_step ? est->max_step : step;
                    step = step < -est->max_step ? -est->max_step : step;
                }
                est->rhat[j] += step;
            }
            if (!est_feasible(est)) { /* the projection is the identity on feasible points */
                est_weights(est, w);
                pim_project_ordered(n, est->rhat, w, est->known_linear);
            }
            *e_delta = ed;
            used = 1;
        }
    }
    est->time += est->dt;
    est->nseg += 1.0;
    const int h = (int)est->head;
    est->vbuf[h] = v;
    est->ybuf[h] = y;
    est->head = (double)((h + 1) % PIM_EST_WIN);
    return used;
}

long pim_est_run(pim_estimator *est, size_t N, const double *v, const double *y, double *R,
                 double *yhat, double *e, double *e_delta, double *used)
{
    for (size_t k = 0; k < N; ++k) {
        int u = pim_est_step(est, v[k], y[k], R ? R + k * est->n : NULL, yhat + k, e + k,
                             e_delta + k);
        if (u < 0) return (long)k;
        if (used) used[k] = (double)u;
    }
    return -1;
}

void pim_est_get_state(const pim_estimator *est, double *state)
{
    const size_t n = est->n;
    memcpy(state, est->rhat, n * sizeof(double));
    memcpy(state + n, est->zhat, n * sizeof(double));
    memcpy(state + 2 * n, est->sat, n * sizeof(double));
    double *s = state + 3 * n;
    s[0] = est->v_first;
    s[1] = est->v_start;
    s[2] = est->v_ext;
    s[3] = est->v_rev;
    s[4] = est->dir;
    s[5] = est->have_rev;
    s[6] = est->started;
    s[7] = est->time;
    s[8] = est->nseg;
    s[9] = est->head;
    memcpy(s + 10, est->vbuf, PIM_EST_WIN * sizeof(double));
    memcpy(s + 10 + PIM_EST_WIN, est->ybuf, PIM_EST_WIN * sizeof(double));
    double *q = s + 10 + 2 * PIM_EST_WIN;
    q[0] = est->t_prev;
    q[1] = est->y_ext;
    q[2] = est->x_last;
    q[3] = est->y_last;
    q[4] = est->width;
    q[5] = est->top;
    q[6] = est->fitted;
    memcpy(q + 7, est->edge, n * sizeof(double));
    memcpy(q + 7 + n, est->S, PIM_EST_BINS * sizeof(double));
    memcpy(q + 7 + n + PIM_EST_BINS, est->C, PIM_EST_BINS * sizeof(double));
}

const char *pim_est_set_state(pim_estimator *est, const double *state)
{
    const size_t n = est->n;
    for (size_t i = 0; i < PIM_EST_STATE_SIZE(n); ++i) {
        if (!isfinite(state[i])) return "state: every entry must be finite";
    }
    for (size_t j = 0; j < n; ++j) {
        if (state[j] < 0.0 || (j > 0 && state[j] < state[j - 1]))
            return "state: radii must satisfy 0 <= r_1 <= ... <= r_n";
    }
    memcpy(est->rhat, state, n * sizeof(double));
    memcpy(est->zhat, state + n, n * sizeof(double));
    memcpy(est->sat, state + 2 * n, n * sizeof(double));
    const double *s = state + 3 * n;
    est->v_first = s[0];
    est->v_start = s[1];
    est->v_ext = s[2];
    est->v_rev = s[3];
    est->dir = s[4];
    est->have_rev = s[5];
    est->started = s[6];
    est->time = s[7];
    est->nseg = s[8];
    est->head = (s[9] >= 0.0 && s[9] < PIM_EST_WIN) ? (double)(int)s[9] : 0.0;
    memcpy(est->vbuf, s + 10, PIM_EST_WIN * sizeof(double));
    memcpy(est->ybuf, s + 10 + PIM_EST_WIN, PIM_EST_WIN * sizeof(double));
    const double *q = s + 10 + 2 * PIM_EST_WIN;
    est->t_prev = q[0];
    est->y_ext = q[1];
    est->x_last = q[2];
    est->y_last = q[3];
    est->width = q[4] > 0.0 ? q[4] : 0.0;
    est->top = (q[5] >= 0.0 && q[5] < PIM_EST_BINS) ? (double)(int)q[5] : -1.0;
    est->fitted = q[6];
    memcpy(est->edge, q + 7, n * sizeof(double));
    memcpy(est->S, q + 7 + n, PIM_EST_BINS * sizeof(double));
    memcpy(est->C, q + 7 + n + PIM_EST_BINS, PIM_EST_BINS * sizeof(double));
    return NULL;
}
