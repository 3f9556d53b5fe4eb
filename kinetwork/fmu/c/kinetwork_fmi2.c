/* kinetwork's FMI 2.0 runtime: Model Exchange and Co-Simulation of one exported model.
 *
 * The model's equations are CasADi's generated C (model.c: kn_rhs, kn_newton, kn_out,
 * kn_start, kn_project, kn_input, kn_select, kn_indicators, kn_times), each of (t, x, z, p):
 * time, the states, the algebraic variables of a DAE formulation and the parameter vector
 * [model parameters and inputs, by their places; then the values the equations' relations
 * are held at between events]. config.h says how many of each there are, their start
 * values and the value references.
 *
 * Value references: states 0..NX-1, their rates NX..2NX-1, then the parameters, the inputs
 * and the outputs, in that order (the model description lists them the same way).
 *
 * Events. A relation of the equations (a < b, a Step, a limiter) is held at a value r
 * between events. Today's equations hold none (NR = 0: kn.simulate integrates through them
 * and so does the FMU, with the relations inside the rates); the machinery below is what the
 * FMU runs once content.py hands it the relations the equations locate events on. A relation
 * on time whose switching instants are known in closed form gives time events (nextEventTime:
 * at each, it is held at its value in the middle of the stretch that begins there); any other
 * gives an event indicator, positive while the value it is held at is its own, which flips
 * where the indicator crosses zero; the relations on the states are then read again until
 * none changes (the event iteration). Co-Simulation steps with the Dormand-Prince method of
 * order 5(4), error controlled, locating such crossings on its dense output and stopping at
 * the time events.
 *
 * Nothing is ever integrated silently wrong: a non-finite rate, a loop whose projection no
 * longer closes (a dead point), algebraic equations that do not converge, or a step size that
 * collapses stop the run with fmi2Error and a message through the logger.
 */
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "model.h"
#include "config.h"

#define NX KN_NX
#define NZ KN_NZ
#define NP KN_NP            /* the System's parameter vector: parameters and inputs */
#define NR KN_NR            /* values the relations are held at */
#define NY KN_NY
#define NPAR KN_NPAR        /* parameters of the model description */
#define NU KN_NU            /* inputs */
#define NG KN_NG            /* event indicators */
#define NT KN_NT            /* relations on time with closed-form instants */

#define VR_X 0
#define VR_DX (VR_X + NX)
#define VR_PAR (VR_DX + NX)
#define VR_U (VR_PAR + NPAR)
#define VR_Y (VR_U + NU)
#define VR_END (VR_Y + NY)

/* rounds of the event iteration at most */
#define EVENT_ITERATIONS 50
/* instants closer than this (relative to the time, at least absolutely) are one */
#define SAME_INSTANT 1e-13
/* Newton iterations at most: the start's projection onto a loop's closure, a DAE's z */
#define NEWTON_ITERATIONS 50
/* a projected loop whose closure is off by more than this no longer closes */
#define CLOSURE_LIMIT 1e-6
/* ... and one whose Jacobian in the dependent speeds has a health (|det| over the product
 * of its rows' norms: 1 for orthogonal rows, 0 when singular) below this, or whose
 * determinant changed sign since the start, is at or past a dead point of its partition */
#define HEALTH_LIMIT 1e-8
#define ND KN_ND
/* the shortest step (relative to the time, at least absolutely) Co-Simulation's error
 * control asks for: one this short is taken as it is */
#define MIN_STEP 1e-12
/* ... but no more than this many such steps in a row: a jump is crossed by one, the rates
 * near a singularity (a dead point, a force that blows up) would take them without end */
#define FORCED_STEPS 8
/* Dormand-Prince steps in one doStep at most (bounded work) */
#define MAX_STEPS 10000000L

enum Mode { INSTANTIATED, INITIALIZATION, EVENT, CONTINUOUS, STEP, TERMINATED, FAILED };

/* What a run's state is: all an FMU state copy holds. */
typedef struct {
    double time;
    double x[NX + 1];
    double z[NZ + 1];
    double p[NP + NR + 1];
    int u_set[NU + 1];          /* input set by the environment (else its own value) */
    int x_set[NX + 1];          /* start value set by the environment */
    double tolerance;           /* the integrator's relative tolerance (Co-Simulation) */
    double t_stop;
    int stop_defined;
    int mode;
    double h;                   /* last step size of the Co-Simulation's integrator */
    double health0;             /* the loops' health at the start (0: not yet known) */
    long steps, events;
} Numbers;

typedef struct {
    Numbers n;
    char *name;
    fmi2Type type;
    fmi2CallbackFunctions cb;
    int logging;
    /* scratch: CasADi's work arrays, the integrator's stages */
    const casadi_real *arg[KN_SZ_ARG + 1];
    casadi_real *res[KN_SZ_RES + 1];
    casadi_int iw[KN_SZ_IW + 1];
    casadi_real w[KN_SZ_W + 1];
    double dx[NX + 1], alg[NZ + 1];
    double k[7][NX + 1], x1[NX + 1], xt[NX + 1], err[NX + 1];
    double y[NY + 1], g[NG + 1], g1[NG + 1], r[NR + 1];
    double jd[ND * ND + 1], lu[ND * ND + 1];
    double tg[NT + 1], tdg[NT + 1];
    char why[512];              /* why the equations could not be evaluated, last time */
} Instance;

/* -- messages ------------------------------------------------------------------------------ */
static void say(Instance *m, fmi2Status status, const char *category, const char *format, ...)
{
    char text[1024], safe[2048];
    va_list ap;
    size_t i, j = 0;
    if (!m || !m->cb.logger)
        return;
    if (status == fmi2OK && !m->logging)
        return;
    va_start(ap, format);
    vsnprintf(text, sizeof text, format, ap);
    va_end(ap);
    /* the logger takes a format: the text goes through it as it is */
    for (i = 0; text[i] && j + 2 < sizeof safe; i++) {
        if (text[i] == '%')
            safe[j++] = '%';
        safe[j++] = text[i];
    }
    safe[j] = 0;
    m->cb.logger(m->cb.componentEnvironment, m->name ? m->name : "kinetwork", status,
                 category, safe);
}

static fmi2Status fail(Instance *m, const char *format, ...)
{
    char text[1024];
    va_list ap;
    va_start(ap, format);
    vsnprintf(text, sizeof text, format, ap);
    va_end(ap);
    say(m, fmi2Error, "logStatusError", "%s", text);
    m->n.mode = FAILED;
    return fmi2Error;
}

/* -- the equations ------------------------------------------------------------------------ */
static int call(Instance *m, int (*f)(const casadi_real **, casadi_real **, casadi_int *,
                                      casadi_real *, int), double t, const double *x,
                const double *z, double *out0, double *out1, double *out2)
{
    static const double none = 0;
    m->arg[0] = &t;
    m->arg[1] = x ? x : &none;
    m->arg[2] = z ? z : &none;
    m->arg[3] = m->n.p;
    m->res[0] = out0;
    m->res[1] = out1;
    m->res[2] = out2;
    m->res[3] = m->jd;          /* kn_rhs's fourth output; no other Function has one */
    return f(m->arg, m->res, m->iw, m->w, 0);
}

/* The signed health of the n-by-n column-major matrix J: det(J) over the product of its
 * rows' norms (Gaussian elimination with partial pivoting on a copy). */
static double health(Instance *m, const double *J, int n)
{
    double *a = m->lu, sign = 1, value = 1;
    int i, j, k;
    for (i = 0; i < n * n; i++)
        a[i] = J[i];
    for (i = 0; i < n; i++) {           /* rows scaled to unit norm */
        double norm = 0;
        for (j = 0; j < n; j++)
            norm += a[i + j * n] * a[i + j * n];
        norm = sqrt(norm);
        if (!(norm > 0))
            return 0;
        for (j = 0; j < n; j++)
            a[i + j * n] /= norm;
    }
    for (k = 0; k < n; k++) {
        int pivot = k;
        for (i = k + 1; i < n; i++)
            if (fabs(a[i + k * n]) > fabs(a[pivot + k * n]))
                pivot = i;
        if (a[pivot + k * n] == 0)
            return 0;
        if (pivot != k) {
            for (j = 0; j < n; j++) {
                double tmp = a[k + j * n];
                a[k + j * n] = a[pivot + j * n];
                a[pivot + j * n] = tmp;
            }
            sign = -sign;
        }
        value *= a[k + k * n];
        for (i = k + 1; i < n; i++) {
            double factor = a[i + k * n] / a[k + k * n];
            for (j = k + 1; j < n; j++)
                a[i + j * n] -= factor * a[k + j * n];
        }
    }
    return sign * value;
}

/* The inputs the environment has not set follow their blocks' own values at time t. */
static void inputs_at(Instance *m, double t)
{
#if NU > 0
    double u[NU];
    int i;
    m->arg[0] = &t;
    m->arg[1] = m->n.p;
    m->res[0] = u;
    kn_input(m->arg, m->res, m->iw, m->w, 0);
    for (i = 0; i < NU; i++)
        if (!m->n.u_set[i])
            m->n.p[kn_u_index[i]] = u[i];
#else
    (void)m;
    (void)t;
#endif
}

static int all_finite(const double *v, int n)
{
    int i;
    for (i = 0; i < n; i++)
        if (!isfinite(v[i]))
            return 0;
    return 1;
}

/* z solved from the algebraic equations at (t, x) by Newton from the last z. */
static int solve_z(Instance *m, double t, const double *x, double *z)
{
#if NZ > 0
    double step[NZ], residual = 0;
    int it, i;
    for (it = 0; it < NEWTON_ITERATIONS; it++) {
        double change = 0, size = 0;
        call(m, kn_newton, t, x, z, step, &residual, NULL);
        for (i = 0; i < NZ; i++) {
            change = fmax(change, fabs(step[i] - z[i]));
            size = fmax(size, fabs(step[i]));
            z[i] = step[i];
        }
        if (!all_finite(z, NZ))
            return 0;
        if (change <= 1e-12 * (1 + size))
            return 1;
    }
    return 0;
#else
    (void)m; (void)t; (void)x; (void)z;
    return 1;
#endif
}

/* The rates at (t, x), z solved; 0 and a message where they cannot be had. */
static int rates(Instance *m, double t, const double *x, double *z, double *dx, int quiet)
{
    double closure = 0;
    inputs_at(m, t);
    m->why[0] = 0;
    if (!solve_z(m, t, x, z))
        snprintf(m->why, sizeof m->why, "t = %.17g s: the algebraic equations (%s) do not "
                 "converge", t, KN_ALGEBRAIC_NAMES);
    else {
        call(m, kn_rhs, t, x, z, dx, m->alg, &closure);
        if (!all_finite(dx, NX))
            snprintf(m->why, sizeof m->why, "t = %.17g s: the rates of the states are not "
                     "finite (a force or a parameter expression blows up%s)", t,
                     KN_PROJECTED ? ", or a kinematic loop reached a dead point" : "");
        else if (KN_PROJECTED && !(closure <= CLOSURE_LIMIT))
            snprintf(m->why, sizeof m->why, "t = %.17g s: the kinematic loops no longer close "
                     "(off by %g): the mechanism reached a dead point, where kinetwork's own "
                     "run re-partitions its coordinates; an FMU keeps those it was exported "
                     "with", t, closure);
#if ND > 0
        else {
            double now = health(m, m->jd, ND);
            if (m->n.health0 == 0)
                m->n.health0 = now;
            if (!(fabs(now) >= HEALTH_LIMIT) || now * m->n.health0 < 0)
                snprintf(m->why, sizeof m->why, "t = %.17g s: the kinematic loops reach a "
                         "dead point of the partition of their speeds this FMU was exported "
                         "with (the closure's Jacobian in the dependent speeds %s); "
                         "kinetwork's own run re-partitions there, an FMU cannot: stop "
                         "before it, or choose other independent coordinates", t,
                         now * m->n.health0 < 0 ? "changed the sign of its determinant"
                                                : "turned singular");
        }
#endif
    }
    if (!m->why[0])
        return 1;
    if (!quiet)
        fail(m, "%s", m->why);
    return 0;
}

/* -- relations ------------------------------------------------------------------------------ */
/* The width of one instant at t. */
static double gap(double t) { return SAME_INSTANT * fmax(1.0, fabs(t)); }

#if NR > 0
/* The first switching instant of the relations on time after t, or INFINITY. */
static double next_time_event(Instance *m, double t)
{
    double best = INFINITY;
#if NT > 0
    int j;
    call(m, kn_times, t, NULL, NULL, m->tg, m->tdg, NULL);
    for (j = 0; j < NT; j++) {
        double g = m->tg[j], rate = m->tdg[j], at = INFINITY;
        if (rate == 0 || !isfinite(rate) || !isfinite(g))
            continue;
        if (!kn_time_level[j]) {
            at = t - g / rate;
        } else {            /* the next whole number the indicator reaches */
            double target = rate > 0 ? floor(g) + 1 : ceil(g) - 1;
            if (rate > 0 && g - floor(g) > 1 - 1e-15)
                target += 1;
            if (rate < 0 && ceil(g) - g > 1 - 1e-15)
                target -= 1;
            at = t + (target - g) / rate;
        }
        if (at > t + gap(t) && at < best)
            best = at;
    }
#else
    (void)m;
    (void)t;
#endif
    return best;
}

/* The relations on time with closed-form instants held at their values in the stretch
 * after t (read at its middle). */
static void hold_time(Instance *m, double t)
{
#if NT > 0
    double end = next_time_event(m, t), mid;
    int round, j;
    if (!isfinite(end))
        end = t + fmax(1.0, fabs(t));
    mid = 0.5 * (t + end);
    for (round = 0; round <= NT; round++) {
        int changed = 0;
        call(m, kn_select, mid, m->n.x, m->n.z, m->r, NULL, NULL);
        for (j = 0; j < NT; j++) {
            int k = kn_time_node[j];
            if (m->n.p[NP + k] != m->r[k]) {
                m->n.p[NP + k] = m->r[k];
                changed = 1;
            }
        }
        if (!changed)
            return;
    }
#else
    (void)m;
    (void)t;
#endif
}

/* The event indicators at (t, x), oriented: positive while each relation's held value is
 * its own (held true, it ends where g reaches zero; held false, where g rises above it). */
static void indicators(Instance *m, double t, const double *x, double *z, double *g)
{
#if NG > 0
    int i;
    call(m, kn_indicators, t, x, z, g, NULL, NULL);
    for (i = 0; i < NG; i++) {
        int held = m->n.p[NP + kn_indicator_node[i]] > 0.5;
        g[i] = held ? g[i] : -g[i];
        /* at zero: a held "<" has ended, a held-false "<=" has begun */
        if (g[i] == 0 && (held ? !kn_indicator_le[i] : kn_indicator_le[i]))
            g[i] = -DBL_MIN;
    }
#else
    (void)m; (void)t; (void)x; (void)z; (void)g;
#endif
}

/* The relations on the states read again at (t, x), the others held, until none changes;
 * ``fixed`` (or -1): the node whose new value stands. */
static int iterate(Instance *m, double t, const int *fixed)
{
#if NG > 0
    int round, i;
    for (round = 0; round < EVENT_ITERATIONS; round++) {
        int changed = 0;
        call(m, kn_select, t, m->n.x, m->n.z, m->r, NULL, NULL);
        for (i = 0; i < NG; i++) {
            int k = kn_indicator_node[i];
            if (!kn_indicator_state[i] || (fixed && fixed[i]))
                continue;
            if (m->n.p[NP + k] != m->r[k]) {
                m->n.p[NP + k] = m->r[k];
                changed = 1;
            }
        }
        if (!changed)
            return 1;
    }
    fail(m, "t = %.17g s: the relations do not settle (their values change each other's "
            "without end)", t);
    return 0;
#else
    (void)m; (void)t; (void)fixed;
    return 1;
#endif
}

/* At (t, x) after a crossing: each relation whose indicator is not positive takes its other
 * value, the others are read again. */
static int flip(Instance *m, double t)
{
#if NG > 0
    int fixed[NG], i, any = 0;
    indicators(m, t, m->n.x, m->n.z, m->g);
    for (i = 0; i < NG; i++) {
        fixed[i] = m->g[i] < 0;
        if (fixed[i]) {
            int k = kn_indicator_node[i];
            m->n.p[NP + k] = 1.0 - m->n.p[NP + k];
            any = 1;
            say(m, fmi2OK, "logEvents", "t = %.17g s: relation %d turns %s", t, k,
                m->n.p[NP + k] > 0.5 ? "true" : "false");
        }
    }
    if (any)
        m->n.events++;
    return iterate(m, t, fixed);
#else
    (void)m; (void)t;
    return 1;
#endif
}

/* The held values at the start of a run. */
static int start_relations(Instance *m, double t)
{
    int i;
    call(m, kn_select, t, m->n.x, m->n.z, m->r, NULL, NULL);
    for (i = 0; i < NR; i++)
        m->n.p[NP + i] = m->r[i];
    hold_time(m, t);
    return iterate(m, t, NULL);
}
#endif

/* -- start ---------------------------------------------------------------------------------- */
static fmi2Status initialize(Instance *m)
{
    double x0[NX + 1];
    int i, it;
    for (i = 0; i < NP; i++)
        if (kn_frozen[i] && m->n.p[i] != kn_p0[i])
            return fail(m, "%s = %.17g: %s; this FMU starts from the state it was exported "
                           "with (%s = %.17g): export it again with the value in the model",
                        kn_p_names[i], m->n.p[i], kn_frozen_why[i], kn_p_names[i], kn_p0[i]);
    for (i = 0; i < NPAR; i++) {
        double v = m->n.p[kn_par_index[i]];
        if (!(v >= kn_par_min[i] && v <= kn_par_max[i]) || (kn_par_positive[i] && !(v > 0)) ||
            (kn_par_nonzero[i] && v == 0))
            return fail(m, "%s = %.17g: must be %s%s within [%g, %g] (%s)",
                        kn_p_names[kn_par_index[i]], v, kn_par_positive[i] ? "> 0 and " : "",
                        kn_par_nonzero[i] ? "not 0 and " : "", kn_par_min[i], kn_par_max[i],
                        kn_par_bound_why[i]);
    }
    if (KN_CLOCK && m->n.time != 0)
        return fail(m, "a kinematic loop of this model follows a prescribed motion in time, "
                       "whose clock (the state 'time') starts at 0: start at t = 0, not %g",
                    m->n.time);
    inputs_at(m, m->n.time);
    m->arg[0] = m->n.p;
    m->res[0] = x0;
    kn_start(m->arg, m->res, m->iw, m->w, 0);
    for (i = 0; i < NX; i++)
        if (!m->n.x_set[i])
            m->n.x[i] = x0[i];
    if (KN_PROJECTED) {
        for (it = 0; it < NEWTON_ITERATIONS; it++) {
            double change = 0, size = 0;
            call(m, kn_project, m->n.time, m->n.x, m->n.z, x0, NULL, NULL);
            for (i = 0; i < NX; i++) {
                change = fmax(change, fabs(x0[i] - m->n.x[i]));
                size = fmax(size, fabs(x0[i]));
                m->n.x[i] = x0[i];
            }
            if (change <= 1e-14 * (1 + size))
                break;
        }
    }
    for (i = 0; i < NZ; i++)
        m->n.z[i] = kn_z0[i];
    if (!all_finite(m->n.x, NX))
        return fail(m, "the initial state is not finite for these parameters");
#if NR > 0
    if (!start_relations(m, m->n.time))
        return fmi2Error;
#endif
    if (!rates(m, m->n.time, m->n.x, m->n.z, m->dx, 0))
        return fmi2Error;
    return fmi2OK;
}

/* -- Co-Simulation: Dormand-Prince 5(4) ---------------------------------------------------- */
static const double C2 = 1.0 / 5, C3 = 3.0 / 10, C4 = 4.0 / 5, C5 = 8.0 / 9;
static const double A21 = 1.0 / 5;
static const double A31 = 3.0 / 40, A32 = 9.0 / 40;
static const double A41 = 44.0 / 45, A42 = -56.0 / 15, A43 = 32.0 / 9;
static const double A51 = 19372.0 / 6561, A52 = -25360.0 / 2187, A53 = 64448.0 / 6561,
                    A54 = -212.0 / 729;
static const double A61 = 9017.0 / 3168, A62 = -355.0 / 33, A63 = 46732.0 / 5247,
                    A64 = 49.0 / 176, A65 = -5103.0 / 18656;
static const double A71 = 35.0 / 384, A73 = 500.0 / 1113, A74 = 125.0 / 192,
                    A75 = -2187.0 / 6784, A76 = 11.0 / 84;
static const double E1 = 71.0 / 57600, E3 = -71.0 / 16695, E4 = 71.0 / 1920,
                    E5 = -17253.0 / 339200, E6 = 22.0 / 525, E7 = -1.0 / 40;
/* dense output (Hairer's contd5) */
static const double D1 = -12715105075.0 / 11282082432, D3 = 87487479700.0 / 32700410799,
                    D4 = -10690763975.0 / 1880347072, D5 = 701980252875.0 / 199316789632,
                    D6 = -1453857185.0 / 822651844, D7 = 69997945.0 / 29380423;

static double scale(Instance *m, int i, double a, double b)
{
    double rtol = m->n.tolerance;
    return rtol * kn_nominal[i] + rtol * fmax(fabs(a), fabs(b));
}

/* One trial step of size h from (t, x) (k[0] holds the rate there): x1 and the error
 * norm, or -1 where the equations cannot be evaluated in it. */
static double trial(Instance *m, double t, const double *x, double h)
{
    double (*k)[NX + 1] = m->k, *xt = m->xt, e = 0;
    int i;
#define STAGE(c, expr, out) \
    for (i = 0; i < NX; i++) xt[i] = x[i] + h * (expr); \
    if (!rates(m, t + (c) * h, xt, m->n.z, out, 1)) return -1;
    STAGE(C2, A21 * k[0][i], k[1])
    STAGE(C3, A31 * k[0][i] + A32 * k[1][i], k[2])
    STAGE(C4, A41 * k[0][i] + A42 * k[1][i] + A43 * k[2][i], k[3])
    STAGE(C5, A51 * k[0][i] + A52 * k[1][i] + A53 * k[2][i] + A54 * k[3][i], k[4])
    STAGE(1.0, A61 * k[0][i] + A62 * k[1][i] + A63 * k[2][i] + A64 * k[3][i] + A65 * k[4][i],
          k[5])
    for (i = 0; i < NX; i++)
        m->x1[i] = x[i] + h * (A71 * k[0][i] + A73 * k[2][i] + A74 * k[3][i] + A75 * k[4][i]
                               + A76 * k[5][i]);
    if (!rates(m, t + h, m->x1, m->n.z, k[6], 1))
        return -1;
#undef STAGE
    for (i = 0; i < NX; i++) {
        double d = h * (E1 * k[0][i] + E3 * k[2][i] + E4 * k[3][i] + E5 * k[4][i]
                        + E6 * k[5][i] + E7 * k[6][i]);
        double s = scale(m, i, x[i], m->x1[i]);
        e += (d / s) * (d / s);
    }
    return NX ? sqrt(e / NX) : 0;
}

/* The state at t0 + theta h on the accepted step from x0 to x1 (Hairer's dense output). */
static void dense(Instance *m, const double *x0, double h, double theta, double *out)
{
    double (*k)[NX + 1] = m->k;
    int i;
    for (i = 0; i < NX; i++) {
        double diff = m->x1[i] - x0[i];
        double b = h * k[0][i] - diff;
        double c = diff - h * k[6][i] - b;
        double d = h * (D1 * k[0][i] + D3 * k[2][i] + D4 * k[3][i] + D5 * k[4][i]
                        + D6 * k[5][i] + D7 * k[6][i]);
        out[i] = x0[i] + theta * (diff + (1 - theta) * (b + theta * (c + (1 - theta) * d)));
    }
}

static double norm_scaled(Instance *m, const double *v, const double *x)
{
    double s = 0;
    int i;
    for (i = 0; i < NX; i++) {
        double r = v[i] / scale(m, i, x[i], x[i]);
        s += r * r;
    }
    return NX ? sqrt(s / NX) : 0;
}

/* A first step size (Hairer's): from the sizes of x and of its rate. */
static double first_step(Instance *m, double t, double span)
{
    double d0 = norm_scaled(m, m->n.x, m->n.x), d1 = norm_scaled(m, m->k[0], m->n.x), h0, h1,
           d2 = 0;
    int i;
    h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
    h0 = fmin(h0, span);
    for (i = 0; i < NX; i++)
        m->xt[i] = m->n.x[i] + h0 * m->k[0][i];
    if (rates(m, t + h0, m->xt, m->n.z, m->k[1], 1)) {
        for (i = 0; i < NX; i++)
            m->err[i] = m->k[1][i] - m->k[0][i];
        d2 = norm_scaled(m, m->err, m->n.x) / h0;
    }
    h1 = fmax(d1, d2) <= 1e-15 ? fmax(1e-6, h0 * 1e-3) : pow(0.01 / fmax(d1, d2), 0.2);
    return fmin(fmin(100 * h0, h1), span);
}

#if NG > 0
/* Where, in (0, h], the first indicator stops being positive on the accepted step from x0:
 * bisected on the dense output to the last bit. */
static double locate(Instance *m, double t, const double *x0, double h)
{
    double lo = 0, hi = 1, *xs = m->err;
    int it, i;
    for (it = 0; it < 200 && (hi - lo) * fabs(h) > gap(t + h) * 0.5; it++) {
        double mid = 0.5 * (lo + hi);
        int crossed = 0;
        dense(m, x0, h, mid, xs);
        solve_z(m, t + mid * h, xs, m->n.z);
        indicators(m, t + mid * h, xs, m->n.z, m->g1);
        for (i = 0; i < NG; i++)
            crossed |= m->g1[i] < 0;
        if (crossed)
            hi = mid;
        else
            lo = mid;
    }
    return hi;
}
#endif

/* Integrate from the present time to t_end, stopping at time events and state events. */
static fmi2Status advance(Instance *m, double t_end)
{
    Numbers *n = &m->n;
    double x0[NX + 1];
    int fresh = 1, forced = 0, i;
    long steps = 0;
    while (t_end - n->time > 1e-15 * fmax(1.0, fabs(t_end))) {
        double t = n->time, bound = t_end, h, e;
        int stop_at_bound;
#if NR > 0
        double te = next_time_event(m, t);
        if (te < bound - gap(bound))
            bound = te;
#endif
        if (fresh) {
            if (!rates(m, t, n->x, n->z, m->k[0], 0))
                return fmi2Error;
            if (!(n->h > 0))
                n->h = first_step(m, t, bound - t);
            fresh = 0;
        }
        h = fmin(n->h, bound - t);
        stop_at_bound = h >= bound - t - gap(bound);
        if (stop_at_bound)
            h = bound - t;
        if (++steps > MAX_STEPS)
            return fail(m, "t = %.17g s: more than %ld steps in one communication step", t,
                        MAX_STEPS);
        e = trial(m, t, n->x, h);
        /* a step no longer than MIN_STEP is taken whatever its error estimate: a rate that
         * jumps at a known instant (a Step at a communication point, seen by the last stage
         * of every step that ends there) costs it at most MIN_STEP times the jump */
        if (!(e >= 0 && isfinite(e)) || !(e <= 1.0 || h <= MIN_STEP * fmax(1.0, fabs(t)))) {
            double factor = e < 0 || !isfinite(e) ? 0.25 : fmax(0.2, 0.9 * pow(e, -0.2));
            /* the equations fail however short the step: whatever they failed on (a dead
             * point, a force that blows up) lies within MIN_STEP, not ahead of it */
            if (h <= MIN_STEP * fmax(1.0, fabs(t)))
                return fail(m, "%s (the step size collapsed to %g s there)",
                            m->why[0] ? m->why : "the error estimate is not finite", h);
            n->h = h * factor;
            continue;
        }
        if (!(e <= 1.0) && ++forced > FORCED_STEPS)
            return fail(m, "t = %.17g s: the step size collapsed (%g s) at the tolerance %g: "
                           "the rates change faster than any step can follow%s", t, h,
                        n->tolerance, KN_PROJECTED ? " (a kinematic loop near a dead point?)"
                                                   : "");
        if (e <= 1.0)
            forced = 0;
        for (i = 0; i < NX; i++)
            x0[i] = n->x[i];
#if NG > 0
        {
            int crossed = 0;
            indicators(m, t + h, m->x1, n->z, m->g1);
            for (i = 0; i < NG; i++)
                crossed |= m->g1[i] < 0;
            if (crossed) {
                double theta = locate(m, t, x0, h);
                dense(m, x0, h, theta, n->x);
                n->time = theta >= 1 ? t + h : t + theta * h;
                solve_z(m, n->time, n->x, n->z);
                if (!flip(m, n->time))
                    return fmi2Error;
                n->steps++;
                fresh = 1;
                continue;
            }
        }
#endif
        for (i = 0; i < NX; i++) {
            n->x[i] = m->x1[i];
            m->k[0][i] = m->k[6][i];
        }
        n->time = stop_at_bound ? bound : t + h;
        n->steps++;
        n->h = fmax(h * fmin(5.0, fmax(0.2, 0.9 * pow(fmax(e, 1e-10), -0.2))),
                    forced ? MIN_STEP * fmax(1.0, fabs(t)) : 0.0);
        if (stop_at_bound && n->h < h)
            n->h = fmax(n->h, h);
#if NR > 0
        if (stop_at_bound && bound < t_end - gap(t_end)) {
            n->events++;
            hold_time(m, n->time);
            if (!iterate(m, n->time, NULL))
                return fmi2Error;
            fresh = 1;
        }
#endif
    }
    n->time = t_end;
    return fmi2OK;
}

/* -- FMI: common ---------------------------------------------------------------------------- */
const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[])
{
    Instance *m = (Instance *)c;
    (void)nCategories;
    (void)categories;
    if (!m)
        return fmi2Error;
    m->logging = loggingOn;
    return fmi2OK;
}

static void defaults(Instance *m)
{
    int i;
    memset(&m->n, 0, sizeof m->n);
    for (i = 0; i < NP; i++)
        m->n.p[i] = kn_p0[i];
    for (i = 0; i < NX; i++)
        m->n.x[i] = kn_x0[i];
    for (i = 0; i < NZ; i++)
        m->n.z[i] = kn_z0[i];
    m->n.tolerance = KN_RTOL;
    m->n.mode = INSTANTIATED;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn)
{
    Instance *m;
    (void)fmuResourceLocation;
    (void)visible;
    if (!functions || !functions->allocateMemory || !functions->freeMemory)
        return NULL;
    m = (Instance *)functions->allocateMemory(1, sizeof(Instance));
    if (!m)
        return NULL;
    memset(m, 0, sizeof *m);
    m->cb = *functions;
    m->logging = loggingOn;
    m->type = fmuType;
    if (instanceName) {
        m->name = (char *)functions->allocateMemory(strlen(instanceName) + 1, 1);
        if (m->name)
            strcpy(m->name, instanceName);
    }
    if (!fmuGUID || strcmp(fmuGUID, KN_GUID) != 0) {
        say(m, fmi2Error, "logStatusError", "wrong GUID %s: this FMU is %s",
            fmuGUID ? fmuGUID : "(none)", KN_GUID);
        if (m->name)
            functions->freeMemory(m->name);
        functions->freeMemory(m);
        return NULL;
    }
    defaults(m);
    return m;
}

void fmi2FreeInstance(fmi2Component c)
{
    Instance *m = (Instance *)c;
    if (!m)
        return;
    if (m->name)
        m->cb.freeMemory(m->name);
    m->cb.freeMemory(m);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined,
                               fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    Instance *m = (Instance *)c;
    if (!m || m->n.mode != INSTANTIATED)
        return m ? fail(m, "fmi2SetupExperiment: only after fmi2Instantiate") : fmi2Error;
    /* a tolerance asked of Co-Simulation is the integrator's own, as FMI 2.0 means it */
    if (toleranceDefined && tolerance > 0)
        m->n.tolerance = fmax(tolerance, 1e-14);
    m->n.time = startTime;
    m->n.stop_defined = stopTimeDefined;
    m->n.t_stop = stopTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    Instance *m = (Instance *)c;
    if (!m || m->n.mode != INSTANTIATED)
        return m ? fail(m, "fmi2EnterInitializationMode: only after fmi2Instantiate")
                 : fmi2Error;
    m->n.mode = INITIALIZATION;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    Instance *m = (Instance *)c;
    fmi2Status s;
    if (!m || m->n.mode != INITIALIZATION)
        return m ? fail(m, "fmi2ExitInitializationMode: only in initialization mode")
                 : fmi2Error;
    s = initialize(m);
    if (s != fmi2OK)
        return s;
    m->n.mode = m->type == fmi2ModelExchange ? EVENT : STEP;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c)
{
    Instance *m = (Instance *)c;
    if (!m)
        return fmi2Error;
    m->n.mode = TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c)
{
    Instance *m = (Instance *)c;
    if (!m)
        return fmi2Error;
    defaults(m);
    return fmi2OK;
}

static int started(Instance *m)
{
    return m->n.mode == EVENT || m->n.mode == CONTINUOUS || m->n.mode == STEP ||
           m->n.mode == TERMINATED;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[])
{
    Instance *m = (Instance *)c;
    size_t i;
    int have_dx = 0, have_y = 0;
    if (!m || m->n.mode == FAILED)
        return fmi2Error;
    for (i = 0; i < nvr; i++) {
        fmi2ValueReference r = vr[i];
        if (r < VR_DX) {
            value[i] = m->n.x[r - VR_X];
        } else if (r < VR_PAR) {
            if (!started(m))
                return fail(m, "fmi2GetReal: the rates are known after initialization");
            if (!have_dx && !rates(m, m->n.time, m->n.x, m->n.z, m->dx, 0))
                return fmi2Error;
            have_dx = 1;
            value[i] = m->dx[r - VR_DX];
        } else if (r < VR_U) {
            value[i] = m->n.p[kn_par_index[r - VR_PAR]];
        } else if (r < VR_Y) {
            inputs_at(m, m->n.time);
            value[i] = m->n.p[kn_u_index[r - VR_U]];
        } else if (r < VR_END) {
            if (!started(m))
                return fail(m, "fmi2GetReal: the outputs are known after initialization");
            if (!have_y) {
                inputs_at(m, m->n.time);
                if (!solve_z(m, m->n.time, m->n.x, m->n.z))
                    return fail(m, "t = %.17g s: the algebraic equations do not converge",
                                m->n.time);
                call(m, kn_out, m->n.time, m->n.x, m->n.z, m->y, NULL, NULL);
            }
            have_y = 1;
            value[i] = m->y[r - VR_Y];
        } else {
            return fail(m, "fmi2GetReal: no Real variable has value reference %u", r);
        }
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[])
{
    Instance *m = (Instance *)c;
    size_t i;
    if (!m || m->n.mode == FAILED || m->n.mode == TERMINATED)
        return fmi2Error;
    for (i = 0; i < nvr; i++) {
        fmi2ValueReference r = vr[i];
        if (r < VR_DX) {
            int k = (int)(r - VR_X);
            if (started(m) || !kn_x_exact[k])
                return fail(m, "fmi2SetReal: %s is a state%s", kn_x_names[k],
                            started(m) ? " (set states with fmi2SetContinuousStates)"
                                       : " whose start the FMU calculates from the parameters");
            m->n.x[k] = value[i];
            m->n.x_set[k] = 1;
        } else if (r < VR_PAR) {
            return fail(m, "fmi2SetReal: the rate of %s is calculated", kn_x_names[r - VR_DX]);
        } else if (r < VR_U) {
            if (m->n.mode == CONTINUOUS)
                return fail(m, "fmi2SetReal: %s is a parameter: tunable in event mode",
                            kn_p_names[kn_par_index[r - VR_PAR]]);
            m->n.p[kn_par_index[r - VR_PAR]] = value[i];
        } else if (r < VR_Y) {
            m->n.p[kn_u_index[r - VR_U]] = value[i];
            m->n.u_set[r - VR_U] = 1;
        } else {
            return fail(m, "fmi2SetReal: value reference %u is an output or none", r);
        }
    }
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[])
{
    (void)vr; (void)value;
    return nvr ? fail((Instance *)c, "fmi2GetInteger: this FMU has no Integer variables")
               : fmi2OK;
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[])
{
    (void)vr; (void)value;
    return nvr ? fail((Instance *)c, "fmi2GetBoolean: this FMU has no Boolean variables")
               : fmi2OK;
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[])
{
    (void)vr; (void)value;
    return nvr ? fail((Instance *)c, "fmi2GetString: this FMU has no String variables")
               : fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[])
{
    (void)vr; (void)value;
    return nvr ? fail((Instance *)c, "fmi2SetInteger: this FMU has no Integer variables")
               : fmi2OK;
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[])
{
    (void)vr; (void)value;
    return nvr ? fail((Instance *)c, "fmi2SetBoolean: this FMU has no Boolean variables")
               : fmi2OK;
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[])
{
    (void)vr; (void)value;
    return nvr ? fail((Instance *)c, "fmi2SetString: this FMU has no String variables")
               : fmi2OK;
}

/* -- FMU states: a copy of the numbers -------------------------------------------------- */
#define STATE_TAG 0x6b6e3032u   /* "kn02" */

typedef struct {
    unsigned tag;
    unsigned size;
    char guid[sizeof KN_GUID];
    Numbers n;
} Saved;

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *state)
{
    Instance *m = (Instance *)c;
    Saved *s;
    if (!m || !state)
        return fmi2Error;
    s = *state ? (Saved *)*state : (Saved *)m->cb.allocateMemory(1, sizeof(Saved));
    if (!s)
        return fail(m, "fmi2GetFMUstate: out of memory");
    s->tag = STATE_TAG;
    s->size = sizeof(Saved);
    memcpy(s->guid, KN_GUID, sizeof KN_GUID);
    s->n = m->n;
    *state = s;
    return fmi2OK;
}

static int valid(const Saved *s)
{
    return s && s->tag == STATE_TAG && s->size == sizeof(Saved) &&
           memcmp(s->guid, KN_GUID, sizeof KN_GUID) == 0;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state)
{
    Instance *m = (Instance *)c;
    if (!m)
        return fmi2Error;
    if (!valid((const Saved *)state))
        return fail(m, "fmi2SetFMUstate: not a state of this FMU");
    m->n = ((const Saved *)state)->n;
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state)
{
    Instance *m = (Instance *)c;
    if (!m || !state)
        return fmi2Error;
    if (*state)
        m->cb.freeMemory(*state);
    *state = NULL;
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t *size)
{
    (void)c;
    (void)state;
    *size = sizeof(Saved);
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[],
                                 size_t size)
{
    Instance *m = (Instance *)c;
    if (!m)
        return fmi2Error;
    if (size < sizeof(Saved) || !valid((const Saved *)state))
        return fail(m, "fmi2SerializeFMUstate: not a state of this FMU, or too few bytes");
    memcpy(bytes, state, sizeof(Saved));
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size,
                                   fmi2FMUstate *state)
{
    Instance *m = (Instance *)c;
    Saved s;
    if (!m || !state)
        return fmi2Error;
    if (size != sizeof(Saved))
        return fail(m, "fmi2DeSerializeFMUstate: %lu bytes are no state of this FMU",
                    (unsigned long)size);
    memcpy(&s, bytes, sizeof s);
    if (!valid(&s))
        return fail(m, "fmi2DeSerializeFMUstate: the bytes are no state of this FMU");
    if (!*state)
        *state = m->cb.allocateMemory(1, sizeof(Saved));
    if (!*state)
        return fail(m, "fmi2DeSerializeFMUstate: out of memory");
    memcpy(*state, &s, sizeof s);
    return fmi2OK;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown[],
                                        size_t nUnknown, const fmi2ValueReference vKnown[],
                                        size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[])
{
    (void)vUnknown; (void)nUnknown; (void)vKnown; (void)nKnown; (void)dvKnown;
    (void)dvUnknown;
    return fail((Instance *)c, "fmi2GetDirectionalDerivative: not provided by this FMU");
}

/* -- FMI: Model Exchange ------------------------------------------------------------------ */
fmi2Status fmi2EnterEventMode(fmi2Component c)
{
    Instance *m = (Instance *)c;
    if (!m || (m->n.mode != CONTINUOUS && m->n.mode != EVENT))
        return m ? fail(m, "fmi2EnterEventMode: only in continuous-time mode") : fmi2Error;
    m->n.mode = EVENT;
    return fmi2OK;
}

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *info)
{
    Instance *m = (Instance *)c;
    if (!m || m->n.mode != EVENT)
        return m ? fail(m, "fmi2NewDiscreteStates: only in event mode") : fmi2Error;
    info->newDiscreteStatesNeeded = fmi2False;
    info->terminateSimulation = fmi2False;
    info->nominalsOfContinuousStatesChanged = fmi2False;
    info->valuesOfContinuousStatesChanged = fmi2False;
    info->nextEventTimeDefined = fmi2False;
    info->nextEventTime = 0;
#if NR > 0
    {
        double t = m->n.time, te;
        inputs_at(m, t);
        solve_z(m, t, m->n.x, m->n.z);
        if (NT > 0) {
            hold_time(m, t);
        }
        if (!flip(m, t))
            return fmi2Error;
        te = next_time_event(m, t);
        if (isfinite(te)) {
            info->nextEventTimeDefined = fmi2True;
            info->nextEventTime = te;
        }
    }
#endif
    return fmi2OK;
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c)
{
    Instance *m = (Instance *)c;
    if (!m || m->n.mode != EVENT)
        return m ? fail(m, "fmi2EnterContinuousTimeMode: only in event mode") : fmi2Error;
    m->n.mode = CONTINUOUS;
    return fmi2OK;
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode,
                                       fmi2Boolean *terminateSimulation)
{
    Instance *m = (Instance *)c;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!m)
        return fmi2Error;
    *enterEventMode = fmi2False;
    *terminateSimulation = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time)
{
    Instance *m = (Instance *)c;
    if (!m || m->n.mode == FAILED)
        return fmi2Error;
    m->n.time = time;
    return fmi2OK;
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx)
{
    Instance *m = (Instance *)c;
    size_t i;
    if (!m || m->n.mode == FAILED)
        return fmi2Error;
    if (nx != NX)
        return fail(m, "fmi2SetContinuousStates: %lu states given, the model has %d",
                    (unsigned long)nx, NX);
    for (i = 0; i < nx; i++)
        m->n.x[i] = x[i];
    return fmi2OK;
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx)
{
    Instance *m = (Instance *)c;
    if (!m || m->n.mode == FAILED)
        return fmi2Error;
    if (nx != NX)
        return fail(m, "fmi2GetDerivatives: %lu rates asked, the model has %d states",
                    (unsigned long)nx, NX);
    if (!rates(m, m->n.time, m->n.x, m->n.z, derivatives, 0))
        return fmi2Error;
    return fmi2OK;
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni)
{
    Instance *m = (Instance *)c;
    if (!m || m->n.mode == FAILED)
        return fmi2Error;
    if (ni != NG)
        return fail(m, "fmi2GetEventIndicators: %lu asked, the model has %d",
                    (unsigned long)ni, NG);
#if NG > 0
    inputs_at(m, m->n.time);
    solve_z(m, m->n.time, m->n.x, m->n.z);
    indicators(m, m->n.time, m->n.x, m->n.z, eventIndicators);
#else
    (void)eventIndicators;
#endif
    return fmi2OK;
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx)
{
    Instance *m = (Instance *)c;
    size_t i;
    if (!m || nx != NX)
        return m ? fail(m, "fmi2GetContinuousStates: %lu states asked, the model has %d",
                        (unsigned long)nx, NX) : fmi2Error;
    for (i = 0; i < nx; i++)
        x[i] = m->n.x[i];
    return fmi2OK;
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx)
{
    Instance *m = (Instance *)c;
    size_t i;
    if (!m || nx != NX)
        return m ? fail(m, "fmi2GetNominalsOfContinuousStates: %lu asked, the model has %d",
                        (unsigned long)nx, NX) : fmi2Error;
    for (i = 0; i < nx; i++)
        x_nominal[i] = kn_nominal[i];
    return fmi2OK;
}

/* -- FMI: Co-Simulation ------------------------------------------------------------------- */
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                       size_t nvr, const fmi2Integer order[],
                                       const fmi2Real value[])
{
    (void)vr; (void)nvr; (void)order; (void)value;
    return fail((Instance *)c, "fmi2SetRealInputDerivatives: this FMU holds its inputs "
                               "constant over a communication step");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t nvr, const fmi2Integer order[],
                                        fmi2Real value[])
{
    (void)vr; (void)nvr; (void)order; (void)value;
    return fail((Instance *)c, "fmi2GetRealOutputDerivatives: not provided by this FMU");
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    Instance *m = (Instance *)c;
    double t_end = currentCommunicationPoint + communicationStepSize;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!m || m->n.mode != STEP)
        return m ? fail(m, "fmi2DoStep: only after initialization (and not after a "
                           "failure)") : fmi2Error;
    if (communicationStepSize < 0)
        return fail(m, "fmi2DoStep: a negative step size (%g)", communicationStepSize);
    if (fabs(currentCommunicationPoint - m->n.time) > 1e-9 * fmax(1.0, fabs(m->n.time)))
        return fail(m, "fmi2DoStep: the FMU is at t = %.17g s, not at %.17g s", m->n.time,
                    currentCommunicationPoint);
    m->n.time = currentCommunicationPoint;
    return advance(m, t_end);
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
    return fail((Instance *)c, "fmi2CancelStep: fmi2DoStep returns when it is done");
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{
    (void)c;
    (void)s;
    *value = fmi2OK;
    return fmi2Discard;
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    Instance *m = (Instance *)c;
    if (!m)
        return fmi2Error;
    if (s == fmi2LastSuccessfulTime) {
        *value = m->n.time;
        return fmi2OK;
    }
    return fmi2Discard;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value)
{
    (void)c; (void)s; (void)value;
    return fmi2Discard;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value)
{
    (void)c;
    if (s == fmi2Terminated) {
        *value = fmi2False;
        return fmi2OK;
    }
    return fmi2Discard;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value)
{
    (void)c; (void)s; (void)value;
    return fmi2Discard;
}
