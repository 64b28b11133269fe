/* The integration schemes of the generated step (see step_core.c): RK4 and Euler with the work of the forces,
 * backward and symplectic Euler by Newton's method. */

/* implicit._newton_update: one Newton step x − J⁻¹r of the implicit schemes, the stuck joints held (their rows and
 * columns of J replaced by the identity's, their residual zero); *converged: the step was below the tolerance. jac
 * and res are overwritten. */
static int armctl_newton_update(double* jac, double* res, const int* stuck, double* x, int* converged) {
  double dx[N];
  int i, j, st;
  if (stuck) for (i = 0; i < N; ++i) if (stuck[i]) {
    for (j = 0; j < N; ++j) { jac[i + N * j] = 0.0; jac[j + N * i] = 0.0; }
    jac[i + N * i] = 1.0;
    res[i] = 0.0;
  }
  for (i = 0; i < N; ++i) res[i] = -res[i];
  if ((st = armctl_lu_solve(jac, res, dx)) != OK) return st;
  for (i = 0; i < N; ++i) x[i] += dx[i];
  *converged = armctl_max_abs(dx) <= NEWTON_TOL * (1.0 + armctl_max_abs(x));
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
    if (m->solved) { /* the stick solve's at this state (armctl_begin) */
      memcpy(a[0], m->start_a, sizeof a[0]);
      memcpy(f, m->start_f, sizeof f);
      memcpy(e, m->start_e, sizeof e);
    } else if ((st = armctl_rhs(q, v, tau, hd, par, m, a[0], f, e)) != OK) {
      return st;
    }
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
        int st = armctl_newton_update(jac, res, stuck, x, &converged);
        if (st != OK) return st;
        if (converged) break;
      }
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
    double p0[N], vb[N], fs[N], jx[N * N], f[N], e[N], K[N * N], jac[N * N], res[N], Mvb[N], Kvb[N];
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
        int st = armctl_newton_update(jac, res, stuck, vb, &converged);
        if (st != OK) return st;
        if (converged) break;
      }
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
    (void)jac; (void)res;
    return OK;
  }
#endif
}
