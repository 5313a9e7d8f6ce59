/* The whole-scan boundary model's per-tick searches, compiled (atoms/searches.py): the
 * nearest point on the followed side, the points around it, and the next face's nearest
 * point.
 *
 * Their numpy paths spend most of their time on the fixed cost of some thirty calls on
 * arrays of a few dozen to a few hundred points; these do the same comparisons in one
 * call each. They are an optional build: without a C compiler mdle installs without them
 * and searches.py uses numpy (the same answers).
 *
 * Every answer is numpy's, exactly: the searches only compare numbers numpy computes the
 * same way (differences of two doubles, the squared ranges given). A distance compared
 * with a limit is a modulus in numpy (its own hypot, rounded within an ulp or so) and a
 * squared distance here; when the two could disagree (the squared distance within 1e-12
 * of the squared limit) or a NaN appears, the call answers AMBIGUOUS and the caller runs
 * the numpy path.
 *
 * Built with -ffp-contract=off: every product is rounded where the numpy path rounds it.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>

/* What a search answers when numpy's comparison could go the other way. */
#define AMBIGUOUS (-2)
/* A squared distance this close (relatively) to the squared limit may compare either way. */
#define BAND 1e-12

/* 1: |d| < limit, 0: not, AMBIGUOUS: too close to tell (or NaN). d2 = |d|^2, lim2 = limit^2. */
static inline int below(double d2, double lim2)
{
    if (d2 < lim2 * (1.0 - BAND))
        return 1;
    if (d2 > lim2 * (1.0 + BAND))
        return 0;
    return AMBIGUOUS;
}

/* A C-contiguous buffer of kind 'd' (float64), 'Z' (complex128) or '?' (bool) with
 * `count` items (-1: any; the count is stored in *count_out). */
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
    if (kind == '?')
        ok = fmt[0] == '?' && fmt[1] == '\0' && view->itemsize == 1;
    else if (kind == 'Z')
        ok = fmt[0] == 'Z' && fmt[1] == 'd' && fmt[2] == '\0' && view->itemsize == 16;
    else
        ok = fmt[0] == 'd' && fmt[1] == '\0' && view->itemsize == 8;
    Py_ssize_t have = ok ? view->len / view->itemsize : -1;
    if (!ok || (count >= 0 && have != count)) {
        PyErr_Format(PyExc_ValueError, "%s: expected %s%s in one C-contiguous block", name,
                     kind == 'Z' ? "complex128" : kind == '?' ? "bool" : "float64",
                     count >= 0 ? " of the points' length" : "");
        PyBuffer_Release(view);
        return -1;
    }
    if (count_out != NULL)
        *count_out = have;
    return 0;
}

/* An array in another form than the search reads (strided, another dtype or length):
 * AMBIGUOUS, so that the numpy path, which takes any form, answers. */
static PyObject *other_form(void)
{
    PyErr_Clear();
    return PyLong_FromLong(AMBIGUOUS);
}

PyDoc_STRVAR(nearest_right_doc,
"nearest_right(z, d2)\n"
"--\n\n"
"Index of the first least d2 among the points z with a negative imaginary part (the\n"
"followed side), as argmin of where(z.imag < 0, d2, inf) gives it; -1 when that least\n"
"is inf (none on that side), -2 (ambiguous) on a NaN.");

static PyObject *nearest_right(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    (void)self;
    if (nargs != 2) {
        PyErr_Format(PyExc_TypeError, "nearest_right() takes 2 arguments (%zd given)", nargs);
        return NULL;
    }
    Py_buffer zb, db;
    Py_ssize_t m;
    if (get_buf(args[0], &zb, 'Z', -1, &m, 0, "z") < 0)
        return other_form();
    if (get_buf(args[1], &db, 'd', m, NULL, 0, "d2") < 0) {
        PyBuffer_Release(&zb);
        return other_form();
    }
    const double *z = zb.buf, *d2 = db.buf;
    double best = INFINITY;
    Py_ssize_t k = -1;
    for (Py_ssize_t i = 0; i < m; i++) {
        if (!(z[2 * i + 1] < 0.0))
            continue;
        double v = d2[i];
        if (v != v) { /* numpy's argmin stops at the first NaN */
            k = AMBIGUOUS;
            break;
        }
        if (v < best) {
            best = v;
            k = i;
        }
    }
    PyBuffer_Release(&zb);
    PyBuffer_Release(&db);
    return PyLong_FromSsize_t(k);
}

PyDoc_STRVAR(squared_ranges_doc,
"squared_ranges(z, d2)\n"
"--\n\n"
"Write the points' squared ranges x x + y y into d2 (float64, in place), rounded as\n"
"numpy's d2 = x * x; d2 += y * y rounds them; -2 for an array in another form.");

static PyObject *squared_ranges(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    (void)self;
    if (nargs != 2) {
        PyErr_Format(PyExc_TypeError, "squared_ranges() takes 2 arguments (%zd given)", nargs);
        return NULL;
    }
    Py_buffer zb, db;
    Py_ssize_t m;
    if (get_buf(args[0], &zb, 'Z', -1, &m, 0, "z") < 0)
        return other_form();
    if (get_buf(args[1], &db, 'd', m, NULL, 1, "d2") < 0) {
        PyBuffer_Release(&zb);
        return other_form();
    }
    const double *z = zb.buf;
    double *d2 = db.buf;
    for (Py_ssize_t i = 0; i < m; i++) {
        double xx = z[2 * i] * z[2 * i], yy = z[2 * i + 1] * z[2 * i + 1];
        d2[i] = xx + yy; /* two rounded products, then their rounded sum: numpy's */
    }
    PyBuffer_Release(&zb);
    PyBuffer_Release(&db);
    return PyLong_FromSsize_t(m);
}

PyDoc_STRVAR(within_doc,
"within(z, q, radius, sel)\n"
"--\n\n"
"Mark in sel (bool, in place) the points z with abs(z - q) < radius and return how\n"
"many; -2 (ambiguous: sel unfinished) when one lies within rounding of the radius.");

static PyObject *within(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    (void)self;
    if (nargs != 4) {
        PyErr_Format(PyExc_TypeError, "within() takes 4 arguments (%zd given)", nargs);
        return NULL;
    }
    Py_complex q = PyComplex_AsCComplex(args[1]);
    double radius = PyFloat_AsDouble(args[2]);
    if (PyErr_Occurred())
        return NULL;
    Py_buffer zb, sb;
    Py_ssize_t m;
    if (get_buf(args[0], &zb, 'Z', -1, &m, 0, "z") < 0)
        return other_form();
    if (get_buf(args[3], &sb, '?', m, NULL, 1, "sel") < 0) {
        PyBuffer_Release(&zb);
        return other_form();
    }
    const double *z = zb.buf;
    char *sel = sb.buf;
    double lim2 = radius * radius;
    Py_ssize_t count = radius > 0.0 ? 0 : AMBIGUOUS; /* (a limit of 0 or less: numpy's) */
    for (Py_ssize_t i = 0; i < m && count != AMBIGUOUS; i++) {
        double dx = z[2 * i] - q.real, dy = z[2 * i + 1] - q.imag;
        int in = below(dx * dx + dy * dy, lim2);
        if (in == AMBIGUOUS) {
            count = AMBIGUOUS;
            break;
        }
        sel[i] = (char)in;
        count += in;
    }
    PyBuffer_Release(&zb);
    PyBuffer_Release(&sb);
    return PyLong_FromSsize_t(count);
}

PyDoc_STRVAR(next_face_doc,
"next_face(z, d2, fitted, window, jump)\n"
"--\n\n"
"Index of the next face's nearest point (searches.next_face_numpy, which says\n"
"what that is), -1 for none, -2 when a distance lies within rounding of jump or a NaN\n"
"appears (the numpy path decides).");

/* Whether points i and i + 1 lie on different surfaces: abs(z[i + 1] - z[i]) > jump. */
static inline int cut_at(const double *z, Py_ssize_t i, double jump2)
{
    double dx = z[2 * i + 2] - z[2 * i], dy = z[2 * i + 3] - z[2 * i + 1];
    int in = below(dx * dx + dy * dy, jump2);
    if (in == AMBIGUOUS)
        return AMBIGUOUS;
    /* below() answers < jump within the band; > jump is its negation outside it */
    return !in;
}

static PyObject *next_face(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    (void)self;
    if (nargs != 5) {
        PyErr_Format(PyExc_TypeError, "next_face() takes 5 arguments (%zd given)", nargs);
        return NULL;
    }
    Py_ssize_t w = PyLong_AsSsize_t(args[3]);
    double jump = PyFloat_AsDouble(args[4]);
    if (PyErr_Occurred())
        return NULL;
    Py_buffer zb, db, fb;
    Py_ssize_t m;
    if (get_buf(args[0], &zb, 'Z', -1, &m, 0, "z") < 0)
        return other_form();
    if (get_buf(args[1], &db, 'd', m, NULL, 0, "d2") < 0) {
        PyBuffer_Release(&zb);
        return other_form();
    }
    if (get_buf(args[2], &fb, '?', m, NULL, 0, "fitted") < 0) {
        PyBuffer_Release(&zb);
        PyBuffer_Release(&db);
        return other_form();
    }
    const double *z = zb.buf, *d2 = db.buf;
    const char *fitted = fb.buf;
    double jump2 = jump * jump;
    Py_ssize_t k = -1;
    if (!(jump > 0.0 && w >= 0)) { /* numpy's answer for those */
        k = AMBIGUOUS;
        goto done;
    }
    for (Py_ssize_t i = 0; i < m; i++)
        if (d2[i] != d2[i]) { /* numpy's minimum carries a NaN through the windows */
            k = AMBIGUOUS;
            goto done;
        }
    /* the face followed: the points between the jumps on either side of its first fitted
     * point (argmax of fitted: 0 when none is) */
    Py_ssize_t f = 0;
    while (f < m && !fitted[f])
        f++;
    if (f == m)
        f = 0;
    Py_ssize_t lo = -1, hi = -1;
    for (Py_ssize_t i = 0; i + 1 < m; i++) {
        if (i >= f && hi >= 0)
            break;
        int c = cut_at(z, i, jump2);
        if (c == AMBIGUOUS) {
            k = AMBIGUOUS;
            goto done;
        }
        if (c) {
            if (i < f)
                lo = i;
            else
                hi = i;
        }
    }
    double best = INFINITY;
    for (Py_ssize_t i = 0; i < m; i++) {
        double v = d2[i];
        /* not the face followed, less than 45 deg left of the heading, and nearer than the
         * best so far (the first of equals wins, as argmin's) */
        if (fitted[i] || !(z[2 * i + 1] < z[2 * i]) || !(v < best))
            continue;
        if (!(i <= lo || (hi >= 0 && i > hi))) {
            /* on the face followed: only a local minimum of the range counts */
            Py_ssize_t a = i - w < 0 ? 0 : i - w, b = i + w >= m ? m - 1 : i + w;
            int least = 1;
            for (Py_ssize_t j = a; j <= b; j++)
                if (d2[j] < v) {
                    least = 0;
                    break;
                }
            if (!least)
                continue;
        }
        best = v;
        k = i;
    }
    if (!(best > 0.0 && best < INFINITY))
        k = -1;
done:
    PyBuffer_Release(&zb);
    PyBuffer_Release(&db);
    PyBuffer_Release(&fb);
    return PyLong_FromSsize_t(k);
}

static PyMethodDef methods[] = {
    {"nearest_right", (PyCFunction)(void (*)(void))nearest_right, METH_FASTCALL,
     nearest_right_doc},
    {"squared_ranges", (PyCFunction)(void (*)(void))squared_ranges, METH_FASTCALL,
     squared_ranges_doc},
    {"within", (PyCFunction)(void (*)(void))within, METH_FASTCALL, within_doc},
    {"next_face", (PyCFunction)(void (*)(void))next_face, METH_FASTCALL, next_face_doc},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, "_searches",
    "The whole-scan boundary model's per-tick searches, compiled (an optional build: "
    "atoms/searches.py falls back to numpy).",
    0, methods, NULL, NULL, NULL, NULL,
};

PyMODINIT_FUNC PyInit__searches(void)
{
    return PyModuleDef_Init(&module);
}
