/* SPDX-License-Identifier: BSD-3-Clause */
#include "cyl/colortable.h"
#include "internal.h"
#include <string.h>

/* An empty inner box: every lower corner above its upper corner. */
static void inner_empty(cyl_colortable *t, unsigned c)
{
    memset(t->inner_lo[c], 0xFF, 3);
    memset(t->inner_hi[c], 0, 3);
}

void cyl_colortable_init(cyl_colortable *t)
{
    unsigned i;
    if (!t) return;
    memset(t, 0, sizeof *t);
    memset(t->yuv, 0xFF, sizeof t->yuv);
    t->lookup = CYL_LOOKUP_UV_Y;
    memset(t->weak_of, CYL_CLASS_NONE, sizeof t->weak_of);
    for (i = 0; i < CYL_MAX_CLASSES; i++) {
        t->rgb[i][0] = t->rgb[i][1] = t->rgb[i][2] = 128;
        inner_empty(t, i);
    }
}

cyl_status cyl_colortable_set_class(cyl_colortable *t, unsigned cls, const char *name,
                                    uint8_t r, uint8_t g, uint8_t b)
{
    size_t n = 0;
    if (!t || !name) return CYL_ERR_ARG;
    if (cls >= CYL_MAX_CLASSES) return CYL_ERR_CLASS;
    while (n < CYL_CLASS_NAME_LEN - 1u && name[n]) n++;
    memset(t->name[cls], 0, CYL_CLASS_NAME_LEN);
    memcpy(t->name[cls], name, n);
    t->rgb[cls][0] = r; t->rgb[cls][1] = g; t->rgb[cls][2] = b;
    return CYL_OK;
}

int cyl_colortable_find_class(const cyl_colortable *t, const char *name)
{
    unsigned i;
    if (!t || !name || !name[0]) return -1;
    for (i = 0; i < CYL_MAX_CLASSES; i++)
        if (strncmp(t->name[i], name, CYL_CLASS_NAME_LEN) == 0) return (int)i;
    return -1;
}

cyl_status cyl_colortable_set_weak(cyl_colortable *t, unsigned weak, unsigned strong)
{
    unsigned i;
    if (!t) return CYL_ERR_ARG;
    if (weak >= CYL_MAX_CLASSES || (strong >= CYL_MAX_CLASSES && strong != CYL_CLASS_NONE)) return CYL_ERR_CLASS;
    if (strong != CYL_CLASS_NONE) {
        if (strong == weak || t->weak_of[strong] != CYL_CLASS_NONE) return CYL_ERR_ARG;
        for (i = 0; i < CYL_MAX_CLASSES; i++)
            if (t->weak_of[i] == weak) return CYL_ERR_ARG;   /* weak has a weak class itself */
    }
    t->weak_of[weak] = (uint8_t)strong;
    return CYL_OK;
}

static int has_weak(const cyl_colortable *t)
{
    unsigned i;
    for (i = 0; i < CYL_MAX_CLASSES; i++)
        if (t->weak_of[i] != CYL_CLASS_NONE) return 1;
    return 0;
}

/* Recompute the coarse chroma map of the vector background skip from uv. */
static void chroma_any_update(cyl_colortable *t)
{
    unsigned u, v;
    memset(t->chroma_any, 0, sizeof t->chroma_any);
    for (u = 0; u < 256; u++)
        for (v = 0; v < 256; v++)
            if (t->uv[u][v]) t->chroma_any[u >> 7][v >> 4] |= (uint8_t)(1u << ((u >> 4) & 7u));
}

/* ---- inner boxes (the vector run extension's fast test) --------------------- */

/* Is every colour of the box [lo, hi] ((Y, U, V), inclusive) of class c? Within each 3-D cell the
 * box's uv and y entries are combined through their AND (for c's bit: every colour has it) and
 * their OR (for the lower classes' bits: no colour can have one), so the answer may be no for a
 * box whose colours are all of class c, never yes for one that holds another colour. */
static int inner_ok(const cyl_colortable *t, unsigned c, const unsigned lo[3], const unsigned hi[3])
{
    const cyl_mask bit = (cyl_mask)(1u << c), lower = (cyl_mask)(bit - 1u);
    cyl_mask yor[CYL_YUV_NY];
    unsigned Y, uc, vc, yc;
    memset(yor, 0, sizeof yor);
    for (Y = lo[0]; Y <= hi[0]; Y++) {
        if (!(t->y[Y] & bit)) return 0;
        yor[Y >> CYL_YUV_YSHIFT] |= t->y[Y];
    }
    for (uc = lo[1] >> CYL_YUV_CSHIFT; uc <= hi[1] >> CYL_YUV_CSHIFT; uc++)
        for (vc = lo[2] >> CYL_YUV_CSHIFT; vc <= hi[2] >> CYL_YUV_CSHIFT; vc++) {
            const unsigned u0 = uc << CYL_YUV_CSHIFT, v0 = vc << CYL_YUV_CSHIFT;
            const unsigned ua = u0 > lo[1] ? u0 : lo[1], ub = u0 + 3u < hi[1] ? u0 + 3u : hi[1];
            const unsigned va = v0 > lo[2] ? v0 : lo[2], vb = v0 + 3u < hi[2] ? v0 + 3u : hi[2];
            cyl_mask any = 0;
            unsigned U, V;
            for (U = ua; U <= ub; U++)
                for (V = va; V <= vb; V++) {
                    if (!(t->uv[U][V] & bit)) return 0;
                    any |= t->uv[U][V];
                }
            for (yc = lo[0] >> CYL_YUV_YSHIFT; yc <= hi[0] >> CYL_YUV_YSHIFT; yc++) {
                const cyl_mask cell = t->yuv[yc][uc][vc];
                if (!(cell & bit) || (any & yor[yc] & cell & lower)) return 0;
            }
        }
    return 1;
}

/* Grow class c's inner box from the colour seed: the six faces in turn, each by the largest step
 * among 16, 8, 4, 2, 1 levels that keeps the box inside the class, until none can move. */
static void inner_grow(cyl_colortable *t, unsigned c, const unsigned seed[3])
{
    unsigned lo[3], hi[3], step[6], k, open = 0x3Fu;
    for (k = 0; k < 3; k++) lo[k] = hi[k] = seed[k];
    if (!inner_ok(t, c, lo, hi)) return;   /* the box stays empty (inner_update emptied it) */
    for (k = 0; k < 6; k++) step[k] = 16u;
    while (open) {
        for (k = 0; k < 6; k++) {
            const unsigned a = k >> 1;
            if (!(open & (1u << k))) continue;
            for (;;) {
                const unsigned room = (k & 1u) ? 255u - hi[a] : lo[a];
                const unsigned s = step[k] < room ? step[k] : room;
                if (s == 0) { open &= ~(1u << k); break; }
                if (k & 1u) hi[a] += s; else lo[a] -= s;
                if (inner_ok(t, c, lo, hi)) break;   /* moved: the next face */
                if (k & 1u) hi[a] -= s; else lo[a] += s;
                if (s == 1u) { open &= ~(1u << k); break; }
                step[k] = s / 2u;
            }
        }
    }
    for (k = 0; k < 3; k++) {
        t->inner_lo[c][k] = (uint8_t)lo[k];
        t->inner_hi[c][k] = (uint8_t)hi[k];
    }
}

/* Every live class's inner box, grown from the centre of its cell nearest to the mean of its
 * cells (cells whose centre colour has the class). */
static void inner_update(cyl_colortable *t)
{
    uint32_t sum[CYL_MAX_CLASSES][3], n[CYL_MAX_CLASSES], best[CYL_MAX_CLASSES];
    unsigned seed[CYL_MAX_CLASSES][3], c, yc, uc, vc, pass;
    memset(sum, 0, sizeof sum);
    memset(n, 0, sizeof n);
    for (c = 0; c < CYL_MAX_CLASSES; c++) { inner_empty(t, c); best[c] = 0xFFFFFFFFu; }
    for (pass = 0; pass < 2u; pass++)
        for (yc = 0; yc < CYL_YUV_NY; yc++)
            for (uc = 0; uc < CYL_YUV_NC; uc++)
                for (vc = 0; vc < CYL_YUV_NC; vc++) {
                    const unsigned p[3] = { (yc << CYL_YUV_YSHIFT) + 4u, (uc << CYL_YUV_CSHIFT) + 2u,
                                            (vc << CYL_YUV_CSHIFT) + 2u };
                    const unsigned k = cyl_mask_class(cyl_colortable_mask(t, (uint8_t)p[0], (uint8_t)p[1],
                                                                          (uint8_t)p[2]));
                    unsigned a;
                    uint32_t d = 0;
                    if (k >= CYL_MAX_CLASSES) continue;
                    if (pass == 0) {
                        for (a = 0; a < 3u; a++) sum[k][a] += p[a];
                        n[k]++;
                        continue;
                    }
                    for (a = 0; a < 3u; a++) {   /* squared distance to the mean, in levels */
                        const int32_t e = (int32_t)p[a] - (int32_t)(sum[k][a] / n[k]);
                        d += (uint32_t)(e * e);
                    }
                    if (d < best[k]) {
                        best[k] = d;
                        for (a = 0; a < 3u; a++) seed[k][a] = p[a];
                    }
                }
    for (c = 0; c < CYL_MAX_CLASSES; c++)
        if (n[c]) inner_grow(t, c, seed[c]);
}

cyl_status cyl_colortable_clear_class(cyl_colortable *t, unsigned cls)
{
    unsigned i, j;
    cyl_mask keep;
    if (!t) return CYL_ERR_ARG;
    if (cls >= CYL_MAX_CLASSES) return CYL_ERR_CLASS;
    keep = (cyl_mask)~(1u << cls);
    for (i = 0; i < 256; i++) {
        t->y[i] &= keep;
        for (j = 0; j < 256; j++) t->uv[i][j] &= keep;
    }
    {
        cyl_mask *c = &t->yuv[0][0][0];
        for (i = 0; i < CYL_YUV_CELLS; i++) c[i] |= (cyl_mask)(1u << cls);
    }
    t->lookup |= CYL_LOOKUP_UV_Y;   /* the class is now held off by uv and y alone */
    t->live &= keep;
    chroma_any_update(t);
    inner_empty(t, cls);   /* the other classes' boxes hold: no colour of theirs had this class's bit */
    return CYL_OK;
}

void cyl_colortable_refresh(cyl_colortable *t)
{
    unsigned b, need_uvy = 0, need_yuv;
    cyl_mask live = 0;
    if (!t) return;
    need_yuv = (unsigned)cyl_colortable_has_yuv(t);
    for (b = 0; b < CYL_MAX_CLASSES; b++) {
        const cyl_mask bit = (cyl_mask)(1u << b);
        uint8_t ymiss[CYL_YUV_NY], uvmiss[CYL_YUV_NC][CYL_YUV_NC];
        unsigned i, j, yc, uc, vc, any_y = 0, any_uv = 0, any_yuv = 0, redundant = 1;
        memset(ymiss, 0, sizeof ymiss);
        memset(uvmiss, 0, sizeof uvmiss);
        for (i = 0; i < 256; i++) {
            if (!(t->y[i] & bit)) ymiss[i >> CYL_YUV_YSHIFT] = 1;
            else any_y = 1;
        }
        for (i = 0; i < 256; i++)
            for (j = 0; j < 256; j++) {
                if (!(t->uv[i][j] & bit)) uvmiss[i >> CYL_YUV_CSHIFT][j >> CYL_YUV_CSHIFT] = 1;
                else any_uv = 1;
            }
        /* does uv & y reject, for this class, some pixel whose 3-D cell accepts it? */
        for (yc = 0; yc < CYL_YUV_NY; yc++)
            for (uc = 0; uc < CYL_YUV_NC; uc++)
                for (vc = 0; vc < CYL_YUV_NC; vc++)
                    if (t->yuv[yc][uc][vc] & bit) {
                        any_yuv = 1;
                        if (ymiss[yc] || uvmiss[uc][vc]) redundant = 0;
                    }
        if (!(any_y && any_uv && any_yuv)) continue;   /* matches no pixel at all */
        live |= bit;
        if (!redundant) need_uvy = 1;
    }
    t->live = live;
    chroma_any_update(t);
    inner_update(t);
    t->lookup = (uint8_t)((need_uvy || !need_yuv ? CYL_LOOKUP_UV_Y : 0u) | (need_yuv ? CYL_LOOKUP_YUV : 0u));
}

int cyl_colortable_has_yuv(const cyl_colortable *t)
{
    const cyl_mask *c;
    unsigned i;
    if (!t) return 0;
    c = &t->yuv[0][0][0];
    for (i = 0; i < CYL_YUV_CELLS; i++)
        if (c[i] != 0xFFu) return 1;
    return 0;
}

cyl_status cyl_colortable_add_box(cyl_colortable *t, unsigned cls,
                                  uint8_t y_lo, uint8_t y_hi,
                                  uint8_t u_lo, uint8_t u_hi,
                                  uint8_t v_lo, uint8_t v_hi)
{
    unsigned u, v, y;
    cyl_mask bit;
    if (!t) return CYL_ERR_ARG;
    if (cls >= CYL_MAX_CLASSES) return CYL_ERR_CLASS;
    if (y_lo > y_hi || u_lo > u_hi || v_lo > v_hi) return CYL_ERR_ARG;
    bit = (cyl_mask)(1u << cls);
    for (u = u_lo; u <= u_hi; u++)
        for (v = v_lo; v <= v_hi; v++) t->uv[u][v] |= bit;
    for (y = y_lo; y <= y_hi; y++) t->y[y] |= bit;
    for (u = u_lo >> 4; u <= (unsigned)u_hi >> 4; u++)
        for (v = v_lo >> 4; v <= (unsigned)v_hi >> 4; v++)
            t->chroma_any[u >> 3][v] |= (uint8_t)(1u << (u & 7u));
    t->lookup |= CYL_LOOKUP_UV_Y;   /* a box class is limited by uv and y */
    t->live |= bit;
    for (u = cls + 1u; u < CYL_MAX_CLASSES; u++) inner_empty(t, u);   /* colours of theirs may now be cls */
    return CYL_OK;
}

unsigned cyl_mask_class(cyl_mask m)
{
    unsigned i;
    if (!m) return CYL_CLASS_NONE;
    for (i = 0; !(m & (1u << i)); i++) {}
    return i;
}

/* cyl_classify() is in segment.c, beside the run-length encoder whose pixel access and
 * background skip it shares. */

/* ---- training ---------------------------------------------------------- */

cyl_train_params cyl_train_params_default(void)
{
    cyl_train_params p;
    p.min_bin_count = 2;
    p.min_bin_fraction = 0.002;
    p.uv_margin = 3;
    p.y_lo_fraction = 0.01;
    p.y_hi_fraction = 0.99;
    p.y_margin = 16;
    return p;
}

size_t cyl_train_workspace_size(void)
{
    return (65536u + 256u) * sizeof(uint32_t);
}

/* Smallest level whose cumulative count exceeds q * total. */
static unsigned quantile(const uint32_t *h, uint64_t total, double q)
{
    uint64_t acc = 0;
    double target = q * (double)total;
    unsigned i;
    for (i = 0; i < 256; i++) {
        acc += h[i];
        if ((double)acc > target) return i;
    }
    return 255;
}

cyl_status cyl_colortable_train(cyl_colortable *t, unsigned cls, const cyl_image *img,
                                const cyl_roi *region, const cyl_train_params *params,
                                void *work, size_t work_size, uint8_t box[6])
{
    cyl_train_params p = params ? *params : cyl_train_params_default();
    uint32_t *uvh, *yh;
    uint32_t x, y, thr;
    uint64_t n, kept = 0;
    unsigned u, v, ulo = 255, uhi = 0, vlo = 255, vhi = 0, ylo, yhi, m = p.uv_margin;
    cyl_roi r;
    cyl_status s;

    if (!t || !work) return CYL_ERR_ARG;
    if (cls >= CYL_MAX_CLASSES) return CYL_ERR_CLASS;
    if (work_size < cyl_train_workspace_size() || ((uintptr_t)work % sizeof(uint32_t)) != 0)
        return CYL_ERR_NOMEM;
    if (!(p.min_bin_fraction >= 0.0 && p.min_bin_fraction <= 1.0) ||
        !(p.y_lo_fraction >= 0.0 && p.y_lo_fraction <= p.y_hi_fraction && p.y_hi_fraction <= 1.0))
        return CYL_ERR_ARG;
    s = cyl_image_check(img);
    if (s != CYL_OK) return s;
    if (!cyl_roi_resolve(img, region, &r)) return CYL_ERR_SIZE;

    uvh = (uint32_t *)work;
    yh = uvh + 65536;
    memset(uvh, 0, cyl_train_workspace_size());
    for (y = r.y; y < r.y + r.height; y++)
        for (x = r.x; x < r.x + r.width; x++) {
            uint8_t Y, U, V;
            cyl_pixel_fetch(img, x, y, &Y, &U, &V);
            uvh[(unsigned)U << 8 | V]++;
        }
    n = (uint64_t)r.width * r.height;
    {
        double f = p.min_bin_fraction * (double)n;
        thr = (uint32_t)f;
        if ((double)thr < f) thr++;
        if (thr < p.min_bin_count) thr = p.min_bin_count;
        if (thr < 1) thr = 1;
    }
    for (u = 0; u < 256; u++)
        for (v = 0; v < 256; v++)
            if (uvh[u << 8 | v] >= thr) {
                if (u < ulo) ulo = u;
                if (u > uhi) uhi = u;
                if (v < vlo) vlo = v;
                if (v > vhi) vhi = v;
            }
    if (ulo > uhi) return CYL_ERR_EMPTY;
    /* Brightness of the pixels whose chrominance survived the threshold. */
    for (y = r.y; y < r.y + r.height; y++)
        for (x = r.x; x < r.x + r.width; x++) {
            uint8_t Y, U, V;
            cyl_pixel_fetch(img, x, y, &Y, &U, &V);
            if (uvh[(unsigned)U << 8 | V] >= thr) { yh[Y]++; kept++; }
        }
    ylo = quantile(yh, kept, p.y_lo_fraction);
    yhi = quantile(yh, kept, p.y_hi_fraction);
    ylo = ylo > p.y_margin ? ylo - p.y_margin : 0u;
    yhi = yhi + p.y_margin < 255u ? yhi + p.y_margin : 255u;
    ulo = ulo > m ? ulo - m : 0u;
    vlo = vlo > m ? vlo - m : 0u;
    uhi = uhi + m < 255u ? uhi + m : 255u;
    vhi = vhi + m < 255u ? vhi + m : 255u;
    if (box) {
        box[0] = (uint8_t)ulo; box[1] = (uint8_t)uhi; box[2] = (uint8_t)vlo;
        box[3] = (uint8_t)vhi; box[4] = (uint8_t)ylo; box[5] = (uint8_t)yhi;
    }
    return cyl_colortable_add_box(t, cls, (uint8_t)ylo, (uint8_t)yhi, (uint8_t)ulo, (uint8_t)uhi,
                                  (uint8_t)vlo, (uint8_t)vhi);
}

/* ---- serialisation ------------------------------------------------------- */

uint32_t cyl_crc32(uint32_t crc, const uint8_t *buf, size_t len)
{
    /* Nibble-wise table of the reflected polynomial 0xEDB88320. */
    static const uint32_t tab[16] = {
        0x00000000u, 0x1DB71064u, 0x3B6E20C8u, 0x26D930ACu, 0x76DC4190u, 0x6B6B51F4u,
        0x4DB26158u, 0x5005713Cu, 0xEDB88320u, 0xF00F9344u, 0xD6D6A3E8u, 0xCB61B38Cu,
        0x9B64C2B0u, 0x86D3D2D4u, 0xA00AE278u, 0xBDBDF21Cu };
    size_t i;
    crc = ~crc;
    for (i = 0; i < len; i++) {
        crc ^= buf[i];
        crc = (crc >> 4) ^ tab[crc & 15u];
        crc = (crc >> 4) ^ tab[crc & 15u];
    }
    return ~crc;
}

#define OFF_CLASSES 8u
#define CLASS_REC 20u
#define OFF_Y (OFF_CLASSES + CYL_MAX_CLASSES * CLASS_REC)
#define OFF_UV (OFF_Y + 256u)
#define OFF_CRC (OFF_UV + 65536u)
#define OFF_YUV OFF_CRC
#define OFF_CRC_V2 (OFF_YUV + CYL_YUV_CELLS)

cyl_status cyl_colortable_save(const cyl_colortable *t, uint8_t *buf, size_t cap, size_t *len)
{
    unsigned i;
    int v2;
    if (!t || !buf) return CYL_ERR_ARG;
    v2 = cyl_colortable_has_yuv(t) || has_weak(t);
    if (cap < (v2 ? CYL_TABLE_FILE_SIZE_V2 : CYL_TABLE_FILE_SIZE)) return CYL_ERR_NOMEM;
    memcpy(buf, "CYLT", 4);
    cyl_put_u16(buf + 4, (uint16_t)(v2 ? CYL_TABLE_FILE_VERSION_V2 : CYL_TABLE_FILE_VERSION));
    buf[6] = CYL_MAX_CLASSES;
    buf[7] = 0;
    for (i = 0; i < CYL_MAX_CLASSES; i++) {
        uint8_t *rec = buf + OFF_CLASSES + i * CLASS_REC;
        unsigned k;
        memset(rec, 0, CLASS_REC);
        for (k = 0; k < CYL_CLASS_NAME_LEN - 1u && t->name[i][k]; k++) rec[k] = (uint8_t)t->name[i][k];
        memcpy(rec + CYL_CLASS_NAME_LEN, t->rgb[i], 3);
        if (v2) rec[CLASS_REC - 1u] = (uint8_t)(t->weak_of[i] == CYL_CLASS_NONE ? 0u : t->weak_of[i] + 1u);
    }
    memcpy(buf + OFF_Y, t->y, 256);
    memcpy(buf + OFF_UV, t->uv, 65536);
    if (v2) {
        memcpy(buf + OFF_YUV, t->yuv, CYL_YUV_CELLS);
        cyl_put_u32(buf + OFF_CRC_V2, cyl_crc32(0, buf, OFF_CRC_V2));
    } else {
        cyl_put_u32(buf + OFF_CRC, cyl_crc32(0, buf, OFF_CRC));
    }
    if (len) *len = v2 ? CYL_TABLE_FILE_SIZE_V2 : CYL_TABLE_FILE_SIZE;
    return CYL_OK;
}

cyl_status cyl_colortable_load(cyl_colortable *t, const uint8_t *buf, size_t len)
{
    unsigned i, k, version;
    size_t size, crc_off;
    if (!t || (!buf && len)) return CYL_ERR_ARG;
    if (len < 4) return CYL_ERR_FILE_TRUNCATED;
    if (memcmp(buf, "CYLT", 4) != 0) return CYL_ERR_FILE_MAGIC;
    if (len < 8) return CYL_ERR_FILE_TRUNCATED;
    version = cyl_get_u16(buf + 4);
    if (version == CYL_TABLE_FILE_VERSION) {
        size = CYL_TABLE_FILE_SIZE;
        crc_off = OFF_CRC;
    } else if (version == CYL_TABLE_FILE_VERSION_V2) {
        size = CYL_TABLE_FILE_SIZE_V2;
        crc_off = OFF_CRC_V2;
    } else {
        return CYL_ERR_FILE_VERSION;
    }
    if (len < size) return CYL_ERR_FILE_TRUNCATED;
    if (cyl_crc32(0, buf, crc_off) != cyl_get_u32(buf + crc_off)) return CYL_ERR_FILE_CHECKSUM;
    if (len > size) return CYL_ERR_FILE_CORRUPT;
    if (buf[6] != CYL_MAX_CLASSES || buf[7] != 0) return CYL_ERR_FILE_CORRUPT;
    for (i = 0; i < CYL_MAX_CLASSES; i++) {
        const uint8_t *rec = buf + OFF_CLASSES + i * CLASS_REC;
        int terminated = 0;
        for (k = 0; k < CYL_CLASS_NAME_LEN; k++)
            if (rec[k] == 0) { terminated = 1; break; }
        if (!terminated) return CYL_ERR_FILE_CORRUPT;
        if (version == CYL_TABLE_FILE_VERSION ? rec[CLASS_REC - 1u] != 0 : rec[CLASS_REC - 1u] > CYL_MAX_CLASSES)
            return CYL_ERR_FILE_CORRUPT;
        for (; k < CYL_CLASS_NAME_LEN; k++)
            if (rec[k] != 0) return CYL_ERR_FILE_CORRUPT; /* padding must be zero */
    }
    if (version == CYL_TABLE_FILE_VERSION_V2) {
        /* weak classes: not their own, and one level only */
        for (i = 0; i < CYL_MAX_CLASSES; i++) {
            unsigned w = buf[OFF_CLASSES + i * CLASS_REC + CLASS_REC - 1u];
            if (w == 0) continue;
            if (w - 1u == i || buf[OFF_CLASSES + (w - 1u) * CLASS_REC + CLASS_REC - 1u] != 0) return CYL_ERR_FILE_CORRUPT;
        }
    }
    for (i = 0; i < CYL_MAX_CLASSES; i++) {
        const uint8_t *rec = buf + OFF_CLASSES + i * CLASS_REC;
        t->weak_of[i] = (uint8_t)(version == CYL_TABLE_FILE_VERSION || rec[CLASS_REC - 1u] == 0
                                      ? CYL_CLASS_NONE : rec[CLASS_REC - 1u] - 1u);
        memcpy(t->name[i], rec, CYL_CLASS_NAME_LEN);
        memcpy(t->rgb[i], rec + CYL_CLASS_NAME_LEN, 3);
    }
    memcpy(t->y, buf + OFF_Y, 256);
    memcpy(t->uv, buf + OFF_UV, 65536);
    if (version == CYL_TABLE_FILE_VERSION_V2)
        memcpy(t->yuv, buf + OFF_YUV, CYL_YUV_CELLS);
    else
        memset(t->yuv, 0xFF, CYL_YUV_CELLS);
    cyl_colortable_refresh(t);
    return CYL_OK;
}
