/* The DiagnosedInverse unit (unit 9): its own rules and helpers, included by the framework
 * fmu/src/fmi/pim_unit.h after the unit struct and unit_error. */

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
}

/* The count (0..PIM_DINV_FMU_SECTIONS) and coefficients of a chain of sections (6 each: b0 b1 b2
 * a0 a1 a2, a0 = 1, no pole at z = 1), with the variable, index and value in the message. */
static int unit_check_sections(pim_unit *u, const char *count_name, int count, const char *name,
                               const double *sos)
{
    if (count < 0 || count > PIM_DINV_FMU_SECTIONS)
        return unit_error(u, "parameter %s = %d out of range: 0 <= %s <= %d", count_name, count,
                          count_name, PIM_DINV_FMU_SECTIONS);
    for (int j = 0; j < 6 * count; ++j) {
        if (!isfinite(sos[j]))
            return unit_error(u, "section coefficient %s[%d] = %g is not finite", name, j + 1,
                              sos[j]);
        if (j % 6 == 3 && sos[j] != 1.0)
            return unit_error(u, "parameter %s[%d] = %g: each section's a0 must be 1 (b0 b1 b2 "
                                 "a0 a1 a2 per section)", name, j + 1, sos[j]);
        if (j % 6 == 5 && sos[j - 2] + sos[j - 1] + sos[j] == 0.0)
            return unit_error(u, "parameters %s[%d..%d] = (%g, %g, %g): the section has a pole "
                                 "at z = 1 (a0 + a1 + a2 = 0), no rest state", name, j - 1,
                              j + 1, sos[j - 2], sos[j - 1], sos[j]);
    }
    return 0;
}

/* The DiagnosedInverse parameter rules, with the variable, index and value in the message. */
static int unit_check_dinv(pim_unit *u)
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
    if (unit_check_sections(u, "n_sections", u->n_sections, "section", u->section) != 0 ||
        unit_check_sections(u, "n_post_sections", u->n_post_sections, "post_section",
                            u->post_section) != 0)
        return -1;
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
