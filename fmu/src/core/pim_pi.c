/* Play and PI operators; semantics in pim_core.h. */
#include "pim_core.h"

#include <math.h>

double pim_pi_step(size_t n, const double *p, const double *r, double *z, double v)
{
    return pim_pi_step_inline(n, p, r, z, v);
}

/* pim_pi_run with the play outputs stored at zhist[k*sk + i*si] (sk, si: the strides). */
static void pi_run_strided(size_t N, size_t n, const double *p, const double *r, double *z,
                           const double *v, double *y, double *zhist, size_t sk, size_t si)
{
    double zl[PIM_MAX_PLAYS];
    if (n > PIM_MAX_PLAYS) { /* general path, state in caller memory */
        for (size_t k = 0; k < N; ++k) {
            y[k] = pim_pi_step(n, p, r, z, v[k]);
            if (zhist) {
                for (size_t i = 0; i < n; ++i) zhist[k * sk + i * si] = z[i];
            }
        }
        return;
    }
    for (size_t i = 0; i < n; ++i) zl[i] = z[i];
    for (size_t k = 0; k < N; ++k) {
        y[k] = pim_pi_step_inline(n, p, r, zl, v[k]);
        if (zhist) {
            for (size_t i = 0; i < n; ++i) zhist[k * sk + i * si] = zl[i];
        }
    }
    for (size_t i = 0; i < n; ++i) z[i] = zl[i];
}

void pim_pi_run(size_t N, size_t n, const double *p, const double *r, double *z,
                const double *v, double *y, double *zhist)
{
    pi_run_strided(N, n, p, r, z, v, y, zhist, n, 1);
}

/* Doubles of the buffer through which pim_pi_run_rows writes its rows (32 KB, on the stack):
 * a block of samples is run into it sample by sample (contiguous stores), then copied out row
 * by row (contiguous again); storing each sample's plays straight into n rows was slower than
 * pim_pi_run and a transposed copy together. */
#define PIM_ROWS_BUFFER 4096

void pim_pi_run_rows(size_t N, size_t n, const double *p, const double *r, double *z,
                     const double *v, double *y, double *zrows, size_t ld)
{
    double buf[PIM_ROWS_BUFFER];
    if (n == 0 || n > PIM_ROWS_BUFFER / 8) { /* few samples per block: stored straight */
        pi_run_strided(N, n, p, r, z, v, y, zrows, 1, ld);
        return;
    }
    const size_t block = PIM_ROWS_BUFFER / n;
    for (size_t k0 = 0; k0 < N; k0 += block) {
        const size_t b = N - k0 < block ? N - k0 : block;
        pi_run_strided(b, n, p, r, z, v + k0, y + k0, buf, n, 1);
        for (size_t i = 0; i < n; ++i) {
            for (size_t j = 0; j < b; ++j) zrows[i * ld + k0 + j] = buf[j * n + i];
        }
    }
}

void pim_tdpi_run(size_t N, size_t n, const double *p, const double *R, double *z,
                  const double *v, double *y, double *zhist)
{
    for (size_t k = 0; k < N; ++k) {
        y[k] = pim_pi_step(n, p, R + k * n, z, v[k]);
        if (zhist) {
            for (size_t i = 0; i < n; ++i) zhist[k * n + i] = z[i];
        }
    }
}

int pim_pi_inverse(size_t n, const double *p, const double *r, const double *z,
                   double *pinv, double *rinv, double *zinv)
{
    if (n == 0 || r[0] != 0.0) return -1;
    double P = 0.0;
    for (size_t i = 0; i < n; ++i) {
        P += p[i];
        if (!(P > 0.0)) return -1;
    }
    double Pprev = 0.0, Pi = 0.0, tail = 0.0, acc_pr = 0.0;
    for (size_t i = 0; i < n; ++i) {
        Pi = Pprev + p[i];
        acc_pr += p[i] * r[i];
        rinv[i] = Pi * r[i] - acc_pr; /* sum_{j<=i} p_j (r_i - r_j) */
        pinv[i] = (i == 0) ? 1.0 / p[0] : -p[i] / (Pi * Pprev);
        Pprev = Pi;
    }
    if (z && zinv) {
        /* zinv_i = P_i z_i + sum_{j>i} p_j z_j, accumulated from the top. */
        Pi = P;
        for (size_t ii = n; ii-- > 0;) {
            zinv[ii] = Pi * z[ii] + tail;
            tail += p[ii] * z[ii];
            Pi -= p[ii];
        }
    }
    return 0;
}

const char *pim_pi_check(size_t n, const double *p, const double *r, int signed_weights)
{
    if (n == 0) return "the number of plays n must be at least 1";
    double P = 0.0;
    for (size_t i = 0; i < n; ++i) {
        if (!isfinite(r[i])) return "a radius r[i] is not finite";
        if (r[i] < 0.0) return "a radius r[i] is negative (radii must be >= 0)";
        if (i > 0 && r[i] < r[i - 1]) return "radii r[i] are not sorted (need r[1] <= ... <= r[n])";
        if (!isfinite(p[i])) return "a weight p[i] is not finite";
        P += p[i];
        if (signed_weights) {
            if (!(P > 0.0)) return "a partial sum of weights p[1]+...+p[i] is not positive";
        } else if (!(p[i] > 0.0)) {
            return "a weight p[i] is not positive (weights must be > 0)";
        }
    }
    return NULL;
}
