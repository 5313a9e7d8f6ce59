/* A scan's points, compiled (atoms/estimators.py, beam_points): the beams that saw a
 * surface, their ranges and their points x + iy, in one call where numpy takes six.
 *
 * An optional build: without a C compiler mdle installs without it and estimators.py
 * uses numpy. The numbers are numpy's: the test of a range (finite and positive) is a
 * comparison, and a point is the range times the beam's unit direction as numpy's complex
 * product rounds it (numpy casts the range to a complex number, then multiplies with a
 * fused multiply-add in its SIMD loop, or plainly: `fused`). estimators.py checks the
 * result against numpy's at import, on awkward ranges, and keeps numpy otherwise.
 *
 * Built with -ffp-contract=off and without GCC's vectoriser (which fuses plain complex
 * products in the FMA clone whatever the contract flag says).
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>

/* A C-contiguous buffer of kind 'd' (float64), 'Z' (complex128) or '?' (bool) with
 * `count` items. */
static int get_buf(PyObject *obj, Py_buffer *view, char kind, Py_ssize_t count, int writable,
                   const char *name)
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
    if (!ok || view->len / view->itemsize != count) {
        PyErr_Format(PyExc_ValueError, "%s: expected %zd %s in one C-contiguous block", name,
                     count, kind == 'Z' ? "complex128" : kind == '?' ? "bool" : "float64");
        PyBuffer_Release(view);
        return -1;
    }
    return 0;
}

/* The points of n beams: ok[k] = isfinite(r) and r > 0 (and valid[k]), rr[k] = r there
 * and NaN elsewhere, z[k] = rr[k] unit[k] (re, im pairs). */
#if defined(__GNUC__) && defined(__x86_64__) && !defined(__clang__)
/* A clone with the FMA instruction where the CPU has it; fma() is a libm call elsewhere. */
__attribute__((target_clones("fma", "default")))
#endif
static void
points(const double *r, const double *unit, const char *valid, Py_ssize_t n, double *z,
       char *ok, double *rr, int fused)
{
    for (Py_ssize_t k = 0; k < n; k++) {
        double x = r[k];
        int seen = isfinite(x) && x > 0.0 && (valid == NULL || valid[k]);
        double y = seen ? x : NAN;
        double ur = unit[2 * k], ui = unit[2 * k + 1];
        /* (y + 0i)(ur + i ui), as numpy's complex product */
        if (fused) {
            z[2 * k] = fma(y, ur, -(0.0 * ui));
            z[2 * k + 1] = fma(y, ui, 0.0 * ur);
        } else {
            z[2 * k] = y * ur - 0.0 * ui;
            z[2 * k + 1] = y * ui + 0.0 * ur;
        }
        ok[k] = (char)seen;
        rr[k] = y;
    }
}

PyDoc_STRVAR(beam_points_doc,
"beam_points(ranges, unit, valid, z, ok, r, fused)\n"
"--\n\n"
"estimators.beam_points, compiled: ranges (n,) float; unit (n,) complex; valid (n,) bool\n"
"or None; writes the points z (n,) complex, ok (n,) bool and r (n,) float. fused: whether\n"
"numpy's complex product rounds with a fused multiply-add here.");

static PyObject *beam_points(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    (void)self;
    if (nargs != 7) {
        PyErr_Format(PyExc_TypeError, "beam_points() takes 7 arguments (%zd given)", nargs);
        return NULL;
    }
    int fused = PyObject_IsTrue(args[6]);
    if (fused < 0)
        return NULL;
    Py_buffer v[6];
    int got = 0;
    if (PyObject_GetBuffer(args[0], &v[0], PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0)
        return NULL;
    Py_ssize_t n = v[0].itemsize ? v[0].len / v[0].itemsize : 0;
    PyBuffer_Release(&v[0]);
    static const char kinds[] = "dZ?Z?d";
    static const char *const names[] = {"ranges", "unit", "valid", "z", "ok", "r"};
    int has_valid = args[2] != Py_None;
    for (int i = 0; i < 6; i++) {
        if (i == 2 && !has_valid)
            continue;
        if (get_buf(args[i], &v[got], kinds[i], n, i >= 3, names[i]) < 0) {
            for (int k = 0; k < got; k++)
                PyBuffer_Release(&v[k]);
            return NULL;
        }
        got++;
    }
    int o = has_valid; /* the outputs' first view */
    points(v[0].buf, v[1].buf, has_valid ? v[2].buf : NULL, n, v[2 + o].buf, v[3 + o].buf,
           v[4 + o].buf, fused);
    for (int k = 0; k < got; k++)
        PyBuffer_Release(&v[k]);
    Py_RETURN_NONE;
}

static PyMethodDef methods[] = {
    {"beam_points", (PyCFunction)(void (*)(void))beam_points, METH_FASTCALL, beam_points_doc},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, "_points",
    "A scan's points, compiled (an optional build: atoms/estimators.py falls back to numpy).",
    0, methods, NULL, NULL, NULL, NULL,
};

PyMODINIT_FUNC PyInit__points(void)
{
    return PyModuleDef_Init(&module);
}
