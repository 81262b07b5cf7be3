/*
 * pimodel C core: play and Prandtl-Ishlinskii (PI) operators on sampled inputs.
 *
 * One implementation shared by the Python package (through ctypes) and the FMUs.
 * Discrete-time semantics (NOTES.md, paper eqs. 1-7), for play i with radius r_i:
 *
 *     z_i[k] = max(v[k] - r_i, min(v[k] + r_i, z_i[k-1])),   z_i[-1] = initial state
 *     y[k]   = sum_i p_i z_i[k]   (summed as pim_pi_step_inline states)
 *
 * so y[k] depends on v[0..k] only (no delay).  The time-dependent form replaces r_i by
 * rhat_i[k] at step k.  All arrays are caller-owned; state arrays `z` (length n) are updated in
 * place so that a run can be continued by another call.  No function allocates memory.
 * Units: v and r share the input unit, y is in the output unit, p is output unit per input unit.
 */
#ifndef PIM_CORE_H
#define PIM_CORE_H

#include <stddef.h>

/* SSE2 for the play step's pairs (pim_pi_step_inline) where the compiler has it */
#if defined(__SSE2__) && !defined(PIM_NO_SIMD)
#define PIM_PI_SSE2 1
#include <emmintrin.h>
#endif

#include "pim_limits.h" /* PIM_MAX_PLAYS (the fixed-size users' limit; the array functions
                            * take any n) and every other limit */

/* PIM_API exports a core function from the Python extension; an FMU build defines
 * PIM_CORE_HIDDEN so that only the FMI functions are exported from the FMU's binary. */
#if defined(PIM_CORE_HIDDEN)
#define PIM_API
#elif defined(_WIN32)
#define PIM_API __declspec(dllexport)
#else
#define PIM_API __attribute__((visibility("default")))
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* One step of the PI operator: updates z[0..n-1] for input v and returns y (p, r, z do not
 * overlap). */
PIM_API double pim_pi_step(size_t n, const double *p, const double *r, double *z, double v);

/* restrict for the inline kernels below (C99; C++ compilers spell it __restrict) */
#ifdef __cplusplus
#define PIM_RESTRICT __restrict
#else
#define PIM_RESTRICT restrict
#endif

/*
 * pim_pi_step's body, inline for the loops that run it once per sample (pim_pi_run, the
 * generalized operator, the FMU units): each play clamped into [v - r_i, v + r_i] with
 * comparisons (no branch), and the weighted sum in four interleaved partial sums, each in play
 * order and started by its first term (0 while empty), added at the end:
 *
 *     s_c = p_c z_c + p_(c+4) z_(c+4) + ...   (c = 1..4)
 *     y   = (s_1 + s_3) + (s_2 + s_4)
 *
 * One order for every caller, so that they agree to the last bit (tests/test_native_sum_order.py
 * holds it to this formula).  Two plays per vector operation ((s_1, s_2) and (s_3, s_4): SSE2
 * where the compiler has it, unless PIM_NO_SIMD; the same operations in scalar code
 * elsewhere), and a chain of about n/4 dependent additions per sample, which is what limits a
 * sample's speed more than the count of instructions (docs/fmu.md, Speed).  A count known when
 * compiled (pim_pi_step_small) is unrolled completely by the compiler.  p, r and z must not
 * overlap.
 */
#ifdef PIM_PI_SSE2

/* Plays i + 1 and i + 2 at input (v, v): z updated, (p_i z_i, p_(i+1) z_(i+1)) returned.
 * minpd and maxpd return their first operand when it compares less (greater), else the second:
 * the scalar code's comparisons. */
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
static inline __m128d pim_pi_pair(const double *PIM_RESTRICT p, const double *PIM_RESTRICT r,
                                  double *PIM_RESTRICT z, __m128d vv, size_t i)
{
    const __m128d ri = _mm_loadu_pd(r + i);
    __m128d a = _mm_min_pd(_mm_loadu_pd(z + i), _mm_add_pd(vv, ri));
    a = _mm_max_pd(a, _mm_sub_pd(vv, ri));
    _mm_storeu_pd(z + i, a);
    return _mm_mul_pd(_mm_loadu_pd(p + i), a);
}
#endif

/* Play i + 1 alone at input v: z[i] updated, p_i z_i into `out`. */
#define PIM_PI_ONE(i, out)                                                                     \
    do {                                                                                       \
        const size_t i_ = (i);                                                                 \
        double a = z[i_] < v + r[i_] ? z[i_] : v + r[i_];                                      \
        a = a > v - r[i_] ? a : v - r[i_];                                                     \
        z[i_] = a;                                                                             \
        out = p[i_] * a;                                                                       \
    } while (0)

static inline double pim_pi_step_inline(size_t n, const double *PIM_RESTRICT p,
                                        const double *PIM_RESTRICT r, double *PIM_RESTRICT z,
                                        double v)
{
    size_t i = 0;
    double t;
#ifdef PIM_PI_SSE2
    const __m128d vv = _mm_set1_pd(v);
    __m128d s12 = _mm_setzero_pd(), s34 = _mm_setzero_pd(); /* (s_1, s_2), (s_3, s_4) */
    if (n >= 4) {
        s12 = pim_pi_pair(p, r, z, vv, 0);
        s34 = pim_pi_pair(p, r, z, vv, 2);
        for (i = 4; i + 4 <= n; i += 4) {
            s12 = _mm_add_pd(s12, pim_pi_pair(p, r, z, vv, i));
            s34 = _mm_add_pd(s34, pim_pi_pair(p, r, z, vv, i + 2));
        }
    }
    if (i + 2 <= n) { /* plays 4k + 1, 4k + 2 */
        s12 = i ? _mm_add_pd(s12, pim_pi_pair(p, r, z, vv, i)) : pim_pi_pair(p, r, z, vv, 0);
        i += 2;
    }
    if (i < n) { /* the last play of an odd n: play 4k + 1 (s_1) or 4k + 3 (s_3) */
        PIM_PI_ONE(i, t);
        if (i & 2)
            s34 = i == 2 ? _mm_set_sd(t) : _mm_add_sd(s34, _mm_set_sd(t));
        else
            s12 = i == 0 ? _mm_set_sd(t) : _mm_add_sd(s12, _mm_set_sd(t));
    }
    const __m128d s = _mm_add_pd(s12, s34); /* (s_1 + s_3, s_2 + s_4) */
    return _mm_cvtsd_f64(_mm_add_sd(s, _mm_unpackhi_pd(s, s)));
#else
    double s[4] = {0.0, 0.0, 0.0, 0.0};
    for (; i < n; ++i) {
        PIM_PI_ONE(i, t);
        s[i & 3] = i < 4 ? t : s[i & 3] + t;
    }
    return (s[0] + s[2]) + (s[1] + s[3]);
#endif
}
#undef PIM_PI_ONE

/* The n up to which pim_pi_step_small has a straight line of code for each n. */
#define PIM_PI_SMALL_N 16

/*
 * pim_pi_step_inline for a caller whose n is small and the same for many samples (the FMU
 * units): a switch on n, each case pim_pi_step_inline with that n as a constant, so without a
 * loop and at fixed offsets (a branch the processor predicts instead of a loop's set-up and
 * branches); larger n run the loop.  The same operations in the same order, the same result.
 */
#define PIM_PI_SMALL_CASE(k) case k: return pim_pi_step_inline(k, p, r, z, v);
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
static inline double pim_pi_step_small(size_t n, const double *PIM_RESTRICT p,
                                       const double *PIM_RESTRICT r, double *PIM_RESTRICT z,
                                       double v)
{
    switch (n) {
    PIM_PI_SMALL_CASE(1) PIM_PI_SMALL_CASE(2) PIM_PI_SMALL_CASE(3) PIM_PI_SMALL_CASE(4)
    PIM_PI_SMALL_CASE(5) PIM_PI_SMALL_CASE(6) PIM_PI_SMALL_CASE(7) PIM_PI_SMALL_CASE(8)
    PIM_PI_SMALL_CASE(9) PIM_PI_SMALL_CASE(10) PIM_PI_SMALL_CASE(11) PIM_PI_SMALL_CASE(12)
    PIM_PI_SMALL_CASE(13) PIM_PI_SMALL_CASE(14) PIM_PI_SMALL_CASE(15) PIM_PI_SMALL_CASE(16)
    default: return pim_pi_step_inline(n, p, r, z, v);
    }
}
#undef PIM_PI_SMALL_CASE

/*
 * Runs the PI operator over v[0..N-1]: y[k] as above, z updated to z[N-1].
 * zhist (nullable) receives the play outputs row by row, zhist[k*n + i] = z_i[k].
 */
PIM_API void pim_pi_run(size_t N, size_t n, const double *p, const double *r, double *z,
                        const double *v, double *y, double *zhist);

/*
 * pim_pi_run with the play outputs as rows (the layout of the diagnosis' fits):
 * zrows[i*ld + k] = z_i[k], ld >= N (not nullable). The same values as pim_pi_run's.
 */
PIM_API void pim_pi_run_rows(size_t N, size_t n, const double *p, const double *r, double *z,
                             const double *v, double *y, double *zrows, size_t ld);

/*
 * Time-dependent PI operator: radii given per sample, R[k*n + i] = rhat_i[k].
 * zhist (nullable) as in pim_pi_run.
 */
PIM_API void pim_tdpi_run(size_t N, size_t n, const double *p, const double *R, double *z,
                          const double *v, double *y, double *zhist);

/*
 * Exact inverse (Krejci & Kuhnen) of a PI operator with r[0] == 0 and all partial sums
 * P_i = p_1 + ... + p_i > 0:  rinv_i = sum_{j<=i} p_j (r_i - r_j),  pinv_1 = 1/p_1,
 * pinv_i = -p_i / (P_i P_{i-1}).  The consistent inverse state for forward play states z is
 * zinv_i = P_i z_i + sum_{j>i} p_j z_j (pass z = NULL to skip).
 * Returns 0 on success, -1 if the operator is not invertible (nothing written then).
 */
PIM_API int pim_pi_inverse(size_t n, const double *p, const double *r, const double *z,
                           double *pinv, double *rinv, double *zinv);

/*
 * Parameter check for a forward PI operator: returns NULL when 0 <= r_1 <= ... <= r_n,
 * all finite, and p_i > 0 (or, with signed != 0, all partial sums positive); else a static
 * message naming the first offending parameter.  Used by the FMUs to report fmi2Error.
 */
PIM_API const char *pim_pi_check(size_t n, const double *p, const double *r, int signed_weights);

/* The limits of pim_limits.h by index 0..pim_limit_count()-1: name (NULL out of range), value,
 * and whether it is an integer (else a real tolerance). */
PIM_API int pim_limit_count(void);
PIM_API const char *pim_limit_name(int i);
PIM_API double pim_limit_value(int i);
PIM_API int pim_limit_is_integer(int i);

/* sizeof of the parameter structs that Python mirrors with ctypes ("pim_asym", "pim_diag",
 * "pim_dinv"), so that pimodel._native refuses a layout that does not match; 0 for another
 * name. */
PIM_API size_t pim_struct_size(const char *name);

#ifdef __cplusplus
}
#endif

#endif /* PIM_CORE_H */
