/* What the three C files of the compiled loop of VisibleFaces.decide_image share: the tables
 * (struct Faces, read by visible_face.c from the arrays visible_face_loop.py lays out), the cell
 * keys and their lookup. visible_face.c says what the loop does, and includes the other two
 * files: one translation unit, so the compiler inlines the tests into the passes as before the
 * split (three units cost about 4% of the loop's time). */
#ifndef POVAGENT_VISIBLE_FACE_H
#define POVAGENT_VISIBLE_FACE_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

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
                           * its own normal and its flags' bits as an int64: its group watched
                           * (WATCHED), overlapped from side 0 (2), side 1 (4) (one cache line a
                           * face, where the pixels gather) */
    int64_t *face_looks;  /* (F + 1,) each face's outline value (low 32 bits) and group (high 32
                           * bits), then -1 and -1 for no face */
    double *group_row;    /* (G, 12) each group's plane normal, its offset from the origin and
                           * its box */
    Memo *face_memo, *edge_memo;
} Faces;

typedef struct {
    int64_t *v;
    size_t n, cap;
} Vec;

/* one call's pixels: embree's triangles in (int32 or int64), the faces shown out (int32; the
 * caller's or, for an int64 answer, widened into it at the end) and their distances (float32 or
 * float64: the float64's rounding) */
typedef struct {
    const void *tri;
    int tri32, t32;
    int32_t *shown;
    void *t;
} Pixels;

static inline int push(Vec *a, int64_t x) {
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

static inline void memo_clear(Memo *m) {
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

static inline void point_at(const Faces *s, Py_ssize_t ray, double t, double p[3]) {
    for (int k = 0; k < 3; k++) p[k] = s->o[k] + dir(s, k, ray) * t;
}

/* the simple loops over a row's pixels are built for each CPU kind (vector_clones.h; integer
 * loads and comparisons: the same values either way) */
#include "vector_clones.h"

/* the pixels are decided a block at a time */
#define BLOCK 256

enum { WATCHED = 1, MET = 2, RIVAL = 4, FINITE_HIT = 8 };
enum { NO_MEMORY = -1, NOT_FINITE = -2, BEYOND = -3, BELOW = -4 }; /* what stopped the loops */

#endif
