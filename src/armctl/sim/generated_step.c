/* The simulator's integration step with stick–slip events, in C around the generated kernels of
 * armctl/sim/generated_plant.py. Appended to the generated code, after these definitions (written by
 * armctl/sim/compiled_plant.py):
 *
 *   ARMCTL_N         joints                         ARMCTL_NPAR      entries of par
 *   ARMCTL_STICKY    1: some joint can stick        ARMCTL_FRICTION  1: the plant has joint friction
 *   ARMCTL_EXTERNAL  1: contact or disturbance      ARMCTL_EXPLICIT  1: rk4 / euler, 0: the implicit schemes
 *
 * It is a line-by-line transcription of the Python step, whose docstrings give the mathematics:
 * Plant.begin and stick_slip.solve_sticking (which joints stick), stepper.advance (events: a sliding joint
 * whose velocity reaches zero within a step), integrators.rk4_work and the Euler step with work, and
 * implicit.implicit_euler / symplectic_euler (Newton's method on the velocity). Each function below names its
 * Python original. Matrices from the kernels are dense, column-major.
 *
 * Exposed (CasADi external functions, dense column vectors):
 *   advance(q, v, tau, W, par, opt, S) -> (q1, v1, a0, out5, S)  one integration step of length h = opt[1]
 *   begin(q, v, tau, W, par, S) -> (S, out)                       the stick solve at the start of a period
 *   accel(q, v, tau, W, par, S) -> (a, out)                       q̈ for the current stick state
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

/* The stick state of a step, unpacked from S. */
typedef struct {
  double dir[N], hold[N];
  int stuck[N], any, all;
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

/* stick_slip.solve_sticking, on M and r (r is changed); m->stuck holds the candidates on entry. */
static int armctl_solve_sticking(const double* M, double* r, armctl_mode* m, const int* held, const double* par) {
  double lam[N], a[N], Ma[N];
  int i;
  for (;;) {
    int all = 1, k = -1;
    double worst = 1.0;
    for (i = 0; i < N; ++i) if (!m->stuck[i]) all = 0;
    if (all) {
      for (i = 0; i < N; ++i) lam[i] = r[i];
    } else {
      int any = 0;
      for (i = 0; i < N; ++i) if (m->stuck[i]) any = 1;
      if (armctl_masked_solve(M, r, any ? m->stuck : 0, a) != OK) return NOT_POSITIVE_DEFINITE;
      armctl_matvec(M, a, Ma);
      for (i = 0; i < N; ++i) lam[i] = r[i] - Ma[i];
    }
    for (i = 0; i < N; ++i) {
      double x, bp, bn, ratio;
      if (!m->stuck[i] || (held && held[i])) continue;
      x = lam[i];
      bp = par[P_BP + i];
      bn = par[P_BN + i];
      ratio = x > 0 ? (bp > 0 ? x / bp : INFINITY) : x < 0 ? (bn > 0 ? -x / bn : INFINITY) : 0.0;
      if (ratio > worst) { worst = ratio; k = i; }
    }
    if (k < 0) {
      for (i = 0; i < N; ++i) m->hold[i] = m->stuck[i] ? lam[i] : 0.0;
      return OK;
    }
    /* joint k breaks away in the direction of the torque that overcame it, against its friction at 0⁺ */
    m->stuck[k] = 0;
    if (lam[k] > 0) {
      m->dir[k] = 1.0;
      r[k] -= par[P_CP + k] + par[P_HP + k];
    } else {
      m->dir[k] = -1.0;
      r[k] -= -par[P_CN + k] - par[P_HN + k];
    }
  }
}

/* Plant.begin: which joints stick for the step starting at (q, v) under tau (held: kept stuck, or 0). */
static int armctl_begin(const double* q, const double* v, const double* tau, const double* hd, const double* par,
                        armctl_mode* m, const int* held, double* S) {
#if ARMCTL_STICKY
  int i, any_zero = 0, any_cand = 0, cand[N];
  double M[N * N], r[N];
  for (i = 0; i < N; ++i) {
    m->dir[i] = par[P_CAP + i] != 0.0 ? (v[i] > 0 ? 1.0 : v[i] < 0 ? -1.0 : 0.0) : 0.0;
    if (v[i] == 0.0) any_zero = 1;
  }
  if (!any_zero) { armctl_free_all(m); return OK; }
  for (i = 0; i < N; ++i) {
    cand[i] = par[P_CAP + i] != 0.0 && v[i] == 0.0;
    if (cand[i]) any_cand = 1;
  }
  if (!any_cand) { armctl_free_all(m); return OK; }
  {
    const double* in[6] = {q, v, tau, m->dir, hd, par};
    double* out[2] = {M, r};
    CALL(pk_terms, 6, in, 2, out);
  }
  for (i = 0; i < N; ++i) m->stuck[i] = cand[i];
  if (armctl_solve_sticking(M, r, m, held, par) != OK) return NOT_POSITIVE_DEFINITE;
  m->any = m->all = 0;
  for (i = 0; i < N; ++i) {
    if (cand[i] && !m->stuck[i]) S[S_BREAKAWAY_EVENTS] += 1.0;
    if (m->stuck[i]) m->any = 1;
  }
  m->all = 1;
  for (i = 0; i < N; ++i) if (!m->stuck[i]) m->all = 0;
  if (!m->any) for (i = 0; i < N; ++i) m->hold[i] = 0.0;
#else
  (void)q; (void)v; (void)tau; (void)hd; (void)par; (void)m; (void)held; (void)S;
#endif
  return OK;
}

/* ----------------------------------------------------------------------------------------- the schemes */
/* One step of length hs starting off into the step [t, t + h] (θ = off/h), for the fixed stick state m.
 * Returns a status; a0 is the accelerations at the start (a0_valid: 0 for the implicit schemes). */
static int armctl_scheme_step(int scheme, double off, double hs, double h, const double* q, const double* v,
                              const double* tau, const double* W, const double* par, const armctl_mode* m, double* S,
                              double* q1, double* v1, double* a0, int* a0_valid, double* wf, double* we) {
  double hd[6];
  int i;
  *wf = *we = 0.0;
  *a0_valid = 0;
#if ARMCTL_EXPLICIT
  if (scheme == RK4) { /* integrators.rk4_work */
    double a[4][N], f[N], e[N], x[N], y[N], pf[4], pe[4], h2 = 0.5 * hs, hh = hs * hs;
    int st;
    armctl_interp(W, off / h, hd);
    if ((st = armctl_rhs(q, v, tau, hd, par, m, a[0], f, e)) != OK) return st;
    pf[0] = -armctl_dot(v, f); pe[0] = armctl_dot(v, e);
    armctl_interp(W, (off + h2) / h, hd);
    for (i = 0; i < N; ++i) { x[i] = q[i] + h2 * v[i]; y[i] = v[i] + h2 * a[0][i]; }
    if ((st = armctl_rhs(x, y, tau, hd, par, m, a[1], f, e)) != OK) return st;
    pf[1] = -armctl_dot(y, f); pe[1] = armctl_dot(y, e);
    for (i = 0; i < N; ++i) { x[i] = q[i] + h2 * v[i] + (hh / 4) * a[0][i]; y[i] = v[i] + h2 * a[1][i]; }
    if ((st = armctl_rhs(x, y, tau, hd, par, m, a[2], f, e)) != OK) return st;
    pf[2] = -armctl_dot(y, f); pe[2] = armctl_dot(y, e);
    armctl_interp(W, (off + hs) / h, hd);
    for (i = 0; i < N; ++i) { x[i] = q[i] + hs * v[i] + (hh / 2) * a[1][i]; y[i] = v[i] + hs * a[2][i]; }
    if ((st = armctl_rhs(x, y, tau, hd, par, m, a[3], f, e)) != OK) return st;
    pf[3] = -armctl_dot(y, f); pe[3] = armctl_dot(y, e);
    for (i = 0; i < N; ++i) {
      q1[i] = q[i] + hs * v[i] + (hh / 6) * a[0][i] + (hh / 6) * a[1][i] + (hh / 6) * a[2][i];
      v1[i] = v[i] + (hs / 6) * a[0][i] + (hs / 3) * a[1][i] + (hs / 3) * a[2][i] + (hs / 6) * a[3][i];
      a0[i] = a[0][i];
    }
    *wf = hs / 6.0 * (pf[0] + 2.0 * (pf[1] + pf[2]) + pf[3]);
    *we = hs / 6.0 * (pe[0] + 2.0 * (pe[1] + pe[2]) + pe[3]);
    *a0_valid = 1;
    return OK;
  } else { /* integrators.make_step's euler_work: the forces' work at the mean velocity */
    double f[N], e[N], mean[N];
    int st;
    armctl_interp(W, off / h, hd);
    if ((st = armctl_rhs(q, v, tau, hd, par, m, a0, f, e)) != OK) return st;
    for (i = 0; i < N; ++i) {
      v1[i] = v[i] + hs * a0[i];
      mean[i] = 0.5 * (v[i] + v1[i]);
      q1[i] = q[i] + hs * v1[i];
    }
    *wf = -hs * armctl_dot(mean, f);
    *we = hs * armctl_dot(mean, e);
    *a0_valid = 1;
    return OK;
  }
#else
  double M[N * N], bias[N], grav[N], base[N];
  const int* stuck = m->any ? m->stuck : 0;
  {
    const double* in[2] = {q, par};
    double* out[1] = {M};
    CALL(pk_mass, 2, in, 1, out);
  }
  {
    const double* in[3] = {q, v, par};
    double* out[2] = {bias, grav};
    CALL(pk_bias, 3, in, 2, out);
  }
  (void)a0;
  if (scheme == IMPLICIT) { /* implicit.implicit_euler */
    double x[N], fimp[N], jx[N * N], f[N], e[N], jac[N * N], res[N], dx[N], Mdv[N], dvel[N];
    int it, converged = 0;
    armctl_interp(W, (off + hs) / h, hd);
    for (i = 0; i < N; ++i) base[i] = tau[i] - bias[i];
#if !ARMCTL_FRICTION && !ARMCTL_EXTERNAL
    if (armctl_masked_solve(M, base, 0, dx) != OK) return NOT_POSITIVE_DEFINITE;
    for (i = 0; i < N; ++i) { v1[i] = v[i] + hs * dx[i]; q1[i] = q[i] + hs * v1[i]; }
    return OK;
#endif
    for (i = 0; i < N; ++i) x[i] = v[i];
    for (it = 0; it < NEWTON_MAX_ITER; ++it) {
      const double* in[6] = {q, x, &hs, m->dir, hd, par};
      double* out[4] = {fimp, jx, f, e};
      CALL(pk_implicit, 6, in, 4, out);
      for (i = 0; i < N * N; ++i) jac[i] = M[i] + jx[i];
      for (i = 0; i < N; ++i) dvel[i] = x[i] - v[i];
      armctl_matvec(M, dvel, Mdv);
      for (i = 0; i < N; ++i) res[i] = Mdv[i] - hs * ((base[i] - f[i]) + e[i]);
      {
        int j, st;
        if (stuck) for (i = 0; i < N; ++i) if (stuck[i]) {
          for (j = 0; j < N; ++j) { jac[i + N * j] = 0.0; jac[j + N * i] = 0.0; }
          jac[i + N * i] = 1.0;
          res[i] = 0.0;
        }
        for (i = 0; i < N; ++i) res[i] = -res[i];
        if ((st = armctl_lu_solve(jac, res, dx)) != OK) return st;
      }
      for (i = 0; i < N; ++i) x[i] += dx[i];
      if (armctl_max_abs(dx) <= NEWTON_TOL * (1.0 + armctl_max_abs(x))) { converged = 1; break; }
    }
    if (!converged) S[S_UNCONVERGED] += 1.0;
    if (stuck) for (i = 0; i < N; ++i) if (stuck[i]) x[i] = 0.0;
    for (i = 0; i < N; ++i) { v1[i] = x[i]; q1[i] = q[i] + hs * x[i]; }
    {
      const double* in[6] = {q, v1, &hs, m->dir, hd, par};
      double* out[4] = {fimp, jx, f, e};
      CALL(pk_implicit, 6, in, 4, out);
#if ARMCTL_FRICTION
      *wf = -hs * armctl_dot(v1, f);
#endif
#if ARMCTL_EXTERNAL
      *we = hs * armctl_dot(v1, e);
#endif
    }
    return OK;
  } else { /* implicit.symplectic_euler */
    double p0[N], vb[N], fs[N], jx[N * N], f[N], e[N], K[N * N], jac[N * N], res[N], dx[N], Mvb[N], Kvb[N];
    int it, converged = 0;
    armctl_interp(W, off / h, hd);
    for (i = 0; i < N; ++i) base[i] = tau[i] - grav[i];
    armctl_matvec(M, v, p0);
    for (i = 0; i < N; ++i) { vb[i] = v[i]; f[i] = e[i] = 0.0; }
    for (i = 0; i < N * N; ++i) K[i] = 0.0;
#if !ARMCTL_FRICTION && !ARMCTL_EXTERNAL
    /* implicit._symplectic_conservative: fixed-point iteration on M's Cholesky factor */
    for (it = 0; it < NEWTON_MAX_ITER; ++it) {
      double rhs[N], nv[N], dv = 0.0;
      const double* in[6] = {q, vb, &hs, m->dir, hd, par};
      double* out[5] = {fs, jx, f, e, K};
      CALL(pk_symplectic, 6, in, 5, out);
      for (i = 0; i < N; ++i) rhs[i] = p0[i] + hs * (base[i] + fs[i]);
      if (armctl_masked_solve(M, rhs, 0, nv) != OK) return NOT_POSITIVE_DEFINITE;
      for (i = 0; i < N; ++i) { double d = fabs(nv[i] - vb[i]); if (d > dv || d != d) dv = d; vb[i] = nv[i]; }
      if (dv <= NEWTON_TOL * (1.0 + armctl_max_abs(vb))) { converged = 1; break; }
    }
#else
    for (it = 0; it < NEWTON_MAX_ITER; ++it) {
      const double* in[6] = {q, vb, &hs, m->dir, hd, par};
      double* out[5] = {fs, jx, f, e, K};
      CALL(pk_symplectic, 6, in, 5, out);
      for (i = 0; i < N * N; ++i) jac[i] = M[i] + jx[i];
      armctl_matvec(M, vb, Mvb);
      for (i = 0; i < N; ++i) res[i] = Mvb[i] - p0[i] - hs * (base[i] + fs[i]);
      {
        int j, st;
        if (stuck) for (i = 0; i < N; ++i) if (stuck[i]) {
          for (j = 0; j < N; ++j) { jac[i + N * j] = 0.0; jac[j + N * i] = 0.0; }
          jac[i + N * i] = 1.0;
          res[i] = 0.0;
        }
        for (i = 0; i < N; ++i) res[i] = -res[i];
        if ((st = armctl_lu_solve(jac, res, dx)) != OK) return st;
      }
      for (i = 0; i < N; ++i) vb[i] += dx[i];
      if (armctl_max_abs(dx) <= NEWTON_TOL * (1.0 + armctl_max_abs(vb))) { converged = 1; break; }
    }
#endif
    if (!converged) S[S_UNCONVERGED] += 1.0;
    if (stuck) for (i = 0; i < N; ++i) if (stuck[i]) vb[i] = 0.0;
    for (i = 0; i < N; ++i) q1[i] = q[i] + hs * vb[i];
    armctl_matvec(M, vb, Mvb);
    {
      const double* in[2] = {q1, par};
      double* out[1] = {M};
      CALL(pk_mass, 2, in, 1, out);
    }
    if (armctl_masked_solve(M, Mvb, stuck, v1) != OK) return NOT_POSITIVE_DEFINITE;
#if ARMCTL_FRICTION
    *wf = -hs * armctl_dot(vb, f);
#endif
#if ARMCTL_EXTERNAL
    armctl_matvec(K, vb, Kvb);
    *we = hs * armctl_dot(vb, e) + 0.5 * hs * hs * armctl_dot(vb, Kvb);
#else
    (void)Kvb;
#endif
    (void)jac; (void)res; (void)dx;
    return OK;
  }
#endif
}

/* stepper.advance: the step from (q, v) over h under tau, with stick–slip events. */
static int armctl_advance(int scheme, double h, int begun, const double* q_in, const double* v_in, const double* tau,
                          const double* W, const double* par, double* S, double* q_out, double* v_out, double* a_first,
                          int* a_first_valid, double* wf_out, double* we_out) {
  armctl_mode m;
  double q[N], v[N], qn[N], vn[N], an[N], off = 0.0, remaining = h, wf = 0.0, we = 0.0, dwf, dwe, hd[6];
  int held[N], have_held = 0, at_start = 1, attempt, budget = 4 * N + 8, an_valid, st, i;
  memcpy(q, q_in, sizeof q);
  memcpy(v, v_in, sizeof v);
  armctl_mode_read(S, &m);
  *a_first_valid = 0;
  for (i = 0; i < N; ++i) held[i] = 0;
#if !ARMCTL_STICKY
  st = armctl_scheme_step(scheme, 0.0, h, h, q, v, tau, W, par, &m, S, q_out, v_out, a_first, a_first_valid, wf_out,
                          we_out);
  (void)begun; (void)qn; (void)vn; (void)an; (void)off; (void)remaining; (void)wf; (void)we; (void)dwf; (void)dwe;
  (void)hd; (void)held; (void)have_held; (void)at_start; (void)attempt; (void)budget; (void)an_valid;
  return st;
#else
  for (attempt = 0; attempt <= budget; ++attempt) {
    int cross[N], any_cross = 0, any_resting = 0, kmin = -1;
    double s = INFINITY, frac;
    if (!begun) {
      armctl_interp(W, off / h, hd);
      if ((st = armctl_begin(q, v, tau, hd, par, &m, have_held ? held : 0, S)) != OK) return st;
    }
    begun = 0;
    if (m.all) { /* nothing moves: q̈ = 0, no power */
      if (at_start) { for (i = 0; i < N; ++i) a_first[i] = 0.0; *a_first_valid = 1; }
      break;
    }
    if ((st = armctl_scheme_step(scheme, off, remaining, h, q, v, tau, W, par, &m, S, qn, vn, an, &an_valid, &dwf,
                                 &dwe)) != OK)
      return st;
    for (i = 0; i < N; ++i) {
      cross[i] = m.dir[i] != 0.0 && m.dir[i] * vn[i] <= 0.0;
      if (cross[i]) any_cross = 1;
    }
    if (!any_cross || attempt == budget) {
      if (at_start) { memcpy(a_first, an, sizeof an); *a_first_valid = an_valid; }
      if (any_cross) { /* too many events in one step: stop the crossing joints where they are */
        double before = armctl_kinetic(qn, vn, par);
        S[S_EVENT_OVERFLOW] += 1.0;
        for (i = 0; i < N; ++i) if (cross[i]) vn[i] = 0.0;
        dwf += armctl_kinetic(qn, vn, par) - before;
      }
      memcpy(q, qn, sizeof q);
      memcpy(v, vn, sizeof v);
      wf += dwf;
      we += dwe;
      break;
    }
    for (i = 0; i < N; ++i) if (cross[i] && v[i] == 0.0) { held[i] = 1; any_resting = 1; }
    if (any_resting) { /* released but did not move its way: hold it and redo the step */
      have_held = 1;
      continue;
    }
    for (i = 0; i < N; ++i) {
      double d0, d1;
      if (!cross[i]) continue;
      d0 = m.dir[i] * v[i];
      d1 = m.dir[i] * vn[i];
      frac = d0 / (d0 - d1);
      if (frac < s) { s = frac; kmin = i; }
    }
    if (s < 1.0 - 1e-12) {
      if ((st = armctl_scheme_step(scheme, off, s * remaining, h, q, v, tau, W, par, &m, S, qn, vn, an, &an_valid,
                                   &dwf, &dwe)) != OK)
        return st;
    }
    if (at_start) { memcpy(a_first, an, sizeof an); *a_first_valid = an_valid; }
    at_start = 0;
    wf += dwf;
    we += dwe;
    { /* zero the joint that reached zero velocity first (and any that crossed in the shortened step) */
      int zero[N];
      double before;
      for (i = 0; i < N; ++i) zero[i] = m.dir[i] != 0.0 && m.dir[i] * vn[i] <= 0.0;
      zero[kmin] = 1;
      before = armctl_kinetic(qn, vn, par);
      for (i = 0; i < N; ++i) if (zero[i]) { vn[i] = 0.0; S[S_STICK_EVENTS] += 1.0; }
      wf += armctl_kinetic(qn, vn, par) - before;
    }
    off += s * remaining;
    remaining -= s * remaining;
    memcpy(q, qn, sizeof q);
    memcpy(v, vn, sizeof v);
    have_held = 0;
    for (i = 0; i < N; ++i) held[i] = 0;
    if (remaining <= 1e-14 * h) break;
  }
  memcpy(q_out, q, sizeof q);
  memcpy(v_out, v, sizeof v);
  armctl_mode_write(&m, S);
  *wf_out = wf;
  *we_out = we;
  return OK;
#endif
}

/* ------------------------------------------------------------------------------ CasADi external functions */
CASADI_SYMBOL_EXPORT int advance(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem) {
  double S[NS], q[N], v[N], tau[N], a0[N], q1[N], v1[N], wf = 0.0, we = 0.0;
  int valid = 0, st, begun;
  (void)iw; (void)w; (void)mem;
  memcpy(S, arg[6], sizeof S);
  memcpy(q, arg[0], sizeof q);
  memcpy(v, arg[1], sizeof v);
  memcpy(tau, arg[2], sizeof tau);
  begun = S[S_BEGUN] != 0.0;
  S[S_BEGUN] = 0.0;
  st = armctl_advance((int)arg[5][2], arg[5][1], begun, q, v, tau, arg[3], arg[4], S, q1, v1, a0, &valid, &wf, &we);
  if (st != OK) {
    memcpy(q1, q, sizeof q);
    memcpy(v1, v, sizeof v);
  }
  { /* the next period's stick state needs no solve if no joint that can stick is at rest: then its friction torque
     * (Plant.friction_torque) is the model's at the sliding directions sgn(q̇₁), computed here (see out[4]) */
    int i, free = st == OK;
#if ARMCTL_STICKY
    for (i = 0; i < N; ++i) if (arg[4][P_CAP + i] != 0.0 && v1[i] == 0.0) free = 0;
#endif
    if (free) { /* what Plant.begin makes of that state: directions sgn(q̇₁), nothing stuck, nothing held */
#if ARMCTL_STICKY
      for (i = 0; i < N; ++i) {
        S[S_DIR + i] = arg[4][P_CAP + i] != 0.0 ? (v1[i] > 0 ? 1.0 : v1[i] < 0 ? -1.0 : 0.0) : 0.0;
        S[S_STUCK + i] = S[S_HOLD + i] = 0.0;
      }
      S[S_ANY] = S[S_ALL] = 0.0;
#endif
#if ARMCTL_FRICTION
      {
        double f[N];
        const double* in[3] = {v1, S + S_DIR, arg[4]};
        double* out[1] = {f};
        CALL(pk_friction, 3, in, 1, out);
        for (i = 0; i < N; ++i) S[S_TAUF + i] = f[i];
      }
#endif
    }
    res[3][4] = free;
  }
  memcpy(res[0], q1, sizeof q1);
  memcpy(res[1], v1, sizeof v1);
  if (valid) memcpy(res[2], a0, sizeof a0);
  res[3][0] = wf;
  res[3][1] = we;
  res[3][2] = valid;
  res[3][3] = st;
  memcpy(res[4], S, sizeof S);
  return 0;
}

CASADI_SYMBOL_EXPORT int begin(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem) {
  double S[NS], q[N], v[N], tau[N], hd[6];
  armctl_mode m;
  int st, i;
  (void)iw; (void)w; (void)mem;
  memcpy(S, arg[5], sizeof S);
  memcpy(q, arg[0], sizeof q);
  memcpy(v, arg[1], sizeof v);
  memcpy(tau, arg[2], sizeof tau);
  armctl_mode_read(S, &m);
  armctl_interp(arg[3], 0.0, hd);
  st = armctl_begin(q, v, tau, hd, arg[4], &m, 0, S);
  armctl_mode_write(&m, S);
#if ARMCTL_FRICTION
  { /* Plant.friction_torque: the friction model's torque for the sliding joints, the holding torque for the stuck */
    double f[N];
    const double* in[3] = {v, m.dir, arg[4]};
    double* out[1] = {f};
    CALL(pk_friction, 3, in, 1, out);
    for (i = 0; i < N; ++i) S[S_TAUF + i] = f[i] + m.hold[i];
  }
#else
  for (i = 0; i < N; ++i) S[S_TAUF + i] = 0.0;
#endif
  S[S_BEGUN] = 1.0;
  memcpy(res[0], S, sizeof S);
  res[1][0] = m.any;
  res[1][1] = m.all;
  res[1][2] = 0.0;
  res[1][3] = st;
  return 0;
}

CASADI_SYMBOL_EXPORT int accel(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem) {
  double q[N], v[N], tau[N], a[N], f[N], e[N], hd[6];
  armctl_mode m;
  int st;
  (void)iw; (void)w; (void)mem;
  memcpy(q, arg[0], sizeof q);
  memcpy(v, arg[1], sizeof v);
  memcpy(tau, arg[2], sizeof tau);
  armctl_mode_read(arg[5], &m);
  armctl_interp(arg[3], 0.0, hd);
  st = m.all ? OK : armctl_rhs(q, v, tau, hd, arg[4], &m, a, f, e);
  if (m.all) memset(a, 0, sizeof a);
  memcpy(res[0], a, sizeof a);
  res[1][0] = res[1][1] = res[1][2] = 0.0;
  res[1][3] = st;
  return 0;
}

#define ARMCTL_SHAPE(name)                                                                                             \
  CASADI_SYMBOL_EXPORT casadi_int name##_n_in(void) { return name##_shape_n_in(); }                                  \
  CASADI_SYMBOL_EXPORT casadi_int name##_n_out(void) { return name##_shape_n_out(); }                                \
  CASADI_SYMBOL_EXPORT const casadi_int* name##_sparsity_in(casadi_int i) { return name##_shape_sparsity_in(i); }    \
  CASADI_SYMBOL_EXPORT const casadi_int* name##_sparsity_out(casadi_int i) { return name##_shape_sparsity_out(i); }  \
  CASADI_SYMBOL_EXPORT int name##_work(casadi_int* sz_arg, casadi_int* sz_res, casadi_int* sz_iw, casadi_int* sz_w) { \
    if (sz_arg) *sz_arg = name##_shape_n_in();                                                                         \
    if (sz_res) *sz_res = name##_shape_n_out();                                                                        \
    if (sz_iw) *sz_iw = 0;                                                                                             \
    if (sz_w) *sz_w = 0;                                                                                               \
    return 0;                                                                                                          \
  }
ARMCTL_SHAPE(advance)
ARMCTL_SHAPE(begin)
ARMCTL_SHAPE(accel)
