/* The joint estimator's per-branch statistics; the rules are documented in pim_joint.h. */
#include "pim_joint.h"

#include <math.h>
#include <string.h>

size_t pim_joint_select(size_t N, const double *v, const double *y, double s,
                        double keep_limit, double travel_range, double *x_out, double *Y_out,
                        long long *outside)
{
    size_t m = 0;
    const double v0 = v[0];
    for (size_t k = 0; k < N; ++k) {
        const double x = fabs(v[k] - v0);
        if (x <= keep_limit) {
            if (x <= travel_range) {
                x_out[m] = x;
                Y_out[m++] = s * y[k];
            } else {
                ++*outside;
            }
        }
    }
    return m;
}

void pim_joint_hinges(size_t m, const double *x, size_t n, const double *r, double *H)
{
    for (size_t k = 0; k < m; ++k)
        for (size_t j = 0; j < n; ++j) {
            const double d = x[k] - 2.0 * r[j];
            H[k * n + j] = (d > 0.0 || d != d) ? d : 0.0; /* NaN stays NaN, as in numpy */
        }
}

double pim_joint_add(size_t m, const double *x, const double *Y, const double *e, double c,
                     size_t bins, double scale, double forgetting, double *stats,
                     double *branch)
{
    double sse = 0.0;
    memset(branch, 0, 3 * bins * sizeof(double));
    for (size_t k = 0; k < m; ++k) {
        const double d = e[k] - c;
        sse += d * d;
        size_t b = (size_t)(long long)(x[k] * scale);
        if (b > bins - 1) b = bins - 1;
        branch[b] += 1.0;
        branch[bins + b] += x[k];
        branch[2 * bins + b] += Y[k] - c;
    }
    if (forgetting != 1.0)
        for (size_t i = 0; i < 3 * bins; ++i) stats[i] *= forgetting;
    for (size_t i = 0; i < 3 * bins; ++i) stats[i] += branch[i];
    return sse;
}
