/* The diagnosed model's causal feedforward; semantics and state layout in pim_diag_inverse.h. */
#include "pim_diag_inverse.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define DINV_NB_MAX (4 * PIM_DINV_MAX_PLAYS + 3) /* breakpoints: z -+ r, zs -+ rs (scaled rate),
                                                   v_prev, 2 ends */
#define DINV_BISECT 200                          /* bisection steps (a double halves ~1100) */

static inline double dinv_clamp(double z, double lo, double hi)
{
    z = z < hi ? z : hi;
    return z > lo ? z : lo;
}

static inline double dinv_sign(double x)
{
    return x > 0.0 ? 1.0 : (x < 0.0 ? -1.0 : 0.0);
}

/* the filtered rate as the terms take it: rho / (1 + rho / S) with rate_saturation S > 0 */
static inline double dinv_saturate(const pim_dinv *d, double rho)
{
    return d->rate_saturation > 0.0 ? rho / (1.0 + rho / d->rate_saturation) : rho;
}

size_t pim_dinv_solver_size(const pim_dinv *d, int rate)
{
    const size_t base = 3 + d->n + d->m + (d->lag_record ? 1 : 0); /* L0 (record start) */
    if (rate && d->rate_family == PIM_DIAG_RATE_SCALED) return base + 1 + d->n; /* s, zs */
    return rate ? base + 2 + d->n + base : base;
}

size_t pim_dinv_state_size(const pim_dinv *d)
{
    return PIM_DINV_HEAD + 2 * (d->ns + d->npost) + pim_dinv_solver_size(d, d->rate_w != NULL);
}

static int finite_all(const double *x, size_t n)
{
    for (size_t i = 0; i < n; ++i)
        if (!isfinite(x[i])) return 0;
    return 1;
}

/* 0 when the ns sections (rows of 6) are finite with a0 = 1 and no pole at z = 1, else 1 (not
 * finite), 2 (a0 != 1) or 3 (a pole at z = 1: no rest state). */
static int sections_bad(const double *sos, size_t ns)
{
    for (size_t j = 0; j < ns; ++j) {
        const double *s = sos + 6 * j;
        if (!finite_all(s, 6)) return 1;
        if (s[3] != 1.0) return 2;
        if (s[3] + s[4] + s[5] == 0.0) return 3;
    }
    return 0;
}

/* The chain of ns sections at rest around the input u (scipy.signal.sosfilt_zi(sos) * u). */
static void sections_rest(const double *sos, size_t ns, double *s, double u)
{
    double scale = 1.0;
    for (size_t j = 0; j < ns; ++j) {
        const double *q = sos + 6 * j;
        const double g = (q[0] + q[1] + q[2]) / (q[3] + q[4] + q[5]);
        s[2 * j] = (q[1] + q[2] - (q[4] + q[5]) * g) * scale * u;
        s[2 * j + 1] = (q[2] - q[5] * g) * scale * u;
        scale *= g;
    }
}

/* One sample of the chain, transposed direct form II as scipy.signal.sosfilt; s advances. */
static double sections_step(const double *sos, size_t ns, double *s, double u)
{
    for (size_t j = 0; j < ns; ++j) {
        const double *q = sos + 6 * j;
        const double y = q[0] * u + s[2 * j];
        s[2 * j] = q[1] * u - q[4] * y + s[2 * j + 1];
        s[2 * j + 1] = q[2] * u - q[5] * y;
        u = y;
    }
    return u;
}

const char *pim_dinv_check(const pim_dinv *d)
{
    if (d->n < 1 || d->n > PIM_DINV_MAX_PLAYS) return "the model needs 1 to 128 plays";
    if (!finite_all(d->w, d->n)) return "a weight is not finite";
    if (!finite_all(d->w0, d->n)) return "a reference weight is not finite";
    for (size_t i = 0; i < d->n; ++i) {
        if (!isfinite(d->r[i]) || d->r[i] < 0.0) return "a radius is negative or not finite";
        if (i > 0 && d->r[i] < d->r[i - 1]) return "radii not sorted";
    }
    if (!isfinite(d->c) || !isfinite(d->c0)) return "an offset is not finite";
    if (!(isfinite(d->dt) && d->dt > 0.0)) return "the sample time must be finite and > 0";
    if (d->m > PIM_DINV_MAX_LAGS) return "more than 64 creep lags";
    for (size_t j = 0; j < d->m; ++j) {
        if (!isfinite(d->lag_g[j])) return "a creep gain is not finite";
        if (!(d->lag_a[j] > 0.0 && d->lag_a[j] < 1.0))
            return "a creep time constant is not finite and > 0";
        if (d->lag_start && !isfinite(d->lag_start[j]))
            return "a creep start level is not finite";
    }
    if (d->lag_record != 0 && d->lag_record != 1)
        return "the creep's record start flag lag_record must be 0 or 1";
    if (d->lag_record && d->lag_start)
        return "a creep counted from the record's start (lag_record) has its lags at rest at "
               "h0[0] (no lag_start)";
    if (d->asym) {
        if (!isfinite(d->q) || !isfinite(d->c3) || !isfinite(d->center))
            return "an asymmetry coefficient is not finite";
        if (!(isfinite(d->half) && d->half > 0.0)) return "half_range must be finite and > 0";
    }
    if (d->rate_w) {
        if (!finite_all(d->rate_w, d->n)) return "a rate band gain is not finite";
        if (!(isfinite(d->rate_scale) && d->rate_scale > 0.0))
            return "rate_scale must be finite and > 0";
        if (d->rate_family != PIM_DIAG_RATE_RADIUS && d->rate_family != PIM_DIAG_RATE_WEIGHT &&
            d->rate_family != PIM_DIAG_RATE_SCALED)
            return "rate_family must be 0 (radius), 1 (weight) or 2 (scaled)";
        if (d->rate_family == PIM_DIAG_RATE_SCALED &&
            !(isfinite(d->rate_tau) && d->rate_tau > 0.0 && isfinite(d->rate_growth)))
            return "the scaled rate family needs rate_tau > 0 s and a finite rate_growth";
        if (!(isfinite(d->rate_tau) && d->rate_tau >= 0.0))
            return "rate_tau must be finite and >= 0 s";
        if (!(isfinite(d->rate_saturation) && d->rate_saturation >= 0.0))
            return "rate_saturation must be finite and >= 0 (0: linear)";
        if (d->rate_tau == 0.0 && !(isfinite(d->input_range) && d->input_range > 0.0))
            return "input_range must be finite and > 0";
    }
    if (!(isfinite(d->reference_range) && d->reference_range >= 0.0))
        return "reference_range must be finite and >= 0";
    if (d->ns > PIM_DINV_MAX_SECTIONS) return "more than 32 prefilter sections";
    switch (sections_bad(d->sos, d->ns)) {
    case 1: return "a prefilter coefficient is not finite";
    case 2: return "a prefilter section's denominator must start with a0 = 1";
    case 3: return "a prefilter section has a pole at z = 1 (no rest state)";
    }
    if (d->npost > PIM_DINV_MAX_SECTIONS) return "more than 32 post sections";
    switch (sections_bad(d->post, d->npost)) {
    case 1: return "a post section's coefficient is not finite";
    case 2: return "a post section's denominator must start with a0 = 1";
    case 3: return "a post section has a pole at z = 1 (no rest state)";
    }
    if (d->npost && d->latency < 1)
        return "post sections need a latency >= 1 (their one-sample advance)";
    if (d->latency > PIM_DINV_MAX_LATENCY) return "the latency is above 1000000 samples";
    if (!(isfinite(d->frac) && d->frac >= 0.0 && d->frac < 1.0))
        return "the delay fraction must be finite, >= 0 and < 1";
    return NULL;
}

void pim_dinv_initial_state(const pim_dinv *d, double *x, const double *z0)
{
    const size_t size = pim_dinv_state_size(d), n = d->n;
    for (size_t j = 0; j < size; ++j) x[j] = 0.0;
    if (!z0) return;
    double *solver = x + PIM_DINV_HEAD + 2 * (d->ns + d->npost);
    for (size_t i = 0; i < n; ++i) solver[3 + i] = z0[i];
    if (d->rate_w && d->rate_family == PIM_DIAG_RATE_SCALED) {
        const size_t zs = 3 + n + d->m + (d->lag_record ? 1 : 0) + 1;
        for (size_t i = 0; i < n; ++i) solver[zs + i] = z0[i];
    } else if (d->rate_w) {
        double *source = solver + pim_dinv_solver_size(d, 0) + 2 + n;
        for (size_t i = 0; i < n; ++i) source[3 + i] = z0[i];
    }
}

/* The static part F_k at the candidate v (pim_diag_inverse.h), for one solve. */
typedef struct {
    const pim_dinv *d;
    const double *z, *mem;
    double lag_acc, lag_sum; /* sum g_j a_j L_j, sum g_j a_j */
    double rec_gain, rec_start; /* lag_record: sum g_j and L0 (h0 itself on the first sample) */
    double rho_k;
    int first, rate;
    const double *zs, *rs; /* the scaled family's plays and radii at sample k (else NULL) */
} dinv_ctx;

static double dinv_F(const dinv_ctx *c, double v)
{
    const pim_dinv *d = c->d;
    const int rate = c->rate && !c->first, radius = d->rate_family == PIM_DIAG_RATE_RADIUS;
    double y = 0.0, h0 = 0.0, rad = 0.0, wgt = 0.0;
    for (size_t i = 0; i < d->n; ++i) {
        const double r = d->r[i], zc = dinv_clamp(c->z[i], v - r, v + r);
        y += d->w[i] * zc;
        h0 += d->w0[i] * zc;
        if (c->zs) {
            const double zsc = dinv_clamp(c->zs[i], v - c->rs[i], v + c->rs[i]);
            rad += (zsc - zc) * (d->rate_w[i] * d->w[i]);
        } else if (rate && radius) {
            const double gap = v - zc;
            const int touch = r > 0.0 && fabs(gap) >= r * (1.0 - 1e-9);
            rad += (touch ? -dinv_sign(gap) * c->rho_k : c->mem[i]) * (d->rate_w[i] * r);
        } else if (rate) {
            wgt += zc * (d->rate_w[i] * d->w0[i]);
        }
    }
    y += d->c;
    h0 += d->c0;
    if (d->m && (!c->first || d->lag_start)) y += c->lag_acc - c->lag_sum * h0;
    if (d->lag_record) y -= c->rec_gain * (c->first ? h0 : c->rec_start);
    if (d->asym) {
        const double u = (h0 - d->center) / d->half;
        y += d->q * (u * u) + d->c3 * (u * u * u);
    }
    if (rate || c->zs) y += rad + c->rho_k * wgt;
    return y;
}

static int dinv_cmp(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The root chosen so far: the nearest the branch guess; on a tie the first in the full scan's
 * order (segment roots by segment, then breakpoints), given by key. */
typedef struct {
    double guess, best, dist;
    size_t key;
    int found;
} dinv_pick;

static void dinv_take(dinv_pick *p, double x, size_t key)
{
    const double e = fabs(x - p->guess);
    if (!p->found || e < p->dist || (e == p->dist && key < p->key)) {
        p->best = x;
        p->dist = e;
        p->key = key;
        p->found = 1;
    }
}

static double cubic_at(const double *a, double x)
{
    return ((a[0] * x + a[1]) * x + a[2]) * x + a[3];
}

/* Real roots in [0, 1] of a[0] x^3 + a[1] x^2 + a[2] x + a[3]: the interval split at the
 * closed-form extrema (where the polynomial is monotone), a sign change on a piece bisected. */
static void cubic_roots01(const double *a, double lo, double width, dinv_pick *p, size_t key)
{
    if (a[0] == 0.0 && a[1] == 0.0 && a[2] == 0.0 && a[3] == 0.0) { /* as np.roots' [0.0] */
        dinv_take(p, lo, key);
        return;
    }
    double pts[5] = {0.0, 1.0, 0.0, 0.0, 0.0};
    size_t np = 2;
    const double disc = sqrt(fmax(4.0 * a[1] * a[1] - 12.0 * a[0] * a[2], 0.0));
    double ext[3] = {NAN, NAN, NAN};
    if (a[0] != 0.0) {
        ext[0] = (-2.0 * a[1] + disc) / (6.0 * a[0]);
        ext[1] = (-2.0 * a[1] - disc) / (6.0 * a[0]);
    }
    if (a[1] != 0.0) ext[2] = -a[2] / (2.0 * a[1]);
    for (int j = 0; j < 3; ++j)
        if (isfinite(ext[j]) && ext[j] > 0.0 && ext[j] < 1.0) pts[np++] = ext[j];
    qsort(pts, np, sizeof pts[0], dinv_cmp);
    for (size_t j = 0; j + 1 < np; ++j) {
        double pa = pts[j], pb = pts[j + 1];
        double fa = cubic_at(a, pa), fb = cubic_at(a, pb);
        if (fa == 0.0) {
            dinv_take(p, lo + pa * width, key);
            continue;
        }
        if (j + 2 == np && fb == 0.0) {
            dinv_take(p, lo + pb * width, key);
            continue;
        }
        if (!((fa < 0.0 && fb > 0.0) || (fa > 0.0 && fb < 0.0))) continue;
        for (int it = 0; it < DINV_BISECT; ++it) {
            const double mid = 0.5 * (pa + pb);
            if (mid <= pa || mid >= pb) break;
            const double fm = cubic_at(a, mid);
            if (fm == 0.0) {
                pa = pb = mid;
                break;
            }
            if ((fm < 0.0) == (fa < 0.0)) {
                pa = mid;
                fa = fm;
            } else {
                pb = mid;
            }
        }
        dinv_take(p, lo + 0.5 * (pa + pb) * width, key);
    }
}

/* The inverse of the Vandermonde matrix of the nodes 1/8, 3/8, 5/8, 7/8 (rows: the
 * coefficients of x^3, x^2, x, 1 from the node values). */
static const double VINV[4][4] = {
    {-32.0 / 3.0, 32.0, -32.0, 32.0 / 3.0},
    {20.0, -52.0, 44.0, -12.0},
    {-71.0 / 6.0, 47.0 / 2.0, -31.0 / 2.0, 23.0 / 6.0},
    {35.0 / 16.0, -35.0 / 16.0, 21.0 / 16.0, -5.0 / 16.0},
};

/* One solve of the static part (pim_diag_inverse.h) on the solver state x; rate: with the rate
 * effect (the solver) or without (its rate source). */
static double dinv_solve(const pim_dinv *d, double *x, double yk, int rate)
{
    const size_t n = d->n, m = d->m;
    double *z = x + 3, *lags = z + n, *l0 = lags + m, *rho_f = l0 + (d->lag_record ? 1 : 0),
           *mem = rho_f + 1, *v0_prev = mem + n, *source = v0_prev + 1;
    const int first = x[0] == 0.0;
    const double v_prev = x[1], guess = x[2];
    double wsum = 0.0;
    for (size_t i = 0; i < n; ++i) wsum += d->w[i];
    const double span = fmax(fmax(2.0 * d->r[n - 1], d->reference_range / fmax(fabs(wsum), 1e-12)),
                             1.0);
    const double a_rate = rate && d->rate_tau > 0.0 ? exp(-d->dt / d->rate_tau) : 0.0;
    const double step_size = PIM_DIAG_STEP_SHARE * d->input_range;
    const int scaled = rate && d->rate_family == PIM_DIAG_RATE_SCALED;
    double rs[PIM_DINV_MAX_PLAYS];
    dinv_ctx c = {d, z, rate ? mem : NULL, 0.0, 0.0, 0.0, 0.0, 0.0, first, rate && !scaled,
                  NULL, NULL};
    double fresh = 0.0;
    if (scaled) { /* radii fixed by the rate before sample k (pim_rdpi_sat_run's) */
        const double beta = d->rate_growth / d->rate_scale, sat = d->rate_saturation * d->rate_scale;
        const double g = sat > 0.0 ? beta * *rho_f / (1.0 + *rho_f / sat) : beta * *rho_f;
        for (size_t i = 0; i < n; ++i) {
            rs[i] = d->r[i] + d->r[i] * g;
            if (first) mem[i] = z[i]; /* the scaled plays at rest with the plays */
        }
        c.zs = mem;
        c.rs = rs;
    } else if (rate) { /* the fresh rate of sample k from the rate-free inverse v0 */
        const double v0 = dinv_solve(d, source, yk, 0);
        const double dv0 = first ? 0.0 : fabs(v0 - *v0_prev);
        fresh = d->rate_tau > 0.0 || dv0 <= step_size ? dv0 / d->dt / d->rate_scale : 0.0;
        *v0_prev = v0;
        c.rho_k = dinv_saturate(d, a_rate * *rho_f + (1.0 - a_rate) * fresh);
    }
    for (size_t j = 0; first && d->lag_start && j < m; ++j) lags[j] = d->lag_start[j];
    for (size_t j = 0; j < m; ++j) {
        const double ga = d->lag_g[j] * d->lag_a[j];
        c.lag_acc += ga * lags[j];
        c.lag_sum += ga;
    }
    if (d->lag_record) { /* less sum_j g_j L_j[-1], L_j[-1] = h0[0] (kept in L0) */
        for (size_t j = 0; j < m; ++j) c.rec_gain += d->lag_g[j];
        c.rec_start = *l0;
    }
    /* breakpoints, sorted and unique, with the bracket 10 span beyond them */
    double b[DINV_NB_MAX];
    size_t nb = 0;
    for (size_t i = 0; i < n; ++i) b[nb++] = z[i] - d->r[i];
    for (size_t i = 0; i < n; ++i) b[nb++] = z[i] + d->r[i];
    for (size_t i = 0; scaled && i < n; ++i) {
        b[nb++] = mem[i] - rs[i];
        b[nb++] = mem[i] + rs[i];
    }
    b[nb++] = v_prev;
    qsort(b, nb, sizeof b[0], dinv_cmp);
    {
        size_t u = 1;
        for (size_t j = 1; j < nb; ++j)
            if (b[j] != b[u - 1]) b[u++] = b[j];
        nb = u;
    }
    const double blo = b[0] - 10.0 * span, bhi = b[nb - 1] + 10.0 * span;
    if (blo < b[0]) {
        memmove(b + 1, b, nb * sizeof b[0]);
        b[0] = blo;
        ++nb;
    }
    if (bhi > b[nb - 1]) b[nb++] = bhi;
    /* the roots, searched outward from the guess: segment s holds roots within [b[s], b[s+1]]
     * (the polynomial from interior nodes), breakpoint s is a root when F(b[s]) is on the
     * target; the search stops where every segment left is farther from the guess than the
     * root found (the choice of the full scan of pim_diag_inverse.h, in O(1) segments when the
     * root is near the guess) */
    dinv_pick pick = {guess, 0.0, 0.0, 0, 0};
    const double tol = 1e-10 * (1.0 + fabs(yk));
    const double slack = 1e-12 * (1.0 + fabs(guess) + span);
    double gb[DINV_NB_MAX];
    unsigned char seen[DINV_NB_MAX];
    memset(seen, 0, nb);
    size_t left = 0; /* the segment holding the guess (or the end one nearest it) */
    while (left + 2 < nb && b[left + 1] <= guess) ++left;
    size_t right = left + 1; /* segments left - 1 .. 0 and right .. nb - 2 are still to do */
    int has_left = nb >= 2; /* (nb >= 3 but for values near the largest doubles) */
    for (;;) {
        const double dl = has_left ? (guess < b[left] ? b[left] - guess
                                      : guess > b[left + 1] ? guess - b[left + 1] : 0.0)
                                   : INFINITY;
        const double dr = right + 1 < nb ? (guess < b[right] ? b[right] - guess : 0.0)
                                         : INFINITY;
        const double dn = dl < dr ? dl : dr;
        if (dn == INFINITY || (pick.found && dn > pick.dist + slack)) break;
        size_t sg;
        if (dl <= dr) {
            sg = left;
            if (left == 0) has_left = 0;
            else --left;
        } else {
            sg = right++;
        }
        const double lo = b[sg], width = b[sg + 1] - b[sg];
        if (!d->asym) {
            const double f0 = dinv_F(&c, lo + 0.25 * width) - yk;
            const double f1 = dinv_F(&c, lo + 0.75 * width) - yk;
            const double slope = 2.0 * (f1 - f0), c0 = 1.5 * f0 - 0.5 * f1;
            const double xr = slope != 0.0 ? -c0 / slope : -1.0;
            if (xr >= 0.0 && xr <= 1.0) dinv_take(&pick, lo + xr * width, sg);
        } else {
            double f[4], a[4] = {0.0, 0.0, 0.0, 0.0};
            for (int j = 0; j < 4; ++j) f[j] = dinv_F(&c, lo + (0.125 + 0.25 * j) * width) - yk;
            for (int i = 0; i < 4; ++i)
                for (int j = 0; j < 4; ++j) a[i] += VINV[i][j] * f[j];
            cubic_roots01(a, lo, width, &pick, sg);
        }
        for (size_t e = sg; e <= sg + 1; ++e) { /* its ends, each once */
            if (seen[e]) continue;
            seen[e] = 1;
            gb[e] = fabs(dinv_F(&c, b[e]) - yk);
            if (gb[e] <= tol) dinv_take(&pick, b[e], nb + e);
        }
    }
    double vk = b[0];
    if (pick.found) {
        vk = pick.best;
    } else { /* out of reach (every breakpoint seen): the closest to the target, the first */
        double gmin = INFINITY;
        for (size_t e = 0; e < nb; ++e)
            if (seen[e] && gb[e] < gmin) {
                gmin = gb[e];
                vk = b[e];
            }
    }
    /* the state after the solve */
    double h = 0.0;
    for (size_t i = 0; i < n; ++i) {
        z[i] = dinv_clamp(z[i], vk - d->r[i], vk + d->r[i]);
        h += z[i] * d->w0[i];
    }
    h += d->c0;
    for (size_t j = 0; j < m; ++j)
        lags[j] = first && !d->lag_start ? h : d->lag_a[j] * lags[j] + (1.0 - d->lag_a[j]) * h;
    if (d->lag_record && first) *l0 = h; /* the lags' start h0[0] */
    if (scaled) {
        for (size_t i = 0; i < n; ++i) mem[i] = dinv_clamp(mem[i], vk - rs[i], vk + rs[i]);
        *rho_f = a_rate * *rho_f + (1.0 - a_rate) * (first ? 0.0 : fabs(vk - v_prev) / d->dt);
    } else if (rate && !first) {
        const double dv = fabs(vk - v_prev);
        double rho = dv <= step_size || d->rate_tau > 0.0 ? dv / d->dt / d->rate_scale : 0.0;
        if (rho > PIM_DINV_RATE_FEEDBACK_CAP * fresh) rho = PIM_DINV_RATE_FEEDBACK_CAP * fresh;
        *rho_f = a_rate * *rho_f + (1.0 - a_rate) * rho;
        for (size_t i = 0; i < n; ++i) {
            const double gap = vk - z[i];
            if (d->r[i] > 0.0 && fabs(gap) >= d->r[i] * (1.0 - 1e-9))
                mem[i] = -dinv_sign(gap) * dinv_saturate(d, *rho_f);
        }
    }
    x[2] = first || fabs(vk - v_prev) > 0.01 * span ? vk : 2.0 * vk - v_prev;
    x[0] = 1.0;
    x[1] = vk;
    return vk;
}

double pim_dinv_step(const pim_dinv *d, double *x, double yd)
{
    double *s = x + PIM_DINV_HEAD, *g = s + 2 * d->ns, *solver = g + 2 * d->npost;
    const int rate = d->rate_w != NULL;
    const double solve_from = (double)(d->latency - (d->npost ? 1 : 0));
    if (x[0] == 0.0) {
        x[0] = 1.0;
        sections_rest(d->sos, d->ns, s, yd);
        if (d->latency) { /* the inverse of y_d[0] from the initial solver state */
            double tmp[PIM_DINV_SOLVER_MAX];
            memcpy(tmp, solver, pim_dinv_solver_size(d, rate) * sizeof tmp[0]);
            x[2] = dinv_solve(d, tmp, yd, rate);
        }
    }
    const double fk = sections_step(d->sos, d->ns, s, yd);
    const double seen = x[1];
    double v = x[2];
    if (!(seen < solve_from)) {
        const double ref = d->frac == 0.0 ? fk : x[3] + (fk - x[3]) * d->frac;
        v = dinv_solve(d, solver, ref, rate);
        if (d->npost) { /* the filter's inverse, at rest around the first solve */
            if (seen == solve_from) sections_rest(d->post, d->npost, g, v);
            v = sections_step(d->post, d->npost, g, v);
        }
    }
    if (seen < (double)d->latency) {
        v = x[2];
        x[1] = seen + 1.0;
    }
    x[3] = fk;
    return v;
}

void pim_dinv_run(const pim_dinv *d, double *x, size_t N, const double *yd, double *v)
{
    for (size_t k = 0; k < N; ++k) v[k] = pim_dinv_step(d, x, yd[k]);
}
