/* The shading of a frame, pixel by pixel: the compiled loop of povagent/generate/renderer.py,
 * whose numpy code (Renderer._directions, _shade_block, _shade, _texture) is the reference.
 * Every value is computed with the same IEEE operations, in the same order and precision, as
 * the numpy passes do (float32 where they work on float32 arrays, double inside _sin), so the
 * colour bytes are the same bits (tests/generate/test_renderer_compiled.py holds the two equal).
 *
 * directions(grid, axes, out): the camera's rays, ``out[k] = grid[0] * axes[0, k] +
 *   grid[1] * axes[1, k] + grid[2] * axes[2, k]`` on float32 rows (3, N).
 * shade_lit(tri, t, d, origin, normals, colors, lights, codes, shadows, planes, shadowed, probe,
 *   start, toward, length) -> number of shadow rays: the colour bytes (3, N) of every pixel as if
 *   its light were not blocked (``planes``), the bytes it has if it is (``shadowed``, written
 *   where ``probe`` is 1), and the shadow rays Embree casts between the two calls: from
 *   ``start`` (N, 3) along ``toward`` (N, 3) for ``length`` (-1: no ray).
 * apply_shadows(occluded, probe, shadowed, planes): the bytes of the pixels whose shadow ray
 *   Embree found blocked (``occluded`` >= 0) replaced by their shadowed bytes.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <stdint.h>

/* povagent/generate/mesh_parts.py's materials and renderer.py's face-code bits (the module's
 * MATERIALS and CODE_BITS, which a test holds equal to the Python ones) */
enum { PLAIN, WOOD, FABRIC, METAL, GLOSS, EMISSIVE, FLOOR_WOOD, FLOOR_TILE, WALL, CEILING, MATERIAL_COUNT };
enum { MATERIAL_BITS = 0x0F, A_IS_Z = 0x10, B_IS_Z = 0x20 };

#define PI 3.141592653589793
static const double TWO_PI = 2.0 * PI, INV_TWO_PI = 1.0 / (2.0 * PI);
/* -1/3!, 1/5!, ... 1/17!: the factorials are exact doubles, each quotient rounded once */
static const double SINE_TERMS[8] = {-1.0 / 6.0, 1.0 / 120.0, -1.0 / 5040.0, 1.0 / 362880.0, -1.0 / 39916800.0,
                                     1.0 / 6227020800.0, -1.0 / 1307674368000.0, 1.0 / 355687428096000.0};

/* renderer._sin of one float32: reduced by 2 pi and folded in double, the Taylor series summed
 * from its last term, rounded to float32 at the end */
static inline float sin32(float x) {
    double r = (double)x;
    r = r - rint(r * INV_TWO_PI) * TWO_PI;
    if (r > PI / 2) r = PI - r;
    if (r < -PI / 2) r = -PI - r;
    double r2 = r * r, total = SINE_TERMS[7];
    for (int k = 6; k >= 0; k--) total = total * r2 + SINE_TERMS[k];
    total *= r2;
    total *= r;
    total += r;
    return (float)total;
}

/* renderer._hash2 of float32 cells, ``b_term`` being b * 78.233 as numpy rounds it */
static inline float hash2_of(float a, float b_term) {
    float v = a * 12.9898f + b_term;
    v = sin32(v) * 43758.5453f;
    return v - floorf(v);
}
static inline float hash2(float a, float b) { return hash2_of(a, b * 78.233f); }

/* renderer._power_40 */
static inline float power_40(float x) {
    float x8 = x * x;
    x8 *= x8;
    x8 *= x8;
    float x32 = x8 * x8;
    x32 *= x32;
    return x32 * x8;
}

/* renderer._texture of one pixel */
static inline float texture(int code, int mat, float px, float py, float pz) {
    float a = (code & A_IS_Z) ? pz : px, b = (code & B_IS_Z) ? pz : py;
    switch (mat) {
    case WOOD:
        return 0.94f + 0.06f * sin32(a * 30.0f + 2.0f * sin32(b * 5.0f + a * 2.0f));
    case FABRIC:
        return 0.93f + 0.07f * hash2(floorf(a * 160.0f), floorf(b * 160.0f));
    case WALL:
        return 0.97f + 0.03f * hash2(floorf(a * 90.0f), floorf(b * 90.0f));
    case FLOOR_WOOD: {
        float across = px / 0.18f, plank = floorf(across);
        float tint = 0.84f + 0.22f * hash2(plank, plank * 0.37f + 1.0f);
        /* _hash2(plank, 7.0): b is a Python float there, 7.0 * 78.233 rounded in double first */
        float shift = hash2_of(plank, (float)(7.0 * 78.233)) * 1.4f;
        float along = (pz + shift) / 1.4f;
        int seam = (across - plank < 0.05f) | (along - floorf(along) < 0.012f);
        float grain = 0.97f + 0.03f * sin32(pz * 25.0f + 1.5f * sin32(px * 20.0f + plank));
        return seam ? 0.55f : tint * grain;
    }
    case FLOOR_TILE: {
        float x = px / 0.4f, z = pz / 0.4f, cx = floorf(x), cz = floorf(z);
        int grout = (x - cx < 0.035f) | (z - cz < 0.035f);
        return grout ? 0.72f : 0.95f + 0.08f * hash2(cx, cz);
    }
    default:
        return 1.0f;
    }
}

/* a colour channel scaled to 0.5-255 and truncated as numpy's unsafe cast does (NaN: 0) */
static inline uint8_t to_byte(float v) {
    v *= 255.0f;
    v += 0.5f;
    if (!isnan(v)) v = v < 0.0f ? 0.0f : (v > 255.0f ? 255.0f : v);
    return isnan(v) ? 0 : (uint8_t)v;
}

typedef struct {
    Py_buffer tri, t, d, origin, normals, colors, lights, codes, planes, shadowed, probe, start, toward, length;
} ShadeBuffers;

static PyObject *shade_lit(PyObject *self, PyObject *args) {
    ShadeBuffers b;
    int shadows;
    memset(&b, 0, sizeof b);
    if (!PyArg_ParseTuple(args, "y*y*y*y*y*y*y*y*pw*w*w*w*w*w*", &b.tri, &b.t, &b.d, &b.origin, &b.normals, &b.colors,
                          &b.lights, &b.codes, &shadows, &b.planes, &b.shadowed, &b.probe, &b.start, &b.toward, &b.length))
        return NULL;
    PyObject *result = NULL;
    Py_ssize_t n = b.tri.len / 8, faces = b.codes.len;
    if (b.tri.len != 8 * n || b.t.len != 8 * n || b.d.len != 12 * n || b.origin.len != 12 || b.normals.len != 12 * faces ||
        b.colors.len != 12 * faces || b.lights.len != 12 * faces || b.planes.len != 3 * n || b.shadowed.len != 3 * n ||
        b.probe.len != n || b.start.len != 12 * n || b.toward.len != 12 * n || b.length.len != 4 * n) {
        PyErr_SetString(PyExc_ValueError, "shade_lit: the buffers' sizes do not match the pixels' and the faces' counts");
        goto done;
    }
    const int64_t *tri = b.tri.buf;
    const double *t64 = b.t.buf;
    const float *d = b.d.buf, *origin = b.origin.buf, *normals = b.normals.buf, *colors = b.colors.buf, *lights = b.lights.buf;
    const uint8_t *codes = b.codes.buf;
    uint8_t *planes = b.planes.buf, *shadowed = b.shadowed.buf, *probe = b.probe.buf;
    float *start = b.start.buf, *toward = b.toward.buf, *length = b.length.buf;
    Py_ssize_t rays = 0, bad = 0;
    Py_BEGIN_ALLOW_THREADS
    const float ox = origin[0], oy = origin[1], oz = origin[2];
    const uint8_t bg[3] = {to_byte(0.55f), to_byte(0.6f), to_byte(0.65f)}; /* renderer.BACKGROUND */
    for (Py_ssize_t i = 0; i < n; i++) {
        int64_t f = tri[i];
        probe[i] = 0;
        length[i] = -1.0f;
        if (f < 0 || f >= faces) {
            bad += f >= faces;
            for (int k = 0; k < 3; k++) {
                planes[k * n + i] = bg[k];
                start[3 * i + k] = 0.0f;
                toward[3 * i + k] = k == 0 ? 1.0f : 0.0f;
            }
            continue;
        }
        float dx = d[i], dy = d[n + i], dz = d[2 * n + i], t = (float)t64[i];
        float px = dx * t + ox, py = dy * t + oy, pz = dz * t + oz;
        float nx = normals[f], ny = normals[faces + f], nz = normals[2 * faces + f];
        float facing = nx * dx + ny * dy + nz * dz;
        if (facing > 0) { nx = -nx; ny = -ny; nz = -nz; } /* face the viewer */
        float fill = fabsf(facing);
        int code = codes[f], mat = code & MATERIAL_BITS;
        float tex = texture(code, mat, px, py, pz);
        float br = colors[f] * tex, bgr = colors[faces + f] * tex, bb = colors[2 * faces + f] * tex;
        float lx = lights[f] - px, ly = lights[faces + f] - py, lz = lights[2 * faces + f] - pz;
        float dist2 = lx * lx + ly * ly + lz * lz, dist = sqrtf(dist2);
        lx /= dist;
        ly /= dist;
        lz /= dist;
        float lambert = nx * lx + ny * ly + nz * lz;
        float falloff = dist2 * 0.06f + 1.0f;
        float diffuse = (lambert >= 0.0f || isnan(lambert)) ? lambert : 0.0f; /* np.maximum */
        diffuse /= falloff;
        float spec = 0.0f;
        int shiny = mat == METAL || mat == GLOSS;
        if (shiny) {
            float hx = lx - dx, hy = ly - dy, hz = lz - dz;
            float norm = sqrtf(hx * hx + hy * hy + hz * hz);
            hx /= norm;
            hy /= norm;
            hz /= norm;
            float s = nx * hx + ny * hy + nz * hz;
            if (!isnan(s)) s = s < 0.0f ? 0.0f : (s > 1.0f ? 1.0f : s); /* np.clip */
            spec = power_40(s) * 0.45f;
        }
        float shade;
        if (mat == CEILING) shade = 0.62f + 0.25f * fill;
        else if (mat == EMISSIVE) shade = 0.95f + 0.05f * fill;
        else shade = diffuse * 0.85f + 0.30f + 0.22f * fill;
        float c[3] = {br * shade, bgr * shade, bb * shade};
        for (int k = 0; k < 3; k++) planes[k * n + i] = to_byte(shiny ? c[k] + spec : c[k]);
        start[3 * i] = nx * 2e-3f + px;
        start[3 * i + 1] = ny * 2e-3f + py;
        start[3 * i + 2] = nz * 2e-3f + pz;
        toward[3 * i] = lx;
        toward[3 * i + 1] = ly;
        toward[3 * i + 2] = lz;
        if (shadows && lambert > 0.02f && mat != EMISSIVE && mat != CEILING) {
            probe[i] = 1;
            length[i] = dist - 0.05f;
            rays++;
            float dark = diffuse * 0.15f; /* the light blocked */
            shade = dark * 0.85f + 0.30f + 0.22f * fill;
            float s[3] = {br * shade, bgr * shade, bb * shade};
            for (int k = 0; k < 3; k++) shadowed[k * n + i] = to_byte(shiny ? s[k] + spec : s[k]);
        }
    }
    Py_END_ALLOW_THREADS
    if (bad) {
        PyErr_SetString(PyExc_ValueError, "shade_lit: a pixel's face index is past the faces");
        goto done;
    }
    result = PyLong_FromSsize_t(rays);
done:
    PyBuffer_Release(&b.tri); PyBuffer_Release(&b.t); PyBuffer_Release(&b.d); PyBuffer_Release(&b.origin);
    PyBuffer_Release(&b.normals); PyBuffer_Release(&b.colors); PyBuffer_Release(&b.lights); PyBuffer_Release(&b.codes);
    PyBuffer_Release(&b.planes); PyBuffer_Release(&b.shadowed); PyBuffer_Release(&b.probe); PyBuffer_Release(&b.start);
    PyBuffer_Release(&b.toward); PyBuffer_Release(&b.length);
    return result;
}

static PyObject *apply_shadows(PyObject *self, PyObject *args) {
    Py_buffer occluded, probe, shadowed, planes;
    if (!PyArg_ParseTuple(args, "y*y*y*w*", &occluded, &probe, &shadowed, &planes)) return NULL;
    PyObject *result = NULL;
    Py_ssize_t n = probe.len;
    if (occluded.len != 4 * n || shadowed.len != 3 * n || planes.len != 3 * n) {
        PyErr_SetString(PyExc_ValueError, "apply_shadows: the buffers' sizes do not match the pixels' count");
        goto done;
    }
    const int32_t *hit = occluded.buf;
    const uint8_t *probed = probe.buf, *dark = shadowed.buf;
    uint8_t *out = planes.buf;
    Py_BEGIN_ALLOW_THREADS
    for (Py_ssize_t i = 0; i < n; i++)
        if (probed[i] && hit[i] >= 0)
            for (int k = 0; k < 3; k++) out[k * n + i] = dark[k * n + i];
    Py_END_ALLOW_THREADS
    result = Py_None;
    Py_INCREF(result);
done:
    PyBuffer_Release(&occluded); PyBuffer_Release(&probe); PyBuffer_Release(&shadowed); PyBuffer_Release(&planes);
    return result;
}

static PyObject *directions(PyObject *self, PyObject *args) {
    Py_buffer grid, axes, out;
    if (!PyArg_ParseTuple(args, "y*y*w*", &grid, &axes, &out)) return NULL;
    PyObject *result = NULL;
    Py_ssize_t n = grid.len / 12;
    if (grid.len != 12 * n || axes.len != 36 || out.len != 12 * n) {
        PyErr_SetString(PyExc_ValueError, "directions: the buffers' sizes do not match");
        goto done;
    }
    const float *g = grid.buf, *ax = axes.buf;
    float *o = out.buf;
    Py_BEGIN_ALLOW_THREADS
    for (int k = 0; k < 3; k++) {
        const float a0 = ax[k], a1 = ax[3 + k], a2 = ax[6 + k];
        float *row = o + k * n;
        for (Py_ssize_t i = 0; i < n; i++) row[i] = g[i] * a0 + g[n + i] * a1 + g[2 * n + i] * a2;
    }
    Py_END_ALLOW_THREADS
    result = Py_None;
    Py_INCREF(result);
done:
    PyBuffer_Release(&grid); PyBuffer_Release(&axes); PyBuffer_Release(&out);
    return result;
}

static PyMethodDef methods[] = {
    {"directions", directions, METH_VARARGS, "The camera's unit rays (3, N) from the camera-space grid and the camera's axes."},
    {"shade_lit", shade_lit, METH_VARARGS, "The colour bytes of every pixel, lit and shadowed, and the shadow rays to cast."},
    {"apply_shadows", apply_shadows, METH_VARARGS, "The shadowed bytes where Embree found the shadow ray blocked."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_shading", "The renderer's shading (compiled loop of renderer.py).", -1, methods};

PyMODINIT_FUNC PyInit__shading(void) {
    PyObject *m = PyModule_Create(&module);
    if (!m) return NULL;
    PyObject *materials = Py_BuildValue("(iiiiiiiiii)", PLAIN, WOOD, FABRIC, METAL, GLOSS, EMISSIVE, FLOOR_WOOD, FLOOR_TILE, WALL, CEILING);
    PyObject *bits = Py_BuildValue("(iii)", MATERIAL_BITS, A_IS_Z, B_IS_Z);
    if (PyModule_AddObject(m, "MATERIALS", materials) < 0 || PyModule_AddObject(m, "CODE_BITS", bits) < 0) {
        Py_XDECREF(materials);
        Py_XDECREF(bits);
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
