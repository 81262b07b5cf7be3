/*
 * The joint estimator's per-branch statistics (pimodel.identification.adaptive.joint, steps 2-3
 * of its module docstring).  NumPy reference: pimodel.reference.joint.
 *
 * A finished branch has samples v[0..N-1] (v[0] its reversal extreme, input unit) and outputs
 * y[0..N-1] (output unit); s = +1 rising, -1 falling.  Sample k has travel x = |v[k] - v[0]|
 * and signed output Y = s y[k].  All arrays are caller-owned; nothing is allocated.
 */
#ifndef PIM_JOINT_H
#define PIM_JOINT_H

#include "pim_core.h"

#ifdef __cplusplus
extern "C" {
#endif

/*
 * The samples the fit uses: x <= keep_limit (the previous branch's travel, with its margin) and
 * x <= travel_range, written in order to x_out and Y_out (room for N each).  Samples with
 * x <= keep_limit beyond travel_range are added to *outside.  Returns their count m.
 */
PIM_API size_t pim_joint_select(size_t N, const double *v, const double *y, double s,
                                double keep_limit, double travel_range, double *x_out,
                                double *Y_out, long long *outside);

/*
 * The hinge matrix of the branch shape: H[k][j] = max(0, x[k] - 2 r[j]) for the m travels x
 * and the n radii r (row-major, m x n), the values numpy gives for
 * np.maximum(0.0, x[:, None] - 2.0 * r[None, :]) (a NaN stays NaN); the branch shape
 * g = H w is then one BLAS product, as in the NumPy reference.
 */
PIM_API void pim_joint_hinges(size_t m, const double *x, size_t n, const double *r, double *H);

/*
 * Adds m >= 1 selected samples (x, Y) to the binned statistics stats[3][bins] (count, sum x,
 * sum Y), centred by c: e[k] = Y[k] - g(x[k]) are their errors about the estimate in force and
 * c = mean(e) (both computed by the caller, with numpy, so that the statistics are those of the
 * NumPy reference to the bit).  Every statistic is first multiplied by `forgetting`; then bin
 * b = min(floor(x scale), bins - 1) (scale = bins / travel_range) gains count 1, x and Y - c,
 * the branch's sums formed in `branch` (scratch, 3 bins) and then added, as numpy.bincount
 * would.  Returns sum (e - c)^2 (output unit squared; summed in order, so it may differ from
 * numpy's dot product in the last bits).
 */
PIM_API double pim_joint_add(size_t m, const double *x, const double *Y, const double *e,
                             double c, size_t bins, double scale, double forgetting,
                             double *stats, double *branch);

#ifdef __cplusplus
}
#endif

#endif
