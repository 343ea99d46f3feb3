/* The wheel-soil laws of slipenv, written once: what the simulation runs at every wheel
 * contact and every physics substep (slipenv/sim/_wheel_loop.c), and what the Python API of
 * slipenv.terramechanics calls (slipenv/terramechanics/_laws.c binds each function).
 *
 * Plain C99 on doubles, no Python: each function is one law, with the paper and equation it
 * implements. The conventions are those of slipenv.terramechanics.contact: slip s > 0 drives,
 * tan_beta = v_lat/|v_long| (Reina Eq. 4) for Reina's law and v_lat/max(|r omega|, |v_long|)
 * (the direction of the sliding velocity) for the Janosi and linear laws (laws_relax_slip),
 * forces in the wheel's heading frame (fx forward, fy to the left), a resistance is a
 * magnitude applied against the travel. The docstrings of the Python
 * functions of the same names (slip_dynamics.py, bekker.py, janosi.py, lindgren.py, reina.py,
 * models.py) say the same in words; tests/terramechanics/reference_laws.py is an independent
 * Python transcription the tests compare against.
 */
#ifndef SLIPENV_LAWS_H
#define SLIPENV_LAWS_H

#include <math.h>

static inline double laws_clip1(double v) { return v > 1.0 ? 1.0 : (v < -1.0 ? -1.0 : v); }

/* -- slip as a state (slip_dynamics.py) ------------------------------------------------- */

/* One backward-Euler step of the slip relaxation ODE (Pacejka, Tyre and Vehicle Dynamics,
 * §7.2.1): sigma ds/dt + V s = r omega - v, sigma db/dt + V_b b = v_lat with
 * V = max(|r omega|, |v|, |v_lat|) and V_b the lateral state's reference speed: V_b = V for a
 * law whose slip angle follows the sliding velocity (Janosi, linear: b -> v_lat/V), or
 * V_b = max(|v|, |v_lat|) for a law in Reina's convention (forward != 0: b -> v_lat/|v|,
 * Reina Eq. 4, up to 45 deg, and +-1 beyond). With h = dt/sigma,
 * s' = (s + h (r omega - v))/(1 + h V), b' = (b + h v_lat)/(1 + h V_b), each clipped to
 * [-1, 1]: no division by a speed, finite at v = 0. Writes s', b', V (the speed the
 * lengthwise damper fades with) and V_b (the lateral damper's). */
static inline void laws_relax_slip(double slip, double tan_beta, double rim, double v_long,
                                   double v_lat, double h, int forward, double *s_out,
                                   double *t_out, double *v_ref_out, double *v_lat_ref_out)
{
    double v_side = fabs(v_lat);
    double v_fwd = fabs(v_long);
    double v_lat_ref = v_fwd > v_side ? v_fwd : v_side;
    double v_ref = fabs(rim) > v_lat_ref ? fabs(rim) : v_lat_ref;
    if (!forward)
        v_lat_ref = v_ref;
    *s_out = laws_clip1((slip + h * (rim - v_long)) / (1.0 + h * v_ref));
    *t_out = laws_clip1((tan_beta + h * v_lat) / (1.0 + h * v_lat_ref));
    *v_ref_out = v_ref;
    *v_lat_ref_out = v_lat_ref;
}

/* Side damper on the lateral shear-deformation rate, faded with speed [N]:
 * F = -d delta(tan_beta)/(1 + (V_b/v_f)^4) (LuGre's sigma_1 term, Canudas de Wit, Olsson,
 * Astrom and Lischinsky, IEEE TAC 40(3), 1995; faded with speed as in Canudas de Wit et al.
 * 2003), V_b the lateral state's leak speed (laws_relax_slip): it damps the spring where the
 * leak does not. Zero in steady side slip. */
static inline double laws_lateral_damping(double tan_beta_change, double v_ref, double d,
                                          double fade_speed)
{
    double fade = v_ref / fade_speed;
    fade *= fade;
    return -d * tan_beta_change / (1.0 + fade * fade);
}

/* Lengthwise damper on the sliding speed r omega - v near standstill [N]:
 * F = (1 - V/v_low) c (r omega - v) for V < v_low, else 0 (Pacejka §7.2: the relaxation state
 * alone is an undamped spring at standstill). */
static inline double laws_longitudinal_damping(double rim, double v_long, double v_ref,
                                               double c, double low_speed)
{
    double speed = v_ref / low_speed;
    return speed < 1.0 ? (1.0 - speed) * c * (rim - v_long) : 0.0;
}

/* Damper c = min(2 zeta sqrt(k m), c_max) [N s/m] of the soil spring k = C/sigma held still
 * (LuGre's sigma_1 sized at zeta of critical, Canudas de Wit et al. 1995). */
static inline double laws_critical_damping(double stiffness, double length, double mass,
                                           double zeta, double c_max)
{
    double c = 2.0 * zeta * sqrt(stiffness / length * mass);
    return c < c_max ? c : c_max;
}

/* Rate-independent motion resistance along one axis, an elasto-plastic Coulomb element
 * (Dupont, Hayward, Armstrong and Altpeter, IEEE TAC 47(5), 2002): u' = clip(u + dx/x_0),
 * r = clip(R u' + c v, -R, R), applied as -r. In sliding r = R sign(v) at any speed; at rest
 * under a push below R the state stays inside the band and the body holds. */
static inline void laws_rut_resistance(double res, double state, double disp, double speed,
                                       double stick, double damping, double *r_out,
                                       double *u_out)
{
    double u = laws_clip1(state + disp / stick);
    double r = res * u + damping * speed;
    *r_out = r > res ? res : (r < -res ? -res : r);
    *u_out = u;
}

/* The same element in the contact plane, for an ideal swivel castor (its rut runs along its
 * contact velocity): u' = u + v dt/x_0 renormalised to the unit disc, r = R u' + c v capped
 * at |r| <= R; in sliding r = R v/|v| (Dupont et al. 2002; physics-notes §1, defect 4). */
static inline void laws_rut_resistance_vector(double res, const double state[3],
                                              const double v[3], double dt, double stick,
                                              double damping, double r_out[3], double u_out[3])
{
    double h = dt / stick;
    double u[3] = {state[0] + h * v[0], state[1] + h * v[1], state[2] + h * v[2]};
    double norm = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    if (norm > 1.0)
        for (int i = 0; i < 3; i++)
            u[i] /= norm;
    double r[3];
    for (int i = 0; i < 3; i++)
        r[i] = res * u[i] + damping * v[i];
    norm = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    double scale = norm > res ? res / norm : 1.0;
    for (int i = 0; i < 3; i++) {
        r_out[i] = r[i] * scale;
        u_out[i] = u[i];
    }
}

/* -- Bekker (bekker.py) ----------------------------------------------------------------- */

/* Static sinkage of a rigid wheel, z = (3 W/((3 - n)(k_c + b k_phi) sqrt(D)))^(2/(2n+1))
 * (Bekker; Wong, Theory of Ground Vehicles, Ch. 5); a negative load counts as 0. */
static inline double laws_wheel_sinkage(double load, double width, double diameter, double k_c,
                                        double k_phi, double n)
{
    double base = 3.0 * (load < 0.0 ? 0.0 : load) / ((3.0 - n) * (k_c + width * k_phi)
                                                      * sqrt(diameter));
    return pow(base, 2.0 / (2.0 * n + 1.0));
}

/* Compaction of a wheel in the rut of a leading wheel: only the work below that rut,
 * R_c(z_f) - R_c(z_rut), floored at 0 (Wong, Theory of Ground Vehicles, §2.4, repetitive
 * loading). */
static inline double laws_rut_following(double compaction, double rut_compaction)
{
    double extra = compaction - rut_compaction;
    return extra > 0.0 ? extra : 0.0;
}

/* Load ratio q = k_eq,f sqrt(D_f)/(k_eq,L sqrt(D_L)), k_eq = k_c + b k_phi: a follower's
 * compaction at a leader's rut depth is its own wheel law at the load q W_leader (the Bekker
 * sinkage and compaction above, both power laws in W with the same exponent); 1 for the same
 * geometry. */
static inline double laws_rut_load_ratio(double width, double diameter, double lead_width,
                                         double lead_diameter, double k_c, double k_phi)
{
    if (width == lead_width && diameter == lead_diameter)
        return 1.0;
    return (k_c + width * k_phi) * sqrt(diameter) / ((k_c + lead_width * k_phi)
                                                      * sqrt(lead_diameter));
}

/* Motion resistance of one wheel, f_r W + gamma W^e [N]: rolling (Wong Ch. 1) plus Bekker
 * compaction R_c = gamma W^e (Wong Ch. 5; bekker.wheel_compaction_law). */
static inline double laws_motion_resistance(double load, double f_r, double gamma,
                                            double exponent)
{
    double res = f_r * load;
    if (gamma != 0.0)
        res += gamma * pow(load, exponent);
    return res;
}

/* -- slip sinkage and bulldozing (bekker.py, sidewall.py) ------------------------------- */

/* Lyasko's slip-sinkage factor z/z0 = (1 + i)/(1 - 0.5 i), i the slip clipped to [0, 1]
 * (Lyasko, "Slip sinkage effect in soil-vehicle mechanics", J. Terramech. 47 (2010) 21-31):
 * the sinkage of a slipping wheel over its static sinkage z0; 1 at i = 0, 4 at i = 1. */
static inline double laws_slip_sinkage_factor(double slip)
{
    double i = slip > 1.0 ? 1.0 : (slip > 0.0 ? slip : 0.0);
    return (1.0 + i) / (1.0 - 0.5 * i);
}

#define LAWS_QUARTER_PI 0.78539816339744830962

/* Bekker's bulldozing coefficients D_1 = cot X_c + tan(X_c + phi),
 * D_2 = cot X_c + cot^2 X_c tan phi, X_c = pi/4 - phi/2 (Bekker, Theory of Land Locomotion,
 * 1956, pp. 280-282; Ishigami, Miwa, Nagatani and Yoshida, J. Field Robotics 24(3), 2007). */
static inline void laws_bulldozing_coefficients(double phi, double *d1, double *d2)
{
    double xc = LAWS_QUARTER_PI - 0.5 * phi;
    double cot = 1.0 / tan(xc);
    *d1 = cot + tan(xc + phi);
    *d2 = cot + cot * cot * tan(phi);
}

/* Bekker's bulldozing resistance per unit width of a wall pushing soil at depth h,
 * R_b = D_1 (c h + D_2 gamma h^2/2) [N/m] (Bekker 1956, pp. 280-282; Wong, Theory of Ground
 * Vehicles, Ch. 5, bulldozing resistance); h <= 0 gives 0. */
static inline double laws_bulldozing_per_width(double depth, double cohesion, double phi,
                                               double unit_weight)
{
    if (!(depth > 0.0))
        return 0.0;
    double d1, d2;
    laws_bulldozing_coefficients(phi, &d1, &d2);
    return d1 * (cohesion * depth + 0.5 * d2 * unit_weight * depth * depth);
}

/* Resistance [N] of a wheel dug a depth d >= 0 below its static rut z0 (sinkage), >= 0 and 0
 * at d = 0: the Bekker compaction R_c = b k_eq z^(n+1)/(n+1) (Wong, Theory of Ground Vehicles,
 * Ch. 5) grows from R_c0 (compaction, at z0) to R_c0 ((z0 + d)/z0)^(n+1), and the soil dug out
 * is pushed ahead of the wheel's front of width b: b R_b(d) (laws_bulldozing_per_width). */
static inline double laws_dug_resistance(double dug, double compaction, double n,
                                         double sinkage, double width, double cohesion,
                                         double phi, double unit_weight)
{
    if (!(dug > 0.0))
        return 0.0;
    double extra = width * laws_bulldozing_per_width(dug, cohesion, phi, unit_weight);
    if (compaction != 0.0 && sinkage > 0.0)
        extra += compaction * (pow(1.0 + dug / sinkage, n + 1.0) - 1.0);
    return extra;
}

/* Resistance a slipping wheel adds to its static one [N], >= 0 and 0 at zero slip: its
 * sinkage grows to z = z0 f(|s|) (laws_slip_sinkage_factor; Lyasko 2010), i.e. it is dug
 * d = z0 (f - 1) below its static rut: laws_dug_resistance at that depth. Braking or locked
 * (s < 0) is taken as the slip of the same magnitude (Lyasko measured driven wheels; the soil
 * under a skidding wheel is sheared and dug out the same way). */
static inline double laws_slip_sinkage_resistance(double slip, double compaction, double n,
                                                  double sinkage, double width,
                                                  double cohesion, double phi,
                                                  double unit_weight)
{
    double f = laws_slip_sinkage_factor(fabs(slip));
    return laws_dug_resistance(sinkage * (f - 1.0), compaction, n, sinkage, width, cohesion,
                               phi, unit_weight);
}

/* Distance rates [m/s] of a wheel over its ground: the rim slides over the soil at
 * |r omega - v| and rolls onto fresh soil at v_roll = min(|r omega|, |v|) when r omega and v
 * point the same way, else 0 (a locked or counter-spinning wheel rolls onto nothing). */
static inline void laws_slide_and_roll(double rim, double v_long, double *slide, double *roll)
{
    *slide = fabs(rim - v_long);
    *roll = rim * v_long > 0.0 ? (fabs(rim) < fabs(v_long) ? fabs(rim) : fabs(v_long)) : 0.0;
}

/* One backward-Euler step of the depth d [m] a wheel has dug below its static rut: slip
 * sinkage as the soil a slipping rim carries out from under its patch to its rear (the
 * excavation behind slip sinkage, Lyasko, J. Terramech. 47 (2010) 21-31), as a state. A mass
 * balance over the patch of length sigma: the rim drags a soil layer whose flux
 * per unit width is delta |r omega - v| out of the patch, and rolling onto fresh soil at
 * v_roll (laws_slide_and_roll) replaces the patch's soil with undug soil,
 *     sigma dd/dt = delta |r omega - v| - v_roll d,   d in [0, cap].
 * It grows with the distance slid and relaxes as exp(-x/sigma) over the distance x rolled; its
 * steady state is d = delta |r omega - v|/v_roll = delta |s|/(1 - |s|) (|s| < 1, Wong's slip,
 * drive or braking); with nothing rolled (spinning in place, locked and skidding) it grows
 * until cap. With h = dt/sigma: d' = (d + h delta |r omega - v|)/(1 + h v_roll), clipped to
 * [0, cap]. */
static inline double laws_slip_sinkage_step(double dug, double rim, double v_long, double h,
                                            double delta, double cap)
{
    double slide, roll;
    laws_slide_and_roll(rim, v_long, &slide, &roll);
    double d = (dug + h * delta * slide) / (1.0 + h * roll);
    return d < cap ? (d > 0.0 ? d : 0.0) : (cap > 0.0 ? cap : 0.0);
}

/* -- force laws (janosi.py, lindgren.py, reina.py) -------------------------------------- */

#define LAWS_X_SMALL 1e-5
#define LAWS_TINY 1e-300

/* Secant slope h(x) = (x - 1 + e^{-x})/x^2 of Okello's curve (Lindgren Eq. 18-20), x >= 0;
 * below 1e-5 the clamped form plus its Taylor term h'(0) = -1/6 (no cancellation, no 0/0). */
static inline double laws_okello_h(double x)
{
    double xc = x > LAWS_X_SMALL ? x : LAWS_X_SMALL;
    return (expm1(-xc) + xc) / (xc * xc) + (xc - x) * (1.0 / 6.0);
}

/* (1 - e^{-y})/y for y >= 0, 1 at y = 0 (Reina Eq. 5's saturation as a secant). */
static inline double laws_exp_secant(double y) { return y > LAWS_TINY ? -expm1(-y) / y : 1.0; }

/* Janosi-Hanamoto shear integrated over the patch, combined slip split by direction
 * (Lindgren Eq. 2-3, 18-20; Reina Eq. 7): F = F_max g(sigma L/K), F_max = A c + W tan phi,
 * fx = F s/sigma, fy = -F kappa tan_beta/sigma, sigma = hypot(s, kappa tan_beta), written as
 * F/sigma = F_max h(sigma L/K) L/K. W <= 0: no force. Its input is the slip in the
 * sliding-velocity convention (laws_relax_slip): the shear displacement j of Eq. 2 at a point
 * x along the patch is the sliding velocity (r omega - v, v_lat) times the time x/(r omega) the
 * rim point has been in contact, so in drive j/x = (s, v_lat/(r omega)) (Wong, Theory of Ground
 * Vehicles, Ch. 5: j = i x), i.e. tan_beta = (1 - s) v_lat/v_x, and the split by direction is
 * along the sliding velocity whatever the reference speed. */
static inline void laws_janosi(double slip, double tan_beta, double load, double ac,
                               double tan_phi, double ratio, double kappa, double *fx,
                               double *fy)
{
    if (load <= 0.0) {
        *fx = *fy = 0.0;
        return;
    }
    double lateral = tan_beta * kappa;
    double secant = (load * tan_phi + ac) * laws_okello_h(hypot(slip, lateral) * ratio) * ratio;
    *fx = secant * slip;
    *fy = -secant * lateral;
}

/* Lindgren's linear slip law, stiffness k_s/r = F_max L/(2K) (Lindgren Eq. 23-24), on the
 * combined slip (s, kappa tan_beta), resultant capped at F_max = A c + W tan phi (Eq. 3). */
static inline void laws_linear(double slip, double tan_beta, double load, double ac,
                               double tan_phi, double ratio, double kappa, double *fx,
                               double *fy)
{
    if (load <= 0.0) {
        *fx = *fy = 0.0;
        return;
    }
    double lateral = kappa * tan_beta;
    double half = 0.5 * ratio;
    double excess = hypot(slip, lateral) * half;
    double secant = (load * tan_phi + ac) * half / (excess > 1.0 ? excess : 1.0);
    *fx = secant * slip;
    *fy = -secant * lateral;
}

/* Reina's combined-slip law (Reina Eq. 5-9): the pure-slip curves at sigma = hypot(s, tan_beta)
 * (Eq. 7) split by direction (Eq. 8-9), fx = s k_x, fy = -tan_beta k_y with
 * k = C (1 - e^{-y})/y - W A, y = C sigma/(mu W), each k floored at 0. Inputs in Reina's
 * convention, s = 1 - v_x/(r omega) (Eq. 3) and tan_beta = v_lat/v_x (Eq. 4): the relaxed
 * state of laws_relax_slip with forward != 0. */
static inline void laws_reina(double slip, double tan_beta, double load, double mu, double c_x,
                              double c_y, double a_x, double a_y, double *fx, double *fy)
{
    if (load <= 0.0) {
        *fx = *fy = 0.0;
        return;
    }
    double per_mu_w = hypot(slip, tan_beta) / (mu * load);
    double k_x = c_x * laws_exp_secant(c_x * per_mu_w) - load * a_x;
    double k_y = c_y * laws_exp_secant(c_y * per_mu_w) - load * a_y;
    *fx = k_x > 0.0 ? slip * k_x : 0.0;
    *fy = k_y > 0.0 ? -tan_beta * k_y : 0.0;
}

/* Reina's curve as gross thrust when compaction is added separately: the extra thrust
 * R_c (1 - e^{-y}) s/sigma, y = C_x sigma/(mu W_y) (Eq. 5's own saturation, i.e. mu raised to
 * mu + R_c/W), R_c = gamma W^e; W_y is W_ref with load scaling, else W. Zero at sigma = 0. */
static inline double laws_reina_gross_extra(double slip, double tan_beta, double load,
                                            double gamma, double exponent, double c_x,
                                            double mu, double w_y)
{
    double sigma = hypot(slip, tan_beta);
    if (!(sigma > 0.0) || gamma == 0.0)
        return 0.0;
    return gamma * pow(load, exponent) * -expm1(-c_x * sigma / (mu * w_y)) * slip / sigma;
}

/* -- the force model of one wheel on one soil (models.py) ------------------------------- */

enum { LAWS_JANOSI = 0, LAWS_LINEAR = 1, LAWS_REINA = 2 };

/* A slipenv force model bound to one soil: slipenv.terramechanics.models.KernelConstants,
 * field for field. */
typedef struct {
    int kind;
    double ac, tan_phi, ratio, kappa;  /* Janosi, linear: A c [N], tan phi, L/K, kappa */
    double mu, c_x, c_y, a_x, a_y;     /* Reina (C over W_ref when scaled) */
    int scaled;                        /* Reina: W times the law at W = 1 */
    int gross;                         /* Reina with compaction: gross thrust */
    double gross_c_x, gross_w_ref;     /* C_x as given; W_ref when scaled, else 0 */
    double f_r, gamma, exponent;       /* resistance f_r W + gamma W^e */
    int slip_sinkage;                  /* add laws_slip_sinkage_resistance */
    double ss_gamma, ss_exponent;      /* the wheel's Bekker compaction gamma W^e */
    double width, diameter, k_c, k_phi, n; /* its static sinkage (laws_wheel_sinkage) */
    double cohesion, phi, unit_weight; /* bulldozing (laws_bulldozing_per_width) */
    int sinkage_state;                 /* the simulation's dug-depth state adds the slip
                                          sinkage (laws_slip_sinkage_step), not the kernel */
    double excavation;                 /* delta [m] of laws_slip_sinkage_step */
} LawsKernel;

/* (fx, fy, resistance) [N] of one wheel: the model's force law, plus its motion resistance
 * (with slip_sinkage, plus what the slip adds: laws_slip_sinkage_resistance). */
static inline void laws_kernel(const LawsKernel *k, double slip, double tan_beta, double load,
                               double *fx, double *fy, double *res)
{
    if (k->kind == LAWS_JANOSI) {
        laws_janosi(slip, tan_beta, load, k->ac, k->tan_phi, k->ratio, k->kappa, fx, fy);
    } else if (k->kind == LAWS_LINEAR) {
        laws_linear(slip, tan_beta, load, k->ac, k->tan_phi, k->ratio, k->kappa, fx, fy);
    } else if (k->scaled) {
        /* C = c W/W_ref makes F proportional to W at a given slip (ReinaForceModel) */
        laws_reina(slip, tan_beta, 1.0, k->mu, k->c_x, k->c_y, k->a_x, k->a_y, fx, fy);
        *fx *= load;
        *fy *= load;
    } else {
        laws_reina(slip, tan_beta, load, k->mu, k->c_x, k->c_y, k->a_x, k->a_y, fx, fy);
    }
    *res = laws_motion_resistance(load, k->f_r, k->gamma, k->exponent);
    if (k->slip_sinkage && slip != 0.0 && load > 0.0) {
        double z0 = laws_wheel_sinkage(load, k->width, k->diameter, k->k_c, k->k_phi, k->n);
        double rc0 = laws_motion_resistance(load, 0.0, k->ss_gamma, k->ss_exponent);
        *res += laws_slip_sinkage_resistance(slip, rc0, k->n, z0, k->width, k->cohesion,
                                             k->phi, k->unit_weight);
    }
    if (k->gross)
        *fx += laws_reina_gross_extra(slip, tan_beta, load, k->gamma, k->exponent,
                                      k->gross_c_x, k->mu, k->scaled ? k->gross_w_ref : load);
}

/* The slip-sinkage state of one wheel over one substep (k->sinkage_state): steps its dug depth
 * *dug (laws_slip_sinkage_step with delta = k->excavation, capped where the wheel is buried to
 * its axle, d = D/2 - z0, z0 its static sinkage under this load) and returns the resistance
 * that depth adds (laws_dug_resistance). h = dt/sigma, rim = r omega. */
static inline double laws_kernel_sinkage_state(const LawsKernel *k, double *dug, double rim,
                                               double v_long, double h, double load)
{
    if (!k->sinkage_state || !(load > 0.0)) {
        *dug = 0.0;
        return 0.0;
    }
    double z0 = laws_wheel_sinkage(load, k->width, k->diameter, k->k_c, k->k_phi, k->n);
    *dug = laws_slip_sinkage_step(*dug, rim, v_long, h, k->excavation, 0.5 * k->diameter - z0);
    double rc0 = laws_motion_resistance(load, 0.0, k->ss_gamma, k->ss_exponent);
    return laws_dug_resistance(*dug, rc0, k->n, z0, k->width, k->cohesion, k->phi,
                               k->unit_weight);
}

/* Resistance [N] of a wheel in the rut of the wheel ahead: the rolling term f_r W whole, the
 * compaction only below the rut (laws_rut_following). res = R(W) of this wheel's law at its
 * load; lead_res = R(q W_leader) of the same law at the load that sinks it as deep as the
 * leader's rut (laws_rut_load_ratio; Wong, Theory of Ground Vehicles, §2.4). */
static inline double laws_multi_pass(double res, double load, double lead_res, double lead_load,
                                     double f_r)
{
    double rolling = f_r * load;
    return rolling + laws_rut_following(res - rolling, lead_res - f_r * lead_load);
}

/* -- the contact frame ------------------------------------------------------------------ */

/* The contact frame and sliding velocity of one wheel, world frame. Centre c = the
 * load-weighted mean of the contact points, n = the normalised load-weighted normal; the axle
 * is the link's y axis (the spin axis, invariant under spin); forward e = axle x n, left
 * l = n x e. v_long is the wheel centre's velocity along e, v_side along l; v_lat is the
 * sliding of the contact point along l, v + omega x (c - centre), which leaves out the
 * chassis roll (rate x radius) that would otherwise feed back into the side force. */
typedef struct {
    double c[3], e[3], l[3];
    double v_long, v_side, v_lat;
} LawsFrame;

/* patch: sum f p (3), sum f n (3); q: link orientation (x, y, z, w); centre, v, omega: the
 * link's position, velocity and angular velocity. Returns -1 if the frame is degenerate (no
 * normal, or the axle along the normal). */
static inline int laws_contact_frame(const double patch[6], double load, const double q[4],
                                     const double centre[3], const double v[3],
                                     const double omega[3], LawsFrame *f)
{
    double nx = patch[3], ny = patch[4], nz = patch[5];
    double norm = sqrt(nx * nx + ny * ny + nz * nz);
    if (!(norm > 0.0) || !(load > 0.0))
        return -1;
    nx /= norm; ny /= norm; nz /= norm;
    for (int i = 0; i < 3; i++)
        f->c[i] = patch[i] / load;
    double qx = q[0], qy = q[1], qz = q[2], qw = q[3];
    double ax = 2.0 * (qx * qy - qw * qz);
    double ay = 1.0 - 2.0 * (qx * qx + qz * qz);
    double az = 2.0 * (qy * qz + qw * qx);
    double ex = ay * nz - az * ny, ey = az * nx - ax * nz, ez = ax * ny - ay * nx;
    norm = sqrt(ex * ex + ey * ey + ez * ez);
    if (!(norm > 0.0))
        return -1;
    ex /= norm; ey /= norm; ez /= norm;
    double lx = ny * ez - nz * ey, ly = nz * ex - nx * ez, lz = nx * ey - ny * ex;
    f->e[0] = ex; f->e[1] = ey; f->e[2] = ez;
    f->l[0] = lx; f->l[1] = ly; f->l[2] = lz;
    f->v_long = v[0] * ex + v[1] * ey + v[2] * ez;
    f->v_side = v[0] * lx + v[1] * ly + v[2] * lz;
    double rx = f->c[0] - centre[0], ry = f->c[1] - centre[1], rz = f->c[2] - centre[2];
    f->v_lat = ((v[0] + omega[1] * rz - omega[2] * ry) * lx
                + (v[1] + omega[2] * rx - omega[0] * rz) * ly
                + (v[2] + omega[0] * ry - omega[1] * rx) * lz);
    return 0;
}

/* -- Python glue (only where Python.h is included) --------------------------------------- */
#ifdef Py_PYTHON_H
/* Read a KernelConstants tuple (kind, ac, tan_phi, ratio, kappa, mu, c_x, c_y, a_x, a_y,
 * scaled, gross, gross_c_x, gross_w_ref, f_r, gamma, exponent, slip_sinkage, ss_gamma,
 * ss_exponent, width, diameter, k_c, k_phi, n, cohesion, phi, unit_weight, sinkage_state,
 * excavation) into k; -1 with an exception. */
static int laws_parse_kernel(PyObject *constants, LawsKernel *k)
{
    if (!PyArg_ParseTuple(constants, "idddddddddppdddddpddddddddddpd;kernel constants",
                          &k->kind, &k->ac, &k->tan_phi, &k->ratio, &k->kappa, &k->mu, &k->c_x,
                          &k->c_y, &k->a_x, &k->a_y, &k->scaled, &k->gross, &k->gross_c_x,
                          &k->gross_w_ref, &k->f_r, &k->gamma, &k->exponent, &k->slip_sinkage,
                          &k->ss_gamma, &k->ss_exponent, &k->width, &k->diameter, &k->k_c,
                          &k->k_phi, &k->n, &k->cohesion, &k->phi, &k->unit_weight,
                          &k->sinkage_state, &k->excavation))
        return -1;
    if (k->kind < LAWS_JANOSI || k->kind > LAWS_REINA) {
        PyErr_Format(PyExc_ValueError, "unknown force law kind %d", k->kind);
        return -1;
    }
    return 0;
}
#endif

#endif /* SLIPENV_LAWS_H */
