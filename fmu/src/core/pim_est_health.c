/* Health of a radius estimate; the checks are documented in pim_est_health.h. */
#include "pim_est_health.h"

#include <math.h>
#include <string.h>

size_t pim_health_sizeof(void) { return sizeof(pim_est_health); }

const char *pim_health_init(pim_est_health *h, size_t n, int with_fit)
{
    if (n < 1 || n > PIM_MAX_PLAYS) return "n: must be between 1 and 64";
    memset(h, 0, sizeof *h);
    h->n = n;
    h->with_fit = with_fit != 0;
    h->block = 1.0;
    h->next = 1.0;
    return NULL;
}

/* One row: running sums, ranges (v not NULL), last row, the fit terms (y, e with with_fit),
 * and a checkpoint when one is due. */
static void health_row(pim_est_health *h, const double *v, const double *r, double y, double e)
{
    const size_t n = h->n;
    if (v && (h->count == 0.0 || *v < h->vmin)) h->vmin = *v;
    if (v && (h->count == 0.0 || *v > h->vmax)) h->vmax = *v;
    if (h->with_fit) {
        if (h->count == 0.0 || y < h->ymin) h->ymin = y;
        if (h->count == 0.0 || y > h->ymax) h->ymax = y;
        if (h->count >= 2.0) h->d2sum += fabs(y - 2.0 * h->y1 + h->y2);
        h->y2 = h->y1;
        h->y1 = y;
        h->esq += e * e;
    }
    for (size_t j = 0; j < n; ++j) h->sum[j] += r[j];
    memcpy(h->last, r, n * sizeof(double));
    h->count += 1.0;
    if (h->count < h->next) return;
    if (h->ncheck == PIM_HEALTH_CHECKPOINTS) { /* full: keep every second, double the block */
        for (int i = 0; i < PIM_HEALTH_CHECKPOINTS / 2; ++i) {
            memcpy(h->check[i], h->check[2 * i + 1], n * sizeof(double));
            h->check_esq[i] = h->check_esq[2 * i + 1];
        }
        h->ncheck = PIM_HEALTH_CHECKPOINTS / 2;
        h->block *= 2.0;
    }
    if (fmod(h->count, h->block) == 0.0) {
        memcpy(h->check[(int)h->ncheck], h->sum, n * sizeof(double));
        h->check_esq[(int)h->ncheck] = h->esq;
        h->ncheck += 1.0;
    }
    h->next = (floor(h->count / h->block) + 1.0) * h->block;
}

void pim_health_add(pim_est_health *h, size_t N, const double *v, const double *R,
                    const double *y, const double *e)
{
    const int fit = h->with_fit && y && e;
    for (size_t k = 0; k < N; ++k)
        health_row(h, v ? v + k : NULL, R + k * h->n, fit ? y[k] : 0.0, fit ? e[k] : 0.0);
}

/* Sum of the first `rows` rows, rows a multiple of the block (0 or a checkpoint) or all. */
static const double *health_prefix(const pim_est_health *h, double rows, const double *zero)
{
    if (rows == h->count) return h->sum;
    const int i = (int)(rows / h->block);
    return i == 0 ? zero : h->check[i - 1];
}

/* The boundaries a, b of the quarters Q3 = [a, b), Q4 = [b, N) on the checkpoint grid; 0 if
 * there are none (q < 1). */
static int health_quarters(const pim_est_health *h, double *a, double *b)
{
    const double N = h->count, q = floor(N / 4.0);
    if (q < 1.0) return 0;
    *a = floor((N - 2.0 * q) / h->block) * h->block;
    *b = floor((N - q) / h->block) * h->block;
    return *b > *a; /* always: the grid is finer than a quarter */
}

/* RMS of e over Q4 and its bound 1.1 sigma_y + 1e-4 range(y); 0 if not checked. */
static int health_fit(const pim_est_health *h, double *rms, double *bound)
{
    double a, b;
    *rms = *bound = 0.0;
    if (!h->with_fit || h->count < 3.0 || !health_quarters(h, &a, &b)) return 0;
    const int i = (int)(b / h->block);
    const double esq_b = i == 0 ? 0.0 : h->check_esq[i - 1];
    const double mean = (h->esq - esq_b) / (h->count - b);
    *rms = sqrt(mean > 0.0 ? mean : 0.0);
    const double sigma = sqrt(2.0 * atan(1.0)) * h->d2sum / (h->count - 2.0) / sqrt(6.0);
    *bound = 1.1 * sigma + 1e-4 * (h->ymax - h->ymin);
    return 1;
}

/* max_j |mean over Q4 - mean over Q3| (the quarters of pim_est_health.h), 0 if q < 1. */
static double health_drift(const pim_est_health *h)
{
    double a, b;
    if (!health_quarters(h, &a, &b)) return 0.0;
    const double N = h->count;
    static const double zero[PIM_MAX_PLAYS];
    const double *sa = health_prefix(h, a, zero), *sb = health_prefix(h, b, zero);
    double drift = 0.0;
    for (size_t j = 0; j < h->n; ++j) {
        const double d = fabs((h->sum[j] - sb[j]) / (N - b) - (sb[j] - sa[j]) / (b - a));
        if (d > drift) drift = d;
    }
    return drift;
}

int pim_health_eval(const pim_est_health *h, const double *p, int linear_play, long reversals,
                    double *drift, double *input_range, double *fit, int *merged, int *pinned)
{
    const size_t n = h->n;
    const double *r = h->last;
    double scale = 0.0, sp = 0.0, spr = 0.0;
    for (size_t j = 0; j < n; ++j) {
        if (r[j] > scale) scale = r[j];
        sp += p[j];
        spr += p[j] * r[j];
    }
    int flags = 0;
    const double range = h->count > 0.0 ? h->vmax - h->vmin : 0.0;
    const double rho = 2.0 * spr / sp;
    if (range == 0.0 || reversals <= 0 || range <= rho || range <= 2.0 * r[n - 1])
        flags |= PIM_HEALTH_EXCITATION;
    const double tol = PIM_HEALTH_MERGE_TOL * (scale > 1e-12 ? scale : 1e-12);
    for (size_t j = 0; j + 1 < n; ++j) {
        const int m = r[j + 1] - r[j] <= tol;
        if (m) flags |= PIM_HEALTH_MERGED;
        if (merged) merged[j] = m;
    }
    for (size_t j = 0; j < n; ++j) {
        const int pin = r[j] == 0.0 && !(linear_play && j == 0);
        if (pin) flags |= PIM_HEALTH_PINNED;
        if (pinned) pinned[j] = pin;
    }
    const double d = health_drift(h);
    if (d > PIM_HEALTH_MOVING_TOL * scale) flags |= PIM_HEALTH_MOVING;
    double rms, bound;
    if (health_fit(h, &rms, &bound) && rms > bound) flags |= PIM_HEALTH_FIT;
    if (drift) *drift = d;
    if (input_range) *input_range = range;
    if (fit) {
        fit[0] = rms;
        fit[1] = bound;
    }
    return flags;
}

const char *pim_health_check(const pim_est_health *h, size_t n)
{
    if (h->n != n) return "health: play count differs from the unit's";
    const double c = h->count, b = h->block;
    if (!isfinite(c) || c < 0.0 || c != floor(c) || c > 9007199254740992.0)
        return "health: row count must be a whole number >= 0";
    if (!isfinite(b) || b < 1.0 || frexp(b, &(int){0}) != 0.5)
        return "health: block must be a power of 2";
    if (h->ncheck != floor(c / b) || h->ncheck > PIM_HEALTH_CHECKPOINTS ||
        h->next != (floor(c / b) + 1.0) * b)
        return "health: checkpoints do not match the row count";
    if (c > 0.0 && !(isfinite(h->vmin) && isfinite(h->vmax) && h->vmin <= h->vmax))
        return "health: input range must be finite";
    for (size_t j = 0; j < n; ++j) {
        if (!isfinite(h->sum[j]) || !isfinite(h->last[j]))
            return "health: sums must be finite";
        for (int i = 0; i < (int)h->ncheck; ++i)
            if (!isfinite(h->check[i][j])) return "health: sums must be finite";
    }
    if (h->with_fit != 0 && h->with_fit != 1) return "health: with_fit must be 0 or 1";
    if (!isfinite(h->esq) || h->esq < 0.0 || !isfinite(h->d2sum) || h->d2sum < 0.0 ||
        !isfinite(h->y1) || !isfinite(h->y2) ||
        (c > 0.0 && !(isfinite(h->ymin) && isfinite(h->ymax) && h->ymin <= h->ymax)))
        return "health: fit sums must be finite and >= 0";
    for (int i = 0; i < (int)h->ncheck; ++i)
        if (!isfinite(h->check_esq[i]) || h->check_esq[i] < 0.0)
            return "health: fit sums must be finite and >= 0";
    return NULL;
}
