/* The C twin of pdfem.kernels.contact.contact_pass as a step runs it: key-sorted candidates
 * (element pairs in canonical orientation, element-wall pairs), the law of the material pair
 * from the law table, the shear history by a merge with the sorted history table, one output
 * row per contact that touches (the last row scratch), the convex case of a pair written out
 * as in the pass. The same algorithm, operation for operation; min and max keep numba's
 * choice on ties (the first argument unless the second is strictly smaller or larger), and
 * the build has -ffp-contract=off (numba fuses no multiply-add), so the results are the same
 * bits. Scope: a non-convex B (the pass splits it into two triangles) is not handled: such a
 * candidate is counted in *unsupported and gets no row. Built by `pdfem bench contact` with
 * gcc -O3 -march=native; used to measure how close the numba kernel comes to compiled C.
 * Returns the rows written (or needed), the guarded contacts in *nbad and the candidates
 * evaluated in *nev. */
#include <math.h>
#include <stdint.h>

#define MIN(a, b) ((b) < (a) ? (b) : (a))
#define MAX(a, b) ((b) > (a) ? (b) : (a))
enum { MAXV = 16 };
enum { OV_OK = 0, OV_NONE = 1, OV_INSIDE = 2, OV_OVERFLOW = 3 };
enum { C_NONE = 0, C_ACTIVE = 1, C_INSIDE = -1, C_NOEDGE = -2, C_NONORMAL = -3,
       C_OVERFLOW = -4 };
enum { K_P = 0, K_Q = 1, K_X = 2 };
enum { P_KN0 = 0, P_DMAX = 1, P_KS = 2, P_MU = 3, P_RCAP = 4, P_ZETA = 5, P_LAW = 6, NPAR = 7 };
enum { R_FN, R_FS, R_ENERGY, R_DISS, R_STIFF, R_DELTA, R_WIDTH, R_NX, R_NY, R_CX, R_CY,
       R_DAMP, R_LEN, R_KSL, R_MEFF, R_AREA, NRES };
static const double SLIVER = 1e-14;
static const double R_SERIES = 0.05;

/* contact_law._phi_hyper: -ln(1 - r) - r */
static double phi_hyper(double r) {
    if (r < R_SERIES) {
        double s = 0.0;
        for (int k = 16; k > 1; k--) s = s * r + 1.0 / k;
        return s * r * r;
    }
    return -log1p(-r) - r;
}

/* contact_law.normal_force with w = 1: the force, the tangent and the energy */
static void normal_force(double delta, double kn0, double dmax, double rcap, double *f,
                         double *kt, double *en) {
    if (delta < 0.0) { *f = 0.0; *kt = 0.0; *en = 0.0; return; }
    double rc = rcap, dc = rc * dmax, t, k, e;
    if (delta <= dc) {
        double r = delta / dmax, g = 1.0 - r;
        t = kn0 * delta / g;
        k = kn0 / (g * g);
        e = kn0 * dmax * dmax * phi_hyper(r);
    } else {
        double g = 1.0 - rc, tc = kn0 * dc / g;
        k = kn0 / (g * g);
        double e0 = kn0 * dmax * dmax * phi_hyper(rc), dd = delta - dc;
        t = tc + k * dd;
        e = e0 + tc * dd + 0.5 * k * dd * dd;
    }
    *f = -1.0 * t;
    *kt = 1.0 * k;
    *en = 1.0 * e;
}

/* contact_law.shear_update */
static void shear_update(double us, double dus, double w, double ks, double mu, double fn,
                         double *us_new, double *fs, double *diss) {
    double kw = ks * w, trial = us + dus, f = kw * trial, lim = mu * fabs(fn);
    if (fabs(f) <= lim) { *us_new = trial; *fs = f; *diss = 0.0; return; }
    *us_new = kw > 0.0 ? copysign(lim / kw, trial) : 0.0;
    *fs = copysign(lim, trial);
    *diss = lim * fabs(trial - *us_new);
}

/* contact_law.effective_mass and damped_traction */
static double effective_mass(double m1, double m2) {
    if (m2 <= 0.0 || !isfinite(m2)) return m1;
    return m1 * m2 / (m1 + m2);
}

static double damped_traction(double tn, double kt, double rate, double meff, double length,
                              double gn, double zeta) {
    if (zeta <= 0.0 || gn <= 0.0) return tn;
    return MAX(tn + 2.0 * zeta * sqrt(meff * kt / length) / gn * rate, 0.0);
}

/* overlap.classify: area and centroid of the clipped polygon (kc vertices, fanned from the
   first); returns 0 and leaves them untouched when it has fewer than 3 vertices or no area */
static int polygon_area(const double *px, const double *py, int kc, double *area, double *cx,
                        double *cy) {
    double a2 = 0.0, sx = 0.0, sy = 0.0;
    for (int i = 1; i < kc - 1; i++) {
        double ux = px[i] - px[0], uy = py[i] - py[0];
        double vx = px[i + 1] - px[0], vy = py[i + 1] - py[0];
        double cr = ux * vy - uy * vx;
        a2 += cr; sx += cr * (ux + vx); sy += cr * (uy + vy);
    }
    if (kc >= 3 && a2 != 0.0) {
        *area = 0.5 * a2;
        *cx = px[0] + sx / (3.0 * a2);
        *cy = py[0] + sy / (3.0 * a2);
        return 1;
    }
    return 0;
}

/* The sliver test's scale: the larger side of element a's box, squared */
static double box_extent2(const double xa[4][2]) {
    double ex = MAX(MAX(MAX(xa[0][0], xa[1][0]), xa[2][0]), xa[3][0])
        - MIN(MIN(MIN(xa[0][0], xa[1][0]), xa[2][0]), xa[3][0]);
    double ey = MAX(MAX(MAX(xa[0][1], xa[1][1]), xa[2][1]), xa[3][1])
        - MIN(MIN(MIN(xa[0][1], xa[1][1]), xa[2][1]), xa[3][1]);
    double ee = MAX(ex, ey);
    return ee * ee;
}

static int key_less(int64_t h0, int64_t h1, int64_t h2, int64_t h3, int64_t k0, int64_t k1,
                    int64_t k2, int64_t k3) {
    if (h0 != k0) return h0 < k0;
    if (h1 != k1) return h1 < k1;
    if (h2 != k2) return h2 < k2;
    return h3 < k3;
}

int64_t contact_pass_c(const double *x, const double *du, const double *m, const int64_t *conn,
                       const int8_t *ebnd, const int64_t *egid, const int64_t *eloc,
                       const double *elen, const int32_t *emat, const double *law, int64_t nmat,
                       const double *wall_p0, const double *wall_n, const double *wall_mu,
                       const int64_t *cand, int64_t nc, const int64_t *hkey, const double *hval,
                       int64_t nh, double dt, int64_t ne, double *bbox, int64_t rows,
                       int8_t *active, int64_t *keys, int64_t *elems, int64_t *nodes,
                       double *weights, double *fnod, double *us_out, double *res,
                       int64_t *nbad_out, int64_t *nev_out, int64_t *unsupported) {
    double px[2][MAXV], py[2][MAXV], xa[4][2], xb[4][2], g[8][2], wgt[8];
    int64_t kind[2][MAXV], srct[2][MAXV], nod[8];
    int64_t last = rows - 1, q = 0, h = 0, nbad = 0, nev = 0, held = -1;
    *unsupported = 0;
    /* Every element's box (broad_phase.element_bboxes) */
    for (int64_t e = 0; e < ne; e++) {
        const int64_t *ce = conn + 4 * e;
        double *bb = bbox + 4 * e;
        bb[0] = x[2 * ce[0]]; bb[1] = x[2 * ce[0] + 1];
        bb[2] = x[2 * ce[0]]; bb[3] = x[2 * ce[0] + 1];
        for (int k = 1; k < 4; k++) {
            bb[0] = MIN(bb[0], x[2 * ce[k]]);
            bb[1] = MIN(bb[1], x[2 * ce[k] + 1]);
            bb[2] = MAX(bb[2], x[2 * ce[k]]);
            bb[3] = MAX(bb[3], x[2 * ce[k] + 1]);
        }
    }
    for (int64_t c = 0; c < nc; c++) {
        int64_t a = cand[2 * c], b = cand[2 * c + 1];
        int wall = b < 0;
        int64_t w = -1 - b;
        double wnx = 0.0, wny = 0.0;
        const double *ba = bbox + 4 * a;
        int near;
        /* The broad phase's exact test of this step */
        if (wall) {
            wnx = wall_n[2 * w];
            wny = wall_n[2 * w + 1];
            double lo = MIN(wnx * (ba[0] - wall_p0[2 * w]), wnx * (ba[2] - wall_p0[2 * w]))
                + MIN(wny * (ba[1] - wall_p0[2 * w + 1]), wny * (ba[3] - wall_p0[2 * w + 1]));
            near = lo < 0.0;
        } else {
            const double *bq = bbox + 4 * b;
            near = ba[0] - bq[2] <= 0.0 && bq[0] - ba[2] <= 0.0 && ba[1] - bq[3] <= 0.0
                && bq[1] - ba[3] <= 0.0;
        }
        if (!near) continue;
        nev++;
        if (a != held) {
            for (int k = 0; k < 4; k++) {
                xa[k][0] = x[2 * conn[4 * a + k]];
                xa[k][1] = x[2 * conn[4 * a + k] + 1];
            }
            held = a;
        }
        if (!wall)
            for (int k = 0; k < 4; k++) {
                xb[k][0] = x[2 * conn[4 * b + k]];
                xb[k][1] = x[2 * conn[4 * b + k] + 1];
            }
        /* Key and shear history */
        int64_t key0 = egid[a], key1 = eloc[a], key2 = wall ? b : egid[b], key3 = wall ? 0 : eloc[b];
        while (h < nh && key_less(hkey[4 * h], hkey[4 * h + 1], hkey[4 * h + 2], hkey[4 * h + 3],
                                  key0, key1, key2, key3))
            h++;
        double us = (h < nh && !key_less(key0, key1, key2, key3, hkey[4 * h], hkey[4 * h + 1],
                                         hkey[4 * h + 2], hkey[4 * h + 3])) ? hval[h] : 0.0;
        int64_t r = MIN(q, last);
        int st = OV_OK, kc = 4;
        double area = 0.0, cx = 0.0, cy = 0.0, nx = 0.0, ny = 0.0, width = 0.0, length;
        for (int k = 0; k < 8; k++) { g[k][0] = 0.0; g[k][1] = 0.0; }
        if (wall) {
            /* One Sutherland-Hodgman step against the wall line (overlap.halfplane_overlap) */
            length = elen[a];
            double x0 = wall_p0[2 * w], y0 = wall_p0[2 * w + 1];
            int64_t k = 0;
            int js = 3;
            double ss = wnx * (xa[js][0] - x0) + wny * (xa[js][1] - y0);
            for (int je = 0; je < 4; je++) {
                double se = wnx * (xa[je][0] - x0) + wny * (xa[je][1] - y0);
                int64_t src = js;
                if (se <= 0.0) {
                    if (ss > 0.0) {
                        double t = ss / (ss - se);
                        px[0][k] = xa[js][0] + t * (xa[je][0] - xa[js][0]);
                        py[0][k] = xa[js][1] + t * (xa[je][1] - xa[js][1]);
                        kind[0][k] = K_X; srct[0][k] = src; k++;
                    }
                    px[0][k] = xa[je][0]; py[0][k] = xa[je][1];
                    kind[0][k] = K_P; srct[0][k] = je; k++;
                } else if (ss <= 0.0) {
                    double t = ss / (ss - se);
                    px[0][k] = xa[js][0] + t * (xa[je][0] - xa[js][0]);
                    py[0][k] = xa[js][1] + t * (xa[je][1] - xa[js][1]);
                    kind[0][k] = K_X; srct[0][k] = -1; k++;
                }
                js = je;
                ss = se;
            }
            kc = (int)k;
            /* overlap.classify: area, sliver, crossing chord */
            if (!polygon_area(px[0], py[0], kc, &area, &cx, &cy) && kc >= 3) {
                cx = px[0][0];
                cy = py[0][0];
            }
            if (area <= SLIVER * box_extent2(xa)) {
                st = OV_NONE;
            } else {
                int ncr = 0;
                double best = -1.0, c1x = 0.0, c1y = 0.0, c2x = 0.0, c2y = 0.0;
                for (int i = 0; i < kc; i++) {
                    if (kind[0][i] != K_X) continue;
                    ncr++;
                    for (int j = i + 1; j < kc; j++) {
                        if (kind[0][j] != K_X) continue;
                        double dx = px[0][j] - px[0][i], dy = py[0][j] - py[0][i];
                        double d2 = dx * dx + dy * dy;
                        if (d2 > best) {
                            best = d2;
                            c1x = px[0][i]; c1y = py[0][i]; c2x = px[0][j]; c2y = py[0][j];
                        }
                    }
                }
                if (ncr < 2 || (c1x == c2x && c1y == c2y)) st = OV_INSIDE;
            }
            nx = -wnx;
            ny = -wny;
            if (st == OV_OK) {
                /* contact_frame.polygon_frame without B, and the width */
                for (int i = 0; i < kc; i++) {
                    int i1 = i + 1 < kc ? i + 1 : 0;
                    int64_t src = srct[0][i];
                    if (src < 0) continue;
                    double ex2 = py[0][i1] - py[0][i], ey2 = px[0][i] - px[0][i1];
                    double mx = 0.5 * (px[0][i] + px[0][i1]), my = 0.5 * (py[0][i] + py[0][i1]);
                    int j = (int)src, j1 = j + 1 < 4 ? j + 1 : 0;
                    double dx = xa[j1][0] - xa[j][0], dy = xa[j1][1] - xa[j][1];
                    double f = ((mx - xa[j][0]) * dx + (my - xa[j][1]) * dy) / (dx * dx + dy * dy);
                    f = MIN(MAX(f, 0.0), 1.0);
                    g[j][0] += (1.0 - f) * ex2; g[j][1] += (1.0 - f) * ey2;
                    g[j1][0] += f * ex2; g[j1][1] += f * ey2;
                }
                double lo = 0.0, hi = 0.0;
                for (int i = 0; i < kc; i++) {
                    double f = (px[0][i] - px[0][0]) * -ny + (py[0][i] - py[0][0]) * nx;
                    lo = MIN(lo, f);
                    hi = MAX(hi, f);
                }
                width = hi - lo;
            }
        } else {
            length = MIN(elen[a], elen[b]);
            for (int k = 0; k < 4; k++) {
                int k1 = k + 1 < 4 ? k + 1 : 0, k2 = k1 + 1 < 4 ? k1 + 1 : 0;
                double cr = (xb[k1][0] - xb[k][0]) * (xb[k2][1] - xb[k1][1])
                    - (xb[k1][1] - xb[k][1]) * (xb[k2][0] - xb[k1][0]);
                if (!(cr > 0.0)) { st = -1; break; }
            }
            if (st == -1) { (*unsupported)++; continue; }
            /* Early out: A wholly outside an edge line of B */
            for (int j = 0; j < 4 && st == OV_OK; j++) {
                int j1 = (j + 1) % 4;
                double lx = xb[j1][1] - xb[j][1], ly = xb[j][0] - xb[j1][0];
                int out = 1;
                for (int i = 0; i < 4; i++)
                    if (lx * (xa[i][0] - xb[j][0]) + ly * (xa[i][1] - xb[j][1]) <= 0.0) {
                        out = 0;
                        break;
                    }
                if (out) st = OV_NONE;
            }
            if (st == OV_OK) {
                /* A clipped by B's four edge lines */
                for (int i = 0; i < 4; i++) {
                    px[0][i] = xa[i][0]; py[0][i] = xa[i][1];
                    kind[0][i] = K_P; srct[0][i] = i;
                }
                int sl = 0;
                for (int j = 0; j < 4; j++) {
                    int j1 = j + 1 < 4 ? j + 1 : 0, d = 1 - sl;
                    double lx = xb[j1][1] - xb[j][1], ly = xb[j][0] - xb[j1][0];
                    double x0 = xb[j][0], y0 = xb[j][1];
                    int kn = 0, js = kc - 1;
                    double ss = lx * (px[sl][js] - x0) + ly * (py[sl][js] - y0);
                    for (int je = 0; je < kc; je++) {
                        double se = lx * (px[sl][je] - x0) + ly * (py[sl][je] - y0);
                        int64_t src = srct[sl][js];
                        int64_t kd = src >= 0 ? K_X : K_Q;
                        if (se <= 0.0) {
                            if (ss > 0.0) {
                                if (kn >= MAXV) { kn = -1; break; }
                                double t = ss / (ss - se);
                                px[d][kn] = px[sl][js] + t * (px[sl][je] - px[sl][js]);
                                py[d][kn] = py[sl][js] + t * (py[sl][je] - py[sl][js]);
                                kind[d][kn] = kd; srct[d][kn] = src; kn++;
                            }
                            if (kn >= MAXV) { kn = -1; break; }
                            px[d][kn] = px[sl][je]; py[d][kn] = py[sl][je];
                            kind[d][kn] = kind[sl][je]; srct[d][kn] = srct[sl][je]; kn++;
                        } else if (ss <= 0.0) {
                            if (kn >= MAXV) { kn = -1; break; }
                            double t = ss / (ss - se);
                            px[d][kn] = px[sl][js] + t * (px[sl][je] - px[sl][js]);
                            py[d][kn] = py[sl][js] + t * (py[sl][je] - py[sl][js]);
                            kind[d][kn] = kd; srct[d][kn] = -1 - j; kn++;
                        }
                        js = je;
                        ss = se;
                    }
                    kc = kn;
                    sl = d;
                    if (kc <= 0) break;
                }
                if (kc < 0) {
                    st = OV_OVERFLOW;
                } else {
                    polygon_area(px[0], py[0], kc, &area, &cx, &cy);
                    if (area <= SLIVER * box_extent2(xa)) {
                        st = OV_NONE;
                    } else {
                        int first = -1, two = 0;
                        for (int i = 0; i < kc; i++) {
                            if (kind[0][i] != K_X) continue;
                            if (first < 0) first = i;
                            else if (px[0][i] != px[0][first] || py[0][i] != py[0][first]) {
                                two = 1;
                                break;
                            }
                        }
                        if (!two) st = OV_INSIDE;
                    }
                }
            }
            if (st == OV_OK) {
                /* Area gradient and normal sums, the unit normal, the width */
                double n0 = 0.0, n1 = 0.0, s0 = 0.0, s1 = 0.0;
                for (int i = 0; i < kc; i++) {
                    int i1 = i + 1 < kc ? i + 1 : 0, r0, r1;
                    int64_t src = srct[0][i];
                    double ex = py[0][i1] - py[0][i], ey = px[0][i] - px[0][i1];
                    double mx = 0.5 * (px[0][i] + px[0][i1]), my = 0.5 * (py[0][i] + py[0][i1]);
                    double f;
                    if (src >= 0) {
                        s0 += ex; s1 += ey;
                        if (ebnd[4 * a + src] != 0) { n0 += ex; n1 += ey; }
                        int j = (int)src, j1 = j + 1 < 4 ? j + 1 : 0;
                        double dx = xa[j1][0] - xa[j][0], dy = xa[j1][1] - xa[j][1];
                        f = ((mx - xa[j][0]) * dx + (my - xa[j][1]) * dy) / (dx * dx + dy * dy);
                        r0 = j; r1 = j1;
                    } else {
                        int j = (int)(-1 - src), j1 = j + 1 < 4 ? j + 1 : 0;
                        if (ebnd[4 * b + j] != 0) { n0 -= ex; n1 -= ey; }
                        double dx = xb[j1][0] - xb[j][0], dy = xb[j1][1] - xb[j][1];
                        f = ((mx - xb[j][0]) * dx + (my - xb[j][1]) * dy) / (dx * dx + dy * dy);
                        r0 = 4 + j; r1 = 4 + j1;
                    }
                    f = MIN(MAX(f, 0.0), 1.0);
                    g[r0][0] += (1.0 - f) * ex; g[r0][1] += (1.0 - f) * ey;
                    g[r1][0] += f * ex; g[r1][1] += f * ey;
                }
                nx = n0; ny = n1;
                if (nx * s0 + ny * s1 <= 0.0) { nx = s0; ny = s1; }
                double rr = sqrt(nx * nx + ny * ny);
                if (rr == 0.0) { nx = 0.0; ny = 0.0; }
                else { nx = nx / rr; ny = ny / rr; }
                double lo = 0.0, hi = 0.0;
                for (int i = 0; i < kc; i++) {
                    double f = (px[0][i] - px[0][0]) * -ny + (py[0][i] - py[0][0]) * nx;
                    lo = MIN(lo, f);
                    hi = MAX(hi, f);
                }
                width = hi - lo;
            }
        }
        if (st == OV_NONE) continue;
        /* Nearest boundary edges, guards */
        int ka = -1, kb = -1, code;
        double sa = 0.0, sb = 0.0;
        if (st != OV_OK) {
            code = st == OV_OVERFLOW ? C_OVERFLOW : C_INSIDE;
        } else {
            double best = INFINITY;
            for (int k = 0; k < 4; k++) {
                if (ebnd[4 * a + k] == 0) continue;
                int k1 = (k + 1) % 4;
                double dx = xa[k1][0] - xa[k][0], dy = xa[k1][1] - xa[k][1];
                double f = ((cx - xa[k][0]) * dx + (cy - xa[k][1]) * dy) / (dx * dx + dy * dy);
                f = MIN(MAX(f, 0.0), 1.0);
                double rx = xa[k][0] + f * dx - cx, ry = xa[k][1] + f * dy - cy;
                double d2 = rx * rx + ry * ry;
                if (d2 < best) { best = d2; ka = k; sa = f; }
            }
            best = INFINITY;
            for (int k = 0; k < (wall ? 0 : 4); k++) {
                if (ebnd[4 * b + k] == 0) continue;
                int k1 = (k + 1) % 4;
                double dx = xb[k1][0] - xb[k][0], dy = xb[k1][1] - xb[k][1];
                double f = ((cx - xb[k][0]) * dx + (cy - xb[k][1]) * dy) / (dx * dx + dy * dy);
                f = MIN(MAX(f, 0.0), 1.0);
                double rx = xb[k][0] + f * dx - cx, ry = xb[k][1] + f * dy - cy;
                double d2 = rx * rx + ry * ry;
                if (d2 < best) { best = d2; kb = k; sb = f; }
            }
            if (wall) {
                code = (ka < 0 || !(length > 0.0)) ? C_NOEDGE : C_ACTIVE;
            } else {
                code = C_ACTIVE;
                if ((nx == 0.0 && ny == 0.0) || ka < 0 || kb < 0 || !(length > 0.0))
                    code = (ka >= 0 && kb >= 0 && length > 0.0) ? C_NONORMAL : C_NOEDGE;
            }
        }
        keys[4 * r] = key0; keys[4 * r + 1] = key1; keys[4 * r + 2] = key2; keys[4 * r + 3] = key3;
        elems[2 * r] = a;
        elems[2 * r + 1] = wall ? -1 : b;
        q++;
        if (code != C_ACTIVE) {
            nbad++;
            active[r] = (int8_t)code;
            for (int k = 0; k < 8; k++) {
                nodes[8 * r + k] = -1; weights[8 * r + k] = 0.0;
                fnod[16 * r + 2 * k] = 0.0; fnod[16 * r + 2 * k + 1] = 0.0;
            }
            us_out[r] = us;
            for (int k = 0; k < NRES; k++) res[NRES * r + k] = 0.0;
            continue;
        }
        for (int k = 0; k < 4; k++) {
            nod[k] = conn[4 * a + k];
            nod[4 + k] = wall ? -1 : conn[4 * b + k];
            wgt[k] = 0.0;
            wgt[4 + k] = 0.0;
        }
        wgt[ka] = 1.0 - sa;
        wgt[(ka + 1) % 4] = sa;
        if (!wall) {
            wgt[4 + kb] = 1.0 - sb;
            wgt[4 + (kb + 1) % 4] = sb;
        }
        double gax = 0.0, gay = 0.0, ma = INFINITY, mb = INFINITY;
        for (int k = 0; k < 4; k++) {
            gax += g[k][0];
            gay += g[k][1];
            if (g[k][0] != 0.0 || g[k][1] != 0.0) ma = MIN(ma, m[nod[k]]);
            if (nod[4 + k] >= 0 && (g[4 + k][0] != 0.0 || g[4 + k][1] != 0.0))
                mb = MIN(mb, m[nod[4 + k]]);
        }
        double meff = wall ? ma : effective_mass(ma, mb);
        /* The law */
        int64_t lr = (int64_t)emat[a] * nmat + (wall ? emat[a] : emat[b]);
        const double *p = law + NPAR * lr;
        double kn0 = p[P_KN0], ks = p[P_KS], mu = wall ? wall_mu[w] : p[P_MU];
        double delta = area / length, mt, kt, ed;
        normal_force(delta, kn0, p[P_DMAX], p[P_RCAP], &mt, &kt, &ed);
        double tn = -mt, da = 0.0, rux = 0.0, ruy = 0.0;
        for (int k = 0; k < 8; k++) {
            int64_t nd = nod[k];
            if (nd < 0) continue;
            da += g[k][0] * du[2 * nd] + g[k][1] * du[2 * nd + 1];
            double sg = k >= 4 ? 1.0 : -1.0;
            rux += sg * wgt[k] * du[2 * nd];
            ruy += sg * wgt[k] * du[2 * nd + 1];
        }
        double t = tn;
        if (dt > 0.0)
            t = damped_traction(tn, kt, da / dt, meff, length, sqrt(gax * gax + gay * gay),
                                p[P_ZETA]);
        double fn = -t * MAX(gax * nx + gay * ny, 0.0), tx = -ny, ty = nx;
        double us_new, fs, diss;
        shear_update(us, rux * tx + ruy * ty, length, ks, mu, fn, &us_new, &fs, &diss);
        for (int k = 0; k < 8; k++) {
            double sgs = k < 4 ? fs : -fs;
            nodes[8 * r + k] = nod[k];
            weights[8 * r + k] = wgt[k];
            fnod[16 * r + 2 * k] = -t * g[k][0] + sgs * wgt[k] * tx;
            fnod[16 * r + 2 * k + 1] = -t * g[k][1] + sgs * wgt[k] * ty;
        }
        double *rs = res + NRES * r;
        active[r] = C_ACTIVE;
        us_out[r] = us_new;
        rs[R_FN] = fn; rs[R_FS] = fs;
        rs[R_ENERGY] = length * ed + 0.5 * ks * length * us_new * us_new;
        rs[R_DISS] = diss; rs[R_STIFF] = kt; rs[R_DELTA] = delta; rs[R_WIDTH] = width;
        rs[R_NX] = 1.0 * nx; rs[R_NY] = 1.0 * ny; rs[R_CX] = cx; rs[R_CY] = cy;
        rs[R_DAMP] = (t - tn) * da; rs[R_LEN] = length; rs[R_KSL] = ks * length;
        rs[R_MEFF] = meff; rs[R_AREA] = area;
    }
    *nbad_out = nbad;
    *nev_out = nev;
    return q;
}
