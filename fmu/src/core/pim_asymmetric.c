/* Asymmetric generalized PI operator and its exact inverse; semantics in pim_asymmetric.h. */
#include "pim_asymmetric.h"

#include "pim_generalized.h"

#include <math.h>

static inline double asym_play(const pim_asym *a, double r, double z, double s)
{
    const double lo = a->al * s + a->dl - r;
    const double hi = a->ar * s + a->dr + r;
    z = z < hi ? z : hi;
    return z > lo ? z : lo;
}

static double asym_sum(const pim_asym *a, size_t n, const double *p, const double *r,
                       const double *z, double s)
{
    double y = a->p0 * s;
    for (size_t i = 0; i < n; ++i) y += p[i] * asym_play(a, r[i], z[i], s);
    return y;
}

size_t pim_asym_run(const pim_asym *a, size_t N, size_t n, const double *p, const double *r,
                    double *z, const double *v, double *y)
{
    for (size_t k = 0; k < N; ++k) {
        const double s = pim_envelope(a->kind, a->c, v[k]);
        if (isnan(s)) {
            y[k] = NAN;
            return k + 1;
        }
        double acc = a->p0 * s;
        for (size_t i = 0; i < n; ++i) {
            z[i] = asym_play(a, r[i], z[i], s);
            acc += p[i] * z[i];
        }
        y[k] = acc;
    }
    return 0;
}

/* df/ds at s (away from kinks): p0 plus al or ar for each play on its lower or upper bound. */
static double asym_slope(const pim_asym *a, size_t n, const double *p, const double *r,
                         const double *z, double s)
{
    double d = a->p0;
    for (size_t i = 0; i < n; ++i) {
        const double lo = a->al * s + a->dl - r[i];
        const double hi = a->ar * s + a->dr + r[i];
        if (lo >= (z[i] < hi ? z[i] : hi)) {
            d += p[i] * a->al;
        } else if (hi < z[i]) {
            d += p[i] * a->ar;
        }
    }
    return d;
}

/* One correction x + (y - f(x)) / d: f is linear with slope d on the segment that holds x and
 * the root, so the residual taken at x (near the root) keeps the digits a distant kink loses
 * (envelopes with near-equal slopes cross at |s| ~ 1e15, where f(kink) has ~1 absolute
 * rounding; issue 32). */
static double asym_refine(const pim_asym *a, size_t n, const double *p, const double *r,
                          const double *z, double y, double x, double d, double lo, double hi)
{
    x += (y - asym_sum(a, n, p, r, z, x)) / d;
    x = x > lo ? x : lo;
    return x < hi ? x : hi;
}

/* s with asym_sum(s) = y: f is continuous, strictly increasing, linear between the kinks;
 * the root is taken from the left kink with the segment's own slope (no long chords), then
 * corrected once from that first estimate (asym_refine). */
double pim_asym_solve(const pim_asym *a, size_t n, const double *p, const double *r,
                         const double *z, double y)
{
    double b[3 * PIM_MAX_PLAYS] = {0.0};
    size_t m = 0;
    for (size_t i = 0; i < n; ++i) {
        b[m++] = (z[i] + r[i] - a->dl) / a->al; /* L_i = z_i */
        b[m++] = (z[i] - r[i] - a->dr) / a->ar; /* U_i = z_i */
        if (a->al != a->ar) b[m++] = (a->dr - a->dl + 2.0 * r[i]) / (a->al - a->ar);
    }
    for (size_t i = 1; i < m; ++i) { /* insertion sort, m <= 192 */
        const double x = b[i];
        size_t j = i;
        while (j > 0 && b[j - 1] > x) {
            b[j] = b[j - 1];
            --j;
        }
        b[j] = x;
    }
    double f_lo = asym_sum(a, n, p, r, z, b[0]);
    if (y <= f_lo) { /* linear left of every kink */
        const double d = asym_slope(a, n, p, r, z, b[0] - 1.0);
        return asym_refine(a, n, p, r, z, y, b[0] - (f_lo - y) / d, d, -INFINITY, b[0]);
    }
    for (size_t j = 1; j < m; ++j) {
        const double f_hi = asym_sum(a, n, p, r, z, b[j]);
        if (y <= f_hi) {
            const double d = asym_slope(a, n, p, r, z, 0.5 * (b[j - 1] + b[j]));
            const double x = b[j - 1] + (y - f_lo) / d;
            return asym_refine(a, n, p, r, z, y, x < b[j] ? x : b[j], d, b[j - 1], b[j]);
        }
        f_lo = f_hi;
    }
    const double d = asym_slope(a, n, p, r, z, b[m - 1] + 1.0);
    return asym_refine(a, n, p, r, z, y, b[m - 1] + (y - f_lo) / d, d, b[m - 1], INFINITY);
}

size_t pim_asym_inverse_run(const pim_asym *a, size_t N, size_t n, const double *p,
                            const double *r, double *z, const double *yd, double *v)
{
    if (n > PIM_MAX_PLAYS) return N + 1;
    for (size_t k = 0; k < N; ++k) {
        const double s = pim_asym_solve(a, n, p, r, z, yd[k]);
        v[k] = pim_envelope(a->kind_inv, a->c, s);
        if (isnan(v[k])) return k + 1;
        for (size_t i = 0; i < n; ++i) z[i] = asym_play(a, r[i], z[i], s);
    }
    return 0;
}
