/* The C yardstick of pdfem.kernels.element.q4_forces_2x2 for Sandler-Rubin cap materials
 * without thermal coupling: the same algorithm, operation for operation (objective
 * Hughes-Winget update with the Cayley rotation of the mid-step spin at each of the 2x2 Gauss
 * points, material dispatch of pdfem.kernels.material, the substepped backward-Euler cap
 * return of pdfem.kernels.cap / cap_surface with all its branches, iterations and status
 * codes, plastic work, trapezoidal stress work, forces with current-configuration gradients),
 * flat arrays in. Python's min/max are spelled as numba lowers them (pmin/pmax), x ** 2 as
 * x * x, int(float) as the x86 truncation numba emits. Float division by zero, which numba
 * raises on, gives inf here (never reached with parameters that pass cap_check_params).
 * Built by pdfem.tools.bench.cyardstick with gcc -O3 -march=native; used to measure how close
 * the numba kernel comes to compiled C. Returns -1, or the first element with a non-positive
 * Gauss-point Jacobian (mid-step or current) or a failed material update. */
#include <math.h>
#include <stdint.h>

static const double GP = 0.5773502691896257;
static const double XI[4] = {-1.0, 1.0, 1.0, -1.0};
static const double ETA[4] = {-1.0, -1.0, 1.0, 1.0};
enum { MODEL = 0, BULK = 2, SHEAR = 3, CAP_A = 4, CAP_B = 5, CAP_C = 6, CAP_D = 7, CAP_R = 8,
       CAP_W = 9, CAP_KAPPA0 = 10, CAP_T = 11, CAP_TOL = 12 };
enum { ELASTIC = 0, CAP = 1 };
enum { MAT_UNKNOWN_MODEL = -1, CAP_OK = 0, CAP_NO_CONVERGENCE = 1, CAP_OUTSIDE = 2,
       CAP_NONFINITE = 3 };
enum { MAXIT = 200, NSUB_MAX = 2000 };
static const double SUB_ETA = 0.01, TOL_DEFAULT = 1e-8;

/* Python's max(a, b) / min(a, b) as numba lowers them: b if b > a (b < a) else a */
static inline double pmax(double a, double b) { return b > a ? b : a; }
static inline double pmin(double a, double b) { return b < a ? b : a; }

/* int(v) as numba emits it on x86-64 (cvttsd2si: out of range or NaN gives INT64_MIN) */
static inline int64_t trunc_i64(double v) {
    if (!(v > -9.223372036854775808e18 && v < 9.223372036854775808e18)) return INT64_MIN;
    return (int64_t)v;
}

/* ---- cap_surface.py ---- */

/* Failure envelope F(I1) = A - C exp(B I1) */
static double env_f(const double *p, double i1) {
    return p[CAP_A] - p[CAP_C] * exp(p[CAP_B] * i1);
}

/* -dF/dI1 = C B exp(B I1) */
static double env_slope(const double *p, double i1) {
    return p[CAP_C] * p[CAP_B] * exp(p[CAP_B] * i1);
}

/* Envelope apex ln(A/C)/B, or +inf */
static double apex(const double *p) {
    if (p[CAP_C] > 0.0 && p[CAP_B] > 0.0) return log(p[CAP_A] / p[CAP_C]) / p[CAP_B];
    return INFINITY;
}

/* Effective tension cut-off min(T, apex) */
static double tension_limit(const double *p) { return pmin(p[CAP_T], apex(p)); }

/* Cap/envelope intersection L = min(kappa, 0) */
static double cap_l(double kap) { return pmin(kap, 0.0); }

/* I1 on the cap side of the corner beyond round-off */
static int cap_side(const double *p, double i1, double kap) {
    double el = cap_l(kap);
    return i1 < el - 1e-12 * (fabs(el) + p[CAP_R] * p[CAP_A]);
}

/* Cap intersection with the I1 axis X = kappa - R F(kappa) */
static double cap_x(const double *p, double kap) { return kap - p[CAP_R] * env_f(p, kap); }

/* Cap semi-axis along I1, L - X clamped at 0 */
static double cap_rho(const double *p, double kap) {
    return pmax(cap_l(kap) - cap_x(p, kap), 0.0);
}

/* Initial cap position X0 */
static double x0(const double *p) { return cap_x(p, p[CAP_KAPPA0]); }

/* Hardening H(kappa) = W exp(D (X(kappa) - X0)) */
static double hard_h(const double *p, double kap, double xa) {
    return p[CAP_W] * exp(p[CAP_D] * (cap_x(p, kap) - xa));
}

/* dH/dkappa */
static double hard_dh(const double *p, double kap, double xa) {
    return p[CAP_D] * hard_h(p, kap, xa) * (1.0 + p[CAP_R] * env_slope(p, kap));
}

/* Normalised yield value at (I1, J): cap or envelope, then the tension cut-off */
static double yield_value(const double *p, double i1, double j, double kap) {
    double a = p[CAP_A], v;
    if (cap_side(p, i1, kap)) {
        double el = cap_l(kap), r = p[CAP_R], t = i1 - el;
        v = (sqrt(r * r * j * j + t * t) - cap_rho(p, kap)) / (r * a);
    } else {
        v = (j - env_f(p, i1)) / a;
    }
    return pmax(v, (i1 - p[CAP_T]) / (3.0 * a));
}

/* Backward-Euler return onto the envelope: safeguarded Newton on I1 */
static double envelope_i1(const double *p, double i1t, double jt, double kb, double gs,
                          int *ok) {
    double q = 9.0 * kb / gs;
    double sl = env_slope(p, i1t);
    double over = q * sl * (jt - env_f(p, i1t));
    *ok = 1;
    if (over <= 0.0) return i1t;
    /* Bracket */
    double hi = i1t, lo = i1t - over;
    double a = p[CAP_A], b = p[CAP_B], c = p[CAP_C];
    if (jt < a && c > 0.0 && b > 0.0) lo = pmax(lo, log((a - jt) / c) / b);
    /* Safeguarded Newton from the right end */
    double x = hi;
    double rtol = 1e-14 * (fabs(i1t) + 3.0 * a);
    for (int it = 0; it < MAXIT; it++) {
        sl = env_slope(p, x);
        double fj = jt - env_f(p, x);
        double r = x - i1t + q * sl * fj;
        if (fabs(r) <= rtol) return x;
        if (r > 0.0) hi = x; else lo = x;
        double xn = x - r / (1.0 + q * (b * sl * fj + sl * sl));
        if (!(lo <= xn && xn <= hi)) xn = 0.5 * (lo + hi);
        if (fabs(xn - x) <= 1e-15 * (fabs(x) + a)) return xn;
        x = xn;
    }
    *ok = 0;
    return x;
}

/* Kappa after a dilatant eps_v^p increment depv, at most lim */
static double dilate_kappa(const double *p, double kap, double depv, double lim, double xa) {
    if (depv <= 0.0 || lim <= kap) return kap;
    double ht = hard_h(p, kap, xa) + depv;
    if (hard_h(p, lim, xa) <= ht) return lim;
    /* Safeguarded Newton on [kap, lim] */
    double lo = kap, hi = lim, k = kap;
    for (int it = 0; it < MAXIT; it++) {
        double r = hard_h(p, k, xa) - ht;
        if (r > 0.0) hi = k; else lo = k;
        double kn = k - r / hard_dh(p, k, xa);
        if (!(lo <= kn && kn <= hi)) kn = 0.5 * (lo + hi);
        if (fabs(kn - k) <= 1e-15 * (fabs(k) + p[CAP_R] * p[CAP_A])) return kn;
        k = kn;
    }
    return k;
}

/* Kappa at the envelope/cap corner: H(k) - H(kap) = (I1t - L(k))/(3K) */
static double corner_kappa(const double *p, double i1t, double kap, double xa, double kb,
                           int *ok) {
    *ok = 1;
    if (kap >= 0.0) return kap;
    double h0 = hard_h(p, kap, xa);
    if (hard_h(p, 0.0, xa) - h0 - i1t / (3.0 * kb) <= 0.0) return 0.0;
    /* Safeguarded Newton on [kap, 0] */
    double lo = kap, hi = 0.0, k = kap;
    for (int it = 0; it < MAXIT; it++) {
        double r = hard_h(p, k, xa) - h0 - (i1t - k) / (3.0 * kb);
        if (r > 0.0) hi = k; else lo = k;
        double kn = k - r / (hard_dh(p, k, xa) + 1.0 / (3.0 * kb));
        if (!(lo <= kn && kn <= hi)) kn = 0.5 * (lo + hi);
        if (fabs(kn - k) <= 1e-15 * (fabs(k) + p[CAP_R] * p[CAP_A])) return kn;
        k = kn;
    }
    *ok = 0;
    return k;
}

/* Backward-Euler return onto the cap of fixed position kap: I1, J and dI1/dkappa */
static void cap_point(const double *p, double i1t, double jt, double kap, double kb, double gs,
                      double *i1o, double *jo, double *di1o) {
    double r = p[CAP_R];
    double el = cap_l(kap);
    double dl = kap < 0.0 ? 1.0 : 0.0;
    double rho = cap_rho(p, kap);
    double a = i1t - el;
    double c = gs * r * r / (9.0 * kb);
    double rj = r * jt;
    /* Inside (s = 1), degenerate cap (s = 0), or safeguarded Newton on [0, 1] */
    double mm = sqrt(rj * rj + a * a);
    if (mm <= rho) { *i1o = i1t; *jo = jt; *di1o = 0.0; return; }
    double s = 0.0, w, q, dm;
    if (rho > 0.0) {
        s = rho / mm;
        double lo = 0.0, hi = 1.0;
        double gtol = 1e-15 * (mm + rho);
        for (int it = 0; it < MAXIT; it++) {
            w = c + (1.0 - c) * s;
            q = rj / w;
            mm = sqrt(q * q + a * a);
            double g = s * mm - rho;
            if (fabs(g) <= gtol) break;
            if (g > 0.0) hi = s; else lo = s;
            dm = -(rj * rj) * (1.0 - c) / (mm * w * w * w);
            double sn = s - g / (mm + s * dm);
            if (!(lo < sn && sn < hi)) sn = 0.5 * (lo + hi);
            if (hi - lo <= 1e-16) { s = sn; break; }
            s = sn;
        }
    }
    w = c + (1.0 - c) * s;
    q = rj / w;
    mm = sqrt(q * q + a * a);
    dm = -(rj * rj) * (1.0 - c) / (mm * w * w * w);
    /* Sensitivity of the return point to the cap position */
    double drho = dl - 1.0 - r * env_slope(p, kap);
    if (rho <= 0.0) drho = pmax(drho, 0.0);
    double dgdk = -s * a * dl / mm - drho;
    double dsdk = -dgdk / (mm + s * dm);
    *i1o = el + a * s;
    *jo = jt * s / w;
    *di1o = dl * (1.0 - s) + a * dsdk;
}

/* Cap return with consistent hardening: outer safeguarded Newton on kappa; returns kappa */
static double cap_return(const double *p, double i1t, double jt, double kap, double xa,
                         double kb, double gs, double *i1, double *j, int *ok) {
    double h0 = hard_h(p, kap, xa);
    double lo = i1t, hi = kap, k = kap, di1;
    double htol = pmax(1e-13 * (cap_l(kap) - i1t) / (3.0 * kb), 4e-16 * (h0 + p[CAP_W]));
    double ktol = 1e-15 * (fabs(kap) + fabs(i1t) + p[CAP_R] * p[CAP_A]);
    *ok = 1;
    for (int it = 0; it < MAXIT; it++) {
        cap_point(p, i1t, jt, k, kb, gs, i1, j, &di1);
        double h = hard_h(p, k, xa) - h0 + (*i1 - i1t) / (3.0 * kb);
        if (fabs(h) <= htol) return k;
        if (h > 0.0) hi = k; else lo = k;
        double dh = hard_dh(p, k, xa) + di1 / (3.0 * kb);
        double kn = dh > 0.0 ? k - h / dh : 0.5 * (lo + hi);
        if (!(lo < kn && kn < hi)) kn = 0.5 * (lo + hi);
        if (fabs(kn - k) <= ktol) {
            cap_point(p, i1t, jt, kn, kb, gs, i1, j, &di1);
            return kn;
        }
        k = kn;
    }
    cap_point(p, i1t, jt, k, kb, gs, i1, j, &di1);
    *ok = 0;
    return k;
}

/* ---- cap.py ---- */

/* Normalised yield tolerance: p[CAP_TOL], or 1e-8 when it is 0 */
static double cap_tolerance(const double *p) {
    return p[CAP_TOL] > 0.0 ? p[CAP_TOL] : TOL_DEFAULT;
}

/* Largest active normalised yield function at stress sig and state st */
static double cap_yield_value(const double *p, const double *sig, const double *st) {
    double i1 = sig[0] + sig[1] + sig[3];
    double m = i1 / 3.0;
    double sx = sig[0] - m, sy = sig[1] - m, sz = sig[3] - m;
    double j = sqrt(0.5 * (sx * sx + sy * sy + sz * sz) + sig[2] * sig[2]);
    return yield_value(p, i1, j, st[0]);
}

/* Elastic trial stress sig + C:d into t[4] */
static void trial(const double *p, const double *sig, double d0, double d1, double d2,
                  double d3, double t[4]) {
    double g2 = 2.0 * p[SHEAR];
    double lam = p[BULK] - g2 / 3.0;
    double dv = d0 + d1 + d3;
    t[0] = sig[0] + (lam * dv + g2 * d0);
    t[1] = sig[1] + (lam * dv + g2 * d1);
    t[2] = sig[2] + g2 * d2;
    t[3] = sig[3] + (lam * dv + g2 * d3);
}

/* Plastic return in invariant space: I1, J, kappa, converged; returns plastic (0/1) */
static int return_invariants(const double *p, double i1t, double jt, double kap, double xa,
                             double tn, double *i1o, double *jo, double *kno, int *ok) {
    double kb = p[BULK], gs = p[SHEAR];
    double el = cap_l(kap);
    *ok = 1;
    /* Cap side of the corner */
    if (cap_side(p, i1t, kap)) {
        double r = p[CAP_R], t = i1t - el;
        if (sqrt(r * r * jt * jt + t * t) <= cap_rho(p, kap)) {
            *i1o = i1t; *jo = jt; *kno = kap;
            return 0;
        }
        *kno = cap_return(p, i1t, jt, kap, xa, kb, gs, i1o, jo, ok);
        return 1;
    }
    /* Envelope side: elastic, tension cut-off, tension corner or envelope */
    if (i1t <= tn && jt <= env_f(p, i1t)) {
        *i1o = i1t; *jo = jt; *kno = kap;
        return 0;
    }
    int envelope = 1;
    double i1 = i1t, j = jt;
    if (i1t > tn) {
        double ftn = env_f(p, tn);
        if (jt <= ftn) {
            i1 = tn;
            envelope = 0;
        } else if (i1t - tn - 9.0 * kb * (jt - ftn) / gs * env_slope(p, tn) >= 0.0) {
            i1 = tn;
            j = ftn;
            envelope = 0;
        }
    }
    if (envelope) {
        i1 = envelope_i1(p, i1t, jt, kb, gs, ok);
        j = pmax(env_f(p, i1), 0.0);
        /* Past the corner: stress at I1 = L(kappa), J = F(L) */
        if (i1 < el) {
            double kn = corner_kappa(p, i1t, kap, xa, kb, ok);
            i1 = cap_l(kn);
            *i1o = i1; *jo = env_f(p, i1); *kno = kn;
            return 1;
        }
    }
    /* Dilatancy retracts the cap, never past the origin or the stress */
    *kno = dilate_kappa(p, kap, (i1t - i1) / (3.0 * kb), pmax(kap, pmin(0.0, i1)), xa);
    *i1o = i1; *jo = j;
    return 1;
}

/* One backward-Euler increment; updates sig, st; returns converged, plastic work into dwp */
static int step(const double *p, double *sig, double *st, double d0, double d1, double d2,
                double d3, double xa, double tn, double *dwp) {
    double kb = p[BULK];
    double g2 = 2.0 * p[SHEAR];
    double t[4];
    trial(p, sig, d0, d1, d2, d3, t);
    double i1t = t[0] + t[1] + t[3];
    double m = i1t / 3.0;
    double s0 = t[0] - m, s1 = t[1] - m, s2 = t[2], s3 = t[3] - m;
    double jt = sqrt(0.5 * (s0 * s0 + s1 * s1 + s3 * s3) + s2 * s2);
    double i1, j, kn;
    int ok;
    int plastic = return_invariants(p, i1t, jt, st[0], xa, tn, &i1, &j, &kn, &ok);
    /* Elastic: the trial stands */
    if (!plastic) {
        sig[0] = t[0]; sig[1] = t[1]; sig[2] = t[2]; sig[3] = t[3];
        *dwp = 0.0;
        return ok;
    }
    /* Deviator scaled along the trial direction, new mean stress */
    double f = jt > 0.0 ? j / jt : 0.0;
    m = i1 / 3.0;
    sig[0] = f * s0 + m;
    sig[1] = f * s1 + m;
    sig[2] = f * s2;
    sig[3] = f * s3 + m;
    /* Plastic strain increment C^-1:(trial - sigma) and its work sigma:deps^p */
    double dv = (i1t - i1) / (3.0 * kb);
    double e0 = (1.0 - f) * s0 / g2;
    double e1 = (1.0 - f) * s1 / g2;
    double e2 = (1.0 - f) * s2 / g2;
    double e3 = (1.0 - f) * s3 / g2;
    *dwp = f * (s0 * e0 + s1 * e1 + s3 * e3 + 2.0 * s2 * e2) + m * dv;
    st[0] = kn;
    st[1] += dv;
    st[2] += e0 + dv / 3.0;
    st[3] += e1 + dv / 3.0;
    st[4] += e2;
    st[5] += e3 + dv / 3.0;
    return ok;
}

/* Substepped plastic update for a trial with normalised overshoot over; returns status */
static int plastic_update(const double *p, double *sig, double *st, double d0, double d1,
                          double d2, double d3, double over, double *dwp) {
    /* Substeps: more of them the further the trial lies outside, against the stress's size
       (the larger of A and the trial's mean stress |I1|/3) */
    double a = p[CAP_A];
    double i1t = sig[0] + sig[1] + sig[3] + 3.0 * p[BULK] * (d0 + d1 + d3);
    double scale = fabs(i1t) / 3.0 > a ? fabs(i1t) / 3.0 : a;
    int64_t ns = 1 + trunc_i64(over * (a / scale) / SUB_ETA);
    int64_t nsub = ns < NSUB_MAX ? ns : NSUB_MAX;
    double xa = x0(p);
    double tn = tension_limit(p);
    double w = 1.0 / (double)nsub;
    int status = CAP_OK;
    *dwp = 0.0;
    for (int64_t i = 0; i < nsub; i++) {
        double dw;
        int ok = step(p, sig, st, w * d0, w * d1, w * d2, w * d3, xa, tn, &dw);
        *dwp += dw;
        if (!ok) status = CAP_NO_CONVERGENCE;
    }
    /* Guards: finite, on or inside the surface */
    if (!isfinite(sig[0] + sig[1] + sig[2] + sig[3] + st[0] + *dwp)) return CAP_NONFINITE;
    if (status == CAP_OK && cap_yield_value(p, sig, st) > cap_tolerance(p))
        status = CAP_OUTSIDE;
    return status;
}

/* Cap model update of sig in place for strain increment deps; returns status */
static int cap_update(const double *p, double *sig, const double *deps, double *st,
                      double *dwp) {
    double d0 = deps[0], d1 = deps[1], d2 = deps[2], d3 = deps[3];
    *dwp = 0.0;
    if (!(isfinite(d0 + d1 + d2 + d3) && isfinite(sig[0] + sig[1] + sig[2] + sig[3] + st[0])))
        return CAP_NONFINITE;
    /* Elastic trial: done when it is inside */
    double t[4];
    trial(p, sig, d0, d1, d2, d3, t);
    double i1t = t[0] + t[1] + t[3];
    double m = i1t / 3.0;
    double a0 = t[0] - m, a1 = t[1] - m, a3 = t[3] - m;
    double jt = sqrt(0.5 * (a0 * a0 + a1 * a1 + a3 * a3) + t[2] * t[2]);
    double over = yield_value(p, i1t, jt, st[0]);
    if (over <= 0.0) {
        sig[0] = t[0]; sig[1] = t[1]; sig[2] = t[2]; sig[3] = t[3];
        return CAP_OK;
    }
    return plastic_update(p, sig, st, d0, d1, d2, d3, over, dwp);
}

/* ---- material.py / elastic.py ---- */

/* Material dispatch on the model id: elastic, cap, or unknown (-1, stress untouched) */
static int material_update(const double *p, double *sig, const double *deps, double *st,
                           double *dwp) {
    int64_t model = trunc_i64(p[MODEL]);
    *dwp = 0.0;
    if (model == ELASTIC) {
        double g2 = 2.0 * p[SHEAR];
        double lam = p[BULK] - g2 / 3.0;
        double dv = deps[0] + deps[1] + deps[3];
        sig[0] += lam * dv + g2 * deps[0];
        sig[1] += lam * dv + g2 * deps[1];
        sig[2] += g2 * deps[2];
        sig[3] += lam * dv + g2 * deps[3];
        return 0;
    }
    if (model == CAP) return cap_update(p, sig, deps, st, dwp);
    return MAT_UNKNOWN_MODEL;
}

/* ---- element.py ---- */

/* Shape function gradients dx, dy at (xi, eta); returns det J (dx, dy unset if <= 0) */
static double ip_grad(double xe[4][2], double xi, double eta, double dx[4],
                      double dy[4]) {
    double j11 = 0.0, j12 = 0.0, j21 = 0.0, j22 = 0.0;
    for (int i = 0; i < 4; i++) {
        double dxi = 0.25 * XI[i] * (1.0 + ETA[i] * eta);
        double deta = 0.25 * ETA[i] * (1.0 + XI[i] * xi);
        j11 += dxi * xe[i][0];
        j12 += deta * xe[i][0];
        j21 += dxi * xe[i][1];
        j22 += deta * xe[i][1];
    }
    double det = j11 * j22 - j12 * j21;
    if (det <= 0.0) return det;
    /* Chain rule through the inverse Jacobian */
    double r = 1.0 / det;
    for (int i = 0; i < 4; i++) {
        double dxi = 0.25 * XI[i] * (1.0 + ETA[i] * eta);
        double deta = 0.25 * ETA[i] * (1.0 + XI[i] * xi);
        dx[i] = (j22 * dxi - j21 * deta) * r;
        dy[i] = (j11 * deta - j12 * dxi) * r;
    }
    return det;
}

int64_t q4_forces_2x2_cap(const double *x, const double *du, const int64_t *conn,
                          const int32_t *emat, const double *mat, int64_t npar, double *sig,
                          double *mst, int64_t nst, int64_t e0, int64_t e1, double *f,
                          double *ewint, double *ewp) {
    double xc[4][2], xm[4][2], ue[4][2], fe[4][2], dx[4], dy[4], deps[4], sold[4];
    for (int64_t e = e0; e < e1; e++) {
        const double *p = mat + (int64_t)emat[e] * npar;
        /* Gather current, mid-step coordinates and increments */
        for (int i = 0; i < 4; i++) {
            int64_t n = conn[4 * e + i];
            for (int k = 0; k < 2; k++) {
                xc[i][k] = x[2 * n + k];
                ue[i][k] = du[2 * n + k];
                xm[i][k] = x[2 * n + k] - 0.5 * du[2 * n + k];
            }
        }
        for (int i = 0; i < 4; i++) { fe[i][0] = 0.0; fe[i][1] = 0.0; }
        for (int ip = 0; ip < 4; ip++) {
            double xi = GP * XI[ip], eta = GP * ETA[ip];
            /* Mid-step gradient of the increment at this point */
            if (ip_grad(xm, xi, eta, dx, dy) <= 0.0) return e;
            double gxx = 0.0, gxy = 0.0, gyx = 0.0, gyy = 0.0;
            for (int i = 0; i < 4; i++) {
                gxx += ue[i][0] * dx[i]; gxy += ue[i][0] * dy[i];
                gyx += ue[i][1] * dx[i]; gyy += ue[i][1] * dy[i];
            }
            double w = 0.5 * (gxy - gyx);
            double d = 1.0 / (1.0 + 0.25 * w * w);
            double c = (1.0 - 0.25 * w * w) * d, sn = w * d;
            /* Rotate the stress, then the material update with the symmetric part */
            double *s = sig + 16 * e + 4 * ip;
            double *st = mst + (4 * e + ip) * nst;
            double sxx = s[0], syy = s[1], sxy = s[2];
            s[0] = c * c * sxx + 2.0 * c * sn * sxy + sn * sn * syy;
            s[1] = sn * sn * sxx - 2.0 * c * sn * sxy + c * c * syy;
            s[2] = c * sn * (syy - sxx) + (c * c - sn * sn) * sxy;
            deps[0] = gxx - 0.0; deps[1] = gyy - 0.0; deps[2] = 0.5 * (gxy + gyx); deps[3] = -0.0;
            for (int k = 0; k < 4; k++) sold[k] = s[k];
            double dwp;
            if (material_update(p, s, deps, st, &dwp) != 0) return e;
            /* Stress power density, trapezoidal in time */
            double wk = 0.5 * ((sold[0] + s[0]) * deps[0] + (sold[1] + s[1]) * deps[1]
                               + 2.0 * (sold[2] + s[2]) * deps[2] + (sold[3] + s[3]) * deps[3]);
            /* Forces and work with the current gradients and volume */
            double dv = ip_grad(xc, xi, eta, dx, dy);
            if (dv <= 0.0) return e;
            ewint[e] += wk * dv;
            ewp[e] += dwp * dv;
            for (int i = 0; i < 4; i++) {
                fe[i][0] += dv * (s[0] * dx[i] + s[2] * dy[i]);
                fe[i][1] += dv * (s[2] * dx[i] + s[1] * dy[i]);
            }
        }
        /* Scatter, f -= fe */
        for (int i = 0; i < 4; i++) {
            int64_t n = conn[4 * e + i];
            f[2 * n] -= fe[i][0];
            f[2 * n + 1] -= fe[i][1];
        }
    }
    return -1;
}
