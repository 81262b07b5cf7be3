/*
 * A second-order linear filter (biquad) applied to many signals at once: the hot loop of the
 * diagnosis' dynamics candidate (pimodel/diagnosis/effects.py: mode_rows), which filters every
 * play output by the same mode at each point of its searches.
 *
 * Discrete-time semantics, per signal (a row x[0..N-1] of the row-major array x, shape m x N),
 * with a[0] = 1 (direct form II transposed, as scipy.signal.lfilter):
 *
 *     y[k] = b0 x[k] + s0[k-1]
 *     s0[k] = b1 x[k] - a1 y[k] + s1[k-1]
 *     s1[k] = b2 x[k] - a2 y[k]
 *
 * started at rest around x[0]: the states s0[-1], s1[-1] are the steady state for a constant
 * input x[0] (scipy.signal.lfilter_zi times x[0]), so a constant row passes at the filter's
 * static gain.  A first-order filter is the case b2 = a2 = 0.  Needs 1 + a1 + a2 != 0 (no pole
 * at z = 1).  Units: y has the units of x times the filter's gain.  Arrays are caller-owned;
 * x and y must not overlap; nothing allocates.
 */
#ifndef PIM_FILTER_H
#define PIM_FILTER_H

#include "pim_core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* y = the biquad (b[0..2], a[0..2], a[0] = 1) applied to each of the m rows of x (N each). */
PIM_API void pim_biquad_rows(size_t m, size_t N, const double *b, const double *a,
                             const double *x, double *y);

/* The same filter on a chunk of each row, its state carried: s (m x 2, row-major) holds each
 * row's s0[k-1], s1[k-1] before the chunk's first sample and is overwritten with them after
 * its last; start != 0: the chunk is the rows' first, the states are set at rest around its
 * first sample as pim_biquad_rows sets them (s is then written, not read).  Filtering a row's
 * consecutive chunks in turn gives the bits of pim_biquad_rows on the whole row. */
PIM_API void pim_biquad_rows_carry(size_t m, size_t N, const double *b, const double *a,
                                   const double *x, double *y, double *s, int start);

#ifdef __cplusplus
}
#endif

#endif /* PIM_FILTER_H */
