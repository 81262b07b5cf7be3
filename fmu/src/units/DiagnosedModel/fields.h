/* DiagnosedModel's own fields of pim_unit (inside the struct, fmi/pim_unit.h; pim_diagnosed.h):
 * the static part (units/shared/diag_fields.h), the LTI part, its further elements (section 0
 * the base mode on h0, PIM_DIAG_SECTION coefficients each in lti_element_b, _a, gains
 * lti_gain), a Wiener model's filter before the plays (wiener_element_b, _a), the delay and the
 * drift (a trend, and a settling drift_settling (1 - exp(-(t - drift_settling_start) /
 * drift_settling_tau))), and the model's flat state. */
#include "diag_fields.h"
double lti_b[PIM_NMAX], lti_a[PIM_NMAX];
double drift_per_s, delay_samples, drift_settling, drift_settling_tau, drift_settling_start;
int lti_order, drift_clock, n_lti_elements, n_wiener_elements, plays_start;
double lti_gain[PIM_NMAX], lti_element_b[PIM_NMAX], lti_element_a[PIM_NMAX];
double wiener_element_b[PIM_NMAX], wiener_element_a[PIM_NMAX];
double dstate[PIM_DIAG_STATE_MAX]; /* pim_diag's state */
