/* The PNG row filters of a frame, chosen as Pillow chooses them: the compiled loop of
 * povagent/generate/frame_png.py (whose numpy passes are the reference; the docstring there
 * lists the facts of Pillow's encoder this follows).
 *
 * filter_rows(pixels, height, width, planar, out): ``pixels`` holds height * width RGB pixels,
 * interleaved (planar 0: r, g, b per pixel, row after row) or as three planes (planar 1: every
 * red byte, then every green, then every blue); ``out`` (height * (3 * width + 1) bytes) gets
 * each row's filter-type byte and filtered bytes: of none, up, sub and paeth (tried in that
 * order, a tie kept by the earlier), the one whose bytes have the least sum of min(v, 256 - v);
 * the row above the first and the pixel left of the first are black.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* min(v, 256 - v): the byte read as signed, its absolute value */
static inline unsigned cost_of(uint8_t v) { int s = (int8_t)v; return (unsigned)(s < 0 ? -s : s); }

/* of the left a, above b and above-left c, the nearest to a + b - c (ties to a, then b),
 * written without branches so the loop vectorizes */
static inline uint8_t paeth(uint8_t a, uint8_t b, uint8_t c) {
    int16_t p = (int16_t)(b - c), q = (int16_t)(a - c);
    int16_t pa = p < 0 ? -p : p, pb = q < 0 ? -q : q, r = (int16_t)(p + q), pc = r < 0 ? -r : r;
    uint8_t bc = pb <= pc ? b : c;
    return (pa <= pb && pa <= pc) ? a : bc;
}

/* a row's passes are built for each CPU kind (vector_clones.h; integer arithmetic: the same
 * bytes either way) */
#include "vector_clones.h"

/* a row's pixels into ``here`` (interleaved), from three planes or an interleaved row */
VECTOR_CLONES
static void gather_row(const uint8_t *restrict r, const uint8_t *restrict g, const uint8_t *restrict b, Py_ssize_t width, uint8_t *restrict here) {
    for (Py_ssize_t x = 0; x < width; x++) {
        here[3 * x] = r[x];
        here[3 * x + 1] = g[x];
        here[3 * x + 2] = b[x];
    }
}

/* the up, sub and paeth bytes of a row (``here`` and ``above`` with three black bytes on their
 * left) into ``cand`` (one row each after the first, unused), and the four filters' costs: one
 * simple pass per filter, each vectorizes (the costs are integer sums) */
VECTOR_CLONES
static void filter_row(const uint8_t *restrict here, const uint8_t *restrict above, Py_ssize_t row, uint8_t *restrict cand, unsigned cost[4]) {
    uint8_t *restrict up = cand + row, *restrict sub = cand + 2 * row, *restrict pa = cand + 3 * row;
    unsigned c0 = 0, c1 = 0, c2 = 0, c3 = 0;
    for (Py_ssize_t i = 0; i < row; i++) c0 += cost_of(here[i]);
    for (Py_ssize_t i = 0; i < row; i++) { up[i] = (uint8_t)(here[i] - above[i]); c1 += cost_of(up[i]); }
    for (Py_ssize_t i = 0; i < row; i++) { sub[i] = (uint8_t)(here[i] - here[i - 3]); c2 += cost_of(sub[i]); }
    for (Py_ssize_t i = 0; i < row; i++) {
        pa[i] = (uint8_t)(here[i] - paeth(here[i - 3], above[i], above[i - 3]));
        c3 += cost_of(pa[i]);
    }
    cost[0] = c0, cost[1] = c1, cost[2] = c2, cost[3] = c3;
}

static PyObject *filter_rows(PyObject *self, PyObject *args) {
    Py_buffer pixels, out;
    Py_ssize_t height, width;
    int planar;
    if (!PyArg_ParseTuple(args, "y*nnpw*", &pixels, &height, &width, &planar, &out)) return NULL;
    PyObject *result = NULL;
    uint8_t *rows = NULL;
    Py_ssize_t row = 3 * width;
    if (height <= 0 || width <= 0 || pixels.len != height * row || out.len != height * (row + 1)) {
        PyErr_SetString(PyExc_ValueError, "filter_rows: the buffers' sizes do not match height and width");
        goto done;
    }
    /* two interleaved rows, each with three black bytes on its left: the row above, this row */
    rows = calloc(2 * (size_t)(row + 3), 1);
    uint8_t *cand = malloc(4 * (size_t)row);
    if (!rows || !cand) { free(cand); PyErr_NoMemory(); goto done; }
    const uint8_t *src = pixels.buf;
    uint8_t *dst = out.buf;
    Py_ssize_t plane = height * width;
    Py_BEGIN_ALLOW_THREADS
    uint8_t *above = rows + 3, *here = rows + row + 6;
    for (Py_ssize_t y = 0; y < height; y++) {
        if (planar) {
            const uint8_t *r = src + y * width;
            gather_row(r, r + plane, r + 2 * plane, width, here);
        } else {
            memcpy(here, src + y * row, (size_t)row);
        }
        unsigned cost[4];
        filter_row(here, above, row, cand, cost);
        static const uint8_t types[4] = {0, 2, 1, 4}; /* none, up, sub, paeth */
        int best = 0;
        for (int k = 1; k < 4; k++) if (cost[k] < cost[best]) best = k;
        uint8_t *line = dst + y * (row + 1);
        line[0] = types[best];
        memcpy(line + 1, best == 0 ? here : cand + best * row, (size_t)row);
        uint8_t *t = above; above = here; here = t;
    }
    Py_END_ALLOW_THREADS
    free(cand);
    result = Py_None;
    Py_INCREF(result);
done:
    free(rows);
    PyBuffer_Release(&pixels);
    PyBuffer_Release(&out);
    return result;
}

static PyMethodDef methods[] = {
    {"filter_rows", filter_rows, METH_VARARGS, "The PNG row filters Pillow chooses for an RGB frame."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_png_rows", "PNG row filters (compiled loop of frame_png).", -1, methods};

PyMODINIT_FUNC PyInit__png_rows(void) { return PyModule_Create(&module); }
