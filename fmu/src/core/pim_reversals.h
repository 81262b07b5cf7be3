/*
 * Streaming reversal detection with a hysteresis threshold (same rule as the radius estimator).
 *
 * A reversal is declared once the input has moved back from the running extreme of the
 * current monotone segment by more than `threshold` (input unit); the reversal sample is the
 * extreme itself.  Before the first move the direction is undetermined; the first move is a
 * departure from v[0] by more than the threshold.  State carries over between calls, so a
 * record may be scanned in chunks; indices are absolute sample numbers counted from the first
 * sample ever passed.
 */
#ifndef PIM_REVERSALS_H
#define PIM_REVERSALS_H

#include "pim_core.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    double v_first;  /* first sample */
    double v_ext;    /* running extreme of the current segment */
    double dir;      /* +1 / -1, 0 before the first move */
    double started;  /* 1 once a sample has been seen */
    long long k;     /* samples seen so far */
    long long k_ext; /* absolute index of the running extreme */
} pim_rev_scan;

/* Resets the scanner to "no sample seen". */
PIM_API void pim_rev_scan_init(pim_rev_scan *s);

/*
 * Scans v[0..N-1] (the next N samples).  For each reversal declared in these samples, writes
 * the absolute index of its extreme to out_ext and of the sample at which it was declared to
 * out_decl (nullable); room for N entries suffices.  Returns the count.  The input must be
 * finite (checked by the caller).
 */
PIM_API size_t pim_rev_scan_run(pim_rev_scan *s, size_t N, const double *v, double threshold,
                                long long *out_ext, long long *out_decl);

PIM_API size_t pim_rev_scan_sizeof(void);

#ifdef __cplusplus
}
#endif

#endif
