/* SPDX-License-Identifier: BSD-3-Clause */
/* Range/bearing geometry and its uncertainty: analytic Jacobians against central differences,
 * first-order covariance against Monte Carlo over all 15 inputs, horizon handling, the error
 * budget, and the paper's Tables 6 and 8 reproduced with its Table 4/5 camera. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <string.h>
#include <math.h>
#include <cmocka.h>

#include "cyl/rangebearing.h"
#include "rng.h"
#include "unc_paper.h"

#define NIN CYL_IN_COUNT

/* central-difference steps per input */
static const double STEP[NIN] = {1e-2, 1e-2, 1e-1, 1e-1, 1e-1, 1e-1, 1e-3, 1e-2, 1e-5, 1e-5, 1e-2,
                                 1e-4, 1e-4, 1e-4, 1e-4};

static void pixel_of(const cyl_camera *cam, double x, double y, double *u, double *v)
{
    assert_int_equal(cyl_rb_project(cam, x, y, u, v), CYL_OK);
}

/* max relative error of jac (and jac_xy) vs central differences at one input vector */
static double jac_check(const double in[NIN], cyl_geom_model model)
{
    double out[2], xy[2], jac[2][NIN], jxy[2][NIN], worst = 0;
    int k, r;
    assert_int_equal(cyl_rb_eval(in, model, out, xy, jac, jxy), CYL_OK);
    for (k = 0; k < NIN; k++) {
        /* five-point central difference: (8 (f(h) - f(-h)) - (f(2h) - f(-2h))) / 12h */
        double o[4][2], x[4][2], n, nx;
        static const double mult[4] = {1, -1, 2, -2};
        int q;
        for (q = 0; q < 4; q++) {
            double ip[NIN];
            memcpy(ip, in, sizeof ip);
            ip[k] += mult[q] * STEP[k];
            assert_int_equal(cyl_rb_eval(ip, model, o[q], x[q], NULL, NULL), CYL_OK);
        }
        for (r = 0; r < 2; r++) {
            double e, ex;
            n = (8 * (o[0][r] - o[1][r]) - (o[2][r] - o[3][r])) / (12 * STEP[k]);
            nx = (8 * (x[0][r] - x[1][r]) - (x[2][r] - x[3][r])) / (12 * STEP[k]);
            /* well conditioned: relative to the derivative itself, floored at 1e-7 output
             * units per input unit (smaller entries are zero or below CD's resolution) */
            e = fabs(jac[r][k] - n) / fmax(fabs(n), 1e-7);
            ex = fabs(jxy[r][k] - nx) / fmax(fabs(nx), 1e-7);
            if (e > worst) worst = e;
            if (ex > worst) worst = ex;
            if (e > 1e-6 || ex > 1e-6) print_message("k=%d r=%d model=%d: %.6g vs %.6g; xy %.6g vs %.6g\n", k, r, (int)model, jac[r][k], n, jxy[r][k], nx);
        }
    }
    return worst;
}

static void test_jacobians(void **st)
{
    cyl_camera cam;
    double worst[2] = {0, 0};
    int m, i, j;
    (void)st;
    unc_distorted_camera(&cam);
    cam.yaw_rad = 3.0 * UNC_DEG;
    cam.tilt_rad = 6.0 * UNC_DEG;
    for (m = 0; m < 2; m++)
        for (i = 0; i < 6; i++)
            for (j = -3; j <= 3; j++) {
                double range = 0.8 + 0.5 * i, bearing = j * 7.0 * UNC_DEG, in[NIN], u, v, e;
                pixel_of(&cam, range * cos(bearing), range * sin(bearing), &u, &v);
                cyl_rb_inputs(&cam, u, v, in);
                e = jac_check(in, (cyl_geom_model)m);
                if (e > worst[m]) worst[m] = e;
            }
    print_message("analytic vs central-difference Jacobians (15 inputs, range/bearing and x/y): "
                  "exact %.3g, paper %.3g\n", worst[0], worst[1]);
    assert_true(worst[0] < 1e-6);
    assert_true(worst[1] < 1e-6);
}

/* identities: with x_n = 0 the two models coincide; the inverse projection round-trips */
static void test_models_agree_on_axis_and_round_trip(void **st)
{
    cyl_camera cam;
    double y, worst = 0;
    (void)st;
    unc_paper_camera(&cam);
    for (y = 0.1; y < 0.9; y += 0.05) {
        double in[NIN], a[2], b[2];
        cyl_rb_inputs(&cam, cam.cx_px, cam.cy_px + y * cam.fy_px, in);
        assert_int_equal(cyl_rb_eval(in, CYL_GEOM_EXACT, a, NULL, NULL, NULL), CYL_OK);
        assert_int_equal(cyl_rb_eval(in, CYL_GEOM_PAPER, b, NULL, NULL, NULL), CYL_OK);
        assert_true(fabs(a[0] - b[0]) < 1e-12 * a[0]);
        assert_true(fabs(a[1]) < 1e-15 && fabs(b[1]) < 1e-15);
    }
    unc_distorted_camera(&cam);
    cam.yaw_rad = -4 * UNC_DEG;
    for (y = -1.0; y <= 1.0; y += 0.25) {
        double x;
        for (x = 0.6; x < 4.0; x += 0.4) {
            double u, v;
            cyl_rb_result r;
            pixel_of(&cam, x, y, &u, &v);
            if (u < 0 || v < 0 || u > 767 || v > 575) continue;
            assert_int_equal(cyl_range_bearing(&cam, CYL_GEOM_EXACT, u, v, 0.02, 0.02, 0, &r), CYL_OK);
            worst = fmax(worst, fmax(fabs(r.x_m - x), fabs(r.y_m - y)));
            assert_true(fabs(r.range_m - hypot(x, y)) < 1e-9);
        }
    }
    print_message("project -> range_bearing round trip: max %.3g m\n", worst);
    assert_true(worst < 1e-9);
}

/* x = r cos b, y = r sin b: cov_xy = G cov_rb G^T to first order */
static void test_cov_xy_consistent(void **st)
{
    cyl_camera cam;
    cyl_rb_result r;
    double u, v, G[2][2], C[2][2];
    int a, b;
    (void)st;
    unc_distorted_camera(&cam);
    pixel_of(&cam, 1.3, 0.4, &u, &v);
    assert_int_equal(cyl_range_bearing(&cam, CYL_GEOM_EXACT, u, v, 0.03, 0.05, 0.01, &r), CYL_OK);
    G[0][0] = cos(r.bearing_rad); G[0][1] = -r.range_m * sin(r.bearing_rad);
    G[1][0] = sin(r.bearing_rad); G[1][1] = r.range_m * cos(r.bearing_rad);
    for (a = 0; a < 2; a++)
        for (b = 0; b < 2; b++) {
            int p, q;
            C[a][b] = 0;
            for (p = 0; p < 2; p++)
                for (q = 0; q < 2; q++) C[a][b] += G[a][p] * r.cov_rb[p][q] * G[b][q];
            assert_true(fabs(C[a][b] - r.cov_xy[a][b]) < 1e-12 * (r.cov_xy[0][0] + r.cov_xy[1][1]));
        }
    assert_true(r.cov_rb[0][1] == r.cov_rb[1][0]);
    assert_true(fabs(r.cov_rb[0][1]) > 0.0);   /* the cross term the paper leaves out */
}

/* ---- Monte Carlo ----------------------------------------------------------- */

/* lower Cholesky factor of a PSD matrix; zero pivots give zero columns */
static void cholesky(const double A[NIN][NIN], double L[NIN][NIN])
{
    int i, j, k;
    memset(L, 0, sizeof(double) * NIN * NIN);
    for (j = 0; j < NIN; j++) {
        double d = A[j][j];
        for (k = 0; k < j; k++) d -= L[j][k] * L[j][k];
        if (d <= 1e-300) continue;
        L[j][j] = sqrt(d);
        for (i = j + 1; i < NIN; i++) {
            double s = A[i][j];
            for (k = 0; k < j; k++) s -= L[i][k] * L[j][k];
            L[i][j] = s / L[j][j];
        }
    }
}

typedef struct mc_result {
    double err_rr, err_bb, err_rb;   /* relative errors of var_r, var_b, and cross / sqrt(var_r var_b) */
    double sigma_rel;                /* sigma_r / r */
    double depression_deg;           /* ray depression below horizontal */
} mc_result;

static void monte_carlo(const cyl_camera *cam, double u, double v, double var_u, double var_v,
                        int n, test_rng *rng, mc_result *res)
{
    double in0[NIN], S[NIN][NIN], L[NIN][NIN], o0[2], s_r = 0, s_b = 0, s_rr = 0, s_bb = 0, s_rb = 0;
    cyl_rb_result lin;
    int t, i, k, used = 0;
    cyl_rb_inputs(cam, u, v, in0);
    cyl_rb_input_cov(cam, var_u, var_v, 0.0, S);
    cholesky(S, L);
    assert_int_equal(cyl_range_bearing(cam, CYL_GEOM_EXACT, u, v, var_u, var_v, 0.0, &lin), CYL_OK);
    assert_int_equal(cyl_rb_eval(in0, CYL_GEOM_EXACT, o0, NULL, NULL, NULL), CYL_OK);
    for (t = 0; t < n; t++) {
        double z[NIN], in[NIN], o[2], dr, db;
        for (k = 0; k < NIN; k++) z[k] = test_rng_normal(rng);
        for (i = 0; i < NIN; i++) {
            in[i] = in0[i];
            for (k = 0; k <= i; k++) in[i] += L[i][k] * z[k];
        }
        if (cyl_rb_eval(in, CYL_GEOM_EXACT, o, NULL, NULL, NULL) != CYL_OK) continue;
        dr = o[0] - o0[0];
        db = o[1] - o0[1];
        s_r += dr; s_b += db; s_rr += dr * dr; s_bb += db * db; s_rb += dr * db;
        used++;
    }
    {
        double m = used, vr = (s_rr - s_r * s_r / m) / (m - 1), vb = (s_bb - s_b * s_b / m) / (m - 1);
        double cb = (s_rb - s_r * s_b / m) / (m - 1);
        res->err_rr = fabs(vr - lin.cov_rb[0][0]) / lin.cov_rb[0][0];
        res->err_bb = fabs(vb - lin.cov_rb[1][1]) / lin.cov_rb[1][1];
        res->err_rb = fabs(cb - lin.cov_rb[0][1]) / sqrt(lin.cov_rb[0][0] * lin.cov_rb[1][1]);
        res->sigma_rel = sqrt(lin.cov_rb[0][0]) / lin.range_m;
        res->depression_deg = atan2(cam->height_m, lin.range_cam_m) / UNC_DEG;
    }
    assert_true(used > n - n / 1000);
}

/* All 15 inputs sampled (paper camera + distortion with sigmas + a correlated fx-cx pair),
 * 100,000 samples per point: sample covariance within 3% of J S J^T at realistic ranges. */
static void test_monte_carlo(void **st)
{
    static const double pts[][2] = {{1.17, 0}, {1.36, 13.2}, {1.62, -8.0}, {1.83, 11.4}, {1.45, -18.4}};
    cyl_camera cam;
    test_rng rng;
    double worst = 0;
    size_t i;
    (void)st;
    unc_distorted_camera(&cam);
    cam.intr_cov[CYL_INTR_FX][CYL_INTR_CX] = cam.intr_cov[CYL_INTR_CX][CYL_INTR_FX] =
        0.5 * 0.4565 * 0.3216;
    test_rng_seed(&rng, 2024u);
    for (i = 0; i < sizeof pts / sizeof pts[0]; i++) {
        double u, v;
        mc_result r;
        pixel_of(&cam, pts[i][0] * cos(pts[i][1] * UNC_DEG), pts[i][0] * sin(pts[i][1] * UNC_DEG), &u, &v);
        monte_carlo(&cam, u, v, 0.02, 0.02, 100000, &rng, &r);
        print_message("MC  r=%.2f m b=%5.1f deg  depression %5.2f deg  sigma_r/r %.3f: "
                      "var_r %.2f%%  var_b %.2f%%  cov_rb %.2f%%\n", pts[i][0], pts[i][1],
                      r.depression_deg, r.sigma_rel, 100 * r.err_rr, 100 * r.err_bb, 100 * r.err_rb);
        worst = fmax(worst, fmax(r.err_rr, fmax(r.err_bb, r.err_rb)));
    }
    assert_true(worst < 0.03);
}

/* Where linearisation breaks: the same camera, ranges towards the horizon. The relative error of
 * the propagated range variance grows roughly with (sigma_tilt / depression)^2; measured here
 * (documented in docs/uncertainty.md) and required to be visibly large near the horizon, so the
 * CYL_OBS_NONLINEAR threshold rests on a measurement. */
static void test_linearisation_limit(void **st)
{
    static const double ranges[] = {2.0, 2.2, 2.97, 4.0, 6.0, 8.0};
    cyl_camera cam;
    test_rng rng;
    double last = 0;
    size_t i;
    (void)st;
    unc_paper_camera(&cam);
    test_rng_seed(&rng, 77u);
    for (i = 0; i < sizeof ranges / sizeof ranges[0]; i++) {
        double u, v;
        mc_result r;
        pixel_of(&cam, ranges[i], 0.0, &u, &v);
        monte_carlo(&cam, u, v, 0.02, 0.02, 100000, &rng, &r);
        print_message("MC  r=%.2f m  depression %5.2f deg  sigma_r/r %.3f: var_r error %.1f%% "
                      "(= %.1f (sigma_r/r)^2)\n", ranges[i], r.depression_deg, r.sigma_rel,
                      100 * r.err_rr, r.err_rr / (r.sigma_rel * r.sigma_rel));
        last = r.err_rr;
        if (ranges[i] <= 2.0) assert_true(r.err_rr < 0.03);
    }
    assert_true(last > 0.10);
}

static void test_horizon(void **st)
{
    cyl_camera cam;
    double v, prev = 0;
    int m, seen_no_range = 0;
    (void)st;
    unc_distorted_camera(&cam);
    for (m = 0; m < 2; m++) {
        prev = 0;
        for (v = 575; v >= 0; v -= 0.5) {
            cyl_rb_result r;
            cyl_status s = cyl_range_bearing(&cam, (cyl_geom_model)m, 420.0, v, 0.02, 0.02, 0, &r);
            if (s == CYL_ERR_NO_RANGE) {
                seen_no_range++;
                assert_true(r.flags & CYL_RB_NO_RANGE);
                assert_true(r.range_m == 0.0 && r.cov_rb[0][0] == 0.0);
                assert_true(isfinite(r.bearing_rad) && r.cov_rb[1][1] > 0.0);
                continue;
            }
            assert_int_equal(s, CYL_OK);
            assert_true(isfinite(r.range_m) && r.range_m > 0.0);
            assert_true(r.range_m >= prev);   /* monotone up the image */
            prev = r.range_m;
            assert_false(seen_no_range && m == 0 && v < 0);   /* unreachable guard */
        }
    }
    assert_true(seen_no_range > 100);
    /* exactly at the horizon of the exact model: y_n = -tan(tilt), no distortion */
    unc_paper_camera(&cam);
    {
        cyl_rb_result r;
        double vh = cam.cy_px - cam.fy_px * tan(cam.tilt_rad);
        assert_int_equal(cyl_range_bearing(&cam, CYL_GEOM_EXACT, 500.0, vh - 1e-9, 0, 0, 0, &r),
                         CYL_ERR_NO_RANGE);
        assert_int_equal(cyl_range_bearing(&cam, CYL_GEOM_EXACT, 500.0, vh + 1e-3, 0, 0, 0, &r), CYL_OK);
        assert_true(r.range_m > 100.0 && isfinite(r.range_m));
        /* bearing at infinity = camera bearing: -atan2(x_n, cos t - y_n sin t) */
        assert_int_equal(cyl_range_bearing(&cam, CYL_GEOM_EXACT, 500.0, vh - 10, 0, 0, 0, &r),
                         CYL_ERR_NO_RANGE);
        {
            double xn = (500.0 - cam.cx_px) / cam.fx_px, yn = (vh - 10 - cam.cy_px) / cam.fy_px;
            double b = -atan2(xn, cos(cam.tilt_rad) - yn * sin(cam.tilt_rad));
            assert_true(fabs(r.bearing_rad - b) < 1e-14);
        }
    }
}

/* Budget: shares of a diagonal input covariance sum to 1; each sensitivity equals the output
 * variance recomputed through cyl_range_bearing with only that source's variances set to 1. */
static void test_budget(void **st)
{
    cyl_camera cam;
    cyl_error_budget b;
    double u, v, sum_r = 0, sum_b = 0;
    int g;
    (void)st;
    unc_distorted_camera(&cam);
    pixel_of(&cam, 1.36 * cos(13.2 * UNC_DEG), 1.36 * sin(13.2 * UNC_DEG), &u, &v);
    assert_int_equal(cyl_error_budget_at(&cam, CYL_GEOM_EXACT, u, v, 0.02, 0.03, 0, &b), CYL_OK);
    for (g = 0; g < CYL_SRC_COUNT; g++) {
        cyl_camera c = cam;
        cyl_rb_result r;
        double vu = 0, vv = 0;
        int i;
        sum_r += b.share_range[g];
        sum_b += b.share_bearing[g];
        memset(c.intr_cov, 0, sizeof c.intr_cov);
        c.tilt_sigma_rad = c.yaw_sigma_rad = c.height_sigma_m = c.offset_sigma_m = 0;
        switch (g) {
        case CYL_SRC_SEGMENTATION: vu = vv = 1; break;
        case CYL_SRC_PRINCIPAL_POINT: c.intr_cov[2][2] = c.intr_cov[3][3] = 1; break;
        case CYL_SRC_FOCAL: c.intr_cov[0][0] = c.intr_cov[1][1] = 1; break;
        case CYL_SRC_DISTORTION: for (i = 4; i < 9; i++) c.intr_cov[i][i] = 1; break;
        case CYL_SRC_HEIGHT: c.height_sigma_m = 1; break;
        case CYL_SRC_TILT: c.tilt_sigma_rad = 1; break;
        case CYL_SRC_YAW: c.yaw_sigma_rad = 1; break;
        default: c.offset_sigma_m = 1; break;
        }
        assert_int_equal(cyl_range_bearing(&c, CYL_GEOM_EXACT, u, v, vu, vv, 0, &r), CYL_OK);
        assert_true(fabs(r.cov_rb[0][0] - b.sens_range[g]) <= 1e-12 * r.cov_rb[0][0] + 1e-300);
        assert_true(fabs(r.cov_rb[1][1] - b.sens_bearing[g]) <= 1e-12 * r.cov_rb[1][1] + 1e-300);
        assert_true(b.sens_range[g] > 0.0 && b.sens_bearing[g] > 0.0);
    }
    assert_true(fabs(sum_r - 1) < 1e-12 && fabs(sum_b - 1) < 1e-12);
    assert_true(fabs(b.cross_share_range) < 1e-12);
    /* a correlated fx-cx pair: shares no longer sum to one, the remainder is reported */
    cam.intr_cov[0][2] = cam.intr_cov[2][0] = 0.9 * 0.4565 * 0.3216;
    assert_int_equal(cyl_error_budget_at(&cam, CYL_GEOM_EXACT, u, v, 0.02, 0.03, 0, &b), CYL_OK);
    sum_b = 0;
    for (g = 0; g < CYL_SRC_COUNT; g++) sum_b += b.share_bearing[g];
    assert_true(fabs(sum_b + b.cross_share_bearing - 1) < 1e-12);
    assert_true(fabs(b.cross_share_bearing) > 1e-6);
    assert_string_equal(cyl_source_name(CYL_SRC_TILT), "camera tilt");
}

/* The paper reproduced: Table 6 sigma of range (paper's calculated ranges, bearing 0) and
 * Table 8 shares at 1.36 m, 13.2 deg, with the Table 4/5 camera (docs/uncertainty.md). */
static void test_paper_tables(void **st)
{
    static const double rng_m[6] = {2.86, 2.84, 1.92, 1.68, 1.44, 1.19};
    static const double sig_paper[6] = {0.34, 0.33, 0.14, 0.11, 0.079, 0.052};
    cyl_camera cam;
    cyl_error_budget b;
    double lo = 1e9, hi = 0, u, v;
    int i;
    (void)st;
    unc_paper_camera(&cam);
    for (i = 0; i < 6; i++) {
        cyl_rb_result r;
        double ratio;
        pixel_of(&cam, rng_m[i], 0.0, &u, &v);
        assert_int_equal(cyl_range_bearing(&cam, CYL_GEOM_EXACT, u, v, 0.02, 0.02, 0, &r), CYL_OK);
        ratio = sqrt(r.cov_rb[0][0]) / sig_paper[i];
        lo = fmin(lo, ratio);
        hi = fmax(hi, ratio);
    }
    print_message("Table 6: sigma ratio ours/paper %.3f .. %.3f (max/min %.3f)\n", lo, hi, hi / lo);
    assert_true(lo >= 0.6 && hi <= 1.4 && hi / lo <= 1.25);
    pixel_of(&cam, 1.36 * cos(13.2 * UNC_DEG), 1.36 * sin(13.2 * UNC_DEG), &u, &v);
    assert_int_equal(cyl_error_budget_at(&cam, CYL_GEOM_EXACT, u, v, 0.02, 0.02, 0, &b), CYL_OK);
    print_message("Table 8: tilt %.1f%% of range variance, yaw %.1f%% of bearing variance\n",
                  100 * b.share_range[CYL_SRC_TILT], 100 * b.share_bearing[CYL_SRC_YAW]);
    assert_true(b.share_range[CYL_SRC_TILT] >= 0.95);
    assert_true(b.share_bearing[CYL_SRC_YAW] >= 0.90);
}

static void test_errors(void **st)
{
    cyl_camera cam;
    cyl_rb_result r;
    double in[NIN], out[2];
    (void)st;
    unc_paper_camera(&cam);
    assert_int_equal(cyl_range_bearing(NULL, CYL_GEOM_EXACT, 1, 1, 0, 0, 0, &r), CYL_ERR_ARG);
    assert_int_equal(cyl_range_bearing(&cam, CYL_GEOM_EXACT, 1, 400, -1, 0, 0, &r), CYL_ERR_ARG);
    cam.fx_px = -1;
    assert_int_equal(cyl_range_bearing(&cam, CYL_GEOM_EXACT, 1, 400, 0, 0, 0, &r), CYL_ERR_CAMERA);
    unc_paper_camera(&cam);
    cyl_rb_inputs(&cam, 300, 400, in);
    assert_int_equal(cyl_rb_eval(in, (cyl_geom_model)5, out, NULL, NULL, NULL), CYL_ERR_ARG);
    in[CYL_IN_V] = NAN;
    assert_int_equal(cyl_rb_eval(in, CYL_GEOM_EXACT, out, NULL, NULL, NULL), CYL_ERR_NUMERIC);
    /* a point behind the camera cannot be projected */
    assert_int_equal(cyl_rb_project(&cam, -3.0, 0.0, &out[0], &out[1]), CYL_ERR_NO_RANGE);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_jacobians),
        cmocka_unit_test(test_models_agree_on_axis_and_round_trip),
        cmocka_unit_test(test_cov_xy_consistent),
        cmocka_unit_test(test_monte_carlo),
        cmocka_unit_test(test_linearisation_limit),
        cmocka_unit_test(test_horizon),
        cmocka_unit_test(test_budget),
        cmocka_unit_test(test_paper_tables),
        cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
