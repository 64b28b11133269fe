/* The simulator's integration step with stick–slip events, in C around the generated kernels of
 * armctl/sim/generated_plant.py: this file (definitions, small linear algebra, the stick state, q̈), then
 * step_schemes.c (the integrators), step_events.c (stick solve, events, the functions CasADi loads) and
 * step_period.c (a control period in one call), appended in that order to the generated code after these
 * definitions (written by armctl/sim/compiled_plant.py):
 *
 *   ARMCTL_N         joints                         ARMCTL_NPAR      entries of par
 *   ARMCTL_STICKY    1: some joint can stick        ARMCTL_FRICTION  1: the plant has joint friction
 *   ARMCTL_EXTERNAL  1: contact or disturbance      ARMCTL_EXPLICIT  1: rk4 / euler, 0: the implicit schemes
 *
 * It is a line-by-line transcription of the Python step, whose docstrings give the mathematics:
 * Plant.begin and stick_slip.solve_sticking (which joints stick), stepper.advance (events: a sliding joint
 * whose velocity reaches zero within a step), integrators.rk4_work and the Euler step with work, and
 * implicit.implicit_euler / symplectic_euler (Newton's method on the velocity). Each function below names its
 * Python original, and each Python original names its copy here: a change to one is a change to the other
 * (tests/sim/test_compiled_plant.py fails when the two steps disagree; bump CODE_VERSION in compiled_plant.py).
 * Matrices from the kernels are dense, column-major.
 *
 * Exposed (CasADi external functions, dense column vectors):
 *   advance(q, v, tau, W, par, opt, S) -> (q1, v1, a0, out5, S)  one integration step of length h = opt[1]
 *   begin(q, v, tau, W, par, S) -> (S, out)                       the stick solve at the start of a period
 *   accel(q, v, tau, W, par, S) -> (a, out)                       q̈ for the current stick state
 *   period(...)                                                    a whole control period (see step_period.c)
 * W: the disturbance h_d at the start, middle and end of the step (18), S: the stick state (see S_* below),
 * opt = [unused, h, scheme], out = [W_friction, W_external, a0 valid, status(, no joint that can stick at rest at
 * the end: S's friction torque is the next period's)].
 */
#include <math.h>
#include <string.h>

#define N ARMCTL_N
#define NS (4 * N + 8)
#define S_DIR 0
#define S_STUCK N
#define S_HOLD (2 * N)
#define S_TAUF (3 * N)
#define S_BEGUN (4 * N)
#define S_ANY (4 * N + 1)
#define S_ALL (4 * N + 2)
#define S_STICK_EVENTS (4 * N + 3)
#define S_BREAKAWAY_EVENTS (4 * N + 4)
#define S_EVENT_OVERFLOW (4 * N + 5)
#define S_UNCONVERGED (4 * N + 6)
/* statuses */
#define OK 0
#define NOT_POSITIVE_DEFINITE 1
#define SINGULAR_NEWTON 2
/* schemes */
#define RK4 0
#define EULER 1
#define SEMI_IMPLICIT 2
#define IMPLICIT 3
/* friction parameters in par, after the 13 inertial parameters per joint (generated_plant.PlantLayout) */
#define P_FR (13 * N)
#define P_CP (P_FR + 1 * N)
#define P_CN (P_FR + 2 * N)
#define P_HP (P_FR + 3 * N)
#define P_HN (P_FR + 4 * N)
#define P_BP (P_FR + 6 * N)
#define P_BN (P_FR + 7 * N)
#define P_CAP (P_FR + 8 * N)
#define NEWTON_TOL 1e-11
#define NEWTON_MAX_ITER 25

typedef int (*armctl_kernel)(const casadi_real**, casadi_real**, casadi_int*, casadi_real*, int);
typedef int (*armctl_kernel_work)(casadi_int*, casadi_int*, casadi_int*, casadi_int*);

/* Call a generated kernel with its work arrays on the stack. */
static int armctl_call(armctl_kernel k, armctl_kernel_work wk, int n_in, const double** in, int n_out, double** out) {
  casadi_int sz_arg, sz_res, sz_iw, sz_w;
  wk(&sz_arg, &sz_res, &sz_iw, &sz_w);
  {
    const casadi_real* arg[sz_arg + 1];
    casadi_real* res[sz_res + 1];
    casadi_int iw[sz_iw + 1];
    casadi_real w[sz_w + 1];
    int i;
    for (i = 0; i < n_in; ++i) arg[i] = in[i];
    for (i = 0; i < n_out; ++i) res[i] = out[i];
    return k(arg, res, iw, w, 0);
  }
}
#define CALL(name, n_in, in, n_out, out) armctl_call(name, name##_work, n_in, in, n_out, out)

/* h_d at θ (0: start, 1/2: middle, 1: end of the step): the parabola through the three samples of W
 * (Plant.disturbance_at). */
static void armctl_interp(const double* W, double theta, double* hd) {
  double l0 = (1.0 - theta) * (1.0 - 2.0 * theta), l1 = 4.0 * theta * (1.0 - theta), l2 = theta * (2.0 * theta - 1.0);
  int i;
  for (i = 0; i < 6; ++i) hd[i] = l0 * W[i] + l1 * W[6 + i] + l2 * W[12 + i];
}

static double armctl_dot(const double* a, const double* b) {
  double s = 0.0;
  int i;
  for (i = 0; i < N; ++i) s += a[i] * b[i];
  return s;
}

static double armctl_max_abs(const double* a) {
  double m = 0.0;
  int i;
  for (i = 0; i < N; ++i) if (fabs(a[i]) > m || a[i] != a[i]) m = a[i] != a[i] ? a[i] : fabs(a[i]);
  return m;
}

/* y = A x for a dense column-major N×N A */
static void armctl_matvec(const double* A, const double* x, double* y) {
  int i, j;
  for (i = 0; i < N; ++i) y[i] = 0.0;
  for (j = 0; j < N; ++j) for (i = 0; i < N; ++i) y[i] += A[i + N * j] * x[j];
}

/* stick_slip.constrained_accel: x_F = A_FF⁻¹ b_F by Cholesky of the free block, x_S = 0 (stuck may be 0:
 * none stuck). NOT_POSITIVE_DEFINITE if a pivot is not > 0 (NaN included, as LAPACK's). */
static int armctl_masked_solve(const double* A, const double* b, const int* stuck, double* x) {
  int idx[N], m = 0, i, k, p;
  double L[N * N], y[N];
  for (i = 0; i < N; ++i) {
    x[i] = 0.0;
    if (!stuck || !stuck[i]) idx[m++] = i;
  }
  for (i = 0; i < m; ++i) {
    for (k = 0; k <= i; ++k) {
      double s = A[idx[i] + N * idx[k]];
      for (p = 0; p < k; ++p) s -= L[i * N + p] * L[k * N + p];
      if (i == k) {
        if (!(s > 0.0)) return NOT_POSITIVE_DEFINITE;
        L[i * N + i] = sqrt(s);
      } else {
        L[i * N + k] = s / L[k * N + k];
      }
    }
  }
  for (i = 0; i < m; ++i) {
    double s = b[idx[i]];
    for (p = 0; p < i; ++p) s -= L[i * N + p] * y[p];
    y[i] = s / L[i * N + i];
  }
  for (i = m - 1; i >= 0; --i) {
    double s = y[i];
    for (p = i + 1; p < m; ++p) s -= L[p * N + i] * x[idx[p]];
    x[idx[i]] = s / L[i * N + i];
  }
  return OK;
}

/* x = A⁻¹ b by LU with partial pivoting (LAPACK's dgesv); A is overwritten. SINGULAR_NEWTON on a zero pivot. */
static int armctl_lu_solve(double* A, const double* b, double* x) {
  int piv[N], i, j, k;
  for (i = 0; i < N; ++i) x[i] = b[i];
  for (k = 0; k < N; ++k) {
    int p = k;
    double big = fabs(A[k + N * k]);
    for (i = k + 1; i < N; ++i) if (fabs(A[i + N * k]) > big) { big = fabs(A[i + N * k]); p = i; }
    piv[k] = p;
    if (A[p + N * k] == 0.0) return SINGULAR_NEWTON;
    if (p != k) {
      for (j = 0; j < N; ++j) { double t = A[k + N * j]; A[k + N * j] = A[p + N * j]; A[p + N * j] = t; }
      { double t = x[k]; x[k] = x[p]; x[p] = t; }
    }
    for (i = k + 1; i < N; ++i) {
      double l = A[i + N * k] / A[k + N * k];
      A[i + N * k] = l;
      for (j = k + 1; j < N; ++j) A[i + N * j] -= l * A[k + N * j];
      x[i] -= l * x[k];
    }
  }
  for (i = N - 1; i >= 0; --i) {
    double s = x[i];
    for (j = i + 1; j < N; ++j) s -= A[i + N * j] * x[j];
    x[i] = s / A[i + N * i];
  }
  (void)piv;
  return OK;
}

/* The stick state of a step, unpacked from S; and what the stick solve of armctl_begin found at the state it solved
 * (not kept in S: valid for that state only): q̈ with the joints it left stuck held (x_S = 0), and the friction and
 * external torques there — RK4's first stage at that state, without a second evaluation. */
typedef struct {
  double dir[N], hold[N];
  int stuck[N], any, all;
  int solved; /* start_a, start_f, start_e hold the state's terms */
  double start_a[N], start_f[N], start_e[N];
} armctl_mode;

static void armctl_mode_read(const double* S, armctl_mode* m) {
  int i;
  for (i = 0; i < N; ++i) {
    m->dir[i] = S[S_DIR + i];
    m->stuck[i] = S[S_STUCK + i] != 0.0;
    m->hold[i] = S[S_HOLD + i];
  }
  m->any = S[S_ANY] != 0.0;
  m->all = S[S_ALL] != 0.0;
  m->solved = 0;
}

static void armctl_mode_write(const armctl_mode* m, double* S) {
  int i;
  for (i = 0; i < N; ++i) {
    S[S_DIR + i] = m->dir[i];
    S[S_STUCK + i] = m->stuck[i];
    S[S_HOLD + i] = m->hold[i];
  }
  S[S_ANY] = m->any;
  S[S_ALL] = m->all;
}

static void armctl_free_all(armctl_mode* m) {
  int i;
  for (i = 0; i < N; ++i) { m->stuck[i] = 0; m->hold[i] = 0.0; }
  m->any = m->all = 0;
}

/* pk_rhs: q̈ (and τ_f, τ_e) for the stick state m (Plant.accel_forces) */
static int armctl_rhs(const double* q, const double* v, const double* tau, const double* hd, const double* par,
                      const armctl_mode* m, double* a, double* f, double* e) {
  double stuck[N], piv;
  int i;
  for (i = 0; i < N; ++i) stuck[i] = m->stuck[i];
  {
    const double* in[7] = {q, v, tau, m->dir, stuck, hd, par};
    double* out[4] = {a, f, e, &piv};
    CALL(pk_rhs, 7, in, 4, out);
  }
  /* as Python: a held joint's solve is LAPACK's, which refuses a block that is not positive definite; the free
   * solve (Pinocchio's ABA there) lets NaN through to the state check */
  if (m->any && !m->all && !(piv > 0.0)) return NOT_POSITIVE_DEFINITE;
  return OK;
}

static double armctl_kinetic(const double* q, const double* v, const double* par) {
  double M[N * N], Mv[N];
  const double* in[2] = {q, par};
  double* out[1] = {M};
  CALL(pk_mass, 2, in, 1, out);
  armctl_matvec(M, v, Mv);
  return 0.5 * armctl_dot(v, Mv);
}
