/* Which face each pixel of a camera shows and how far away it is: the compiled loop of
 * povagent/generate/visible_face.py's VisibleFaces.decide_image (whose numpy code is the
 * reference: the module docstring there says what is decided and why). Every number is the
 * one numpy computes: the same IEEE operations, in the same order, in the same precision
 * (float32 directions read as float64, dot products summed x, then y, then z; no FMA, see
 * setup.py), and the cell tables looked up by a binary search over their sorted keys.
 *
 * decide_image(tables, numbers, tri, origin, directions, height, width, want_distance, skip,
 *              shown, t):
 *   tables: the VisibleFaces' arrays in the order of enum Table (visible_face_loop.py packs
 *   them); numbers: (mask origin x, y, z, mask shape x, y, z, has mask, 1 / mask cell,
 *   1 / CELL, 1 / EDGE_CELL, EDGE_MARGIN, CONTAINS_TOLERANCE); tri: embree's int64 triangle
 *   per pixel (-1: none); origin: (x, y, z); directions: float32 (3, height * width) rows;
 *   shown: int64 out, the face shown per pixel; t: float64 out, its distance (empty unless
 *   want_distance), written in place. IndexError, as numpy's path raises it, for a triangle
 *   beyond the mesh or a direction that is not finite (where the near cells are looked up);
 *   ValueError for arrays whose sizes do not match.
 *
 * The passes: every pixel's distance and flags a block at a time (decide_rays), the exact tests
 * of the few hits that can be decided otherwise, then row by row the outline (three rows of
 * outline values kept) and each outline or crease pixel's candidates (resolve_pixels).
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#ifdef __SSE2__
#include <emmintrin.h>
#endif

enum Table {
    T_GROUP, T_PLANE, T_HOLDING, T_GROUP_WATCHING, T_OVERLAPPED, T_OUTLINE,
    T_GROUP_NORMAL, T_GROUP_OFFSET, T_BOX, T_WATCHING,
    T_FACE_KEYS, T_FACE_STARTS, T_FACE_ITEMS, T_MIXED,
    T_EDGE_KEYS, T_EDGE_STARTS, T_EDGE_ITEMS,
    T_EDGE_ROWS, T_ACROSS, T_MARKED,
    T_COUNT
};

/* (cell_table.py) keys pack a cell's coordinates, this many values an axis */
#define CELL_SPAN 2048
#define HALF_SPAN 1024

typedef struct Memo Memo;

typedef struct {
    const int64_t *group;          /* (F,) each face's group */
    const double *plane;           /* (4, F) each face's group plane: normal, offset */
    const double *holding;         /* (F, 16) each face's own normal, whether it is open (not a
                                    * closed solid's: 1, else 0), its 3 inward edge normals and
                                    * offsets (the containment test's numbers, side by side) */
    const uint8_t *group_watching; /* (F,) the face's group has a watched edge */
    const uint8_t *overlapped;     /* (2 F,) face * 2 + side */
    const int32_t *outline;        /* (F,) what tells two pixels apart */
    const double *group_normal;    /* (3, G) */
    const double *group_offset;    /* (G,) */
    const double *box;             /* (6, G) low x, y, z, high x, y, z */
    const uint8_t *watching;       /* (G,) the group has a watched edge */
    const int64_t *face_keys, *face_starts, *face_items;
    const uint8_t *mixed;          /* (K,) the key's faces do not all look alike */
    const int64_t *edge_keys, *edge_starts, *edge_items;
    const double *edge_rows;       /* (E, 10) each watched edge's in-plane line (4), direction
                                    * and extent (5) */
    const int64_t *across;         /* (E, 2) the groups across it, -1: none */
    const uint8_t *marked;         /* the near cells' grid, 8 cells a byte (the first the lowest bit) */
    Py_ssize_t faces, groups, edge_count, keys, edge_key_count;
    Py_ssize_t shape[3];
    int has_mask;
    double mask_origin[3], inv_mask, inv_cell, inv_edge_cell, margin, tolerance;
    /* per call */
    double o[3];
    const float *d;
    Py_ssize_t n;
    double *face_row;     /* (F, 8) each face's group plane normal, its offset from the origin,
                           * its own normal (one cache line a face, where the pixels gather) */
    uint8_t *face_flags;  /* (F,) its group watched (1), overlapped from side 0 (2), side 1 (4) */
    double *group_row;    /* (G, 12) each group's plane normal, its offset from the origin and
                           * its box */
    Memo *face_memo, *edge_memo;
} Faces;

typedef struct {
    int64_t *v;
    size_t n, cap;
} Vec;

static int push(Vec *a, int64_t x) {
    if (a->n == a->cap) {
        size_t cap = a->cap ? 2 * a->cap : 256;
        int64_t *v = realloc(a->v, cap * sizeof *v);
        if (!v) return -1;
        a->v = v;
        a->cap = cap;
    }
    a->v[a->n++] = x;
    return 0;
}

/* floor(q) as an integer, for q in int32's range: the truncation, one less where it rounded up */
static inline int32_t floor_small(double q) {
    int32_t v = (int32_t)q;
    return v - ((double)v > q);
}

/* cell_table.cell then key_of's clip and shift: floor(p * inv) clipped to [-HALF_SPAN,
 * HALF_SPAN - 1], plus HALF_SPAN. Clamping the product first changes no clipped cell (floor is
 * monotonic) and keeps it in int32's range; a product of 2**63 or more becomes the least int64
 * in numpy's cast (x86), so it clips to the low end */
static inline int64_t cell_of(double p, double inv) {
    double q = p * inv;
    if (!(q < 9223372036854775808.0)) return 0;
    q = q < -HALF_SPAN - 1.0 ? -HALF_SPAN - 1.0 : (q > HALF_SPAN ? (double)HALF_SPAN : q);
    int32_t v = floor_small(q);
    v = v < -HALF_SPAN ? -HALF_SPAN : (v > HALF_SPAN - 1 ? HALF_SPAN - 1 : v);
    return v + HALF_SPAN;
}

static inline int64_t key_of(int64_t group, const double p[3], double inv) {
    int64_t key = group;
    for (int k = 0; k < 3; k++) key = key * CELL_SPAN + cell_of(p[k], inv);
    return key;
}

/* CellTable.find: the index of key among the sorted keys, -1 where it is not listed */
static inline Py_ssize_t find(const int64_t *keys, Py_ssize_t count, int64_t key) {
    Py_ssize_t lo = 0, hi = count;
    while (lo < hi) {
        Py_ssize_t mid = lo + (hi - lo) / 2;
        if (keys[mid] < key) lo = mid + 1;
        else hi = mid;
    }
    return (lo < count && keys[lo] == key) ? lo : -1;
}

/* the last keys found in a table, by a hash of the key: neighbouring pixels look up the same
 * few keys (a cell spans many pixels), so most lookups end here instead of in a binary search */
#define MEMO_BITS 14
struct Memo {
    int64_t key[1 << MEMO_BITS];
    Py_ssize_t at[1 << MEMO_BITS];
};

static void memo_clear(Memo *m) {
    for (int k = 0; k < (1 << MEMO_BITS); k++) m->key[k] = -1; /* no key is negative */
}

static inline Py_ssize_t find_memo(Memo *m, const int64_t *keys, Py_ssize_t count, int64_t key) {
    size_t slot = (size_t)(((uint64_t)key * 0x9E3779B97F4A7C15u) >> (64 - MEMO_BITS));
    if (m->key[slot] != key) {
        m->key[slot] = key;
        m->at[slot] = find(keys, count, key);
    }
    return m->at[slot];
}

static inline double dir(const Faces *s, int k, Py_ssize_t ray) { return (double)s->d[k * s->n + ray]; }

/* the pixels are decided a block at a time */
#define BLOCK 256

/* CellMask.covers for a block of pixels' hits (o + d * at, at: every finite distance, else 0),
 * ANDed into bit 0 of their flags. numpy works in float64 (whole numbers, exact): floor, minus
 * the grid's origin, clipped to the grid. Here the product is clamped to one cell beyond the
 * grid first (that changes no clipped cell, floor being monotonic), then floored in float64:
 * q + 1.5 * 2**52 rounds it to a whole number (the default rounding, to nearest), the
 * difference takes that back exactly, one less where it rounded up. One coordinate at a time
 * over the block, two pixels at once with SSE2 (the same IEEE operations). -1 where a cell is
 * not in the grid: a NaN direction (numpy's path raises IndexError there too) */
static int covers_block(const Faces *s, Py_ssize_t start, Py_ssize_t count, const double *every, uint8_t *flags) {
    const double whole = 6755399441055744.0;
    double at[BLOCK], index[BLOCK];
    for (Py_ssize_t j = 0; j < count; j++) at[j] = isfinite(every[j]) ? every[j] : 0.0;
    for (int k = 0; k < 3; k++) {
        const float *d = s->d + k * s->n + start;
        double o = s->o[k], inv = s->inv_mask, low = s->mask_origin[k] - 1.0, high = s->mask_origin[k] + (double)s->shape[k];
        double origin = s->mask_origin[k], top = (double)(s->shape[k] - 1), size = (double)s->shape[k];
        Py_ssize_t j = 0;
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
        flags[j] &= (uint8_t)(0xFE | (s->marked[i >> 3] >> (i & 7)));
    }
    return 0;
}

static inline void point_at(const Faces *s, Py_ssize_t ray, double t, double p[3]) {
    for (int k = 0; k < 3; k++) p[k] = s->o[k] + dir(s, k, ray) * t;
}

/* VisibleFaces._near_watched for one point of group g: whether it lies within the margin of a
 * watched edge; the groups across the creases it lies near are pushed as (ray, group) pairs */
static int near_watched(const Faces *s, int64_t g, const double p[3], Py_ssize_t ray, Vec *pair_ray, Vec *pair_group, int *near) {
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
static int64_t highest_holding(const Faces *s, Py_ssize_t at, const double p[3], Py_ssize_t ray) {
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

/* VisibleFaces._decide for every pixel, a block at a time: first for each pixel without a
 * branch (the CPU overlaps the pixels' divisions) the distance to its face's group plane
 * (_face_distance: inf where parallel or nothing is hit) and whether its hit can be decided
 * otherwise (a watched group's hit, in a near cell where skip asks, or a rival overlapping its
 * face from the side met: _side); then those hits' exact tests. The crease pairs they find are
 * pushed, in pixel order */
enum { WATCHED = 1, MET = 2, RIVAL = 4, FINITE_HIT = 8 };
enum { NO_MEMORY = -1, NOT_FINITE = -2, BEYOND = -3 }; /* what stopped the loops */
static int decide_rays(const Faces *s, const int64_t *tri, int want, int skip, int64_t *shown, double *t, Vec *crease_ray, Vec *crease_group) {
    int masked = skip && s->has_mask;
    double every[BLOCK];
    uint8_t flags[BLOCK];
    int beyond = 0; /* a triangle index beyond the mesh's faces */
    /* (the struct's fields read once: the byte stores below may alias anything) */
    const float *dx = s->d, *dy = s->d + s->n, *dz = s->d + 2 * s->n;
    const double *face_row = s->face_row;
    const uint8_t *face_flags = s->face_flags;
    const Py_ssize_t faces = s->faces;
    for (Py_ssize_t start = 0; start < s->n; start += BLOCK) {
        Py_ssize_t count = s->n - start < BLOCK ? s->n - start : BLOCK;
        for (Py_ssize_t j = 0; j < count; j++) {
            Py_ssize_t i = start + j;
            int64_t f = tri[i];
            int hit = f >= 0;
            beyond |= f >= faces;
            int64_t face = hit && f < faces ? f : 0;
            const double *row = face_row + 8 * face;
            double d0 = dx[i], d1 = dy[i], d2 = dz[i];
            double along = row[0] * d0;
            along += row[1] * d1;
            along += row[2] * d2;
            double q = row[3] / along;
            double e = (hit && along != 0) ? q : INFINITY;
            double facing = row[4] * d0;
            facing += row[5] * d1;
            facing += row[6] * d2;
            int met = facing >= 0, bits = face_flags[face];
            flags[j] = (uint8_t)((bits & WATCHED) | (met ? MET : 0) | (((bits >> (1 + met)) & 1) ? RIVAL : 0) | (hit && isfinite(e) ? FINITE_HIT : 0));
            every[j] = e;
            shown[i] = f;
            if (want) t[i] = e;
        }
        if (beyond) return BEYOND;
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
            int64_t f = tri[i], g = s->group[f];
            double p[3];
            point_at(s, i, every[j], p);
            int near;
            if (near_watched(s, g, p, i, crease_ray, crease_group, &near)) return -1;
            if (!((bits & RIVAL) || near)) continue;
            Py_ssize_t at = find_memo(s->face_memo, s->face_keys, s->keys, key_of(g, p, s->inv_cell));
            if (at < 0 || !s->mixed[at]) continue;
            int64_t best = highest_holding(s, at, p, i);
            shown[i] = best >= 0 ? best : f;
        }
    }
    return 0;
}

/* a row's outline values and groups: of the face each pixel shows (-1: none), as the exact tests
 * left it */
static void outline_row(const Faces *s, const int64_t *shown, Py_ssize_t width, int32_t *seen, int32_t *group) {
    for (Py_ssize_t x = 0; x < width; x++) {
        seen[x] = shown[x] >= 0 ? s->outline[shown[x]] : -1;
        group[x] = shown[x] >= 0 ? (int32_t)s->group[shown[x]] : -1;
    }
}

/* whether one of pixel x's 8 neighbours in the frame (the rows above and below: NULL beyond the
 * frame) shows another outline value */
static inline uint8_t differs_around(const int32_t *up, const int32_t *row, const int32_t *down, Py_ssize_t x, Py_ssize_t width) {
    const int32_t *rows[3] = {up, row, down};
    for (int r = 0; r < 3; r++) {
        if (!rows[r]) continue;
        for (Py_ssize_t u = x > 0 ? x - 1 : 0; u <= x + 1 && u < width; u++)
            if (rows[r][u] != row[x]) return 1;
    }
    return 0;
}

/* differs_around for a row: its inner pixels in one branchless pass (it vectorizes) */
static void outline_edges(const int32_t *up, const int32_t *row, const int32_t *down, Py_ssize_t width, uint8_t *edge) {
    if (!up || !down || width < 3) {
        for (Py_ssize_t x = 0; x < width; x++) edge[x] = differs_around(up, row, down, x, width);
        return;
    }
    edge[0] = differs_around(up, row, down, 0, width);
    for (Py_ssize_t x = 1; x < width - 1; x++) {
        int32_t c = row[x];
        edge[x] = (uint8_t)((up[x - 1] != c) | (up[x] != c) | (up[x + 1] != c) | (row[x - 1] != c) | (row[x + 1] != c) | (down[x - 1] != c) |
                            (down[x] != c) | (down[x + 1] != c));
    }
    edge[width - 1] = differs_around(up, row, down, width - 1, width);
}

/* a (ray, candidate group) pair the ray reaches: its distance and point */
typedef struct {
    int64_t group;
    double dist, p[3];
} Reach;

typedef struct {
    Reach *v;
    size_t n, cap;
} Reaches;

/* VisibleFaces._reachable for one pair: whether the ray meets group g's plane ahead, at a point
 * inside the group's box (then pushed) */
static int reach(const Faces *s, int64_t g, Py_ssize_t ray, Reaches *out) {
    const double *row = s->group_row + 12 * g;
    double along = row[0] * dir(s, 0, ray);
    along += row[1] * dir(s, 1, ray);
    along += row[2] * dir(s, 2, ray);
    double dist = along != 0 ? row[3] / along : INFINITY;
    if (!(isfinite(dist) && dist > 0)) return 0;
    Reach r = {g, dist, {0, 0, 0}};
    point_at(s, ray, dist, r.p);
    for (int k = 0; k < 3; k++)
        if (!(r.p[k] >= row[4 + k] && r.p[k] <= row[7 + k])) return 0;
    if (out->n == out->cap) {
        size_t cap = out->cap ? 2 * out->cap : 64;
        Reach *v = realloc(out->v, cap * sizeof *v);
        if (!v) return -1;
        out->v = v;
        out->cap = cap;
    }
    out->v[out->n++] = r;
    return 0;
}

static int contains(const int64_t *v, size_t n, int64_t x) {
    for (size_t k = 0; k < n; k++)
        if (v[k] == x) return 1;
    return 0;
}

/* VisibleFaces.decide_image's candidates for pixel i: the distinct groups its 3x3 neighbourhood
 * shows (on an outline; a neighbour beyond the border: the border pixel), those across a crease
 * near its hit, and those across a crease near where its ray meets one of them; it shows the
 * nearest whose faces hold the ray (a tie: the highest face), tested nearest first
 * (VisibleFaces._nearest_holding), and is left as it is where none does */
typedef struct {
    Vec cand, extra_ray, extra_group;
    Reaches reached;
    Vec ray, face, dist; /* the pixels decided, written to the frame once all are (dist: the
                          * float64's bits) */
} Scratch;

static int resolve(const Faces *s, Scratch *w, const int32_t *const rows[3], int edge, Py_ssize_t i, Py_ssize_t x, Py_ssize_t width,
                   const int64_t *crease, size_t creases) {
    w->cand.n = w->extra_ray.n = w->extra_group.n = w->reached.n = 0;
    if (edge) {
        for (int r = 0; r < 3; r++)
            for (Py_ssize_t dx = -1; dx <= 1; dx++) {
                Py_ssize_t u = x + dx < 0 ? 0 : (x + dx >= width ? width - 1 : x + dx);
                int64_t g = rows[r][u];
                if (g >= 0 && !contains(w->cand.v, w->cand.n, g) && push(&w->cand, g)) return -1;
            }
    }
    for (size_t k = 0; k < creases; k++)
        if (!contains(w->cand.v, w->cand.n, crease[k]) && push(&w->cand, crease[k])) return -1;
    for (size_t k = 0; k < w->cand.n; k++)
        if (reach(s, w->cand.v[k], i, &w->reached)) return -1;
    /* the groups across a crease near where the ray meets a candidate (a candidate not reached
     * is not reached either when it comes again) */
    size_t first = w->reached.n;
    int near;
    for (size_t k = 0; k < first; k++)
        if (near_watched(s, w->reached.v[k].group, w->reached.v[k].p, i, &w->extra_ray, &w->extra_group, &near)) return -1;
    for (size_t k = 0; k < w->extra_group.n; k++) {
        int64_t g = w->extra_group.v[k];
        if (contains(w->cand.v, w->cand.n, g)) continue;
        if (push(&w->cand, g) || reach(s, g, i, &w->reached)) return -1;
    }
    Reach *r = w->reached.v;
    size_t live = w->reached.n;
    while (live) {
        double nearest = r[0].dist;
        for (size_t k = 1; k < live; k++)
            if (r[k].dist < nearest) nearest = r[k].dist;
        int64_t best = -1;
        for (size_t k = 0; k < live;) {
            if (r[k].dist != nearest) {
                k++;
                continue;
            }
            Py_ssize_t at = find_memo(s->face_memo, s->face_keys, s->keys, key_of(r[k].group, r[k].p, s->inv_cell));
            if (at >= 0) {
                int64_t face = highest_holding(s, at, r[k].p, i);
                if (face > best) best = face;
            }
            r[k] = r[--live];
        }
        if (best >= 0) {
            int64_t bits;
            memcpy(&bits, &nearest, sizeof bits);
            if (push(&w->ray, i) || push(&w->face, best) || push(&w->dist, bits)) return -1;
            break;
        }
    }
    return 0;
}

/* every pixel on an outline or near a crease, resolved among its candidates, a row at a time
 * (three rows of outline values kept); the neighbourhoods are read as the exact tests left
 * them: the pixels resolved are written once all are */
static int resolve_pixels(const Faces *s, Py_ssize_t height, Py_ssize_t width, const Vec *crease_ray, const Vec *crease_group, int64_t *shown, double *t) {
    Scratch w;
    memset(&w, 0, sizeof w);
    int32_t *seen = malloc((size_t)(6 * width + 1) * sizeof(int32_t)), *group = seen + 3 * width;
    uint8_t *edge = malloc((size_t)width + 1);
    int failed = !seen || !edge;
    size_t c = 0;
    if (!failed && height > 0) outline_row(s, shown, width, seen, group);
    for (Py_ssize_t y = 0; y < height && !failed; y++) {
        if (y + 1 < height) outline_row(s, shown + (y + 1) * width, width, seen + ((y + 1) % 3) * width, group + ((y + 1) % 3) * width);
        const int32_t *up = y > 0 ? seen + ((y - 1) % 3) * width : NULL, *down = y + 1 < height ? seen + ((y + 1) % 3) * width : NULL;
        outline_edges(up, seen + (y % 3) * width, down, width, edge);
        /* the groups of the rows above, of this one and below (beyond the border: the border's) */
        const int32_t *rows[3] = {group + ((y > 0 ? y - 1 : y) % 3) * width, group + (y % 3) * width, group + ((y + 1 < height ? y + 1 : y) % 3) * width};
        Py_ssize_t next = c < crease_ray->n ? crease_ray->v[c] - y * width : width; /* the row's next crease pixel */
        for (Py_ssize_t x = 0; x < width && !failed; x++) {
            if (x + 8 <= width && x + 8 <= next) { /* eight pixels on no outline and no crease: skipped at once */
                uint64_t eight;
                memcpy(&eight, edge + x, 8);
                if (!eight) {
                    x += 7;
                    continue;
                }
            }
            Py_ssize_t i = y * width + x;
            if (!edge[x] && (c == crease_ray->n || crease_ray->v[c] != i)) continue;
            size_t from = c;
            while (c < crease_ray->n && crease_ray->v[c] == i) c++;
            failed = resolve(s, &w, rows, edge[x], i, x, width, c > from ? crease_group->v + from : NULL, c - from);
            next = c < crease_ray->n ? crease_ray->v[c] - y * width : width;
        }
    }
    for (size_t k = 0; k < w.ray.n && !failed; k++) {
        shown[w.ray.v[k]] = w.face.v[k];
        if (t) memcpy(&t[w.ray.v[k]], &w.dist.v[k], sizeof(double));
    }
    free(seen);
    free(edge);
    free(w.ray.v);
    free(w.face.v);
    free(w.dist.v);
    free(w.cand.v);
    free(w.extra_ray.v);
    free(w.extra_group.v);
    free(w.reached.v);
    return failed;
}

static const char *const TABLE_NAMES[T_COUNT] = {
    "group", "plane", "holding", "group_watching", "overlapped", "outline",
    "group_normal", "group_offset", "box", "watching", "face_keys", "face_starts", "face_items", "mixed",
    "edge_keys", "edge_starts", "edge_items", "edge_rows", "across", "marked",
};

/* the tables' buffers, their sizes checked against each other (F faces, G groups, E edges) */
static int read_tables(PyObject *tables, Py_buffer *views, Faces *s) {
    if (!PyTuple_Check(tables) || PyTuple_GET_SIZE(tables) != T_COUNT) {
        PyErr_SetString(PyExc_ValueError, "decide_image: tables must be a tuple of the arrays enum Table lists");
        return -1;
    }
    for (int k = 0; k < T_COUNT; k++) {
        if (PyObject_GetBuffer(PyTuple_GET_ITEM(tables, k), &views[k], PyBUF_C_CONTIGUOUS) < 0) {
            for (int j = 0; j < k; j++) PyBuffer_Release(&views[j]);
            return -1;
        }
    }
#define LEN(k, size) (views[k].len / (size))
    Py_ssize_t F = LEN(T_GROUP, 8), G = LEN(T_GROUP_OFFSET, 8), E = LEN(T_EDGE_ROWS, 80), K = LEN(T_FACE_KEYS, 8), W = LEN(T_EDGE_KEYS, 8);
    Py_ssize_t expected[T_COUNT] = {
        8 * F, 32 * F, 128 * F, F, 2 * F, 4 * F,
        24 * G, 8 * G, 48 * G, G,
        8 * K, 8 * (K + 1), -1, K,
        8 * W, 8 * (W + 1), -1,
        80 * E, 16 * E,
        s->has_mask ? (s->shape[0] * s->shape[1] * s->shape[2] + 7) / 8 : -1,
    };
#undef LEN
    for (int k = 0; k < T_COUNT; k++) {
        if (expected[k] >= 0 && views[k].len != expected[k]) {
            PyErr_Format(PyExc_ValueError, "decide_image: table %s has %zd bytes, not %zd", TABLE_NAMES[k], views[k].len, expected[k]);
            for (int j = 0; j < T_COUNT; j++) PyBuffer_Release(&views[j]);
            return -1;
        }
    }
    s->faces = F, s->groups = G, s->edge_count = E, s->keys = K, s->edge_key_count = W;
    s->group = views[T_GROUP].buf, s->plane = views[T_PLANE].buf, s->holding = views[T_HOLDING].buf;
    s->group_watching = views[T_GROUP_WATCHING].buf, s->overlapped = views[T_OVERLAPPED].buf;
    s->outline = views[T_OUTLINE].buf;
    s->group_normal = views[T_GROUP_NORMAL].buf, s->group_offset = views[T_GROUP_OFFSET].buf, s->box = views[T_BOX].buf;
    s->watching = views[T_WATCHING].buf;
    s->face_keys = views[T_FACE_KEYS].buf, s->face_starts = views[T_FACE_STARTS].buf, s->face_items = views[T_FACE_ITEMS].buf;
    s->mixed = views[T_MIXED].buf;
    s->edge_keys = views[T_EDGE_KEYS].buf, s->edge_starts = views[T_EDGE_STARTS].buf, s->edge_items = views[T_EDGE_ITEMS].buf;
    s->edge_rows = views[T_EDGE_ROWS].buf, s->across = views[T_ACROSS].buf, s->marked = views[T_MARKED].buf;
    return 0;
}

static PyObject *decide_image(PyObject *self, PyObject *args) {
    PyObject *tables, *numbers;
    Py_buffer tri, directions, shown, t, views[T_COUNT];
    Py_ssize_t height, width;
    int want, skip;
    Faces s;
    memset(&s, 0, sizeof s);
    if (!PyArg_ParseTuple(args, "OO!y*(ddd)y*nnppw*w*", &tables, &PyTuple_Type, &numbers, &tri, &s.o[0], &s.o[1], &s.o[2], &directions, &height, &width, &want, &skip, &shown, &t))
        return NULL;
    PyObject *result = NULL;
    int tables_read = 0;
    Vec crease_ray = {0}, crease_group = {0};
    if (!PyArg_ParseTuple(numbers, "dddnnnpddddd", &s.mask_origin[0], &s.mask_origin[1], &s.mask_origin[2], &s.shape[0], &s.shape[1], &s.shape[2],
                          &s.has_mask, &s.inv_mask, &s.inv_cell, &s.inv_edge_cell, &s.margin, &s.tolerance))
        goto done;
    if (read_tables(tables, views, &s) < 0) goto done;
    tables_read = 1;
    s.n = height * width;
    if (height < 0 || width < 0 || tri.len != 8 * s.n || directions.len != 12 * s.n || shown.len != 8 * s.n || t.len != (want ? 8 * s.n : 0)) {
        PyErr_SetString(PyExc_ValueError, "decide_image: the pixel arrays' sizes do not match height and width");
        goto done;
    }
    const int64_t *faces_in = tri.buf;
    s.d = directions.buf;
    s.face_row = malloc((size_t)(8 * s.faces + 12 * s.groups + 1) * sizeof(double));
    s.face_flags = malloc((size_t)s.faces + 1);
    s.face_memo = malloc(2 * sizeof(Memo));
    if (!s.face_row || !s.face_flags || !s.face_memo) {
        PyErr_NoMemory();
        goto done;
    }
    s.group_row = s.face_row + 8 * s.faces;
    s.edge_memo = s.face_memo + 1;
    memo_clear(s.face_memo);
    memo_clear(s.edge_memo);
    /* the plane's offset from the one origin, once per face and once per group, as numpy sums
     * it; each face's numbers side by side (one cache line, where the pixels gather them) */
    for (Py_ssize_t f = 0; f < s.faces; f++) {
        Py_ssize_t F = s.faces;
        double *row = s.face_row + 8 * f;
        row[0] = s.plane[f], row[1] = s.plane[F + f], row[2] = s.plane[2 * F + f];
        row[3] = s.plane[3 * F + f] - (s.plane[f] * s.o[0] + s.plane[F + f] * s.o[1] + s.plane[2 * F + f] * s.o[2]);
        row[4] = s.holding[16 * f], row[5] = s.holding[16 * f + 1], row[6] = s.holding[16 * f + 2], row[7] = 0;
        s.face_flags[f] = (uint8_t)((s.group_watching[f] ? 1 : 0) | (s.overlapped[2 * f] ? 2 : 0) | (s.overlapped[2 * f + 1] ? 4 : 0));
    }
    for (Py_ssize_t g = 0; g < s.groups; g++) {
        Py_ssize_t G = s.groups;
        double *row = s.group_row + 12 * g;
        row[0] = s.group_normal[g], row[1] = s.group_normal[G + g], row[2] = s.group_normal[2 * G + g];
        row[3] = s.group_offset[g] - (s.group_normal[g] * s.o[0] + s.group_normal[G + g] * s.o[1] + s.group_normal[2 * G + g] * s.o[2]);
        for (int k = 0; k < 6; k++) row[4 + k] = s.box[k * G + g];
        row[10] = row[11] = 0;
    }
    int failed = 0;
    Py_BEGIN_ALLOW_THREADS
    failed = decide_rays(&s, faces_in, want, skip, shown.buf, t.buf, &crease_ray, &crease_group);
    if (!failed) failed = resolve_pixels(&s, height, width, &crease_ray, &crease_group, shown.buf, want ? t.buf : NULL);
    Py_END_ALLOW_THREADS
    if (failed == BEYOND) {
        PyErr_SetString(PyExc_IndexError, "decide_image: a triangle index beyond the mesh's faces");
        goto done;
    }
    if (failed == NOT_FINITE) {
        PyErr_SetString(PyExc_IndexError, "decide_image: a ray's hit lies in no cell (a direction is not finite)");
        goto done;
    }
    if (failed) {
        PyErr_NoMemory();
        goto done;
    }
    result = Py_None;
    Py_INCREF(result);
done:
    free(s.face_row);
    free(s.face_flags);
    free(s.face_memo);
    free(crease_ray.v);
    free(crease_group.v);
    if (tables_read)
        for (int k = 0; k < T_COUNT; k++) PyBuffer_Release(&views[k]);
    PyBuffer_Release(&tri);
    PyBuffer_Release(&directions);
    PyBuffer_Release(&shown);
    PyBuffer_Release(&t);
    return result;
}

static PyMethodDef methods[] = {
    {"decide_image", decide_image, METH_VARARGS, "The face each pixel of a camera shows and its distance (VisibleFaces.decide_image)."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_visible_face", "Which face each pixel shows (compiled loop of visible_face).", -1, methods};

PyMODINIT_FUNC PyInit__visible_face(void) { return PyModule_Create(&module); }
