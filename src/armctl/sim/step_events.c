/* Stick–slip of the generated step (see step_core.c): which joints stick, the events within a step, and the
 * functions CasADi loads. */

/* stick_slip.solve_sticking, on M and r (r is changed); m->stuck holds the candidates on entry. On return, a holds the
 * accelerations of the joints left free (the stuck ones' 0) unless every joint is stuck. */
static int armctl_solve_sticking(const double* M, double* r, armctl_mode* m, const int* held, const double* par,
                                 double* a) {
  double lam[N], Ma[N];
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
  m->solved = 0;
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
    double* out[4] = {M, r, m->start_f, m->start_e};
    CALL(pk_terms, 6, in, 4, out);
  }
  for (i = 0; i < N; ++i) m->stuck[i] = cand[i];
  if (armctl_solve_sticking(M, r, m, held, par, m->start_a) != OK) return NOT_POSITIVE_DEFINITE;
  m->any = m->all = 0;
  for (i = 0; i < N; ++i) {
    if (cand[i] && !m->stuck[i]) S[S_BREAKAWAY_EVENTS] += 1.0;
    if (m->stuck[i]) m->any = 1;
  }
  m->all = 1;
  for (i = 0; i < N; ++i) if (!m->stuck[i]) m->all = 0;
  if (!m->any) for (i = 0; i < N; ++i) m->hold[i] = 0.0;
  /* q̈ at this state as pk_rhs gives it for the stick state found: the solve's last (r as pk_rhs's right-hand side
   * with the directions of the joints that broke away; their friction force does no work at their zero velocity) */
  m->solved = !m->all;
#else
  (void)q; (void)v; (void)tau; (void)hd; (void)par; (void)m; (void)held; (void)S;
#endif
  return OK;
}

/* stepper.advance: the step from (q, v) over h under tau, with stick–slip events. begun: the stick state is S's, solved
 * at (q, v) — the mode itself if given (with what its solve found there), else read from S. */
static int armctl_advance(int scheme, double h, int begun, const armctl_mode* begun_mode, const double* q_in,
                          const double* v_in, const double* tau, const double* W, const double* par, double* S,
                          double* q_out, double* v_out, double* a_first, int* a_first_valid, double* wf_out,
                          double* we_out) {
  armctl_mode m;
  double q[N], v[N], qn[N], vn[N], an[N], off = 0.0, remaining = h, wf = 0.0, we = 0.0, dwf, dwe, hd[6];
  int held[N], have_held = 0, at_start = 1, attempt, budget = 4 * N + 8, an_valid, st, i;
  memcpy(q, q_in, sizeof q);
  memcpy(v, v_in, sizeof v);
  if (begun && begun_mode)
    m = *begun_mode;
  else
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

/* Plant.friction_torque: the friction model's torque for the sliding joints, the holding torque for the stuck ones,
 * into S's friction torque (zeros without friction). */
static void armctl_friction_torque(const double* v, const armctl_mode* m, const double* par, double* S) {
  int i;
#if ARMCTL_FRICTION
  double f[N];
  const double* in[3] = {v, m->dir, par};
  double* out[1] = {f};
  CALL(pk_friction, 3, in, 1, out);
  for (i = 0; i < N; ++i) S[S_TAUF + i] = f[i] + m->hold[i];
#else
  (void)v; (void)m; (void)par;
  for (i = 0; i < N; ++i) S[S_TAUF + i] = 0.0;
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
  st = armctl_advance((int)arg[5][2], arg[5][1], begun, 0, q, v, tau, arg[3], arg[4], S, q1, v1, a0, &valid, &wf, &we);
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

/* begin and accel read q, v and tau where they are (inputs no output aliases); S is copied in (the state is both
 * an input and the output of begin). */
CASADI_SYMBOL_EXPORT int begin(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem) {
  double S[NS], hd[6];
  armctl_mode m;
  int st;
  (void)iw; (void)w; (void)mem;
  memcpy(S, arg[5], sizeof S);
  armctl_mode_read(S, &m);
  armctl_interp(arg[3], 0.0, hd);
  st = armctl_begin(arg[0], arg[1], arg[2], hd, arg[4], &m, 0, S);
  armctl_mode_write(&m, S);
  armctl_friction_torque(arg[1], &m, arg[4], S);
  S[S_BEGUN] = 1.0;
  memcpy(res[0], S, sizeof S);
  res[1][0] = m.any;
  res[1][1] = m.all;
  res[1][2] = 0.0;
  res[1][3] = st;
  return 0;
}

CASADI_SYMBOL_EXPORT int accel(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem) {
  double a[N], f[N], e[N], hd[6];
  armctl_mode m;
  int st;
  (void)iw; (void)w; (void)mem;
  armctl_mode_read(arg[5], &m);
  armctl_interp(arg[3], 0.0, hd);
  st = m.all ? OK : armctl_rhs(arg[0], arg[1], arg[2], hd, arg[4], &m, a, f, e);
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
