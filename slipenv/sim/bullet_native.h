/* Native access to a pybullet physics client through Bullet's C API.
 *
 * pybullet's Python functions are thin wrappers over Bullet's client C API
 * (examples/SharedMemory/PhysicsClientC_API.h): each one builds a command, submits it to the
 * physics server and turns the status into Python tuples. The module exports that C API
 * (b3InitRequestContactPointInformation, b3GetLinkState, b3ApplyExternalForce, ...), so a kernel
 * can submit the same commands and read the same doubles without building any Python object.
 * The one thing it needs is the client handle behind a client id, which pybullet keeps in its
 * static table sPhysicsClients1; slipenv.sim.bullet_native finds that table's offset in the
 * module's ELF symbol table and passes it here.
 *
 * The structs below mirror SharedMemoryPublic.h of the pybullet releases listed in
 * slipenv.sim.bullet_native.NATIVE_PYBULLET_VERSIONS (the only ones bound). Two checks catch a
 * layout that does not match all the same: every struct pybullet fills lives on the heap,
 * followed by a guard region of BULLET_GUARD_BYTES canary bytes checked after each substep's
 * calls (a larger struct in pybullet writes into it); and the loop compares its native readings
 * with the Python API's bit for bit, in every value it acts on (inputs_differ in
 * _wheel_loop.c), until the first substep with contact, then on every verify_every-th substep
 * with contact. Either check failing switches the loop to the Python API
 * (WheelLoop.native_mismatch). pybullet's array of contact points is read in place with the
 * mirror's stride, so a b3ContactPointData of another size shows in the readings, where the
 * comparisons catch it.
 */
#ifndef SLIPENV_BULLET_NATIVE_H
#define SLIPENV_BULLET_NATIVE_H

#ifndef _WIN32
#ifndef _GNU_SOURCE
#define _GNU_SOURCE /* dladdr */
#endif
#include <dlfcn.h>
#define BULLET_NATIVE_AVAILABLE 1
#else
#define BULLET_NATIVE_AVAILABLE 0
#endif

typedef void *b3Handle;

struct b3ContactPointData {
    int m_contactFlags;
    int m_bodyUniqueIdA;
    int m_bodyUniqueIdB;
    int m_linkIndexA;
    int m_linkIndexB;
    double m_positionOnAInWS[3];
    double m_positionOnBInWS[3];
    double m_contactNormalOnBInWS[3];
    double m_contactDistance;
    double m_normalForce;
    double m_linearFrictionForce1;
    double m_linearFrictionForce2;
    double m_linearFrictionDirection1[3];
    double m_linearFrictionDirection2[3];
};

struct b3ContactInformation {
    int m_numContactPoints;
    struct b3ContactPointData *m_contactPointData;
};

struct b3LinkState {
    double m_worldPosition[3];
    double m_worldOrientation[4];
    double m_localInertialPosition[3];
    double m_localInertialOrientation[4];
    double m_worldLinkFramePosition[3];
    double m_worldLinkFrameOrientation[4];
    double m_worldLinearVelocity[3];
    double m_worldAngularVelocity[3];
    double m_worldAABBMin[3];
    double m_worldAABBMax[3];
};

struct b3JointSensorState {
    double m_jointPosition;
    double m_jointVelocity;
    double m_jointForceTorque[6];
    double m_jointMotorTorque;
};

/* Bytes of canary after each struct pybullet fills: a struct grown by up to this much in a
 * pybullet build writes only into the guard, where the check finds it. */
#define BULLET_GUARD_BYTES 512

/* The canary: a byte sequence no store of ints or doubles reproduces by chance. */
static unsigned char bullet_canary[BULLET_GUARD_BYTES];

static void bullet_canary_init(void)
{
    for (int i = 0; i < BULLET_GUARD_BYTES; i++)
        bullet_canary[i] = (unsigned char)(0xA5 ^ (i * 0x3B) ^ (i >> 3));
}

/* The structs pybullet fills, each followed by its guard region (heap, one block each). */
typedef struct {
    struct b3ContactInformation *contacts;
    struct b3LinkState *link;
    struct b3JointSensorState *joint;
} BulletBuffers;

static void *bullet_guarded_alloc(size_t size)
{
    unsigned char *buf = PyMem_Malloc(size + BULLET_GUARD_BYTES);
    if (buf != NULL) {
        memset(buf, 0, size);
        memcpy(buf + size, bullet_canary, BULLET_GUARD_BYTES);
    }
    return buf;
}

static void bullet_buffers_free(BulletBuffers *b)
{
    PyMem_Free(b->contacts);
    PyMem_Free(b->link);
    PyMem_Free(b->joint);
    b->contacts = NULL;
    b->link = NULL;
    b->joint = NULL;
}

/* 0 on success, -1 with MemoryError set. */
static int bullet_buffers_alloc(BulletBuffers *b)
{
    bullet_canary_init();
    b->contacts = bullet_guarded_alloc(sizeof(struct b3ContactInformation));
    b->link = bullet_guarded_alloc(sizeof(struct b3LinkState));
    b->joint = bullet_guarded_alloc(sizeof(struct b3JointSensorState));
    if (b->contacts == NULL || b->link == NULL || b->joint == NULL) {
        bullet_buffers_free(b);
        PyErr_NoMemory();
        return -1;
    }
    return 0;
}

/* Restore every guard region (after a detected mismatch, before native reads resume). */
static void bullet_guards_reset(BulletBuffers *b)
{
    memcpy((unsigned char *)b->contacts + sizeof(struct b3ContactInformation), bullet_canary,
           BULLET_GUARD_BYTES);
    memcpy((unsigned char *)b->link + sizeof(struct b3LinkState), bullet_canary,
           BULLET_GUARD_BYTES);
    memcpy((unsigned char *)b->joint + sizeof(struct b3JointSensorState), bullet_canary,
           BULLET_GUARD_BYTES);
}

/* The name of the first struct whose guard region changed, or NULL if all are intact. */
static const char *bullet_guard_broken(const BulletBuffers *b)
{
    if (memcmp((const unsigned char *)b->contacts + sizeof(struct b3ContactInformation),
               bullet_canary, BULLET_GUARD_BYTES) != 0)
        return "b3ContactInformation";
    if (memcmp((const unsigned char *)b->link + sizeof(struct b3LinkState), bullet_canary,
               BULLET_GUARD_BYTES) != 0)
        return "b3LinkState";
    if (memcmp((const unsigned char *)b->joint + sizeof(struct b3JointSensorState),
               bullet_canary, BULLET_GUARD_BYTES) != 0)
        return "b3JointSensorState";
    return NULL;
}

typedef struct {
    b3Handle *clients; /* pybullet's sPhysicsClients1 */
    long n_clients;    /* its length (MAX_PHYSICS_CLIENTS) */
    int (*can_submit)(b3Handle);
    b3Handle (*submit)(b3Handle, b3Handle);
    int (*status_type)(b3Handle);
    b3Handle (*init_contacts)(b3Handle);
    void (*filter_body_a)(b3Handle, int);
    void (*filter_body_b)(b3Handle, int);
    void (*contacts)(b3Handle, struct b3ContactInformation *);
    b3Handle (*init_state)(b3Handle, int);
    int (*link_velocity)(b3Handle, int);
    int (*link_state)(b3Handle, b3Handle, int, struct b3LinkState *);
    int (*joint_state)(b3Handle, b3Handle, int, struct b3JointSensorState *);
    b3Handle (*init_force)(b3Handle);
    void (*force)(b3Handle, int, int, const double *, const double *, int);
} BulletApi;

/* Bind `api` to the loaded pybullet module at `path`: its exported C API, and its client
 * table at `clients_offset` from the module's load address (`anchor_offset` is the symbol
 * offset of b3CanSubmitCommand, whose address gives the load address). 0 on success, -1 with
 * a Python OSError set. */
static int bullet_api_bind(BulletApi *api, const char *path, unsigned long long clients_offset,
                           long n_clients, unsigned long long anchor_offset)
{
#if BULLET_NATIVE_AVAILABLE
    void *lib = dlopen(path, RTLD_NOW | RTLD_NOLOAD);
    if (lib == NULL) {
        PyErr_Format(PyExc_OSError, "pybullet is not loaded from %s", path);
        return -1;
    }
#define BIND(FIELD, NAME)                                                                  \
    do {                                                                                   \
        void *sym = dlsym(lib, NAME);                                                      \
        if (sym == NULL) {                                                                 \
            dlclose(lib);                                                                  \
            PyErr_Format(PyExc_OSError, "%s does not export %s", path, NAME);              \
            return -1;                                                                     \
        }                                                                                  \
        *(void **)(&api->FIELD) = sym;                                                     \
    } while (0)
    BIND(can_submit, "b3CanSubmitCommand");
    BIND(submit, "b3SubmitClientCommandAndWaitStatus");
    BIND(status_type, "b3GetStatusType");
    BIND(init_contacts, "b3InitRequestContactPointInformation");
    BIND(filter_body_a, "b3SetContactFilterBodyA");
    BIND(filter_body_b, "b3SetContactFilterBodyB");
    BIND(contacts, "b3GetContactPointInformation");
    BIND(init_state, "b3RequestActualStateCommandInit");
    BIND(link_velocity, "b3RequestActualStateCommandComputeLinkVelocity");
    BIND(link_state, "b3GetLinkState");
    BIND(joint_state, "b3GetJointState");
    BIND(init_force, "b3ApplyExternalForceCommandInit");
    BIND(force, "b3ApplyExternalForce");
#undef BIND
    char *base = (char *)*(void **)(&api->can_submit) - anchor_offset;
    /* The offsets come from the file at `path`; the loaded module must be that file. */
    Dl_info info;
    if (!dladdr(*(void **)(&api->can_submit), &info) || (char *)info.dli_fbase != base) {
        dlclose(lib);
        PyErr_Format(PyExc_OSError, "the pybullet module loaded is not the file %s", path);
        return -1;
    }
    api->clients = (b3Handle *)(base + clients_offset);
    api->n_clients = n_clients;
    /* pybullet's own import holds the module loaded; drop the reference dlopen added. */
    dlclose(lib);
    return 0;
#else
    (void)api; (void)path; (void)clients_offset; (void)n_clients; (void)anchor_offset;
    PyErr_SetString(PyExc_OSError, "native PyBullet access is not built on this platform");
    return -1;
#endif
}

/* The handle of client `client`, or NULL (no Python error set) if it is not connected. */
static b3Handle bullet_client(const BulletApi *api, long client)
{
    if (client < 0 || client >= api->n_clients)
        return NULL;
    b3Handle sm = api->clients[client];
    if (sm == NULL || !api->can_submit(sm))
        return NULL;
    return sm;
}

#endif
