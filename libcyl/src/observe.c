/* SPDX-License-Identifier: BSD-3-Clause */
/* libcyl -- blobs to observations. */
#include "cyl/config.h"
#include "cyl/observe.h"
#include "cyl/silhouette.h"
#include "unc_internal.h"
#include "internal.h"

#include <math.h>
#include <string.h>

cyl_observe_params cyl_observe_params_default(void)
{
    cyl_observe_params p;
    memset(&p, 0, sizeof p);
    p.estimator = CYL_NOISE_LOCAL;
    p.model = CYL_GEOM_EXACT;
    p.class_mask = 0xFFu;
    p.min_area = 1;
    p.min_var_px2 = 0.0;
    p.nonlinear_rel_sigma = 0.055;
    p.partial_aspect_min = CYL_PARTIAL_ASPECT_MIN_DEFAULT;
    p.partial_area_min = CYL_PARTIAL_AREA_MIN_DEFAULT;
    p.partial_side_max = CYL_PARTIAL_SIDE_MAX_DEFAULT;
    p.partial_offset_max = CYL_PARTIAL_OFFSET_MAX_DEFAULT;
    p.silhouette_rel_sigma = 0.25;
    p.silhouette_sigma_u_px = 0.25;
    p.silhouette_sigma_v_px = 0.25;
    p.group_silhouette_sigma_u_px = 0.25;
    p.group_silhouette_sigma_v_px = 0.25;
    p.image_noise = cyl_noise_image_params_default();
    p.subpixel = 0;
    p.subpixel_params = cyl_subpixel_params_default();
    p.subpixel_rel_sigma = 0.0;
    p.missing_part_share = CYL_MISSING_PART_SHARE_DEFAULT;
    p.side_sigma_rel = CYL_SIDE_SIGMA_REL_DEFAULT;
    p.side_sigma_free = CYL_SIDE_SIGMA_FREE_DEFAULT;
    return p;
}

cyl_observe_params cyl_observe_params_default_frame(void)
{
    cyl_observe_params p = cyl_observe_params_default();
    p.estimator = CYL_NOISE_IMAGE;
    p.subpixel = 1;
    /* what sub-pixel edges leave of the centroid's bias: on the tuning seeds 1-20 of the synthetic
     * scene (cyl-synth-validate --pixel-only --runs 40 --seed N), the values on a 0.025 px grid
     * whose mean NEES of u and of v is nearest 1 */
    p.silhouette_sigma_u_px = 0.05;
    p.silhouette_sigma_v_px = 0.125;
    return p;
}

size_t cyl_observe_work_size(const cyl_segmentation *seg, const cyl_observe_params *p)
{
    if (!p || p->estimator != CYL_NOISE_COLUMN) return 0;
    return cyl_noise_work_size_seg(seg);
}

/* What the silhouette bias is computed for: a single-colour cylinder of a class's size, or the
 * bands in band_mask of a landmark model standing base_z_m above the centroid plane. */
typedef struct shape_ref {
    const cyl_landmark_size *size;
    const cyl_landmark_model *model;
#if CYL_CONFIG_MODELS
    double base_z_m;
    uint32_t band_mask;
#endif
} shape_ref;

/* The silhouette offset's absolute sigmas, px: a grouped landmark's or a single blob's. */
static void abs_sigmas(const cyl_observe_params *p, const shape_ref *sh, double *su, double *sv)
{
    *su = sh->model ? p->group_silhouette_sigma_u_px : p->silhouette_sigma_u_px;
    *sv = sh->model ? p->group_silhouette_sigma_v_px : p->silhouette_sigma_v_px;
}

static cyl_status bias_of(const cyl_camera *cam, const cyl_observe_params *p, const shape_ref *sh, double x_m,
                          double y_m, cyl_silhouette_bias *sb)
{
#if CYL_CONFIG_MODELS
    cyl_status st = sh->model ? cyl_silhouette_bias_model(cam, x_m, y_m, sh->model, sh->base_z_m, sh->band_mask,
                                                          p->silhouette_rel_sigma, 0.0, sb)
                              : cyl_silhouette_bias_at(cam, x_m, y_m, sh->size, p->silhouette_rel_sigma, 0.0, sb);
#else
    cyl_status st = cyl_silhouette_bias_at(cam, x_m, y_m, sh->size, p->silhouette_rel_sigma, 0.0, sb);
#endif
    if (st == CYL_OK) {   /* what is not geometry, per axis */
        double su, sv;
        abs_sigmas(p, sh, &su, &sv);
        sb->var_u_px2 += su * su;
        sb->var_v_px2 += sv * sv;
    }
    return st;
}

/* The silhouette's geometric bias (cyl/silhouette.h) taken out of the measurement point: the
 * offset at the landmark's position, which comes from the point itself, so twice (on the synthetic
 * camera at 0.8-4 m one pass leaves the point up to 0.081 px from the image of the centre, two
 * 0.003 px). The offset's variance is added to the centroid's, and for a single blob so is the
 * sub-pixel edges' shift's (o->subpixel_du_px, dv: a correction too, with subpixel_rel_sigma of
 * itself as its uncertainty). On any failure the uncorrected result stays. */
static void correct_silhouette(cyl_observation *o, const cyl_camera *cam, const cyl_observe_params *p,
                               const shape_ref *sh, cyl_rb_result *rb, double *sil_area_px2)
{
    const double var_cu = o->var_u_px2, var_cv = o->var_v_px2;   /* the centroid's own */
    int it;
    for (it = 0; it < 2; it++) {
        cyl_silhouette_bias sb;
        cyl_rb_result r2;
        double u, v, vu, vv;
        if (bias_of(cam, p, sh, rb->x_m, rb->y_m, &sb) != CYL_OK) return;
        if (!sh->model && p->subpixel_rel_sigma > 0.0) {
            const double su = p->subpixel_rel_sigma * o->subpixel_du_px, sv = p->subpixel_rel_sigma * o->subpixel_dv_px;
            sb.var_u_px2 += su * su;
            sb.var_v_px2 += sv * sv;
        }
        u = o->centroid_u_px - sb.du_px;
        v = o->centroid_v_px - sb.dv_px;
        vu = var_cu + sb.var_u_px2;
        vv = var_cv + sb.var_v_px2;
        if (cyl_rb_compute(cam, p->model, u, v, vu, vv, 0.0, &r2) != CYL_OK) return;
        *rb = r2;
        o->u_px = u;
        o->v_px = v;
        o->var_u_px2 = vu;
        o->var_v_px2 = vv;
        o->bias_u_px = sb.du_px;
        o->bias_v_px = sb.dv_px;
        o->bias_var_u_px2 = sb.var_u_px2;
        o->bias_var_v_px2 = sb.var_v_px2;
        *sil_area_px2 = sb.area_px2;
    }
}

static const int calib_in[CYL_CALIB_COUNT] = {CYL_IN_FX, CYL_IN_FY, CYL_IN_CX, CYL_IN_CY,
                                              CYL_IN_TILT, CYL_IN_YAW, CYL_IN_H, CYL_IN_S};

void cyl_calib_cov(const cyl_camera *cam, double cov[CYL_CALIB_COUNT][CYL_CALIB_COUNT])
{
    int i, j;
    const double sg[4] = {cam->tilt_sigma_rad, cam->yaw_sigma_rad, cam->height_sigma_m, cam->offset_sigma_m};
    for (i = 0; i < CYL_CALIB_COUNT; i++)
        for (j = 0; j < CYL_CALIB_COUNT; j++)
            cov[i][j] = (i < 4 && j < 4) ? cam->intr_cov[i][j] : (i == j ? sg[i - 4] * sg[i - 4] : 0.0);
}

/* jac_calib and cov_rb_frame: J S' J^T over the inputs that remain once the calibration's rows
 * and columns are removed -- the centroid (u, v; var_u, var_v, independent) and the distortion
 * terms (their block of the intrinsic covariance; usually zero, then skipped). */
static void calib_share(cyl_observation *o, const cyl_camera *cam, const cyl_rb_result *rb)
{
    int a, c, k, m;
    for (a = 0; a < 2; a++)
        for (k = 0; k < CYL_CALIB_COUNT; k++) o->jac_calib[a][k] = rb->jac[a][calib_in[k]];
    for (a = 0; a < 2; a++)
        for (c = 0; c < 2; c++) {
            double acc = rb->jac[a][CYL_IN_U] * o->var_u_px2 * rb->jac[c][CYL_IN_U] +
                         rb->jac[a][CYL_IN_V] * o->var_v_px2 * rb->jac[c][CYL_IN_V];
            for (k = CYL_INTR_K1; k <= CYL_INTR_K3; k++)
                for (m = CYL_INTR_K1; m <= CYL_INTR_K3; m++)
                    if (cam->intr_cov[k][m] != 0.0)
                        acc += rb->jac[a][CYL_IN_K1 + k - CYL_INTR_K1] * cam->intr_cov[k][m] *
                               rb->jac[c][CYL_IN_K1 + m - CYL_INTR_K1];
            o->cov_rb_frame[a][c] = acc;
        }
}

/* After a located observation's point variances (var_u_px2, var_v_px2) have grown: its
 * covariances (cov_rb, cov_xy, and jac_calib with cov_rb_frame) propagated again from them at the
 * same point; the point, range and flags stay. */
static void propagate_again(cyl_observation *o, const cyl_camera *cam, const cyl_observe_params *p)
{
    cyl_rb_result rb;
    if (cyl_rb_compute(cam, p->model, o->u_px, o->v_px, o->var_u_px2, o->var_v_px2, 0.0, &rb) != CYL_OK) return;
    memcpy(o->cov_rb, rb.cov_rb, sizeof o->cov_rb);
    memcpy(o->cov_xy, rb.cov_xy, sizeof o->cov_xy);
    calib_share(o, cam, &rb);
}

/* A part missing from the blob's box, or extra, as aspect_rel measures it against the whole
 * landmark's (a side: aspect_rel < 1; the top or bottom: > 1), moves the centroid by half its size
 * if it lies on one side, and which side is not known: `share` of that shift is the sigma of a
 * bias added to the point's variances (var_*, bias_var_*), then propagated (propagate_again). */
static void add_missing_part(cyl_observation *o, const cyl_camera *cam, const cyl_observe_params *p, double share)
{
    const double su = share * o->w_px * fmax(1.0 / o->aspect_rel - 1.0, 0.0) / 2.0;
    const double sv = share * o->h_px * fmax(1.0 - 1.0 / o->aspect_rel, 0.0) / 2.0;
    o->var_u_px2 += su * su;
    o->var_v_px2 += sv * sv;
    o->bias_var_u_px2 += su * su;
    o->bias_var_v_px2 += sv * sv;
    propagate_again(o, cam, p);
}

#if CYL_CONFIG_SUBPIXEL   /* side_colour_rel reads the image around the blob's edges, as sub-pixel edges do */
/* The landmark's colour beyond one side of the box (side_colour_rel) as a sigma of the view's u
 * bias, added to var_u_px2 alone (it changes from view to view, unlike bias_var), then propagated
 * (propagate_again). Only observations with a range (locate() succeeded). */
static void add_side_sigma(cyl_observation *o, const cyl_camera *cam, const cyl_observe_params *p)
{
    const double su = p->side_sigma_rel * fmax(fabs(o->side_colour_rel) - p->side_sigma_free, 0.0) * o->w_px;
    if (!(su > 0.0) || (o->flags & (CYL_OBS_INVALID | CYL_OBS_NO_RANGE))) return;
    o->var_u_px2 += su * su;
    propagate_again(o, cam, p);
}

/* The share of one strip's pixels whose chroma (U - 128, V - 128) points within acos(0.9) of the
 * blob's mean chroma (mu, mv; its length m) and is at least half as long. */
static double strip_share(const cyl_image *img, uint32_t xa, uint32_t xb, uint32_t ya, uint32_t yb,
                          double mu, double mv, double m)
{
    uint32_t x, y, n = 0, k = 0;
    for (y = ya; y <= yb; y++)
        for (x = xa; x <= xb; x++) {
            uint8_t Y, U, V;
            double cu, cv, c;
            cyl_pixel_fetch(img, x, y, &Y, &U, &V);
            cu = (double)U - 128.0;
            cv = (double)V - 128.0;
            c = sqrt(cu * cu + cv * cv);
            n++;
            if (c >= 0.5 * m && cu * mu + cv * mv > 0.9 * c * m) k++;
        }
    return n ? (double)k / (double)n : 0.0;
}

/* side_colour_rel of a blob's box (x0..x1, y0..y1 inclusive, px): the landmark's colour beyond
 * its left side less beyond its right (cyl_observation.side_colour_rel); 0 when a strip would
 * leave the frame or the blob has no chroma to compare. */
static double side_colour(const cyl_image *img, const cyl_blob *b)
{
    const uint32_t strip = 3u;
    uint32_t ya, yb, x, y, n = 0, h, sx, sy;
    double su = 0.0, sv = 0.0, mu, mv, m;
    if (b->x0 < strip || b->x1 + strip >= img->width || b->y1 >= img->height || b->x1 < b->x0 + 2u) return 0.0;
    h = b->y1 - b->y0 + 1u;
    ya = b->y0 + (uint32_t)(0.2 * (double)h);
    yb = b->y1 - (uint32_t)(0.2 * (double)h);
    if (yb < ya) return 0.0;
    /* the blob's mean chroma from at most about 16 x 16 of its pixels (the strips are read whole) */
    sx = (b->x1 - b->x0 - 1u) / 16u + 1u;
    sy = (yb - ya + 1u) / 16u + 1u;
    for (y = ya; y <= yb; y += sy)
        for (x = b->x0 + 1u; x < b->x1; x += sx) {
            uint8_t Y, U, V;
            cyl_pixel_fetch(img, x, y, &Y, &U, &V);
            su += (double)U - 128.0;
            sv += (double)V - 128.0;
            n++;
        }
    mu = su / (double)n;
    mv = sv / (double)n;
    m = sqrt(mu * mu + mv * mv);
    if (!(m >= 1.0)) return 0.0;
    return strip_share(img, b->x0 - strip, b->x0 - 1u, ya, yb, mu, mv, m) -
           strip_share(img, b->x1 + 1u, b->x1 + strip, ya, yb, mu, mv, m);
}
#endif

/* From the measurement point's centroid and variances (o->centroid_*, o->var_*) and box (w_px,
 * h_px): the silhouette correction, range and bearing with their covariances, the calibration's
 * share, the non-linearity flag, the confidence against the expected box of conf_size, and (a
 * single blob's, blob_area_px2 > 0) its area against the silhouette's. */
static void locate(cyl_observation *o, const cyl_camera *cam, const cyl_observe_params *p, const shape_ref *sh,
                   const cyl_landmark_size *conf_size, uint32_t blob_flags, double blob_area_px2, double box_mid_u_px)
{
    cyl_rb_result rb;
    cyl_status st = cyl_rb_compute(cam, p->model, o->u_px, o->v_px, o->var_u_px2, o->var_v_px2, 0.0, &rb);
    double su, sv, sil_area_px2 = 0.0;
    abs_sigmas(p, sh, &su, &sv);
    if (st == CYL_OK && p->silhouette_rel_sigma >= 0.0 && su >= 0.0 && sv >= 0.0 && !(o->flags & CYL_OBS_CUT) &&
        (sh->model || (sh->size->diameter_m > 0.0 && sh->size->height_m > 0.0)))
        correct_silhouette(o, cam, p, sh, &rb, &sil_area_px2);
    if (st == CYL_ERR_NO_RANGE) {
        o->flags |= CYL_OBS_NO_RANGE;
        o->bearing_rad = rb.bearing_rad;
        o->cov_rb[1][1] = rb.cov_rb[1][1];
        return;
    }
    if (st != CYL_OK) { o->flags |= CYL_OBS_INVALID; return; }
    o->range_m = rb.range_m;
    o->bearing_rad = rb.bearing_rad;
    memcpy(o->cov_rb, rb.cov_rb, sizeof o->cov_rb);
    o->x_m = rb.x_m;
    o->y_m = rb.y_m;
    memcpy(o->cov_xy, rb.cov_xy, sizeof o->cov_xy);
    o->depth_m = rb.depth_m;
    calib_share(o, cam, &rb);
    if (p->nonlinear_rel_sigma > 0.0 && sqrt(rb.cov_rb[0][0]) > p->nonlinear_rel_sigma * rb.range_m)
        o->flags |= CYL_OBS_NONLINEAR;
    {
        cyl_confidence c;
        double we, he;
        if (cyl_landmark_expected_size(cam, rb.xn, rb.yn, o->depth_m, conf_size, &we, &he) == CYL_OK &&
            cyl_landmark_confidence_expected(o->w_px, o->h_px, we, he, blob_flags, &c) == CYL_OK) {
            o->confidence = c.confidence;
            o->confidence_uncut = c.confidence_uncut;
            o->w_est_px = c.w_est_px;
            o->h_est_px = c.h_est_px;
            o->aspect_rel = c.ratio_w / c.ratio_h;
            if (p->partial_aspect_min > 0.0 &&
                (o->aspect_rel < p->partial_aspect_min || o->aspect_rel * p->partial_aspect_min > 1.0))
                o->flags |= CYL_OBS_PARTIAL;
            /* both judged only where the range is accurate (as on the views they were chosen on):
             * the silhouette's area goes as 1/range^2, so a range off by sigma_r/r moves area_rel
             * by about 2 sigma_r/r; and a far landmark's narrow box is rounded by a large share
             * of its width */
            if (blob_area_px2 > 0.0 && sil_area_px2 > 0.0) {
                o->area_rel = blob_area_px2 / sil_area_px2;
                o->offset_rel = (o->u_px - box_mid_u_px) / o->w_px;
                if (!(o->flags & CYL_OBS_NONLINEAR) &&
                    ((p->partial_area_min > 0.0 && o->area_rel < p->partial_area_min) ||
                     (p->partial_offset_max > 0.0 && fabs(o->offset_rel) > p->partial_offset_max)))
                    o->flags |= CYL_OBS_PARTIAL;
                /* after the flags: the range's linearity is judged on the centroid's own spread */
                if (p->missing_part_share > 0.0 && o->aspect_rel > 0.0)
                    add_missing_part(o, cam, p, p->missing_part_share);
            }
        } else {
            o->flags |= CYL_OBS_NO_SIZE;
        }
    }
}

static cyl_status observe_check(const cyl_segmentation *seg, const cyl_camera *cam, const cyl_observe_params *p,
                                size_t work_size, uint32_t cap, const void *out, const uint32_t *n_out);

/* A blob's centroid and its variance by the chosen estimator; with params.subpixel the centroid
 * is moved to the one with sub-pixel edges, whose shift goes to *du, *dv (else 0). *area_px2: the
 * blob's area, px^2 (with its edges moved, when they are). */
static cyl_status blob_noise(const cyl_segmentation *seg, const cyl_blob *b, const cyl_observe_params *p, void *work,
                             size_t work_size, cyl_centroid_noise *cn, double *du, double *dv, double *area_px2)
{
#if CYL_CONFIG_IMAGE_ESTIMATOR
    cyl_status st = p->estimator == CYL_NOISE_IMAGE ? cyl_noise_blob_image(seg, b, p->image, p->table, &p->image_noise, cn)
                                                     : cyl_noise_blob(seg, b, p->estimator, work, work_size, cn);
#else
    cyl_status st = p->estimator == CYL_NOISE_IMAGE ? CYL_ERR_UNSUPPORTED
                                                     : cyl_noise_blob(seg, b, p->estimator, work, work_size, cn);
#endif
    *du = *dv = 0.0;
    *area_px2 = st == CYL_OK ? (double)cn->n * (double)seg->x_step * (double)seg->y_step : 0.0;
#if CYL_CONFIG_SUBPIXEL
    if (st == CYL_OK && p->subpixel) {
        cyl_subpixel_result r;
        cyl_status s2 = cyl_subpixel_centroid(seg, b, p->image, p->table, &p->subpixel_params, &r);
        if (s2 == CYL_OK) {
            *du = r.cx_px - cn->cx_px;
            *dv = r.cy_px - cn->cy_px;
            cn->cx_px = r.cx_px;
            cn->cy_px = r.cy_px;
            *area_px2 = r.area_px2;
        } else if (s2 != CYL_ERR_EMPTY) {
            return s2;
        }
    }
#else
    if (st == CYL_OK && p->subpixel) return CYL_ERR_UNSUPPORTED;
#endif
    return st;
}

cyl_status cyl_observe(const cyl_segmentation *seg, const cyl_camera *cam,
                       const cyl_observe_params *p, void *work, size_t work_size,
                       cyl_observation *out, uint32_t cap, uint32_t *n_out)
{
    uint32_t bi, n = 0;
    cyl_status st, ret = CYL_OK;
    if (n_out) *n_out = 0;
    st = observe_check(seg, cam, p, work_size, cap, out, n_out);
    if (st != CYL_OK) return st;
    for (bi = 0; bi < seg->n_blobs; bi++) {
        const cyl_blob *b = &seg->blobs[bi];
        cyl_observation *o;
        cyl_centroid_noise cn;
        double du, dv, area_px2;
        if (b->cls >= CYL_MAX_CLASSES || !(p->class_mask & (1u << b->cls))) continue;
        if (b->area < p->min_area) continue;
        if (n == cap) { ret = CYL_TRUNCATED; break; }
        st = blob_noise(seg, b, p, work, work_size, &cn, &du, &dv, &area_px2);
        if (st == CYL_ERR_EMPTY) continue;
        if (st != CYL_OK) return st;
        o = &out[n++];
        memset(o, 0, sizeof *o);
        o->blob = bi;
        o->cls = b->cls;
        o->model = CYL_NO_MODEL;
        o->landmark_id = -1;
        o->flags = b->flags & (CYL_BLOB_TOUCH_ANY | CYL_BLOB_MERGED);
        if (b->flags & CYL_BLOB_TOUCH_ANY) o->flags |= CYL_OBS_CUT;
        o->area = cn.n;
        o->centroid_u_px = o->u_px = cn.cx_px;
        o->centroid_v_px = o->v_px = cn.cy_px;
        o->subpixel_du_px = du;
        o->subpixel_dv_px = dv;
        o->var_u_px2 = cn.var_x_px2 > p->min_var_px2 ? cn.var_x_px2 : p->min_var_px2;
        o->var_v_px2 = cn.var_y_px2 > p->min_var_px2 ? cn.var_y_px2 : p->min_var_px2;
        o->w_px = (double)cn.box_w * (double)seg->x_step;
        o->h_px = (double)cn.box_h * (double)seg->y_step;
        {
            shape_ref sh;
            memset(&sh, 0, sizeof sh);
            sh.size = &p->size[b->cls];
            locate(o, cam, p, &sh, &p->size[b->cls], b->flags, area_px2, 0.5 * ((double)b->x0 + (double)b->x1));
        }
#if CYL_CONFIG_SUBPIXEL
        if (p->image) {
            o->side_colour_rel = side_colour(p->image, b);
            if (p->partial_side_max > 0.0 && fabs(o->side_colour_rel) > p->partial_side_max)
                o->flags |= CYL_OBS_PARTIAL;
            if (p->side_sigma_rel > 0.0) add_side_sigma(o, cam, p);
        }
#endif
    }
    *n_out = n;
    return ret;
}

static cyl_status observe_check(const cyl_segmentation *seg, const cyl_camera *cam, const cyl_observe_params *p,
                                size_t work_size, uint32_t cap, const void *out, const uint32_t *n_out)
{
    cyl_status st;
    if (!seg || !cam || !p || !n_out || (cap > 0 && !out)) return CYL_ERR_ARG;
    if (seg->n_blobs > 0 && !seg->blobs) return CYL_ERR_ARG;
    st = cyl_camera_check(cam);
    if (st != CYL_OK) return st;
    if (work_size < cyl_observe_work_size(seg, p)) return CYL_ERR_NOMEM;
    if (p->model != CYL_GEOM_EXACT && p->model != CYL_GEOM_PAPER) return CYL_ERR_ARG;
    if (!(p->min_var_px2 >= 0.0)) return CYL_ERR_ARG;
    if ((p->estimator == CYL_NOISE_IMAGE && !CYL_CONFIG_IMAGE_ESTIMATOR) ||
        ((p->subpixel || p->partial_side_max > 0.0) && !CYL_CONFIG_SUBPIXEL))
        return CYL_ERR_UNSUPPORTED;   /* compiled out (cyl/config.h) */
    if ((p->estimator == CYL_NOISE_IMAGE || p->subpixel) && (!p->image || !p->table)) return CYL_ERR_ARG;
    if (p->subpixel && (p->subpixel_params.reach < 2u || p->subpixel_params.reach > CYL_SUBPIXEL_MAX_REACH ||
                        !(p->subpixel_params.min_contrast >= 0.0) || !isfinite(p->subpixel_params.min_contrast)))
        return CYL_ERR_ARG;
    /* a sigma of the silhouette's offset may be negative (no correction) but not infinite or NaN */
    if (!isfinite(p->silhouette_rel_sigma) || !isfinite(p->silhouette_sigma_u_px) || !isfinite(p->silhouette_sigma_v_px) ||
        !isfinite(p->subpixel_rel_sigma) ||
        !isfinite(p->missing_part_share) || p->missing_part_share < 0.0 || !isfinite(p->partial_side_max) ||
        !(p->side_sigma_rel >= 0.0) || !isfinite(p->side_sigma_rel) ||
        !(p->side_sigma_free >= 0.0 && p->side_sigma_free <= 1.0) ||
        !isfinite(p->group_silhouette_sigma_u_px) || !isfinite(p->group_silhouette_sigma_v_px))
        return CYL_ERR_ARG;
    return CYL_OK;
}

#if CYL_CONFIG_MODELS
cyl_status cyl_observe_groups(const cyl_segmentation *seg, const cyl_group *groups, uint32_t n_groups,
                              const cyl_landmark_model *models, uint32_t n_models, double plane_height_m,
                              const cyl_camera *cam, const cyl_observe_params *p, void *work, size_t work_size,
                              cyl_observation *out, uint32_t cap, uint32_t *n_out)
{
    uint32_t gi, n = 0;
    cyl_status st, ret = CYL_OK;
    if (n_out) *n_out = 0;
    st = observe_check(seg, cam, p, work_size, cap, out, n_out);
    if (st != CYL_OK) return st;
    if ((n_groups > 0 && !groups) || !(plane_height_m >= 0.0) || !isfinite(plane_height_m)) return CYL_ERR_ARG;
    if (n_groups > 0) {
        st = cyl_landmark_models_check(models, n_models);
        if (st != CYL_OK) return st;
    }
    for (gi = 0; gi < n_groups; gi++)
        if (groups[gi].model >= n_models) return CYL_ERR_ARG;
    for (gi = 0; gi < n_groups; gi++) {
        const cyl_group *g = &groups[gi];
        const cyl_landmark_model *m = &models[g->model];
        cyl_observation *o;
        const double total_h = cyl_landmark_height_m(m);
        double sx = 0.0, sy = 0.0, vx = 0.0, vy = 0.0, sdu = 0.0, sdv = 0.0;
        uint32_t mask = 0, first = CYL_NONE, blob_flags = 0, nsamp = 0;
        int k;
        shape_ref sh;
        cyl_landmark_size whole;
        for (k = 0; k < m->n_bands; k++) {
            const uint32_t bi = g->blob[k];
            const cyl_blob *b;
            cyl_centroid_noise cn;
            double du, dv, area_px2;
            if (bi == CYL_NONE) continue;
            if (bi >= seg->n_blobs) return CYL_ERR_ARG;
            b = &seg->blobs[bi];
            st = blob_noise(seg, b, p, work, work_size, &cn, &du, &dv, &area_px2);
            if (st == CYL_ERR_EMPTY) continue;
            if (st != CYL_OK) return st;
            if (first == CYL_NONE) first = bi;
            mask |= 1u << k;
            blob_flags |= b->flags;
            nsamp += cn.n;
            vx += (double)cn.n * (double)cn.n * cn.var_x_px2;   /* divided by N^2 below */
            vy += (double)cn.n * (double)cn.n * cn.var_y_px2;
            sx += (double)cn.n * cn.cx_px;
            sy += (double)cn.n * cn.cy_px;
            sdu += (double)cn.n * du;
            sdv += (double)cn.n * dv;
        }
        if (!mask || nsamp == 0) continue;
        if (n == cap) { ret = CYL_TRUNCATED; break; }
        vx /= (double)nsamp * (double)nsamp;
        vy /= (double)nsamp * (double)nsamp;
        o = &out[n++];
        memset(o, 0, sizeof *o);
        o->blob = first;
        o->cls = seg->blobs[first].cls;
        o->model = g->model;
        o->group_flags = g->flags;
        o->landmark_id = g->id;
        o->code_confidence = g->code_confidence;
        o->flags = blob_flags & (CYL_BLOB_TOUCH_ANY | CYL_BLOB_MERGED);
        if (blob_flags & CYL_BLOB_TOUCH_ANY) o->flags |= CYL_OBS_CUT;
        o->area = nsamp;
        o->centroid_u_px = o->u_px = sx / (double)nsamp;
        o->centroid_v_px = o->v_px = sy / (double)nsamp;
        o->subpixel_du_px = sdu / (double)nsamp;
        o->subpixel_dv_px = sdv / (double)nsamp;
        o->var_u_px2 = vx > p->min_var_px2 ? vx : p->min_var_px2;
        o->var_v_px2 = vy > p->min_var_px2 ? vy : p->min_var_px2;
        o->w_px = (double)g->x1 - (double)g->x0 + (double)seg->x_step;
        o->h_px = (double)g->y1 - (double)g->y0 + (double)seg->y_step;
        /* The reference point: the landmark's axis at z_ref, the middle of its matched bands
         * weighted by their side areas (height x mean diameter), so the silhouette offset that
         * remains is small (a cone's colour sits low: from the centroid plane its offset would be
         * tens of px, and neither the fixed-point iteration nor a relative uncertainty of it would
         * be right). The camera's height is then counted from the plane at z_ref. */
        {
            double z = -plane_height_m, zw = 0.0, ww = 0.0;
            const double d_top = cyl_landmark_diameter_at_m(m, total_h);
            cyl_camera cam_ref = *cam;
            for (k = m->n_bands - 1; k >= 0; k--) {
                const double z0 = z, z1 = z + m->band_height_m[k];
                const double d0 = cyl_landmark_diameter_at_m(m, z0 + plane_height_m);
                const double d1 = cyl_landmark_diameter_at_m(m, z1 + plane_height_m);
                const double w = m->band_height_m[k] * 0.5 * (d0 + d1);
                if (mask & (1u << k)) {
                    zw += w * 0.5 * (z0 + z1);
                    ww += w;
                }
                z = z1;
            }
            o->z_ref_m = ww > 0.0 ? zw / ww : 0.0;
            cam_ref.height_m = cam->height_m - o->z_ref_m;
            memset(&sh, 0, sizeof sh);
            sh.model = m;
            sh.base_z_m = -plane_height_m - o->z_ref_m;
            sh.band_mask = mask;
            whole.diameter_m = d_top > m->diameter_bottom_m ? d_top : m->diameter_bottom_m;
            whole.height_m = total_h;
            locate(o, &cam_ref, p, &sh, &whole, blob_flags, 0.0, 0.0);   /* no area or offset check: bands */
        }
    }
    *n_out = n;
    return ret;
}
#else /* CYL_CONFIG_MODELS */
cyl_status cyl_observe_groups(const cyl_segmentation *seg, const cyl_group *groups, uint32_t n_groups,
                              const cyl_landmark_model *models, uint32_t n_models, double plane_height_m,
                              const cyl_camera *cam, const cyl_observe_params *p, void *work, size_t work_size,
                              cyl_observation *out, uint32_t cap, uint32_t *n_out)
{
    (void)seg; (void)groups; (void)n_groups; (void)models; (void)n_models; (void)plane_height_m; (void)cam;
    (void)p; (void)work; (void)work_size; (void)out; (void)cap;
    if (n_out) *n_out = 0;
    return CYL_ERR_UNSUPPORTED;
}
#endif

cyl_status cyl_observation_budget(const cyl_observation *obs, const cyl_camera *cam,
                                  cyl_geom_model model, cyl_error_budget *b)
{
    if (!obs || !cam || !b) return CYL_ERR_ARG;
    return cyl_error_budget_at(cam, model, obs->u_px, obs->v_px, obs->var_u_px2, obs->var_v_px2,
                               0.0, b);
}
