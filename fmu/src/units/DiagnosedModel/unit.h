/* The DiagnosedModel unit (unit 8): the model a diagnosis chose (pim_diagnosed.h), signed play
 * weights and the effect terms in parallel; input v (in1), output y (out1).  Its hooks
 * (fmi/pim_unit.h), included after the unit struct. */
/* creep_start 2: the lags at rest at h0[0], the creep counted from the record's start
 * (pim_diag.lag_record; params creep_start "record" of pimodel.diagnosis.creep) */
#define PIM_CREEP_START_MAX 2
#define PIM_CREEP_START_MORE ", 2 at rest at h0[0] counted from the record's start"
#include "diag_static.h"
#include "sections.h"
#define HAS_MODEL_DEFAULTS
#define HAS_MODEL_DERIVE
#define HAS_MODEL_OUTPUTS_FINITE

static void model_defaults(pim_unit *u)
{
    unit_diag_defaults(u);
    u->lti_a[0] = 1.0; /* lti_order 0: no LTI */
    for (int j = 0; j <= PIM_DIAG_MAX_ELEMENTS; ++j) /* each section's a[0] = 1 */
        u->lti_element_a[PIM_DIAG_SECTION * j] = 1.0;
    for (int j = 0; j < PIM_DIAG_MAX_ELEMENTS; ++j)
        u->wiener_element_a[PIM_DIAG_SECTION * j] = 1.0;
}

/* The model of the unit's parameters (pointers into u; built per sample, never stored, so that
 * a restored FMU state holds no pointer).  The asymmetry and rate terms are on when a
 * coefficient is non-zero; the state layout (pim_diagnosed.h) follows from the parameters. */
static void unit_diag(const pim_unit *u, pim_diag *d)
{
    PIM_FILL_STATIC(d, u);
    d->order = (size_t)u->lti_order;
    d->b = u->lti_b;
    d->a = u->lti_a;
    d->delay = u->delay_samples;
    d->drift_clock = u->drift_clock;
    d->drift = u->drift_per_s;
    d->ne = u->n_lti_elements > 0 ? (size_t)u->n_lti_elements : 0;
    d->el_b = u->lti_element_b;
    d->el_a = u->lti_element_a;
    d->el_g = u->lti_gain;
    d->nw = u->n_wiener_elements > 0 ? (size_t)u->n_wiener_elements : 0;
    d->wf_b = u->wiener_element_b;
    d->wf_a = u->wiener_element_a;
    d->plays_start = u->plays_start;
    d->settle = u->drift_settling;
    d->settle_tau = u->drift_settling_tau;
    d->settle_t0 = u->drift_settling_start;
    d->lag_record = u->creep_start == 2; /* less sum_j g_j h0[0] (pim_diagnosed.h) */
}

/* The DiagnosedModel parameter rules, with the variable, index and value in the message. */
static int model_check_parameters(pim_unit *u)
{
    if (unit_check_diag_static(u) != 0) return -1;
    if (!isfinite(u->drift_per_s))
        return unit_error(u, "parameter drift_per_s = %g: must be finite", u->drift_per_s);
    if (u->drift_clock < 0 || u->drift_clock > 2)
        return unit_error(u, "parameter drift_clock = %d out of range: 0 none, 1 record, "
                             "2 absolute", u->drift_clock);
    if (!isfinite(u->drift_settling_tau) || u->drift_settling_tau < 0.0)
        return unit_error(u, "parameter drift_settling_tau = %g: must be finite and >= 0 (0: no "
                             "settling)", u->drift_settling_tau);
    if (!isfinite(u->drift_settling) || !isfinite(u->drift_settling_start))
        return unit_error(u, "parameters drift_settling = %g, drift_settling_start = %g: must be "
                             "finite", u->drift_settling, u->drift_settling_start);
    if (u->plays_start < 0 || u->plays_start > 1)
        return unit_error(u, "parameter plays_start = %d out of range: 0 at z0, 1 at rest at "
                             "the first input v[0]", u->plays_start);
    if (u->lti_order < 0 || u->lti_order > PIM_DIAG_MAX_ORDER)
        return unit_error(u, "parameter lti_order = %d out of range: 0 <= lti_order <= %d",
                          u->lti_order, PIM_DIAG_MAX_ORDER);
    for (int j = 0; j <= u->lti_order && u->lti_order > 0; ++j) {
        if (!isfinite(u->lti_b[j]))
            return unit_error(u, "LTI coefficient lti_b[%d] = %g is not finite", j + 1,
                              u->lti_b[j]);
        if (!isfinite(u->lti_a[j]))
            return unit_error(u, "LTI coefficient lti_a[%d] = %g is not finite", j + 1,
                              u->lti_a[j]);
    }
    if (u->lti_order > 0 && u->lti_a[0] != 1.0)
        return unit_error(u, "parameter lti_a[1] = %g: the LTI denominator must be normalised "
                             "(lti_a[1] = 1)", u->lti_a[0]);
    const sections_chain elements = {
        "n_lti_elements", u->n_lti_elements, PIM_DIAG_MAX_ELEMENTS,
        u->n_lti_elements > 0 ? u->n_lti_elements + 1 : 0, /* and the base section 0 */
        "LTI element coefficient", "lti_element_b", "lti_element_a", u->lti_element_b,
        u->lti_element_a, 0};
    if (sections_check(u, &elements) != 0) return -1;
    for (int j = 0; j < u->n_lti_elements; ++j)
        if (!isfinite(u->lti_gain[j]))
            return unit_error(u, "LTI element gain lti_gain[%d] = %g is not finite", j + 1,
                              u->lti_gain[j]);
    const sections_chain wiener = {
        "n_wiener_elements", u->n_wiener_elements, PIM_DIAG_MAX_ELEMENTS, u->n_wiener_elements,
        "prefilter coefficient", "wiener_element_b", "wiener_element_a", u->wiener_element_b,
        u->wiener_element_a, 1};
    if (sections_check(u, &wiener) != 0) return -1;
    if (!isfinite(u->delay_samples) || u->delay_samples < 0.0 ||
        u->delay_samples > PIM_DIAG_MAX_DELAY - 2)
        return unit_error(u, "parameter delay_samples = %g out of range: 0 <= delay_samples <= "
                             "%d", u->delay_samples, PIM_DIAG_MAX_DELAY - 2);
    pim_diag d;
    unit_diag(u, &d);
    const char *msg = pim_diag_check(&d);
    if (msg) return unit_error(u, "bad parameters: %s", msg);
    return 0;
}

static int model_derive(pim_unit *u)
{
    unit_diag_derive(u);
    return 0;
}

static int model_setup(pim_unit *u)
{
    memset(u->dstate, 0, sizeof u->dstate); /* not started; plays (and a prefilter's) at z0 */
    pim_diag d;
    unit_diag(u, &d);
    pim_diag_initial_state(&d, u->dstate, u->z0);
    return model_derive(u);
}

static void model_sample(pim_unit *u)
{
    pim_diag d;
    unit_diag(u, &d);
    u->out1 = pim_diag_step(&d, u->dstate, u->in1, (double)u->k_next * u->Ts);
}

/* With a delay, the terms a step put into the delay lines are finite too (they reach y later). */
static int model_outputs_finite(const pim_unit *u)
{
    if (!(u->delay_samples > 0.0)) return 1; /* no delay lines */
    pim_diag d;
    unit_diag(u, &d);
    return pim_diag_pending_finite(&d, u->dstate);
}

static void model_save(const pim_unit *u, model_saved *s)
{
    pim_diag d;
    unit_diag(u, &d);
    unit_diag_save(u, s, pim_diag_state_size(&d));
}

/* The model's flat state: finite, started 0 or 1, the delay line's head in range, the filtered
 * rate >= 0. */
static int model_check_states(pim_unit *u, pim_unit *s)
{
    pim_diag d;
    unit_diag(s, &d);
    const size_t size = pim_diag_state_size(&d), nbuf = pim_diag_delay_length(d.delay);
    const double *x = s->dstate;
    if (!unit_all_finite(x, size))
        return unit_error(u, "FMU state rejected: a model state is not finite");
    if ((x[0] != 0.0 && x[0] != 1.0) || x[3] < 0.0 || x[3] != floor(x[3]) ||
        (nbuf ? x[3] >= (double)nbuf : x[3] != 0.0))
        return unit_error(u, "FMU state rejected: model state started = %g, head = %g "
                             "(expected 0 or 1, and 0 <= head < %llu)", x[0], x[3],
                          (unsigned long long)(nbuf ? nbuf : 1));
    if (pim_diag_rate_size(&d) && x[PIM_DIAG_HEADER + d.n] < 0.0)
        return unit_error(u, "FMU state rejected: the filtered rate rho_f = %g must be "
                             ">= 0", x[PIM_DIAG_HEADER + d.n]);
    return 0;
}
