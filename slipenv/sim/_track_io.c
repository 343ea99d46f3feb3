/* Native PyBullet reads and force commands of the Wong-Chiang track injector
 * (slipenv.sim.track_soil.TrackSoilInjector).
 *
 * The track model's physics is not here: it is slipenv/terramechanics/track.py, compiled with
 * numba. Per substep the injector needs the road wheels' contact loads, the hull's pose and
 * twist and the road wheels' spin rates, and then applies one force per road wheel and a few
 * on the hull. Through pybullet's Python functions that costs several times the compiled law,
 * so this module submits the same server commands through Bullet's client C API, as the
 * wheel loop does (bullet_native.h: the struct mirrors, the client table, the guard regions):
 * one contact query filtered on body and ground, one actual-state request (base position and
 * orientation, base velocity and joint states all come from it, as pybullet's
 * getBasePositionAndOrientation, getBaseVelocity and getJointStates read them) and one
 * applyExternalForce/Torque command per force. The injector compares these readings with the
 * Python API's bit for bit (on the first substep with contact and then periodically) and reads
 * through the Python API for good after a mismatch or a broken guard. The module also gives
 * the compiled substep the address of the wheels' slip-sinkage law (_laws.h).
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <string.h>

#include "_laws.h"
#include "bullet_native.h"

/* The wheels' slip-sinkage law (Lyasko, _laws.h), for the compiled track substep: numba calls
 * it by address (slip_sinkage_factor_address), so the track uses the one C text. */
static double track_io_slip_sinkage_factor(double slip)
{
    return laws_slip_sinkage_factor(slip);
}

typedef struct {
    PyObject_HEAD
    long client, body, ground, world;
    int n, n_spin, max_link;
    int *link_to_wheel; /* link + 1 -> road wheel, -1 */
    int *spin_joints;
    BulletApi api;
    int (*actual_state)(b3Handle, int *, int *, int *, const double **, const double **,
                        const double **, const double **);
    void (*torque)(b3Handle, int, int, const double *, int);
    BulletBuffers buf;
    int bound;
} TrackIO;

static void io_dealloc(TrackIO *self)
{
    bullet_buffers_free(&self->buf);
    PyMem_Free(self->link_to_wheel);
    PyMem_Free(self->spin_joints);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static int int_list(PyObject *list, int **out, int *n, long lo)
{
    if (!PyList_Check(list)) {
        PyErr_SetString(PyExc_TypeError, "expected a list of ints");
        return -1;
    }
    *n = (int)PyList_GET_SIZE(list);
    *out = PyMem_Calloc(*n > 0 ? *n : 1, sizeof(int));
    if (*out == NULL) {
        PyErr_NoMemory();
        return -1;
    }
    for (int i = 0; i < *n; i++) {
        long v = PyLong_AsLong(PyList_GET_ITEM(list, i));
        if (v == -1 && PyErr_Occurred())
            return -1;
        if (v < lo || v > 100000) {
            PyErr_Format(PyExc_ValueError, "index %ld out of range", v);
            return -1;
        }
        (*out)[i] = (int)v;
    }
    return 0;
}

/* TrackIO(client, body, ground, world_frame, links, spin_joints) */
static int io_init(TrackIO *self, PyObject *args, PyObject *kwds)
{
    PyObject *links, *spin;
    if (!PyArg_ParseTuple(args, "llllOO", &self->client, &self->body, &self->ground,
                          &self->world, &links, &spin))
        return -1;
    int *link_ids = NULL;
    if (int_list(links, &link_ids, &self->n, -1) < 0
        || int_list(spin, &self->spin_joints, &self->n_spin, 0) < 0) {
        PyMem_Free(link_ids);
        return -1;
    }
    self->max_link = -1;
    for (int k = 0; k < self->n; k++)
        if (link_ids[k] > self->max_link)
            self->max_link = link_ids[k];
    self->link_to_wheel = PyMem_Malloc(sizeof(int) * (self->max_link + 2));
    if (self->link_to_wheel == NULL) {
        PyMem_Free(link_ids);
        PyErr_NoMemory();
        return -1;
    }
    for (int i = 0; i < self->max_link + 2; i++)
        self->link_to_wheel[i] = -1;
    for (int k = 0; k < self->n; k++)
        self->link_to_wheel[link_ids[k] + 1] = k;
    PyMem_Free(link_ids);
    return 0;
}

/* bind(pybullet_path, clients_offset, n_clients, anchor_offset): as WheelLoop.bind_native. */
static PyObject *io_bind(TrackIO *self, PyObject *args)
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
#if BULLET_NATIVE_AVAILABLE
    void *lib = dlopen(path, RTLD_NOW | RTLD_NOLOAD);
    if (lib == NULL) {
        PyErr_Format(PyExc_OSError, "pybullet is not loaded from %s", path);
        return NULL;
    }
    void *state = dlsym(lib, "b3GetStatusActualState");
    void *torque = dlsym(lib, "b3ApplyExternalTorque");
    dlclose(lib);
    if (state == NULL || torque == NULL) {
        PyErr_Format(PyExc_OSError, "%s does not export the actual-state and torque calls", path);
        return NULL;
    }
    *(void **)(&self->actual_state) = state;
    *(void **)(&self->torque) = torque;
#endif
    if (bullet_client(&api, self->client) == NULL) {
        PyErr_Format(PyExc_OSError, "client %ld is not in pybullet's client table", self->client);
        return NULL;
    }
    if (self->buf.link == NULL && bullet_buffers_alloc(&self->buf) < 0)
        return NULL;
    bullet_guards_reset(&self->buf);
    self->api = api;
    self->bound = 1;
    Py_RETURN_NONE;
}

static b3Handle io_client(TrackIO *self)
{
    if (!self->bound) {
        PyErr_SetString(PyExc_ValueError, "native queries are not bound (bind)");
        return NULL;
    }
    b3Handle sm = bullet_client(&self->api, self->client);
    if (sm == NULL)
        PyErr_SetString(PyExc_RuntimeError, "Not connected to physics server.");
    return sm;
}

static int writable(PyObject *obj, Py_buffer *view, Py_ssize_t n_doubles)
{
    if (PyObject_GetBuffer(obj, view, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0)
        return -1;
    if (view->itemsize != sizeof(double) || strcmp(view->format, "d") != 0
        || view->len < n_doubles * (Py_ssize_t)sizeof(double)) {
        PyBuffer_Release(view);
        PyErr_Format(PyExc_ValueError, "expected a contiguous float64 buffer of %zd values",
                     n_doubles);
        return -1;
    }
    return 0;
}

/* read(out): out[0:3] base position, [3:7] orientation, [7:10] linear and [10:13] angular
 * velocity (world frame), [13:13+n] each road wheel's load (the sum of its positive normal
 * forces, in the server's order), then the spin joints' velocities, then 1.0 if a link that is
 * not a road wheel touched the ground, else 0.0. Returns 1 if a road wheel is loaded, else 0,
 * or the name of the struct whose guard region was overwritten (the guards are then reset). */
static PyObject *io_read(TrackIO *self, PyObject *arg)
{
    b3Handle sm = io_client(self);
    if (sm == NULL)
        return NULL;
    Py_buffer view;
    if (writable(arg, &view, 14 + self->n + self->n_spin) < 0)
        return NULL;
    double *out = (double *)view.buf;
    const BulletApi *api = &self->api;
    b3Handle cmd = api->init_contacts(sm);
    api->filter_body_a(cmd, (int)self->body);
    api->filter_body_b(cmd, (int)self->ground);
    api->submit(sm, cmd);
    struct b3ContactInformation *info = self->buf.contacts;
    api->contacts(sm, info);
    double *load = out + 13;
    double chassis = 0.0;
    for (int k = 0; k < self->n; k++)
        load[k] = 0.0;
    for (int i = 0; i < info->m_numContactPoints; i++) {
        const struct b3ContactPointData *cp = &info->m_contactPointData[i];
        double f = cp->m_normalForce;
        if (f <= 0.0)
            continue;
        int link = cp->m_linkIndexA;
        int k = (link >= -1 && link <= self->max_link) ? self->link_to_wheel[link + 1] : -1;
        if (k < 0)
            chassis = 1.0;
        else
            load[k] += f;
    }
    cmd = api->init_state(sm, (int)self->body);
    b3Handle status = api->submit(sm, cmd);
    const double *q = NULL, *qdot = NULL;
    if (!self->actual_state(status, NULL, NULL, NULL, NULL, &q, &qdot, NULL) || q == NULL
        || qdot == NULL) {
        PyBuffer_Release(&view);
        PyErr_SetString(PyExc_RuntimeError, "getBasePositionAndOrientation failed");
        return NULL;
    }
    memcpy(out, q, 7 * sizeof(double));
    memcpy(out + 7, qdot, 6 * sizeof(double));
    struct b3JointSensorState *js = self->buf.joint;
    double *rate = load + self->n;
    for (int j = 0; j < self->n_spin; j++) {
        if (!api->joint_state(sm, status, self->spin_joints[j], js)) {
            PyBuffer_Release(&view);
            PyErr_Format(PyExc_RuntimeError, "getJointStates failed for joint %d",
                         self->spin_joints[j]);
            return NULL;
        }
        rate[j] = js->m_jointVelocity;
    }
    rate[self->n_spin] = chassis;
    PyBuffer_Release(&view);
    const char *broken = bullet_guard_broken(&self->buf);
    if (broken != NULL) {
        bullet_guards_reset(&self->buf);
        return PyUnicode_FromString(broken);
    }
    int contact = 0;
    for (int k = 0; k < self->n; k++)
        contact |= load[k] > 0.0;
    return PyLong_FromLong(contact);
}

/* apply(rows, count): the first `count` rows of a (m, 8) float64 array, each [link, kind, x,
 * y, z, px, py, pz]: kind 0 a force (x, y, z) at the point (px, py, pz), kind 1 a torque, all
 * in the world frame; one command each, in order (as pybullet's applyExternalForce: a batched
 * command would store the forces at the wrong offsets, see _wheel_loop.c). */
static PyObject *io_apply(TrackIO *self, PyObject *args)
{
    PyObject *obj;
    Py_ssize_t count;
    if (!PyArg_ParseTuple(args, "On", &obj, &count))
        return NULL;
    b3Handle sm = io_client(self);
    if (sm == NULL)
        return NULL;
    Py_buffer view;
    if (writable(obj, &view, 8 * count) < 0)
        return NULL;
    const double *rows = (const double *)view.buf;
    for (Py_ssize_t i = 0; i < count; i++) {
        const double *r = rows + 8 * i;
        b3Handle cmd = self->api.init_force(sm);
        if (r[1] == 0.0)
            self->api.force(cmd, (int)self->body, (int)r[0], r + 2, r + 5, (int)self->world);
        else
            self->torque(cmd, (int)self->body, (int)r[0], r + 2, (int)self->world);
        self->api.submit(sm, cmd);
    }
    PyBuffer_Release(&view);
    Py_RETURN_NONE;
}

/* Test hook: overwrite one byte of the guard region after b3ContactInformation. */
static PyObject *io_scribble_guard(TrackIO *self, PyObject *unused)
{
    if (!self->bound) {
        PyErr_SetString(PyExc_ValueError, "native queries are not bound (bind)");
        return NULL;
    }
    ((unsigned char *)self->buf.contacts + sizeof(struct b3ContactInformation))[0] ^= 0xFF;
    Py_RETURN_NONE;
}

static PyMethodDef io_methods[] = {
    {"bind", (PyCFunction)io_bind, METH_VARARGS,
     "bind(pybullet_path, clients_offset, n_clients, anchor_offset): Bullet's C API."},
    {"read", (PyCFunction)io_read, METH_O,
     "read(out): this substep's readings into out; 1 with contact, 0 without, or the name "
     "of the struct whose guard region was overwritten"},
    {"apply", (PyCFunction)io_apply, METH_VARARGS,
     "apply(rows, count): apply the first count force/torque rows."},
    {"scribble_guard", (PyCFunction)io_scribble_guard, METH_NOARGS,
     "test hook: break the guard after b3ContactInformation"},
    {NULL, NULL, 0, NULL},
};

static PyTypeObject TrackIOType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "slipenv.sim._track_io.TrackIO",
    .tp_basicsize = sizeof(TrackIO),
    .tp_dealloc = (destructor)io_dealloc,
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "Native reads and force commands of one tracked vehicle's injector.",
    .tp_methods = io_methods,
    .tp_init = (initproc)io_init,
    .tp_new = PyType_GenericNew,
};

static struct PyModuleDef module_def = {
    PyModuleDef_HEAD_INIT, "_track_io",
    "Native PyBullet reads and force commands of the Wong-Chiang track injector.", -1, NULL,
};

PyMODINIT_FUNC PyInit__track_io(void)
{
    if (PyType_Ready(&TrackIOType) < 0)
        return NULL;
    PyObject *m = PyModule_Create(&module_def);
    if (m == NULL)
        return NULL;
    Py_INCREF(&TrackIOType);
    if (PyModule_AddObject(m, "TrackIO", (PyObject *)&TrackIOType) < 0) {
        Py_DECREF(&TrackIOType);
        Py_DECREF(m);
        return NULL;
    }
    PyObject *address = PyLong_FromVoidPtr((void *)&track_io_slip_sinkage_factor);
    if (address == NULL || PyModule_AddObject(m, "slip_sinkage_factor_address", address) < 0) {
        Py_XDECREF(address);
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
