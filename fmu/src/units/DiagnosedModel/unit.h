/* The DiagnosedModel unit (unit 8): its own rules and helpers, included by the framework
 * fmu/src/fmi/pim_unit.h after the unit struct and unit_error. */

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
}

/* The DiagnosedModel parameter rules, with the variable, index and value in the message. */
static int unit_check_diag(pim_unit *u)
{
    if (unit_check_diag_static(u) != 0) return -1;
    if (!isfinite(u->drift_per_s))
        return unit_error(u, "parameter drift_per_s = %g: must be finite", u->drift_per_s);
    if (u->drift_clock < 0 || u->drift_clock > 2)
        return unit_error(u, "parameter drift_clock = %d out of range: 0 none, 1 record, "
                             "2 absolute", u->drift_clock);
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
    if (u->n_lti_elements < 0 || u->n_lti_elements > PIM_DIAG_MAX_ELEMENTS)
        return unit_error(u, "parameter n_lti_elements = %d out of range: 0 <= n_lti_elements "
                             "<= %d", u->n_lti_elements, PIM_DIAG_MAX_ELEMENTS);
    for (int j = 0; u->n_lti_elements > 0 && j < PIM_DIAG_SECTION * (u->n_lti_elements + 1);
         ++j) {
        if (!isfinite(u->lti_element_b[j]))
            return unit_error(u, "LTI element coefficient lti_element_b[%d] = %g is not finite",
                              j + 1, u->lti_element_b[j]);
        if (!isfinite(u->lti_element_a[j]))
            return unit_error(u, "LTI element coefficient lti_element_a[%d] = %g is not finite",
                              j + 1, u->lti_element_a[j]);
        if (j % PIM_DIAG_SECTION == 0 && u->lti_element_a[j] != 1.0)
            return unit_error(u, "parameter lti_element_a[%d] = %g: each section's denominator "
                                 "must be normalised (lti_element_a[%d] = 1)", j + 1,
                              u->lti_element_a[j], j + 1);
    }
    for (int j = 0; j < u->n_lti_elements; ++j)
        if (!isfinite(u->lti_gain[j]))
            return unit_error(u, "LTI element gain lti_gain[%d] = %g is not finite", j + 1,
                              u->lti_gain[j]);
    if (u->n_wiener_elements < 0 || u->n_wiener_elements > PIM_DIAG_MAX_ELEMENTS)
        return unit_error(u, "parameter n_wiener_elements = %d out of range: 0 <= "
                             "n_wiener_elements <= %d", u->n_wiener_elements,
                          PIM_DIAG_MAX_ELEMENTS);
    for (int j = 0; j < PIM_DIAG_SECTION * u->n_wiener_elements; ++j) {
        if (!isfinite(u->wiener_element_b[j]))
            return unit_error(u, "prefilter coefficient wiener_element_b[%d] = %g is not finite",
                              j + 1, u->wiener_element_b[j]);
        if (!isfinite(u->wiener_element_a[j]))
            return unit_error(u, "prefilter coefficient wiener_element_a[%d] = %g is not finite",
                              j + 1, u->wiener_element_a[j]);
        if (j % PIM_DIAG_SECTION == 0 && u->wiener_element_a[j] != 1.0)
            return unit_error(u, "parameter wiener_element_a[%d] = %g: each section's "
                                 "denominator must be normalised (wiener_element_a[%d] = 1)",
                              j + 1, u->wiener_element_a[j], j + 1);
        if (j % PIM_DIAG_SECTION == PIM_DIAG_SECTION - 1) {
            const double *a = u->wiener_element_a + j + 1 - PIM_DIAG_SECTION;
            if (a[0] + a[1] + a[2] == 0.0)
                return unit_error(u, "parameters wiener_element_a[%d..%d] = (%g, %g, %g): the "
                                     "section has a pole at z = 1 (the coefficients sum to 0), "
                                     "no rest state", j + 2 - PIM_DIAG_SECTION, j + 1, a[0],
                                  a[1], a[2]);
        }
    }
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
