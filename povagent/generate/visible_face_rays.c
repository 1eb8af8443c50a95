/* Every pixel's distance to its face's group plane and the exact tests of the hits that can be
 * decided otherwise (VisibleFaces._decide), with the near-edge and containment tests the
 * outline's pass (visible_face_outline.c) shares: part of the compiled loop of
 * VisibleFaces.decide_image (visible_face.c says what it does, and includes this file). */
#include "visible_face.h"
#ifdef __SSE2__
#include <emmintrin.h>
#endif
#if defined(__GNUC__) && defined(__x86_64__) && !defined(POVAGENT_ONE_BUILD)
#include <immintrin.h>
#define HAS_AVX_PATH 1
/* whether this CPU has AVX: set once when the module loads (PyInit__visible_face) */
static int cpu_has_avx = 0;

/* covers_block's loop for one coordinate, four pixels at once with AVX where the CPU has it
 * (the same IEEE operations as the SSE2 and scalar loops below, lane by lane: the same cells);
 * returns how many pixels it did (a multiple of 4) */
__attribute__((target("avx"))) static Py_ssize_t cells_avx(const float *d, const double *at, Py_ssize_t count, int first, double *index, const double v[9]) {
    __m256d vo = _mm256_set1_pd(v[0]), vinv = _mm256_set1_pd(v[1]), vlow = _mm256_set1_pd(v[2]), vhigh = _mm256_set1_pd(v[3]);
    __m256d vwhole = _mm256_set1_pd(v[4]), vorigin = _mm256_set1_pd(v[5]), vtop = _mm256_set1_pd(v[6]), vsize = _mm256_set1_pd(v[7]);
    __m256d one = _mm256_set1_pd(1.0), zero = _mm256_setzero_pd();
    Py_ssize_t j = 0;
    for (; j + 3 < count; j += 4) {
        __m256d dj = _mm256_cvtps_pd(_mm_loadu_ps(d + j));
        __m256d q = _mm256_mul_pd(_mm256_add_pd(vo, _mm256_mul_pd(dj, _mm256_loadu_pd(at + j))), vinv);
        q = _mm256_min_pd(vhigh, _mm256_max_pd(vlow, q));
        __m256d t = _mm256_sub_pd(_mm256_add_pd(q, vwhole), vwhole);
        __m256d c = _mm256_sub_pd(_mm256_sub_pd(t, _mm256_and_pd(_mm256_cmp_pd(t, q, _CMP_GT_OQ), one)), vorigin);
        c = _mm256_min_pd(vtop, _mm256_max_pd(zero, c));
        _mm256_storeu_pd(index + j, first ? c : _mm256_add_pd(_mm256_mul_pd(_mm256_loadu_pd(index + j), vsize), c));
    }
    return j;
}

/* pixel_block's loop four pixels at once with AVX2 where the CPU has it: each pixel's face row
 * read as two vectors and the four rows turned into columns, then the same IEEE operations as
 * the scalar loop, lane by lane (C's != holds for NaN: _CMP_NEQ_UQ; >= does not: _CMP_GE_OQ;
 * e - e == 0 is isfinite(e)); returns how many pixels it did (a multiple of 4) */
static int cpu_has_avx2 = 0;

__attribute__((target("avx2"))) static inline void columns(const double *r0, const double *r1, const double *r2, const double *r3, __m256d c[4]) {
    __m256d a = _mm256_loadu_pd(r0), b = _mm256_loadu_pd(r1), e = _mm256_loadu_pd(r2), f = _mm256_loadu_pd(r3);
    __m256d lo0 = _mm256_unpacklo_pd(a, b), hi0 = _mm256_unpackhi_pd(a, b), lo1 = _mm256_unpacklo_pd(e, f), hi1 = _mm256_unpackhi_pd(e, f);
    c[0] = _mm256_permute2f128_pd(lo0, lo1, 0x20);
    c[1] = _mm256_permute2f128_pd(hi0, hi1, 0x20);
    c[2] = _mm256_permute2f128_pd(lo0, lo1, 0x31);
    c[3] = _mm256_permute2f128_pd(hi0, hi1, 0x31);
}

__attribute__((target("avx2"))) static Py_ssize_t pixels_avx2(Py_ssize_t count, const int64_t *tri, const float *dx, const float *dy, const float *dz,
                                                              const double *face_row, int64_t faces, double *every, int64_t *flags, int64_t *beyond) {
    const __m256i none = _mm256_set1_epi64x(-1), limit = _mm256_set1_epi64x(faces), one = _mm256_set1_epi64x(1);
    const __m256i watched = _mm256_set1_epi64x(WATCHED), met_bit = _mm256_set1_epi64x(MET), finite_bit = _mm256_set1_epi64x(FINITE_HIT);
    const __m256d zero = _mm256_setzero_pd(), inf = _mm256_set1_pd(INFINITY);
    __m256i past = _mm256_setzero_si256();
    Py_ssize_t j = 0;
    for (; j + 3 < count; j += 4) {
        __m256i f = _mm256_loadu_si256((const __m256i *)(tri + j));
        __m256i hit = _mm256_cmpgt_epi64(f, none), below = _mm256_cmpgt_epi64(limit, f);
        past = _mm256_or_si256(past, _mm256_andnot_si256(below, one));
        int64_t face[4];
        _mm256_storeu_si256((__m256i *)face, _mm256_and_si256(_mm256_and_si256(hit, below), f));
        const double *r0 = face_row + 8 * face[0], *r1 = face_row + 8 * face[1], *r2 = face_row + 8 * face[2], *r3 = face_row + 8 * face[3];
        __m256d c[4], k[4];
        columns(r0, r1, r2, r3, c);
        columns(r0 + 4, r1 + 4, r2 + 4, r3 + 4, k);
        __m256d d0 = _mm256_cvtps_pd(_mm_loadu_ps(dx + j)), d1 = _mm256_cvtps_pd(_mm_loadu_ps(dy + j)), d2 = _mm256_cvtps_pd(_mm_loadu_ps(dz + j));
        __m256d along = _mm256_mul_pd(c[0], d0);
        along = _mm256_add_pd(along, _mm256_mul_pd(c[1], d1));
        along = _mm256_add_pd(along, _mm256_mul_pd(c[2], d2));
        __m256d q = _mm256_div_pd(c[3], along);
        __m256d use = _mm256_and_pd(_mm256_castsi256_pd(hit), _mm256_cmp_pd(along, zero, _CMP_NEQ_UQ));
        __m256d e = _mm256_blendv_pd(inf, q, use);
        __m256d facing = _mm256_mul_pd(k[0], d0);
        facing = _mm256_add_pd(facing, _mm256_mul_pd(k[1], d1));
        facing = _mm256_add_pd(facing, _mm256_mul_pd(k[2], d2));
        __m256i met = _mm256_castpd_si256(_mm256_cmp_pd(facing, zero, _CMP_GE_OQ));
        __m256i bits = _mm256_castpd_si256(k[3]);
        __m256i side = _mm256_add_epi64(one, _mm256_and_si256(met, one));
        __m256i rival = _mm256_slli_epi64(_mm256_and_si256(_mm256_srlv_epi64(bits, side), one), 2); /* RIVAL = 4 */
        __m256i finite = _mm256_and_si256(hit, _mm256_castpd_si256(_mm256_cmp_pd(_mm256_sub_pd(e, e), zero, _CMP_EQ_OQ)));
        __m256i out = _mm256_or_si256(_mm256_and_si256(bits, watched), _mm256_and_si256(met, met_bit));
        out = _mm256_or_si256(out, _mm256_or_si256(rival, _mm256_and_si256(finite, finite_bit)));
        _mm256_storeu_si256((__m256i *)(flags + j), out);
        _mm256_storeu_pd(every + j, e);
    }
    int64_t lanes[4];
    _mm256_storeu_si256((__m256i *)lanes, past);
    *beyond |= lanes[0] | lanes[1] | lanes[2] | lanes[3];
    return j;
}
#endif

/* CellMask.covers for a block of pixels' hits (o + d * at, at: every finite distance, else 0),
 * ANDed into bit 0 of their flags. numpy works in float64 (whole numbers, exact): floor, minus
 * the grid's origin, clipped to the grid. Here the product is clamped to one cell beyond the
 * grid first (that changes no clipped cell, floor being monotonic), then floored in float64:
 * q + 1.5 * 2**52 rounds it to a whole number (the default rounding, to nearest), the
 * difference takes that back exactly, one less where it rounded up. One coordinate at a time
 * over the block, four pixels at once with AVX or two with SSE2 (the same IEEE operations). -1 where a cell is
 * not in the grid: a NaN direction (numpy's path raises IndexError there too) */
static int covers_block(const Faces *s, Py_ssize_t start, Py_ssize_t count, const double *every, int64_t *flags) {
    const double whole = 6755399441055744.0;
    double at[BLOCK], index[BLOCK];
    for (Py_ssize_t j = 0; j < count; j++) at[j] = isfinite(every[j]) ? every[j] : 0.0;
    for (int k = 0; k < 3; k++) {
        const float *d = s->d + k * s->n + start;
        double o = s->o[k], inv = s->inv_mask, low = s->mask_origin[k] - 1.0, high = s->mask_origin[k] + (double)s->shape[k];
        double origin = s->mask_origin[k], top = (double)(s->shape[k] - 1), size = (double)s->shape[k];
        Py_ssize_t j = 0;
#ifdef HAS_AVX_PATH
        if (cpu_has_avx) {
            const double v[9] = {o, inv, low, high, whole, origin, top, size, 0};
            j = cells_avx(d, at, count, k == 0, index, v);
        }
#endif
#ifdef __SSE2__
        __m128d vo = _mm_set1_pd(o), vinv = _mm_set1_pd(inv), vlow = _mm_set1_pd(low), vhigh = _mm_set1_pd(high), vwhole = _mm_set1_pd(whole);
        __m128d vorigin = _mm_set1_pd(origin), vtop = _mm_set1_pd(top), vsize = _mm_set1_pd(size), one = _mm_set1_pd(1.0), zero = _mm_setzero_pd();
        for (; j + 1 < count; j += 2) {
            __m128d dj = _mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64((const __m128i *)(d + j))));
            __m128d q = _mm_mul_pd(_mm_add_pd(vo, _mm_mul_pd(dj, _mm_loadu_pd(at + j))), vinv);
            q = _mm_min_pd(vhigh, _mm_max_pd(vlow, q)); /* q < low ? low : q, then q > high ? high : q */
            __m128d t = _mm_sub_pd(_mm_add_pd(q, vwhole), vwhole);
            __m128d c = _mm_sub_pd(_mm_sub_pd(t, _mm_and_pd(_mm_cmpgt_pd(t, q), one)), vorigin);
            c = _mm_min_pd(vtop, _mm_max_pd(zero, c));
            _mm_storeu_pd(index + j, k ? _mm_add_pd(_mm_mul_pd(_mm_loadu_pd(index + j), vsize), c) : c);
        }
#endif
        for (; j < count; j++) {
            double q = (o + (double)d[j] * at[j]) * inv;
            q = q < low ? low : q;
            q = q > high ? high : q;
            double t = (q + whole) - whole;
            double c = (t > q ? t - 1.0 : t) - origin;
            c = c < 0 ? 0 : c;
            c = c > top ? top : c;
            index[j] = k ? index[j] * size + c : c;
        }
    }
    double cells = (double)s->shape[0] * (double)s->shape[1] * (double)s->shape[2];
    for (Py_ssize_t j = 0; j < count; j++) {
        if (!(index[j] >= 0 && index[j] < cells)) return -1;
        int32_t i = (int32_t)index[j];
        flags[j] &= ~(int64_t)1 | ((s->marked[i >> 3] >> (i & 7)) & 1);
    }
    return 0;
}

/* VisibleFaces._near_watched for one point of group g: whether it lies within the margin of a
 * watched edge; the groups across the creases it lies near are pushed as (ray, group) pairs */
static int vf_near_watched(const Faces *s, int64_t g, const double p[3], Py_ssize_t ray, Vec *pair_ray, Vec *pair_group, int *near) {
    *near = 0;
    if (!s->watching[g]) return 0;
    Py_ssize_t at = find_memo(s->edge_memo, s->edge_keys, s->edge_key_count, key_of(g, p, s->inv_edge_cell));
    if (at < 0) return 0;
    double m = s->margin;
    for (int64_t j = s->edge_starts[at]; j < s->edge_starts[at + 1]; j++) {
        int64_t e = s->edge_items[j];
        const double *r = s->edge_rows + 10 * e;
        double off = r[0] * p[0];
        off += r[1] * p[1];
        off += r[2] * p[2];
        off -= r[3];
        double pos = r[4] * p[0];
        pos += r[5] * p[1];
        pos += r[6] * p[2];
        if (!(fabs(off) < m && pos > r[7] - m && pos < r[8] + m)) continue;
        *near = 1;
        for (int c = 0; c < 2; c++) {
            int64_t other = s->across[2 * e + c];
            if (other < 0) continue;
            if (pair_ray && (push(pair_ray, ray) || push(pair_group, other))) return -1;
        }
    }
    return 0;
}

/* VisibleFaces._highest_holding for one point: the highest face listed under face-table key at
 * whose triangle holds p (within the tolerance) and that the ray can meet; -1 where none */
static int64_t vf_highest_holding(const Faces *s, Py_ssize_t at, const double p[3], Py_ssize_t ray) {
    double d0 = dir(s, 0, ray), d1 = dir(s, 1, ray), d2 = dir(s, 2, ray);
    for (int64_t j = s->face_starts[at]; j < s->face_starts[at + 1]; j++) {
        int64_t g = s->face_items[j];
        const double *h = s->holding + 16 * g;
        double facing = h[0] * d0;
        facing += h[1] * d1;
        facing += h[2] * d2;
        if (!(h[3] != 0 || facing < 0)) continue;
        int inside = 1;
        for (int e = 0; e < 3 && inside; e++) {
            const double *m = h + 4 + 4 * e;
            double signed_ = m[0] * p[0];
            signed_ += m[1] * p[1];
            signed_ += m[2] * p[2];
            signed_ -= m[3];
            inside = signed_ >= -s->tolerance;
        }
        if (inside) return g;
    }
    return -1;
}

/* vf_decide_rays's first pass over a block's pixels (the comment there says what): each pixel's
 * face row (face_row: 8 doubles a face, the flags' bits in the last) read whole; returns
 * whether a triangle index lies beyond the faces */
static int64_t pixel_block(Py_ssize_t count, const int64_t *tri, const float *dx, const float *dy, const float *dz, const double *face_row,
                           int64_t faces, double *every, int64_t *flags) {
    int64_t beyond = 0;
    Py_ssize_t j = 0;
#ifdef HAS_AVX_PATH
    if (cpu_has_avx2) j = pixels_avx2(count, tri, dx, dy, dz, face_row, faces, every, flags, &beyond);
#endif
    for (; j < count; j++) {
        int64_t f = tri[j];
        int64_t hit = f >= 0;
        beyond |= f >= faces;
        const double *row = face_row + 8 * (hit && f < faces ? f : 0);
        double d0 = dx[j], d1 = dy[j], d2 = dz[j];
        double along = row[0] * d0;
        along += row[1] * d1;
        along += row[2] * d2;
        double q = row[3] / along;
        double e = (hit && along != 0) ? q : INFINITY;
        double facing = row[4] * d0;
        facing += row[5] * d1;
        facing += row[6] * d2;
        int64_t met = facing >= 0, bits;
        memcpy(&bits, row + 7, sizeof bits);
        flags[j] = (bits & WATCHED) | (met ? MET : 0) | (((bits >> (1 + met)) & 1) ? RIVAL : 0) | (hit && isfinite(e) ? FINITE_HIT : 0);
        every[j] = e;
    }
    return beyond;
}

/* VisibleFaces._decide for every pixel, a block at a time: first for each pixel without a
 * branch (the CPU overlaps the pixels' divisions) the distance to its face's group plane
 * (_face_distance: inf where parallel or nothing is hit) and whether its hit can be decided
 * otherwise (a watched group's hit, in a near cell where skip asks, or a rival overlapping its
 * face from the side met: _side); then those hits' exact tests. The crease pairs they find are
 * pushed, in pixel order */
static int vf_decide_rays(const Faces *s, const Pixels *px, int want, int skip, Vec *crease_ray, Vec *crease_group) {
    int masked = skip && s->has_mask;
    double every[BLOCK];
    int64_t flags[BLOCK];
    int64_t beyond = 0; /* a triangle index beyond the mesh's faces */
    /* (the struct's fields read once: the byte stores below may alias anything) */
    const float *dx = s->d, *dy = s->d + s->n, *dz = s->d + 2 * s->n;
    const double *face_row = s->face_row;
    const Py_ssize_t faces = s->faces;
    int32_t *shown = px->shown;
    int64_t tri[BLOCK], below = 0; /* the block's triangles; an int64 one below int32's range */
    for (Py_ssize_t start = 0; start < s->n; start += BLOCK) {
        Py_ssize_t count = s->n - start < BLOCK ? s->n - start : BLOCK;
        if (px->tri32) {
            const int32_t *from = (const int32_t *)px->tri + start;
            for (Py_ssize_t j = 0; j < count; j++) tri[j] = from[j];
        } else {
            memcpy(tri, (const int64_t *)px->tri + start, (size_t)count * sizeof *tri);
            for (Py_ssize_t j = 0; j < count; j++) below |= tri[j] < INT32_MIN;
        }
        beyond |= pixel_block(count, tri, dx + start, dy + start, dz + start, face_row, faces, every, flags);
        if (beyond) return BEYOND;
        if (below) return BELOW;
        for (Py_ssize_t j = 0; j < count; j++) shown[start + j] = (int32_t)tri[j];
        if (want && px->t32)
            for (Py_ssize_t j = 0; j < count; j++) ((float *)px->t)[start + j] = (float)every[j];
        else if (want)
            memcpy((double *)px->t + start, every, (size_t)count * sizeof *every);
        if (masked && covers_block(s, start, count, every, flags)) return NOT_FINITE;
        /* the block's hits that can be decided otherwise, listed without a branch (a few in
         * six: a branch per pixel would be mispredicted at every run's end) */
        int examined[BLOCK], listed = 0;
        for (Py_ssize_t j = 0; j < count; j++) {
            int bits = flags[j];
            examined[listed] = (int)j;
            listed += (bits & (WATCHED | RIVAL)) && (bits & FINITE_HIT);
        }
        for (int k = 0; k < listed; k++) {
            Py_ssize_t j = examined[k];
            int bits = flags[j];
            Py_ssize_t i = start + j;
            int64_t f = tri[j], g = s->group[f];
            double p[3];
            point_at(s, i, every[j], p);
            int near;
            if (vf_near_watched(s, g, p, i, crease_ray, crease_group, &near)) return -1;
            if (!((bits & RIVAL) || near)) continue;
            Py_ssize_t at = find_memo(s->face_memo, s->face_keys, s->keys, key_of(g, p, s->inv_cell));
            if (at < 0 || !s->mixed[at]) continue;
            int64_t best = vf_highest_holding(s, at, p, i);
            shown[i] = (int32_t)(best >= 0 ? best : f);
        }
    }
    return 0;
}
