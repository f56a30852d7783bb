/* The C yardstick of pdfem.kernels.element.q4_forces_1pt for elastic materials: the same
 * algorithm, operation for operation (objective Hughes-Winget update with the Cayley rotation
 * of the mid-step spin, hypo-elastic increment, trapezoidal stress work, total-form stiffness
 * hourglass control from the reference hg[e] = (gamma_0..3, hg_coef A0 (b0.b0), A0); a linear
 * bulk, so the spring's modulus is constant: K + 4G/3 for hg_model 0, the coefficient's,
 * (8G/3)(3K + G)/(3K + 4G) for hg_model 1, the bending one, and (2/3)(K + 7G/3) for hg_model
 * 2, the full one), flat arrays in. Built by `pdfem bench elements` with
 * gcc -O3 -march=native; used to measure how close the numba kernel comes to compiled C.
 * Returns -1, or the first element with a non-positive area. */
#include <stdint.h>

enum { RHO = 1, BULK = 2, SHEAR = 3 };

/* Centroid gradients of a quad (x[4][2]); returns the area */
static double bvec(const double xe[4][2], double bx[4], double by[4]) {
    double a = 0.5 * ((xe[2][0] - xe[0][0]) * (xe[3][1] - xe[1][1])
                      - (xe[3][0] - xe[1][0]) * (xe[2][1] - xe[0][1]));
    if (a <= 0.0) return a;
    double r = 1.0 / (2.0 * a);
    for (int i = 0; i < 4; i++) {
        int ip = (i + 1) % 4, im = (i + 3) % 4;
        bx[i] = (xe[ip][1] - xe[im][1]) * r;
        by[i] = (xe[im][0] - xe[ip][0]) * r;
    }
    return a;
}

int64_t q4_forces_1pt_elastic(const double *x, const double *du, const int64_t *conn,
                              const int32_t *emat, const double *mat, int64_t npar, double *sig,
                              const double *hg, int64_t nhg, int64_t hg_model, int64_t e0,
                              int64_t e1, double *f, double *ewint) {
    double xc[4][2], xm[4][2], ue[4][2], fe[4][2], bx[4], by[4], deps[4], sold[4];
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
        /* Mid-step gradient of the increment */
        double am = bvec(xm, bx, by);
        if (am <= 0.0) return e;
        double gxx = 0.0, gxy = 0.0, gyx = 0.0, gyy = 0.0;
        for (int i = 0; i < 4; i++) {
            gxx += ue[i][0] * bx[i]; gxy += ue[i][0] * by[i];
            gyx += ue[i][1] * bx[i]; gyy += ue[i][1] * by[i];
        }
        double w = 0.5 * (gxy - gyx);
        double d = 1.0 / (1.0 + 0.25 * w * w);
        double c = (1.0 - 0.25 * w * w) * d, sn = w * d;
        /* Rotate the stress, then the hypo-elastic increment */
        double *s = sig + 4 * e;
        double sxx = s[0], syy = s[1], sxy = s[2];
        s[0] = c * c * sxx + 2.0 * c * sn * sxy + sn * sn * syy;
        s[1] = sn * sn * sxx - 2.0 * c * sn * sxy + c * c * syy;
        s[2] = c * sn * (syy - sxx) + (c * c - sn * sn) * sxy;
        deps[0] = gxx - 0.0; deps[1] = gyy - 0.0; deps[2] = 0.5 * (gxy + gyx); deps[3] = -0.0;
        for (int k = 0; k < 4; k++) sold[k] = s[k];
        double g2 = 2.0 * p[SHEAR], lam = p[BULK] - g2 / 3.0;
        double dv = deps[0] + deps[1] + deps[3];
        s[0] += lam * dv + g2 * deps[0];
        s[1] += lam * dv + g2 * deps[1];
        s[2] += g2 * deps[2];
        s[3] += lam * dv + g2 * deps[3];
        double wk = 0.5 * ((sold[0] + s[0]) * deps[0] + (sold[1] + s[1]) * deps[1]
                           + 2.0 * (sold[2] + s[2]) * deps[2] + (sold[3] + s[3]) * deps[3]);
        /* Current geometry and the stress-divergence forces */
        double a = bvec(xc, bx, by);
        if (a <= 0.0) return e;
        ewint[e] += wk * a;
        for (int i = 0; i < 4; i++) {
            fe[i][0] = a * (s[0] * bx[i] + s[2] * by[i]);
            fe[i][1] = a * (s[2] * bx[i] + s[1] * by[i]);
        }
        /* Hourglass: the mode of the current and the last positions, energy change, forces */
        if (nhg > 0) {
            const double *g = hg + 6 * e;
            double m = p[BULK] + 4.0 * p[SHEAR] / 3.0;
            if (hg_model == 1)
                m = 8.0 * p[SHEAR] * (3.0 * p[BULK] + p[SHEAR])
                    / (3.0 * (3.0 * p[BULK] + 4.0 * p[SHEAR]));
            else if (hg_model == 2)
                m = 2.0 * (p[BULK] + 7.0 * p[SHEAR] / 3.0) / 3.0;
            double k = g[4] * m, q0 = 0.0, q1 = 0.0, p0 = 0.0, p1 = 0.0;
            for (int i = 1; i < 4; i++) {
                q0 += g[i] * (xc[i][0] - xc[0][0]); q1 += g[i] * (xc[i][1] - xc[0][1]);
            }
            for (int i = 1; i < 4; i++) {
                p0 += g[i] * (ue[i][0] - ue[0][0]); p1 += g[i] * (ue[i][1] - ue[0][1]);
            }
            p0 = q0 - p0; p1 = q1 - p1;
            ewint[e] += 0.5 * k * ((q0 * q0 + q1 * q1) - (p0 * p0 + p1 * p1));
            for (int i = 0; i < 4; i++) { fe[i][0] += k * q0 * g[i]; fe[i][1] += k * q1 * g[i]; }
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
