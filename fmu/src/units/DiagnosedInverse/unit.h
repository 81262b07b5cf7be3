/* The DiagnosedInverse unit (unit 9): the diagnosed model's causal feedforward
 * (pim_diag_inverse.h), input y_d (in1), output v (out1); the static part's variables as
 * DiagnosedModel's (same names and references), plus the prefilter sections (n_sections,
 * section), the post sections of a Wiener model's filter inverse (n_post_sections,
 * post_section), latency, delay_fraction and reference_range.  Its hooks (fmi/pim_unit.h),
 * included after the unit struct. */
/* creep_start 2: the lags at rest at h0[0], the creep counted from the record's start
 * (pim_dinv.lag_record; params creep_start "record" of pimodel.diagnosis.creep) */
#define PIM_CREEP_START_MAX 2
#define PIM_CREEP_START_MORE ", 2 at rest at h0[0] counted from the record's start"
#include "diag_static.h"
#include "sections.h"
#define HAS_MODEL_DEFAULTS
#define HAS_MODEL_DERIVE

static void model_defaults(pim_unit *u)
{
    unit_diag_defaults(u);
    for (int j = 0; j < PIM_DINV_FMU_SECTIONS; ++j) /* a0 = 1 */
        u->section[6 * j + 3] = u->post_section[6 * j + 3] = 1.0;
}

/* The feedforward of the unit's parameters (pointers into u, built per sample as unit_diag). */
static void unit_dinv(const pim_unit *u, pim_dinv *d)
{
    PIM_FILL_STATIC(d, u);
    d->reference_range = u->reference_range;
    d->ns = u->n_sections > 0 ? (size_t)u->n_sections : 0;
    d->sos = u->section;
    d->npost = u->n_post_sections > 0 ? (size_t)u->n_post_sections : 0;
    d->post = u->post_section;
    d->latency = u->latency > 0 ? (size_t)u->latency : 0;
    d->frac = u->delay_fraction;
    d->lag_record = u->creep_start == 2; /* less sum_j g_j h0[0] (pim_diag_inverse.h) */
}

/* The DiagnosedInverse parameter rules, with the variable, index and value in the message. */
static int model_check_parameters(pim_unit *u)
{
    if (unit_check_diag_static(u) != 0) return -1;
    if (!isfinite(u->reference_range) || u->reference_range < 0.0)
        return unit_error(u, "parameter reference_range = %g: must be finite and >= 0",
                          u->reference_range);
    if (u->latency < 0 || u->latency > PIM_DINV_MAX_LATENCY)
        return unit_error(u, "parameter latency = %d out of range: 0 <= latency <= %d",
                          u->latency, PIM_DINV_MAX_LATENCY);
    if (!isfinite(u->delay_fraction) || u->delay_fraction < 0.0 || !(u->delay_fraction < 1.0))
        return unit_error(u, "parameter delay_fraction = %g out of range: 0 <= delay_fraction "
                             "< 1", u->delay_fraction);
    const sections_chain pre = {"n_sections", u->n_sections, PIM_DINV_FMU_SECTIONS,
                                u->n_sections, "section coefficient", "section", "section",
                                u->section, u->section, 1};
    const sections_chain post = {"n_post_sections", u->n_post_sections, PIM_DINV_FMU_SECTIONS,
                                 u->n_post_sections, "section coefficient", "post_section",
                                 "post_section", u->post_section, u->post_section, 1};
    if (sections_check(u, &pre) != 0 || sections_check(u, &post) != 0) return -1;
    if (u->n_post_sections > 0 && u->latency < 1)
        return unit_error(u, "parameter latency = %d: post sections (n_post_sections = %d) need "
                             "a latency >= 1 (their one-sample advance)", u->latency,
                          u->n_post_sections);
    pim_dinv d;
    unit_dinv(u, &d);
    const char *msg = pim_dinv_check(&d);
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
    memset(u->dstate, 0, sizeof u->dstate); /* not started; plays (and the rate source's) at z0 */
    double z0[PIM_DINV_MAX_PLAYS];
    for (int i = 0; i < u->n; ++i) z0[i] = u->z0;
    pim_dinv d;
    unit_diag_join(u); /* the joined arrays for d (model_derive below recomputes them) */
    unit_dinv(u, &d);
    pim_dinv_initial_state(&d, u->dstate, z0);
    return model_derive(u);
}

static void model_sample(pim_unit *u)
{
    pim_dinv d;
    unit_dinv(u, &d);
    u->out1 = pim_dinv_step(&d, u->dstate, u->in1);
}

static void model_save(const pim_unit *u, model_saved *s)
{
    pim_dinv d;
    unit_dinv(u, &d);
    unit_diag_save(u, s, pim_dinv_state_size(&d));
}

/* The feedforward's flat state: finite, started 0 or 1, 0 <= seen <= latency, the solver
 * started 0 or 1, the filtered rate >= 0. */
static int model_check_states(pim_unit *u, pim_unit *s)
{
    pim_dinv d;
    unit_diag_join(s);
    unit_dinv(s, &d);
    const double *x = s->dstate, *solver = x + PIM_DINV_HEAD + 2 * (d.ns + d.npost);
    const size_t rho_f = 3 + d.n + d.m + (d.lag_record ? 1 : 0); /* after L0 (record start) */
    if (!unit_all_finite(x, pim_dinv_state_size(&d)))
        return unit_error(u, "FMU state rejected: a feedforward state is not finite");
    if ((x[0] != 0.0 && x[0] != 1.0) || x[1] < 0.0 || x[1] != floor(x[1]) ||
        x[1] > (double)d.latency || (solver[0] != 0.0 && solver[0] != 1.0))
        return unit_error(u, "FMU state rejected: feedforward state started = %g, seen = %g, "
                             "solver started = %g (expected 0 or 1, 0 <= seen <= latency "
                             "%llu)", x[0], x[1], solver[0],
                          (unsigned long long)d.latency);
    if (d.rate_w && solver[rho_f] < 0.0)
        return unit_error(u, "FMU state rejected: the filtered rate rho_f = %g must be "
                             ">= 0", solver[rho_f]);
    return 0;
}
