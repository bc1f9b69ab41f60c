/* The chain's velocity-Verlet step, compiled (ssw.chain.kernel loads it through ctypes).

   The physics is documented in ssw/chain/integrate.py (the scheme, the damping's predicted
   velocity, the forward sensitivities, the time step's own column), ssw/chain/impulse.py
   (the contact laws averaged over the step's relative motion: psi, its series far from
   events, the dashpot's closed share Phi, the averaged sqrt) and ssw/chain/dissipation.py
   (the dissipation laws). Arrays are C-contiguous doubles: bead quantities (N, n), their
   sensitivities (N, n, k), positions and velocities stacked (2, N, n) and (2, N, n, k);
   contact j joins beads j and j + 1, contact N - 1 is the wall (its force, and its
   sensitivities, are written by the caller before ssw_forces: any wall law, with or
   without state; or by the step itself, for a piecewise-linear law,
   ssw.walls.fem.PiecewiseLinearWall, and for a power law, ssw.chain.wall_power.PowerWall).

   No Python C-API: a plain shared library, built by setuptools with the package (setup.py)
   and checked by its loader against this file's hash (SSW_STEP_SOURCE), its constants and
   the layout of ssw_chain (ssw_chain_layout). Portable C99 for GCC, Clang and MSVC; what
   differs between them is behind #if at the top: exports, inlining, the SIMD lanes of the
   far law (x86-64 intrinsics, or the scalar path) and the CPU's features.

   Every exported function checks the sizes it is given and returns 0, or an error code
   (ssw_step_error: the size refused, and what is allowed) without touching an array.

   Arithmetic: IEEE operations one by one, in the order written. No fused multiply-add
   (which rounds once where the code rounds twice: the SIMD lanes, the scalar path and every
   compiler give the same bits only without it): contraction off here for the compilers that
   take a pragma, and in setup.py's flags (-ffp-contract=off; MSVC's /fp:precise, whose
   contraction is off by default from Visual Studio 2022 on and, by the pragma, before). No
   -ffast-math: the step tests NaN and signed zeros. */
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#elif defined(__GNUC__)
/* GCC ignores the STDC pragma (and fuses by default in GNU C) */
#pragma GCC optimize("fp-contract=off")
#elif defined(_MSC_VER)
#pragma fp_contract(off)
#endif
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

/* Exported functions, inlining */
#if defined(_WIN32)
#define SSW_API __declspec(dllexport)
#elif defined(__GNUC__)
#define SSW_API __attribute__((visibility("default")))
#else
#define SSW_API
#endif
#if defined(_MSC_VER) && !defined(__clang__)
#define SSW_INLINE static __inline
#define SSW_ALWAYS_INLINE static __forceinline
#define SSW_NOINLINE static __declspec(noinline)
#elif defined(__GNUC__)
#define SSW_INLINE static inline
#define SSW_ALWAYS_INLINE static inline __attribute__((always_inline))
#define SSW_NOINLINE static __attribute__((noinline))
#else
#define SSW_INLINE static inline
#define SSW_ALWAYS_INLINE static inline
#define SSW_NOINLINE static
#endif

/* The far law's SIMD lanes: x86-64 intrinsics (AVX2 where the CPU and the OS have it, else
   SSE2; -DSSW_NO_AVX2: SSE2) with GCC, Clang and MSVC; the scalar path elsewhere, or with
   -DSSW_SCALAR. */
#if !defined(SSW_SCALAR) && (defined(__GNUC__) || defined(_MSC_VER)) &&                   \
    (defined(__x86_64__) || (defined(_M_X64) && !defined(_M_ARM64EC)))
#define SSW_X86_LANES 1
#include <immintrin.h>
#if defined(_MSC_VER) && !defined(__clang__)
#include <intrin.h>
#define SSW_MSVC_X86 1
#else
#include <cpuid.h>
#endif
#endif

/* The hash of the source built in (setup.py: -DSSW_STEP_SOURCE=<16 hex digits>, a bare
   token made a string here: no quotes to survive a command line) */
#define SSW_STR_(x) #x
#define SSW_STR(x) SSW_STR_(x)
#ifdef SSW_STEP_SOURCE
#define SSW_SOURCE_DIGEST SSW_STR(SSW_STEP_SOURCE)
#else
#define SSW_SOURCE_DIGEST "unknown"
#endif

/* ssw.chain.impulse.FAR, SERIES and ROOT_SERIES */
#define FAR 20.0
#define C1 (1.0 / 16.0)
#define C2 (1.0 / 640.0)
#define R1 (1.0 / 48.0)
#define R2 (1.0 / 384.0)
#define R3 (3.0 / 4096.0)
/* scratch doubles per contact (ssw.chain.kernel.WORK_BLOCKS): WORK_BLOCKS N n + N n k */
#define WORK_BLOCKS 9

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
    double *work;         /* scratch: WORK_BLOCKS N n + N n k doubles */
    /* the record (ssw_record): the sensor's two contacts, the wall force, their
       sensitivities, in block buffers of rec_rows rows whose scene axis has stride n_rec
       (the run's first n); the largest wall indentation and bead-bead forces so far (n) and
       (N - 1, n) */
    int s, n_rec, rec_rows;
    double *pair;         /* (rec_rows, 2, n_rec) */
    double *wall;         /* (rec_rows, n_rec) */
    double *dpair;        /* (rec_rows, 2, n_rec, k) or NULL */
    double *peak_u;       /* (n) */
    double *peak_f;       /* (N - 1, n) */
    /* a piecewise-linear wall the step evaluates itself (ssw_piecewise; K1 > 0), its rows
       (n, K1): breakpoints (m), a (N), b (N/m), da/dE and db/dE (or NULL); c_E the
       modulus's sensitivity column (-1: none). K1 = 0: the caller writes the wall row. */
    int K1, c_E;
    double *wd, *wa, *wb, *wda, *wdb;
    /* a power law the step evaluates itself (ssw_power_law; power_law = 1, K1 = 0), its
       rows (n): coef (N/m^e), e, dcoef/dE (N/m^e/Pa, or NULL) and de/dE (1/Pa, or NULL:
       constant). power_law = 0: none. */
    int power_law;
    double *pc, *pe, *pdc, *pde;
} ssw_chain;

/* ssw_chain's fields in their order, for the loader's check of its ctypes mirror
   (ssw_chain_layout): a field added above and not here changes sizeof(ssw_chain), or
   leaves the mirror with a field the C side does not name */
#define SSW_CHAIN_FIELDS(X)                                                                 \
    X(N) X(n) X(k) X(predict) X(damped_tangent) X(law) X(c_D) X(c_P) X(c_T) X(n_mass)       \
    X(mass_row) X(mass_col) X(A) X(dt) X(damping) X(g) X(z) X(acc) X(inv_m) X(preload)      \
    X(f) X(power) X(ZT) X(Acc) X(dF) X(work) X(s) X(n_rec) X(rec_rows) X(pair) X(wall)      \
    X(dpair) X(peak_u) X(peak_f) X(K1) X(c_E) X(wd) X(wa) X(wb) X(wda) X(wdb)          \
    X(power_law) X(pc) X(pe) X(pdc) X(pde)

/* The exported functions' answers: 0, or the size they refused (ssw_step_error) */
enum {
    SSW_OK = 0,
    E_BEADS,
    E_SCENES,
    E_COLUMNS,
    E_INDEX,
    E_COLUMN,
    E_MASS,
    E_LAW,
    E_ARRAY,
    E_WALL_LAW,
    E_RECORD,
    E_ROW,
    E_COUNT,
    E_BREAKPOINTS,
    E_ROWS,
    E_STRIDE,
    E_CAPACITY,
    E_CODES
};

static const char *const ERRORS[E_CODES] = {
    "no error",
    "N, the beads: at least 2",
    "n, the scenes: at least 0",
    "k, the sensitivity columns: at least 0",
    "N n (WORK_BLOCKS + k), the largest index: at most INT_MAX (run the scenes in batches)",
    "c_D, c_P, c_T and c_E, the sensitivity columns: -1 (none) or 0 .. k - 1",
    "n_mass, the masses differentiated: 0, 1 or 2, their beads 0 .. N - 1 and columns "
    "0 .. k - 1",
    "law, the dissipation law: 0 (dashpot), 1 (Kuwabara-Kono) or 2 (Hunt-Crossley)",
    "an array the call needs is NULL",
    "the step's wall law: K1, the piecewise law's breakpoints per scene, 0 (none) or at "
    "least 1 with its rows wd, wa, wb (and wda, wdb with the modulus's column c_E); "
    "power_law, 0 (none) or 1 with K1 = 0 and its rows pc, pe (and pdc with c_E); neither: "
    "the caller writes the wall row",
    "the record: s, the sensor bead, 1 .. N - 1; n_rec >= n scenes; pair and wall set; "
    "rec_rows >= 1 (ssw.chain.kernel.Stepper.start_record)",
    "row, the record's row: 0 .. rec_rows - 1, a block's rows >= 0 within them",
    "m and n, the values' rows and scenes: at least 0",
    "K1, the piecewise law's breakpoints per scene: at least 1",
    "rows, the block's rows: at least 1",
    "stride, the block's row stride (doubles): at least n",
    "cap, the output's capacity: too small (ssw_step_constants: 7; ssw_chain_layout: 1 + 2 "
    "per field)",
};

SSW_API const char *ssw_step_error(int code)
{
    return code >= 0 && code < E_CODES ? ERRORS[code] : "unknown error code";
}

SSW_API const char *ssw_step_source(void) { return SSW_SOURCE_DIGEST; }

/* FAR, C1, C2, R1, R2 and R3, for the loader's check against ssw.chain.impulse, and
   WORK_BLOCKS, against ssw.chain.kernel's (7 doubles). */
SSW_API int ssw_step_constants(double *out, int cap)
{
    if (!out)
        return E_ARRAY;
    if (cap < 7)
        return E_CAPACITY;
    out[0] = FAR;
    out[1] = C1;
    out[2] = C2;
    out[3] = R1;
    out[4] = R2;
    out[5] = R3;
    out[6] = WORK_BLOCKS;
    return SSW_OK;
}

/* The names of ssw_chain's fields, in order, separated by spaces. */
SSW_API const char *ssw_chain_fields(void)
{
#define SSW_NAME(f) #f " "
    return SSW_CHAIN_FIELDS(SSW_NAME);
#undef SSW_NAME
}

/* sizeof(ssw_chain), then each field's offsetof and sizeof in ssw_chain_fields' order
   (bytes): 1 + 2 per field values in out (cap of them). */
SSW_API int ssw_chain_layout(int64_t *out, int cap)
{
#define SSW_AT(f) (int64_t)offsetof(ssw_chain, f), (int64_t)sizeof(((ssw_chain *)0)->f),
    const int64_t v[] = {(int64_t)sizeof(ssw_chain), SSW_CHAIN_FIELDS(SSW_AT)};
#undef SSW_AT
    const int len = (int)(sizeof v / sizeof v[0]);
    if (!out)
        return E_ARRAY;
    if (cap < len)
        return E_CAPACITY;
    memcpy(out, v, sizeof v);
    return SSW_OK;
}

/* The sizes and arrays a chain's step reads and writes (0, or an error code). */
static int chain_error(const ssw_chain *c)
{
    if (!c)
        return E_ARRAY;
    const int N = c->N, n = c->n, k = c->k;
    if (N < 2)
        return E_BEADS;
    if (n < 0)
        return E_SCENES;
    if (k < 0)
        return E_COLUMNS;
    if ((int64_t)N * n > INT_MAX / ((int64_t)WORK_BLOCKS + k))
        return E_INDEX;
    if (c->c_D < -1 || c->c_D >= k || c->c_P < -1 || c->c_P >= k || c->c_T < -1 ||
        c->c_T >= k || c->c_E < -1 || c->c_E >= k)
        return E_COLUMN;
    if (c->n_mass < 0 || c->n_mass > 2)
        return E_MASS;
    for (int t = 0; k > 0 && t < c->n_mass; t++)
        if (c->mass_row[t] < 0 || c->mass_row[t] >= N || c->mass_col[t] < 0 ||
            c->mass_col[t] >= k)
            return E_MASS;
    if (c->law < DASHPOT || c->law > HUNT_CROSSLEY)
        return E_LAW;
    if (!c->z || !c->acc || !c->inv_m || !c->f || !c->work || !c->peak_u || !c->peak_f ||
        (k > 0 && (!c->ZT || !c->Acc || !c->dF)))
        return E_ARRAY;
    if (c->K1 < 0 || (c->K1 > 0 && (!c->wd || !c->wa || !c->wb ||
                                    (k > 0 && c->c_E >= 0 && (!c->wda || !c->wdb)))))
        return E_WALL_LAW;
    if (c->power_law < 0 || c->power_law > 1 ||
        (c->power_law && (c->K1 || !c->pc || !c->pe || (k > 0 && c->c_E >= 0 && !c->pdc))))
        return E_WALL_LAW;
    return SSW_OK;
}

/* The record's buffers and rows row0 .. row0 + rows - 1 of them (0, or an error code). */
static int record_error(const ssw_chain *c, int row0, int rows)
{
    if (!c->pair || !c->wall || c->rec_rows < 1 || c->n_rec < c->n || c->s < 1 ||
        c->s > c->N - 1)
        return E_RECORD;
    if (row0 < 0 || rows < 0 || row0 > c->rec_rows - rows)
        return E_ROW;
    return SSW_OK;
}

/* (y)_+^(7/2) and (y)_+^(5/2) */
SSW_INLINE void pow_plus(double y, double *p35, double *p25)
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
SSW_INLINE int near_event(double x) { return x > -1.0 && x < FAR; }

SSW_INLINE double hertz_near(double x, double a, double A, double *fd, double *fa)
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

/* The far law of M contacts, d = d1 - d0, a = |v1 - v0| dt, x = d / a (kept in x),
   d_+ = max(d, 0) (NaN: 0), r = min(1 / x^2, 1) (NaN: 1):
   F = A d_+ sqrt(d_+) (1 + r C1 + r^2 C2) and, with fd, fa,
   dF/dd = A sqrt(d_+) (1.5 poly - 2 r dpoly), dF/d|delta| = 2 A dpoly a / sqrt(d_+)
   (0 for d_+ = 0), dpoly = C1 + 2 C2 r; then hertz_near in the contacts near an event
   (near_lanes). In SIMD lanes (FAR_FORCES) or one contact at a time (the scalar path): the
   same operations in the same order, so the same bits, whatever the path. */
#ifdef SSW_X86_LANES
/* One ISA's lanes: the vector type and its operations (AVX: 4 doubles, SSE2: 2). The
   comparisons are C's (ordered: false for NaN), the square root the correctly rounded
   one. MSVC does not clear the upper halves of the AVX registers before SSE code by
   itself: V4_LEAVE does. */
#define V4_T __m256d
#define V4_SET1 _mm256_set1_pd
#define V4_LOAD _mm256_loadu_pd
#define V4_STORE _mm256_storeu_pd
#define V4_ADD _mm256_add_pd
#define V4_SUB _mm256_sub_pd
#define V4_MUL _mm256_mul_pd
#define V4_DIV _mm256_div_pd
#define V4_SQRT _mm256_sqrt_pd
#define V4_AND _mm256_and_pd
#define V4_ANDNOT _mm256_andnot_pd
#define V4_OR _mm256_or_pd
#define V4_GT(a, b) _mm256_cmp_pd(a, b, _CMP_GT_OS)
#define V4_LT(a, b) _mm256_cmp_pd(a, b, _CMP_LT_OS)
#define V4_MASK _mm256_movemask_pd
#ifdef SSW_MSVC_X86
#define V4_LEAVE() _mm256_zeroupper()
#define SSW_AVX2
#else
#define V4_LEAVE() ((void)0)
#define SSW_AVX2 __attribute__((target("avx2")))
#endif
#define V2_T __m128d
#define V2_SET1 _mm_set1_pd
#define V2_LOAD _mm_loadu_pd
#define V2_STORE _mm_storeu_pd
#define V2_ADD _mm_add_pd
#define V2_SUB _mm_sub_pd
#define V2_MUL _mm_mul_pd
#define V2_DIV _mm_div_pd
#define V2_SQRT _mm_sqrt_pd
#define V2_AND _mm_and_pd
#define V2_ANDNOT _mm_andnot_pd
#define V2_OR _mm_or_pd
#define V2_GT _mm_cmpgt_pd
#define V2_LT _mm_cmplt_pd
#define V2_MASK _mm_movemask_pd
#define V2_LEAVE() ((void)0)

/* NAME(M, ...): the far law in W lanes of the ISA V (V2, V4), rows of M; the last partial
   vector through a padded copy. NAME_lanes: one vector; whether a lane is near an event. */
#define FAR_FORCES(NAME, W, V, ATTR)                                                        \
    ATTR SSW_ALWAYS_INLINE int NAME##_lanes(const double *d1, const double *d0,             \
                                            const double *v1, const double *v0, double dt,  \
                                            double A, double *x_out, double *f, double *fd, \
                                            double *fa)                                     \
    {                                                                                       \
        const V##_T zero = V##_SET1(0.0), one = V##_SET1(1.0);                              \
        const V##_T d = V##_SUB(V##_LOAD(d1), V##_LOAD(d0));                                \
        const V##_T a = V##_MUL(V##_ANDNOT(V##_SET1(-0.0), V##_SUB(V##_LOAD(v1),            \
                                                                   V##_LOAD(v0))),          \
                                V##_SET1(dt));                                              \
        const V##_T x = V##_DIV(d, a);                                                      \
        const V##_T dp = V##_AND(V##_GT(d, zero), d);                                       \
        const V##_T sq = V##_SQRT(dp);                                                      \
        const V##_T r0 = V##_DIV(one, V##_MUL(x, x)), low = V##_LT(r0, one);                \
        const V##_T r = V##_OR(V##_AND(low, r0), V##_ANDNOT(low, one));                     \
        const V##_T poly =                                                                  \
            V##_ADD(one, V##_MUL(r, V##_ADD(V##_SET1(C1), V##_MUL(r, V##_SET1(C2)))));      \
        V##_STORE(x_out, x);                                                                \
        V##_STORE(f, V##_MUL(V##_MUL(V##_MUL(V##_SET1(A), dp), sq), poly));                 \
        if (fd) {                                                                           \
            const V##_T dpoly = V##_ADD(V##_SET1(C1), V##_MUL(V##_SET1(2.0 * C2), r));      \
            const V##_T inner = V##_SUB(V##_MUL(V##_SET1(1.5), poly),                       \
                                        V##_MUL(V##_MUL(V##_SET1(2.0), r), dpoly));         \
            const V##_T Fa =                                                                \
                V##_DIV(V##_MUL(V##_MUL(V##_SET1(2.0 * A), dpoly), a), sq);                 \
            V##_STORE(fd, V##_MUL(V##_MUL(V##_SET1(A), sq), inner));                        \
            V##_STORE(fa, V##_AND(V##_GT(dp, zero), Fa));                                   \
        }                                                                                   \
        return V##_MASK(V##_AND(V##_GT(x, V##_SET1(-1.0)), V##_LT(x, V##_SET1(FAR)))) != 0; \
    }                                                                                       \
    ATTR static void NAME(int M, const double *d1, const double *d0, const double *v1,      \
                          const double *v0, double dt, double A, double *x, double *f,      \
                          double *fd, double *fa)                                           \
    {                                                                                       \
        int q = 0;                                                                          \
        for (; q + W <= M; q += W)                                                          \
            if (NAME##_lanes(d1 + q, d0 + q, v1 + q, v0 + q, dt, A, x + q, f + q,           \
                             fd ? fd + q : 0, fa ? fa + q : 0)) {                           \
                V##_LEAVE();                                                                \
                near_lanes(q, W, v1, v0, dt, A, x, f, fd, fa);                              \
            }                                                                               \
        if (q < M) {                                                                        \
            double b[7][W] = {{0}};                                                         \
            const int r = M - q;                                                            \
            memcpy(b[0], d1 + q, sizeof(double) * r);                                       \
            memcpy(b[1], d0 + q, sizeof(double) * r);                                       \
            memcpy(b[2], v1 + q, sizeof(double) * r);                                       \
            memcpy(b[3], v0 + q, sizeof(double) * r);                                       \
            NAME##_lanes(b[0], b[1], b[2], b[3], dt, A, b[4], b[5], fd ? b[6] : 0,          \
                         fd ? b[0] : 0);                                                    \
            V##_LEAVE();                                                                    \
            memcpy(x + q, b[4], sizeof(double) * r);                                        \
            memcpy(f + q, b[5], sizeof(double) * r);                                        \
            if (fd) {                                                                       \
                memcpy(fd + q, b[6], sizeof(double) * r);                                   \
                memcpy(fa + q, b[0], sizeof(double) * r);                                   \
            }                                                                               \
            near_lanes(q, r, v1, v0, dt, A, x, f, fd, fa);                                  \
        }                                                                                   \
        V##_LEAVE();                                                                        \
    }

FAR_FORCES(far_avx2, 4, V4, SSW_AVX2)
FAR_FORCES(far_sse2, 2, V2, )

/* The lanes of this CPU (ssw_step_lanes): 4 where AVX2 runs, else 2 (SSE2, every x86-64).
   Written once while the library is loaded (load_lanes), before the loader returns it to
   anyone, and only read after: no call of the step races it. */
static int lanes = 2;

/* CPUID's EAX, EBX, ECX, EDX for a leaf and sub-leaf */
static void cpuid(unsigned leaf, unsigned sub, unsigned r[4])
{
#ifdef SSW_MSVC_X86
    int x[4];
    __cpuidex(x, (int)leaf, (int)sub);
    for (int i = 0; i < 4; i++)
        r[i] = (unsigned)x[i];
#else
    __cpuid_count(leaf, sub, r[0], r[1], r[2], r[3]);
#endif
}

/* XCR0: the register state the OS saves (bit 1 SSE, bit 2 AVX) */
static uint64_t xcr0(void)
{
#ifdef SSW_MSVC_X86
    return _xgetbv(0);
#else
    uint32_t lo, hi;
    __asm__ __volatile__("xgetbv" : "=a"(lo), "=d"(hi) : "c"(0));
    return ((uint64_t)hi << 32) | lo;
#endif
}

/* AVX2 usable: the CPU has it (CPUID 7.0 EBX bit 5) and AVX with the OS's XSAVE (CPUID 1
   ECX bits 28 and 27), and the OS saves the SSE and AVX state (XCR0 bits 1, 2). Not
   __builtin_cpu_supports: on x86-64 macOS it needs libgcc's ___cpu_model, which Apple's
   toolchain does not link (the library would not load). */
static int has_avx2(void)
{
    unsigned r[4];
    cpuid(0, 0, r);
    if (r[0] < 7)
        return 0;
    cpuid(1, 0, r);
    if ((r[2] & (3u << 27)) != (3u << 27) || (xcr0() & 6) != 6)
        return 0;
    cpuid(7, 0, r);
    return (r[1] >> 5) & 1;
}

/* -DSSW_NO_AVX2: SSE2 whatever the CPU (the tests compare the lanes' paths on one machine) */
#ifdef SSW_NO_AVX2
#define SSW_AVX2_ALLOWED 0
#else
#define SSW_AVX2_ALLOWED 1
#endif
static void load_lanes(void) { lanes = SSW_AVX2_ALLOWED && has_avx2() ? 4 : 2; }

#ifdef SSW_MSVC_X86
/* The DLL's entry point: the C runtime's calls it once on load (DLL_PROCESS_ATTACH, 1),
   before LoadLibrary returns. Declared without windows.h, whose FAR and near macros this
   file's names would meet. */
int __stdcall DllMain(void *module, unsigned long reason, void *reserved)
{
    (void)module;
    (void)reserved;
    if (reason == 1)
        load_lanes();
    return 1;
}
#else
/* run by the dynamic loader, before dlopen returns */
__attribute__((constructor)) static void load(void) { load_lanes(); }
#endif

static void far_forces(int M, const double *d1, const double *d0, const double *v1,
                       const double *v0, double dt, double A, double *x, double *f,
                       double *fd, double *fa)
{
    (lanes == 4 ? far_avx2 : far_sse2)(M, d1, d0, v1, v0, dt, A, x, f, fd, fa);
}
#else
/* The scalar path: one contact at a time, the lanes' operations in their order. */
static const int lanes = 1;

static void far_forces(int M, const double *d1, const double *d0, const double *v1,
                       const double *v0, double dt, double A, double *x, double *f,
                       double *fd, double *fa)
{
    for (int q = 0; q < M; q++) {
        const double d = d1[q] - d0[q], a = fabs(v1[q] - v0[q]) * dt, xq = d / a;
        const double dp = d > 0.0 ? d : 0.0, sq = sqrt(dp);
        double r = 1.0 / (xq * xq);
        if (!(r < 1.0))
            r = 1.0;
        const double poly = 1.0 + r * (C1 + r * C2);
        x[q] = xq;
        f[q] = A * dp * sq * poly;
        if (fd) {
            const double dpoly = C1 + 2.0 * C2 * r;
            fd[q] = A * sq * (1.5 * poly - 2.0 * r * dpoly);
            fa[q] = dp > 0.0 ? 2.0 * A * dpoly * a / sq : 0.0;
        }
    }
    near_lanes(0, M, v1, v0, dt, A, x, f, fd, fa);
}
#endif

/* The far law's SIMD lanes: 4 (AVX2), 2 (SSE2) or 1 (the scalar path). */
SSW_API int ssw_step_lanes(void) { return lanes; }

/* The hat-weighted share Phi(d / a) of the step a contact is closed, and its slopes (the
   dashpot's factor). */
SSW_INLINE double closed_share(double d, double a, double *gd, double *ga)
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
SSW_INLINE void pow_half(double y, double *p25, double *p15)
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
SSW_INLINE double root_share(double d, double a, double *gd, double *ga)
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
SSW_INLINE double piecewise(const double *d, const double *a, const double *b,
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
SSW_API int ssw_piecewise(int64_t m, int n, int K1, const double *d, const double *a,
                          const double *b, const double *da, const double *db,
                          const double *x, double *F, double *kd, double *kE, int *piece)
{
    if (m < 0 || n < 0)
        return E_COUNT;
    if (K1 < 1)
        return E_BREAKPOINTS;
    if (!d || !a || !b || !x || !F || (kE && (!da || !db)))
        return E_ARRAY;
    for (ptrdiff_t r = 0; r < m; r++)
        for (int i = 0; i < n; i++) {
            const ptrdiff_t o = (ptrdiff_t)i * K1, q = r * n + i;
            F[q] = piecewise(d + o, a + o, b + o, da ? da + o : 0, db ? db + o : 0, K1, x[q],
                             kd ? kd + q : 0, kE ? kE + q : 0, piece ? piece + q : 0);
        }
    return SSW_OK;
}

/* The wall's row of f (and of dF) from the step's own piecewise-linear law. */
static void wall_row(const ssw_chain *c)
{
    const int N = c->N, n = c->n, k = c->k, K1 = c->K1;
    const double *u_last = c->z + (ptrdiff_t)(N - 1) * n;
    for (int i = 0; i < n; i++) {
        const ptrdiff_t o = (ptrdiff_t)i * K1;
        double kd = 0.0, kE = 0.0;
        const int wantE = k && c->c_E >= 0;
        c->f[(ptrdiff_t)(N - 1) * n + i] =
            piecewise(c->wd + o, c->wa + o, c->wb + o, wantE ? c->wda + o : 0,
                      wantE ? c->wdb + o : 0, K1, u_last[i], &kd, wantE ? &kE : 0, 0);
        if (k) {
            const double *U = c->ZT + ((ptrdiff_t)(N - 1) * n + i) * k;
            double *dF = c->dF + ((ptrdiff_t)(N - 1) * n + i) * k;
            for (int p = 0; p < k; p++)
                dF[p] = kd * U[p];
            if (wantE)
                dF[c->c_E] += kE;
        }
    }
}

/* The power law F = coef dp^e at the indentation x, dp = max(x, 0) (numpy's maximum: a
   NaN stays), ssw.chain.wall_power.PowerWall's operations in their order: with hertzian
   (every exponent of the law 1.5) F = (coef dp) sqrt(dp), kd = (1.5 coef) sqrt(dp), dn =
   dp sqrt(dp); else F = coef pow(dp, e), kd = (e coef) pow(dp, e - 1) (0 unless dp > 0), dn
   = pow(dp, e). With kE (needs dc): dF/dE = dc dn, plus ((coef dn) ln(dp) de with de (ln 1
   = 0 unless dp > 0). kd, kE: NULL where not wanted. */
SSW_INLINE double power_law(double coef, double e, double dc, const double *de,
                            int hertzian, double x, double *kd, double *kE)
{
    const double dp = (x > 0.0 || x != x) ? x : 0.0;
    double F, dn;
    if (hertzian) {
        const double sq = sqrt(dp);
        F = coef * dp * sq;
        dn = dp * sq;
        if (kd)
            *kd = 1.5 * coef * sq;
    } else {
        dn = pow(dp, e);
        F = coef * dn;
        if (kd)
            *kd = dp > 0.0 ? e * coef * pow(dp, e - 1.0) : 0.0;
    }
    if (kE) {
        double out = dc * dn;
        if (de)
            out = out + coef * dn * log(dp > 0.0 ? dp : 1.0) * *de;
        *kE = out;
    }
    return F;
}

/* Every exponent of a power law of n scenes is 1.5 (PowerWall.hertzian: its sqrt form). */
SSW_INLINE int all_hertzian(const double *e, int64_t n)
{
    int h = 1;
    for (int64_t i = 0; i < n; i++)
        h &= e[i] == 1.5;
    return h;
}

/* The power law of m values (ssw.chain.wall_power.PowerWall), each with its own coef, e,
   dc, de (dc, de may be NULL; de NULL: constant exponents) at x: F, and kd, kE where not
   NULL (kE needs dc); the sqrt form where hertzian is 1 (the caller's law has every
   exponent 1.5). */
SSW_API int ssw_power_law(int64_t m, int hertzian, const double *coef, const double *e,
                          const double *dc, const double *de, const double *x, double *F,
                          double *kd, double *kE)
{
    if (m < 0)
        return E_COUNT;
    if (!coef || !e || !x || !F || (kE && !dc))
        return E_ARRAY;
    for (int64_t q = 0; q < m; q++)
        F[q] = power_law(coef[q], e[q], dc ? dc[q] : 0.0, de ? de + q : 0, hertzian != 0, x[q],
                         kd ? kd + q : 0, kE ? kE + q : 0);
    return SSW_OK;
}

/* The wall's row of f (and of dF) from the step's own power law, as the caller's
   (ssw.chain.integrate._WallDrive.write_row): dF = U kd, then dF[c_E] += kE. Its sqrt form
   while every current scene's exponent is 1.5 (as PowerWall.take's law of the scenes
   kept). */
static void power_row(const ssw_chain *c)
{
    const int N = c->N, n = c->n, k = c->k;
    const int wantE = k && c->c_E >= 0, hertzian = all_hertzian(c->pe, n);
    const double *u_last = c->z + (ptrdiff_t)(N - 1) * n;
    for (int i = 0; i < n; i++) {
        double kd = 0.0, kE = 0.0;
        c->f[(ptrdiff_t)(N - 1) * n + i] =
            power_law(c->pc[i], c->pe[i], wantE ? c->pdc[i] : 0.0,
                      wantE && c->pde ? c->pde + i : 0, hertzian, u_last[i], k ? &kd : 0,
                      wantE ? &kE : 0);
        if (k) {
            const double *U = c->ZT + ((ptrdiff_t)(N - 1) * n + i) * k;
            double *dF = c->dF + ((ptrdiff_t)(N - 1) * n + i) * k;
            for (int p = 0; p < k; p++)
                dF[p] = U[p] * kd;
            if (wantE)
                dF[c->c_E] += kE;
        }
    }
}

/* Averaged Hertz forces of m contacts (tests and any caller outside the step), by the
   step's far_forces; fd and fa both or neither. */
SSW_API int ssw_hertz(int64_t m, const double *d, const double *a, double A, double *out,
                      double *fd, double *fa)
{
    enum { CHUNK = 64 };
    const double zero[CHUNK] = {0};
    double x[CHUNK];
    if (m < 0)
        return E_COUNT;
    if (!d || !a || !out || !fd != !fa)
        return E_ARRAY;
    for (ptrdiff_t q = 0; q < m; q += CHUNK)
        far_forces(m - q < CHUNK ? (int)(m - q) : CHUNK, d + q, zero, a + q, zero, 1.0, A, x,
                   out + q, fd ? fd + q : 0, fa ? fa + q : 0);
    return SSW_OK;
}

/* Row `row` of the record, and the peaks, from the step just taken. */
SSW_NOINLINE void record(const ssw_chain *c, int row)
{
    const int N = c->N, n = c->n, k = c->k, nr = c->n_rec, s = c->s;
    const double *f = c->f;
    double *pair = c->pair + (ptrdiff_t)row * 2 * nr;
    for (int i = 0; i < n; i++) {
        pair[i] = f[(s - 1) * n + i];
        pair[nr + i] = f[s * n + i];
        c->wall[(ptrdiff_t)row * nr + i] = f[(N - 1) * n + i];
    }
    if (k && c->dpair) {
        double *dp = c->dpair + (ptrdiff_t)row * 2 * nr * k;
        memcpy(dp, c->dF + (ptrdiff_t)(s - 1) * n * k, sizeof(double) * n * k);
        memcpy(dp + (ptrdiff_t)nr * k, c->dF + (ptrdiff_t)s * n * k, sizeof(double) * n * k);
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
SSW_NOINLINE void drift(const ssw_chain *c)
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
                const ptrdiff_t r = (ptrdiff_t)i * c->k + c->c_T;
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
SSW_ALWAYS_INLINE double damping_factor(
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
SSW_ALWAYS_INLINE void contact_rates(const ssw_chain *c, int law, int has_old)
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
SSW_NOINLINE void forces(const ssw_chain *c, int has_old, int kick)
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
    else if (c->power_law)
        power_row(c);
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
            const double *fj = f + (ptrdiff_t)j * n, *im = inv_m + (ptrdiff_t)j * n;
            double *aj = acc + (ptrdiff_t)j * n, *vj = vw + (ptrdiff_t)j * n;
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
                    Vw[(ptrdiff_t)q * k + c_T] += 0.5 * acc[q];
        }
    }
}

/* The exported step: each checks the chain (chain_error) and the record's rows
   (record_error) first, then runs drift, forces or record. Those three stay out of line
   (SSW_NOINLINE), one copy for both callers: inlined into each, GCC 12 compiled the
   force loops into 0.7 % more instructions per step. */
SSW_API int ssw_drift(const ssw_chain *c)
{
    const int e = chain_error(c);
    if (e)
        return e;
    drift(c);
    return SSW_OK;
}

SSW_API int ssw_forces(const ssw_chain *c, int has_old, int kick)
{
    const int e = chain_error(c);
    if (e)
        return e;
    forces(c, has_old, kick);
    return SSW_OK;
}

SSW_API int ssw_record(const ssw_chain *c, int row)
{
    int e = chain_error(c);
    if (!e)
        e = record_error(c, row, 1);
    if (e)
        return e;
    record(c, row);
    return SSW_OK;
}

/* Steps of a run whose wall row the step writes itself (K1 > 0, or power_law) or that is
   held fixed: rows times drift, forces (has_old, kick) and record into rows row0 .. row0 +
   rows - 1 of the block buffers: one call for a block of steps. */
SSW_API int ssw_advance(const ssw_chain *c, int rows, int row0)
{
    int e = chain_error(c);
    if (!e)
        e = record_error(c, row0, rows);
    if (e)
        return e;
    for (int r = 0; r < rows; r++) {
        drift(c);
        forces(c, 1, 1);
        record(c, row0 + r);
    }
    return SSW_OK;
}

/* numpy's max and argmax of x[0] - base, x[stride] - base, ... (rows values): a NaN is
   the maximum, the first one its index. */
SSW_INLINE double max_at(const double *x, ptrdiff_t stride, int rows, double base, int *at)
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
   numpy expressions of the rule. rows >= 1: the block's last time is read. */
SSW_API int ssw_stop_update(int rows, int n, int64_t stride, const double *S, const double *W,
                            const double *times, const double *k, double *F, unsigned char *B,
                            unsigned char *done)
{
    if (rows < 1)
        return E_ROWS;
    if (n < 0)
        return E_SCENES;
    if (stride < n)
        return E_STRIDE;
    if (!S || !W || !times || !k || !F || !B || !done)
        return E_ARRAY;
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
    return SSW_OK;
}
