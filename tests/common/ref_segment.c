/* SPDX-License-Identifier: BSD-3-Clause */
#include "ref_segment.h"
#include <stdlib.h>
#include <string.h>

static int before(const ref_blob *a, const ref_blob *b)
{
    if (a->cls != b->cls) return a->cls < b->cls;
    if (a->area != b->area) return a->area > b->area;
    if (a->y0 != b->y0) return a->y0 < b->y0;
    if (a->x0 != b->x0) return a->x0 < b->x0;
    if (a->first_y != b->first_y) return a->first_y < b->first_y;
    return a->first_x < b->first_x;
}

int ref_segment(const cyl_colortable *t, const cyl_image *img, const cyl_segment_params *p,
                ref_blob *out, int max_blobs, int *label_out)
{
    uint32_t rx = p->roi.x, ry = p->roi.y, rw = p->roi.width, rh = p->roi.height;
    uint32_t xs = p->x_step, ys = p->y_step, nx, ny, i, j;
    int *cls, *lab, *stack, nb = 0, nout = 0, a, b, weak = 0, has_strong = 0;
    char *strong_px;
    ref_blob *all;
    if (rw == 0 || rh == 0) { rx = 0; ry = 0; rw = img->width; rh = img->height; }
    nx = (rw + xs - 1) / xs;
    ny = (rh + ys - 1) / ys;
    cls = (int *)malloc(sizeof(int) * nx * ny);
    lab = (int *)malloc(sizeof(int) * nx * ny);
    stack = (int *)malloc(sizeof(int) * nx * ny);
    all = (ref_blob *)malloc(sizeof(ref_blob) * nx * ny);
    strong_px = (char *)malloc(nx * ny);
    if (!cls || !lab || !stack || !all || !strong_px) { free(cls); free(lab); free(stack); free(all); free(strong_px); return -1; }
    for (j = 0; j < ny; j++)
        for (i = 0; i < nx; i++) {
            uint8_t Y, U, V;
            unsigned m, c = CYL_CLASS_NONE, k;
            cyl_image_pixel(img, rx + i * xs, ry + j * ys, &Y, &U, &V);
            /* the table's rule written out: chroma, brightness and the 3-D cell */
            m = t->uv[U][V] & t->y[Y] & t->yuv[Y / 8u][U / 4u][V / 4u];
            for (k = 0; k < 8; k++) if (m & (1u << k)) { c = k; break; }
            cls[j * nx + i] = c == CYL_CLASS_NONE ? -1 : (int)c;
        }
    /* drop runs shorter than min_run */
    for (j = 0; j < ny; j++) {
        i = 0;
        while (i < nx) {
            uint32_t e = i;
            while (e < nx && cls[j * nx + e] == cls[j * nx + i]) e++;
            if (cls[j * nx + i] >= 0 && e - i < p->min_run_px)
                for (; i < e; i++) cls[j * nx + i] = -1;
            i = e;
        }
    }
    /* weak classes (hysteresis): a weak pixel belongs to its strong class's blobs; remember
     * which pixels are strong in the sign of a second array (stack is free until the fill) */
    for (i = 0; i < nx * ny; i++) {
        int c0 = cls[i];
        stack[i] = 1;
        if (c0 >= 0 && t->weak_of[c0] < 8 && t->weak_of[t->weak_of[c0]] == CYL_CLASS_NONE) {
            cls[i] = t->weak_of[c0];
            stack[i] = 0;
            weak = 1;
        }
    }
    for (i = 0; i < nx * ny; i++) strong_px[i] = (char)stack[i];
    for (i = 0; i < nx * ny; i++) lab[i] = -1;
    for (j = 0; j < ny; j++)
        for (i = 0; i < nx; i++) {
            int sp = 0, s0 = (int)(j * nx + i);
            ref_blob *rb;
            double n, sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
            if (cls[s0] < 0 || lab[s0] >= 0) continue;
            has_strong = 0;
            rb = &all[nb];
            memset(rb, 0, sizeof *rb);
            rb->cls = (unsigned)cls[s0];
            rb->x0 = rb->y0 = 0xFFFFFFFFu;
            rb->first_x = rx + i * xs; rb->first_y = ry + j * ys;
            lab[s0] = nb;
            stack[sp++] = s0;
            while (sp > 0) {
                int s = stack[--sp], nbr[4], q;
                uint32_t si = (uint32_t)s % nx, sj = (uint32_t)s / nx;
                double X = rx + si * xs, Yc = ry + sj * ys;
                rb->area++;
                has_strong |= strong_px[s];
                sx += X; sy += Yc; sxx += X * X; syy += Yc * Yc; sxy += X * Yc;
                if (X < rb->x0) rb->x0 = (uint32_t)X;
                if (X > rb->x1) rb->x1 = (uint32_t)X;
                if (Yc < rb->y0) rb->y0 = (uint32_t)Yc;
                if (Yc > rb->y1) rb->y1 = (uint32_t)Yc;
                nbr[0] = si > 0 ? s - 1 : -1;
                nbr[1] = si + 1 < nx ? s + 1 : -1;
                nbr[2] = sj > 0 ? s - (int)nx : -1;
                nbr[3] = sj + 1 < ny ? s + (int)nx : -1;
                for (q = 0; q < 4; q++)
                    if (nbr[q] >= 0 && lab[nbr[q]] < 0 && cls[nbr[q]] == cls[s0]) {
                        lab[nbr[q]] = nb;
                        stack[sp++] = nbr[q];
                    }
            }
            n = rb->area;
            rb->cx = sx / n; rb->cy = sy / n;
            rb->mxx = sxx / n - rb->cx * rb->cx;
            rb->myy = syy / n - rb->cy * rb->cy;
            rb->mxy = sxy / n - rb->cx * rb->cy;
            if (rb->x0 == rx) rb->touches |= CYL_BLOB_TOUCH_LEFT;
            if (rb->x1 == rx + (nx - 1) * xs) rb->touches |= CYL_BLOB_TOUCH_RIGHT;
            if (rb->y0 == ry) rb->touches |= CYL_BLOB_TOUCH_TOP;
            if (rb->y1 == ry + (ny - 1) * ys) rb->touches |= CYL_BLOB_TOUCH_BOTTOM;
            rb->weak_only = weak && !has_strong;
            if (weak && !has_strong &&   /* weak evidence alone: no blob, unless large enough */
                (p->cls[rb->cls].weak_alone_min_area == 0 || rb->area < p->cls[rb->cls].weak_alone_min_area))
                rb->area = 0;
            nb++;
        }
    /* filter by min_area, selection sort into out */
    for (a = 0; a < nb; a++)
        if (all[a].area < p->cls[all[a].cls].min_area) all[a].area = 0;
    for (;;) {
        int best = -1;
        for (b = 0; b < nb; b++)
            if (all[b].area > 0 && (best < 0 || before(&all[b], &all[best]))) best = b;
        if (best < 0 || nout >= max_blobs) break;
        out[nout++] = all[best];
        all[best].area = 0;
    }
    if (label_out) memcpy(label_out, lab, sizeof(int) * nx * ny);
    free(cls); free(lab); free(stack); free(all); free(strong_px);
    return nout;
}
