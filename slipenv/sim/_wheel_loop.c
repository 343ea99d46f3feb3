/* The per-substep wheel-soil force loop of slipenv.sim.wheel_soil, compiled (issue 15 item 1).
 *
 * This file is a transcription, not a second source of the physics. Each function below
 * mirrors one plain Python function, operation for operation, so that the results are the
 * same bit for bit (tests/sim/test_wheel_loop_compiled.py checks every one of them against its
 * Python original under fuzzing, and every registered env against the Python loop):
 *
 *   relax_slip, lateral_soil_damping_n, longitudinal_soil_damping_n, rut_resistance_n,
 *   rut_resistance_vector_n       slipenv/terramechanics/slip_dynamics.py
 *   janosi (_okello_h)            slipenv/terramechanics/janosi.py   (janosi_forces)
 *   linear                        slipenv/terramechanics/lindgren.py (linear_slip_forces)
 *   reina (_exp_secant)           slipenv/terramechanics/reina.py    (reina_forces)
 *   kernel                        slipenv/terramechanics/models.py   (_PatchModel.scalar_kernel,
 *                                 ReinaForceModel.scalar_kernel's gross thrust)
 *   rut_following                 slipenv/terramechanics/bekker.py   (rut_following_compaction_n)
 *   WheelLoop.apply               WheelSoilInjector._python_apply and _patches
 *
 * Rounding is Python's: IEEE doubles, no fused multiply-add (setup.py: -ffp-contract=off),
 * libm's sqrt/expm1/pow as Python's math module and float ** use, and Python's own math.hypot
 * (CPython computes it with its own algorithm, not libm's hypot), called through the module.
 * Where Python would raise (a division by zero, pow overflowing), this raises the same
 * exception type.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <string.h>
#include <time.h>

#include "bullet_native.h"

static PyObject *g_hypot = NULL; /* math.hypot */

/* -- float helpers with Python's error behaviour ---------------------------------------- */

static int py_hypot(double a, double b, double *out)
{
    PyObject *args[2];
    args[0] = PyFloat_FromDouble(a);
    args[1] = PyFloat_FromDouble(b);
    PyObject *r = NULL;
    if (args[0] && args[1])
        r = PyObject_Vectorcall(g_hypot, args, 2, NULL);
    Py_XDECREF(args[0]);
    Py_XDECREF(args[1]);
    if (r == NULL)
        return -1;
    *out = PyFloat_AS_DOUBLE(r);
    Py_DECREF(r);
    return 0;
}

static int py_div(double a, double b, double *out)
{
    if (b == 0.0) {
        PyErr_SetString(PyExc_ZeroDivisionError, "float division by zero");
        return -1;
    }
    *out = a / b;
    return 0;
}

/* x ** y for x > 0 (loads), as float_pow: pow(), OverflowError on overflow. */
static int py_pow(double x, double y, double *out)
{
    if (y == 0.0) {
        *out = 1.0;
        return 0;
    }
    double r = pow(x, y);
    if (isinf(r) && isfinite(x) && isfinite(y)) {
        PyErr_SetString(PyExc_OverflowError, "(34, 'Numerical result out of range')");
        return -1;
    }
    *out = r;
    return 0;
}

static inline double clip1(double v) { return v > 1.0 ? 1.0 : (v < -1.0 ? -1.0 : v); }

/* -- slip_dynamics ----------------------------------------------------------------------- */

static void relax_slip(double slip, double tan_beta, double rim, double vlong, double vlat,
                       double h, double *s_out, double *t_out, double *vref_out)
{
    double v_ref = fabs(rim); /* max(|a|, |b|, |c|): the first of the largest, as builtins.max */
    double a = fabs(vlong), c = fabs(vlat);
    if (a > v_ref) v_ref = a;
    if (c > v_ref) v_ref = c;
    double leak = 1.0 + h * v_ref;
    double s = (slip + h * (rim - vlong)) / leak;
    double t = (tan_beta + h * vlat) / leak;
    *s_out = clip1(s);
    *t_out = clip1(t);
    *vref_out = v_ref;
}

static double lateral_damping(double change, double v_ref, double d, double fade_speed)
{
    double fade = v_ref / fade_speed;
    fade *= fade;
    return -d * change / (1.0 + fade * fade);
}

static double longitudinal_damping(double rim, double vlong, double v_ref, double c,
                                   double low_speed)
{
    double speed = v_ref / low_speed;
    if (speed < 1.0)
        return (1.0 - speed) * c * (rim - vlong);
    return 0.0;
}

static void rut_resistance(double res, double state, double disp, double speed, double stick,
                           double damping, double *r_out, double *u_out)
{
    double u = clip1(state + disp / stick);
    double r = res * u + damping * speed;
    r = r > res ? res : (r < -res ? -res : r);
    *r_out = r;
    *u_out = u;
}

static void rut_resistance_vector(double res, const double state[3], const double v[3],
                                  double dt, double stick, double damping, double r_out[3],
                                  double u_out[3])
{
    double h = dt / stick;
    double ux = state[0] + h * v[0], uy = state[1] + h * v[1], uz = state[2] + h * v[2];
    double norm = sqrt(ux * ux + uy * uy + uz * uz);
    if (norm > 1.0) {
        ux = ux / norm;
        uy = uy / norm;
        uz = uz / norm;
    }
    double rx = res * ux + damping * v[0];
    double ry = res * uy + damping * v[1];
    double rz = res * uz + damping * v[2];
    norm = sqrt(rx * rx + ry * ry + rz * rz);
    if (norm > res) {
        double scale = res / norm;
        rx = rx * scale;
        ry = ry * scale;
        rz = rz * scale;
    }
    r_out[0] = rx; r_out[1] = ry; r_out[2] = rz;
    u_out[0] = ux; u_out[1] = uy; u_out[2] = uz;
}

/* -- force laws -------------------------------------------------------------------------- */

enum { KIND_JANOSI = 0, KIND_LINEAR = 1, KIND_REINA = 2 };

/* A force model bound to one soil: what `ForceModel.kernel_constants(soil)` returns
 * (slipenv.terramechanics.models.KernelConstants, a NamedTuple with these fields in order). */
typedef struct {
    int kind;
    /* janosi, linear: cohesion force A c [N], tan phi, shear ratio L/K, kappa */
    double ac, tan_phi, ratio, kappa;
    /* reina: mu, C_x, C_y (divided by W_ref if scaled), A_x, A_y; scaled: 1 = load-scaled */
    double mu, c_x, c_y, a_x, a_y;
    int scaled;
    /* reina gross thrust (compaction=True): raw C_x, and W_ref (used when scaled) */
    int gross;
    double gross_c_x, gross_w_ref;
    /* resistance: f_r W + gamma W^e */
    double f_r, gamma, exponent;
} Kernel;

#define X_SMALL 1e-5
#define SIXTH (1.0 / 6.0)
#define TINY 1e-300

static double okello_h(double x)
{
    double xc = x > X_SMALL ? x : X_SMALL;
    return (expm1(-xc) + xc) / (xc * xc) + (xc - x) * SIXTH;
}

static double exp_secant(double y) { return y > TINY ? -expm1(-y) / y : 1.0; }

static int reina_forces(double slip, double tb, double load, double mu, double c_x, double c_y,
                        double a_x, double a_y, double *fx, double *fy)
{
    if (load <= 0.0) {
        *fx = 0.0;
        *fy = 0.0;
        return 0;
    }
    double hyp, sig;
    if (py_hypot(slip, tb, &hyp) < 0 || py_div(hyp, mu * load, &sig) < 0)
        return -1;
    double k_x = c_x * exp_secant(c_x * sig) - load * a_x;
    double k_y = c_y * exp_secant(c_y * sig) - load * a_y;
    *fx = k_x > 0.0 ? slip * k_x : 0.0;
    *fy = k_y > 0.0 ? -tb * k_y : 0.0;
    return 0;
}

/* (fx, fy, resistance) of one wheel: the model's scalar kernel. */
static int kernel_eval(const Kernel *k, double slip, double tb, double load, double *fx_out,
                       double *fy_out, double *res_out)
{
    double fx, fy;
    if (k->kind == KIND_JANOSI) {
        if (load <= 0.0) {
            fx = 0.0;
            fy = 0.0;
        } else {
            double f_max = load * k->tan_phi + k->ac;
            double lateral = tb * k->kappa;
            double hyp;
            if (py_hypot(slip, lateral, &hyp) < 0)
                return -1;
            double secant = f_max * okello_h(hyp * k->ratio) * k->ratio;
            fx = secant * slip;
            fy = -secant * lateral;
        }
    } else if (k->kind == KIND_LINEAR) {
        double t = k->kappa * tb;
        if (load <= 0.0) {
            fx = 0.0;
            fy = 0.0;
        } else {
            double half = 0.5 * k->ratio;
            double hyp;
            if (py_hypot(slip, t, &hyp) < 0)
                return -1;
            double excess = hyp * half;
            double secant = (load * k->tan_phi + k->ac) * half / (excess > 1.0 ? excess : 1.0);
            fx = secant * slip;
            fy = -secant * t;
        }
    } else {
        if (k->scaled) {
            if (reina_forces(slip, tb, 1.0, k->mu, k->c_x, k->c_y, k->a_x, k->a_y, &fx, &fy) < 0)
                return -1;
            fx = fx * load;
            fy = fy * load;
        } else if (reina_forces(slip, tb, load, k->mu, k->c_x, k->c_y, k->a_x, k->a_y, &fx,
                                &fy) < 0) {
            return -1;
        }
    }
    double res = k->f_r * load;
    if (k->gamma != 0.0) {
        double w_e;
        if (py_pow(load, k->exponent, &w_e) < 0)
            return -1;
        res += k->gamma * w_e;
    }
    if (k->gross) {
        double sigma;
        if (py_hypot(slip, tb, &sigma) < 0)
            return -1;
        if (sigma > 0.0 && k->gamma != 0.0) {
            double y, w_e;
            if (py_div(k->gross_c_x * sigma,
                       k->mu * (k->scaled ? k->gross_w_ref : load), &y) < 0
                || py_pow(load, k->exponent, &w_e) < 0)
                return -1;
            fx += k->gamma * w_e * -expm1(-y) * slip / sigma;
        }
    }
    *fx_out = fx;
    *fy_out = fy;
    *res_out = res;
    return 0;
}

static double rut_following(double compaction, double rut_compaction)
{
    double extra = compaction - rut_compaction;
    return extra > 0.0 ? extra : 0.0;
}

static int parse_kernel(PyObject *spec, Kernel *k)
{
    /* (kind, ac, tan_phi, ratio, kappa, mu, c_x, c_y, a_x, a_y, scaled, gross, gross_c_x,
        gross_w_ref, f_r, gamma, exponent): ForceModel.kernel_constants */
    memset(k, 0, sizeof(*k));
    if (!PyArg_ParseTuple(spec, "idddddddddppddddd;kernel constants", &k->kind, &k->ac,
                          &k->tan_phi, &k->ratio, &k->kappa, &k->mu, &k->c_x, &k->c_y, &k->a_x,
                          &k->a_y, &k->scaled, &k->gross, &k->gross_c_x, &k->gross_w_ref,
                          &k->f_r, &k->gamma, &k->exponent))
        return -1;
    if (k->kind < KIND_JANOSI || k->kind > KIND_REINA) {
        PyErr_Format(PyExc_ValueError, "unknown kernel kind %d", k->kind);
        return -1;
    }
    return 0;
}

/* -- the loop ---------------------------------------------------------------------------- */

typedef struct {
    int link, driven, spin_index;
    int lead_front, lead_back;
    double rut_ratio_front, rut_ratio_back; /* bekker.rut_load_ratio of each leader's rut */
    double r_eff, h, c_long, d_lat, rut_damping;
    Kernel kernel;
    /* state */
    double s, b, rut, rut_vec[3];
    /* last substep */
    double load, fx, fy, res, damper, force[3];
} Wheel;

/* What one substep reads from PyBullet, in the form the loop uses. */
typedef struct {
    double *load;  /* n: normal load [N], the sum of the wheel's contact forces */
    double *patch; /* n x 6: load-weighted sums of contact points and normals */
    int *has_patch;
    double *link;  /* n x 13: COM orientation (4), position (3), velocity (3), angular (3) */
    double *rate;  /* n_spin: spin joint velocities */
    int chassis;   /* a body other than a wheel touched the ground */
} Inputs;

#define LINK_WIDTH 13

typedef struct {
    PyObject_HEAD
    int n, n_spin;
    long body, ground, client, world;
    double dt, stick, fade_speed, low_speed;
    int multi_pass, chassis_contact;
    PyObject *contacts_fn, *links_fn, *joints_fn, *apply_fn, *error_type;
    PyObject *contacts_args, *links_args, *joints_args; /* argument tuples */
    PyObject *body_obj, *client_obj, *world_obj;
    int max_link;
    int *link_to_wheel; /* link index -> wheel, -1 */
    int *spin_joints;   /* n_spin joint indices */
    Wheel *w;
    Inputs in, check;   /* this substep's readings; `check` verifies the native ones */
    int n_forces;
    int *force_link;    /* 2n */
    double *force_vec;  /* 2n x 6: force, point of application (world frame) */
    /* native queries through Bullet's C API (bullet_native.h) */
    BulletApi api;
    int bound, native, verify, mismatch, contact_status, state_status;
    /* optional timing of the substep's parts (slipenv bench): seconds, substeps */
    int timing;
    double t_read, t_law, t_apply;
    long timed_substeps;
} WheelLoop;

static double now_s(void)
{
#ifndef _WIN32
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
#else
    return 0.0; /* no part timing on Windows: the parts read as zero */
#endif
}

static int inputs_alloc(Inputs *in, int n, int n_spin)
{
    int m = n > 0 ? n : 1;
    in->load = PyMem_Calloc(m, sizeof(double));
    in->patch = PyMem_Calloc(6 * m, sizeof(double));
    in->has_patch = PyMem_Calloc(m, sizeof(int));
    in->link = PyMem_Calloc(LINK_WIDTH * m, sizeof(double));
    in->rate = PyMem_Calloc(n_spin > 0 ? n_spin : 1, sizeof(double));
    in->chassis = 0;
    if (!in->load || !in->patch || !in->has_patch || !in->link || !in->rate) {
        PyErr_NoMemory();
        return -1;
    }
    return 0;
}

static void inputs_free(Inputs *in)
{
    PyMem_Free(in->load);
    PyMem_Free(in->patch);
    PyMem_Free(in->has_patch);
    PyMem_Free(in->link);
    PyMem_Free(in->rate);
}

/* Bit-for-bit equality of two readings (memcmp: a -0.0 or a NaN pattern counts). */
static int inputs_equal(const Inputs *a, const Inputs *b, int n, int n_spin)
{
    return a->chassis == b->chassis
           && memcmp(a->load, b->load, n * sizeof(double)) == 0
           && memcmp(a->has_patch, b->has_patch, n * sizeof(int)) == 0
           && memcmp(a->patch, b->patch, 6 * n * sizeof(double)) == 0
           && memcmp(a->link, b->link, LINK_WIDTH * n * sizeof(double)) == 0
           && memcmp(a->rate, b->rate, n_spin * sizeof(double)) == 0;
}

static void loop_dealloc(WheelLoop *self)
{
    Py_XDECREF(self->contacts_fn);
    Py_XDECREF(self->links_fn);
    Py_XDECREF(self->joints_fn);
    Py_XDECREF(self->apply_fn);
    Py_XDECREF(self->error_type);
    Py_XDECREF(self->contacts_args);
    Py_XDECREF(self->links_args);
    Py_XDECREF(self->joints_args);
    Py_XDECREF(self->body_obj);
    Py_XDECREF(self->client_obj);
    Py_XDECREF(self->world_obj);
    PyMem_Free(self->link_to_wheel);
    PyMem_Free(self->spin_joints);
    PyMem_Free(self->w);
    inputs_free(&self->in);
    inputs_free(&self->check);
    PyMem_Free(self->force_link);
    PyMem_Free(self->force_vec);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

/* WheelLoop(pybullet, body, ground, client, links, spin_joints, dt, stick, fade_speed,
 *           low_speed, multi_pass) */
static int loop_init(WheelLoop *self, PyObject *args, PyObject *kwds)
{
    PyObject *pb, *links, *spin_joints;
    int multi_pass;
    if (!PyArg_ParseTuple(args, "OlllOOddddp", &pb, &self->body, &self->ground, &self->client,
                          &links, &spin_joints, &self->dt, &self->stick, &self->fade_speed,
                          &self->low_speed, &multi_pass))
        return -1;
    self->multi_pass = multi_pass;
    if (!PyList_Check(links) || !PyList_Check(spin_joints)) {
        PyErr_SetString(PyExc_TypeError, "links and spin_joints must be lists");
        return -1;
    }
    self->n = (int)PyList_GET_SIZE(links);
    self->contacts_fn = PyObject_GetAttrString(pb, "getContactPoints");
    self->links_fn = PyObject_GetAttrString(pb, "getLinkStates");
    self->joints_fn = PyObject_GetAttrString(pb, "getJointStates");
    self->apply_fn = PyObject_GetAttrString(pb, "applyExternalForce");
    self->error_type = PyObject_GetAttrString(pb, "error");
    PyObject *world = PyObject_GetAttrString(pb, "WORLD_FRAME");
    if (!self->contacts_fn || !self->links_fn || !self->joints_fn || !self->apply_fn
        || !self->error_type || !world)
        return -1;
    self->world = PyLong_AsLong(world);
    self->world_obj = world;
    self->body_obj = PyLong_FromLong(self->body);
    self->client_obj = PyLong_FromLong(self->client);
    /* getContactPoints(body, ground, -2, -2, client); getLinkStates(body, links, 1, 0,
       client); getJointStates(body, spin_joints, client): positional, as the Python loop. */
    self->contacts_args = Py_BuildValue("(lliil)", self->body, self->ground, -2, -2,
                                        self->client);
    self->links_args = Py_BuildValue("(lOiil)", self->body, links, 1, 0, self->client);
    self->joints_args = Py_BuildValue("(lOl)", self->body, spin_joints, self->client);
    if (!self->body_obj || !self->client_obj || !self->contacts_args || !self->links_args
        || !self->joints_args)
        return -1;
    self->n_spin = (int)PyList_GET_SIZE(spin_joints);
    self->w = PyMem_Calloc(self->n > 0 ? self->n : 1, sizeof(Wheel));
    self->spin_joints = PyMem_Calloc(self->n_spin > 0 ? self->n_spin : 1, sizeof(int));
    self->force_link = PyMem_Calloc(2 * (self->n > 0 ? self->n : 1), sizeof(int));
    self->force_vec = PyMem_Calloc(12 * (self->n > 0 ? self->n : 1), sizeof(double));
    if (!self->w || !self->spin_joints || !self->force_link || !self->force_vec) {
        PyErr_NoMemory();
        return -1;
    }
    if (inputs_alloc(&self->in, self->n, self->n_spin) < 0
        || inputs_alloc(&self->check, self->n, self->n_spin) < 0)
        return -1;
    for (int j = 0; j < self->n_spin; j++) {
        long joint = PyLong_AsLong(PyList_GET_ITEM(spin_joints, j));
        if (joint == -1 && PyErr_Occurred())
            return -1;
        if (joint < 0 || joint > 100000) {
            PyErr_Format(PyExc_ValueError, "spin joint index %ld out of range", joint);
            return -1;
        }
        self->spin_joints[j] = (int)joint;
    }
    self->max_link = -1;
    for (int k = 0; k < self->n; k++) {
        long link = PyLong_AsLong(PyList_GET_ITEM(links, k));
        if (link == -1 && PyErr_Occurred())
            return -1;
        if (link < -1 || link > 100000) {
            PyErr_Format(PyExc_ValueError, "wheel link index %ld out of range", link);
            return -1;
        }
        self->w[k].link = (int)link;
        self->w[k].lead_front = self->w[k].lead_back = -1;
        self->w[k].spin_index = -1;
        if (link > self->max_link)
            self->max_link = (int)link;
    }
    self->link_to_wheel = PyMem_Malloc(sizeof(int) * (self->max_link + 2));
    if (!self->link_to_wheel) {
        PyErr_NoMemory();
        return -1;
    }
    /* index 0 holds link -1 (the base), index i + 1 link i */
    for (int i = 0; i < self->max_link + 2; i++)
        self->link_to_wheel[i] = -1;
    for (int k = 0; k < self->n; k++)
        self->link_to_wheel[self->w[k].link + 1] = k;
    return 0;
}

static int check_wheel(WheelLoop *self, int k)
{
    if (k < 0 || k >= self->n) {
        PyErr_Format(PyExc_IndexError, "wheel %d out of range (n = %d)", k, self->n);
        return -1;
    }
    return 0;
}

/* set_wheel(k, driven, spin_index, r_eff, h, c_long, d_lat, rut_damping, lead_front,
             lead_back, rut_ratio_front, rut_ratio_back, kernel_constants) */
static PyObject *loop_set_wheel(WheelLoop *self, PyObject *args)
{
    int k, driven, spin_index, lead_front, lead_back;
    double r_eff, h, c_long, d_lat, rut_damping, ratio_front, ratio_back;
    PyObject *spec;
    if (!PyArg_ParseTuple(args, "ipidddddiiddO!", &k, &driven, &spin_index, &r_eff, &h,
                          &c_long, &d_lat, &rut_damping, &lead_front, &lead_back, &ratio_front,
                          &ratio_back, &PyTuple_Type, &spec))
        return NULL;
    if ((lead_front >= self->n) || (lead_back >= self->n)) {
        PyErr_Format(PyExc_IndexError, "leader out of range (n = %d)", self->n);
        return NULL;
    }
    if (check_wheel(self, k) < 0)
        return NULL;
    Kernel kern;
    if (parse_kernel(spec, &kern) < 0)
        return NULL;
    Wheel *w = &self->w[k];
    w->driven = driven;
    w->spin_index = spin_index;
    w->r_eff = r_eff;
    w->h = h;
    w->c_long = c_long;
    w->d_lat = d_lat;
    w->rut_damping = rut_damping;
    w->lead_front = lead_front;
    w->lead_back = lead_back;
    w->rut_ratio_front = ratio_front;
    w->rut_ratio_back = ratio_back;
    w->kernel = kern;
    Py_RETURN_NONE;
}

static PyObject *loop_reset(WheelLoop *self, PyObject *unused)
{
    for (int k = 0; k < self->n; k++) {
        Wheel *w = &self->w[k];
        w->s = w->b = w->rut = 0.0;
        w->rut_vec[0] = w->rut_vec[1] = w->rut_vec[2] = 0.0;
        w->load = w->fx = w->fy = w->res = w->damper = 0.0;
        w->force[0] = w->force[1] = w->force[2] = 0.0;
    }
    self->chassis_contact = 0;
    Py_RETURN_NONE;
}

static inline int get_double(PyObject *seq, Py_ssize_t i, double *out)
{
    PyObject *item = PyTuple_Check(seq) ? PyTuple_GET_ITEM(seq, i) : PySequence_GetItem(seq, i);
    if (item == NULL)
        return -1;
    double v = PyFloat_Check(item) ? PyFloat_AS_DOUBLE(item) : PyFloat_AsDouble(item);
    if (!PyTuple_Check(seq))
        Py_DECREF(item);
    if (v == -1.0 && PyErr_Occurred())
        return -1;
    *out = v;
    return 0;
}

static int get_vec(PyObject *seq, Py_ssize_t n, double *out)
{
    if (!PyTuple_Check(seq) || PyTuple_GET_SIZE(seq) < n) {
        PyErr_SetString(PyExc_TypeError, "expected a tuple of floats from PyBullet");
        return -1;
    }
    for (Py_ssize_t i = 0; i < n; i++)
        if (get_double(seq, i, &out[i]) < 0)
            return -1;
    return 0;
}

/* Queue a force [N] at a point (world frame) on `link`; `submit_forces` applies the queue. */
static void queue_force(WheelLoop *self, int link, double fx, double fy, double fz, double px,
                        double py, double pz)
{
    int i = self->n_forces++;
    double *f = &self->force_vec[6 * i];
    self->force_link[i] = link;
    f[0] = fx; f[1] = fy; f[2] = fz;
    f[3] = px; f[4] = py; f[5] = pz;
}

/* Apply the queued forces in order, each as its own applyExternalForce command: natively
 * through Bullet's C API, or through the Python API. One command per force, as pybullet does:
 * b3ApplyExternalForce can queue several forces in one command, but it stores the i-th force
 * at [i + j] where the server reads [3 i + j] (PhysicsClientC_API.cpp against
 * PhysicsServerCommandProcessor.cpp), so a batched command applies wrong forces. */
static int submit_forces(WheelLoop *self, b3Handle sm)
{
    int m = self->n_forces;
    self->n_forces = 0;
    if (sm != NULL) {
        for (int i = 0; i < m; i++) {
            b3Handle cmd = self->api.init_force(sm);
            self->api.force(cmd, (int)self->body, self->force_link[i], &self->force_vec[6 * i],
                            &self->force_vec[6 * i + 3], (int)self->world);
            self->api.submit(sm, cmd);
        }
        return 0;
    }
    for (int i = 0; i < m; i++) {
        const double *f = &self->force_vec[6 * i];
        PyObject *force = Py_BuildValue("(ddd)", f[0], f[1], f[2]);
        PyObject *pos = Py_BuildValue("(ddd)", f[3], f[4], f[5]);
        PyObject *link_obj = PyLong_FromLong(self->force_link[i]);
        PyObject *r = NULL;
        if (force && pos && link_obj) {
            PyObject *args[6] = {self->body_obj, link_obj, force, pos, self->world_obj,
                                 self->client_obj};
            r = PyObject_Vectorcall(self->apply_fn, args, 6, NULL);
        }
        Py_XDECREF(force);
        Py_XDECREF(pos);
        Py_XDECREF(link_obj);
        if (r == NULL)
            return -1;
        Py_DECREF(r);
    }
    return 0;
}

/* Resistance of wheel k in the rut of the wheel ahead (WheelSoilInjector._multi_pass). */
static int multi_pass(WheelLoop *self, int k, double res, double load_n, double v_long,
                      double *out)
{
    Wheel *w = &self->w[k];
    int forward = v_long >= 0.0;
    int leader = forward ? w->lead_front : w->lead_back;
    if (leader < 0 || self->w[leader].load <= 0.0) {
        *out = res;
        return 0;
    }
    double f_r = w->kernel.f_r, fx, fy, lead;
    double w_lead = (forward ? w->rut_ratio_front : w->rut_ratio_back) * self->w[leader].load;
    if (kernel_eval(&w->kernel, 0.0, 0.0, w_lead, &fx, &fy, &lead) < 0)
        return -1;
    lead = lead - f_r * w_lead;
    double rolling = f_r * load_n;
    *out = rolling + rut_following(res - rolling, lead);
    return 0;
}

static void clear_patches(WheelLoop *self, Inputs *in)
{
    for (int k = 0; k < self->n; k++) {
        in->load[k] = 0.0;
        in->has_patch[k] = 0;
    }
    in->chassis = 0;
}

/* Add one contact point (load f > 0 on `link`, point p and normal nrm on the ground) to the
 * wheel's load-weighted sums (WheelSoilInjector._patches). */
static void add_contact(WheelLoop *self, Inputs *in, long link, double f, const double *p,
                        const double *nrm)
{
    int k = (link >= -1 && link <= self->max_link) ? self->link_to_wheel[link + 1] : -1;
    if (k < 0) {
        in->chassis = 1;
        return;
    }
    double *a = &in->patch[6 * k];
    if (!in->has_patch[k]) {
        a[0] = f * p[0]; a[1] = f * p[1]; a[2] = f * p[2];
        a[3] = f * nrm[0]; a[4] = f * nrm[1]; a[5] = f * nrm[2];
        in->has_patch[k] = 1;
    } else {
        a[0] += f * p[0]; a[1] += f * p[1]; a[2] += f * p[2];
        a[3] += f * nrm[0]; a[4] += f * nrm[1]; a[5] += f * nrm[2];
    }
    in->load[k] += f;
}

static PyObject *call_query(PyObject *fn, PyObject *args)
{
    return PyObject_Call(fn, args, NULL);
}

/* This substep's readings through pybullet's Python API: getContactPoints(body, ground),
 * getLinkStates(body, wheel links, computeLinkVelocity=1), getJointStates(spin joints). */
static int acquire_python(WheelLoop *self, Inputs *in)
{
    int rc = -1;
    PyObject *links = NULL, *joints = NULL;
    PyObject *contacts = call_query(self->contacts_fn, self->contacts_args);
    if (contacts == NULL)
        return -1;
    if ((links = call_query(self->links_fn, self->links_args)) == NULL
        || (joints = call_query(self->joints_fn, self->joints_args)) == NULL)
        goto done;
    if (!PyTuple_Check(contacts)) {
        PyErr_SetString(PyExc_TypeError, "getContactPoints did not return a tuple");
        goto done;
    }
    if (!PyTuple_Check(links) || PyTuple_GET_SIZE(links) != self->n || !PyTuple_Check(joints)
        || PyTuple_GET_SIZE(joints) != self->n_spin) {
        PyErr_SetString(PyExc_TypeError, "unexpected PyBullet link or joint states");
        goto done;
    }
    clear_patches(self, in);
    Py_ssize_t m = PyTuple_GET_SIZE(contacts);
    for (Py_ssize_t i = 0; i < m; i++) {
        PyObject *cp = PyTuple_GET_ITEM(contacts, i);
        if (!PyTuple_Check(cp) || PyTuple_GET_SIZE(cp) < 10) {
            PyErr_SetString(PyExc_TypeError, "malformed contact point from PyBullet");
            goto done;
        }
        double f;
        if (get_double(cp, 9, &f) < 0)
            goto done;
        if (f <= 0.0)
            continue;
        long link = PyLong_AsLong(PyTuple_GET_ITEM(cp, 3));
        if (link == -1 && PyErr_Occurred())
            goto done;
        double p[3], nrm[3];
        if (get_vec(PyTuple_GET_ITEM(cp, 6), 3, p) < 0
            || get_vec(PyTuple_GET_ITEM(cp, 7), 3, nrm) < 0)
            goto done;
        add_contact(self, in, link, f, p, nrm);
    }
    for (int k = 0; k < self->n; k++) {
        PyObject *ls = PyTuple_GET_ITEM(links, k);
        double *d = &in->link[LINK_WIDTH * k];
        if (!PyTuple_Check(ls) || PyTuple_GET_SIZE(ls) < 8) {
            PyErr_SetString(PyExc_TypeError, "malformed link state from PyBullet");
            goto done;
        }
        if (get_vec(PyTuple_GET_ITEM(ls, 1), 4, d) < 0
            || get_vec(PyTuple_GET_ITEM(ls, 0), 3, d + 4) < 0
            || get_vec(PyTuple_GET_ITEM(ls, 6), 3, d + 7) < 0
            || get_vec(PyTuple_GET_ITEM(ls, 7), 3, d + 10) < 0)
            goto done;
    }
    for (int j = 0; j < self->n_spin; j++) {
        PyObject *js = PyTuple_GET_ITEM(joints, j);
        if (!PyTuple_Check(js) || PyTuple_GET_SIZE(js) < 2 || get_double(js, 1, &in->rate[j]) < 0) {
            if (!PyErr_Occurred())
                PyErr_SetString(PyExc_TypeError, "malformed joint state from PyBullet");
            goto done;
        }
    }
    rc = 0;
done:
    Py_DECREF(contacts);
    Py_XDECREF(links);
    Py_XDECREF(joints);
    return rc;
}

/* The same readings through Bullet's C API (bullet_native.h): the same two server commands
 * pybullet submits (a contact query filtered on body and ground; one actual-state request with
 * link velocities, which carries the joint states too), read without building tuples. */
static int acquire_native(WheelLoop *self, Inputs *in, b3Handle sm)
{
    const BulletApi *api = &self->api;
    b3Handle cmd = api->init_contacts(sm);
    api->filter_body_a(cmd, (int)self->body);
    api->filter_body_b(cmd, (int)self->ground);
    int type = api->status_type(api->submit(sm, cmd));
    if (!self->verify && type != self->contact_status) {
        PyErr_Format(self->error_type, "getContactPoints failed (status %d)", type);
        return -1;
    }
    self->contact_status = type;
    struct b3ContactInformation info;
    api->contacts(sm, &info);
    clear_patches(self, in);
    for (int i = 0; i < info.m_numContactPoints; i++) {
        const struct b3ContactPointData *cp = &info.m_contactPointData[i];
        double f = cp->m_normalForce;
        if (f <= 0.0)
            continue;
        add_contact(self, in, cp->m_linkIndexA, f, cp->m_positionOnBInWS,
                    cp->m_contactNormalOnBInWS);
    }
    cmd = api->init_state(sm, (int)self->body);
    api->link_velocity(cmd, 1);
    b3Handle status = api->submit(sm, cmd);
    type = api->status_type(status);
    if (!self->verify && type != self->state_status) {
        PyErr_Format(self->error_type, "getLinkStates failed (status %d)", type);
        return -1;
    }
    self->state_status = type;
    for (int k = 0; k < self->n; k++) {
        struct b3LinkState ls;
        double *d = &in->link[LINK_WIDTH * k];
        if (!api->link_state(sm, status, self->w[k].link, &ls)) {
            PyErr_Format(self->error_type, "getLinkStates failed for link %d", self->w[k].link);
            return -1;
        }
        memcpy(d, ls.m_worldOrientation, 4 * sizeof(double));
        memcpy(d + 4, ls.m_worldPosition, 3 * sizeof(double));
        memcpy(d + 7, ls.m_worldLinearVelocity, 3 * sizeof(double));
        memcpy(d + 10, ls.m_worldAngularVelocity, 3 * sizeof(double));
    }
    for (int j = 0; j < self->n_spin; j++) {
        struct b3JointSensorState js;
        if (!api->joint_state(sm, status, self->spin_joints[j], &js)) {
            PyErr_Format(self->error_type, "getJointStates failed for joint %d",
                         self->spin_joints[j]);
            return -1;
        }
        in->rate[j] = js.m_jointVelocity;
    }
    return 0;
}

/* This substep's readings into self->in: natively once verified, else through the Python
 * API. Until a substep with a wheel on the ground has read the same bits both ways, both
 * run; a difference switches the loop to the Python API for good (self->mismatch). Returns
 * the native client handle to apply the forces through, or NULL for the Python API (check
 * PyErr_Occurred). */
static b3Handle acquire(WheelLoop *self)
{
    if (!self->native) {
        acquire_python(self, &self->in);
        return NULL;
    }
    b3Handle sm = bullet_client(&self->api, self->client);
    if (sm == NULL) {
        PyErr_SetString(self->error_type, "Not connected to physics server.");
        return NULL;
    }
    int failed = acquire_native(self, &self->in, sm) < 0;
    if (failed && !self->verify)
        return NULL;
    if (self->verify) {
        PyErr_Clear(); /* a native failure before verification is a mismatch, not an error */
        if (acquire_python(self, &self->check) < 0)
            return NULL;
        if (failed || !inputs_equal(&self->in, &self->check, self->n, self->n_spin)) {
            Inputs tmp = self->in;
            self->in = self->check;
            self->check = tmp;
            self->native = self->verify = 0;
            self->mismatch = 1;
            return NULL;
        }
        for (int k = 0; k < self->n; k++)
            if (self->in.has_patch[k])
                self->verify = 0;
    }
    return sm;
}

/* One substep: read PyBullet, compute every wheel's forces, apply them. */
static int loop_step(WheelLoop *self)
{
    double t0 = self->timing ? now_s() : 0.0;
    b3Handle sm = acquire(self);
    if (sm == NULL && PyErr_Occurred())
        return -1;
    double t1 = self->timing ? now_s() : 0.0;
    Inputs *in = &self->in;
    if (in->chassis)
        self->chassis_contact = 1;
    self->n_forces = 0;
    double dt = self->dt, stick = self->stick;
    for (int k = 0; k < self->n; k++)
        self->w[k].load = in->load[k];
    for (int k = 0; k < self->n; k++) {
        Wheel *w = &self->w[k];
        double load = w->load;
        w->fx = w->fy = w->res = w->damper = 0.0;
        if (load <= 0.0) {
            w->s = w->b = w->rut = 0.0;
            w->rut_vec[0] = w->rut_vec[1] = w->rut_vec[2] = 0.0;
            w->force[0] = w->force[1] = w->force[2] = 0.0;
            continue;
        }
        const double *d = &in->link[LINK_WIDTH * k];
        const double *q = d, *centre = d + 4, *v = d + 7;
        const double *a = &in->patch[6 * k];
        double inv_w, inv;
        if (py_div(1.0, load, &inv_w) < 0)
            return -1;
        double cx = a[0] * inv_w, cy = a[1] * inv_w, cz = a[2] * inv_w;
        double nx = a[3], ny = a[4], nz = a[5];
        if (py_div(1.0, sqrt(nx * nx + ny * ny + nz * nz), &inv) < 0)
            return -1;
        nx = nx * inv; ny = ny * inv; nz = nz * inv;
        double qx = q[0], qy = q[1], qz = q[2], qw = q[3];
        double ax = 2.0 * (qx * qy - qw * qz);
        double ay = 1.0 - 2.0 * (qx * qx + qz * qz);
        double az = 2.0 * (qy * qz + qw * qx);
        double ex = ay * nz - az * ny, ey = az * nx - ax * nz, ez = ax * ny - ay * nx;
        if (py_div(1.0, sqrt(ex * ex + ey * ey + ez * ez), &inv) < 0)
            return -1;
        ex = ex * inv; ey = ey * inv; ez = ez * inv;
        double lx = ny * ez - nz * ey, ly = nz * ex - nx * ez, lz = nx * ey - ny * ex;
        double px = centre[0], py = centre[1], pz = centre[2];
        double vx = v[0], vy = v[1], vz = v[2];
        double v_long = vx * ex + vy * ey + vz * ez;
        double force[3], r_abs;
        if (w->driven) {
            const double *om = d + 10;
            if (w->spin_index < 0 || w->spin_index >= self->n_spin) {
                PyErr_SetString(PyExc_IndexError, "driven wheel without a spin joint state");
                return -1;
            }
            double rate = in->rate[w->spin_index];
            double wx = om[0], wy = om[1], wz = om[2];
            double rx = cx - px, ry = cy - py, rz = cz - pz;
            double v_lat = ((vx + wy * rz - wz * ry) * lx + (vy + wz * rx - wx * rz) * ly
                            + (vz + wx * ry - wy * rx) * lz);
            double r_omega = w->r_eff * rate;
            double t_old = w->b, s, t, v_ref;
            relax_slip(w->s, t_old, r_omega, v_long, v_lat, w->h, &s, &t, &v_ref);
            w->s = s;
            w->b = t;
            double f_long, f_lat, res;
            if (kernel_eval(&w->kernel, s, t, load, &f_long, &f_lat, &res) < 0)
                return -1;
            w->fx = f_long;
            w->fy = f_lat;
            double d_y = lateral_damping(t - t_old, v_ref, w->d_lat, self->fade_speed);
            double d_x = longitudinal_damping(r_omega, v_long, v_ref, w->c_long,
                                              self->low_speed);
            f_lat += d_y;
            f_long += d_x;
            queue_force(self, w->link, f_long * ex + f_lat * lx, f_long * ey + f_lat * ly,
                        f_long * ez + f_lat * lz, cx, cy, cz);
            if (self->multi_pass && multi_pass(self, k, res, load, v_long, &res) < 0)
                return -1;
            double r_k, u_k;
            rut_resistance(res, w->rut, v_long * dt, v_long, stick, w->rut_damping, &r_k, &u_k);
            w->rut = u_k;
            w->damper = fabs(d_x) + fabs(d_y) + fabs(r_k - res * u_k);
            w->res = r_abs = fabs(r_k);
            force[0] = -r_k * ex;
            force[1] = -r_k * ey;
            force[2] = -r_k * ez;
        } else {
            double fx, fy, res;
            if (kernel_eval(&w->kernel, 0.0, 0.0, load, &fx, &fy, &res) < 0)
                return -1;
            if (self->multi_pass && multi_pass(self, k, res, load, v_long, &res) < 0)
                return -1;
            double v_side = vx * lx + vy * ly + vz * lz;
            double vel[3] = {v_long * ex + v_side * lx, v_long * ey + v_side * ly,
                             v_long * ez + v_side * lz};
            double r[3], u[3];
            rut_resistance_vector(res, w->rut_vec, vel, dt, stick, w->rut_damping, r, u);
            w->rut_vec[0] = u[0]; w->rut_vec[1] = u[1]; w->rut_vec[2] = u[2];
            w->res = r_abs = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
            double dx = r[0] - res * u[0], dy = r[1] - res * u[1], dz = r[2] - res * u[2];
            w->damper = sqrt(dx * dx + dy * dy + dz * dz);
            force[0] = -r[0];
            force[1] = -r[1];
            force[2] = -r[2];
        }
        w->force[0] = force[0]; w->force[1] = force[1]; w->force[2] = force[2];
        if (r_abs != 0.0)
            queue_force(self, w->link, force[0], force[1], force[2], px, py, pz);
    }
    double t2 = self->timing ? now_s() : 0.0;
    int rc = submit_forces(self, sm);
    if (self->timing) {
        self->t_read += t1 - t0;
        self->t_law += t2 - t1;
        self->t_apply += now_s() - t2;
        self->timed_substeps += 1;
    }
    return rc;
}

/* bind_native(pybullet_path, clients_offset, n_clients, anchor_offset): read PyBullet through
 * Bullet's C API from the next substep on, verified against the Python API first. */
static PyObject *loop_bind_native(WheelLoop *self, PyObject *args)
{
    const char *path;
    unsigned long long clients_offset, anchor_offset;
    long n_clients;
    if (!PyArg_ParseTuple(args, "sKlK", &path, &clients_offset, &n_clients, &anchor_offset))
        return NULL;
    if (self->client < 0 || self->client >= n_clients) {
        PyErr_Format(PyExc_ValueError, "client %ld outside pybullet's table of %ld", self->client,
                     n_clients);
        return NULL;
    }
    BulletApi api;
    if (bullet_api_bind(&api, path, clients_offset, n_clients, anchor_offset) < 0)
        return NULL;
    if (bullet_client(&api, self->client) == NULL) {
        PyErr_Format(PyExc_OSError, "client %ld is not in pybullet's client table at offset "
                     "%llu", self->client, clients_offset);
        return NULL;
    }
    self->api = api;
    self->bound = self->native = self->verify = 1;
    self->mismatch = 0;
    Py_RETURN_NONE;
}

static PyObject *loop_apply(WheelLoop *self, PyObject *unused)
{
    if (loop_step(self) < 0)
        return NULL;
    Py_RETURN_NONE;
}

/* -- reading and writing the per-wheel state ---------------------------------------------- */

#define FIELD_LIST(NAME, EXPR)                                                    \
    static PyObject *get_##NAME(WheelLoop *self, void *closure)                   \
    {                                                                             \
        PyObject *out = PyList_New(self->n);                                      \
        if (out == NULL)                                                          \
            return NULL;                                                          \
        for (int k = 0; k < self->n; k++) {                                       \
            Wheel *w = &self->w[k];                                               \
            PyObject *v = (EXPR);                                                 \
            if (v == NULL) {                                                      \
                Py_DECREF(out);                                                   \
                return NULL;                                                      \
            }                                                                     \
            PyList_SET_ITEM(out, k, v);                                           \
        }                                                                         \
        return out;                                                               \
    }

FIELD_LIST(s, PyFloat_FromDouble(w->s))
FIELD_LIST(b, PyFloat_FromDouble(w->b))
FIELD_LIST(rut, PyFloat_FromDouble(w->rut))
FIELD_LIST(load, PyFloat_FromDouble(w->load))
FIELD_LIST(fx, PyFloat_FromDouble(w->fx))
FIELD_LIST(fy, PyFloat_FromDouble(w->fy))
FIELD_LIST(res, PyFloat_FromDouble(w->res))
FIELD_LIST(damper, PyFloat_FromDouble(w->damper))
FIELD_LIST(rut_vec, Py_BuildValue("(ddd)", w->rut_vec[0], w->rut_vec[1], w->rut_vec[2]))
FIELD_LIST(force, Py_BuildValue("(ddd)", w->force[0], w->force[1], w->force[2]))

static PyObject *get_chassis_contact(WheelLoop *self, void *closure)
{
    return PyBool_FromLong(self->chassis_contact);
}

static int set_chassis_contact(WheelLoop *self, PyObject *value, void *closure)
{
    int v = value ? PyObject_IsTrue(value) : 0;
    if (v < 0)
        return -1;
    self->chassis_contact = v;
    return 0;
}

static PyObject *get_native(WheelLoop *self, void *closure)
{
    return PyBool_FromLong(self->native);
}

static int set_native(WheelLoop *self, PyObject *value, void *closure)
{
    int v = value ? PyObject_IsTrue(value) : 0;
    if (v < 0)
        return -1;
    if (v && !self->bound) {
        PyErr_SetString(PyExc_ValueError, "native queries are not bound (bind_native)");
        return -1;
    }
    if (v && !self->native) {
        self->verify = 1;
        self->mismatch = 0;
    }
    self->native = v;
    return 0;
}

static PyObject *get_timing(WheelLoop *self, void *closure)
{
    return PyBool_FromLong(self->timing);
}

/* Setting `timing` to True starts from zero; to False keeps the times for reading. */
static int set_timing(WheelLoop *self, PyObject *value, void *closure)
{
    int v = value ? PyObject_IsTrue(value) : 0;
    if (v < 0)
        return -1;
    self->timing = v;
    if (v) {
        self->t_read = self->t_law = self->t_apply = 0.0;
        self->timed_substeps = 0;
    }
    return 0;
}

static PyObject *get_timings(WheelLoop *self, void *closure)
{
    return Py_BuildValue("{s:d,s:d,s:d,s:l}", "read_s", self->t_read, "force_law_s", self->t_law,
                         "apply_s", self->t_apply, "substeps", self->timed_substeps);
}

static PyObject *get_native_verified(WheelLoop *self, void *closure)
{
    return PyBool_FromLong(self->native && !self->verify);
}

static PyObject *get_native_mismatch(WheelLoop *self, void *closure)
{
    return PyBool_FromLong(self->mismatch);
}

static PyGetSetDef loop_getset[] = {
    {"s", (getter)get_s, NULL, "slip ratio per wheel", NULL},
    {"b", (getter)get_b, NULL, "tan of the slip angle per wheel", NULL},
    {"rut", (getter)get_rut, NULL, "resistance element state per driven wheel", NULL},
    {"rut_vec", (getter)get_rut_vec, NULL, "resistance element state per castor", NULL},
    {"load", (getter)get_load, NULL, "normal load per wheel [N]", NULL},
    {"fx", (getter)get_fx, NULL, "longitudinal force law per wheel [N]", NULL},
    {"fy", (getter)get_fy, NULL, "lateral force law per wheel [N]", NULL},
    {"res", (getter)get_res, NULL, "applied resistance per wheel [N]", NULL},
    {"damper", (getter)get_damper, NULL, "dampers' share per wheel [N]", NULL},
    {"resistance_force_n", (getter)get_force, NULL, "applied resistance force [N]", NULL},
    {"chassis_contact", (getter)get_chassis_contact, (setter)set_chassis_contact,
     "a body other than a wheel touched the ground", NULL},
    {"native", (getter)get_native, (setter)set_native,
     "PyBullet is read through Bullet's C API (bind_native), not its Python API", NULL},
    {"timing", (getter)get_timing, (setter)set_timing,
     "time the parts of each substep (see `timings`); setting it True zeroes them", NULL},
    {"timings", (getter)get_timings, NULL,
     "seconds spent reading PyBullet (read_s), in the force law and dampers (force_law_s) and "
     "applying the forces (apply_s) over `substeps` timed substeps", NULL},
    {"native_verified", (getter)get_native_verified, NULL,
     "the native readings matched the Python API's bit for bit on a substep with contact", NULL},
    {"native_mismatch", (getter)get_native_mismatch, NULL,
     "the native readings differed from the Python API's, so the loop uses the Python API",
     NULL},
    {NULL, NULL, NULL, NULL, NULL},
};

static PyMethodDef loop_methods[] = {
    {"set_wheel", (PyCFunction)loop_set_wheel, METH_VARARGS,
     "set_wheel(k, driven, spin_index, r_eff, h, c_long, d_lat, rut_damping, lead_front, "
     "lead_back, rut_ratio_front, rut_ratio_back, kernel_constants): bind wheel k's constants "
     "(once per soil sample)."},
    {"reset", (PyCFunction)loop_reset, METH_NOARGS, "Zero every wheel's state."},
    {"apply", (PyCFunction)loop_apply, METH_NOARGS,
     "One substep's forces: query PyBullet, compute, apply."},
    {"bind_native", (PyCFunction)loop_bind_native, METH_VARARGS,
     "bind_native(pybullet_path, clients_offset, n_clients, anchor_offset): read PyBullet "
     "through Bullet's C API (slipenv.sim.bullet_native)."},
    {NULL, NULL, 0, NULL},
};

static PyTypeObject WheelLoopType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "slipenv.sim._wheel_loop.WheelLoop",
    .tp_basicsize = sizeof(WheelLoop),
    .tp_dealloc = (destructor)loop_dealloc,
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "The compiled per-substep loop of WheelSoilInjector (see the module docstring).",
    .tp_methods = loop_methods,
    .tp_getset = loop_getset,
    .tp_init = (initproc)loop_init,
    .tp_new = PyType_GenericNew,
};

/* -- the transcribed functions, one by one, for the bit-for-bit tests --------------------- */

static PyObject *fn_kernel(PyObject *mod, PyObject *args)
{
    PyObject *spec;
    double slip, tb, load, fx, fy, res;
    Kernel k;
    if (!PyArg_ParseTuple(args, "O!ddd", &PyTuple_Type, &spec, &slip, &tb, &load)
        || parse_kernel(spec, &k) < 0 || kernel_eval(&k, slip, tb, load, &fx, &fy, &res) < 0)
        return NULL;
    return Py_BuildValue("(ddd)", fx, fy, res);
}

static PyObject *fn_relax_slip(PyObject *mod, PyObject *args)
{
    double a[6], s, t, v;
    if (!PyArg_ParseTuple(args, "dddddd", &a[0], &a[1], &a[2], &a[3], &a[4], &a[5]))
        return NULL;
    relax_slip(a[0], a[1], a[2], a[3], a[4], a[5], &s, &t, &v);
    return Py_BuildValue("(ddd)", s, t, v);
}

static PyObject *fn_lateral(PyObject *mod, PyObject *args)
{
    double a[4];
    if (!PyArg_ParseTuple(args, "dddd", &a[0], &a[1], &a[2], &a[3]))
        return NULL;
    return PyFloat_FromDouble(lateral_damping(a[0], a[1], a[2], a[3]));
}

static PyObject *fn_longitudinal(PyObject *mod, PyObject *args)
{
    double a[5];
    if (!PyArg_ParseTuple(args, "ddddd", &a[0], &a[1], &a[2], &a[3], &a[4]))
        return NULL;
    return PyFloat_FromDouble(longitudinal_damping(a[0], a[1], a[2], a[3], a[4]));
}

static PyObject *fn_rut(PyObject *mod, PyObject *args)
{
    double a[6], r, u;
    if (!PyArg_ParseTuple(args, "dddddd", &a[0], &a[1], &a[2], &a[3], &a[4], &a[5]))
        return NULL;
    rut_resistance(a[0], a[1], a[2], a[3], a[4], a[5], &r, &u);
    return Py_BuildValue("(dd)", r, u);
}

static PyObject *fn_rut_vector(PyObject *mod, PyObject *args)
{
    double res, st[3], v[3], dt, stick, damping, r[3], u[3];
    if (!PyArg_ParseTuple(args, "d(ddd)(ddd)ddd", &res, &st[0], &st[1], &st[2], &v[0], &v[1],
                          &v[2], &dt, &stick, &damping))
        return NULL;
    rut_resistance_vector(res, st, v, dt, stick, damping, r, u);
    return Py_BuildValue("((ddd)(ddd))", r[0], r[1], r[2], u[0], u[1], u[2]);
}

static PyObject *fn_rut_following(PyObject *mod, PyObject *args)
{
    double a, b;
    if (!PyArg_ParseTuple(args, "dd", &a, &b))
        return NULL;
    return PyFloat_FromDouble(rut_following(a, b));
}

static PyMethodDef module_methods[] = {
    {"kernel", fn_kernel, METH_VARARGS,
     "kernel(kernel_constants, slip, tan_beta, load_n) -> (fx_n, fy_n, resistance_n)"},
    {"relax_slip", fn_relax_slip, METH_VARARGS, "slip_dynamics.relax_slip"},
    {"lateral_soil_damping_n", fn_lateral, METH_VARARGS, "slip_dynamics.lateral_soil_damping_n"},
    {"longitudinal_soil_damping_n", fn_longitudinal, METH_VARARGS,
     "slip_dynamics.longitudinal_soil_damping_n"},
    {"rut_resistance_n", fn_rut, METH_VARARGS, "slip_dynamics.rut_resistance_n"},
    {"rut_resistance_vector_n", fn_rut_vector, METH_VARARGS,
     "slip_dynamics.rut_resistance_vector_n"},
    {"rut_following_compaction_n", fn_rut_following, METH_VARARGS,
     "bekker.rut_following_compaction_n"},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module_def = {
    PyModuleDef_HEAD_INIT, "_wheel_loop",
    "The compiled per-substep wheel-soil loop (a transcription of the plain functions).", -1,
    module_methods,
};

PyMODINIT_FUNC PyInit__wheel_loop(void)
{
    PyObject *math = PyImport_ImportModule("math");
    if (math == NULL)
        return NULL;
    g_hypot = PyObject_GetAttrString(math, "hypot");
    Py_DECREF(math);
    if (g_hypot == NULL || PyType_Ready(&WheelLoopType) < 0)
        return NULL;
    PyObject *m = PyModule_Create(&module_def);
    if (m == NULL)
        return NULL;
    Py_INCREF(&WheelLoopType);
    if (PyModule_AddObject(m, "WheelLoop", (PyObject *)&WheelLoopType) < 0) {
        Py_DECREF(&WheelLoopType);
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
