/* SPDX-License-Identifier: BSD-3-Clause */
/* The vector background skip of cyl_segment() (internal, included by segment.c only).
 *
 * Where no run is open, the scalar path reads each chroma pair's uv entry to find the
 * next pixel that may be coloured. The vector path does the same test 16 chroma pairs
 * (32 pixels) at a time on a coarse map, cyl_colortable.chroma_any: one bit per 16x16
 * block of (U, V), set when any uv entry in the block is non-zero. A pair whose block
 * bit is clear is certainly background, so skipping it cannot change the result; a pair
 * whose bit is set is handed back to the scalar path, which decides it exactly. The
 * results are therefore bit-identical to the scalar path by construction.
 *
 * The block bit of a pair is two 16-entry table lookups (byte shuffles: SSSE3 pshufb,
 * NEON tbl): row = chroma_any[U >> 7][V >> 4], bit = 1 << ((U >> 4) & 7).
 *
 * Paths: x86 (GCC or Clang) AVX2 (32 pairs at a time) or SSSE3 (16), chosen at run time
 * from the CPU (or fixed, when the build targets them; -DCYL_SKIP_MAX_X86=1 stops at
 * SSSE3); AArch64 NEON and ARMv7 NEON (when the build enables NEON).
 * Everything else, Cortex-M included, and any build with -DCYL_NO_SIMD, has only the
 * scalar path.
 *
 * Each skip function returns the first pair index q in [p, n) that may be coloured
 * (block bit set) among the whole blocks of 16 pairs it examined; when fewer than 16
 * pairs are left it stops and returns the first pair it did not examine. It reads only
 * the chroma bytes of pairs [p, q] rounded up to its block: no byte past pair n - 1.
 */
#ifndef CYL_SEGMENT_VECTOR_H
#define CYL_SEGMENT_VECTOR_H

#include <stdint.h>
#include "cyl/colortable.h"

/* u: pointer to pair 0's bytes (packed formats: the row; NV12: the interleaved chroma row;
 * I420: the U row), v: I420's V row (else unused). */
typedef uint32_t (*cyl_skip_fn)(const uint8_t *u, const uint8_t *v, const uint8_t (*map)[16],
                                uint32_t p, uint32_t n);

/* Run extension (AVX2 only: it needs gathers): with a run of class cur open at pair p, the first
 * pair index q in [p, n) at which some pixel is not of class cur, examining 8 pairs (16 pixels)
 * at a time; when fewer than 8 pairs are left it returns the first pair it did not examine.
 * y: the luma row (packed formats: the row), u, v: as for cyl_skip_fn. */
typedef uint32_t (*cyl_extend_fn)(const cyl_colortable *t, const uint8_t *y, const uint8_t *u,
                                  const uint8_t *v, uint32_t p, uint32_t n, unsigned cur);

typedef struct cyl_skip_set {
    cyl_skip_fn yuyv, uyvy, nv12, i420;
    cyl_extend_fn ext_yuyv, ext_uyvy, ext_nv12, ext_i420;
    const char *name;
} cyl_skip_set;

#if !defined(CYL_NO_SIMD) && defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#define CYL_SKIP_X86 1
#include <immintrin.h>
#if defined(__SSSE3__)
#define CYL_SKIP_TARGET
#else
#define CYL_SKIP_TARGET __attribute__((target("ssse3")))
#endif

/* bits of the candidate pairs among 16, from their U >> 4 and V >> 4 nibbles */
CYL_SKIP_TARGET static inline unsigned cyl_skip_hits(__m128i un, __m128i vn, const uint8_t (*map)[16])
{
    const __m128i bitlo = _mm_setr_epi8(1, 2, 4, 8, 16, 32, 64, (char)128, 0, 0, 0, 0, 0, 0, 0, 0);
    const __m128i bithi = _mm_setr_epi8(0, 0, 0, 0, 0, 0, 0, 0, 1, 2, 4, 8, 16, 32, 64, (char)128);
    const __m128i lo = _mm_loadu_si128((const __m128i *)(const void *)map[0]);
    const __m128i hi = _mm_loadu_si128((const __m128i *)(const void *)map[1]);
    __m128i a = _mm_and_si128(_mm_shuffle_epi8(lo, vn), _mm_shuffle_epi8(bitlo, un));
    __m128i b = _mm_and_si128(_mm_shuffle_epi8(hi, vn), _mm_shuffle_epi8(bithi, un));
    __m128i h = _mm_or_si128(a, b);
    return (unsigned)_mm_movemask_epi8(_mm_cmpeq_epi8(h, _mm_setzero_si128())) ^ 0xFFFFu;
}

/* 4-byte pairs (YUYV, UYVY): U at byte UO of each pair, V at byte UO + 2. A byte shuffle per
 * 16 bytes gathers 4 U then 4 V; two unpacks put 16 U in one register and 16 V in another,
 * in pair order. */
#define CYL_SKIP_PACKED(NAME, UO)                                                              \
    CYL_SKIP_TARGET static uint32_t NAME(const uint8_t *u, const uint8_t *v,                   \
                                         const uint8_t (*map)[16], uint32_t p, uint32_t n)     \
    {                                                                                          \
        const __m128i nib = _mm_set1_epi8(0xF);                                                \
        const __m128i sh = _mm_setr_epi8(UO, UO + 4, UO + 8, UO + 12, UO + 2, UO + 6, UO + 10, \
                                         UO + 14, -1, -1, -1, -1, -1, -1, -1, -1);             \
        (void)v;                                                                               \
        for (; p + 16u <= n; p += 16u) {                                                       \
            const uint8_t *b = u + 4u * (size_t)p;                                             \
            __m128i w0 = _mm_shuffle_epi8(_mm_loadu_si128((const __m128i *)(const void *)b), sh);        \
            __m128i w1 = _mm_shuffle_epi8(_mm_loadu_si128((const __m128i *)(const void *)(b + 16)), sh); \
            __m128i w2 = _mm_shuffle_epi8(_mm_loadu_si128((const __m128i *)(const void *)(b + 32)), sh); \
            __m128i w3 = _mm_shuffle_epi8(_mm_loadu_si128((const __m128i *)(const void *)(b + 48)), sh); \
            __m128i a = _mm_unpacklo_epi32(w0, w1), c = _mm_unpacklo_epi32(w2, w3);             \
            __m128i un = _mm_and_si128(_mm_srli_epi16(_mm_unpacklo_epi64(a, c), 4), nib);      \
            __m128i vn = _mm_and_si128(_mm_srli_epi16(_mm_unpackhi_epi64(a, c), 4), nib);      \
            unsigned m = cyl_skip_hits(un, vn, map);                                           \
            if (m) return p + (uint32_t)__builtin_ctz(m);                                      \
        }                                                                                      \
        return p;                                                                              \
    }
CYL_SKIP_PACKED(cyl_skip_yuyv_ssse3, 1)
CYL_SKIP_PACKED(cyl_skip_uyvy_ssse3, 0)
#undef CYL_SKIP_PACKED

CYL_SKIP_TARGET static uint32_t cyl_skip_nv12_ssse3(const uint8_t *u, const uint8_t *v,
                                                    const uint8_t (*map)[16], uint32_t p, uint32_t n)
{
    const __m128i nib = _mm_set1_epi16(0xF);
    (void)v;
    for (; p + 16u <= n; p += 16u) {
        const uint8_t *b = u + 2u * (size_t)p;
        __m128i w0 = _mm_loadu_si128((const __m128i *)(const void *)b);
        __m128i w1 = _mm_loadu_si128((const __m128i *)(const void *)(b + 16));
        __m128i un = _mm_packus_epi16(_mm_and_si128(_mm_srli_epi16(w0, 4), nib),
                                      _mm_and_si128(_mm_srli_epi16(w1, 4), nib));
        __m128i vn = _mm_packus_epi16(_mm_srli_epi16(w0, 12), _mm_srli_epi16(w1, 12));
        unsigned m = cyl_skip_hits(un, vn, map);
        if (m) return p + (uint32_t)__builtin_ctz(m);
    }
    return p;
}

CYL_SKIP_TARGET static uint32_t cyl_skip_i420_ssse3(const uint8_t *u, const uint8_t *v,
                                                    const uint8_t (*map)[16], uint32_t p, uint32_t n)
{
    const __m128i nib = _mm_set1_epi8(0xF);
    for (; p + 16u <= n; p += 16u) {
        __m128i un = _mm_and_si128(_mm_srli_epi16(_mm_loadu_si128((const __m128i *)(const void *)(u + p)), 4), nib);
        __m128i vn = _mm_and_si128(_mm_srli_epi16(_mm_loadu_si128((const __m128i *)(const void *)(v + p)), 4), nib);
        unsigned m = cyl_skip_hits(un, vn, map);
        if (m) return p + (uint32_t)__builtin_ctz(m);
    }
    return p;
}

/* AVX2: 32 pairs at a time. The in-lane shuffles and packs leave the pairs permuted (U and V
 * alike), which is enough to tell that a block has no candidate; a block that has one goes to
 * the SSSE3 code, which finds the first in pair order. */
#if defined(__AVX2__)
#define CYL_SKIP_TARGET_AVX2
#else
#define CYL_SKIP_TARGET_AVX2 __attribute__((target("avx2")))
#endif

CYL_SKIP_TARGET_AVX2 static inline int cyl_skip_none256(__m256i un, __m256i vn, const uint8_t (*map)[16])
{
    const __m256i bitlo = _mm256_setr_epi8(1, 2, 4, 8, 16, 32, 64, (char)128, 0, 0, 0, 0, 0, 0, 0, 0,
                                           1, 2, 4, 8, 16, 32, 64, (char)128, 0, 0, 0, 0, 0, 0, 0, 0);
    const __m256i bithi = _mm256_setr_epi8(0, 0, 0, 0, 0, 0, 0, 0, 1, 2, 4, 8, 16, 32, 64, (char)128,
                                           0, 0, 0, 0, 0, 0, 0, 0, 1, 2, 4, 8, 16, 32, 64, (char)128);
    const __m256i lo = _mm256_broadcastsi128_si256(_mm_loadu_si128((const __m128i *)(const void *)map[0]));
    const __m256i hi = _mm256_broadcastsi128_si256(_mm_loadu_si128((const __m128i *)(const void *)map[1]));
    __m256i a = _mm256_and_si256(_mm256_shuffle_epi8(lo, vn), _mm256_shuffle_epi8(bitlo, un));
    __m256i b = _mm256_and_si256(_mm256_shuffle_epi8(hi, vn), _mm256_shuffle_epi8(bithi, un));
    __m256i h = _mm256_or_si256(a, b);
    return _mm256_testz_si256(h, h);
}

#define CYL_SKIP_PACKED_AVX2(NAME, UO, FINE)                                                   \
    CYL_SKIP_TARGET_AVX2 static uint32_t NAME(const uint8_t *u, const uint8_t *v,              \
                                              const uint8_t (*map)[16], uint32_t p, uint32_t n) \
    {                                                                                          \
        const __m256i nib = _mm256_set1_epi8(0xF);                                             \
        const __m256i sh = _mm256_setr_epi8(UO, UO + 4, UO + 8, UO + 12, UO + 2, UO + 6, UO + 10, \
                                            UO + 14, -1, -1, -1, -1, -1, -1, -1, -1,           \
                                            UO, UO + 4, UO + 8, UO + 12, UO + 2, UO + 6, UO + 10, \
                                            UO + 14, -1, -1, -1, -1, -1, -1, -1, -1);          \
        for (; p + 32u <= n; p += 32u) {                                                       \
            const uint8_t *b = u + 4u * (size_t)p;                                             \
            __m256i w0 = _mm256_shuffle_epi8(_mm256_loadu_si256((const __m256i *)(const void *)b), sh);        \
            __m256i w1 = _mm256_shuffle_epi8(_mm256_loadu_si256((const __m256i *)(const void *)(b + 32)), sh); \
            __m256i w2 = _mm256_shuffle_epi8(_mm256_loadu_si256((const __m256i *)(const void *)(b + 64)), sh); \
            __m256i w3 = _mm256_shuffle_epi8(_mm256_loadu_si256((const __m256i *)(const void *)(b + 96)), sh); \
            __m256i a = _mm256_unpacklo_epi32(w0, w1), c = _mm256_unpacklo_epi32(w2, w3);      \
            __m256i un = _mm256_and_si256(_mm256_srli_epi16(_mm256_unpacklo_epi64(a, c), 4), nib); \
            __m256i vn = _mm256_and_si256(_mm256_srli_epi16(_mm256_unpackhi_epi64(a, c), 4), nib); \
            if (!cyl_skip_none256(un, vn, map)) {                                              \
                uint32_t q;                                                                    \
                _mm256_zeroupper();                                                            \
                q = FINE(u, v, map, p, p + 32u);                                               \
                if (q < p + 32u) return q;                                                     \
            }                                                                                  \
        }                                                                                      \
        _mm256_zeroupper();                                                                    \
        return FINE(u, v, map, p, n);                                                          \
    }
CYL_SKIP_PACKED_AVX2(cyl_skip_yuyv_avx2, 1, cyl_skip_yuyv_ssse3)
CYL_SKIP_PACKED_AVX2(cyl_skip_uyvy_avx2, 0, cyl_skip_uyvy_ssse3)
#undef CYL_SKIP_PACKED_AVX2

CYL_SKIP_TARGET_AVX2 static uint32_t cyl_skip_nv12_avx2(const uint8_t *u, const uint8_t *v,
                                                        const uint8_t (*map)[16], uint32_t p, uint32_t n)
{
    const __m256i nib = _mm256_set1_epi16(0xF);
    for (; p + 32u <= n; p += 32u) {
        const uint8_t *b = u + 2u * (size_t)p;
        __m256i w0 = _mm256_loadu_si256((const __m256i *)(const void *)b);
        __m256i w1 = _mm256_loadu_si256((const __m256i *)(const void *)(b + 32));
        __m256i un = _mm256_packus_epi16(_mm256_and_si256(_mm256_srli_epi16(w0, 4), nib),
                                         _mm256_and_si256(_mm256_srli_epi16(w1, 4), nib));
        __m256i vn = _mm256_packus_epi16(_mm256_srli_epi16(w0, 12), _mm256_srli_epi16(w1, 12));
        if (!cyl_skip_none256(un, vn, map)) {
            uint32_t q;
            _mm256_zeroupper();   /* the SSSE3 code is not VEX-encoded: no transition penalty */
            q = cyl_skip_nv12_ssse3(u, v, map, p, p + 32u);
            if (q < p + 32u) return q;
        }
    }
    _mm256_zeroupper();
    return cyl_skip_nv12_ssse3(u, v, map, p, n);
}

CYL_SKIP_TARGET_AVX2 static uint32_t cyl_skip_i420_avx2(const uint8_t *u, const uint8_t *v,
                                                        const uint8_t (*map)[16], uint32_t p, uint32_t n)
{
    const __m256i nib = _mm256_set1_epi8(0xF);
    for (; p + 32u <= n; p += 32u) {
        __m256i un = _mm256_and_si256(_mm256_srli_epi16(_mm256_loadu_si256((const __m256i *)(const void *)(u + p)), 4), nib);
        __m256i vn = _mm256_and_si256(_mm256_srli_epi16(_mm256_loadu_si256((const __m256i *)(const void *)(v + p)), 4), nib);
        if (!cyl_skip_none256(un, vn, map)) {
            uint32_t q;
            _mm256_zeroupper();   /* the SSSE3 code is not VEX-encoded: no transition penalty */
            q = cyl_skip_i420_ssse3(u, v, map, p, p + 32u);
            if (q < p + 32u) return q;
        }
    }
    _mm256_zeroupper();
    return cyl_skip_i420_ssse3(u, v, map, p, n);
}

/* Class masks of 16 pixels (even pixels Y0, odd Y1; chroma U, V per pair; 32-bit lanes) by the
 * table's rule (cyl_colortable_mask, with t->lookup's parts), compared with class cur: bit i of
 * the result set when pair i has a pixel of another class. The gathers read 4 bytes from each
 * entry, so up to 3 bytes after a table: still inside cyl_colortable (y follows uv, yuv follows
 * y, lookup and weak_of follow yuv). */
CYL_SKIP_TARGET_AVX2 static inline unsigned cyl_run_breaks(const cyl_colortable *t, __m256i Y0, __m256i Y1,
                                                           __m256i U, __m256i V, unsigned cur)
{
    const __m256i low = _mm256_set1_epi32((int)((2u << cur) - 1u)), bit = _mm256_set1_epi32((int)(1u << cur));
    __m256i m0, m1;
    unsigned ok;
    if (t->lookup & CYL_LOOKUP_UV_Y) {
        const __m256i muv = _mm256_i32gather_epi32((const int *)(const void *)&t->uv[0][0],
                                                   _mm256_or_si256(_mm256_slli_epi32(U, 8), V), 1);
        m0 = _mm256_and_si256(muv, _mm256_i32gather_epi32((const int *)(const void *)t->y, Y0, 1));
        m1 = _mm256_and_si256(muv, _mm256_i32gather_epi32((const int *)(const void *)t->y, Y1, 1));
    } else {
        m0 = m1 = _mm256_set1_epi32(t->live);
    }
    if (t->lookup & CYL_LOOKUP_YUV) {
        const int *yuv = (const int *)(const void *)&t->yuv[0][0][0];
        const __m256i c = _mm256_or_si256(_mm256_slli_epi32(_mm256_srli_epi32(U, CYL_YUV_CSHIFT), 6),
                                          _mm256_srli_epi32(V, CYL_YUV_CSHIFT));
        m0 = _mm256_and_si256(m0, _mm256_i32gather_epi32(yuv, _mm256_or_si256(c, _mm256_slli_epi32(
                                      _mm256_srli_epi32(Y0, CYL_YUV_YSHIFT), 12)), 1));
        m1 = _mm256_and_si256(m1, _mm256_i32gather_epi32(yuv, _mm256_or_si256(c, _mm256_slli_epi32(
                                      _mm256_srli_epi32(Y1, CYL_YUV_YSHIFT), 12)), 1));
    }
    /* lowest set bit == cur  <=>  (mask & ((2 << cur) - 1)) == 1 << cur */
    ok = (unsigned)_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(_mm256_and_si256(m0, low), bit))) &
         (unsigned)_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(_mm256_and_si256(m1, low), bit)));
    return ~ok & 0xFFu;
}

#define CYL_EXTEND_AVX2(NAME, LOAD)                                                            \
    CYL_SKIP_TARGET_AVX2 static uint32_t NAME(const cyl_colortable *t, const uint8_t *y,       \
                                              const uint8_t *u, const uint8_t *v, uint32_t p,  \
                                              uint32_t n, unsigned cur)                        \
    {                                                                                          \
        const __m256i ff = _mm256_set1_epi32(0xFF);                                            \
        (void)u; (void)v; (void)ff;                                                            \
        for (; p + 8u <= n; p += 8u) {                                                         \
            __m256i Y0, Y1, U, V;                                                              \
            unsigned b;                                                                        \
            LOAD                                                                               \
            b = cyl_run_breaks(t, Y0, Y1, U, V, cur);                                          \
            if (b) { _mm256_zeroupper(); return p + (uint32_t)__builtin_ctz(b); }              \
        }                                                                                      \
        _mm256_zeroupper();                                                                    \
        return p;                                                                              \
    }
/* packed: each 32-bit lane is one pair's 4 bytes */
CYL_EXTEND_AVX2(cyl_extend_yuyv_avx2, {
    const __m256i w = _mm256_loadu_si256((const __m256i *)(const void *)(y + 4u * (size_t)p));
    Y0 = _mm256_and_si256(w, ff); U = _mm256_and_si256(_mm256_srli_epi32(w, 8), ff);
    Y1 = _mm256_and_si256(_mm256_srli_epi32(w, 16), ff); V = _mm256_srli_epi32(w, 24); })
CYL_EXTEND_AVX2(cyl_extend_uyvy_avx2, {
    const __m256i w = _mm256_loadu_si256((const __m256i *)(const void *)(y + 4u * (size_t)p));
    U = _mm256_and_si256(w, ff); Y0 = _mm256_and_si256(_mm256_srli_epi32(w, 8), ff);
    V = _mm256_and_si256(_mm256_srli_epi32(w, 16), ff); Y1 = _mm256_srli_epi32(w, 24); })
/* planar luma: 16 bytes widened to 8 lanes of two pixels each */
CYL_EXTEND_AVX2(cyl_extend_nv12_avx2, {
    const __m256i l = _mm256_cvtepu16_epi32(_mm_loadu_si128((const __m128i *)(const void *)(y + 2u * (size_t)p)));
    const __m256i c = _mm256_cvtepu16_epi32(_mm_loadu_si128((const __m128i *)(const void *)(u + 2u * (size_t)p)));
    Y0 = _mm256_and_si256(l, ff); Y1 = _mm256_srli_epi32(l, 8);
    U = _mm256_and_si256(c, ff); V = _mm256_srli_epi32(c, 8); })
CYL_EXTEND_AVX2(cyl_extend_i420_avx2, {
    const __m256i l = _mm256_cvtepu16_epi32(_mm_loadu_si128((const __m128i *)(const void *)(y + 2u * (size_t)p)));
    Y0 = _mm256_and_si256(l, ff); Y1 = _mm256_srli_epi32(l, 8);
    U = _mm256_cvtepu8_epi32(_mm_loadl_epi64((const __m128i *)(const void *)(u + p)));
    V = _mm256_cvtepu8_epi32(_mm_loadl_epi64((const __m128i *)(const void *)(v + p))); })
#undef CYL_EXTEND_AVX2

/* CYL_SKIP_MAX_X86 (build option): 1 = SSSE3 at most, 2 = AVX2 at most (default). */
#ifndef CYL_SKIP_MAX_X86
#define CYL_SKIP_MAX_X86 2
#endif

static inline int cyl_skip_have_avx2(void)
{
#if defined(__AVX2__)
    return CYL_SKIP_MAX_X86 >= 2;
#else
    return CYL_SKIP_MAX_X86 >= 2 && __builtin_cpu_supports("avx2");
#endif
}

static inline int cyl_skip_have_ssse3(void)
{
#if defined(__SSSE3__)
    return 1;
#else
    return __builtin_cpu_supports("ssse3") != 0;
#endif
}

static inline cyl_skip_set cyl_skip_select(void)
{
    cyl_skip_set s = { 0, 0, 0, 0, 0, 0, 0, 0, "scalar" };
    if (cyl_skip_have_avx2()) {
        s.yuyv = cyl_skip_yuyv_avx2;
        s.uyvy = cyl_skip_uyvy_avx2;
        s.nv12 = cyl_skip_nv12_avx2;
        s.i420 = cyl_skip_i420_avx2;
        s.ext_yuyv = cyl_extend_yuyv_avx2;
        s.ext_uyvy = cyl_extend_uyvy_avx2;
        s.ext_nv12 = cyl_extend_nv12_avx2;
        s.ext_i420 = cyl_extend_i420_avx2;
        s.name = "avx2";
    } else if (cyl_skip_have_ssse3()) {
        s.yuyv = cyl_skip_yuyv_ssse3;
        s.uyvy = cyl_skip_uyvy_ssse3;
        s.nv12 = cyl_skip_nv12_ssse3;
        s.i420 = cyl_skip_i420_ssse3;
        s.name = "ssse3";
    }
    return s;
}

#elif !defined(CYL_NO_SIMD) && defined(__ARM_NEON) && (defined(__aarch64__) || defined(__GNUC__))
#define CYL_SKIP_NEON 1
#include <arm_neon.h>

#if defined(__aarch64__)
static inline uint8x16_t cyl_tbl16(uint8x16_t t, uint8x16_t i) { return vqtbl1q_u8(t, i); }
#else
static inline uint8x16_t cyl_tbl16(uint8x16_t t, uint8x16_t i)
{
    uint8x8x2_t tt;
    tt.val[0] = vget_low_u8(t);
    tt.val[1] = vget_high_u8(t);
    return vcombine_u8(vtbl2_u8(tt, vget_low_u8(i)), vtbl2_u8(tt, vget_high_u8(i)));
}
#endif

/* index of the first candidate pair among 16 (16 if none), from U >> 4 and V >> 4 */
static inline unsigned cyl_skip_first(uint8x16_t un, uint8x16_t vn, const uint8_t (*map)[16])
{
    static const uint8_t bits[2][16] = { { 1, 2, 4, 8, 16, 32, 64, 128, 0, 0, 0, 0, 0, 0, 0, 0 },
                                         { 0, 0, 0, 0, 0, 0, 0, 0, 1, 2, 4, 8, 16, 32, 64, 128 } };
    uint8x16_t a = vandq_u8(cyl_tbl16(vld1q_u8(map[0]), vn), cyl_tbl16(vld1q_u8(bits[0]), un));
    uint8x16_t b = vandq_u8(cyl_tbl16(vld1q_u8(map[1]), vn), cyl_tbl16(vld1q_u8(bits[1]), un));
    uint8x16_t h = vtstq_u8(vorrq_u8(a, b), vorrq_u8(a, b));   /* 0xFF where a candidate */
    /* 4 bits per lane, in lane order */
    uint64_t m = vget_lane_u64(vreinterpret_u64_u8(vshrn_n_u16(vreinterpretq_u16_u8(h), 4)), 0);
    return m ? (unsigned)__builtin_ctzll(m) >> 2 : 16u;
}

#define CYL_SKIP_NEON_FN(NAME, LOAD)                                                           \
    static uint32_t NAME(const uint8_t *u, const uint8_t *v, const uint8_t (*map)[16],        \
                         uint32_t p, uint32_t n)                                               \
    {                                                                                          \
        (void)v;                                                                               \
        for (; p + 16u <= n; p += 16u) {                                                       \
            uint8x16_t un, vn;                                                                 \
            unsigned f;                                                                        \
            LOAD                                                                               \
            f = cyl_skip_first(vshrq_n_u8(un, 4), vshrq_n_u8(vn, 4), map);                     \
            if (f < 16u) return p + f;                                                         \
        }                                                                                      \
        return p;                                                                              \
    }
CYL_SKIP_NEON_FN(cyl_skip_yuyv_neon, { uint8x16x4_t q = vld4q_u8(u + 4u * (size_t)p); un = q.val[1]; vn = q.val[3]; })
CYL_SKIP_NEON_FN(cyl_skip_uyvy_neon, { uint8x16x4_t q = vld4q_u8(u + 4u * (size_t)p); un = q.val[0]; vn = q.val[2]; })
CYL_SKIP_NEON_FN(cyl_skip_nv12_neon, { uint8x16x2_t q = vld2q_u8(u + 2u * (size_t)p); un = q.val[0]; vn = q.val[1]; })
CYL_SKIP_NEON_FN(cyl_skip_i420_neon, { un = vld1q_u8(u + p); vn = vld1q_u8(v + p); })
#undef CYL_SKIP_NEON_FN

static inline cyl_skip_set cyl_skip_select(void)
{
    cyl_skip_set s = { cyl_skip_yuyv_neon, cyl_skip_uyvy_neon, cyl_skip_nv12_neon, cyl_skip_i420_neon,
                       0, 0, 0, 0, "neon" };
    return s;
}

#else
static inline cyl_skip_set cyl_skip_select(void)
{
    cyl_skip_set s = { 0, 0, 0, 0, 0, 0, 0, 0, "scalar" };
    return s;
}
#endif

#endif /* CYL_SEGMENT_VECTOR_H */
