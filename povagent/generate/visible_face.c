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
 *   want_distance). Returns (crease rays, crease groups, outline pixels) as int64 bytes.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

enum Table {
    T_GROUP, T_PLANE, T_OWN, T_OPEN, T_EDGES, T_GROUP_WATCHING, T_OVERLAPPED, T_OVERLAPPED_ANY, T_OUTLINE,
    T_GROUP_NORMAL, T_GROUP_OFFSET, T_BOX, T_WATCHING,
    T_FACE_KEYS, T_FACE_STARTS, T_FACE_ITEMS, T_MIXED,
    T_EDGE_KEYS, T_EDGE_STARTS, T_EDGE_ITEMS,
    T_LINE, T_ALONG, T_ACROSS, T_MARKED,
    T_COUNT
};

/* (cell_table.py) keys pack a cell's coordinates, this many values an axis */
#define CELL_SPAN 2048
#define HALF_SPAN 1024

typedef struct {
    const int64_t *group;          /* (F,) each face's group */
    const double *plane;           /* (4, F) each face's group plane: normal, offset */
    const double *own;             /* (3, F) each face's own normal */
    const uint8_t *open;           /* (F,) not a closed solid's face */
    const double *edges;           /* (3 edges, 4, F) inward edge normal and offset */
    const uint8_t *group_watching; /* (F,) the face's group has a watched edge */
    const uint8_t *overlapped;     /* (2 F,) face * 2 + side */
    const uint8_t *overlapped_any; /* (F,) */
    const int32_t *outline;        /* (F,) what tells two pixels apart */
    const double *group_normal;    /* (3, G) */
    const double *group_offset;    /* (G,) */
    const double *box;             /* (6, G) low x, y, z, high x, y, z */
    const uint8_t *watching;       /* (G,) the group has a watched edge */
    const int64_t *face_keys, *face_starts, *face_items;
    const uint8_t *mixed;          /* (K,) the key's faces do not all look alike */
    const int64_t *edge_keys, *edge_starts, *edge_items;
    const double *line;            /* (4, E) each watched edge's in-plane line */
    const double *along;           /* (5, E) its direction, extent */
    const int64_t *across;         /* (E, 2) the groups across it, -1: none */
    const uint8_t *marked;         /* the near cells' grid */
    Py_ssize_t faces, groups, edge_count, keys, edge_key_count;
    Py_ssize_t shape[3];
    int has_mask;
    double mask_origin[3], inv_mask, inv_cell, inv_edge_cell, margin, tolerance;
    /* per call */
    double o[3];
    const float *d;
    Py_ssize_t n;
    double *face_across;  /* (F,) each face's group plane offset from the origin */
    double *group_across; /* (G,) */
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

/* cell_table.cell then key_of's clip: floor(p * inv) as numpy casts it to int64 on x86 (a value
 * out of int64's range becomes its least, so it clips to the low end) */
static inline int64_t cell_of(double p, double inv) {
    double c = floor(p * inv);
    int64_t v = (c >= -9223372036854775808.0 && c < 9223372036854775808.0) ? (int64_t)c : INT64_MIN;
    if (v < -HALF_SPAN) v = -HALF_SPAN;
    if (v > HALF_SPAN - 1) v = HALF_SPAN - 1;
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

/* CellMask.covers: whether the point lies in a marked cell (whole numbers in float64, exact) */
static inline int covers(const Faces *s, const double p[3]) {
    Py_ssize_t index = 0;
    for (int k = 0; k < 3; k++) {
        double c = floor(p[k] * s->inv_mask) - s->mask_origin[k];
        double top = (double)(s->shape[k] - 1);
        c = c < 0 ? 0 : (c > top ? top : c);
        index = index * s->shape[k] + (Py_ssize_t)c;
    }
    return s->marked[index];
}

static inline double dir(const Faces *s, int k, Py_ssize_t ray) { return (double)s->d[k * s->n + ray]; }

/* VisibleFaces._face_distance: along ray to face f's group plane (inf where parallel) */
static inline double face_distance(const Faces *s, Py_ssize_t f, Py_ssize_t ray) {
    Py_ssize_t F = s->faces;
    double along = s->plane[f] * dir(s, 0, ray);
    along += s->plane[F + f] * dir(s, 1, ray);
    along += s->plane[2 * F + f] * dir(s, 2, ray);
    return along != 0 ? s->face_across[f] / along : INFINITY;
}

/* VisibleFaces._side: 0 where the ray meets face f against its normal, 1 along it */
static inline int side(const Faces *s, Py_ssize_t f, Py_ssize_t ray) {
    Py_ssize_t F = s->faces;
    double facing = s->own[f] * dir(s, 0, ray);
    facing += s->own[F + f] * dir(s, 1, ray);
    facing += s->own[2 * F + f] * dir(s, 2, ray);
    return facing >= 0;
}

static inline void point_at(const Faces *s, Py_ssize_t ray, double t, double p[3]) {
    for (int k = 0; k < 3; k++) p[k] = s->o[k] + dir(s, k, ray) * t;
}

/* VisibleFaces._near_watched for one point of group g: whether it lies within the margin of a
 * watched edge; the groups across the creases it lies near are pushed as (ray, group) pairs */
static int near_watched(const Faces *s, int64_t g, const double p[3], Py_ssize_t ray, Vec *pair_ray, Vec *pair_group, int *near) {
    *near = 0;
    if (!s->watching[g]) return 0;
    Py_ssize_t at = find(s->edge_keys, s->edge_key_count, key_of(g, p, s->inv_edge_cell));
    if (at < 0) return 0;
    Py_ssize_t E = s->edge_count;
    double m = s->margin;
    for (int64_t j = s->edge_starts[at]; j < s->edge_starts[at + 1]; j++) {
        int64_t e = s->edge_items[j];
        double off = s->line[e] * p[0];
        off += s->line[E + e] * p[1];
        off += s->line[2 * E + e] * p[2];
        off -= s->line[3 * E + e];
        double pos = s->along[e] * p[0];
        pos += s->along[E + e] * p[1];
        pos += s->along[2 * E + e] * p[2];
        if (!(fabs(off) < m && pos > s->along[3 * E + e] - m && pos < s->along[4 * E + e] + m)) continue;
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
    Py_ssize_t F = s->faces;
    double d0 = dir(s, 0, ray), d1 = dir(s, 1, ray), d2 = dir(s, 2, ray);
    for (int64_t j = s->face_starts[at]; j < s->face_starts[at + 1]; j++) {
        int64_t g = s->face_items[j];
        double facing = s->own[g] * d0;
        facing += s->own[F + g] * d1;
        facing += s->own[2 * F + g] * d2;
        if (!(s->open[g] || facing < 0)) continue;
        int inside = 1;
        for (int e = 0; e < 3 && inside; e++) {
            const double *m = s->edges + (Py_ssize_t)e * 4 * F;
            double signed_ = m[g] * p[0];
            signed_ += m[F + g] * p[1];
            signed_ += m[2 * F + g] * p[2];
            signed_ -= m[3 * F + g];
            inside = signed_ >= -s->tolerance;
        }
        if (inside) return g;
    }
    return -1;
}

/* VisibleFaces._decide for every pixel: the distance to its face's group plane, and where the
 * hit can be decided otherwise (a watched group's hit in a near cell, or a rival overlapping
 * its face from the side met), the exact tests; the crease pairs they find are pushed */
static int decide_rays(const Faces *s, const int64_t *tri, int want, int skip, int64_t *shown, double *t, Vec *crease_ray, Vec *crease_group) {
    int masked = skip && s->has_mask;
    for (Py_ssize_t i = 0; i < s->n; i++) {
        int64_t f = tri[i];
        shown[i] = f;
        if (f < 0) {
            if (want) t[i] = INFINITY;
            continue;
        }
        double every = 0;
        int computed = want || masked;
        if (computed) every = face_distance(s, f, i);
        if (want) t[i] = every;
        int examined = s->group_watching[f];
        double p[3];
        if (masked && examined) {
            point_at(s, i, isfinite(every) ? every : 0.0, p);
            examined = covers(s, p);
        }
        if (!examined && s->overlapped_any[f]) examined = s->overlapped[2 * f + side(s, f, i)];
        if (!examined) continue;
        if (!computed) every = face_distance(s, f, i);
        if (!isfinite(every)) continue;
        point_at(s, i, every, p);
        int64_t g = s->group[f];
        int near;
        if (near_watched(s, g, p, i, crease_ray, crease_group, &near)) return -1;
        if (!(s->overlapped[2 * f + side(s, f, i)] || near)) continue;
        Py_ssize_t at = find(s->face_keys, s->keys, key_of(g, p, s->inv_cell));
        if (at < 0 || !s->mixed[at]) continue;
        int64_t best = highest_holding(s, at, p, i);
        shown[i] = best >= 0 ? best : f;
    }
    return 0;
}

/* per pixel, what tells it from its neighbours (outline of the face shown, -1: none) */
static void outline_of(const Faces *s, const int64_t *shown, int32_t *seen) {
    for (Py_ssize_t i = 0; i < s->n; i++) seen[i] = shown[i] >= 0 ? s->outline[shown[i]] : -1;
}

/* whether one of the pixel's 8 neighbours in the frame shows another outline value */
static inline int on_outline(const int32_t *seen, Py_ssize_t y, Py_ssize_t x, Py_ssize_t height, Py_ssize_t width) {
    int32_t here = seen[y * width + x];
    for (Py_ssize_t v = y > 0 ? y - 1 : 0; v <= y + 1 && v < height; v++)
        for (Py_ssize_t u = x > 0 ? x - 1 : 0; u <= x + 1 && u < width; u++)
            if (seen[v * width + u] != here) return 1;
    return 0;
}

static const char *const TABLE_NAMES[T_COUNT] = {
    "group", "plane", "own", "open", "edges", "group_watching", "overlapped", "overlapped_any", "outline",
    "group_normal", "group_offset", "box", "watching", "face_keys", "face_starts", "face_items", "mixed",
    "edge_keys", "edge_starts", "edge_items", "line", "along", "across", "marked",
};

/* the tables' buffers, their sizes checked against each other (F faces, G groups, E edges) */
static int read_tables(PyObject *tables, Py_buffer *views, Faces *s) {
    if (!PyTuple_Check(tables) || PyTuple_GET_SIZE(tables) != T_COUNT) {
        PyErr_SetString(PyExc_ValueError, "decide_image: tables must be a tuple of the 24 arrays");
        return -1;
    }
    for (int k = 0; k < T_COUNT; k++) {
        if (PyObject_GetBuffer(PyTuple_GET_ITEM(tables, k), &views[k], PyBUF_C_CONTIGUOUS) < 0) {
            for (int j = 0; j < k; j++) PyBuffer_Release(&views[j]);
            return -1;
        }
    }
#define LEN(k, size) (views[k].len / (size))
    Py_ssize_t F = LEN(T_GROUP, 8), G = LEN(T_GROUP_OFFSET, 8), E = LEN(T_LINE, 32), K = LEN(T_FACE_KEYS, 8), W = LEN(T_EDGE_KEYS, 8);
    Py_ssize_t expected[T_COUNT] = {
        8 * F, 32 * F, 24 * F, F, 96 * F, F, 2 * F, F, 4 * F,
        24 * G, 8 * G, 48 * G, G,
        8 * K, 8 * (K + 1), -1, K,
        8 * W, 8 * (W + 1), -1,
        32 * E, 40 * E, 16 * E,
        s->has_mask ? s->shape[0] * s->shape[1] * s->shape[2] : -1,
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
    s->group = views[T_GROUP].buf, s->plane = views[T_PLANE].buf, s->own = views[T_OWN].buf, s->open = views[T_OPEN].buf;
    s->edges = views[T_EDGES].buf, s->group_watching = views[T_GROUP_WATCHING].buf, s->overlapped = views[T_OVERLAPPED].buf;
    s->overlapped_any = views[T_OVERLAPPED_ANY].buf, s->outline = views[T_OUTLINE].buf;
    s->group_normal = views[T_GROUP_NORMAL].buf, s->group_offset = views[T_GROUP_OFFSET].buf, s->box = views[T_BOX].buf;
    s->watching = views[T_WATCHING].buf;
    s->face_keys = views[T_FACE_KEYS].buf, s->face_starts = views[T_FACE_STARTS].buf, s->face_items = views[T_FACE_ITEMS].buf;
    s->mixed = views[T_MIXED].buf;
    s->edge_keys = views[T_EDGE_KEYS].buf, s->edge_starts = views[T_EDGE_STARTS].buf, s->edge_items = views[T_EDGE_ITEMS].buf;
    s->line = views[T_LINE].buf, s->along = views[T_ALONG].buf, s->across = views[T_ACROSS].buf, s->marked = views[T_MARKED].buf;
    return 0;
}

static PyObject *as_bytes(const Vec *a) { return PyBytes_FromStringAndSize((const char *)a->v, (Py_ssize_t)(a->n * sizeof(int64_t))); }

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
    Vec crease_ray = {0}, crease_group = {0}, pixels = {0};
    int32_t *seen = NULL;
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
    for (Py_ssize_t i = 0; i < s.n; i++) {
        if (faces_in[i] >= s.faces) {
            PyErr_SetString(PyExc_ValueError, "decide_image: a triangle index beyond the mesh's faces");
            goto done;
        }
    }
    s.d = directions.buf;
    s.face_across = malloc((size_t)(s.faces + s.groups + 1) * sizeof(double));
    seen = malloc((size_t)(s.n + 1) * sizeof(int32_t));
    if (!s.face_across || !seen) {
        PyErr_NoMemory();
        goto done;
    }
    s.group_across = s.face_across + s.faces;
    /* the plane's offset from the one origin, once per face and once per group, as numpy sums it */
    for (Py_ssize_t f = 0; f < s.faces; f++) {
        Py_ssize_t F = s.faces;
        s.face_across[f] = s.plane[3 * F + f] - (s.plane[f] * s.o[0] + s.plane[F + f] * s.o[1] + s.plane[2 * F + f] * s.o[2]);
    }
    for (Py_ssize_t g = 0; g < s.groups; g++) {
        Py_ssize_t G = s.groups;
        s.group_across[g] = s.group_offset[g] - (s.group_normal[g] * s.o[0] + s.group_normal[G + g] * s.o[1] + s.group_normal[2 * G + g] * s.o[2]);
    }
    int failed = 0;
    Py_BEGIN_ALLOW_THREADS
    failed = decide_rays(&s, faces_in, want, skip, shown.buf, t.buf, &crease_ray, &crease_group);
    if (!failed) {
        outline_of(&s, shown.buf, seen);
        for (Py_ssize_t y = 0; y < height && !failed; y++)
            for (Py_ssize_t x = 0; x < width && !failed; x++)
                if (on_outline(seen, y, x, height, width)) failed = push(&pixels, y * width + x);
    }
    Py_END_ALLOW_THREADS
    if (failed) {
        PyErr_NoMemory();
        goto done;
    }
    result = Py_BuildValue("(NNN)", as_bytes(&crease_ray), as_bytes(&crease_group), as_bytes(&pixels));
done:
    free(s.face_across);
    free(seen);
    free(crease_ray.v);
    free(crease_group.v);
    free(pixels.v);
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
