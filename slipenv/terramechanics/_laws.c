/* slipenv.terramechanics._laws: the laws of _laws.h, callable from Python.
 *
 * Bindings only: each function unpacks its floats, calls the law in _laws.h and packs the
 * result. The Python API (slip_dynamics.py, bekker.py, models.py) wraps these with their
 * documented signatures; `Kernel` is a force model bound to one soil (what
 * `ForceModel.scalar_kernel` returns for slipenv's models).
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stddef.h>

#include "_laws.h"

static int floats(PyObject *const *args, Py_ssize_t nargs, Py_ssize_t n, const char *name,
                  double *out)
{
    if (nargs != n) {
        PyErr_Format(PyExc_TypeError, "%s() takes %zd arguments (%zd given)", name, n, nargs);
        return -1;
    }
    for (Py_ssize_t i = 0; i < n; i++) {
        PyObject *a = args[i];
        out[i] = PyFloat_CheckExact(a) ? PyFloat_AS_DOUBLE(a) : PyFloat_AsDouble(a);
        if (out[i] == -1.0 && PyErr_Occurred())
            return -1;
    }
    return 0;
}

static int vec_n(PyObject *obj, Py_ssize_t n, double *out)
{
    PyObject *seq = PySequence_Fast(obj, "expected a sequence of floats");
    if (seq == NULL)
        return -1;
    int rc = -1;
    if (PySequence_Fast_GET_SIZE(seq) != n) {
        PyErr_Format(PyExc_ValueError, "expected %zd floats", n);
        goto done;
    }
    for (Py_ssize_t i = 0; i < n; i++) {
        out[i] = PyFloat_AsDouble(PySequence_Fast_GET_ITEM(seq, i));
        if (out[i] == -1.0 && PyErr_Occurred())
            goto done;
    }
    rc = 0;
done:
    Py_DECREF(seq);
    return rc;
}

/* -- Kernel: a force model bound to one soil ---------------------------------------------- */

typedef struct {
    PyObject_HEAD
    LawsKernel k;
    PyObject *constants;
    vectorcallfunc vectorcall;
} KernelObject;

static PyObject *kernel_vectorcall(PyObject *self, PyObject *const *args, size_t nargsf,
                                   PyObject *kwnames)
{
    double a[3], fx, fy, res;
    if (kwnames != NULL && PyTuple_GET_SIZE(kwnames)) {
        PyErr_SetString(PyExc_TypeError, "kernel(slip, tan_beta, load_n) takes no keywords");
        return NULL;
    }
    if (floats(args, PyVectorcall_NARGS(nargsf), 3, "kernel", a) < 0)
        return NULL;
    laws_kernel(&((KernelObject *)self)->k, a[0], a[1], a[2], &fx, &fy, &res);
    return Py_BuildValue("(ddd)", fx, fy, res);
}

static PyObject *kernel_new(PyTypeObject *type, PyObject *args, PyObject *kwds)
{
    PyObject *constants;
    if (!PyArg_ParseTuple(args, "O!:Kernel", &PyTuple_Type, &constants))
        return NULL;
    KernelObject *self = (KernelObject *)type->tp_alloc(type, 0);
    if (self == NULL)
        return NULL;
    if (laws_parse_kernel(constants, &self->k) < 0) {
        Py_DECREF(self);
        return NULL;
    }
    Py_INCREF(constants);
    self->constants = constants;
    self->vectorcall = kernel_vectorcall;
    return (PyObject *)self;
}

static void kernel_dealloc(KernelObject *self)
{
    Py_XDECREF(self->constants);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static PyObject *kernel_get_constants(KernelObject *self, void *closure)
{
    Py_INCREF(self->constants);
    return self->constants;
}

static PyObject *kernel_repr(KernelObject *self)
{
    return PyUnicode_FromFormat("Kernel(%R)", self->constants);
}

static PyGetSetDef kernel_getset[] = {
    {"constants", (getter)kernel_get_constants, NULL, "the KernelConstants bound", NULL},
    {NULL, NULL, NULL, NULL, NULL},
};

static PyTypeObject KernelType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "slipenv.terramechanics._laws.Kernel",
    .tp_basicsize = sizeof(KernelObject),
    .tp_dealloc = (destructor)kernel_dealloc,
    .tp_vectorcall_offset = offsetof(KernelObject, vectorcall),
    .tp_call = PyVectorcall_Call,
    .tp_repr = (reprfunc)kernel_repr,
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_VECTORCALL,
    .tp_doc = "Kernel(kernel_constants): (slip, tan_beta, load_n) -> (fx_n, fy_n, "
              "resistance_n), the force model of one wheel on one soil (_laws.h, laws_kernel).",
    .tp_getset = kernel_getset,
    .tp_new = kernel_new,
};

/* -- module functions ----------------------------------------------------------------------- */

static PyObject *fn_kernel(PyObject *mod, PyObject *const *args, Py_ssize_t nargs)
{
    LawsKernel k;
    double a[3], fx, fy, res;
    if (nargs != 4) {
        PyErr_SetString(PyExc_TypeError, "kernel(constants, slip, tan_beta, load_n)");
        return NULL;
    }
    if (!PyTuple_Check(args[0])) {
        PyErr_SetString(PyExc_TypeError, "kernel constants must be a tuple");
        return NULL;
    }
    if (laws_parse_kernel(args[0], &k) < 0 || floats(args + 1, 3, 3, "kernel", a) < 0)
        return NULL;
    laws_kernel(&k, a[0], a[1], a[2], &fx, &fy, &res);
    return Py_BuildValue("(ddd)", fx, fy, res);
}

static PyObject *fn_relax_slip(PyObject *mod, PyObject *const *args, Py_ssize_t nargs)
{
    double a[6], s, t, v, v_b;
    if (nargs != 7) {
        PyErr_Format(PyExc_TypeError, "relax_slip() takes 7 arguments (%zd given)", nargs);
        return NULL;
    }
    int forward = PyObject_IsTrue(args[6]);
    if (forward < 0 || floats(args, 6, 6, "relax_slip", a) < 0)
        return NULL;
    laws_relax_slip(a[0], a[1], a[2], a[3], a[4], a[5], forward, &s, &t, &v, &v_b);
    return Py_BuildValue("(dddd)", s, t, v, v_b);
}

static PyObject *fn_lateral(PyObject *mod, PyObject *const *args, Py_ssize_t nargs)
{
    double a[4];
    if (floats(args, nargs, 4, "lateral_soil_damping_n", a) < 0)
        return NULL;
    return PyFloat_FromDouble(laws_lateral_damping(a[0], a[1], a[2], a[3]));
}

static PyObject *fn_longitudinal(PyObject *mod, PyObject *const *args, Py_ssize_t nargs)
{
    double a[5];
    if (floats(args, nargs, 5, "longitudinal_soil_damping_n", a) < 0)
        return NULL;
    return PyFloat_FromDouble(laws_longitudinal_damping(a[0], a[1], a[2], a[3], a[4]));
}

static PyObject *fn_critical(PyObject *mod, PyObject *const *args, Py_ssize_t nargs)
{
    double a[5];
    if (floats(args, nargs, 5, "critical_damping_ns_per_m", a) < 0)
        return NULL;
    return PyFloat_FromDouble(laws_critical_damping(a[0], a[1], a[2], a[3], a[4]));
}

static PyObject *fn_rut(PyObject *mod, PyObject *const *args, Py_ssize_t nargs)
{
    double a[6], r, u;
    if (floats(args, nargs, 6, "rut_resistance_n", a) < 0)
        return NULL;
    laws_rut_resistance(a[0], a[1], a[2], a[3], a[4], a[5], &r, &u);
    return Py_BuildValue("(dd)", r, u);
}

static PyObject *fn_rut_vector(PyObject *mod, PyObject *args)
{
    double res, st[3], v[3], dt, stick, damping, r[3], u[3];
    PyObject *state, *vel;
    if (!PyArg_ParseTuple(args, "dOOddd:rut_resistance_vector_n", &res, &state, &vel, &dt,
                          &stick, &damping)
        || vec_n(state, 3, st) < 0 || vec_n(vel, 3, v) < 0)
        return NULL;
    laws_rut_resistance_vector(res, st, v, dt, stick, damping, r, u);
    return Py_BuildValue("((ddd)(ddd))", r[0], r[1], r[2], u[0], u[1], u[2]);
}

static PyObject *fn_sinkage(PyObject *mod, PyObject *const *args, Py_ssize_t nargs)
{
    double a[6];
    if (floats(args, nargs, 6, "wheel_sinkage_m", a) < 0)
        return NULL;
    return PyFloat_FromDouble(laws_wheel_sinkage(a[0], a[1], a[2], a[3], a[4], a[5]));
}

static PyObject *fn_rut_following(PyObject *mod, PyObject *const *args, Py_ssize_t nargs)
{
    double a[2];
    if (floats(args, nargs, 2, "rut_following_compaction_n", a) < 0)
        return NULL;
    return PyFloat_FromDouble(laws_rut_following(a[0], a[1]));
}

static PyObject *fn_rut_ratio(PyObject *mod, PyObject *const *args, Py_ssize_t nargs)
{
    double a[6];
    if (floats(args, nargs, 6, "rut_load_ratio", a) < 0)
        return NULL;
    return PyFloat_FromDouble(laws_rut_load_ratio(a[0], a[1], a[2], a[3], a[4], a[5]));
}

static PyObject *fn_multi_pass(PyObject *mod, PyObject *const *args, Py_ssize_t nargs)
{
    double a[5];
    if (floats(args, nargs, 5, "multi_pass_resistance_n", a) < 0)
        return NULL;
    return PyFloat_FromDouble(laws_multi_pass(a[0], a[1], a[2], a[3], a[4]));
}

static PyObject *fn_resistance(PyObject *mod, PyObject *const *args, Py_ssize_t nargs)
{
    double a[4];
    if (floats(args, nargs, 4, "motion_resistance_n", a) < 0)
        return NULL;
    return PyFloat_FromDouble(laws_motion_resistance(a[0], a[1], a[2], a[3]));
}

static PyObject *fn_slip_sinkage_factor(PyObject *mod, PyObject *const *args,
                                        Py_ssize_t nargs)
{
    double s;
    if (floats(args, nargs, 1, "slip_sinkage_factor", &s) < 0)
        return NULL;
    return PyFloat_FromDouble(laws_slip_sinkage_factor(s));
}

static PyObject *fn_bulldozing_coefficients(PyObject *mod, PyObject *const *args,
                                            Py_ssize_t nargs)
{
    double phi, d1, d2;
    if (floats(args, nargs, 1, "bulldozing_coefficients", &phi) < 0)
        return NULL;
    laws_bulldozing_coefficients(phi, &d1, &d2);
    return Py_BuildValue("(dd)", d1, d2);
}

static PyObject *fn_bulldozing(PyObject *mod, PyObject *const *args, Py_ssize_t nargs)
{
    double a[4];
    if (floats(args, nargs, 4, "bulldozing_resistance_n_per_m", a) < 0)
        return NULL;
    return PyFloat_FromDouble(laws_bulldozing_per_width(a[0], a[1], a[2], a[3]));
}

static PyObject *fn_slip_sinkage_resistance(PyObject *mod, PyObject *const *args,
                                            Py_ssize_t nargs)
{
    double a[8];
    if (floats(args, nargs, 8, "slip_sinkage_resistance_n", a) < 0)
        return NULL;
    return PyFloat_FromDouble(
        laws_slip_sinkage_resistance(a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7]));
}

static PyObject *fn_dug_resistance(PyObject *mod, PyObject *const *args, Py_ssize_t nargs)
{
    double a[8];
    if (floats(args, nargs, 8, "dug_resistance_n", a) < 0)
        return NULL;
    return PyFloat_FromDouble(
        laws_dug_resistance(a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7]));
}

static PyObject *fn_slip_sinkage_step(PyObject *mod, PyObject *const *args, Py_ssize_t nargs)
{
    double a[6];
    if (floats(args, nargs, 6, "slip_sinkage_step", a) < 0)
        return NULL;
    return PyFloat_FromDouble(laws_slip_sinkage_step(a[0], a[1], a[2], a[3], a[4], a[5]));
}

static PyObject *fn_kernel_sinkage_state(PyObject *mod, PyObject *const *args,
                                         Py_ssize_t nargs)
{
    LawsKernel k;
    double a[5];
    if (nargs != 6) {
        PyErr_Format(PyExc_TypeError, "kernel_sinkage_state() takes 6 arguments (%zd given)",
                     nargs);
        return NULL;
    }
    if (laws_parse_kernel(args[0], &k) < 0
        || floats(args + 1, 5, 5, "kernel_sinkage_state", a) < 0)
        return NULL;
    double dug = a[0];
    double res = laws_kernel_sinkage_state(&k, &dug, a[1], a[2], a[3], a[4]);
    return Py_BuildValue("(dd)", dug, res);
}

static PyObject *fn_okello_h(PyObject *mod, PyObject *const *args, Py_ssize_t nargs)
{
    double x;
    if (floats(args, nargs, 1, "okello_h", &x) < 0)
        return NULL;
    return PyFloat_FromDouble(laws_okello_h(x));
}

static PyObject *fn_exp_secant(PyObject *mod, PyObject *const *args, Py_ssize_t nargs)
{
    double y;
    if (floats(args, nargs, 1, "exp_secant", &y) < 0)
        return NULL;
    return PyFloat_FromDouble(laws_exp_secant(y));
}

static PyObject *fn_janosi(PyObject *mod, PyObject *const *args, Py_ssize_t nargs)
{
    double a[7], fx, fy;
    if (floats(args, nargs, 7, "janosi_forces", a) < 0)
        return NULL;
    laws_janosi(a[0], a[1], a[2], a[3], a[4], a[5], a[6], &fx, &fy);
    return Py_BuildValue("(dd)", fx, fy);
}

static PyObject *fn_linear(PyObject *mod, PyObject *const *args, Py_ssize_t nargs)
{
    double a[7], fx, fy;
    if (floats(args, nargs, 7, "linear_slip_forces", a) < 0)
        return NULL;
    laws_linear(a[0], a[1], a[2], a[3], a[4], a[5], a[6], &fx, &fy);
    return Py_BuildValue("(dd)", fx, fy);
}

static PyObject *fn_reina(PyObject *mod, PyObject *const *args, Py_ssize_t nargs)
{
    double a[8], fx, fy;
    if (floats(args, nargs, 8, "reina_forces", a) < 0)
        return NULL;
    laws_reina(a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], &fx, &fy);
    return Py_BuildValue("(dd)", fx, fy);
}

static PyObject *fn_reina_gross(PyObject *mod, PyObject *const *args, Py_ssize_t nargs)
{
    double a[8];
    if (floats(args, nargs, 8, "reina_gross_extra_n", a) < 0)
        return NULL;
    return PyFloat_FromDouble(laws_reina_gross_extra(a[0], a[1], a[2], a[3], a[4], a[5], a[6],
                                                     a[7]));
}

static PyObject *fn_frame(PyObject *mod, PyObject *args)
{
    PyObject *po, *qo, *co, *vo, *wo;
    double patch[6], load, q[4], centre[3], v[3], omega[3];
    LawsFrame f;
    if (!PyArg_ParseTuple(args, "OdOOOO:contact_frame", &po, &load, &qo, &co, &vo, &wo)
        || vec_n(po, 6, patch) < 0 || vec_n(qo, 4, q) < 0 || vec_n(co, 3, centre) < 0
        || vec_n(vo, 3, v) < 0 || vec_n(wo, 3, omega) < 0)
        return NULL;
    if (laws_contact_frame(patch, load, q, centre, v, omega, &f) < 0) {
        PyErr_SetString(PyExc_ValueError, "degenerate contact frame");
        return NULL;
    }
    return Py_BuildValue("((ddd)(ddd)(ddd)ddd)", f.c[0], f.c[1], f.c[2], f.e[0], f.e[1],
                         f.e[2], f.l[0], f.l[1], f.l[2], f.v_long, f.v_side, f.v_lat);
}

#define FAST(name, fn, doc) {name, (PyCFunction)(void (*)(void))fn, METH_FASTCALL, doc}

static PyMethodDef module_methods[] = {
    FAST("kernel", fn_kernel,
         "kernel(constants, slip, tan_beta, load_n) -> (fx_n, fy_n, resistance_n)"),
    FAST("relax_slip", fn_relax_slip,
         "relax_slip(slip, tan_beta, rim, v_long, v_lat, h, forward) -> (slip, tan_beta, v_ref, "
         "v_lat_ref)"),
    FAST("lateral_soil_damping_n", fn_lateral,
         "lateral_soil_damping_n(change, v_ref, d, fade_speed)"),
    FAST("longitudinal_soil_damping_n", fn_longitudinal,
         "longitudinal_soil_damping_n(rim, v_long, v_ref, c, low_speed)"),
    FAST("critical_damping_ns_per_m", fn_critical,
         "critical_damping_ns_per_m(stiffness, length, mass, zeta, c_max)"),
    FAST("rut_resistance_n", fn_rut,
         "rut_resistance_n(R, state, dx, v, stick, c) -> (r, state)"),
    {"rut_resistance_vector_n", (PyCFunction)fn_rut_vector, METH_VARARGS,
     "rut_resistance_vector_n(R, state3, v3, dt, stick, c) -> (r3, state3)"},
    FAST("wheel_sinkage_m", fn_sinkage, "wheel_sinkage_m(load, width, diameter, k_c, k_phi, n)"),
    FAST("rut_following_compaction_n", fn_rut_following,
         "rut_following_compaction_n(compaction, rut_compaction)"),
    FAST("rut_load_ratio", fn_rut_ratio,
         "rut_load_ratio(width, diameter, lead_width, lead_diameter, k_c, k_phi)"),
    FAST("multi_pass_resistance_n", fn_multi_pass,
         "multi_pass_resistance_n(res, load, lead_res, lead_load, f_r)"),
    FAST("motion_resistance_n", fn_resistance, "motion_resistance_n(load, f_r, gamma, e)"),
    FAST("slip_sinkage_factor", fn_slip_sinkage_factor, "slip_sinkage_factor(slip)"),
    FAST("bulldozing_coefficients", fn_bulldozing_coefficients,
         "bulldozing_coefficients(phi) -> (d1, d2)"),
    FAST("bulldozing_resistance_n_per_m", fn_bulldozing,
         "bulldozing_resistance_n_per_m(depth, cohesion, phi, unit_weight)"),
    FAST("slip_sinkage_resistance_n", fn_slip_sinkage_resistance,
         "slip_sinkage_resistance_n(slip, compaction, n, sinkage, width, cohesion, phi, "
         "unit_weight)"),
    FAST("dug_resistance_n", fn_dug_resistance,
         "dug_resistance_n(dug, compaction, n, sinkage, width, cohesion, phi, unit_weight)"),
    FAST("slip_sinkage_step", fn_slip_sinkage_step,
         "slip_sinkage_step(dug, rim, v_long, h, delta, cap) -> dug"),
    FAST("kernel_sinkage_state", fn_kernel_sinkage_state,
         "kernel_sinkage_state(constants, dug, rim, v_long, h, load_n) -> (dug, resistance_n)"),
    FAST("okello_h", fn_okello_h, "okello_h(x)"),
    FAST("exp_secant", fn_exp_secant, "exp_secant(y)"),
    FAST("janosi_forces", fn_janosi,
         "janosi_forces(slip, tan_beta, load, ac, tan_phi, ratio, kappa) -> (fx, fy)"),
    FAST("linear_slip_forces", fn_linear,
         "linear_slip_forces(slip, tan_beta, load, ac, tan_phi, ratio, kappa) -> (fx, fy)"),
    FAST("reina_forces", fn_reina,
         "reina_forces(slip, tan_beta, load, mu, c_x, c_y, a_x, a_y) -> (fx, fy)"),
    FAST("reina_gross_extra_n", fn_reina_gross,
         "reina_gross_extra_n(slip, tan_beta, load, gamma, e, c_x, mu, w_y)"),
    {"contact_frame", (PyCFunction)fn_frame, METH_VARARGS,
     "contact_frame(patch6, load, q4, centre3, v3, omega3) -> (c, e, l, v_long, v_side, "
     "v_lat)"},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module_def = {
    PyModuleDef_HEAD_INIT, "_laws",
    "The wheel-soil laws of slipenv (_laws.h), callable from Python.", -1, module_methods,
};

PyMODINIT_FUNC PyInit__laws(void)
{
    if (PyType_Ready(&KernelType) < 0)
        return NULL;
    PyObject *m = PyModule_Create(&module_def);
    if (m == NULL)
        return NULL;
    Py_INCREF(&KernelType);
    if (PyModule_AddObject(m, "Kernel", (PyObject *)&KernelType) < 0) {
        Py_DECREF(&KernelType);
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
