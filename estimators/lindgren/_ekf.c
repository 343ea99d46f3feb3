/* Compiled arithmetic of the Lindgren EKF (issue 15, item 3): the prediction (Lindgren Eq. 6-7
 * with the process model of Eq. 13) and the bearing (Eq. 17), inertial and inclinometer
 * (Eq. 14) and odometric (Eq. 15-16, 37-41) Kalman updates (Eq. 8-11) of
 * slipenv.estimators.lindgren.ekf.LindgrenEKF, in place on the filter's float64 buffers:
 * predict, update_bearing, update_inertial, update_odometry, one call each per use.
 *
 * The numpy methods of LindgrenEKF stay the reference and the fallback; this module is only the
 * same arithmetic without numpy's per-call overhead (~0.5 us per call on 13 x 13 arrays, which
 * is what the numpy filter costs). Every formula below is the numpy method's, term by term in
 * the same order, so f(x), F and Q are bit-for-bit those of models.process_fx / process_F /
 * process_Q (tested); the matrix products sum in a different order from BLAS, so x and P differ
 * from the numpy filter in rounding only (tested to 1e-9 relative over a FarmField-length run,
 * tests/estimators/test_lindgren_compiled.py). Built with -ffp-contract=off (no fused a*b+c).
 * The Python side keeps the bookkeeping: frame validation, skip counts, history, restoring the
 * state of a failed frame.
 *
 * Plain CPython C API with the buffer protocol: no numpy headers. Buffers must be C-contiguous
 * float64 arrays (the filter's own); format and length are checked (TypeError, ValueError).
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <string.h>

#define NMAX 13
/* state layout of models.py */
#define IX 0
#define IY 1
#define ITH 2
#define IV 3
#define IOM 4
#define IVD 5
#define IOMD 6
#define IA1 7
#define IA2 8
#define IRL 9
#define IRR 10
#define IKL 11
#define IKR 12

static const double PI = 3.141592653589793;
static const double TWO_PI = 6.283185307179586;

/* Python's float modulo (Objects/floatobject.c, float_rem): the sign of the divisor. */
static double py_mod(double vx, double wx) {
    double mod = fmod(vx, wx);
    if (mod != 0.0) {
        if ((wx < 0) != (mod < 0)) mod += wx;
    } else {
        mod = copysign(0.0, wx);
    }
    return mod;
}

/* slipenv.contracts.wrap_angle: pi - (pi - a) % 2 pi, to (-pi, pi]. */
static double wrap_angle(double a) { return PI - py_mod(PI - a, TWO_PI); }

/* ---- argument helpers ------------------------------------------------------------------- */

static int is_float64(const Py_buffer *view) {
    const char *f = view->format;
    return view->itemsize == (Py_ssize_t)sizeof(double) && f != NULL &&
           (strcmp(f, "d") == 0 || strcmp(f, "=d") == 0 || strcmp(f, "@d") == 0);
}

static int get_buf_flags(PyObject *obj, Py_buffer *view, Py_ssize_t n_doubles,
                         const char *name, int flags) {
    if (PyObject_GetBuffer(obj, view, flags | PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0) return -1;
    if (!is_float64(view)) {
        PyErr_Format(PyExc_TypeError, "%s must be a float64 array", name);
        PyBuffer_Release(view);
        return -1;
    }
    if (view->len != n_doubles * (Py_ssize_t)sizeof(double)) {
        PyErr_Format(PyExc_ValueError, "%s must hold %zd float64 values, got %zd bytes", name,
                     n_doubles, view->len);
        PyBuffer_Release(view);
        return -1;
    }
    return 0;
}

static int get_buf(PyObject *obj, Py_buffer *view, Py_ssize_t n_doubles, const char *name) {
    return get_buf_flags(obj, view, n_doubles, name, PyBUF_WRITABLE);
}

/* x (n) and P (n, n) with n = 9 or 13 from x's length. */
static int get_xP(PyObject *xo, PyObject *Po, Py_buffer *xb, Py_buffer *Pb, int *n) {
    if (PyObject_GetBuffer(xo, xb, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0)
        return -1;
    if (!is_float64(xb)) {
        PyErr_SetString(PyExc_TypeError, "x must be a float64 array");
        PyBuffer_Release(xb);
        return -1;
    }
    Py_ssize_t len = xb->len / (Py_ssize_t)sizeof(double);
    if ((len != 9 && len != NMAX) || xb->len % (Py_ssize_t)sizeof(double)) {
        PyErr_SetString(PyExc_ValueError, "x must hold 9 or 13 float64 values");
        PyBuffer_Release(xb);
        return -1;
    }
    *n = (int)len;
    if (get_buf(Po, Pb, len * len, "P") < 0) {
        PyBuffer_Release(xb);
        return -1;
    }
    return 0;
}

static int get_doubles(PyObject *const *args, Py_ssize_t start, Py_ssize_t count, double *out) {
    for (Py_ssize_t i = 0; i < count; i++) {
        out[i] = PyFloat_AsDouble(args[start + i]);
        if (out[i] == -1.0 && PyErr_Occurred()) return -1;
    }
    return 0;
}

static int check_nargs(Py_ssize_t nargs, Py_ssize_t want, const char *fname) {
    if (nargs != want) {
        PyErr_Format(PyExc_TypeError, "%s takes %zd arguments (%zd given)", fname, want, nargs);
        return -1;
    }
    return 0;
}

/* ---- prediction ------------------------------------------------------------------------- */

/* LindgrenEKF._process: f(x) into x, F and Q into their buffers (all n x n entries). */
static void process(int n, double *xs, double *F, double *Q, double tau, const double *qp) {
    double qv = qp[0], qw = qp[1], tilt_psd = qp[2], radius_var = qp[3], ks_rel_var = qp[4];
    double px = xs[IX], py = xs[IY], th = xs[ITH], v = xs[IV], om = xs[IOM], vd = xs[IVD],
           omd = xs[IOMD], a1 = xs[IA1], a2 = xs[IA2];
    double ht = 0.5 * tau;
    double tt = ht * tau;
    double v_bar = v + ht * vd;
    double dth = tau * (om + ht * omd);
    double th_mid = th + 0.5 * dth;
    double c = cos(th_mid), s = sin(th_mid);
    double cd = cos(dth), sd = sin(dth);
    double da1 = -sd * a1 - cd * a2;
    double da2 = cd * a1 - sd * a2;
    double tv = tau * v_bar;
    double ntvs = -tau * v_bar * s;
    double tvc = tv * c;
    memset(F, 0, sizeof(double) * n * n);
    for (int i = 0; i < n; i++) F[i * n + i] = 1.0;
#define AT(M, i, j) M[(i) * n + (j)]
    AT(F, IX, ITH) = ntvs;
    AT(F, IX, IV) = tau * c;
    AT(F, IX, IVD) = tt * c;
    AT(F, IX, IOM) = ntvs * 0.5 * tau;
    AT(F, IX, IOMD) = ntvs * 0.25 * tau * tau;
    AT(F, IY, ITH) = tvc;
    AT(F, IY, IV) = tau * s;
    AT(F, IY, IVD) = tt * s;
    AT(F, IY, IOM) = tvc * 0.5 * tau;
    AT(F, IY, IOMD) = tvc * 0.25 * tau * tau;
    AT(F, ITH, IOM) = tau;
    AT(F, ITH, IOMD) = tt;
    AT(F, IV, IVD) = tau;
    AT(F, IOM, IOMD) = tau;
    AT(F, IA1, IA1) = cd;
    AT(F, IA1, IA2) = -sd;
    AT(F, IA2, IA1) = sd;
    AT(F, IA2, IA2) = cd;
    AT(F, IA1, IOM) = tau * da1;
    AT(F, IA1, IOMD) = tt * da1;
    AT(F, IA2, IOM) = tau * da2;
    AT(F, IA2, IOMD) = tt * da2;
    xs[IX] = px + tvc;
    xs[IY] = py + tv * s;
    xs[ITH] = wrap_angle(th + dth);
    xs[IV] = v + tau * vd;
    xs[IOM] = om + tau * omd;
    xs[IVD] = vd;
    xs[IOMD] = omd;
    xs[IA1] = cd * a1 - sd * a2;
    xs[IA2] = sd * a1 + cd * a2;
    /* process_Q: white jerk on the along-track and yaw chains, tilt random walks */
    double t2 = tau * tau;
    double t3 = t2 * tau;
    double b00 = t3 * t2 / 20.0, b01 = t2 * t2 / 8.0, b02 = t3 / 6.0;
    double b11 = t3 / 3.0, b12 = t2 / 2.0;
    double q00 = qv * b00, q01 = qv * b01, q02 = qv * b02;
    double q_tilt = tilt_psd * tau;
    double qu0 = q01 * c, qu1 = q01 * s, qu2 = q02 * c, qu3 = q02 * s;
    memset(Q, 0, sizeof(double) * n * n);
    AT(Q, 0, 0) = q00 * (c * c);
    AT(Q, 0, 1) = q00 * (c * s);
    AT(Q, 1, 0) = q00 * (s * c);
    AT(Q, 1, 1) = q00 * (s * s);
    AT(Q, 0, IV) = qu0;
    AT(Q, 1, IV) = qu1;
    AT(Q, 0, IVD) = qu2;
    AT(Q, 1, IVD) = qu3;
    AT(Q, IV, IV) = qv * b11;
    AT(Q, IV, IVD) = qv * b12;
    AT(Q, IVD, IV) = qv * b12;
    AT(Q, IVD, IVD) = qv * tau;
    AT(Q, ITH, ITH) = qw * b00;
    AT(Q, ITH, IOM) = qw * b01;
    AT(Q, ITH, IOMD) = qw * b02;
    AT(Q, IOM, ITH) = qw * b01;
    AT(Q, IOM, IOM) = qw * b11;
    AT(Q, IOM, IOMD) = qw * b12;
    AT(Q, IOMD, ITH) = qw * b02;
    AT(Q, IOMD, IOM) = qw * b12;
    AT(Q, IOMD, IOMD) = qw * tau;
    AT(Q, IA1, IA1) = q_tilt;
    AT(Q, IA2, IA2) = q_tilt;
    AT(Q, IV, 0) = qu0;
    AT(Q, IV, 1) = qu1;
    AT(Q, IVD, 0) = qu2;
    AT(Q, IVD, 1) = qu3;
    if (n == NMAX) {
        double d = fabs(v_bar) * tau;
        double q_r = radius_var * d;
        AT(Q, IRL, IRL) = q_r;
        AT(Q, IRR, IRR) = q_r;
        AT(Q, IKL, IKL) = ks_rel_var * d * (xs[IKL] * xs[IKL]);
        AT(Q, IKR, IKR) = ks_rel_var * d * (xs[IKR] * xs[IKR]);
    }
#undef AT
}

/* predict(x, P, F, Q, tau, jerk_psd_v, jerk_psd_omega, tilt_psd, radius_var_per_m,
 *         k_s_rel_var_per_m) -> None
 * x <- f(x); F, Q <- the Jacobian and process noise over tau; P <- sym(F P F' + Q). */
static PyObject *predict(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    if (check_nargs(nargs, 10, "predict") < 0) return NULL;
    double pars[6];
    if (get_doubles(args, 4, 6, pars) < 0) return NULL;
    Py_buffer xb, Pb, Fb, Qb;
    int n;
    if (get_xP(args[0], args[1], &xb, &Pb, &n) < 0) return NULL;
    if (get_buf(args[2], &Fb, (Py_ssize_t)n * n, "F") < 0) goto fail_xP;
    if (get_buf(args[3], &Qb, (Py_ssize_t)n * n, "Q") < 0) goto fail_F;
    {
        double *x = xb.buf, *P = Pb.buf, *F = Fb.buf, *Q = Qb.buf;
        double M[NMAX * NMAX], N[NMAX * NMAX];
        int nnz[NMAX], col[NMAX][NMAX];  /* the non-zeros of each row of F, in column order */
        double val[NMAX][NMAX];
        process(n, x, F, Q, pars[0], pars + 1);
        for (int i = 0; i < n; i++) {
            nnz[i] = 0;
            for (int k = 0; k < n; k++)
                if (F[i * n + k] != 0.0) {
                    col[i][nnz[i]] = k;
                    val[i][nnz[i]++] = F[i * n + k];
                }
        }
        /* M = F P over F's non-zeros (at most 6 a row; an exact zero would add 0 * finite) */
        for (int i = 0; i < n; i++) {
            double *mi = M + i * n;
            for (int j = 0; j < n; j++) mi[j] = 0.0;
            for (int e = 0; e < nnz[i]; e++) {
                double f = val[i][e];
                const double *pk = P + col[i][e] * n;
                for (int j = 0; j < n; j++) mi[j] += f * pk[j];
            }
        }
        /* N = M F' + Q */
        for (int i = 0; i < n; i++) {
            const double *mi = M + i * n;
            for (int j = 0; j < n; j++) {
                double acc = 0.0;
                for (int e = 0; e < nnz[j]; e++) acc += mi[col[j][e]] * val[j][e];
                N[i * n + j] = acc + Q[i * n + j];
            }
        }
        for (int i = 0; i < n; i++)
            for (int j = i; j < n; j++) {
                double v = 0.5 * (N[i * n + j] + N[j * n + i]);
                P[i * n + j] = v;
                P[j * n + i] = v;
            }
    }
    PyBuffer_Release(&Qb);
    PyBuffer_Release(&Fb);
    PyBuffer_Release(&Pb);
    PyBuffer_Release(&xb);
    Py_RETURN_NONE;
fail_F:
    PyBuffer_Release(&Fb);
fail_xP:
    PyBuffer_Release(&Pb);
    PyBuffer_Release(&xb);
    return NULL;
}

/* ---- updates ---------------------------------------------------------------------------- */

/* The scalar update of LindgrenEKF._update_scalar (no gate check here): x += ph y / s, wrap θ;
 * P -= a a' with a = ph / sqrt(s). */
static void commit_scalar(int n, double *x, double *P, const double *ph, double y, double s) {
    double gain = y / s;
    for (int i = 0; i < n; i++) x[i] = x[i] + ph[i] * gain;
    x[ITH] = wrap_angle(x[ITH]);
    double inv = 1.0 / sqrt(s);
    double a[NMAX];
    for (int i = 0; i < n; i++) a[i] = ph[i] * inv;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) P[i * n + j] = P[i * n + j] - a[i] * a[j];
}

/* Write y and s to the history buffers y_out (1 float64) and s_out (1 float64). */
static int put_ys(PyObject *y_obj, PyObject *s_obj, double y, double s) {
    Py_buffer yb, sb;
    if (get_buf(y_obj, &yb, 1, "y_out") < 0) return -1;
    if (get_buf(s_obj, &sb, 1, "s_out") < 0) {
        PyBuffer_Release(&yb);
        return -1;
    }
    *(double *)yb.buf = y;
    *(double *)sb.buf = s;
    PyBuffer_Release(&sb);
    PyBuffer_Release(&yb);
    return 0;
}

/* The 2-vector Kalman update of LindgrenEKF._update, in place. H: the (2, n) Jacobian, or NULL
 * for the two directly measured states idx, idx + 1 (rows of I). R = (r00, r01, r10, r11).
 * S = H P H' + R goes to S (4 doubles). Returns 1 committed; 0 when y' S^-1 y > gate (nothing
 * changed); -1 when the updated state has an entry <= 0 from index soil_from on (R_w, k_s;
 * soil_from < 0: no check; nothing changed). */
static int vec_update(int n, double *x, double *P, const double *H, long idx, double y0,
                      double y1, const double *r, double gate, long soil_from, double *S) {
    double p0[NMAX], p1[NMAX];  /* the columns of P H' */
    double s00, s01, s10, s11;
    if (H == NULL) {
        for (int i = 0; i < n; i++) {
            p0[i] = P[i * n + idx];
            p1[i] = P[i * n + idx + 1];
        }
        s00 = p0[idx] + r[0];
        s01 = p1[idx] + r[1];
        s10 = p0[idx + 1] + r[2];
        s11 = p1[idx + 1] + r[3];
    } else {
        const double *h0 = H, *h1 = H + n;
        for (int i = 0; i < n; i++) {
            const double *pi = P + i * n;
            double a0 = 0.0, a1 = 0.0;
            for (int k = 0; k < n; k++) {
                a0 += pi[k] * h0[k];
                a1 += pi[k] * h1[k];
            }
            p0[i] = a0;
            p1[i] = a1;
        }
        double hp00 = 0.0, hp01 = 0.0, hp10 = 0.0, hp11 = 0.0;
        for (int k = 0; k < n; k++) {
            hp00 += h0[k] * p0[k];
            hp01 += h0[k] * p1[k];
            hp10 += h1[k] * p0[k];
            hp11 += h1[k] * p1[k];
        }
        s00 = hp00 + r[0];
        s01 = hp01 + r[1];
        s10 = hp10 + r[2];
        s11 = hp11 + r[3];
    }
    S[0] = s00;
    S[1] = s01;
    S[2] = s10;
    S[3] = s11;
    double sym = 0.5 * (s01 + s10);
    double det = s00 * s11 - sym * sym;
    double w0 = (s11 * y0 - sym * y1) / det, w1 = (s00 * y1 - sym * y0) / det;
    if (y0 * w0 + y1 * w1 > gate) return 0;
    double xn[NMAX];
    for (int i = 0; i < n; i++) xn[i] = x[i] + (p0[i] * w0 + p1[i] * w1);
    xn[ITH] = wrap_angle(xn[ITH]);
    if (soil_from >= 0)
        for (long i = soil_from; i < n; i++)
            if (xn[i] <= 0.0) return -1;
    double l00 = sqrt(s00);
    double l10 = sym / l00;
    double l11 = sqrt(s11 - l10 * l10);
    double m00 = 1.0 / l00, m01 = -l10 / (l00 * l11), m11 = 1.0 / l11;
    double a0[NMAX], a1[NMAX];
    for (int i = 0; i < n; i++) {
        a0[i] = p0[i] * m00;
        a1[i] = p0[i] * m01 + p1[i] * m11;
    }
    memcpy(x, xn, sizeof(double) * n);
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++)
            P[i * n + j] = P[i * n + j] - (a0[i] * a0[j] + a1[i] * a1[j]);
    return 1;
}

/* update_inertial(x, P, H_acc, R_acc, R_tilt, gz, ax, ay, pitch, roll, r_gyro, out) -> mask
 * LindgrenEKF._update_inertial (Lindgren Eq. 14), in place: the yaw gyro (g1 = Ω), then the
 * accelerometer pair (H_acc: the filter's (2, n) buffer, its row-1 entries for v and Ω written
 * here), then the inclinometer (α1, α2 measured directly; REP 103 pitch/roll are -α1, -α2).
 * A sensor is used when its readings are finite (bit 0 gyro, 1 acc, 2 tilt of the returned mask).
 * out (14 float64): y, s of the gyro; y (2), S (2 x 2) of the accelerometers; y, S of the
 * inclinometer. */
static PyObject *update_inertial(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    if (check_nargs(nargs, 12, "update_inertial") < 0) return NULL;
    double d[6];  /* gz, ax, ay, pitch, roll, r_gyro */
    if (get_doubles(args, 5, 6, d) < 0) return NULL;
    Py_buffer xb, Pb, Hb, Rab, Rtb, ob;
    int n, mask = 0;
    if (get_xP(args[0], args[1], &xb, &Pb, &n) < 0) return NULL;
    if (get_buf(args[2], &Hb, 2 * (Py_ssize_t)n, "H_acc") < 0) goto fail_xP;
    if (get_buf_flags(args[3], &Rab, 4, "R_acc", PyBUF_SIMPLE) < 0) goto fail_H;
    if (get_buf_flags(args[4], &Rtb, 4, "R_tilt", PyBUF_SIMPLE) < 0) goto fail_Ra;
    if (get_buf(args[11], &ob, 14, "out") < 0) goto fail_Rt;
    {
        double *x = xb.buf, *P = Pb.buf, *H = Hb.buf, *out = ob.buf;
        double gz = d[0], ax = d[1], ay = d[2], pitch = d[3], roll = d[4];
        if (isfinite(gz)) {
            double y = gz - x[IOM], ph[NMAX], s;
            for (int i = 0; i < n; i++) ph[i] = P[i * n + IOM];
            s = ph[IOM] + d[5];
            commit_scalar(n, x, P, ph, y, s);  /* no gate */
            out[0] = y;
            out[1] = s;
            mask |= 1;
        }
        if (isfinite(ax) && isfinite(ay)) {
            const double g = 9.80665;  /* models.G_MPS2 */
            double v = x[IV], om = x[IOM], vd = x[IVD], a1 = x[IA1], a2 = x[IA2];
            double y0 = ax / g - (vd / g + a1), y1 = ay / g - (v * om / g - a2);
            H[n + IV] = om / g;
            H[n + IOM] = v / g;
            vec_update(n, x, P, H, -1, y0, y1, Rab.buf, INFINITY, -1, out + 4);
            out[2] = y0;
            out[3] = y1;
            mask |= 2;
        }
        if (isfinite(pitch) && isfinite(roll)) {
            double y0 = -pitch - x[IA1], y1 = -roll - x[IA2];
            vec_update(n, x, P, NULL, IA1, y0, y1, Rtb.buf, INFINITY, -1, out + 10);
            out[8] = y0;
            out[9] = y1;
            mask |= 4;
        }
    }
    PyBuffer_Release(&ob);
    PyBuffer_Release(&Rtb);
    PyBuffer_Release(&Rab);
    PyBuffer_Release(&Hb);
    PyBuffer_Release(&Pb);
    PyBuffer_Release(&xb);
    return PyLong_FromLong(mask);
fail_Rt:
    PyBuffer_Release(&Rtb);
fail_Ra:
    PyBuffer_Release(&Rab);
fail_H:
    PyBuffer_Release(&Hb);
fail_xP:
    PyBuffer_Release(&Pb);
    PyBuffer_Release(&xb);
    return NULL;
}

/* update_odometry(x, P, H, R_odo, tau, dc0, dc1, T0, T1, W, cpr, mode, r_w0, r_w1, k_s0, k_s1,
 *                 max_slip, out) -> status
 * LindgrenEKF._update_odometry, in place: the side-mean counts over the frame interval by
 * Eq. 15-16 (mode 0: no slip model, r_w0 the nominal radius) or Eq. 37-41 (mode 1: R_w, k_s
 * given (the oracle); mode 2: R_w, k_s from the state, whose entries must stay > 0), the
 * predictions and Jacobians of observations.odo_hx / odo_H / odo_slip_hx / odo_slip_H written
 * out per wheel term by term as the numpy method does. H: the filter's (2, n) buffer. out
 * (6 float64): y (2), S (2 x 2). Status: 1 committed; -1 the update would make R_w or k_s <= 0
 * (undone); -2 a torque is not finite; -3 a wheel's |T / k_s| >= max_slip (nothing changed). */
static PyObject *update_odometry(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    if (check_nargs(nargs, 18, "update_odometry") < 0) return NULL;
    double d[13];  /* tau, dc0, dc1, T0, T1, W, cpr, (mode), r_w0, r_w1, k_s0, k_s1, max_slip */
    if (get_doubles(args, 4, 7, d) < 0) return NULL;
    long mode = PyLong_AsLong(args[11]);
    if (mode == -1 && PyErr_Occurred()) return NULL;
    if (get_doubles(args, 12, 5, d + 7) < 0) return NULL;
    Py_buffer xb, Pb, Hb, Rb, ob;
    int n, status = 1;
    if (get_xP(args[0], args[1], &xb, &Pb, &n) < 0) return NULL;
    if ((mode == 2) != (n == NMAX) || mode < 0 || mode > 2) {
        PyErr_SetString(PyExc_ValueError, "mode 2 (soil in the state) needs n = 13, 0-1 n = 9");
        goto fail_xP;
    }
    if (get_buf(args[2], &Hb, 2 * (Py_ssize_t)n, "H") < 0) goto fail_xP;
    if (get_buf_flags(args[3], &Rb, 4, "R_odo", PyBUF_SIMPLE) < 0) goto fail_H;
    if (get_buf(args[17], &ob, 6, "out") < 0) goto fail_R;
    {
        double *x = xb.buf, *P = Pb.buf, *H = Hb.buf, *out = ob.buf;
        double tau = d[0], dc[2] = {d[1], d[2]}, T[2] = {d[3], d[4]}, W = d[5], cpr = d[6];
        double v_mid = x[IV] - 0.5 * tau * x[IVD];
        double om_mid = x[IOM] - 0.5 * tau * x[IOMD];
        double half_w = 0.5 * W;
        double v_w[2] = {v_mid + -half_w * om_mid, v_mid + half_w * om_mid};
        double y[2], dz[2];
        if (mode == 0) {  /* Eq. 15-16 */
            double gain = tau * cpr / d[7];
            y[0] = dc[0] - gain * v_w[0];
            y[1] = dc[1] - gain * v_w[1];
            dz[0] = dz[1] = gain;
        } else {  /* Eq. 37-41 */
            double r_w[2], k_s[2], sigma[2], den[2];
            if (!(isfinite(T[0]) && isfinite(T[1]))) {
                status = -2;
                goto done;
            }
            if (mode == 1) {
                r_w[0] = d[7], r_w[1] = d[8], k_s[0] = d[9], k_s[1] = d[10];
            } else {
                r_w[0] = x[IRL], r_w[1] = x[IRR], k_s[0] = x[IKL], k_s[1] = x[IKR];
            }
            for (int i = 0; i < 2; i++) sigma[i] = v_w[i] >= 0.0 ? 1.0 : -1.0;
            for (int i = 0; i < 2; i++)
                if (fabs(sigma[i] * T[i] / k_s[i]) >= d[11]) {
                    status = -3;
                    goto done;
                }
            for (int i = 0; i < 2; i++) {
                den[i] = k_s[i] - sigma[i] * T[i];
                y[i] = dc[i] - tau * cpr * v_w[i] * k_s[i] / (r_w[i] * den[i]);
            }
            for (int i = 0; i < 2; i++) dz[i] = tau * cpr * k_s[i] / (r_w[i] * den[i]);  /* 38 */
            if (mode == 2) {
                H[IRL] = -(dz[0] * v_w[0]) / r_w[0];  /* Eq. 40 */
                H[n + IRR] = -(dz[1] * v_w[1]) / r_w[1];
                H[IKL] = -tau * cpr * sigma[0] * T[0] * v_w[0] / (r_w[0] * (den[0] * den[0]));
                H[n + IKR] = -tau * cpr * sigma[1] * T[1] * v_w[1] / (r_w[1] * (den[1] * den[1]));
            }
        }
        double d_om[2] = {-dz[0] * 0.5 * W, dz[1] * 0.5 * W};  /* Eq. 39 */
        for (int i = 0; i < 2; i++) {
            H[i * n + IV] = dz[i];
            H[i * n + IOM] = d_om[i];
            H[i * n + IVD] = -0.5 * tau * dz[i];
            H[i * n + IOMD] = -0.5 * tau * d_om[i];
        }
        out[0] = y[0];
        out[1] = y[1];
        status = vec_update(n, x, P, H, -1, y[0], y[1], Rb.buf, INFINITY,
                            mode == 2 ? IRL : -1, out + 2);
    }
done:
    PyBuffer_Release(&ob);
    PyBuffer_Release(&Rb);
    PyBuffer_Release(&Hb);
    PyBuffer_Release(&Pb);
    PyBuffer_Release(&xb);
    return PyLong_FromLong(status);
fail_R:
    PyBuffer_Release(&Rb);
fail_H:
    PyBuffer_Release(&Hb);
fail_xP:
    PyBuffer_Release(&Pb);
    PyBuffer_Release(&xb);
    return NULL;
}

/* update_bearing(x, P, bx, by, z, r, gate, y_out, s_out) -> True, or False when gated
 * LindgrenEKF._update_bearing: nearest-innovation beacon (largest cos(z + θ - atan2(dy, dx)),
 * the first on ties, as np.argmax), innovation y = wrap(z - wrap(atan2(dy, dx) - θ)) (Eq. 17),
 * h = (dy / r², -dx / r², -1 at θ), then the scalar update with the χ² gate; y and s to y_out
 * and s_out (1 float64 each). */
static PyObject *update_bearing(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    if (check_nargs(nargs, 9, "update_bearing") < 0) return NULL;
    double d[3];  /* z, r, gate */
    if (get_doubles(args, 4, 3, d) < 0) return NULL;
    Py_buffer xb, Pb, bxb, byb;
    int n;
    if (get_xP(args[0], args[1], &xb, &Pb, &n) < 0) return NULL;
    if (PyObject_GetBuffer(args[2], &bxb, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0) goto fail_xP;
    Py_ssize_t m = bxb.len / (Py_ssize_t)sizeof(double);
    if (!is_float64(&bxb)) {
        PyErr_SetString(PyExc_TypeError, "bx must be a float64 array");
        PyBuffer_Release(&bxb);
        goto fail_xP;
    }
    if (m < 1 || get_buf_flags(args[3], &byb, m, "by", PyBUF_SIMPLE) < 0) {
        if (m < 1) PyErr_SetString(PyExc_ValueError, "no beacons");
        PyBuffer_Release(&bxb);
        goto fail_xP;
    }
    double *x = xb.buf, *P = Pb.buf;
    const double *bx = bxb.buf, *by = byb.buf;
    double z = d[0], px = x[IX], py = x[IY], th = x[ITH];
    double best = -INFINITY, dx = 0.0, dy = 0.0;
    for (Py_ssize_t j = 0; j < m; j++) {
        double ex = bx[j] - px, ey = by[j] - py;
        double cj = cos((z + th) - atan2(ey, ex));
        if (cj > best || j == 0) {
            best = cj;
            dx = ex;
            dy = ey;
        }
    }
    PyBuffer_Release(&byb);
    PyBuffer_Release(&bxb);
    double y = wrap_angle(z - wrap_angle(atan2(dy, dx) - th));
    double r2 = dx * dx + dy * dy;
    double h0 = dy / r2, h1 = -dx / r2;
    double ph[NMAX];
    for (int i = 0; i < n; i++) {
        const double *pi = P + i * n;
        ph[i] = (pi[IX] * h0 + pi[IY] * h1) - pi[ITH];
    }
    double s = ((h0 * ph[IX] + h1 * ph[IY]) - ph[ITH]) + d[1];
    if (put_ys(args[7], args[8], y, s) < 0) goto fail_xP;
    int accept = !(y * y / s > d[2]);
    if (accept) commit_scalar(n, x, P, ph, y, s);
    PyBuffer_Release(&Pb);
    PyBuffer_Release(&xb);
    return PyBool_FromLong(accept);
fail_xP:
    PyBuffer_Release(&Pb);
    PyBuffer_Release(&xb);
    return NULL;
}

static PyMethodDef methods[] = {
    {"predict", (PyCFunction)(void (*)(void))predict, METH_FASTCALL,
     "predict(x, P, F, Q, tau, jerk_psd_v, jerk_psd_omega, tilt_psd, radius_var_per_m, "
     "k_s_rel_var_per_m): x <- f(x), F, Q <- Jacobian and noise, P <- sym(F P F' + Q)."},
    {"update_inertial", (PyCFunction)(void (*)(void))update_inertial, METH_FASTCALL,
     "update_inertial(x, P, H_acc, R_acc, R_tilt, gz, ax, ay, pitch, roll, r_gyro, out) -> "
     "mask of the sensors used (1 gyro, 2 acc, 4 tilt); out: y, S of each (14 float64)."},
    {"update_odometry", (PyCFunction)(void (*)(void))update_odometry, METH_FASTCALL,
     "update_odometry(x, P, H, R_odo, tau, dc0, dc1, T0, T1, W, cpr, mode, r_w0, r_w1, k_s0, "
     "k_s1, max_slip, out) -> status: 1 committed, -1 soil <= 0, -2 torque NaN, -3 slip range; "
     "out: y (2), S (2 x 2)."},
    {"update_bearing", (PyCFunction)(void (*)(void))update_bearing, METH_FASTCALL,
     "update_bearing(x, P, bx, by, z, r, gate, y_out, s_out) -> accepted; y, s written to "
     "y_out, s_out."},
    {NULL, NULL, 0, NULL}};

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, "_ekf",
    "Compiled prediction and updates of the Lindgren EKF (slipenv.estimators.lindgren.ekf).",
    -1, methods};

PyMODINIT_FUNC PyInit__ekf(void) { return PyModule_Create(&module); }
