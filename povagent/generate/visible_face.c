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
 *   1 / CELL, 1 / EDGE_CELL, EDGE_MARGIN, CONTAINS_TOLERANCE); tri: embree's triangle per
 *   pixel (-1: none), int32 (as embree gives it) or int64; origin: (x, y, z); directions:
 *   float32 (3, height * width) rows; shown: out, the face shown per pixel, int32 or int64;
 *   t: out, its distance, float64 or float32 (the float64 rounded; empty unless
 *   want_distance), written in place (each kind told by its buffer's size). IndexError, as
 *   numpy's path raises it, for a triangle beyond the mesh or a direction that is not finite
 *   (where the near cells are looked up); ValueError for arrays whose sizes do not match, or an
 *   int64 triangle below int32's range (the faces are kept as int32).
 *
 * The passes: every pixel's distance and flags a block at a time, the exact tests of the few
 * hits that can be decided otherwise (visible_face_rays.c), then row by row the outline (three
 * rows of outline values kept) and each outline or crease pixel's candidates
 * (visible_face_outline.c); this file reads the arguments and runs them. The shared tables and
 * lookups: visible_face.h.
 */
#include "visible_face.h"
/* one translation unit (visible_face.h says why) */
#include "visible_face_rays.c"
#include "visible_face_outline.c"

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
    Pixels px = {0};
    int shown32 = 0;
    if (!PyArg_ParseTuple(numbers, "dddnnnpddddd", &s.mask_origin[0], &s.mask_origin[1], &s.mask_origin[2], &s.shape[0], &s.shape[1], &s.shape[2],
                          &s.has_mask, &s.inv_mask, &s.inv_cell, &s.inv_edge_cell, &s.margin, &s.tolerance))
        goto done;
    if (read_tables(tables, views, &s) < 0) goto done;
    tables_read = 1;
    s.n = height * width;
    shown32 = shown.len == 4 * s.n;
    int tri32 = tri.len == 4 * s.n, t32 = want && t.len == 4 * s.n;
    if (height < 0 || width < 0 || (!tri32 && tri.len != 8 * s.n) || directions.len != 12 * s.n || (!shown32 && shown.len != 8 * s.n) ||
        (want ? !t32 && t.len != 8 * s.n : t.len != 0) || s.faces > INT32_MAX) {
        PyErr_SetString(PyExc_ValueError, "decide_image: the pixel arrays' sizes do not match height and width");
        goto done;
    }
    px.tri = tri.buf, px.tri32 = tri32, px.t32 = t32, px.t = t.buf;
    px.shown = shown32 ? shown.buf : malloc((size_t)(s.n + 1) * sizeof(int32_t));
    s.d = directions.buf;
    s.face_row = malloc((size_t)(8 * s.faces + 12 * s.groups + 1) * sizeof(double));
    s.face_looks = malloc((size_t)(s.faces + 1) * sizeof(int64_t));
    s.face_memo = malloc(2 * sizeof(Memo));
    if (!s.face_row || !s.face_looks || !s.face_memo || !px.shown) {
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
        row[4] = s.holding[16 * f], row[5] = s.holding[16 * f + 1], row[6] = s.holding[16 * f + 2];
        int64_t bits = (s.group_watching[f] ? WATCHED : 0) | (s.overlapped[2 * f] ? 2 : 0) | (s.overlapped[2 * f + 1] ? 4 : 0);
        memcpy(row + 7, &bits, sizeof bits); /* the flags' bits (pixel_block) */
        s.face_looks[f] = (int64_t)(((uint64_t)(uint32_t)s.group[f] << 32) | (uint32_t)s.outline[f]);
    }
    s.face_looks[s.faces] = -1;
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
    failed = vf_decide_rays(&s, &px, want, skip, &crease_ray, &crease_group);
    if (!failed) failed = vf_resolve_pixels(&s, height, width, &crease_ray, &crease_group, &px, want);
    if (!failed && !shown32)
        for (Py_ssize_t i = 0; i < s.n; i++) ((int64_t *)shown.buf)[i] = px.shown[i];
    Py_END_ALLOW_THREADS
    if (failed == BEYOND) {
        PyErr_SetString(PyExc_IndexError, "decide_image: a triangle index beyond the mesh's faces");
        goto done;
    }
    if (failed == BELOW) {
        PyErr_SetString(PyExc_ValueError, "decide_image: an int64 triangle index below int32's range");
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
    if (!shown32) free(px.shown);
    free(s.face_row);
    free(s.face_looks);
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

PyMODINIT_FUNC PyInit__visible_face(void) {
#ifdef HAS_AVX_PATH
    __builtin_cpu_init();
    cpu_has_avx = __builtin_cpu_supports("avx") ? 1 : 0;
    cpu_has_avx2 = __builtin_cpu_supports("avx2") ? 1 : 0;
#endif
    return PyModule_Create(&module);
}
