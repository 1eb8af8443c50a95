/* The outline of a camera's pixels and each outline or crease pixel resolved among its
 * candidate groups (the rest of VisibleFaces.decide_image: _reachable, _nearest_holding): part
 * of its compiled loop (visible_face.c says what it does, and includes this file). */
#include "visible_face.h"

/* the outline values and groups of a row's pixels: of the face each shows (-1: none), as the
 * exact tests left it (one branchless load a pixel, of Faces.face_looks, whose entry ``none``
 * is no face's: a loop the compiler vectorizes with gathers) */
VECTOR_CLONES
static void looks_of(const int64_t *restrict face_looks, int32_t none, const int32_t *restrict shown, Py_ssize_t width, int32_t *restrict seen,
                     int32_t *restrict group) {
    for (Py_ssize_t x = 0; x < width; x++) {
        int64_t both = face_looks[shown[x] >= 0 ? shown[x] : none];
        seen[x] = (int32_t)both;
        group[x] = (int32_t)(both >> 32);
    }
}

static void outline_row(const Faces *s, const int32_t *shown, Py_ssize_t width, int32_t *seen, int32_t *group) {
    looks_of(s->face_looks, (int32_t)s->faces, shown, width, seen, group);
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

/* whether each inner pixel of a row differs from one of its 8 neighbours: one branchless pass
 * (it vectorizes) */
VECTOR_CLONES
static void inner_edges(const int32_t *restrict up, const int32_t *restrict row, const int32_t *restrict down, Py_ssize_t width, uint8_t *restrict edge) {
    for (Py_ssize_t x = 1; x < width - 1; x++) {
        int32_t c = row[x];
        edge[x] = (uint8_t)((up[x - 1] != c) | (up[x] != c) | (up[x + 1] != c) | (row[x - 1] != c) | (row[x + 1] != c) | (down[x - 1] != c) |
                            (down[x] != c) | (down[x + 1] != c));
    }
}

/* differs_around for a row: its inner pixels in one branchless pass */
static void outline_edges(const int32_t *up, const int32_t *row, const int32_t *down, Py_ssize_t width, uint8_t *edge) {
    if (!up || !down || width < 3) {
        for (Py_ssize_t x = 0; x < width; x++) edge[x] = differs_around(up, row, down, x, width);
        return;
    }
    edge[0] = differs_around(up, row, down, 0, width);
    inner_edges(up, row, down, width, edge);
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
     * is not reached either when it comes again). Not looked for again at the pixel's own hit
     * (its own group: the same plane, distance and point as vf_decide_rays's, whose exact tests
     * keep a face's group): those groups came in as its crease pairs, already candidates, or
     * there are none (a hit in no near cell, or of a group with no watched edge) */
    size_t first = w->reached.n;
    int near;
    int64_t own = rows[1][x];
    for (size_t k = 0; k < first; k++) {
        if (w->reached.v[k].group == own) continue;
        if (vf_near_watched(s, w->reached.v[k].group, w->reached.v[k].p, i, &w->extra_ray, &w->extra_group, &near)) return -1;
    }
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
                int64_t face = vf_highest_holding(s, at, r[k].p, i);
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
static int vf_resolve_pixels(const Faces *s, Py_ssize_t height, Py_ssize_t width, const Vec *crease_ray, const Vec *crease_group, const Pixels *px, int want) {
    int32_t *shown = px->shown;
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
        Py_ssize_t i = w.ray.v[k];
        shown[i] = (int32_t)w.face.v[k];
        double dist;
        memcpy(&dist, &w.dist.v[k], sizeof dist);
        if (want && px->t32) ((float *)px->t)[i] = (float)dist;
        else if (want) ((double *)px->t)[i] = dist;
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
