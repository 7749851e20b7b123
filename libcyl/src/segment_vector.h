/* SPDX-License-Identifier: BSD-3-Clause */
/* The vector background skip and run extension of cyl_segment() (internal, included by segment.c
 * only).
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
 * The AVX2 skip examines a range of at least 32 pairs to its end (its last block is the
 * range's last 32 pairs, reading up to 31 pairs before p, which are not reported) and
 * returns n when no pair is a candidate.
 *
 * Inside a run the vector path tests whole blocks of pairs against the run's class's inner box
 * (cyl_colortable.inner_lo / inner_hi, computed by cyl_colortable_refresh(): colours that are
 * certainly of that class) with byte compares, and hands the first pair outside the box to an exact
 * test. As with the skip, the box can only say "certainly", so the runs are the scalar path's.
 */
#ifndef CYL_SEGMENT_VECTOR_H
#define CYL_SEGMENT_VECTOR_H

#include <stdint.h>
#include "cyl/colortable.h"
#include "lowbit.h"

/* u: pointer to pair 0's bytes (packed formats: the row; NV12: the interleaved chroma row;
 * I420: the U row), v: I420's V row (else unused). */
typedef uint32_t (*cyl_skip_fn)(const uint8_t *u, const uint8_t *v, const uint8_t (*map)[16],
                                uint32_t p, uint32_t n);

/* Run extension: with a run of class cur open at pair p, a pair index q in [p, n) such that every
 * pixel of pairs [p, q) is of class cur, found a block of 8 (x86) or 16 (NEON) pairs at a time with
 * the class's inner box. AVX2 returns the first pair of another class (it decides the pairs outside
 * the box exactly, by gathers); SSE and NEON return the first pair outside the box, which the scalar
 * path decides. When less than a block is left it returns the first pair it did not examine.
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
 * alike), which is enough to tell that a block has no candidate; in a block that has one, a
 * cross-lane permutation puts the hits back in pair order and the first is the answer. A range of
 * fewer than 32 pairs goes to the SSSE3 code (see CYL_SKIP_AVX2). */
#if defined(__AVX2__)
#define CYL_SKIP_TARGET_AVX2
#else
#define CYL_SKIP_TARGET_AVX2 __attribute__((target("avx2")))
#endif

/* The candidate bytes among 32 (0xFF where the block bit is set), in the order the lanes hold them. */
CYL_SKIP_TARGET_AVX2 static inline __m256i cyl_skip_hits256(__m256i un, __m256i vn, __m256i lo, __m256i hi)
{
    const __m256i bitlo = _mm256_setr_epi8(1, 2, 4, 8, 16, 32, 64, (char)128, 0, 0, 0, 0, 0, 0, 0, 0,
                                           1, 2, 4, 8, 16, 32, 64, (char)128, 0, 0, 0, 0, 0, 0, 0, 0);
    const __m256i bithi = _mm256_setr_epi8(0, 0, 0, 0, 0, 0, 0, 0, 1, 2, 4, 8, 16, 32, 64, (char)128,
                                           0, 0, 0, 0, 0, 0, 0, 0, 1, 2, 4, 8, 16, 32, 64, (char)128);
    __m256i a = _mm256_and_si256(_mm256_shuffle_epi8(lo, vn), _mm256_shuffle_epi8(bitlo, un));
    __m256i b = _mm256_and_si256(_mm256_shuffle_epi8(hi, vn), _mm256_shuffle_epi8(bithi, un));
    return _mm256_or_si256(a, b);
}

/* one bit a pair, in pair order, from hit bytes already in pair order */
CYL_SKIP_TARGET_AVX2 static inline unsigned cyl_skip_bits256(__m256i h)
{
    return ~(unsigned)_mm256_movemask_epi8(_mm256_cmpeq_epi8(h, _mm256_setzero_si256()));
}

/* The coarse map's hit bytes of the 32 pairs from pair p (non-zero where the pair's block bit is
 * set), in the order the lanes hold them; lo, hi: the map's two halves in both lanes. */
#define CYL_HITS_PACKED_AVX2(NAME, UO)                                                         \
    CYL_SKIP_TARGET_AVX2 static inline __m256i NAME(const uint8_t *u, const uint8_t *v,        \
                                                    __m256i lo, __m256i hi, uint32_t p)        \
    {                                                                                          \
        const __m256i nib = _mm256_set1_epi8(0xF);                                             \
        const __m256i sh = _mm256_setr_epi8(UO, UO + 4, UO + 8, UO + 12, UO + 2, UO + 6, UO + 10, \
                                            UO + 14, -1, -1, -1, -1, -1, -1, -1, -1,           \
                                            UO, UO + 4, UO + 8, UO + 12, UO + 2, UO + 6, UO + 10, \
                                            UO + 14, -1, -1, -1, -1, -1, -1, -1, -1);          \
        const uint8_t *b = u + 4u * (size_t)p;                                                 \
        __m256i w0 = _mm256_shuffle_epi8(_mm256_loadu_si256((const __m256i *)(const void *)b), sh);        \
        __m256i w1 = _mm256_shuffle_epi8(_mm256_loadu_si256((const __m256i *)(const void *)(b + 32)), sh); \
        __m256i w2 = _mm256_shuffle_epi8(_mm256_loadu_si256((const __m256i *)(const void *)(b + 64)), sh); \
        __m256i w3 = _mm256_shuffle_epi8(_mm256_loadu_si256((const __m256i *)(const void *)(b + 96)), sh); \
        __m256i a = _mm256_unpacklo_epi32(w0, w1), c = _mm256_unpacklo_epi32(w2, w3);          \
        __m256i un = _mm256_and_si256(_mm256_srli_epi16(_mm256_unpacklo_epi64(a, c), 4), nib); \
        __m256i vn = _mm256_and_si256(_mm256_srli_epi16(_mm256_unpackhi_epi64(a, c), 4), nib); \
        (void)v;                                                                               \
        return cyl_skip_hits256(un, vn, lo, hi);                                               \
    }
CYL_HITS_PACKED_AVX2(cyl_hits_yuyv_avx2, 1)
CYL_HITS_PACKED_AVX2(cyl_hits_uyvy_avx2, 0)
#undef CYL_HITS_PACKED_AVX2

CYL_SKIP_TARGET_AVX2 static inline __m256i cyl_hits_nv12_avx2(const uint8_t *u, const uint8_t *v,
                                                              __m256i lo, __m256i hi, uint32_t p)
{
    const __m256i nib = _mm256_set1_epi16(0xF);
    const uint8_t *b = u + 2u * (size_t)p;
    __m256i w0 = _mm256_loadu_si256((const __m256i *)(const void *)b);
    __m256i w1 = _mm256_loadu_si256((const __m256i *)(const void *)(b + 32));
    __m256i un = _mm256_packus_epi16(_mm256_and_si256(_mm256_srli_epi16(w0, 4), nib),
                                     _mm256_and_si256(_mm256_srli_epi16(w1, 4), nib));
    __m256i vn = _mm256_packus_epi16(_mm256_srli_epi16(w0, 12), _mm256_srli_epi16(w1, 12));
    (void)v;
    return cyl_skip_hits256(un, vn, lo, hi);
}

CYL_SKIP_TARGET_AVX2 static inline __m256i cyl_hits_i420_avx2(const uint8_t *u, const uint8_t *v,
                                                              __m256i lo, __m256i hi, uint32_t p)
{
    const __m256i nib = _mm256_set1_epi8(0xF);
    __m256i un = _mm256_and_si256(_mm256_srli_epi16(_mm256_loadu_si256((const __m256i *)(const void *)(u + p)), 4), nib);
    __m256i vn = _mm256_and_si256(_mm256_srli_epi16(_mm256_loadu_si256((const __m256i *)(const void *)(v + p)), 4), nib);
    return cyl_skip_hits256(un, vn, lo, hi);
}

/* A block's hit bytes put back in pair order, one bit a pair. Packed: the dwords hold pairs 0-3,
 * 8-11, 16-19, 24-27 | 4-7, 12-15, 20-23, 28-31; NV12: the in-lane packs leave the qwords holding
 * pairs 0-7, 16-23 | 8-15, 24-31; I420: already in pair order. */
CYL_SKIP_TARGET_AVX2 static inline unsigned cyl_bits_packed_avx2(__m256i h)
{
    return cyl_skip_bits256(_mm256_permutevar8x32_epi32(h, _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7)));
}
CYL_SKIP_TARGET_AVX2 static inline unsigned cyl_bits_nv12_avx2(__m256i h)
{
    return cyl_skip_bits256(_mm256_permute4x64_epi64(h, 0xD8));
}
CYL_SKIP_TARGET_AVX2 static inline unsigned cyl_bits_i420_avx2(__m256i h) { return cyl_skip_bits256(h); }

/* The AVX2 skip: 32 pairs at a time (the map's halves loaded once); the last pairs of a range of
 * at least 32 are examined as the range's last 32 (the bits of the pairs before p masked off: they
 * were examined, or lie before the range, and are read but not reported), so the whole range is
 * examined and n comes back when no pair of it is a candidate. A range of fewer than 32 pairs goes
 * to the SSSE3 code (FINE). */
#define CYL_SKIP_AVX2(NAME, HITS, BITS, FINE)                                                  \
    CYL_SKIP_TARGET_AVX2 static uint32_t NAME(const uint8_t *u, const uint8_t *v,              \
                                              const uint8_t (*map)[16], uint32_t p, uint32_t n) \
    {                                                                                          \
        __m256i lo, hi, h0;                                                                    \
        unsigned m;                                                                            \
        if (p + 32u > n) return FINE(u, v, map, p, n);                                         \
        lo = _mm256_broadcastsi128_si256(_mm_loadu_si128((const __m128i *)(const void *)map[0])); \
        hi = _mm256_broadcastsi128_si256(_mm_loadu_si128((const __m128i *)(const void *)map[1])); \
        for (; p + 32u <= n; p += 32u) {                                                       \
            h0 = HITS(u, v, lo, hi, p);                                                        \
            if (!_mm256_testz_si256(h0, h0)) {                                                 \
                m = BITS(h0);                                                                  \
                _mm256_zeroupper();                                                            \
                return p + (uint32_t)__builtin_ctz(m);                                         \
            }                                                                                  \
        }                                                                                      \
        if (p < n) {                                                                           \
            const uint32_t q = n - 32u;                                                        \
            m = BITS(HITS(u, v, lo, hi, q)) & (0xFFFFFFFFu << (p - q));                        \
            _mm256_zeroupper();                                                                \
            return m ? q + (uint32_t)__builtin_ctz(m) : n;                                     \
        }                                                                                      \
        _mm256_zeroupper();                                                                    \
        return n;                                                                              \
    }
CYL_SKIP_AVX2(cyl_skip_yuyv_avx2, cyl_hits_yuyv_avx2, cyl_bits_packed_avx2, cyl_skip_yuyv_ssse3)
CYL_SKIP_AVX2(cyl_skip_uyvy_avx2, cyl_hits_uyvy_avx2, cyl_bits_packed_avx2, cyl_skip_uyvy_ssse3)
CYL_SKIP_AVX2(cyl_skip_nv12_avx2, cyl_hits_nv12_avx2, cyl_bits_nv12_avx2, cyl_skip_nv12_ssse3)
CYL_SKIP_AVX2(cyl_skip_i420_avx2, cyl_hits_i420_avx2, cyl_bits_i420_avx2, cyl_skip_i420_ssse3)
#undef CYL_SKIP_AVX2

/* A packed pair's 4 box bytes (corner c: Y, U, V) with Y0, Y1, U, V at byte offsets oy0, oy1, ou, ov. */
static inline uint32_t cyl_box_word(const uint8_t *c, unsigned oy0, unsigned oy1, unsigned ou, unsigned ov)
{
    return (uint32_t)c[0] << (8u * oy0) | (uint32_t)c[0] << (8u * oy1) | (uint32_t)c[1] << (8u * ou) |
           (uint32_t)c[2] << (8u * ov);
}

/* The run extension's box test (cyl_colortable.inner_lo / inner_hi: colours that are certainly of
 * class cur), 8 pairs at a time with byte compares in 128-bit registers: the first pair with a byte
 * outside the box, or the first pair not examined when less than 8 are left; p itself when the
 * box is empty. This is the whole extension where there are no gathers (SSSE3): the scalar path
 * decides the pair it stops at and, where the run goes on, extends again. */
#define CYL_IN128(w, l, h) (unsigned)_mm_movemask_epi8(_mm_cmpeq_epi8(_mm_min_epu8(_mm_max_epu8(w, l), h), w))
/* packed formats: a pair's 4 bytes hold Y0, Y1, U, V at offsets OY0, OY1, OU, OV; MASK8(b, bl, bh)
 * is one bit a byte for the 32 bytes at b (8 pairs), set where the byte lies in the box */
#define CYL_BOX_PACKED(NAME, TARGET, VEC, SET1, MASK8, OY0, OY1, OU, OV)                        \
    TARGET static uint32_t NAME(const cyl_colortable *t, const uint8_t *y, const uint8_t *u,   \
                                const uint8_t *v, uint32_t p, uint32_t n, unsigned cur)        \
    {                                                                                          \
        const VEC bl = SET1((int)cyl_box_word(t->inner_lo[cur], OY0, OY1, OU, OV));            \
        const VEC bh = SET1((int)cyl_box_word(t->inner_hi[cur], OY0, OY1, OU, OV));            \
        (void)u; (void)v;                                                                      \
        if (t->inner_lo[cur][0] > t->inner_hi[cur][0]) return p;   /* no box */                \
        for (; p + 8u <= n; p += 8u) {                                                         \
            const unsigned m = MASK8(y + 4u * (size_t)p, bl, bh);                              \
            if (m != 0xFFFFFFFFu) return p + (uint32_t)__builtin_ctz(~m) / 4u;                 \
        }                                                                                      \
        return p;                                                                              \
    }
#define CYL_MASK8_SSE(b, bl, bh) \
    (CYL_IN128(_mm_loadu_si128((const __m128i *)(const void *)(b)), bl, bh) | \
     CYL_IN128(_mm_loadu_si128((const __m128i *)(const void *)((b) + 16)), bl, bh) << 16)
CYL_BOX_PACKED(cyl_extend_yuyv_sse, CYL_SKIP_TARGET, __m128i, _mm_set1_epi32, CYL_MASK8_SSE, 0, 2, 1, 3)
CYL_BOX_PACKED(cyl_extend_uyvy_sse, CYL_SKIP_TARGET, __m128i, _mm_set1_epi32, CYL_MASK8_SSE, 1, 3, 0, 2)
#undef CYL_MASK8_SSE
/* planar: 16 luma bytes and 8 (U, V) byte pairs (NV12's chroma row as it is, I420's two interleaved) */
#define CYL_EXTEND_PLANAR_SSE(NAME, CHROMA)                                                     \
    CYL_SKIP_TARGET static uint32_t NAME(const cyl_colortable *t, const uint8_t *y,            \
                                         const uint8_t *u, const uint8_t *v, uint32_t p,       \
                                         uint32_t n, unsigned cur)                             \
    {                                                                                          \
        const uint8_t *lo = t->inner_lo[cur], *hi = t->inner_hi[cur];                          \
        const __m128i yl = _mm_set1_epi8((char)lo[0]), yh = _mm_set1_epi8((char)hi[0]);        \
        const __m128i cl = _mm_set1_epi16((short)(lo[1] | lo[2] << 8)), ch = _mm_set1_epi16((short)(hi[1] | hi[2] << 8)); \
        (void)v;                                                                               \
        if (lo[0] > hi[0]) return p;                                                           \
        for (; p + 8u <= n; p += 8u) {                                                         \
            const __m128i lb = _mm_loadu_si128((const __m128i *)(const void *)(y + 2u * (size_t)p)); \
            const unsigned m = CYL_IN128(lb, yl, yh) & CYL_IN128(CHROMA, cl, ch);              \
            if (m != 0xFFFFu) return p + (uint32_t)__builtin_ctz(~m) / 2u;                     \
        }                                                                                      \
        return p;                                                                              \
    }
CYL_EXTEND_PLANAR_SSE(cyl_extend_nv12_sse, _mm_loadu_si128((const __m128i *)(const void *)(u + 2u * (size_t)p)))
CYL_EXTEND_PLANAR_SSE(cyl_extend_i420_sse, _mm_unpacklo_epi8(_mm_loadl_epi64((const __m128i *)(const void *)(u + p)),
                                                             _mm_loadl_epi64((const __m128i *)(const void *)(v + p))))
#undef CYL_EXTEND_PLANAR_SSE
#undef CYL_IN128

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

/* The exact test of a run by gathers, 8 pairs at a time: the first pair with a pixel of another
 * class, or the first pair not examined when less than 8 are left. */
#define CYL_GATHER_AVX2(NAME, LOAD)                                                            \
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
CYL_GATHER_AVX2(cyl_gather_yuyv_avx2, {
    const __m256i w = _mm256_loadu_si256((const __m256i *)(const void *)(y + 4u * (size_t)p));
    Y0 = _mm256_and_si256(w, ff); U = _mm256_and_si256(_mm256_srli_epi32(w, 8), ff);
    Y1 = _mm256_and_si256(_mm256_srli_epi32(w, 16), ff); V = _mm256_srli_epi32(w, 24); })
CYL_GATHER_AVX2(cyl_gather_uyvy_avx2, {
    const __m256i w = _mm256_loadu_si256((const __m256i *)(const void *)(y + 4u * (size_t)p));
    U = _mm256_and_si256(w, ff); Y0 = _mm256_and_si256(_mm256_srli_epi32(w, 8), ff);
    V = _mm256_and_si256(_mm256_srli_epi32(w, 16), ff); Y1 = _mm256_srli_epi32(w, 24); })
/* planar luma: 16 bytes widened to 8 lanes of two pixels each */
CYL_GATHER_AVX2(cyl_gather_nv12_avx2, {
    const __m256i l = _mm256_cvtepu16_epi32(_mm_loadu_si128((const __m128i *)(const void *)(y + 2u * (size_t)p)));
    const __m256i c = _mm256_cvtepu16_epi32(_mm_loadu_si128((const __m128i *)(const void *)(u + 2u * (size_t)p)));
    Y0 = _mm256_and_si256(l, ff); Y1 = _mm256_srli_epi32(l, 8);
    U = _mm256_and_si256(c, ff); V = _mm256_srli_epi32(c, 8); })
CYL_GATHER_AVX2(cyl_gather_i420_avx2, {
    const __m256i l = _mm256_cvtepu16_epi32(_mm_loadu_si128((const __m128i *)(const void *)(y + 2u * (size_t)p)));
    Y0 = _mm256_and_si256(l, ff); Y1 = _mm256_srli_epi32(l, 8);
    U = _mm256_cvtepu8_epi32(_mm_loadl_epi64((const __m128i *)(const void *)(u + p)));
    V = _mm256_cvtepu8_epi32(_mm_loadl_epi64((const __m128i *)(const void *)(v + p))); })
#undef CYL_GATHER_AVX2

/* The box test of the packed formats in 256-bit registers: 8 pairs a load. */
#define CYL_MASK8_AVX2(b, bl, bh)                                                               \
    (unsigned)_mm256_movemask_epi8(_mm256_cmpeq_epi8(                                          \
        _mm256_min_epu8(_mm256_max_epu8(_mm256_loadu_si256((const __m256i *)(const void *)(b)), bl), bh), \
        _mm256_loadu_si256((const __m256i *)(const void *)(b))))
CYL_BOX_PACKED(cyl_box_yuyv_avx2, CYL_SKIP_TARGET_AVX2, __m256i, _mm256_set1_epi32, CYL_MASK8_AVX2, 0, 2, 1, 3)
CYL_BOX_PACKED(cyl_box_uyvy_avx2, CYL_SKIP_TARGET_AVX2, __m256i, _mm256_set1_epi32, CYL_MASK8_AVX2, 1, 3, 0, 2)
#undef CYL_MASK8_AVX2
#undef CYL_BOX_PACKED

/* The AVX2 run extension: the box test, then at the pair it stops at an exact lookup
 * (cyl_colortable_mask). A pair of another class ends the run there (where runs usually end: no
 * gathers); a pair of class cur means the run's colours leave the box, and the rest of the run
 * takes the exact test by gathers. The box is a subset of the class, so the answer is the exact
 * lookup's in every case; an empty box leaves the whole run to the gathers. The pair's chroma
 * entry alone settles most run ends: no bit of class cur there, no pixel of the pair is of cur.
 * Y0, Y1, U, V: pair q's bytes. */
#define CYL_EXTEND_AVX2(NAME, BOX, GATHER, Y0, Y1, U, V)                                       \
    CYL_SKIP_TARGET_AVX2 static uint32_t NAME(const cyl_colortable *t, const uint8_t *y,       \
                                              const uint8_t *u, const uint8_t *v, uint32_t p,  \
                                              uint32_t n, unsigned cur)                        \
    {                                                                                          \
        const uint32_t q = BOX(t, y, u, v, p, n, cur);                                         \
        (void)u; (void)v;                                                                      \
        if (q >= n || !((t->uv[U][V] >> cur) & 1u) ||                                          \
            cyl_lowbit[cyl_colortable_mask(t, Y0, U, V)] != cur ||                             \
            cyl_lowbit[cyl_colortable_mask(t, Y1, U, V)] != cur)                               \
            return q;                                                                          \
        return GATHER(t, y, u, v, q + 1u, n, cur);                                             \
    }
CYL_EXTEND_AVX2(cyl_extend_yuyv_avx2, cyl_box_yuyv_avx2, cyl_gather_yuyv_avx2,
                y[4u * q], y[4u * q + 2u], y[4u * q + 1u], y[4u * q + 3u])
CYL_EXTEND_AVX2(cyl_extend_uyvy_avx2, cyl_box_uyvy_avx2, cyl_gather_uyvy_avx2,
                y[4u * q + 1u], y[4u * q + 3u], y[4u * q], y[4u * q + 2u])
CYL_EXTEND_AVX2(cyl_extend_nv12_avx2, cyl_extend_nv12_sse, cyl_gather_nv12_avx2,
                y[2u * q], y[2u * q + 1u], u[2u * q], u[2u * q + 1u])
CYL_EXTEND_AVX2(cyl_extend_i420_avx2, cyl_extend_i420_sse, cyl_gather_i420_avx2,
                y[2u * q], y[2u * q + 1u], u[q], v[q])
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
        s.ext_yuyv = cyl_extend_yuyv_sse;
        s.ext_uyvy = cyl_extend_uyvy_sse;
        s.ext_nv12 = cyl_extend_nv12_sse;
        s.ext_i420 = cyl_extend_i420_sse;
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

/* The run extension on NEON: 16 pairs at a time against class cur's inner box, ending at the first
 * pair with a value outside it (as the SSE extension; the scalar path decides that pair). LOAD sets
 * the pairs' Y0, Y1, U and V, one pair a lane. */
#define CYL_EXTEND_NEON_FN(NAME, LOAD)                                                         \
    static uint32_t NAME(const cyl_colortable *t, const uint8_t *y, const uint8_t *u,          \
                         const uint8_t *v, uint32_t p, uint32_t n, unsigned cur)               \
    {                                                                                          \
        const uint8_t *lo = t->inner_lo[cur], *hi = t->inner_hi[cur];                          \
        const uint8x16_t yl = vdupq_n_u8(lo[0]), yh = vdupq_n_u8(hi[0]), ul = vdupq_n_u8(lo[1]), \
                         uh = vdupq_n_u8(hi[1]), vl = vdupq_n_u8(lo[2]), vh = vdupq_n_u8(hi[2]); \
        (void)u; (void)v;                                                                      \
        if (lo[0] > hi[0]) return p;                                                           \
        for (; p + 16u <= n; p += 16u) {                                                       \
            uint8x16_t Y0, Y1, U, V, in;                                                       \
            uint64_t m;                                                                        \
            LOAD                                                                               \
            in = vandq_u8(vandq_u8(vcgeq_u8(Y0, yl), vcleq_u8(Y0, yh)), vandq_u8(vcgeq_u8(Y1, yl), vcleq_u8(Y1, yh))); \
            in = vandq_u8(in, vandq_u8(vandq_u8(vcgeq_u8(U, ul), vcleq_u8(U, uh)), vandq_u8(vcgeq_u8(V, vl), vcleq_u8(V, vh)))); \
            /* 4 bits a lane, set where the lane is outside the box */                          \
            m = vget_lane_u64(vreinterpret_u64_u8(vshrn_n_u16(vreinterpretq_u16_u8(vmvnq_u8(in)), 4)), 0); \
            if (m) return p + ((uint32_t)__builtin_ctzll(m) >> 2);                             \
        }                                                                                      \
        return p;                                                                              \
    }
CYL_EXTEND_NEON_FN(cyl_extend_yuyv_neon, { uint8x16x4_t q = vld4q_u8(y + 4u * (size_t)p);
                                           Y0 = q.val[0]; U = q.val[1]; Y1 = q.val[2]; V = q.val[3]; })
CYL_EXTEND_NEON_FN(cyl_extend_uyvy_neon, { uint8x16x4_t q = vld4q_u8(y + 4u * (size_t)p);
                                           U = q.val[0]; Y0 = q.val[1]; V = q.val[2]; Y1 = q.val[3]; })
CYL_EXTEND_NEON_FN(cyl_extend_nv12_neon, { uint8x16x2_t l = vld2q_u8(y + 2u * (size_t)p);
                                           uint8x16x2_t c = vld2q_u8(u + 2u * (size_t)p);
                                           Y0 = l.val[0]; Y1 = l.val[1]; U = c.val[0]; V = c.val[1]; })
CYL_EXTEND_NEON_FN(cyl_extend_i420_neon, { uint8x16x2_t l = vld2q_u8(y + 2u * (size_t)p);
                                           Y0 = l.val[0]; Y1 = l.val[1]; U = vld1q_u8(u + p); V = vld1q_u8(v + p); })
#undef CYL_EXTEND_NEON_FN

static inline cyl_skip_set cyl_skip_select(void)
{
    cyl_skip_set s = { cyl_skip_yuyv_neon, cyl_skip_uyvy_neon, cyl_skip_nv12_neon, cyl_skip_i420_neon,
                       cyl_extend_yuyv_neon, cyl_extend_uyvy_neon, cyl_extend_nv12_neon,
                       cyl_extend_i420_neon, "neon" };
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
