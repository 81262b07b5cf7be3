/* The CreepOperator unit (unit 7): its own rules and helpers, included by the framework
 * fmu/src/fmi/pim_unit.h after the unit struct and unit_error. */

/* Creep: gains c[i] (stored in p) finite and > 0, time constants tau[i] (in r) finite and > 0,
 * and G minimum phase (sum_i c_i (1 - a_i) / (1 + a_i) < 1, exact for c_i > 0; pim_creep.h). */
static int unit_check_creep(pim_unit *u)
{
    double s = 0.0;
    for (int i = 0; i < u->n; ++i) {
        if (!isfinite(u->p[i]) || !(u->p[i] > 0.0))
            return unit_error(u, "gain c[%d] = %g is not positive (creep gains must be finite "
                                 "and > 0)", i + 1, u->p[i]);
        if (!isfinite(u->r[i]) || !(u->r[i] > 0.0))
            return unit_error(u, "time constant tau[%d] = %g is not positive (must be finite "
                                 "and > 0 s)", i + 1, u->r[i]);
        const double a = exp(-u->Ts / u->r[i]);
        s += u->p[i] * (1.0 - a) / (1.0 + a);
    }
    if (!(s < 1.0))
        return unit_error(u, "bad parameters: the creep G(z) is not minimum phase (sum c_i "
                             "(1 - a_i) / (1 + a_i) = %g >= 1), its inverse would be unstable",
                          s);
    return 0;
}
