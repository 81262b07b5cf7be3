/* The diagnosed model streamed sample by sample; semantics and state layout in pim_diagnosed.h. */
#include "pim_diagnosed.h"

#include "pim_rate_dependent.h"

#include <math.h>

static inline double diag_clamp(double z, double lo, double hi)
{
    z = z < hi ? z : hi; /* as pim_pi.c, so the play states are the operator's bit for bit */
    return z > lo ? z : lo;
}

size_t pim_diag_delay_length(double delay)
{
    return delay > 0.0 ? (size_t)floor(delay) + 2 : 0;
}

size_t pim_diag_rate_size(const pim_diag *d)
{
    if (!d->rate_w) return 0;
    return d->rate_family == PIM_DIAG_RATE_WEIGHT ? 1 : 1 + d->n;
}

size_t pim_diag_state_size(const pim_diag *d)
{
    return PIM_DIAG_HEADER + d->n + pim_diag_rate_size(d) + d->m + d->order +
           pim_diag_element_states(d) + 2 * pim_diag_delay_length(d->delay) +
           pim_diag_prefilter_states(d) + pim_diag_record_states(d);
}

size_t pim_diag_record_states(const pim_diag *d)
{
    return d->lag_record && d->m ? 1 : 0;
}

size_t pim_diag_prefilter_states(const pim_diag *d)
{
    return d->nw ? d->n + (PIM_DIAG_SECTION - 1) * d->nw : 0;
}

void pim_diag_initial_state(const pim_diag *d, double *x, double z0)
{
    const size_t size = pim_diag_state_size(d), nf = pim_diag_prefilter_states(d);
    for (size_t j = 0; j < size; ++j) x[j] = 0.0;
    for (size_t i = 0; i < d->n; ++i) x[PIM_DIAG_HEADER + i] = z0;
    const size_t nrec = pim_diag_record_states(d);
    for (size_t i = 0; nf && i < d->n; ++i) x[size - nrec - nf + i] = z0; /* zf */
    if (d->rate_w && d->rate_family == PIM_DIAG_RATE_SCALED) /* zs */
        for (size_t i = 0; i < d->n; ++i) x[PIM_DIAG_HEADER + d->n + 1 + i] = z0;
}

size_t pim_diag_element_states(const pim_diag *d)
{
    return d->ne ? 2 * (d->ne + 1) : 0;
}

static int all_finite(const double *x, size_t n)
{
    for (size_t i = 0; i < n; ++i)
        if (!isfinite(x[i])) return 0;
    return 1;
}

/* 0 when b[0..q], a[0..q] are finite with a[0] = 1 and sum a != 0 (a rest state exists), else
 * 1 (not finite), 2 (a[0] != 1) or 3 (a pole at z = 1). */
static int lti_bad(const double *b, const double *a, size_t q)
{
    if (!all_finite(b, q + 1) || !all_finite(a, q + 1)) return 1;
    if (a[0] != 1.0) return 2;
    double sa = 0.0;
    for (size_t j = 0; j <= q; ++j) sa += a[j];
    return sa == 0.0 ? 3 : 0;
}

/* One sample of b(z^-1) / a(z^-1) (order q >= 1, a[0] = 1) in transposed direct form II, as
 * scipy.signal.lfilter; on the first sample the states s[0..q-1] start at rest around x. */
static double lti_step(const double *b, const double *a, size_t q, double *s, double x,
                       int first)
{
    if (first) {
        double sb = 0.0, sa = 0.0;
        for (size_t j = 0; j <= q; ++j) {
            sb += b[j];
            sa += a[j];
        }
        const double gain = sb / sa;
        double acc = 0.0;
        for (size_t j = q; j >= 1; --j) {
            acc += b[j] - a[j] * gain;
            s[j - 1] = acc * x;
        }
    }
    const double y = b[0] * x + s[0];
    for (size_t j = 1; j < q; ++j) s[j - 1] = b[j] * x - a[j] * y + s[j];
    s[q - 1] = b[q] * x - a[q] * y;
    return y;
}

const char *pim_diag_check(const pim_diag *d)
{
    if (d->n < 1) return "the model needs at least one play";
    if (!all_finite(d->w, d->n)) return "a weight is not finite";
    if (!all_finite(d->w0, d->n)) return "a reference weight is not finite";
    for (size_t i = 0; i < d->n; ++i) {
        if (!isfinite(d->r[i]) || d->r[i] < 0.0) return "a radius is negative or not finite";
        if (i > 0 && d->r[i] < d->r[i - 1]) return "radii not sorted";
    }
    if (!isfinite(d->c) || !isfinite(d->c0)) return "an offset is not finite";
    if (!(isfinite(d->dt) && d->dt > 0.0)) return "the sample time must be finite and > 0";
    for (size_t j = 0; j < d->m; ++j) {
        if (!isfinite(d->lag_g[j])) return "a creep gain is not finite";
        if (!(d->lag_a[j] > 0.0 && d->lag_a[j] < 1.0))
            return "a creep time constant is not finite and > 0";
        if (d->lag_start && !isfinite(d->lag_start[j]))
            return "a creep start level is not finite";
    }
    if (d->lag_record != 0 && d->lag_record != 1)
        return "the creep's record start flag lag_record must be 0 or 1";
    if (d->asym) {
        if (!isfinite(d->q) || !isfinite(d->c3) || !isfinite(d->center))
            return "an asymmetry coefficient is not finite";
        if (!(isfinite(d->half) && d->half > 0.0)) return "half_range must be finite and > 0";
    }
    if (d->rate_w) {
        if (!all_finite(d->rate_w, d->n)) return "a rate band gain is not finite";
        if (!(isfinite(d->rate_scale) && d->rate_scale > 0.0))
            return "rate_scale must be finite and > 0";
        if (d->rate_family != PIM_DIAG_RATE_RADIUS && d->rate_family != PIM_DIAG_RATE_WEIGHT &&
            d->rate_family != PIM_DIAG_RATE_SCALED)
            return "rate_family must be 0 (radius), 1 (weight) or 2 (scaled)";
        if (d->rate_family == PIM_DIAG_RATE_SCALED &&
            !(isfinite(d->rate_tau) && d->rate_tau > 0.0 && isfinite(d->rate_growth)))
            return "the scaled rate family needs rate_tau > 0 s and a finite rate_growth";
        if (!(isfinite(d->rate_tau) && d->rate_tau >= 0.0))
            return "rate_tau must be finite and >= 0 s";
        if (!(isfinite(d->rate_saturation) && d->rate_saturation >= 0.0))
            return "rate_saturation must be finite and >= 0 (0: linear)";
        if (d->rate_tau == 0.0 && !(isfinite(d->input_range) && d->input_range > 0.0))
            return "input_range must be finite and > 0";
    }
    if (d->order > PIM_DIAG_MAX_ORDER) return "the LTI order is above 63";
    switch (d->order > 0 ? lti_bad(d->b, d->a, d->order) : 0) {
    case 1: return "an LTI coefficient is not finite";
    case 2: return "the LTI denominator must start with a[0] = 1";
    case 3: return "the LTI has a pole at z = 1 (sum of a is 0): no rest state";
    }
    if (d->ne > PIM_DIAG_MAX_ELEMENTS) return "more than 8 further LTI elements";
    for (size_t j = 0; d->ne && j <= d->ne; ++j) {
        switch (lti_bad(d->el_b + PIM_DIAG_SECTION * j, d->el_a + PIM_DIAG_SECTION * j,
                        PIM_DIAG_SECTION - 1)) {
        case 1: return "a coefficient of a further LTI element is not finite";
        case 2: return "a further LTI element's denominator must start with a[0] = 1";
        case 3: return "a further LTI element has a pole at z = 1 (sum of a is 0)";
        }
        if (j > 0 && !isfinite(d->el_g[j - 1]))
            return "a further LTI element's gain is not finite";
    }
    if (d->nw > PIM_DIAG_MAX_ELEMENTS) return "more than 8 prefilter sections";
    for (size_t j = 0; j < d->nw; ++j) {
        switch (lti_bad(d->wf_b + PIM_DIAG_SECTION * j, d->wf_a + PIM_DIAG_SECTION * j,
                        PIM_DIAG_SECTION - 1)) {
        case 1: return "a prefilter coefficient is not finite";
        case 2: return "a prefilter section's denominator must start with a[0] = 1";
        case 3: return "a prefilter section has a pole at z = 1 (sum of a is 0): no rest state";
        }
    }
    if (!(isfinite(d->delay) && d->delay >= 0.0 && d->delay <= PIM_DIAG_MAX_DELAY - 2))
        return "the delay must be finite, >= 0 and <= 4094 samples";
    if (d->drift_clock < 0 || d->drift_clock > 2) return "drift_clock must be 0, 1 or 2";
    if (d->plays_start != 0 && d->plays_start != 1) return "plays_start must be 0 or 1";
    if (!isfinite(d->drift)) return "the drift is not finite";
    if (!(isfinite(d->settle_tau) && d->settle_tau >= 0.0))
        return "the settling time constant must be finite and >= 0 (0: none)";
    if (!isfinite(d->settle) || !isfinite(d->settle_t0))
        return "the settling amount and start must be finite";
    return NULL;
}

/* Where the delay lines start in the state (pim_diagnosed.h: after the element states). */
static size_t delay_lines_at(const pim_diag *d)
{
    return PIM_DIAG_HEADER + d->n + pim_diag_rate_size(d) + d->m + d->order +
           pim_diag_element_states(d);
}

/* The asymmetry term q u^2 + c3 u^3 of h0, u = (h0 - center) / half. */
static double asymmetry_term(const pim_diag *d, double h0)
{
    const double u = (h0 - d->center) / d->half;
    return d->q * (u * u) + d->c3 * (u * u * u);
}

/* The value `delay` samples before the newest, buf[head], of the ring buf[nbuf] (a fractional
 * part interpolates linearly, as pimodel.diagnosis.filters.shift). */
static double delayed(const double *buf, size_t nbuf, size_t head, double delay)
{
    const size_t d0 = (size_t)floor(delay);
    const double f = delay - (double)d0;
    const double x0 = buf[(head + nbuf - d0) % nbuf];
    if (f > 1e-12) return (1.0 - f) * x0 + f * buf[(head + nbuf - d0 - 1) % nbuf];
    return x0;
}

double pim_diag_step(const pim_diag *d, double *x, double v, double t)
{
    const size_t n = d->n, nr = pim_diag_rate_size(d), q = d->order;
    const size_t nbuf = pim_diag_delay_length(d->delay);
    double *z = x + PIM_DIAG_HEADER, *rate = z + n, *mem = rate + 1, *lag = rate + nr,
           *s = lag + d->m, *es = s + q, *buf = x + delay_lines_at(d),
           *hbuf = buf + nbuf, *zf = hbuf + nbuf, *fs = zf + n,
           *l0 = x + pim_diag_state_size(d) - pim_diag_record_states(d);
    const int radius = nr && d->rate_family == PIM_DIAG_RATE_RADIUS;
    const int scaled = nr && d->rate_family == PIM_DIAG_RATE_SCALED;
    const int first = x[0] == 0.0;
    if (first) {
        x[1] = v;
        x[2] = t;
        for (size_t i = 0; d->plays_start && i < n; ++i) z[i] = v; /* at rest at v[0] */
        for (size_t i = 0; scaled && d->plays_start && i < n; ++i) mem[i] = v; /* zs */
    }
    /* the scaled family: its plays, one step of pim_rdpi_sat_run (rate.scaled_play_sums) */
    double scaled_term = 0.0;
    if (scaled) {
        double p[PIM_DIAG_MAX_PLAYS], hist[2] = {x[1], rate[0]}, ys = 0.0;
        for (size_t i = 0; i < n; ++i) p[i] = d->rate_w[i] * d->w[i];
        pim_rdpi_sat_run(1, n, p, d->r, d->rate_growth / d->rate_scale,
                         d->rate_saturation * d->rate_scale, exp(-d->dt / d->rate_tau), d->dt,
                         mem, hist, &v, &ys);
        rate[0] = hist[1];
        scaled_term = ys;
    }
    /* the filtered rate rho_f[k] (rate.input_rate) */
    double rho_f = 0.0;
    if (nr && !scaled) {
        double rho = 0.0;
        if (!first) {
            const double dv = fabs(v - x[1]);
            rho = dv / d->dt / d->rate_scale;
            if (d->rate_tau == 0.0 && !(dv <= PIM_DIAG_STEP_SHARE * d->input_range))
                rho = 0.0; /* a sampled step */
        }
        if (d->rate_tau > 0.0) {
            const double a = exp(-d->dt / d->rate_tau);
            rho_f = (1.0 - a) * rho + a * rate[0];
        } else {
            rho_f = rho;
        }
        rate[0] = rho_f; /* the filter's state; the terms take the saturated rate */
        if (d->rate_saturation > 0.0) rho_f /= 1.0 + rho_f / d->rate_saturation;
    }
    /* plays, the hysteresis h and the reference h0; the radius family's term of each play in
     * contact (rate.RateBasis: -(v - z_i) rho_f, held after the contact) */
    double h = 0.0, h0 = 0.0;
    for (size_t i = 0; i < n; ++i) {
        const double zn = diag_clamp(z[i], v - d->r[i], v + d->r[i]);
        z[i] = zn;
        h += d->w[i] * zn;
        h0 += d->w0[i] * zn;
        if (radius && d->r[i] > 0.0) {
            const double gap = v - zn;
            if (fabs(gap) >= d->r[i] * (1.0 - 1e-9)) mem[i] = -gap * rho_f;
        }
    }
    h0 += d->c0;
    for (size_t i = 0; scaled && i < n; ++i) scaled_term -= d->rate_w[i] * (d->w[i] * z[i]);
    /* a prefilter (Wiener model): h from the plays zf of the filtered input x_f instead */
    if (d->nw) {
        const size_t m = PIM_DIAG_SECTION, o = PIM_DIAG_SECTION - 1;
        double xf = v;
        for (size_t j = 0; j < d->nw; ++j)
            xf = lti_step(d->wf_b + m * j, d->wf_a + m * j, o, fs + o * j, xf, first);
        for (size_t i = 0; first && d->plays_start && i < n; ++i) zf[i] = xf; /* at x_f[0] */
        h = 0.0;
        for (size_t i = 0; i < n; ++i) {
            zf[i] = diag_clamp(zf[i], xf - d->r[i], xf + d->r[i]);
            h += d->w[i] * zf[i];
        }
    }
    /* LTI, transposed direct form II, started at rest around h[0] */
    double xk = q ? lti_step(d->b, d->a, q, s, h, first) : h;
    /* the further elements on h0 (lti.lti_columns): sum_j g_j (E_j[h0] - M_1[h0]) */
    if (d->ne) {
        const size_t m = PIM_DIAG_SECTION, o = PIM_DIAG_SECTION - 1;
        const double base = lti_step(d->el_b, d->el_a, o, es, h0, first);
        double acc = 0.0;
        for (size_t j = 1; j <= d->ne; ++j)
            acc += d->el_g[j - 1] *
                   (lti_step(d->el_b + m * j, d->el_a + m * j, o, es + o * j, h0, first) - base);
        xk += acc;
    }
    /* delay lines: buf[head] holds x[k], hbuf[head] h0[k] after the write; the delay acts on
     * the input of everything the plays drive, so the effect terms below take h0 delayed */
    double y = xk;
    if (nbuf) {
        size_t head = first ? 0 : ((size_t)x[3] + 1) % nbuf;
        if (first)
            for (size_t j = 0; j < nbuf; ++j) {
                buf[j] = xk;
                hbuf[j] = h0;
            }
        buf[head] = xk;
        hbuf[head] = h0;
        x[3] = (double)head;
        y = delayed(buf, nbuf, head, d->delay);
        h0 = delayed(hbuf, nbuf, head, d->delay);
    }
    y += d->c;
    /* the effect terms, in the order of DiagnosedModel.simulate */
    const int record = d->lag_record && d->m;
    if (record && first) l0[0] = h0; /* the lags' start at rest, kept for the record */
    for (size_t j = 0; j < d->m; ++j) {
        const double a = d->lag_a[j];
        const double before = !first ? lag[j] : d->lag_start ? d->lag_start[j] : h0;
        lag[j] = (1.0 - a) * h0 + a * before;
        if (record) /* counted from the record's start: less g_j L_j[-1] */
            y += d->lag_g[j] * (lag[j] - h0 - (d->lag_start ? d->lag_start[j] : l0[0]));
        else
            y += d->lag_g[j] * (lag[j] - h0);
    }
    if (d->asym) y += asymmetry_term(d, h0);
    if (radius) {
        double acc = 0.0;
        for (size_t i = 0; i < n; ++i) acc += d->rate_w[i] * mem[i];
        y += acc;
    } else if (scaled) {
        y += scaled_term;
    } else if (nr) {
        double acc = 0.0;
        for (size_t i = 0; i < n; ++i) acc += d->rate_w[i] * (d->w0[i] * z[i]);
        y += rho_f * acc;
    }
    if (d->drift_clock == 1)
        y += d->drift * (t - x[2]);
    else if (d->drift_clock == 2)
        y += d->drift * t;
    if (d->settle_tau > 0.0) y += d->settle * -expm1(-(t - d->settle_t0) / d->settle_tau);
    x[0] = 1.0;
    x[1] = v;
    return y;
}

int pim_diag_pending_finite(const pim_diag *d, const double *x)
{
    const size_t nbuf = pim_diag_delay_length(d->delay);
    if (!nbuf || x[0] == 0.0) return 1;
    const double *buf = x + delay_lines_at(d);
    const size_t head = (size_t)x[3];
    const double xk = buf[head], h0 = buf[nbuf + head];
    return isfinite(xk) && isfinite(h0) && (!d->asym || isfinite(asymmetry_term(d, h0)));
}

void pim_diag_run(const pim_diag *d, double *x, size_t N, const double *v, const double *t,
                  double *y)
{
    for (size_t k = 0; k < N; ++k) y[k] = pim_diag_step(d, x, v[k], t ? t[k] : (double)k * d->dt);
}
