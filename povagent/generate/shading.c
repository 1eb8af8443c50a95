/* The shading of a frame, pixel by pixel: the compiled loop of povagent/generate/renderer.py,
 * whose numpy code (Renderer._directions, _shade_block, _shade, _texture) is the reference.
 * Every value is computed with the same IEEE operations, in the same order and precision, as
 * the numpy passes do (float32 where they work on float32 arrays, double inside _sin), so the
 * colour bytes are the same bits (tests/generate/test_renderer_compiled.py holds the two equal).
 *
 * directions(grid, axes, out): the camera's rays, ``out[k] = grid[0] * axes[0, k] +
 *   grid[1] * axes[1, k] + grid[2] * axes[2, k]`` on float32 rows (3, N).
 * shade_lit(tri, t, d, origin, normals, colors, lights, codes, shadows, planes, shadowed, probe,
 *   start, toward, length) -> number of shadow rays: of the pixels' int32 faces (-1: none) at
 *   float32 distances t (VisibleFaces.decide_image's narrow answer), the colour bytes (3, N) of every pixel as if
 *   its light were not blocked (``planes``), the bytes it has if it is (``shadowed``, read
 *   where ``probe`` is 1), and the shadow rays Embree casts between the two calls: from
 *   ``start`` (N, 3) along ``toward`` (N, 3) for ``length`` (-1: no ray).
 * apply_shadows(occluded, probe, shadowed, planes): the bytes of the pixels whose shadow ray
 *   Embree found blocked (``occluded`` >= 0) replaced by their shadowed bytes.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <stdint.h>

/* The tile functions are built for each CPU kind (vector_clones.h): the same IEEE operations
 * either way (no fused multiply-add: -ffp-contract=off; floor, rint and sqrt are exact), so the
 * same bits. (setup.py's -fno-math-errno and -fno-trapping-math let GCC vectorize the loops with
 * square roots and choices; they change no value.) */
#include "vector_clones.h"
#if defined(__GNUC__) && !defined(__clang__)
/* GCC cannot see that a tile's argument list is written as far as it is read (count entries) */
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

/* povagent/generate/mesh_parts.py's materials and renderer.py's face-code bits (the module's
 * MATERIALS and CODE_BITS, which a test holds equal to the Python ones) */
enum { PLAIN, WOOD, FABRIC, METAL, GLOSS, EMISSIVE, FLOOR_WOOD, FLOOR_TILE, WALL, CEILING };
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
    double above = PI - r; /* both sides computed, then chosen: no branch, so the loops vectorize */
    r = r > PI / 2 ? above : r;
    double below = -PI - r;
    r = r < -PI / 2 ? below : r;
    double r2 = r * r, total = SINE_TERMS[7];
    for (int k = 6; k >= 0; k--) total = total * r2 + SINE_TERMS[k];
    total *= r2;
    total *= r;
    total += r;
    return (float)total;
}

/* renderer._power_40 */
static inline float power_40(float x) {
    float x8 = x * x;
    x8 *= x8;
    x8 *= x8;
    float x32 = x8 * x8;
    x32 *= x32;
    return x32 * x8;
}

/* renderer._hash2's end: the sine of a cell's value stretched, its fraction */
static inline float fraction(float sine) {
    float v = sine * 43758.5453f;
    return v - floorf(v);
}

/* a colour channel scaled to 0.5-255, clipped (NaN stays NaN: neither comparison holds) and
 * truncated as numpy's unsafe cast does (NaN: 0) */
static inline int32_t to_byte(float v) {
    v = v * 255.0f + 0.5f;
    v = v < 0.0f ? 0.0f : v;
    v = v > 255.0f ? 255.0f : v;
    return (int32_t)(v == v ? v : 0.0f);
}

/* renderer.BACKGROUND's bytes (set when the module loads) */
static int32_t BACKGROUND_BYTES[3];

/* What the tiles read and write: one frame's pixels and faces (see the top of the file). */
typedef struct {
    const int32_t *tri;
    const float *t;
    const float *d, *normals, *colors, *lights;
    const int32_t *codes;
    float ox, oy, oz;
    Py_ssize_t n, faces;
    int shadows;
    uint8_t *planes, *shadowed, *probe;
    float *start, *toward, *length;
} Frame;

/* Pixels shaded together: each step below is a simple loop over a tile's arrays (a few dozen
 * kilobytes, in the CPU's first cache), so the compiler turns the arithmetic into vector
 * instructions; the sines of the textures are gathered into one list per round and computed in
 * one such loop. */
#define TILE 256

/* the sines of a round's list (a function of its own: its one loop is vectorized alike wherever
 * it is called) */
VECTOR_CLONES __attribute__((noinline))
static void sines(const float *restrict x, float *restrict y, int count) {
    for (int k = 0; k < count; k++) y[k] = sin32(x[k]);
}

/* renderer._texture's factors from the sines of a tile's pixels (each pixel's choice by its
 * material: a loop of its own, which the compiler vectorizes where inside shade_tile it did not) */
VECTOR_CLONES __attribute__((noinline))
static void blend_textures(int count, const int32_t *restrict mat, const float *restrict sine, const float *restrict shift_sine,
                           const float *restrict second, const float *restrict pz, const float *restrict across,
                           const float *restrict plank, const int32_t *restrict grout, float *restrict tex) {
    for (int i = 0; i < count; i++) {
        int m = mat[i];
        float h = fraction(sine[i]);
        float shift = fraction(shift_sine[i]) * 1.4f;
        float along = (pz[i] + shift) / 1.4f;
        int seam = (across[i] - plank[i] < 0.05f) | (along - floorf(along) < 0.012f);
        float grain = (0.84f + 0.22f * h) * (0.97f + 0.03f * second[i]);
        float boards = seam ? 0.55f : grain;
        float tiles = 0.95f + 0.08f * h;
        tiles = grout[i] ? 0.72f : tiles;
        float v = m == WOOD ? 0.94f + 0.06f * second[i] : 1.0f;
        v = m == FABRIC ? 0.93f + 0.07f * h : v;
        v = m == WALL ? 0.97f + 0.03f * h : v;
        v = m == FLOOR_WOOD ? boards : v;
        tex[i] = m == FLOOR_TILE ? tiles : v;
    }
}

/* the texture loop's arguments of a tile's pixels (shade_tile says what; a loop of its own, which
 * the compiler vectorizes where inside shade_tile it did not) */
VECTOR_CLONES __attribute__((noinline))
static void texture_args(int count, const int32_t *restrict mat, const int32_t *restrict code, const float *restrict px, const float *restrict py,
                         const float *restrict pz, float *restrict across, float *restrict plank, float *restrict shift_arg, float *restrict inner,
                         int32_t *restrict grout, float *restrict arg, float *restrict along_a) {
    for (int i = 0; i < count; i++) {
        int m = mat[i], k = code[i];
        float x = px[i], y = py[i], z = pz[i];
        float a = (k & A_IS_Z) ? z : x, b = (k & B_IS_Z) ? z : y;
        float scale = m == FABRIC ? 160.0f : 90.0f;
        float cell = floorf(a * scale) * 12.9898f + floorf(b * scale) * 78.233f;
        float over = x / 0.18f, p = floorf(over);
        across[i] = over;
        plank[i] = p;
        float tint = p * 12.9898f + (p * 0.37f + 1.0f) * 78.233f;
        /* _hash2(plank, 7.0): b is a Python float there, 7.0 * 78.233 rounded in double first */
        shift_arg[i] = p * 12.9898f + (float)(7.0 * 78.233);
        inner[i] = x * 20.0f + p;
        float tx = x / 0.4f, tz = z / 0.4f, cx = floorf(tx), cz = floorf(tz);
        grout[i] = (tx - cx < 0.035f) | (tz - cz < 0.035f);
        float tile = cx * 12.9898f + cz * 78.233f, wood = b * 5.0f + a * 2.0f;
        float first_arg = (m == FABRIC || m == WALL) ? cell : 0.0f;
        first_arg = m == WOOD ? wood : first_arg;
        first_arg = m == FLOOR_WOOD ? tint : first_arg;
        arg[i] = m == FLOOR_TILE ? tile : first_arg;
        along_a[i] = a;
    }
}

/* Shades pixels first .. first + count - 1 (count <= TILE); returns the shadow rays' count and
 * adds to *bad the pixels whose face index is past the faces. Each loop keeps to 32-bit values
 * (the compiler vectorizes no loop that mixes bytes or doubles with floats). */
VECTOR_CLONES
static Py_ssize_t shade_tile(const Frame *fr, Py_ssize_t first, int count, Py_ssize_t *bad) {
    const Py_ssize_t n = fr->n, faces = fr->faces;
    const float *restrict dx = fr->d + first, *restrict dy = dx + n, *restrict dz = dy + n;
    const float *restrict normals = fr->normals, *restrict colors = fr->colors, *restrict lights = fr->lights;
    const float ox = fr->ox, oy = fr->oy, oz = fr->oz;
    const float *restrict t = fr->t + first; /* the distances, read where they are */
    float px[TILE], py[TILE], pz[TILE], nx[TILE], ny[TILE], nz[TILE], fill[TILE];
    float lx[TILE], ly[TILE], lz[TILE], dist[TILE], lambert[TILE], diffuse[TILE], tex[TILE];
    float across[TILE], plank[TILE], shift_arg[TILE], inner[TILE], along_a[TILE], second[TILE], shift_sine[TILE];
    float arg[2 * TILE], sine[TILE], later[2 * TILE], last[TILE];
    float highlight[TILE];
    int32_t face[TILE], hit[TILE], code[TILE], mat[TILE], grout[TILE], plank_at[TILE], wood_at[TILE], shiny_at[TILE];
    int32_t lit_bytes[3][TILE], dark_bytes[3][TILE], cast[TILE];
    Py_ssize_t wrong = 0;

    /* which face each pixel shows (a miss reads face 0's values, then shows the background) */
    for (int i = 0; i < count; i++) {
        int32_t f = fr->tri[first + i];
        wrong += f >= faces;
        hit[i] = f >= 0 && f < faces;
        face[i] = hit[i] ? f : 0;
    }
    for (int i = 0; i < count; i++) {
        code[i] = fr->codes[face[i]];
        mat[i] = hit[i] ? code[i] & MATERIAL_BITS : PLAIN;
    }
    /* the hit point, the face's normal turned to the viewer, the unit vector to the light */
    for (int i = 0; i < count; i++) {
        int32_t f = face[i];
        float x = dx[i] * t[i] + ox, y = dy[i] * t[i] + oy, z = dz[i] * t[i] + oz;
        px[i] = x;
        py[i] = y;
        pz[i] = z;
        float a = normals[f], b = normals[faces + f], c = normals[2 * faces + f];
        float facing = a * dx[i] + b * dy[i] + c * dz[i];
        int away = facing > 0; /* face the viewer */
        a = away ? -a : a;
        b = away ? -b : b;
        c = away ? -c : c;
        nx[i] = a;
        ny[i] = b;
        nz[i] = c;
        fill[i] = fabsf(facing);
        float u = lights[f] - x, v = lights[faces + f] - y, w = lights[2 * faces + f] - z;
        float dist2 = u * u + v * v + w * w, length = sqrtf(dist2);
        u /= length;
        v /= length;
        w /= length;
        lx[i] = u;
        ly[i] = v;
        lz[i] = w;
        dist[i] = length;
        float cosine = a * u + b * v + c * w;
        lambert[i] = cosine;
        float falloff = dist2 * 0.06f + 1.0f;
        diffuse[i] = (cosine < 0.0f ? 0.0f : cosine) / falloff; /* np.maximum keeps a NaN */
    }

    /* the textures (renderer._texture): every pixel's first sine (a cell's hash for fabric,
     * walls and tiles, a plank's tint, the wood's inner sine) computed for every pixel and chosen
     * by material, so the loops vectorize; the floor planks' and the wood's further sines only
     * for their pixels, gathered into lists */
    texture_args(count, mat, code, px, py, pz, across, plank, shift_arg, inner, grout, arg, along_a);
    for (int i = 0; i < count; i++) {
        second[i] = 0.0f;
        shift_sine[i] = 0.0f;
        highlight[i] = 0.0f;
    }
    sines(arg, sine, count);
    /* the lists of the planks', the wood's and the shiny pixels */
    int planks = 0, woods = 0, shinies = 0;
    for (int i = 0; i < count; i++) {
        int m = mat[i];
        planks += m == FLOOR_WOOD;
        woods += m == WOOD;
        shinies += m == METAL || m == GLOSS;
    }
    /* each list built only in the tiles showing its material (counted first, in a loop the compiler
     * vectorizes): most tiles show no shiny pixel, many no plank or no wood */
    if (planks) {
        planks = 0;
        for (int i = 0; i < count; i++) {
            plank_at[planks] = i; /* written every time, kept only for a plank's pixel */
            planks += mat[i] == FLOOR_WOOD;
        }
    }
    if (woods) {
        woods = 0;
        for (int i = 0; i < count; i++) {
            wood_at[woods] = i;
            woods += mat[i] == WOOD;
        }
    }
    if (shinies) {
        shinies = 0;
        for (int i = 0; i < count; i++) {
            shiny_at[shinies] = i;
            shinies += mat[i] == METAL || mat[i] == GLOSS;
        }
    }
    for (int j = 0; j < planks; j++) {
        arg[j] = shift_arg[plank_at[j]];
        arg[planks + j] = inner[plank_at[j]];
    }
    sines(arg, later, 2 * planks);
    for (int j = 0; j < woods; j++) arg[j] = along_a[wood_at[j]] * 30.0f + 2.0f * sine[wood_at[j]];
    for (int j = 0; j < planks; j++) arg[woods + j] = pz[plank_at[j]] * 25.0f + 1.5f * later[planks + j];
    sines(arg, last, woods + planks);
    for (int j = 0; j < woods; j++) second[wood_at[j]] = last[j];
    for (int j = 0; j < planks; j++) {
        second[plank_at[j]] = last[woods + j];
        shift_sine[plank_at[j]] = later[j];
    }
    blend_textures(count, mat, sine, shift_sine, second, pz, across, plank, grout, tex);

    /* the highlights of metal and gloss, for their pixels only */
    for (int j = 0; j < shinies; j++) {
        int i = shiny_at[j];
        float hx = lx[i] - dx[i], hy = ly[i] - dy[i], hz = lz[i] - dz[i];
        float norm = sqrtf(hx * hx + hy * hy + hz * hz);
        hx /= norm;
        hy /= norm;
        hz /= norm;
        float s = nx[i] * hx + ny[i] * hy + nz[i] * hz;
        s = s < 0.0f ? 0.0f : s; /* np.clip keeps a NaN */
        s = s > 1.0f ? 1.0f : s;
        highlight[i] = power_40(s) * 0.45f;
    }

    /* the colours, lit and shadowed (every choice made by selecting, so the loop vectorizes) */
    const int shadows = fr->shadows;
    for (int i = 0; i < count; i++) {
        int32_t f = face[i];
        int m = mat[i], shiny = m == METAL || m == GLOSS, lit = m != CEILING && m != EMISSIVE;
        float spec = highlight[i];
        float shade = m == CEILING ? 0.62f + 0.25f * fill[i] : 0.95f + 0.05f * fill[i];
        shade = lit ? diffuse[i] * 0.85f + 0.30f + 0.22f * fill[i] : shade;
        float dark = (diffuse[i] * 0.15f) * 0.85f + 0.30f + 0.22f * fill[i]; /* the light blocked */
        float r = colors[f] * tex[i], g = colors[faces + f] * tex[i], b = colors[2 * faces + f] * tex[i];
        float cr = r * shade, cg = g * shade, cb = b * shade, sr = r * dark, sg = g * dark, sb = b * dark;
        lit_bytes[0][i] = hit[i] ? to_byte(shiny ? cr + spec : cr) : BACKGROUND_BYTES[0];
        lit_bytes[1][i] = hit[i] ? to_byte(shiny ? cg + spec : cg) : BACKGROUND_BYTES[1];
        lit_bytes[2][i] = hit[i] ? to_byte(shiny ? cb + spec : cb) : BACKGROUND_BYTES[2];
        dark_bytes[0][i] = to_byte(shiny ? sr + spec : sr);
        dark_bytes[1][i] = to_byte(shiny ? sg + spec : sg);
        dark_bytes[2][i] = to_byte(shiny ? sb + spec : sb);
        cast[i] = shadows && hit[i] && lit && lambert[i] > 0.02f;
    }

    /* the shadow rays: from just off the surface towards the light, to 5 cm short of it */
    Py_ssize_t rays = 0;
    float *restrict start = fr->start + 3 * first, *restrict toward = fr->toward + 3 * first;
    float *restrict ray_length = fr->length + first;
    for (int i = 0; i < count; i++) {
        rays += cast[i];
        ray_length[i] = cast[i] ? dist[i] - 0.05f : -1.0f;
        start[3 * i] = nx[i] * 2e-3f + px[i];
        start[3 * i + 1] = ny[i] * 2e-3f + py[i];
        start[3 * i + 2] = nz[i] * 2e-3f + pz[i];
        toward[3 * i] = lx[i];
        toward[3 * i + 1] = ly[i];
        toward[3 * i + 2] = lz[i];
    }
    for (int k = 0; k < 3; k++) {
        uint8_t *restrict out = fr->planes + k * n + first, *restrict dark = fr->shadowed + k * n + first;
        for (int i = 0; i < count; i++) {
            out[i] = (uint8_t)lit_bytes[k][i];
            dark[i] = (uint8_t)dark_bytes[k][i];
        }
    }
    uint8_t *restrict probe = fr->probe + first;
    for (int i = 0; i < count; i++) probe[i] = (uint8_t)cast[i];
    *bad += wrong;
    return rays;
}

/* apply_shadows' loop: in tiles, the pixels to darken found first (32-bit values), then each
 * plane's bytes chosen (byte values), each a loop the compiler vectorizes */
VECTOR_CLONES
static void apply_tiles(Py_ssize_t n, const int32_t *restrict hit, const uint8_t *restrict probed, const uint8_t *restrict dark,
                        uint8_t *restrict out) {
    for (Py_ssize_t first = 0; first < n; first += TILE) {
        int count = (int)(n - first < TILE ? n - first : TILE);
        uint8_t blocked[TILE];
        for (int i = 0; i < count; i++) blocked[i] = (uint8_t)-(hit[first + i] >= 0); /* 0xff or 0 */
        for (int i = 0; i < count; i++) blocked[i] &= (uint8_t)-(probed[first + i] != 0);
        for (int k = 0; k < 3; k++) {
            uint8_t *restrict o = out + k * n + first;
            const uint8_t *restrict d = dark + k * n + first;
            for (int i = 0; i < count; i++) o[i] = (uint8_t)((d[i] & blocked[i]) | (o[i] & ~blocked[i]));
        }
    }
}

static PyObject *shade_lit(PyObject *self, PyObject *args) {
    Py_buffer tri, t, d, origin, normals, colors, lights, codes, planes, shadowed, probe, start, toward, length;
    int shadows;
    if (!PyArg_ParseTuple(args, "y*y*y*y*y*y*y*y*pw*w*w*w*w*w*", &tri, &t, &d, &origin, &normals, &colors, &lights, &codes,
                          &shadows, &planes, &shadowed, &probe, &start, &toward, &length))
        return NULL;
    PyObject *result = NULL;
    Py_ssize_t n = tri.len / 4, faces = codes.len / 4;
    if (tri.len != 4 * n || t.len != 4 * n || d.len != 12 * n || origin.len != 12 || normals.len != 12 * faces ||
        colors.len != 12 * faces || lights.len != 12 * faces || codes.len != 4 * faces || planes.len != 3 * n || shadowed.len != 3 * n ||
        probe.len != n || start.len != 12 * n || toward.len != 12 * n || length.len != 4 * n || faces > INT32_MAX) {
        PyErr_SetString(PyExc_ValueError, "shade_lit: the buffers' sizes do not match the pixels' and the faces' counts");
        goto done;
    }
    const float *o = origin.buf;
    Frame fr = {tri.buf, t.buf, d.buf, normals.buf, colors.buf, lights.buf, codes.buf, o[0], o[1], o[2], n, faces,
                shadows, planes.buf, shadowed.buf, probe.buf, start.buf, toward.buf, length.buf};
    Py_ssize_t rays = 0, bad = 0;
    if (faces == 0) {
        /* no face to gather from: every pixel must be a miss */
        for (Py_ssize_t i = 0; i < n; i++) bad += ((const int32_t *)tri.buf)[i] >= 0;
    } else {
        Py_BEGIN_ALLOW_THREADS
        for (Py_ssize_t first = 0; first < n; first += TILE)
            rays += shade_tile(&fr, first, (int)(n - first < TILE ? n - first : TILE), &bad);
        Py_END_ALLOW_THREADS
    }
    if (bad) {
        PyErr_SetString(PyExc_ValueError, "shade_lit: a pixel's face index is past the faces");
        goto done;
    }
    result = PyLong_FromSsize_t(rays);
done:
    PyBuffer_Release(&tri); PyBuffer_Release(&t); PyBuffer_Release(&d); PyBuffer_Release(&origin);
    PyBuffer_Release(&normals); PyBuffer_Release(&colors); PyBuffer_Release(&lights); PyBuffer_Release(&codes);
    PyBuffer_Release(&planes); PyBuffer_Release(&shadowed); PyBuffer_Release(&probe); PyBuffer_Release(&start);
    PyBuffer_Release(&toward); PyBuffer_Release(&length);
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
    apply_tiles(n, hit, probed, dark, out);
    Py_END_ALLOW_THREADS
    result = Py_None;
    Py_INCREF(result);
done:
    PyBuffer_Release(&occluded); PyBuffer_Release(&probe); PyBuffer_Release(&shadowed); PyBuffer_Release(&planes);
    return result;
}

/* directions' loop: the grid's three rows read once, the three rows of the rays written in the
 * same pass (each the sum of its three products, in that order) */
VECTOR_CLONES
static void turn_rows(Py_ssize_t n, const float *restrict g0, const float *restrict g1, const float *restrict g2, const float *restrict ax,
                      float *restrict x, float *restrict y, float *restrict z) {
    const float x0 = ax[0], x1 = ax[3], x2 = ax[6], y0 = ax[1], y1 = ax[4], y2 = ax[7], z0 = ax[2], z1 = ax[5], z2 = ax[8];
    for (Py_ssize_t i = 0; i < n; i++) {
        x[i] = g0[i] * x0 + g1[i] * x1 + g2[i] * x2;
        y[i] = g0[i] * y0 + g1[i] * y1 + g2[i] * y2;
        z[i] = g0[i] * z0 + g1[i] * z1 + g2[i] * z2;
    }
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
    turn_rows(n, g, g + n, g + 2 * n, ax, o, o + n, o + 2 * n);
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

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_shading", "The renderer's shading (compiled loop of renderer.py).", -1, methods, NULL, NULL, NULL, NULL};

PyMODINIT_FUNC PyInit__shading(void) {
    BACKGROUND_BYTES[0] = to_byte(0.55f);
    BACKGROUND_BYTES[1] = to_byte(0.6f);
    BACKGROUND_BYTES[2] = to_byte(0.65f);
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
