/* The chain's velocity-Verlet step, compiled (ssw.chain.kernel loads it through ctypes).

   The physics is documented in ssw/chain/integrate.py (the scheme, the damping's predicted
   velocity, the forward sensitivities, the time step's own column), ssw/chain/impulse.py
   (the contact laws averaged over the step's relative motion: psi, its series far from
   events, the dashpot's closed share Phi, the averaged sqrt) and ssw/chain/dissipation.py
   (the dissipation laws). Arrays are C-contiguous doubles: bead quantities (N, n), their
   sensitivities (N, n, k), positions and velocities stacked (2, N, n) and (2, N, n, k);
   contact j joins beads j and j + 1, contact N - 1 is the wall (its force, and its
   sensitivities, are written by the caller before ssw_forces: any wall law, with or
   without state; or, for a piecewise-linear law, ssw.walls.fem.PiecewiseLinearWall, by
   the step itself).

   No Python C-API: a plain shared library, built by setuptools with the package (setup.py)
   and checked against this file's hash by its loader (SSW_STEP_SOURCE). */
#if defined(__GNUC__) && !defined(__clang__)
/* loops vectorized (SIMD lanes give the scalar code's results: IEEE operations one by one),
   no fused multiply-add */
#pragma GCC optimize("O3", "fp-contract=off")
#endif
#include <math.h>
#include <float.h>
#include <string.h>

#ifndef SSW_STEP_SOURCE
#define SSW_STEP_SOURCE "unknown"
#endif

/* ssw.chain.impulse.FAR, SERIES and ROOT_SERIES */
#define FAR 20.0
#define C1 (1.0 / 16.0)
#define C2 (1.0 / 640.0)
#define R1 (1.0 / 48.0)
#define R2 (1.0 / 384.0)
#define R3 (3.0 / 4096.0)

/* ssw.chain.dissipation.LAWS' codes */
enum { DASHPOT = 0, KUWABARA_KONO = 1, HUNT_CROSSLEY = 2 };

typedef struct {
    int N, n, k;          /* beads, active scenes, sensitivity columns (0: none) */
    int predict;          /* the damping's velocity and factor are needed */
    int damped_tangent;   /* damping > 0 with sensitivities: the factor's own slopes */
    int law;              /* the dissipation law (DASHPOT, KUWABARA_KONO, HUNT_CROSSLEY) */
    int c_D, c_P, c_T;    /* columns of the damping, the preload, the time step (-1: none) */
    int n_mass;           /* masses differentiated (<= 2): rows and columns */
    int mass_row[2], mass_col[2];
    double A, dt, damping, g; /* N/m^1.5, s, the law's coefficient, m/s^2 */
    double *z;            /* (2, N, n) u, v (m, m/s) */
    double *acc;          /* (N, n) m/s^2, the last accelerations (replaced) */
    double *inv_m;        /* (N, n) 1/kg */
    double *preload;      /* (n) N on bead 1, or NULL */
    double *f;            /* (N, n) N, written; row N - 1 holds the wall's force on entry */
    double *power;        /* (n) W, the damping's dissipation rate, or NULL */
    double *ZT;           /* (2, N, n, k) */
    double *Acc;          /* (N, n, k), the last accelerations' sensitivities (replaced) */
    double *dF;           /* (N, n, k), written; row N - 1 holds the wall's on entry */
    double *work;         /* scratch: 9 N n + N n k doubles */
    /* the record (ssw_record): the sensor's two contacts, the wall force, their
       sensitivities, in block buffers whose scene axis has stride n_rec (the run's first n);
       the largest wall indentation and bead-bead forces so far (n) and (N - 1, n) */
    int s, n_rec;
    double *pair;         /* (rows, 2, n_rec) */
    double *wall;         /* (rows, n_rec) */
    double *dpair;        /* (rows, 2, n_rec, k) or NULL */
    double *peak_u;       /* (n) */
    double *peak_f;       /* (N - 1, n) */
    /* a piecewise-linear wall the step evaluates itself (ssw_piecewise; K1 > 0), its rows
       (n, K1): breakpoints (m), a (N), b (N/m), da/dE and db/dE (or NULL); c_E the
       modulus's sensitivity column (-1: none). K1 = 0: the caller writes the wall row. */
    int K1, c_E;
    double *wd, *wa, *wb, *wda, *wdb;
} ssw_chain;

const char *ssw_step_source(void) { return SSW_STEP_SOURCE; }

/* FAR, C1, C2, R1, R2 and R3, for the loader's check against ssw.chain.impulse */
void ssw_step_constants(double *out)
{
    out[0] = FAR;
    out[1] = C1;
    out[2] = C2;
    out[3] = R1;
    out[4] = R2;
    out[5] = R3;
}

/* (y)_+^(7/2) and (y)_+^(5/2) */
static inline void pow_plus(double y, double *p35, double *p25)
{
    if (y > 0.0) {
        double q = y * y * sqrt(y);
        *p25 = q;
        *p35 = q * y;
    } else {
        *p25 = 0.0;
        *p35 = 0.0;
    }
}

/* The Hertz force the step applies to one contact (impulse.py): F = A |delta|^1.5 psi(x),
   x = d / |delta|, near an event (-1 < x < FAR, hertz_near), else A d_+^1.5 (1 + r/16 +
   r^2/640), r = min(1 / x^2, 1) (far_forces). With fd, fa: dF/dd and dF/d|delta| (N/m). */
static inline int near_event(double x) { return x > -1.0 && x < FAR; }

static inline double hertz_near(double x, double a, double A, double *fd, double *fa)
{
    double t0, t1, t2, s0, s1, s2;
    pow_plus(x + 1.0, &t0, &s0);
    pow_plus(x, &t1, &s1);
    pow_plus(x - 1.0, &t2, &s2);
    double val = (t0 - 2.0 * t1 + t2) / 8.75;
    double s = A * sqrt(a);
    if (fd) {
        double dval = 3.5 * ((s0 - 2.0 * s1 + s2) / 8.75);
        *fd = s * dval;
        *fa = s * (1.5 * val - x * dval);
    }
    return s * a * val;
}

/* hertz_near in place of the far law for the contacts q .. q + w - 1 near an event (x
   = d / a, a = |v1 - v0| dt). */
static void near_lanes(int q, int w, const double *v1, const double *v0, double dt, double A,
                       const double *x, double *f, double *fd, double *fa)
{
    for (int i = q; i < q + w; i++)
        if (near_event(x[i]))
            f[i] = hertz_near(x[i], fabs(v1[i] - v0[i]) * dt, A, fd ? fd + i : 0,
                              fa ? fa + i : 0);
}

/* The far law of W contacts at once, in vector lanes (GCC vector extensions; every lane
   gives the scalar result: the same numbers whatever W): with d = d1 - d0, a = |v1 - v0| dt,
   x = d / a, d_+ = max(d, 0) (NaN: 0), r = min(1 / x^2, 1) (NaN: 1),
   F = A d_+ sqrt(d_+) (1 + r C1 + r^2 C2) and, with fd, fa,
   dF/dd = A sqrt(d_+) (1.5 poly - 2 r dpoly), dF/d|delta| = 2 A dpoly a / sqrt(d_+)
   (0 for d_+ = 0), dpoly = C1 + 2 C2 r; then hertz_near in the lanes near an event
   (near_lanes). Rows of M, the last partial vector through a padded copy. The lanes'
   square root is the ISA's (SQRT). */
#define FAR_FORCES(NAME, W, SQRT, ATTR)                                                     \
    typedef double NAME##_v __attribute__((vector_size(8 * W)));                            \
    typedef long long NAME##_m __attribute__((vector_size(8 * W)));                         \
    ATTR static inline NAME##_v NAME##_sel(NAME##_m m, NAME##_v a, NAME##_v b)              \
    {                                                                                       \
        return (NAME##_v)((m & (NAME##_m)a) | (~m & (NAME##_m)b));                          \
    }                                                                                       \
    ATTR static inline __attribute__((always_inline)) int NAME##_lanes(                     \
        const double *d1, const double *d0, const double *v1, const double *v0, double dt,  \
        double A, double *x_out, double *f, double *fd, double *fa)                         \
    {                                                                                       \
        NAME##_v D1, D0, V1, V0, zero = {0}, one = zero + 1.0;                              \
        memcpy(&D1, d1, sizeof D1);                                                         \
        memcpy(&D0, d0, sizeof D0);                                                         \
        memcpy(&V1, v1, sizeof V1);                                                         \
        memcpy(&V0, v0, sizeof V0);                                                         \
        const NAME##_v d = D1 - D0;                                                         \
        const NAME##_v a = (NAME##_v)((NAME##_m)(V1 - V0) & ~(NAME##_m)(-zero)) * dt;       \
        const NAME##_v x = d / a;                                                           \
        const NAME##_v dp = (NAME##_v)((NAME##_m)(d > zero) & (NAME##_m)d);                 \
        const NAME##_v sq = SQRT(dp);                                                       \
        NAME##_v r = one / (x * x);                                                         \
        r = NAME##_sel(r < one, r, one);                                                    \
        const NAME##_v poly = one + r * (C1 + r * C2);                                      \
        const NAME##_v F = A * dp * sq * poly;                                              \
        memcpy(x_out, &x, sizeof x);                                                        \
        memcpy(f, &F, sizeof F);                                                            \
        if (fd) {                                                                           \
            const NAME##_v dpoly = C1 + 2.0 * C2 * r;                                       \
            const NAME##_v Fd = A * sq * (1.5 * poly - 2.0 * r * dpoly);                    \
            const NAME##_v Fa = NAME##_sel(dp > zero, 2.0 * A * dpoly * a / sq, zero);      \
            memcpy(fd, &Fd, sizeof Fd);                                                     \
            memcpy(fa, &Fa, sizeof Fa);                                                     \
        }                                                                                   \
        const NAME##_m near = (x > -1.0) & (x < FAR);                                       \
        long long any = 0;                                                                  \
        for (int l = 0; l < W; l++)                                                         \
            any |= near[l];                                                                 \
        return any != 0;                                                                    \
    }                                                                                       \
    ATTR static void NAME(int M, const double *d1, const double *d0, const double *v1,      \
                          const double *v0, double dt, double A, double *x, double *f,      \
                          double *fd, double *fa)                                           \
    {                                                                                       \
        int q = 0;                                                                          \
        for (; q + W <= M; q += W)                                                          \
            if (NAME##_lanes(d1 + q, d0 + q, v1 + q, v0 + q, dt, A, x + q, f + q,           \
                             fd ? fd + q : 0, fa ? fa + q : 0))                             \
                near_lanes(q, W, v1, v0, dt, A, x, f, fd, fa);                              \
        if (q < M) {                                                                        \
            double b[7][W] = {{0}};                                                         \
            const int r = M - q;                                                            \
            memcpy(b[0], d1 + q, sizeof(double) * r);                                       \
            memcpy(b[1], d0 + q, sizeof(double) * r);                                       \
            memcpy(b[2], v1 + q, sizeof(double) * r);                                       \
            memcpy(b[3], v0 + q, sizeof(double) * r);                                       \
            NAME##_lanes(b[0], b[1], b[2], b[3], dt, A, b[4], b[5], fd ? b[6] : 0,          \
                         fd ? b[0] : 0);                                                    \
            memcpy(x + q, b[4], sizeof(double) * r);                                        \
            memcpy(f + q, b[5], sizeof(double) * r);                                        \
            if (fd) {                                                                       \
                memcpy(fd + q, b[6], sizeof(double) * r);                                   \
                memcpy(fa + q, b[0], sizeof(double) * r);                                   \
            }                                                                               \
            near_lanes(q, r, v1, v0, dt, A, x, f, fd, fa);                                  \
        }                                                                                   \
    }

#if defined(__x86_64__) && defined(__GNUC__)
#define SQRT4(v) __builtin_ia32_sqrtpd256(v)
#define SQRT2(v) __builtin_ia32_sqrtpd(v)
FAR_FORCES(far_avx2, 4, SQRT4, __attribute__((target("avx2"))))
FAR_FORCES(far_sse2, 2, SQRT2, )
/* The widest lanes this CPU runs (AVX2: 4, else SSE2: 2). */
static void far_forces(int M, const double *d1, const double *d0, const double *v1,
                       const double *v0, double dt, double A, double *x, double *f,
                       double *fd, double *fa)
{
    static int avx2 = -1;
    if (avx2 < 0) {
        __builtin_cpu_init();
        avx2 = __builtin_cpu_supports("avx2") ? 1 : 0;
    }
    (avx2 ? far_avx2 : far_sse2)(M, d1, d0, v1, v0, dt, A, x, f, fd, fa);
}
#else
static inline double sqrt_lane(double v) { return sqrt(v); }
#define SQRT1(v) ((far_forces_v){sqrt_lane((v)[0])})
FAR_FORCES(far_forces, 1, SQRT1, )
#endif

/* The hat-weighted share Phi(d / a) of the step a contact is closed, and its slopes (the
   dashpot's factor). */
static inline double closed_share(double d, double a, double *gd, double *ga)
{
    double x = d / a;
    if (x > -1.0 && x < 1.0) {
        double slope = 1.0 - fabs(x);
        if (gd) {
            *gd = slope / a;
            *ga = -slope * x / a;
        }
        return x <= 0.0 ? 0.5 * (1.0 + x) * (1.0 + x) : 1.0 - 0.5 * (1.0 - x) * (1.0 - x);
    }
    if (gd) {
        *gd = 0.0;
        *ga = 0.0;
    }
    return d > 0.0 ? 1.0 : 0.0;
}

/* (y)_+^(5/2) and (y)_+^(3/2) */
static inline void pow_half(double y, double *p25, double *p15)
{
    if (y > 0.0) {
        double q = y * sqrt(y);
        *p15 = q;
        *p25 = q * y;
    } else {
        *p15 = 0.0;
        *p25 = 0.0;
    }
}

/* The Kuwabara-Kono factor: the hat average of sqrt(d_+) over the step's relative motion
   (impulse.py), a^(1/2) P(x), x = d / a, P = [(x + 1)_+^(5/2) - 2 x_+^(5/2) + (x - 1)_+^(5/2)]
   / (15/4) near an event (-1 < x < FAR), else sqrt(d_+) (1 - r R1 - r^2 R2 - r^3 R3), r =
   min(1 / x^2, 1); with gd, ga its slopes in d and in a (1/m^(1/2), 0 for d_+ = 0 far). */
static inline double root_share(double d, double a, double *gd, double *ga)
{
    const double x = d / a;
    if (near_event(x)) {
        double u0, u1, u2, w0, w1, w2;
        pow_half(x + 1.0, &u0, &w0);
        pow_half(x, &u1, &w1);
        pow_half(x - 1.0, &u2, &w2);
        const double P = (u0 - 2.0 * u1 + u2) / 3.75, sa = sqrt(a);
        if (gd) {
            const double P1 = (w0 - 2.0 * w1 + w2) / 1.5;
            *gd = P1 / sa;
            *ga = (0.5 * P - x * P1) / sa;
        }
        return sa * P;
    }
    const double dp = d > 0.0 ? d : 0.0, sq = sqrt(dp);
    double r = 1.0 / (x * x);
    if (!(r < 1.0))
        r = 1.0;
    const double q = 1.0 - r * (R1 + r * (R2 + r * R3));
    if (gd) {
        const double q1 = -(R1 + r * (2.0 * R2 + 3.0 * r * R3));
        *gd = dp > 0.0 ? (0.5 * q - 2.0 * r * q1) / sq : 0.0;
        *ga = dp > 0.0 ? 2.0 * a * q1 / (dp * sq) : 0.0;
    }
    return sq * q;
}

/* A piecewise-linear law F = a_j + b_j d on [d_j, d_(j+1)] at the indentation x (one row of
   K1 breakpoints, d_0 = 0, the last piece continued beyond d_(K1-1)): F at d = max(x, 0),
   with kd the slope (0 for x <= 0) and, with da, kE = da_j + db_j d (0 for x <= 0). */
static inline double piecewise(const double *d, const double *a, const double *b,
                               const double *da, const double *db, int K1, double x,
                               double *kd, double *kE, int *piece)
{
    const double dp = x > 0.0 ? x : 0.0;
    int lo = 0, hi = K1; /* the last j with d_j <= dp: d[lo] <= dp < d[hi] (d[K1] = inf) */
    while (hi - lo > 1) {
        const int mid = (lo + hi) / 2;
        if (d[mid] <= dp)
            lo = mid;
        else
            hi = mid;
    }
    if (piece)
        *piece = lo;
    if (kd)
        *kd = x > 0.0 ? b[lo] : 0.0;
    if (kE)
        *kE = x > 0.0 ? da[lo] + db[lo] * dp : 0.0;
    return a[lo] + b[lo] * dp;
}

/* The piecewise-linear law of n scenes (rows of K1) at x (m, n): F, and kd, kE and the
   piece (its index in the row) where not NULL (kE needs da, db), (m, n) each. */
void ssw_piecewise(long m, int n, int K1, const double *d, const double *a, const double *b,
                   const double *da, const double *db, const double *x, double *F,
                   double *kd, double *kE, int *piece)
{
    for (long r = 0; r < m; r++)
        for (int i = 0; i < n; i++) {
            const long o = (long)i * K1, q = r * n + i;
            F[q] = piecewise(d + o, a + o, b + o, da ? da + o : 0, db ? db + o : 0, K1, x[q],
                             kd ? kd + q : 0, kE ? kE + q : 0, piece ? piece + q : 0);
        }
}

/* The wall's row of f (and of dF) from the step's own piecewise-linear law. */
static void wall_row(const ssw_chain *c)
{
    const int N = c->N, n = c->n, k = c->k, K1 = c->K1;
    const double *u_last = c->z + (long)(N - 1) * n;
    for (int i = 0; i < n; i++) {
        const long o = (long)i * K1;
        double kd = 0.0, kE = 0.0;
        const int wantE = k && c->c_E >= 0;
        c->f[(long)(N - 1) * n + i] =
            piecewise(c->wd + o, c->wa + o, c->wb + o, wantE ? c->wda + o : 0,
                      wantE ? c->wdb + o : 0, K1, u_last[i], &kd, wantE ? &kE : 0, 0);
        if (k) {
            const double *U = c->ZT + ((long)(N - 1) * n + i) * k;
            double *dF = c->dF + ((long)(N - 1) * n + i) * k;
            for (int p = 0; p < k; p++)
                dF[p] = kd * U[p];
            if (wantE)
                dF[c->c_E] += kE;
        }
    }
}

/* Averaged Hertz forces of m contacts (tests and any caller outside the step), by the
   step's far_forces. */
void ssw_hertz(int m, const double *d, const double *a, double A, double *out, double *fd,
               double *fa)
{
    enum { CHUNK = 64 };
    const double zero[CHUNK] = {0};
    double x[CHUNK];
    for (int q = 0; q < m; q += CHUNK)
        far_forces(m - q < CHUNK ? m - q : CHUNK, d + q, zero, a + q, zero, 1.0, A, x,
                   out + q, fd ? fd + q : 0, fa ? fa + q : 0);
}

/* Row `row` of the record, and the peaks, from the step just taken. */
void ssw_record(const ssw_chain *c, int row)
{
    const int N = c->N, n = c->n, k = c->k, nr = c->n_rec, s = c->s;
    const double *f = c->f;
    double *pair = c->pair + (long)row * 2 * nr;
    for (int i = 0; i < n; i++) {
        pair[i] = f[(s - 1) * n + i];
        pair[nr + i] = f[s * n + i];
        c->wall[(long)row * nr + i] = f[(N - 1) * n + i];
    }
    if (k && c->dpair) {
        double *dp = c->dpair + (long)row * 2 * nr * k;
        memcpy(dp, c->dF + (long)(s - 1) * n * k, sizeof(double) * n * k);
        memcpy(dp + (long)nr * k, c->dF + (long)s * n * k, sizeof(double) * n * k);
    }
    const double *u_last = c->z + (N - 1) * n;
    double *peak_u = c->peak_u, *peak_f = c->peak_f;
    /* as numpy.maximum: a NaN stays (selects without branches: vector loops) */
    for (int i = 0; i < n; i++) {
        const double x = u_last[i], p = peak_u[i];
        peak_u[i] = (x > p || x != x) ? x : p;
    }
    for (int q = 0; q < (N - 1) * n; q++) {
        const double x = f[q], p = peak_f[q];
        peak_f[q] = (x > p || x != x) ? x : p;
    }
}

/* The step's first half: v += dt/2 acc, u += dt v (and the same for the sensitivities; the
   time step's column, c_T, also differentiates the explicit dt: V += acc / 2, U += dt acc
   / 2 + v). */
void ssw_drift(const ssw_chain *c)
{
    const int Nn = c->N * c->n, m = Nn * c->k;
    const double half = 0.5 * c->dt, dt = c->dt;
    double *u = c->z, *v = c->z + Nn;
    for (int i = 0; i < Nn; i++) {
        v[i] += half * c->acc[i];
        u[i] += dt * v[i];
    }
    if (c->k) {
        double *U = c->ZT, *V = c->ZT + m;
        for (int i = 0; i < m; i++) {
            V[i] += half * c->Acc[i];
            U[i] += dt * V[i];
        }
        if (c->c_T >= 0)
            for (int i = 0; i < Nn; i++) {
                const long r = (long)i * c->k + c->c_T;
                const double ha = 0.5 * c->acc[i];
                V[r] += ha;
                U[r] += dt * ha + v[i];
            }
    }
}

/* The bead-bead contacts' Hertz forces (and with the tangent their slopes fd, fa) at the
   drifted state: far_forces on all M = (N - 1) n contacts (x kept in w_x). */
static void contact_forces(const ssw_chain *c, double *w_x, double *w_fd, double *w_fa)
{
    const int n = c->n;
    const double *u = c->z, *v = c->z + c->N * n;
    far_forces((c->N - 1) * n, u, u + n, v, v + n, c->dt, c->A, w_x, c->f, w_fd, w_fa);
}

/* The damping factor K of one contact by the law (dissipation.py), averaged over the step's
   relative motion (d, a = |delta|): the dashpot's closed share, the Kuwabara-Kono averaged
   sqrt, or the Hunt-Crossley elastic force fe (the averaged Hertz force of a bead-bead
   contact, the wall's force at the wall) with its slopes fe_d, fe_a; with gd: dK/dd,
   dK/da (0 at the wall for Hunt-Crossley: the wall's own sensitivities, dF, carry it). */
static inline __attribute__((always_inline)) double damping_factor(
    int law, double d, double a, double fe, double fe_d, double fe_a, double *gd, double *ga)
{
    if (law == KUWABARA_KONO)
        return root_share(d, a, gd, ga);
    if (law == HUNT_CROSSLEY) {
        if (gd) {
            *gd = fe_d;
            *ga = fe_a;
        }
        return fe;
    }
    return closed_share(d, a, gd, ga);
}

/* Per contact, at the drifted state: the relative velocity's sign times dt and the Hertz
   slope fa times it (with the tangent), and with the damping (predict) its predicted
   velocity, its factor K (damping_factor), c K dvp added to f (and to the power), K's
   slopes; the time step's column, its explicit dt slope w_et. The work rows are
   ssw_forces'. */
static inline __attribute__((always_inline)) void contact_rates(const ssw_chain *c, int law,
                                                                int has_old)
{
    const int N = c->N, n = c->n, Nn = N * n, tangent = c->k > 0;
    const int c_T = tangent ? c->c_T : -1;
    const double dt = c->dt, half = 0.5 * dt, cd = c->damping;
    const double *u = c->z, *v = c->z + Nn, *acc = c->acc;
    double *f = c->f, *power = c->power;
    const int predict = c->predict, damped = c->damped_tangent;
    double *w_fd = c->work, *w_fa = w_fd + Nn, *w_sdt = w_fa + Nn, *w_dvp = w_sdt + Nn;
    double *w_sh = w_dvp + Nn, *w_gd = w_sh + Nn, *w_ga = w_gd + Nn, *w_x = w_ga + Nn;
    double *w_et = w_x + Nn;
    for (int j = 0; j < N; j++) {
        const int last = j == N - 1;
        for (int i = 0; i < n; i++) {
            const int q = j * n + i;
            const double d = last ? u[q] : u[q] - u[q + n];
            const double dv = last ? v[q] : v[q] - v[q + n];
            const double a = fabs(dv) * dt;
            /* the Hertz force's slope in |delta| (a bead-bead contact's) */
            double fe_a = 0.0;
            if (tangent) {
                const double sg =
                    dv > 0.0 ? 1.0 : (dv < 0.0 ? -1.0 : (dv == 0.0 ? 0.0 : dv));
                w_sdt[q] = sg * dt;
                if (!last) {
                    fe_a = w_fa[q];
                    w_fa[q] *= w_sdt[q];
                }
                if (c_T >= 0)
                    w_et[q] = fe_a * fabs(dv);
            }
            if (predict) {
                double dvp = dv;
                if (has_old)
                    dvp += half * (last ? acc[q] : acc[q] - acc[q + n]);
                /* Hunt-Crossley's factor: the contact's elastic force and its slopes */
                double fe = 0.0, fe_d = 0.0;
                if (law == HUNT_CROSSLEY) {
                    fe = f[q];
                    fe_d = tangent && !last ? w_fd[q] : 0.0;
                }
                double gd = 0.0, ga = 0.0;
                const double sh = damping_factor(law, d, a, fe, fe_d, fe_a,
                                                 damped ? &gd : 0, damped ? &ga : 0);
                if (cd > 0.0) {
                    f[q] += cd * dvp * sh;
                    if (power)
                        power[i] += cd * dvp * dvp * sh;
                }
                if (tangent) {
                    w_dvp[q] = dvp;
                    w_sh[q] = sh;
                    w_gd[q] = gd;
                    w_ga[q] = ga;
                    if (c_T >= 0 && cd > 0.0) {
                        /* the predicted velocity's explicit dt: acc_old / 2 */
                        const double ao = !has_old ? 0.0 : last ? acc[q] : acc[q] - acc[q + n];
                        w_et[q] += cd * (dvp * ga * fabs(dv) + 0.5 * sh * ao);
                    }
                }
            }
        }
    }
}

/* Contact forces, accelerations and (k > 0) their sensitivities at the drifted state; with
   kick, the step's second half v += dt/2 acc. has_old: acc (and Acc) hold the last step's
   accelerations (the damping's predicted velocity v + dt/2 acc_old); 0 at the start. The
   damping of a closed contact is c K dvp (damping_factor; dvp the predicted relative
   velocity), its tangent c (K dDVP + dvp (K_d dD + K_a sign(dv) dt dDV)); the time step's
   column adds each force's explicit slope in dt (the averaging's |delta| = |dv| dt, the
   predicted velocity's dt/2 acc_old), w_et. */
void ssw_forces(const ssw_chain *c, int has_old, int kick)
{
    const int N = c->N, n = c->n, k = c->k, Nn = N * n;
    const double dt = c->dt, half = 0.5 * dt, cd = c->damping;
    double *f = c->f, *acc = c->acc;
    /* per contact (contact_rates): fd, fa sign(dv) dt, sign(dv) dt, dvp, factor K, K_d, K_a,
       x = d / |delta|, the explicit dt slope */
    double *w_fd = c->work, *w_fa = w_fd + Nn, *w_sdt = w_fa + Nn, *w_dvp = w_sdt + Nn;
    double *w_sh = w_dvp + Nn, *w_gd = w_sh + Nn, *w_ga = w_gd + Nn, *w_x = w_ga + Nn;
    double *w_et = w_x + Nn;
    const int tangent = k > 0, law = c->law, c_T = tangent ? c->c_T : -1;

    if (c->K1)
        wall_row(c);
    if (c->power)
        memset(c->power, 0, sizeof(double) * n);
    contact_forces(c, w_x, tangent ? w_fd : 0, tangent ? w_fa : 0);
    if (tangent || c->predict) {
        /* one loop per law: the law a constant in each (the dashpot's the loop it was) */
        if (c->law == KUWABARA_KONO)
            contact_rates(c, KUWABARA_KONO, has_old);
        else if (c->law == HUNT_CROSSLEY)
            contact_rates(c, HUNT_CROSSLEY, has_old);
        else
            contact_rates(c, DASHPOT, has_old);
    }
    /* m_i a_i = F_(i-1) - F_i (+ P on bead 1) + m_i g, into acc (its old values are not
       needed any more), and with kick v += dt/2 acc; row by row, each a vector loop */
    {
        const double g = c->g, *inv_m = c->inv_m, *pre = c->preload;
        double *vw = c->z + Nn;
        for (int j = 0; j < N; j++) {
            const double *fj = f + (long)j * n, *im = inv_m + (long)j * n;
            double *aj = acc + (long)j * n, *vj = vw + (long)j * n;
            if (j == 0)
                for (int i = 0; i < n; i++)
                    aj[i] = (0.0 - fj[i]) * im[i] + g;
            else if (j == 1 && pre)
                for (int i = 0; i < n; i++)
                    aj[i] = (fj[i - n] - fj[i] + pre[i]) * im[i] + g;
            else
                for (int i = 0; i < n; i++)
                    aj[i] = (fj[i - n] - fj[i]) * im[i] + g;
            if (kick)
                for (int i = 0; i < n; i++)
                    vj[i] += half * aj[i];
        }
    }
    if (tangent) {
        const int m = Nn * k;
        const double *U = c->ZT, *V = c->ZT + m;
        double *dF = c->dF, *Acc = c->Acc;
        for (int j = 0; j < N; j++) {
            const int last = j == N - 1;
            for (int i = 0; i < n; i++) {
                const int q = j * n + i;
                const double fd = w_fd[q], fa = w_fa[q], sdt = w_sdt[q];
                const double dvp = w_dvp[q], sh = w_sh[q];
                const double tD = cd * dvp * w_gd[q], tV = cd * dvp * w_ga[q] * sdt;
                const double tP = cd * sh;
                /* Hunt-Crossley at the wall: c F_w dvp moves with the wall's own dF */
                const int hc_wall = last && law == HUNT_CROSSLEY && cd > 0.0;
                for (int p = 0; p < k; p++) {
                    const int r = q * k + p;
                    const double dD = last ? U[r] : U[r] - U[r + n * k];
                    const double dDV = last ? V[r] : V[r] - V[r + n * k];
                    double df = last ? dF[r] : dD * fd + dDV * fa;
                    if (cd > 0.0) {
                        double dDVP = dDV;
                        if (has_old)
                            dDVP += half * (last ? Acc[r] : Acc[r] - Acc[r + n * k]);
                        df += tP * dDVP + tV * dDV + tD * dD;
                        if (hc_wall)
                            df += cd * dvp * dF[r];
                    }
                    if (p == c->c_D)
                        df += dvp * sh;
                    if (p == c_T)
                        df += w_et[q];
                    dF[r] = df;
                }
            }
        }
        for (int j = 0; j < N; j++)
            for (int i = 0; i < n; i++) {
                const int q = j * n + i;
                for (int p = 0; p < k; p++) {
                    const int r = q * k + p;
                    double dnet = (j ? dF[r - n * k] : 0.0) - dF[r];
                    if (j == 1 && p == c->c_P)
                        dnet += 1.0;
                    Acc[r] = dnet * c->inv_m[q];
                }
            }
        /* the masses' own columns: d(F / m)/dm = -(acc - g) / m */
        for (int t = 0; t < c->n_mass; t++) {
            const int j = c->mass_row[t], p = c->mass_col[t];
            for (int i = 0; i < n; i++) {
                const int q = j * n + i;
                Acc[q * k + p] -= (acc[q] - c->g) * c->inv_m[q];
            }
        }
        if (kick) {
            double *Vw = c->ZT + m;
            for (int r = 0; r < m; r++)
                Vw[r] += half * Acc[r];
            if (c_T >= 0)
                for (int q = 0; q < Nn; q++)
                    Vw[(long)q * k + c_T] += 0.5 * acc[q];
        }
    }
}

/* Steps of a run whose wall row the step writes itself (K1 > 0) or that is held fixed:
   rows times ssw_drift, ssw_forces (has_old, kick) and ssw_record into rows row0 ..
   row0 + rows - 1 of the block buffers: one call for a block of steps. */
void ssw_advance(const ssw_chain *c, int rows, int row0)
{
    for (int r = 0; r < rows; r++) {
        ssw_drift(c);
        ssw_forces(c, 1, 1);
        ssw_record(c, row0 + r);
    }
}

/* numpy's max and argmax of x[0] - base, x[stride] - base, ... (rows values): a NaN is
   the maximum, the first one its index. */
static inline double max_at(const double *x, long stride, int rows, double base, int *at)
{
    double m = x[0] - base;
    *at = 0;
    for (int r = 1; r < rows && m == m; r++) {
        const double v = x[r * stride] - base;
        if (v > m || v != v) {
            m = v;
            *at = r;
        }
    }
    return m;
}

/* The early-stop rule over a block (ssw.chain.integrate._StopRule.update, whose docstring
   states it): rows (rows, n) of the sensor S and the wall force W (row stride `stride`),
   their times; k = (INCIDENT_END, WALL_RELEASE, TRAVEL_FACTOR, TAIL_CONTACTS); the per
   scene state, rows of n: F = sensor0, wall0, f_noise, t_c (the baselines, the noise
   force, the contact time), inc_max, t_inc, t_onset, w_max, t_rel and B = inc_done,
   released, updated; done: the scenes that may stop. The same IEEE operations as the
   numpy expressions of the rule. */
void ssw_stop_update(int rows, int n, long stride, const double *S, const double *W,
                     const double *times, const double *k, double *F, unsigned char *B,
                     unsigned char *done)
{
    const double *sensor0 = F, *wall0 = F + n, *f_noise = F + 2 * n, *t_c = F + 3 * n;
    double *inc_max = F + 4 * n, *t_inc = F + 5 * n, *t_onset = F + 6 * n;
    double *w_max = F + 7 * n, *t_rel = F + 8 * n;
    unsigned char *inc_done = B, *released = B + n;
    const double t_last = times[rows - 1];
    for (int i = 0; i < n; i++) {
        /* the incident pulse: its peak, and its fall below INCIDENT_END of it */
        int at, first = -1;
        const double bm = max_at(S + i, stride, rows, sensor0[i], &at);
        if (!inc_done[i] && bm > inc_max[i]) {
            inc_max[i] = bm;
            t_inc[i] = times[at];
        }
        const double s_last = S[(rows - 1) * stride + i] - sensor0[i];
        inc_done[i] |= (inc_max[i] > f_noise[i]) & (s_last < k[0] * inc_max[i]);
        /* the wall force: its onset above the noise, its peak and its release */
        const double wm = max_at(W + i, stride, rows, wall0[i], &at);
        for (int r = 0; r < rows && first < 0; r++)
            if (W[r * stride + i] - wall0[i] > f_noise[i])
                first = r;
        if (t_onset[i] != t_onset[i] && first >= 0)
            t_onset[i] = times[first];
        if (!released[i] && wm > w_max[i])
            w_max[i] = wm;
        const double w_last = W[(rows - 1) * stride + i] - wall0[i];
        const int newly = !released[i] && inc_done[i] && w_max[i] > f_noise[i] &&
                          w_last < k[1] * w_max[i];
        released[i] |= newly;
        if (newly)
            t_rel[i] = t_last;
        /* numpy.nan_to_num of the sensor-to-wall travel time */
        double travel = t_onset[i] - t_inc[i];
        if (travel != travel)
            travel = 0.0;
        else if (isinf(travel))
            travel = travel > 0.0 ? DBL_MAX : -DBL_MAX;
        travel = travel + t_c[i];
        done[i] = released[i] && t_last > t_rel[i] + k[2] * travel + k[3] * t_c[i];
    }
}
