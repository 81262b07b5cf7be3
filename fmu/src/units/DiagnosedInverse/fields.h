/* DiagnosedInverse's own fields of pim_unit (inside the struct, fmi/pim_unit.h;
 * pim_diag_inverse.h): the static part (units/shared/diag_fields.h), the root rule's scale,
 * latency A, the delay's fraction, the prefilter's and the post sections (6 coefficients each:
 * b0 b1 b2 a0 a1 a2), and the feedforward's flat state. */
#include "diag_fields.h"
double reference_range, delay_fraction;
int latency, n_sections, n_post_sections;
double section[PIM_NMAX], post_section[PIM_NMAX];
double dstate[PIM_DIAG_STATE_MAX]; /* pim_dinv's state */
