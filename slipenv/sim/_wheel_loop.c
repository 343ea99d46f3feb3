/* The per-substep wheel-soil force loop of slipenv.sim.wheel_soil (WheelSoilInjector).
 *
 * Per substep: read the contacts, the wheel links' states and the spin joints' rates from
 * PyBullet (through pybullet's Python API, or through Bullet's C API once verified against it:
 * bullet_native.h); per loaded wheel, the contact frame, then for a driven wheel the slip
 * relaxation step, the force law and the two soil dampers, applied at the contact patch, and
 * for every wheel the rate-independent motion resistance, applied at the wheel centre (for a
 * driven wheel with the slip-sinkage state, plus what its dug depth adds:
 * laws_kernel_sinkage_state). The physics is not written here: every law is a function of
 * slipenv/terramechanics/_laws.h (sources and equations there), the one implementation the
 * Python API binds as well. A force model that is not one of slipenv's (its kernel_constants is
 * None: a user's law) is called back as its Python kernel, (slip, tan_beta, load_n) -> (fx_n,
 * fy_n, resistance_n).
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <string.h>
#include <time.h>

#include "_laws.h"
#include "bullet_native.h"

/* -- the loop ---------------------------------------------------------------------------- */

typedef struct {
    int link, driven, spin_index;
    int forward_angle; /* the law takes Reina's tan_beta = v_lat/v_x (laws_relax_slip) */
    int lead_front, lead_back;
    double rut_ratio_front, rut_ratio_back; /* bekker.rut_load_ratio of each leader's rut */
    double r_eff, h, c_long, d_lat, rut_damping;
    LawsKernel kernel;
    PyObject *py_kernel; /* a user's law (Python callable), else NULL: `kernel` runs */
    double f_r;          /* rolling resistance coefficient of the law (multi-pass) */
    /* state */
    double s, b, rut, rut_vec[3];
    double dug; /* depth dug below the static rut (laws_kernel_sinkage_state) */
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
    BulletBuffers buf;  /* the structs pybullet fills, each with its guard region */
    long verify_every;  /* compare with the Python API every this-many substeps with contact */
    long contact_substeps, verifications;
    PyObject *on_mismatch; /* called with the reason when a check fails (warns once) */
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

/* The first difference between two readings in what the loop acts on, described in `what`
 * (e.g. "contact patch of wheel 2"), or 0 if they agree bit for bit (memcmp: a -0.0 or a NaN
 * pattern counts). A wheel's patch sums are compared only where it has a patch: for a wheel
 * without one, clear_patches leaves the sums of the last substep on which that buffer saw it
 * in contact, and the loop never reads them (no load). `in` is refilled on every substep but
 * `check` only on compared ones, so a wheel that touched the ground between two comparisons
 * and is off it at the second (a rover rocking over a heightfield) holds leftovers of different
 * substeps in the two: they would differ though every value the loop uses agrees. Where a
 * patch exists its sums must agree bit for bit, not as a set of points: both readings sum the
 * same server reply in the order it lists the points. Link states and spin rates are read
 * afresh for every wheel on every substep, so all of them are compared. */
static int inputs_differ(const Inputs *a, const Inputs *b, int n, int n_spin, char *what,
                         size_t size)
{
    if (a->chassis != b->chassis) {
        PyOS_snprintf(what, size, "chassis contact");
        return 1;
    }
    for (int k = 0; k < n; k++) {
        const char *field = NULL;
        if (a->has_patch[k] != b->has_patch[k])
            field = "contact";
        else if (memcmp(&a->load[k], &b->load[k], sizeof(double)) != 0)
            field = "load";
        else if (a->has_patch[k]
                 && memcmp(&a->patch[6 * k], &b->patch[6 * k], 6 * sizeof(double)) != 0)
            field = "contact patch";
        else if (memcmp(&a->link[LINK_WIDTH * k], &b->link[LINK_WIDTH * k],
                        LINK_WIDTH * sizeof(double)) != 0)
            field = "link state";
        if (field != NULL) {
            PyOS_snprintf(what, size, "%s of wheel %d", field, k);
            return 1;
        }
    }
    for (int j = 0; j < n_spin; j++)
        if (memcmp(&a->rate[j], &b->rate[j], sizeof(double)) != 0) {
            PyOS_snprintf(what, size, "rate of spin joint %d", j);
            return 1;
        }
    return 0;
}

static void loop_dealloc(WheelLoop *self)
{
    bullet_buffers_free(&self->buf);
    Py_XDECREF(self->on_mismatch);
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
    if (self->w != NULL)
        for (int k = 0; k < self->n; k++)
            Py_XDECREF(self->w[k].py_kernel);
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
       client); getJointStates(body, spin_joints, client): positional (keywords cost more). */
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
             lead_back, rut_ratio_front, rut_ratio_back, law, f_r, forward_angle): law is the
   force model's KernelConstants (a tuple, evaluated by laws_kernel) or its Python kernel (a
   user's law); forward_angle: the law's slip angle is Reina's v_lat/v_x, not the sliding
   velocity's (laws_relax_slip). */
static PyObject *loop_set_wheel(WheelLoop *self, PyObject *args)
{
    int k, driven, spin_index, lead_front, lead_back, forward_angle;
    double r_eff, h, c_long, d_lat, rut_damping, ratio_front, ratio_back, f_r;
    PyObject *law;
    if (!PyArg_ParseTuple(args, "ipidddddiiddOdp", &k, &driven, &spin_index, &r_eff, &h,
                          &c_long, &d_lat, &rut_damping, &lead_front, &lead_back, &ratio_front,
                          &ratio_back, &law, &f_r, &forward_angle))
        return NULL;
    if ((lead_front >= self->n) || (lead_back >= self->n)) {
        PyErr_Format(PyExc_IndexError, "leader out of range (n = %d)", self->n);
        return NULL;
    }
    if (check_wheel(self, k) < 0)
        return NULL;
    LawsKernel kern;
    memset(&kern, 0, sizeof(kern));
    PyObject *py_kernel = NULL;
    if (PyTuple_Check(law)) {
        if (laws_parse_kernel(law, &kern) < 0)
            return NULL;
    } else if (PyCallable_Check(law)) {
        py_kernel = law;
        Py_INCREF(py_kernel);
    } else {
        PyErr_SetString(PyExc_TypeError, "law must be kernel constants or a callable kernel");
        return NULL;
    }
    Wheel *w = &self->w[k];
    w->driven = driven;
    w->spin_index = spin_index;
    w->forward_angle = forward_angle;
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
    Py_XSETREF(w->py_kernel, py_kernel);
    w->f_r = py_kernel != NULL ? f_r : kern.f_r;
    Py_RETURN_NONE;
}

/* (fx, fy, resistance) of wheel w's force law; -1 with an exception from a user's law. */
static int wheel_law(const Wheel *w, double slip, double tan_beta, double load, double *fx,
                     double *fy, double *res)
{
    if (w->py_kernel == NULL) {
        laws_kernel(&w->kernel, slip, tan_beta, load, fx, fy, res);
        return 0;
    }
    PyObject *args[3] = {PyFloat_FromDouble(slip), PyFloat_FromDouble(tan_beta),
                         PyFloat_FromDouble(load)};
    PyObject *out = NULL;
    if (args[0] && args[1] && args[2])
        out = PyObject_Vectorcall(w->py_kernel, args, 3, NULL);
    for (int i = 0; i < 3; i++)
        Py_XDECREF(args[i]);
    if (out == NULL)
        return -1;
    int ok = PyArg_ParseTuple(out, "ddd;a force kernel returns (fx_n, fy_n, resistance_n)", fx,
                              fy, res);
    Py_DECREF(out);
    return ok ? 0 : -1;
}

static PyObject *loop_reset(WheelLoop *self, PyObject *unused)
{
    for (int k = 0; k < self->n; k++) {
        Wheel *w = &self->w[k];
        w->s = w->b = w->rut = w->dug = 0.0;
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

/* Resistance of wheel k in the rut of the wheel ahead in the direction of travel, whose rut
 * is as deep as this wheel would sink under q W_leader (laws_multi_pass). */
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
    double fx, fy, lead_res;
    double w_lead = (forward ? w->rut_ratio_front : w->rut_ratio_back) * self->w[leader].load;
    if (wheel_law(w, 0.0, 0.0, w_lead, &fx, &fy, &lead_res) < 0)
        return -1;
    *out = laws_multi_pass(res, load_n, lead_res, w_lead, w->f_r);
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
 * wheel's load-weighted sums (the contact patch: laws_contact_frame). */
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
    struct b3ContactInformation *info = self->buf.contacts;
    api->contacts(sm, info);
    clear_patches(self, in);
    for (int i = 0; i < info->m_numContactPoints; i++) {
        const struct b3ContactPointData *cp = &info->m_contactPointData[i];
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
    struct b3LinkState *ls = self->buf.link;
    for (int k = 0; k < self->n; k++) {
        double *d = &in->link[LINK_WIDTH * k];
        if (!api->link_state(sm, status, self->w[k].link, ls)) {
            PyErr_Format(self->error_type, "getLinkStates failed for link %d", self->w[k].link);
            return -1;
        }
        memcpy(d, ls->m_worldOrientation, 4 * sizeof(double));
        memcpy(d + 4, ls->m_worldPosition, 3 * sizeof(double));
        memcpy(d + 7, ls->m_worldLinearVelocity, 3 * sizeof(double));
        memcpy(d + 10, ls->m_worldAngularVelocity, 3 * sizeof(double));
    }
    struct b3JointSensorState *js = self->buf.joint;
    for (int j = 0; j < self->n_spin; j++) {
        if (!api->joint_state(sm, status, self->spin_joints[j], js)) {
            PyErr_Format(self->error_type, "getJointStates failed for joint %d",
                         self->spin_joints[j]);
            return -1;
        }
        in->rate[j] = js->m_jointVelocity;
    }
    return 0;
}

/* A failed check: keep this substep's Python-API readings (self->check), read through the
 * Python API from now on, and report `why` once (on_mismatch). -1 if the report raised (a
 * warnings filter set to "error"), else 0. */
static int native_fallback(WheelLoop *self, const char *why)
{
    Inputs tmp = self->in;
    self->in = self->check;
    self->check = tmp;
    self->native = self->verify = 0;
    self->mismatch = 1;
    if (self->on_mismatch == NULL)
        return PyErr_WarnEx(PyExc_RuntimeWarning, why, 1);
    PyObject *r = PyObject_CallFunction(self->on_mismatch, "s", why);
    Py_XDECREF(r);
    return r == NULL ? -1 : 0;
}

/* This substep's readings into self->in: natively once verified, else through the Python
 * API. The native readings are compared with the Python API's bit for bit (inputs_differ) on
 * every substep up to the first with a wheel on the ground, then on every verify_every-th
 * substep with contact; the guard regions after the structs pybullet filled are checked on
 * every substep. A failed check switches the loop to the Python API for good
 * (native_fallback). Returns the native client handle to apply the forces through, or NULL for
 * the Python API (check PyErr_Occurred). */
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
    const char *broken = bullet_guard_broken(&self->buf);
    if (failed && !self->verify && broken == NULL)
        return NULL;
    int contact = 0;
    for (int k = 0; k < self->n; k++)
        contact |= self->in.has_patch[k];
    int periodic = 0;
    if (!self->verify && !failed && contact && self->verify_every > 0
        && ++self->contact_substeps >= self->verify_every) {
        self->contact_substeps = 0;
        periodic = 1;
    }
    if (!self->verify && !periodic && broken == NULL)
        return sm;
    PyErr_Clear(); /* a native failure while checking is a mismatch, not an error */
    if (acquire_python(self, &self->check) < 0)
        return NULL;
    self->verifications += 1;
    char why[160], what[64];
    if (broken != NULL)
        PyOS_snprintf(why, sizeof why, "the guard region after %s was overwritten", broken);
    else if (failed)
        PyOS_snprintf(why, sizeof why, "a native query failed where the Python API's did not");
    else if (inputs_differ(&self->in, &self->check, self->n, self->n_spin, what, sizeof what))
        PyOS_snprintf(why, sizeof why, "the native readings differ from the Python API's: %s",
                      what);
    else {
        if (contact)
            self->verify = 0;
        return sm;
    }
    native_fallback(self, why);
    return NULL;
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
            /* off the ground: out of its rut too */
            w->s = w->b = w->rut = w->dug = 0.0;
            w->rut_vec[0] = w->rut_vec[1] = w->rut_vec[2] = 0.0;
            w->force[0] = w->force[1] = w->force[2] = 0.0;
            continue;
        }
        const double *d = &in->link[LINK_WIDTH * k];
        const double *centre = d + 4;
        LawsFrame f;
        if (laws_contact_frame(&in->patch[6 * k], load, d, centre, d + 7, d + 10, &f) < 0) {
            PyErr_Format(PyExc_ZeroDivisionError, "degenerate contact frame at wheel %d", k);
            return -1;
        }
        const double *e = f.e, *l = f.l;
        double v_long = f.v_long;
        double force[3], r_abs;
        if (w->driven) {
            if (w->spin_index < 0 || w->spin_index >= self->n_spin) {
                PyErr_SetString(PyExc_IndexError, "driven wheel without a spin joint state");
                return -1;
            }
            double r_omega = w->r_eff * in->rate[w->spin_index];
            double t_old = w->b, s, t, v_ref, v_lat_ref;
            laws_relax_slip(w->s, t_old, r_omega, v_long, f.v_lat, w->h, w->forward_angle, &s,
                            &t, &v_ref, &v_lat_ref);
            w->s = s;
            w->b = t;
            double f_long, f_lat, res;
            if (wheel_law(w, s, t, load, &f_long, &f_lat, &res) < 0)
                return -1;
            w->fx = f_long;
            w->fy = f_lat;
            if (w->py_kernel == NULL && w->kernel.sinkage_state)
                res += laws_kernel_sinkage_state(&w->kernel, &w->dug, r_omega, v_long, w->h,
                                                 load);
            /* the side damper fades with the leak of the state it damps */
            double d_y = laws_lateral_damping(t - t_old, v_lat_ref, w->d_lat, self->fade_speed);
            double d_x = laws_longitudinal_damping(r_omega, v_long, v_ref, w->c_long,
                                                   self->low_speed);
            f_lat += d_y;
            f_long += d_x;
            /* shear (traction, side force) acts at the contact patch: the motor feels r F */
            queue_force(self, w->link, f_long * e[0] + f_lat * l[0],
                        f_long * e[1] + f_lat * l[1], f_long * e[2] + f_lat * l[2], f.c[0],
                        f.c[1], f.c[2]);
            if (self->multi_pass && multi_pass(self, k, res, load, v_long, &res) < 0)
                return -1;
            /* resistance along the heading, rate-independent (Coulomb-like) */
            double r_k, u_k;
            laws_rut_resistance(res, w->rut, v_long * dt, v_long, stick, w->rut_damping, &r_k,
                                &u_k);
            w->rut = u_k;
            w->damper = fabs(d_x) + fabs(d_y) + fabs(r_k - res * u_k);
            w->res = r_abs = fabs(r_k);
            for (int i = 0; i < 3; i++)
                force[i] = -r_k * e[i];
        } else {
            double fx, fy, res;
            if (wheel_law(w, 0.0, 0.0, load, &fx, &fy, &res) < 0)
                return -1;
            if (self->multi_pass && multi_pass(self, k, res, load, v_long, &res) < 0)
                return -1;
            /* a swivel castor: resistance along its contact velocity (in the contact plane) */
            double vel[3], r[3], u[3], dd[3];
            for (int i = 0; i < 3; i++)
                vel[i] = v_long * e[i] + f.v_side * l[i];
            laws_rut_resistance_vector(res, w->rut_vec, vel, dt, stick, w->rut_damping, r, u);
            for (int i = 0; i < 3; i++) {
                w->rut_vec[i] = u[i];
                dd[i] = r[i] - res * u[i];
                force[i] = -r[i];
            }
            w->res = r_abs = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
            w->damper = sqrt(dd[0] * dd[0] + dd[1] * dd[1] + dd[2] * dd[2]);
        }
        w->force[0] = force[0]; w->force[1] = force[1]; w->force[2] = force[2];
        if (r_abs != 0.0)
            queue_force(self, w->link, force[0], force[1], force[2], centre[0], centre[1],
                        centre[2]);
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

/* bind_native(pybullet_path, clients_offset, n_clients, anchor_offset, verify_every=0,
 * on_mismatch=None): read PyBullet through Bullet's C API from the next substep on, checked
 * against the Python API (acquire). */
static PyObject *loop_bind_native(WheelLoop *self, PyObject *args)
{
    const char *path;
    unsigned long long clients_offset, anchor_offset;
    long n_clients, verify_every = 0;
    PyObject *on_mismatch = Py_None;
    if (!PyArg_ParseTuple(args, "sKlK|lO", &path, &clients_offset, &n_clients, &anchor_offset,
                          &verify_every, &on_mismatch))
        return NULL;
    if (verify_every < 0) {
        PyErr_Format(PyExc_ValueError, "verify_every must be >= 0, got %ld", verify_every);
        return NULL;
    }
    if (on_mismatch != Py_None && !PyCallable_Check(on_mismatch)) {
        PyErr_SetString(PyExc_TypeError, "on_mismatch must be callable or None");
        return NULL;
    }
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
    if (self->buf.link == NULL && bullet_buffers_alloc(&self->buf) < 0)
        return NULL;
    bullet_guards_reset(&self->buf);
    self->api = api;
    self->bound = self->native = self->verify = 1;
    self->mismatch = 0;
    self->verify_every = verify_every;
    self->contact_substeps = self->verifications = 0;
    Py_XDECREF(self->on_mismatch);
    self->on_mismatch = NULL;
    if (on_mismatch != Py_None) {
        Py_INCREF(on_mismatch);
        self->on_mismatch = on_mismatch;
    }
    Py_RETURN_NONE;
}

/* Test hook: overwrite one byte of the guard region after b3LinkState, as a pybullet whose
 * struct is larger than the mirror would. */
static PyObject *loop_scribble_guard(WheelLoop *self, PyObject *unused)
{
    if (self->buf.link == NULL) {
        PyErr_SetString(PyExc_ValueError, "native queries are not bound (bind_native)");
        return NULL;
    }
    unsigned char *guard = (unsigned char *)self->buf.link + sizeof(struct b3LinkState);
    guard[0] ^= 0xFF;
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
FIELD_LIST(dug, PyFloat_FromDouble(w->dug))
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
        bullet_guards_reset(&self->buf);
        self->verify = 1;
        self->mismatch = 0;
        self->contact_substeps = 0;
    }
    self->native = v;
    return 0;
}

static PyObject *get_verify_every(WheelLoop *self, void *closure)
{
    return PyLong_FromLong(self->verify_every);
}

static int set_verify_every(WheelLoop *self, PyObject *value, void *closure)
{
    long v = value ? PyLong_AsLong(value) : -1;
    if (v == -1 && PyErr_Occurred())
        return -1;
    if (v < 0) {
        PyErr_Format(PyExc_ValueError, "verify_every must be >= 0, got %ld", v);
        return -1;
    }
    self->verify_every = v;
    self->contact_substeps = 0;
    return 0;
}

static PyObject *get_native_verifications(WheelLoop *self, void *closure)
{
    return PyLong_FromLong(self->verifications);
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
    {"dug", (getter)get_dug, NULL,
     "depth dug below the static rut per driven wheel [m] (slip sinkage state)", NULL},
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
     "a check of the native reader failed (readings differ from the Python API's, or a guard "
     "region changed), so the loop uses the Python API", NULL},
    {"verify_every", (getter)get_verify_every, (setter)set_verify_every,
     "compare the native readings with the Python API's every this-many substeps with contact "
     "(0: only until the first)", NULL},
    {"native_verifications", (getter)get_native_verifications, NULL,
     "substeps on which the native readings were compared with the Python API's", NULL},
    {NULL, NULL, NULL, NULL, NULL},
};

static PyMethodDef loop_methods[] = {
    {"set_wheel", (PyCFunction)loop_set_wheel, METH_VARARGS,
     "set_wheel(k, driven, spin_index, r_eff, h, c_long, d_lat, rut_damping, lead_front, "
     "lead_back, rut_ratio_front, rut_ratio_back, law, f_r, forward_angle): bind wheel k's "
     "constants and force law (KernelConstants or a Python kernel), once per soil sample."},
    {"reset", (PyCFunction)loop_reset, METH_NOARGS, "Zero every wheel's state."},
    {"apply", (PyCFunction)loop_apply, METH_NOARGS,
     "One substep's forces: query PyBullet, compute, apply."},
    {"bind_native", (PyCFunction)loop_bind_native, METH_VARARGS,
     "bind_native(pybullet_path, clients_offset, n_clients, anchor_offset, verify_every=0, "
     "on_mismatch=None): read PyBullet through Bullet's C API (slipenv.sim.bullet_native)."},
    {"_scribble_guard", (PyCFunction)loop_scribble_guard, METH_NOARGS,
     "Test hook: overwrite the guard region after b3LinkState (a detected mismatch)."},
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

static struct PyModuleDef module_def = {
    PyModuleDef_HEAD_INIT, "_wheel_loop",
    "The per-substep wheel-soil loop (see WheelLoop); the laws are _laws.h's.", -1, NULL,
};

PyMODINIT_FUNC PyInit__wheel_loop(void)
{
    if (PyType_Ready(&WheelLoopType) < 0)
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
