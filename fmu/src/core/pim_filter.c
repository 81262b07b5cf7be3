/* A biquad applied to many signals (rows), each at rest around its first sample; semantics in
 * pim_filter.h.  Rows are filtered four at a time: one row is a chain of dependent
 * multiply-adds, four independent chains keep the floating-point units busy. */
#include "pim_filter.h"

#define LANES 4

void pim_biquad_rows(size_t m, size_t N, const double *b, const double *a, const double *x,
                     double *y)
{
    const double b0 = b[0], b1 = b[1], b2 = b[2], a1 = a[1], a2 = a[2];
    /* steady state for a unit input: solves (I - A) s = B, B = b[1:] - a[1:] b0 */
    const double B0 = b1 - a1 * b0, B1 = b2 - a2 * b0;
    const double zi0 = (B0 + B1) / (1.0 + a1 + a2), zi1 = B1 - a2 * zi0;
    size_t i = 0;
    for (; i + LANES <= m; i += LANES) {
        const double *xr[LANES];
        double *yr[LANES], s0[LANES], s1[LANES];
        for (int l = 0; l < LANES; ++l) {
            xr[l] = x + (i + l) * N;
            yr[l] = y + (i + l) * N;
            s0[l] = zi0 * xr[l][0];
            s1[l] = zi1 * xr[l][0];
        }
        for (size_t k = 0; k < N; ++k) {
            for (int l = 0; l < LANES; ++l) {
                const double xk = xr[l][k], yk = s0[l] + b0 * xk;
                s0[l] = s1[l] + xk * b1 - yk * a1;
                s1[l] = xk * b2 - yk * a2;
                yr[l][k] = yk;
            }
        }
    }
    for (; i < m; ++i) {
        const double *xr = x + i * N;
        double *yr = y + i * N, s0 = zi0 * xr[0], s1 = zi1 * xr[0];
        for (size_t k = 0; k < N; ++k) {
            const double xk = xr[k], yk = s0 + b0 * xk;
            s0 = s1 + xk * b1 - yk * a1;
            s1 = xk * b2 - yk * a2;
            yr[k] = yk;
        }
    }
}

void pim_biquad_rows_carry(size_t m, size_t N, const double *b, const double *a, const double *x,
                           double *y, double *s, int start)
{
    const double b0 = b[0], b1 = b[1], b2 = b[2], a1 = a[1], a2 = a[2];
    const double B0 = b1 - a1 * b0, B1 = b2 - a2 * b0;
    const double zi0 = (B0 + B1) / (1.0 + a1 + a2), zi1 = B1 - a2 * zi0;
    for (size_t i = 0; i < m; ++i) {
        const double *xr = x + i * N;
        double *yr = y + i * N, s0, s1;
        if (start) {
            s0 = zi0 * xr[0];
            s1 = zi1 * xr[0];
        } else {
            s0 = s[2 * i];
            s1 = s[2 * i + 1];
        }
        for (size_t k = 0; k < N; ++k) {
            const double xk = xr[k], yk = s0 + b0 * xk;
            s0 = s1 + xk * b1 - yk * a1;
            s1 = xk * b2 - yk * a2;
            yr[k] = yk;
        }
        s[2 * i] = s0;
        s[2 * i + 1] = s1;
    }
}
