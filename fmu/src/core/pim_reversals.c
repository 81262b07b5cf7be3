/* Streaming reversal detection; the rule is documented in pim_reversals.h. */
#include "pim_reversals.h"

#include <math.h>
#include <string.h>

void pim_rev_scan_init(pim_rev_scan *s) { memset(s, 0, sizeof(*s)); }

size_t pim_rev_scan_sizeof(void) { return sizeof(pim_rev_scan); }

size_t pim_rev_scan_run(pim_rev_scan *s, size_t N, const double *v, double threshold,
                        long long *out_ext, long long *out_decl)
{
    size_t count = 0;
    for (size_t i = 0; i < N; ++i, ++s->k) {
        const double x = v[i];
        if (!s->started) {
            s->started = 1.0;
            s->v_first = x;
            s->v_ext = x;
            s->k_ext = s->k;
        } else if (s->dir == 0.0) {
            if (fabs(x - s->v_first) > threshold) {
                s->dir = x > s->v_first ? 1.0 : -1.0;
                s->v_ext = x;
                s->k_ext = s->k;
            }
        } else if (s->dir * (x - s->v_ext) > 0.0) {
            s->v_ext = x;
            s->k_ext = s->k;
        } else if (fabs(x - s->v_ext) > threshold) {
            if (out_decl) out_decl[count] = s->k;
            out_ext[count++] = s->k_ext;
            s->dir = -s->dir;
            s->v_ext = x;
            s->k_ext = s->k;
        }
    }
    return count;
}
