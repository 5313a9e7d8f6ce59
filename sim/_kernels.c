/* The simulator's per-tick loops, compiled: the fan cast's faces (sim/raycast.py,
 * FanCaster._faces), the same walked through a grid of the faces in big worlds
 * (GridWalk, over sim/faceindex.py's FaceGrid), the fan's ellipses
 * (FanCaster._ellipses), and a team's occlusions of the scans by the robots' discs
 * (sim/crowd.py, occlusions).
 *
 * The numpy paths spend most of their time on the fixed cost of ~25-40 calls on arrays of
 * a few hundred numbers; these do the same arithmetic in one call each. They are an
 * optional build: without a C compiler mdle installs without them and uses numpy.
 *
 * Both reproduce the numpy paths bit for bit.
 *
 * faces: complex products take numpy's form on this
 * machine (`fused`: the fused multiply-add numpy's SIMD loops use, or plain products,
 * found by a probe at import); a complex divided by a real is a product with the
 * reciprocal, as numpy's division gives. The bearings come from libm's atan2, which can
 * differ from numpy's arctan2 in the last bit: they only choose which beams a face's
 * interval (widened by 1e-10 rad) holds, so a difference matters only for a beam within
 * an ulp of a widened end, which meets the face's line within 1e-10 rad of the end.
 *
 * ellipses: numpy's complex absolute value (its own SIMD algorithm, not hypot), its
 * in-place products of a single number (a plain scalar loop) and its matmul of the beams
 * (OpenBLAS's zgemv for one ellipse), each reproduced and checked by a probe before use.
 *
 * Built with -ffp-contract=off and without GCC's vectoriser (which fuses a complex
 * product's plain multiplies and add/subtract in the FMA clones, whatever the contract
 * flag says): every product is rounded where the numpy path rounds it.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <structmember.h>
#include <math.h>
#include <stdlib.h>

#define TAU 6.283185307179586

typedef struct {
    double re, im;
} cplx;

/* numpy's complex product of a and b (in that order), fused or plain. */
static inline cplx cmul(cplx a, cplx b, int fused)
{
    cplx r;
    if (fused) {
        r.re = fma(a.re, b.re, -(a.im * b.im));
        r.im = fma(a.re, b.im, a.im * b.re);
    } else {
        r.re = a.re * b.re - a.im * b.im;
        r.im = a.re * b.im + a.im * b.re;
    }
    return r;
}

/* The first index whose value is >= x (numpy's searchsorted, side="left"). */
static inline Py_ssize_t lower_bound(const double *v, Py_ssize_t n, double x)
{
    Py_ssize_t lo = 0, hi = n;
    while (lo < hi) {
        Py_ssize_t mid = (lo + hi) >> 1;
        if (v[mid] < x)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

typedef struct {
    double hi, lo;
    cplx f;
} face;

/* Face j of the world rows z (end, conj(start), kappa start, edge; m faces a row) seen
 * in one scan's fan frame: its ends q and conj(p), w = conj(p) q, and f, with
 * 1/t = Im(conj(d) f) for a beam d. Returns 0 for a back face (or the origin on its
 * line). Both face loops call this: the same numbers. */
static inline int face_turned(const cplx *z, const double *front_min, Py_ssize_t m,
                              Py_ssize_t j, cplx rot, cplx rot_c, cplx c, int fused, cplx *q,
                              cplx *pc, cplx *w, cplx *f)
{
    *q = cmul(z[j], rot, fused);
    *pc = cmul(z[m + j], rot_c, fused);
    q->re -= c.re;
    q->im -= c.im;
    pc->re -= c.re;
    pc->im -= -c.im;
    *w = cmul(*pc, *q, fused); /* conj(p) q = (p . q) + i cross(p, e) */
    if (!(w->im > front_min[j]))
        return 0;
    cplx e = cmul(z[3 * m + j], rot, fused);
    double s = 1.0 / w->im;
    f->re = e.re * s;
    f->im = e.im * s;
    return 1;
}

/* face_turned, and the face's bearing interval from psi, widened by eps (cast_faces's). */
static inline int face_in_fan(const cplx *z, const double *front_min, Py_ssize_t m,
                              Py_ssize_t j, cplx rot, cplx rot_c, cplx c, cplx kc,
                              double eps, int fused, face *f)
{
    cplx q, pc, w;
    if (!face_turned(z, front_min, m, j, rot, rot_c, c, fused, &q, &pc, &w, &f->f))
        return 0;
    cplx kp = cmul(z[2 * m + j], rot, fused);
    kp.re -= kc.re;
    kp.im -= kc.im;
    double lo = atan2(kp.im, kp.re);
    double hi = atan2(w.im, w.re) + lo;
    f->hi = hi + eps;
    f->lo = lo + -eps;
    return 1;
}

/* A face as the grid walk keeps it for a scan: f, and the directions of its ends turned
 * outwards by eps (lo from p clockwise, hi from q counter-clockwise), fan frame; and the
 * scan it was turned for (one cache line a face). */
typedef struct {
    cplx f, lo, hi;
    Py_ssize_t scan;
    double pad;
} walk_face;

/* Raise best[k] (1/t) to each front face's hit. Returns 0, or -1 when out of memory. */
#if defined(__GNUC__) && defined(__x86_64__) && !defined(__clang__)
/* A clone with the FMA instruction where the CPU has it; fma() is a libm call elsewhere. */
__attribute__((target_clones("fma", "default")))
#endif
static int
cast_faces(const double *zw, const double *front_min, Py_ssize_t m, double *best,
           const double *rel_s, const double *dconj, Py_ssize_t n, cplx rot, cplx c, cplx kc,
           double eps, double wrap_hi, int may_wrap, int fused)
{
    const cplx *z = (const cplx *)zw; /* rows: end, conj(start), kappa start, edge */
    const cplx *d = (const cplx *)dconj;
    cplx rot_c = {rot.re, -rot.im};
    face *fs = malloc((size_t)(m > 0 ? m : 1) * sizeof(face));
    Py_ssize_t nf = 0;
    double top = -INFINITY;
    if (fs == NULL)
        return -1;
    for (Py_ssize_t j = 0; j < m; j++) {
        face *f = &fs[nf];
        if (!face_in_fan(z, front_min, m, j, rot, rot_c, c, kc, eps, fused, f))
            continue;
        nf++;
        if (f->hi > top)
            top = f->hi;
    }
    /* A fan wider than a half turn can also meet an interval one turn down. */
    int turns = (may_wrap && top >= wrap_hi) ? 2 : 1;
    for (int turn = 0; turn < turns; turn++) {
        for (Py_ssize_t i = 0; i < nf; i++) {
            double hi = turn ? fs[i].hi - TAU : fs[i].hi;
            double lo = turn ? fs[i].lo - TAU : fs[i].lo;
            Py_ssize_t k_hi = lower_bound(rel_s, n, hi);
            cplx f = fs[i].f;
            for (Py_ssize_t k = lower_bound(rel_s, n, lo); k < k_hi; k++) {
                double inv = cmul(d[k], f, fused).im;
                if (inv > best[k])
                    best[k] = inv;
            }
        }
    }
    free(fs);
    return 0;
}

/* A uniform grid over the faces (sim/faceindex.py, FaceGrid): cell (ix, iy) spans
 * [x0 + ix h, x0 + (ix + 1) h) x [y0 + iy h, ...) and holds the faces cell_faces[start[i] ..
 * start[i + 1]) (i = iy nx + ix); a face is listed in every cell within `pad` of it. */
typedef struct {
    double x0, y0, h;
    Py_ssize_t nx, ny, n_faces;
    const Py_ssize_t *start, *faces;
} face_grid;

/* The faces' loop of one scan, walking each beam through the grid (Amanatides and Woo's
 * DDA) and stopping at the first cell whose far side lies beyond the nearest hit found:
 * the cost follows what the beam crosses, not the size of the world. Each face met is
 * turned into the fan frame once a scan (face_turned, kept in memo, marked with the scan),
 * and a beam meets it when it lies between the face's ends widened by eps, told by two
 * cross products where cast_faces compares bearings (two atan2 a face, the dearest part
 * of a scan): the same interval, so the tests differ only for a beam within rounding of
 * a widened end, 1e-10 rad beyond a vertex. 1/t is f's very product, so a beam's range
 * is the same number wherever the faces met are the same. t_lim: the farthest a hit may
 * lie (beyond max_range nothing counts); tol: the margin of the stopping test, far above
 * rounding and below the grid's pad. Returns how many faces the scan met. */
#if defined(__GNUC__) && defined(__x86_64__) && !defined(__clang__)
__attribute__((target_clones("fma", "default")))
#endif
static Py_ssize_t
grid_cast(const double *zw, const double *front_min, Py_ssize_t m, double *best,
          const double *dconj, Py_ssize_t n, cplx rot, cplx c, double eps, int fused,
          const face_grid *g, double ox, double oy, double t_lim, double tol,
          walk_face *memo, Py_ssize_t scan)
{
    const cplx *z = (const cplx *)zw;
    const cplx *d = (const cplx *)dconj;
    cplx rot_c = {rot.re, -rot.im};
    double ce = cos(eps), se = sin(eps);
    double h = g->h, x1 = g->x0 + h * (double)g->nx, y1 = g->y0 + h * (double)g->ny;
    int inside_box = ox >= g->x0 && ox <= x1 && oy >= g->y0 && oy <= y1;
    Py_ssize_t met = 0;
    for (Py_ssize_t k = 0; k < n; k++) {
        /* The beam's world direction, conj(dconj[k] rot): only steers the walk. */
        double dx = d[k].re * rot.re - d[k].im * rot.im;
        double dy = -(d[k].re * rot.im + d[k].im * rot.re);
        double idx = 1.0 / dx, idy = 1.0 / dy; /* inf for an axis-parallel beam */
        /* Where the beam is inside the grid's box: [t0, t1], clipped to t_lim. From
         * inside the box (the usual case) the walk ends where it leaves the cells. */
        double t0 = 0.0, t1 = t_lim;
        if (!inside_box) {
            if (dx != 0.0) {
                double ta = (g->x0 - ox) * idx, tb = (x1 - ox) * idx;
                t0 = fmax(t0, fmin(ta, tb));
                t1 = fmin(t1, fmax(ta, tb));
            } else if (!(ox >= g->x0 && ox <= x1)) {
                continue;
            }
            if (dy != 0.0) {
                double ta = (g->y0 - oy) * idy, tb = (y1 - oy) * idy;
                t0 = fmax(t0, fmin(ta, tb));
                t1 = fmin(t1, fmax(ta, tb));
            } else if (!(oy >= g->y0 && oy <= y1)) {
                continue;
            }
            if (!(t0 <= t1))
                continue; /* misses the box (or NaN) */
        }
        double fx = floor((ox + t0 * dx - g->x0) / h), fy = floor((oy + t0 * dy - g->y0) / h);
        /* Clamped before any conversion (NaN lands in cell 0): every step moves one cell,
         * so a walk ends within nx + ny steps whatever the numbers. */
        Py_ssize_t ix = fx >= 0.0 ? (fx < (double)g->nx ? (Py_ssize_t)fx : g->nx - 1) : 0;
        Py_ssize_t iy = fy >= 0.0 ? (fy < (double)g->ny ? (Py_ssize_t)fy : g->ny - 1) : 0;
        Py_ssize_t sx = dx > 0.0 ? 1 : dx < 0.0 ? -1 : 0;
        Py_ssize_t sy = dy > 0.0 ? 1 : dy < 0.0 ? -1 : 0;
        double next_x = sx ? (g->x0 + h * (double)(ix + (sx > 0)) - ox) * idx : INFINITY;
        double next_y = sy ? (g->y0 + h * (double)(iy + (sy > 0)) - oy) * idy : INFINITY;
        double step_x = sx ? h * fabs(idx) : INFINITY, step_y = sy ? h * fabs(idy) : INFINITY;
        double bx = d[k].re, by = -d[k].im; /* the beam's direction, fan frame */
        double inv_seen = NAN, t_seen = INFINITY;  /* best[k], and 1 / best[k] */
        for (;;) {
            Py_ssize_t cell = iy * g->nx + ix;
            Py_ssize_t end = g->start[cell + 1] < g->n_faces ? g->start[cell + 1] : g->n_faces;
            for (Py_ssize_t p = g->start[cell] > 0 ? g->start[cell] : 0; p < end; p++) {
                Py_ssize_t j = g->faces[p];
                if (j < 0 || j >= m)
                    continue; /* not a face: a broken grid never reads outside the arrays */
                walk_face *f = &memo[j];
                if (f->scan != scan) {
                    cplx q, pc, w;
                    f->scan = scan;
                    met++;
                    if (face_turned(z, front_min, m, j, rot, rot_c, c, fused, &q, &pc, &w,
                                    &f->f)) {
                        f->lo.re = pc.re * ce - pc.im * se; /* p turned by -eps */
                        f->lo.im = -pc.im * ce - pc.re * se;
                        f->hi.re = q.re * ce - q.im * se; /* q turned by +eps */
                        f->hi.im = q.im * ce + q.re * se;
                    } else {
                        f->lo.re = f->lo.im = NAN; /* a back face: no beam is inside */
                    }
                }
                /* Inside [lo, hi): lo at or clockwise of the beam, hi strictly beyond. */
                if (f->lo.re * by - f->lo.im * bx >= 0.0 && bx * f->hi.im - by * f->hi.re > 0.0) {
                    double inv = cmul(d[k], f->f, fused).im;
                    if (inv > best[k])
                        best[k] = inv;
                }
            }
            double t_next = next_x < next_y ? next_x : next_y; /* (fmin: a libm call) */
            if (best[k] != inv_seen) { /* a nearer hit: its distance, once */
                inv_seen = best[k];
                t_seen = 1.0 / inv_seen;
            }
            if (!(t_next < t1) || t_seen <= t_next - tol)
                break; /* out of the box or of range, or the nearest hit is found */
            if (next_x < next_y) {
                ix += sx;
                next_x += step_x;
            } else {
                iy += sy;
                next_y += step_y;
            }
            if (ix < 0 || ix >= g->nx || iy < 0 || iy >= g->ny)
                break;
        }
    }
    return met;
}

typedef struct {
    /* Either the cuts as (scan, beam, distance), room for `cap`; */
    Py_ssize_t cap, *scan, *beam;
    double *t;
    /* or, where `ranges` is set, applied to the scans' rows of `width` beams at once:
     * ranges = min(ranges, distance) and valid = 1 (np.minimum.at and an assignment). */
    double *ranges;
    char *valid;
    Py_ssize_t width;
} cut_sink;

/* Where the discs cut the rays of several scans (crowd.occlusions, its arithmetic in its
 * order). Writes (scan, beam, distance) of every cut, grouped by scan, into the out
 * arrays (room for `cap`); returns how many, or -1 when they have no room. The disc's
 * window of beams comes from libm's asin and atan2 (numpy's can differ in the last bit:
 * as for faces, only a beam within an ulp of a window's end, a ray grazing the disc,
 * could change side); the distances use cos, sin and sqrt, which numpy computes as libm
 * does here (a probe in crowd.py checks it). */
static Py_ssize_t
disc_cuts(Py_ssize_t S, const double *ox, const double *oy, const double *first,
          const double *step, const Py_ssize_t *beams, const double *max_range,
          const Py_ssize_t *skip, Py_ssize_t N, const double *cx, const double *cy,
          const double *r, const cut_sink *out)
{
    Py_ssize_t n = 0;
    for (Py_ssize_t s = 0; s < S; s++) {
        Py_ssize_t own = skip[s] < 0 ? skip[s] + N : skip[s]; /* numpy's negative index */
        double st = step[s];
        double last = (double)(beams[s] - 1);
        for (Py_ssize_t k = 0; k < N; k++) {
            double dx = cx[k] - ox[s];
            double dy = cy[k] - oy[s];
            double d2 = dx * dx + dy * dy;
            double reach = max_range[s] + r[k];
            if (k == own || !(d2 > r[k] * r[k]) || !(d2 < reach * reach))
                continue;
            double rp = r[k];
            double half = asin(rp / sqrt(d2));
            double phi = fmod(atan2(dy, dx) - first[s], TAU); /* np.mod: the divisor's sign */
            if (phi != 0.0) {
                if (phi < 0.0)
                    phi += TAU;
            } else {
                phi = 0.0;
            }
            double lo_f = ceil((phi - half) / st);
            double hi_f = floor((phi + half) / st);
            lo_f = lo_f > 0.0 ? lo_f : 0.0;
            hi_f = hi_f < last ? hi_f : last;
            if (!(lo_f <= hi_f))
                continue; /* no beam (or NaN): never an index outside [0, beams) */
            Py_ssize_t lo = (Py_ssize_t)lo_f, hi = (Py_ssize_t)hi_f;
            double c = d2 - rp * rp;
            for (Py_ssize_t b = lo; b <= hi; b++) {
                double angle = first[s] + (double)b * st;
                double proj = dx * cos(angle) + dy * sin(angle);
                double disc = proj * proj - c;
                double t = proj - sqrt(disc > 0.0 ? disc : 0.0);
                if (disc >= 0.0 && proj > 0.0 && t <= max_range[s]) {
                    if (out->ranges != NULL) {
                        double *at = &out->ranges[s * out->width + b];
                        if (t < *at)
                            *at = t;
                        out->valid[s * out->width + b] = 1;
                    } else {
                        if (n >= out->cap)
                            return -1;
                        out->scan[n] = s;
                        out->beam[n] = b;
                        out->t[n] = t;
                    }
                    n++;
                }
            }
        }
    }
    return n;
}

/* A C-contiguous buffer of `count` numbers (-1: any count, stored in *count_out) of
 * kind 'd' (float64), 'Z' (complex128: two doubles each, counted as such) or 'n'
 * (numpy's intp). */
static int get_buf(PyObject *obj, Py_buffer *view, char kind, Py_ssize_t count,
                   Py_ssize_t *count_out, int writable, const char *name)
{
    int flags = PyBUF_C_CONTIGUOUS | PyBUF_FORMAT | (writable ? PyBUF_WRITABLE : 0);
    if (PyObject_GetBuffer(obj, view, flags) < 0)
        return -1;
    const char *fmt = view->format ? view->format : "B";
    if (fmt[0] == '<' || fmt[0] == '=' || fmt[0] == '@')
        fmt++;
    int ok;
    Py_ssize_t size;
    if (kind == '?') {
        ok = fmt[0] == '?' && fmt[1] == '\0' && view->itemsize == 1;
        size = 1;
    } else if (kind == 'n') {
        ok = (fmt[0] == 'l' || fmt[0] == 'q' || fmt[0] == 'n') && fmt[1] == '\0' &&
             view->itemsize == (Py_ssize_t)sizeof(Py_ssize_t);
        size = (Py_ssize_t)sizeof(Py_ssize_t);
    } else {
        ok = (kind == 'Z') ? (fmt[0] == 'Z' && fmt[1] == 'd' && fmt[2] == '\0')
                           : (fmt[0] == 'd' && fmt[1] == '\0');
        size = (Py_ssize_t)sizeof(double);
    }
    Py_ssize_t have = view->len / size;
    if (!ok || (count >= 0 && have != count)) {
        if (count >= 0)
            PyErr_Format(PyExc_ValueError, "%s: expected %zd %s in one C-contiguous block",
                         name, count, kind == 'n' ? "intp" : "doubles");
        else
            PyErr_Format(PyExc_ValueError, "%s: expected %s in one C-contiguous block", name,
                         kind == 'n' ? "intp" : kind == 'Z' ? "complex128"
                         : kind == '?' ? "bool" : "float64");
        PyBuffer_Release(view);
        return -1;
    }
    if (count_out != NULL)
        *count_out = have;
    return 0;
}

static void release_all(Py_buffer *views, int n)
{
    for (int i = 0; i < n; i++)
        PyBuffer_Release(&views[i]);
}

/* numpy's complex absolute value (np.abs of complex128) as its SIMD loop computes it on
 * x86-64 with AVX2 or AVX-512 (loops_unary_complex.dispatch.c.src): the larger magnitude
 * times sqrt(1 + ratio^2), ratio = smaller / larger, the square added with a fused
 * multiply-add (`fused`; a plain product and sum where numpy's baseline has no FMA). It
 * differs from libm's hypot in the last bit for about a third of values. An infinite part
 * gives inf, else a NaN part NaN; 0/0 and inf/inf are never divided. */
static inline double np_cabs(double re, double im, int fused)
{
    re = fabs(re);
    im = fabs(im);
    int re_inf = re == INFINITY, im_inf = im == INFINITY;
    if (re_inf)
        im = INFINITY;
    if (im_inf)
        re = INFINITY;
    int re_nan = isnan(re), im_nan = isnan(im);
    if (re_nan)
        im = NAN;
    if (im_nan)
        re = NAN;
    double larger = re > im ? re : im;
    double smaller = im < re ? im : re;
    double ratio = (larger == 0.0 || smaller == INFINITY) ? 0.0 : smaller / larger;
    double root = sqrt(fused ? fma(ratio, ratio, 1.0) : ratio * ratio + 1.0);
    return root * larger;
}

/* One element of numpy's matmul (B, 2) @ (2, E) of complex128 for E = 1, as it reaches
 * OpenBLAS's zgemv (the transposed kernel's tail of two rows, in plain products, then
 * y = 0 + (1 temp - 0 temp'), alpha = 1 and beta = 0): the row (a0, a1) times the
 * column (x0, x1). The fan's ellipses check at construction that this is numpy's
 * number for their shapes (raycast.FanCaster), and keep numpy's product otherwise. */
static inline cplx gemv_2(cplx a0, cplx a1, cplx x0, cplx x1)
{
    double tr = a0.re * x0.re - a0.im * x0.im;
    double ti = a0.re * x0.im + a0.im * x0.re;
    tr += a1.re * x1.re - a1.im * x1.im;
    ti += a1.re * x1.im + a1.im * x1.re;
    cplx r;
    r.re = 0.0 + (1.0 * tr - 0.0 * ti);
    r.im = 0.0 + (1.0 * ti + 0.0 * tr);
    return r;
}

/* What the ellipses do to one scan (FanCaster._ellipses, its arithmetic in its order):
 * lower t[k] to the nearest entry (from outside) or exit (from inside) of beam k into
 * each of the E ellipses. dd: (B, 2) beams [dirs, conj(dirs)]; rows: (2, E) the
 * ellipses' [alpha conj(u), beta u]; centre, uconj: (E,) complex; alpha, beta: (E,);
 * o: the ladar's place; turn: the fan's turn, conjugated. Returns 0, or -1 when out of
 * memory. */
#if defined(__GNUC__) && defined(__x86_64__) && !defined(__clang__)
__attribute__((target_clones("fma", "default")))
#endif
static int
cast_ellipses(double *t, const cplx *dd, Py_ssize_t n, const cplx *rows, const cplx *centre,
              const cplx *uconj, const double *alpha, const double *beta, Py_ssize_t e,
              cplx o, cplx turn, double t_min, int fused, int abs_fused, int inplace_fused)
{
    /* Per ellipse: conj(alpha v + beta conj(v)) (v the origin in its frame), |.|^2 - 1,
     * its sign, and the two coefficients of the beams' product (rows times the turns). */
    cplx *oc = malloc((size_t)(e > 0 ? e : 1) * 3 * sizeof(cplx));
    double *cs = malloc((size_t)(e > 0 ? e : 1) * 2 * sizeof(double));
    if (oc == NULL || cs == NULL) {
        free(oc);
        free(cs);
        return -1;
    }
    cplx *coef = oc + e; /* coef[2 j], coef[2 j + 1] */
    double *sign = cs + e;
    cplx turn_c = {turn.re, -turn.im};
    for (Py_ssize_t j = 0; j < e; j++) {
        cplx v = {o.re - centre[j].re, o.im - centre[j].im};
        /* numpy's in-place products of E numbers (v *= uconj ...): rounded as its loop
         * for that length does (a single number takes its plain scalar loop). */
        v = cmul(v, uconj[j], inplace_fused);
        cplx w = {v.re, -v.im};
        cplx a = {alpha[j], 0.0}, b = {beta[j], 0.0}; /* numpy casts the reals to complex */
        w = cmul(w, a, inplace_fused);
        v = cmul(v, b, inplace_fused);
        w.re += v.re;
        w.im += v.im;
        oc[j] = w;
        double c = np_cabs(w.re, w.im, abs_fused);
        c *= c;
        c -= 1.0; /* > 0: the origin is outside */
        cs[j] = c;
        sign[j] = c > 0.0 ? 1.0 : c < 0.0 ? -1.0 : c == 0.0 ? 0.0 : c; /* np.sign */
        coef[2 * j] = cmul(rows[j], turn, fused);
        coef[2 * j + 1] = cmul(rows[e + j], turn_c, fused);
    }
    for (Py_ssize_t k = 0; k < n; k++) {
        double low = INFINITY;
        for (Py_ssize_t j = 0; j < e; j++) {
            cplx m = gemv_2(dd[2 * k], dd[2 * k + 1], coef[2 * j], coef[2 * j + 1]);
            double a = np_cabs(m.re, m.im, abs_fused);
            a *= a; /* |m|^2 */
            cplx q = cmul(m, oc[j], fused); /* real: m . o, imaginary: cross(o, m) */
            double disc = a - q.im * q.im;
            double root = sqrt(disc); /* NaN for a miss */
            root *= sign[j];
            root -= q.re;
            double hit = cs[j] / root;
            if (!(hit > t_min))
                hit = INFINITY; /* behind, grazing at the origin, missed */
            if (hit < low)
                low = hit;
        }
        if (low < t[k]) /* np.minimum: a NaN in t stays */
            t[k] = low;
    }
    free(oc);
    free(cs);
    return 0;
}

PyDoc_STRVAR(faces_doc,
"faces(zw, front_min, best, rel_s, dconj, rot, c, kc, eps, wrap_hi, may_wrap, fused)\n"
"--\n\n"
"Raise best (1/t per beam, in place) to the faces' hits: FanCaster._faces, compiled.\n"
"zw: (4, m) complex world rows; front_min: (m,); rel_s: (n,) float; dconj: (n,) complex;\n"
"rot, c, kc: complex (the fan's turn, the turned origin, kappa times it) and best (n,),\n"
"or (S,) complex arrays of them and best (S, n): S scans in one call.");

static int get_complex(PyObject *obj, cplx *out)
{
    Py_complex z = PyComplex_AsCComplex(obj);
    out->re = z.real;
    out->im = z.imag;
    return PyErr_Occurred() ? -1 : 0;
}

static PyObject *faces(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    (void)self;
    if (nargs != 12) {
        PyErr_Format(PyExc_TypeError, "faces() takes 12 arguments (%zd given)", nargs);
        return NULL;
    }
    double eps = PyFloat_AsDouble(args[8]);
    double wrap_hi = PyFloat_AsDouble(args[9]);
    int may_wrap = PyObject_IsTrue(args[10]);
    int fused = PyObject_IsTrue(args[11]);
    if (PyErr_Occurred() || may_wrap < 0 || fused < 0)
        return NULL;
    Py_buffer v[8];
    Py_ssize_t m, n, S = 1, two_s;
    cplx one[3];
    const cplx *per[3] = {&one[0], &one[1], &one[2]}; /* rot, c, kc of each scan */
    int got = 0;
    int batch = PyObject_CheckBuffer(args[5]);
    if (!batch) {
        for (int i = 0; i < 3; i++)
            if (get_complex(args[5 + i], &one[i]) < 0)
                return NULL;
    }
    if (get_buf(args[1], &v[got], 'd', -1, &m, 0, "front_min") < 0)
        goto fail;
    got++;
    if (get_buf(args[0], &v[got], 'Z', 8 * m, NULL, 0, "zw") < 0)
        goto fail;
    got++;
    if (get_buf(args[3], &v[got], 'd', -1, &n, 0, "rel_s") < 0)
        goto fail;
    got++;
    if (get_buf(args[4], &v[got], 'Z', 2 * n, NULL, 0, "dconj") < 0)
        goto fail;
    got++;
    if (batch) {
        static const char *const names[] = {"rot", "c", "kc"};
        for (int i = 0; i < 3; i++) {
            if (get_buf(args[5 + i], &v[got], 'Z', i ? 2 * S : -1, &two_s, 0, names[i]) < 0)
                goto fail;
            S = two_s / 2;
            per[i] = (const cplx *)v[got].buf;
            got++;
        }
    }
    if (get_buf(args[2], &v[got], 'd', S * n, NULL, 1, "best") < 0)
        goto fail;
    got++;
    double *best = (double *)v[got - 1].buf;
    int status = 0;
    for (Py_ssize_t k = 0; k < S && status == 0; k++)
        status = cast_faces((const double *)v[1].buf, (const double *)v[0].buf, m,
                            best + k * n, (const double *)v[2].buf,
                            (const double *)v[3].buf, n, per[0][batch ? k : 0],
                            per[1][batch ? k : 0], per[2][batch ? k : 0], eps, wrap_hi,
                            may_wrap, fused);
    release_all(v, got);
    if (status < 0)
        return PyErr_NoMemory();
    Py_RETURN_NONE;
fail:
    release_all(v, got);
    return NULL;
}

/* A fan's walk through a world's grid, with every array it reads or writes held (their
 * buffers taken once, not on every scan) and its per-face scratch. */
typedef struct {
    PyObject_HEAD
    Py_buffer v[9]; /* zw, front_min, dconj, box, start, faces; best, ranges, hit */
    int got;
    face_grid g;
    Py_ssize_t m, n, scan, met;
    double eps, t_lim, tol, inv_none, inv_hit, max_range;
    int fused;
    walk_face *memo;
} grid_walk;

static void grid_walk_dealloc(grid_walk *self)
{
    release_all(self->v, self->got);
    free(self->memo);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

PyDoc_STRVAR(grid_walk_doc,
"GridWalk(zw, front_min, dconj, box, start, faces, best, ranges, hit, eps, fused, t_lim,\n"
"         tol, inv_none, inv_hit, max_range)\n"
"--\n\n"
"One fan's scans through a world's grid of faces (FanCaster with a FaceGrid).\n"
"zw: (4, m) complex world rows; front_min: (m,); dconj: (n,) complex, the beams;\n"
"box: (x0, y0, cell, nx, ny) float; start: (nx ny + 1,) intp; faces: intp (FaceGrid);\n"
"best, ranges: (n,) float and hit: (n,) bool, written by each scan; then FanCaster's\n"
"constants. The arrays are held, and must not be resized, while it lives.");

static int grid_walk_init(grid_walk *self, PyObject *args, PyObject *kwds)
{
    PyObject *a[9];
    if (kwds != NULL && PyDict_GET_SIZE(kwds) > 0) {
        PyErr_SetString(PyExc_TypeError, "GridWalk() takes no keyword arguments");
        return -1;
    }
    if (self->got > 0) {
        PyErr_SetString(PyExc_TypeError, "GridWalk() is made once");
        return -1;
    }
    if (!PyArg_ParseTuple(args, "OOOOOOOOOdpddddd", &a[0], &a[1], &a[2], &a[3], &a[4], &a[5],
                          &a[6], &a[7], &a[8], &self->eps, &self->fused, &self->t_lim,
                          &self->tol, &self->inv_none, &self->inv_hit, &self->max_range))
        return -1;
    /* front_min first (it gives m), then the rest in order; `got` counts the taken. */
    static const int order[] = {1, 0, 2, 3, 4, 5, 6, 7, 8};
    static const char kinds[] = "Zd" "Zdnn" "dd?";
    static const char *const names[] = {"zw", "front_min", "dconj", "box", "start", "faces",
                                        "best", "ranges", "hit"};
    Py_ssize_t m = 0, n = 0, n_start = 0, n_faces = 0;
    for (int o = 0; o < 9; o++) {
        int i = order[o];
        Py_ssize_t want = i == 0 ? 8 * m : i == 3 ? 5 : i >= 6 ? n : -1;
        Py_ssize_t *out = i == 1 ? &m : i == 2 ? &n : i == 4 ? &n_start : i == 5 ? &n_faces
                          : NULL;
        if (get_buf(a[i], &self->v[i], kinds[i], want, out, i >= 6, names[i]) < 0) {
            for (int k = 0; k < o; k++)
                PyBuffer_Release(&self->v[order[k]]);
            return -1;
        }
        if (i == 2)
            n /= 2; /* complex: two doubles each */
    }
    self->got = 9;
    const double *box = self->v[3].buf;
    if (!(box[2] > 0.0 && box[3] >= 1.0 && box[4] >= 1.0 &&
          box[3] * box[4] + 1.0 == (double)n_start)) {
        PyErr_SetString(PyExc_ValueError, "GridWalk: the grid's box and cells do not fit "
                        "together");
        return -1;
    }
    self->g.x0 = box[0];
    self->g.y0 = box[1];
    self->g.h = box[2];
    self->g.nx = (Py_ssize_t)box[3];
    self->g.ny = (Py_ssize_t)box[4];
    self->g.start = self->v[4].buf;
    self->g.faces = self->v[5].buf;
    self->g.n_faces = n_faces;
    self->m = m;
    self->n = n;
    self->scan = 0;
    self->memo = malloc((size_t)(m > 0 ? m : 1) * sizeof(walk_face));
    if (self->memo == NULL) {
        PyErr_NoMemory();
        return -1;
    }
    for (Py_ssize_t j = 0; j < m; j++)
        self->memo[j].scan = -1;
    return 0;
}

/* The walk from the scan's origin and turns (ox, oy, rot, c: args[0..3]) into best. */
static int grid_walk_run(grid_walk *self, PyObject *const *args, Py_ssize_t nargs,
                         const char *name)
{
    if (nargs != 4) {
        PyErr_Format(PyExc_TypeError, "%s() takes 4 arguments (%zd given)", name, nargs);
        return -1;
    }
    if (self->got < 9) {
        PyErr_SetString(PyExc_ValueError, "GridWalk: not made");
        return -1;
    }
    double ox = PyFloat_AsDouble(args[0]);
    double oy = PyFloat_AsDouble(args[1]);
    cplx rc[2];
    if (PyErr_Occurred())
        return -1;
    for (int i = 0; i < 2; i++)
        if (get_complex(args[2 + i], &rc[i]) < 0)
            return -1;
    self->scan++;
    self->met = grid_cast(self->v[0].buf, self->v[1].buf, self->m, self->v[6].buf,
                          self->v[2].buf, self->n, rc[0], rc[1], self->eps, self->fused,
                          &self->g, ox, oy, self->t_lim, self->tol, self->memo, self->scan);
    return 0;
}

PyDoc_STRVAR(grid_walk_faces_doc,
"faces(ox, oy, rot, c)\n"
"--\n\n"
"Raise best (1/t per beam, in place) to the hits of the faces along the beams from\n"
"(ox, oy): FanCaster._faces. rot, c: the fan's turn and c = (ox + i oy) rot, as Python's\n"
"complex product rounds it.");

static PyObject *grid_walk_faces(grid_walk *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (grid_walk_run(self, args, nargs, "faces") < 0)
        return NULL;
    Py_RETURN_NONE;
}

PyDoc_STRVAR(grid_walk_scan_doc,
"scan(ox, oy, rot, c)\n"
"--\n\n"
"A whole scan of a world of straight faces: best filled with inv_none and raised\n"
"(faces), then ranges = min(1 / best, max_range) and hit = best >= inv_hit, as\n"
"FanCaster.cast finishes them.");

static PyObject *grid_walk_scan(grid_walk *self, PyObject *const *args, Py_ssize_t nargs)
{
    double *best = self->v[6].buf;
    for (Py_ssize_t k = 0; self->got == 9 && k < self->n; k++)
        best[k] = self->inv_none;
    if (grid_walk_run(self, args, nargs, "scan") < 0)
        return NULL;
    double *ranges = self->v[7].buf;
    char *hit = self->v[8].buf;
    for (Py_ssize_t k = 0; k < self->n; k++) {
        double t = 1.0 / best[k];
        ranges[k] = t < self->max_range ? t : self->max_range;
        hit[k] = best[k] >= self->inv_hit;
    }
    Py_RETURN_NONE;
}

static PyMethodDef grid_walk_methods[] = {
    {"faces", (PyCFunction)(void (*)(void))grid_walk_faces, METH_FASTCALL, grid_walk_faces_doc},
    {"scan", (PyCFunction)(void (*)(void))grid_walk_scan, METH_FASTCALL, grid_walk_scan_doc},
    {NULL, NULL, 0, NULL},
};

static PyMemberDef grid_walk_members[] = {
    {"met", T_PYSSIZET, offsetof(grid_walk, met), READONLY,
     "how many faces the last scan met (turned into its fan's frame)"},
    {NULL, 0, 0, 0, NULL},
};

static PyTypeObject grid_walk_type = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "mdle.sim._kernels.GridWalk",
    .tp_basicsize = sizeof(grid_walk),
    .tp_dealloc = (destructor)grid_walk_dealloc,
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = grid_walk_doc,
    .tp_methods = grid_walk_methods,
    .tp_members = grid_walk_members,
    .tp_init = (initproc)grid_walk_init,
    .tp_new = PyType_GenericNew,
};

PyDoc_STRVAR(occlusions_doc,
"occlusions(ox, oy, first, step, beams, max_range, skip, cx, cy, r, scan, beam, t)\n"
"--\n\n"
"Where the discs cut the rays of several scans: crowd.occlusions, compiled.\n"
"Scans: ox, oy, first, step, max_range (S,) float; beams, skip (S,) intp. Discs: cx, cy,\n"
"r (N,) float. Writes the cuts into scan, beam (intp) and t (float), grouped by scan,\n"
"and returns how many; ValueError when they have no room.");

PyDoc_STRVAR(occlude_doc,
"occlude(ox, oy, first, step, beams, max_range, skip, cx, cy, r, ranges, valid)\n"
"--\n\n"
"occlusions, applied: ranges (S, B) float becomes the nearer of itself and each cut,\n"
"and valid (S, B) bool is set where a disc cuts. Returns how many cuts.");

/* The scans' and discs' arrays (args[0..9]) of occlusions and occlude. */
static int get_scans_discs(PyObject *const *args, Py_buffer *v, int *got, Py_ssize_t *S,
                           Py_ssize_t *N)
{
    static const char kinds[] = "ddddndnddd";
    static const char *const names[] = {"ox", "oy", "first", "step", "beams", "max_range",
                                        "skip", "cx", "cy", "r"};
    for (; *got < 10; (*got)++) {
        int i = *got;
        Py_ssize_t want = i == 0 ? -1 : i < 7 ? *S : i == 7 ? -1 : *N;
        Py_ssize_t *out = i == 0 ? S : i == 7 ? N : NULL;
        if (get_buf(args[i], &v[i], kinds[i], want, out, 0, names[i]) < 0)
            return -1;
    }
    return 0;
}

/* occlusions (apply = 0: the cuts into scan, beam, t) and occlude (apply = 1: into
 * ranges, valid): the same scans and discs, and a different sink. */
static PyObject *disc_entry(PyObject *const *args, Py_ssize_t nargs, int apply)
{
    const char *name = apply ? "occlude" : "occlusions";
    Py_ssize_t want = apply ? 12 : 13;
    if (nargs != want) {
        PyErr_Format(PyExc_TypeError, "%s() takes %zd arguments (%zd given)", name, want,
                     nargs);
        return NULL;
    }
    Py_buffer v[13];
    Py_ssize_t S, N, count;
    int got = 0;
    cut_sink sink = {0, NULL, NULL, NULL, NULL, NULL, 0};
    if (get_scans_discs(args, v, &got, &S, &N) < 0)
        goto fail;
    /* The sink's arrays, writable, as long as the first: scan, beam, t or ranges, valid. */
    static const char *const sink_names[2][3] = {{"scan", "beam", "t"},
                                                 {"ranges", "valid", NULL}};
    static const char sink_kinds[2][4] = {"nnd", "d?"};
    for (int i = 0; i < 3 - apply; i++, got++)
        if (get_buf(args[10 + i], &v[got], sink_kinds[apply][i], i ? count : -1,
                    i ? NULL : &count, 1, sink_names[apply][i]) < 0)
            goto fail;
    if (apply) {
        Py_ssize_t width = S ? count / S : 0;
        const Py_ssize_t *beams = v[4].buf;
        for (Py_ssize_t s = 0; s < S; s++) {
            if (beams[s] > width || width * S != count) {
                PyErr_Format(PyExc_ValueError, "occlude: ranges has %zd cells, not %zd rows "
                             "of at least %zd beams", count, S, beams[s]);
                goto fail;
            }
        }
        sink.ranges = v[10].buf;
        sink.valid = v[11].buf;
        sink.width = width;
    } else {
        sink.cap = count;
        sink.scan = v[10].buf;
        sink.beam = v[11].buf;
        sink.t = v[12].buf;
    }
    Py_ssize_t n = disc_cuts(S, v[0].buf, v[1].buf, v[2].buf, v[3].buf, v[4].buf, v[5].buf,
                             v[6].buf, N, v[7].buf, v[8].buf, v[9].buf, &sink);
    release_all(v, got);
    if (n < 0) {
        PyErr_SetString(PyExc_ValueError, "occlusions: the out arrays have no room left");
        return NULL;
    }
    return PyLong_FromSsize_t(n);
fail:
    release_all(v, got);
    return NULL;
}

static PyObject *occlusions(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    (void)self;
    return disc_entry(args, nargs, 0);
}

static PyObject *occlude(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    (void)self;
    return disc_entry(args, nargs, 1);
}

/* libm's pow, reached through a pointer the compiler cannot see through: GCC turns a
 * direct pow(v, 2.0) into v * v, and glibc's pow rounds a square otherwise for about one
 * value in a thousand. Python's ** calls libm's pow. */
static double (*const volatile libm_pow)(double, double) = pow;

/* sim/distance.py's ellipse_nearest_point, in the same double operations in the same
 * order (Python's floats are these doubles; ** 2 is libm's pow, as Python calls it):
 * the nearest point (x, y) of the axis-aligned ellipse of semi-axes a, b to (y0, y1). */
static void ellipse_nearest_point(double a, double b, double y0, double y1, double *x_out,
                                  double *y_out)
{
    int swap = a < b;
    if (swap) {
        double t;
        t = a, a = b, b = t;
        t = y0, y0 = y1, y1 = t;
    }
    double z0 = fabs(y0), z1 = fabs(y1);
    double a2 = a * a, b2 = b * b;
    double x, y;
    if (z1 == 0.0) {
        if (z0 < (a2 - b2) / a) { /* inside, near the centre: off the axis */
            x = a2 * z0 / (a2 - b2);
            double v = 1.0 - libm_pow(x / a, 2.0);
            y = b * sqrt(v > 0.0 ? v : 0.0);        /* max(0.0, v): 0.0 unless v > 0 */
        } else {
            x = a;
            y = 0.0;
        }
    } else {
        double az = a * z0, bz = b * z1;
        double t = bz - b2 > az - a2 ? bz - b2 : az - a2; /* Python's max */
        for (int i = 0; i < 60; i++) {              /* distance.py's _NEWTON_STEPS */
            double ta = t + a2, tb = t + b2;
            double p = az / ta, q = bz / tb;
            p = p * p;
            q = q * q;
            double step = 0.5 * (p + q - 1.0) / (p / ta + q / tb);
            t += step;
            if (step <= 1e-14 * (fabs(t) + a2))
                break;
        }
        x = a2 * z0 / (t + a2);
        y = b2 * z1 / (t + b2);
    }
    if (y0 < 0)
        x = -x;
    if (y1 < 0)
        y = -y;
    *x_out = swap ? y : x;
    *y_out = swap ? x : y;
}

PyDoc_STRVAR(ellipse_near_doc,
"ellipse_near(x, y, best, centre, uconj, bound, axes, fused, abs_fused)\n"
"--\n\n"
"The ellipses a clearance query from (x, y) must measure, and their nearest points:\n"
"Collider.distance's few-ellipses branch, compiled. centre, uconj: (E,) complex; bound:\n"
"(E,) float; axes: (E, 2) float. Each ellipse whose |(x, y) - centre| - bound is below\n"
"best gives (the query in its frame: re, im; its nearest point: x, y; its index), in\n"
"order; the caller measures the distances with Python's math.hypot.");

static PyObject *ellipse_near(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    (void)self;
    if (nargs != 9) {
        PyErr_Format(PyExc_TypeError, "ellipse_near() takes 9 arguments (%zd given)", nargs);
        return NULL;
    }
    double x = PyFloat_AsDouble(args[0]);
    double y = PyFloat_AsDouble(args[1]);
    double best = PyFloat_AsDouble(args[2]);
    int fused = PyObject_IsTrue(args[7]);
    int abs_fused = PyObject_IsTrue(args[8]);
    if (PyErr_Occurred() || fused < 0 || abs_fused < 0)
        return NULL;
    Py_buffer v[4];
    Py_ssize_t two_e;
    int got = 0;
    PyObject *out = NULL;
    if (get_buf(args[3], &v[got], 'Z', -1, &two_e, 0, "centre") < 0)
        goto done;
    got++;
    Py_ssize_t e = two_e / 2;
    if (get_buf(args[4], &v[got], 'Z', 2 * e, NULL, 0, "uconj") < 0)
        goto done;
    got++;
    if (get_buf(args[5], &v[got], 'd', e, NULL, 0, "bound") < 0)
        goto done;
    got++;
    if (get_buf(args[6], &v[got], 'd', 2 * e, NULL, 0, "axes") < 0)
        goto done;
    got++;
    const cplx *centre = v[0].buf, *uconj = v[1].buf;
    const double *bound = v[2].buf, *axes = v[3].buf;
    out = PyList_New(0);
    for (Py_ssize_t j = 0; out != NULL && j < e; j++) {
        cplx w = {x - centre[j].re, y - centre[j].im};  /* q - c */
        double lower = np_cabs(w.re, w.im, abs_fused) - bound[j];
        if (!(lower < best))
            continue;
        cplx l = cmul(w, uconj[j], fused);             /* the query in the ellipse's frame */
        double ex, ey;
        ellipse_nearest_point(axes[2 * j], axes[2 * j + 1], l.re, l.im, &ex, &ey);
        PyObject *item = Py_BuildValue("(ddddn)", l.re, l.im, ex, ey, j);
        if (item == NULL || PyList_Append(out, item) < 0)
            Py_CLEAR(out);
        Py_XDECREF(item);
    }
done:
    release_all(v, got);
    return out;
}

/* numpy's maximum and minimum: a NaN of either operand (the first's first), else the
 * larger (smaller), the second where they are equal (which decides a zero's sign). */
static inline double np_maximum(double a, double b)
{
    return isnan(a) ? a : isnan(b) ? b : a > b ? a : b;
}

static inline double np_minimum(double a, double b)
{
    return isnan(a) ? a : isnan(b) ? b : a < b ? a : b;
}

PyDoc_STRVAR(settle_doc,
"settle(ranges, valid, noise, sigma, relative, resolution, max_range)\n"
"--\n\n"
"A ladar's noise, quantum and clipping, in place: sim/ladar.py's _Settling.settle,\n"
"compiled. ranges, noise: (n,) float (noise: standard normal draws, scaled in place as\n"
"numpy scales them; None: no noise); valid: (n,) bool; resolution 0: no quantum.");

static PyObject *settle(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    (void)self;
    if (nargs != 7) {
        PyErr_Format(PyExc_TypeError, "settle() takes 7 arguments (%zd given)", nargs);
        return NULL;
    }
    double sigma = PyFloat_AsDouble(args[3]);
    int relative = PyObject_IsTrue(args[4]);
    double res = PyFloat_AsDouble(args[5]);
    double top = PyFloat_AsDouble(args[6]);
    if (PyErr_Occurred() || relative < 0)
        return NULL;
    Py_buffer v[3];
    Py_ssize_t n;
    int got = 0;
    if (get_buf(args[0], &v[got], 'd', -1, &n, 1, "ranges") < 0)
        goto fail;
    got++;
    if (get_buf(args[1], &v[got], '?', n, NULL, 0, "valid") < 0)
        goto fail;
    got++;
    int noisy = args[2] != Py_None;
    if (noisy && get_buf(args[2], &v[got++], 'd', n, NULL, 1, "noise") < 0) {
        got--;
        goto fail;
    }
    double *r = v[0].buf;
    const char *ok = v[1].buf;
    double *noise = noisy ? v[2].buf : NULL;
    for (Py_ssize_t k = 0; k < n; k++) {
        double x = r[k];
        if (noisy) {
            double e = noise[k] * sigma;
            if (relative)
                e *= x;
            e *= ok[k] ? 1.0 : 0.0;         /* numpy casts the bools to 1.0 and 0.0 */
            noise[k] = e;
            x += e;
        }
        if (res != 0.0) {
            x /= res;
            x = rint(x);                    /* to even, as np.rint */
            x *= res;
        }
        r[k] = np_minimum(np_maximum(x, 0.0), top);
    }
    release_all(v, got);
    Py_RETURN_NONE;
fail:
    release_all(v, got);
    return NULL;
}

PyDoc_STRVAR(absolute_doc,
"absolute(z, out, fused)\n"
"--\n\n"
"out = |z| for z (n,) complex, as numpy's SIMD loop rounds it (fused: with a fused\n"
"multiply-add): the import-time probe of sim/raycast.py and the tests compare it with\n"
"np.abs.");

static PyObject *absolute(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    (void)self;
    if (nargs != 3) {
        PyErr_Format(PyExc_TypeError, "absolute() takes 3 arguments (%zd given)", nargs);
        return NULL;
    }
    int fused = PyObject_IsTrue(args[2]);
    if (fused < 0)
        return NULL;
    Py_buffer v[2];
    Py_ssize_t two_n;
    if (get_buf(args[0], &v[0], 'Z', -1, &two_n, 0, "z") < 0)
        return NULL;
    if (get_buf(args[1], &v[1], 'd', two_n / 2, NULL, 1, "out") < 0) {
        release_all(v, 1);
        return NULL;
    }
    const double *z = v[0].buf;
    double *out = v[1].buf;
    for (Py_ssize_t k = 0; k < two_n / 2; k++)
        out[k] = np_cabs(z[2 * k], z[2 * k + 1], fused);
    release_all(v, 2);
    Py_RETURN_NONE;
}

PyDoc_STRVAR(beam_product_doc,
"beam_product(dd, coef, out)\n"
"--\n\n"
"out = dd @ coef for dd (B, 2) and coef (2, E) complex, as numpy's matmul gives it for\n"
"E = 1 (OpenBLAS's zgemv): the number the compiled ellipses use, which a fan checks\n"
"against numpy's own product before it uses them.");

static PyObject *beam_product(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    (void)self;
    if (nargs != 3) {
        PyErr_Format(PyExc_TypeError, "beam_product() takes 3 arguments (%zd given)", nargs);
        return NULL;
    }
    Py_buffer v[3];
    Py_ssize_t two_b, two_2e;
    int got = 0;
    if (get_buf(args[0], &v[got], 'Z', -1, &two_b, 0, "dd") < 0)
        goto fail;
    got++;
    if (get_buf(args[1], &v[got], 'Z', -1, &two_2e, 0, "coef") < 0)
        goto fail;
    got++;
    Py_ssize_t b = two_b / 4, e = two_2e / 4;
    if (two_b % 4 || two_2e % 4) {
        PyErr_SetString(PyExc_ValueError, "beam_product: dd is (B, 2) and coef (2, E)");
        goto fail;
    }
    if (get_buf(args[2], &v[got], 'Z', 2 * b * e, NULL, 1, "out") < 0)
        goto fail;
    got++;
    const cplx *dd = v[0].buf, *coef = v[1].buf;
    cplx *out = v[2].buf;
    for (Py_ssize_t k = 0; k < b; k++)
        for (Py_ssize_t j = 0; j < e; j++)
            out[k * e + j] = gemv_2(dd[2 * k], dd[2 * k + 1], coef[j], coef[e + j]);
    release_all(v, got);
    Py_RETURN_NONE;
fail:
    release_all(v, got);
    return NULL;
}

PyDoc_STRVAR(ellipses_doc,
"ellipses(t, dd, rows, centre, uconj, alpha, beta, o, turn, t_min, fused, abs_fused,\n"
"         inplace_fused)\n"
"--\n\n"
"Lower t (B,) in place to each beam's nearest ellipse hit: FanCaster._ellipses, compiled.\n"
"dd: (B, 2) complex; rows: (2, E) complex; centre, uconj: (E,) complex; alpha, beta:\n"
"(E,) float; o, turn: complex; t_min: float; fused, abs_fused, inplace_fused: how numpy\n"
"rounds its complex products, absolute values and in-place products of E numbers here.");

PyDoc_STRVAR(ellipse_scan_doc,
"ellipse_scan(t, hit, t_none, t_hit, max_range, dd, rows, centre, uconj, alpha, beta, o,\n"
"             turn, t_min, fused, abs_fused, inplace_fused)\n"
"--\n\n"
"A whole scan of a world of ellipses only (FanCaster.cast): t (B,) filled with t_none\n"
"and lowered (ellipses), then hit (B,) bool = t <= t_hit and t = min(t, max_range).");

/* ellipses (scan = 0: args[0] is t) and ellipse_scan (scan = 1: t, hit, t_none, t_hit,
 * max_range first): the same ellipses, and a whole scan's start and finish. */
static PyObject *ellipse_entry(PyObject *const *args, Py_ssize_t nargs, int scan)
{
    const char *name = scan ? "ellipse_scan" : "ellipses";
    Py_ssize_t want = scan ? 17 : 13;
    if (nargs != want) {
        PyErr_Format(PyExc_TypeError, "%s() takes %zd arguments (%zd given)", name, want,
                     nargs);
        return NULL;
    }
    PyObject *const *a = args + (scan ? 4 : 0); /* a[0] is t, a[1..12] as in ellipses() */
    cplx o, turn;
    if (get_complex(a[7], &o) < 0 || get_complex(a[8], &turn) < 0)
        return NULL;
    double t_min = PyFloat_AsDouble(a[9]);
    int fused = PyObject_IsTrue(a[10]);
    int abs_fused = PyObject_IsTrue(a[11]);
    int inplace_fused = PyObject_IsTrue(a[12]);
    double t_none = scan ? PyFloat_AsDouble(args[2]) : 0.0;
    double t_hit = scan ? PyFloat_AsDouble(args[3]) : 0.0;
    double top = scan ? PyFloat_AsDouble(args[4]) : 0.0;
    if (PyErr_Occurred() || fused < 0 || abs_fused < 0 || inplace_fused < 0)
        return NULL;
    Py_buffer v[8];
    Py_ssize_t n, two_e;
    int got = 0;
    if (get_buf(a[3], &v[got], 'Z', -1, &two_e, 0, "centre") < 0)
        goto fail;
    got++;
    Py_ssize_t e = two_e / 2;
    if (get_buf(args[0], &v[got], 'd', -1, &n, 1, "t") < 0)
        goto fail;
    got++;
    if (get_buf(a[1], &v[got], 'Z', 4 * n, NULL, 0, "dd") < 0)
        goto fail;
    got++;
    if (get_buf(a[2], &v[got], 'Z', 4 * e, NULL, 0, "rows") < 0)
        goto fail;
    got++;
    if (get_buf(a[4], &v[got], 'Z', 2 * e, NULL, 0, "uconj") < 0)
        goto fail;
    got++;
    if (get_buf(a[5], &v[got], 'd', e, NULL, 0, "alpha") < 0)
        goto fail;
    got++;
    if (get_buf(a[6], &v[got], 'd', e, NULL, 0, "beta") < 0)
        goto fail;
    got++;
    if (scan && get_buf(args[1], &v[got++], '?', n, NULL, 1, "hit") < 0) {
        got--;
        goto fail;
    }
    double *t = v[1].buf;
    for (Py_ssize_t k = 0; scan && k < n; k++)
        t[k] = t_none;
    int status = cast_ellipses(t, v[2].buf, n, v[3].buf, v[0].buf, v[4].buf, v[5].buf,
                               v[6].buf, e, o, turn, t_min, fused, abs_fused, inplace_fused);
    if (scan && status == 0) {
        char *hit = v[7].buf;
        for (Py_ssize_t k = 0; k < n; k++) {
            hit[k] = t[k] <= t_hit;
            t[k] = np_minimum(t[k], top);
        }
    }
    release_all(v, got);
    if (status < 0)
        return PyErr_NoMemory();
    Py_RETURN_NONE;
fail:
    release_all(v, got);
    return NULL;
}

static PyObject *ellipses(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    (void)self;
    return ellipse_entry(args, nargs, 0);
}

static PyObject *ellipse_scan(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    (void)self;
    return ellipse_entry(args, nargs, 1);
}

static PyMethodDef methods[] = {
    {"absolute", (PyCFunction)(void (*)(void))absolute, METH_FASTCALL, absolute_doc},
    {"beam_product", (PyCFunction)(void (*)(void))beam_product, METH_FASTCALL,
     beam_product_doc},
    {"ellipses", (PyCFunction)(void (*)(void))ellipses, METH_FASTCALL, ellipses_doc},
    {"ellipse_scan", (PyCFunction)(void (*)(void))ellipse_scan, METH_FASTCALL,
     ellipse_scan_doc},
    {"settle", (PyCFunction)(void (*)(void))settle, METH_FASTCALL, settle_doc},
    {"ellipse_near", (PyCFunction)(void (*)(void))ellipse_near, METH_FASTCALL,
     ellipse_near_doc},
    {"faces", (PyCFunction)(void (*)(void))faces, METH_FASTCALL, faces_doc},
    {"occlusions", (PyCFunction)(void (*)(void))occlusions, METH_FASTCALL, occlusions_doc},
    {"occlude", (PyCFunction)(void (*)(void))occlude, METH_FASTCALL, occlude_doc},
    {NULL, NULL, 0, NULL},
};

static int add_types(PyObject *mod)
{
    if (PyType_Ready(&grid_walk_type) < 0)
        return -1;
    Py_INCREF(&grid_walk_type);
    if (PyModule_AddObject(mod, "GridWalk", (PyObject *)&grid_walk_type) < 0) {
        Py_DECREF(&grid_walk_type);
        return -1;
    }
    return 0;
}

static PyModuleDef_Slot slots[] = {
    {Py_mod_exec, (void *)add_types},
    {0, NULL},
};

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, "_kernels",
    "The simulator's per-tick loops, compiled (an optional build: sim/raycast.py and "
    "sim/crowd.py fall back to numpy).",
    0, methods, slots, NULL, NULL, NULL,
};

PyMODINIT_FUNC PyInit__kernels(void)
{
    return PyModuleDef_Init(&module);
}
