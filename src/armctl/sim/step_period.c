/* One control period of the simulator's loop in one call (see step_core.c for the definitions; appended after
 * step_events.c): the C transcription of PythonEngine.advance_period and PythonEngine.last_sample
 * (armctl/sim/python_engine.py), the plant's side of the period [t_k, t_k + Δt_c) under the held τ_k — the stick
 * solve at t_k (Plant.begin), the friction torque and the stuck joints recorded there (Recorder.record_friction),
 * q̈ at t_k, the m sub-steps with their events (stepper.advance), the friction and external work accumulated over
 * them. A change to one is a change to the other (tests/sim/test_compiled_plant.py compares them). Before them, the
 * torque is held as every engine holds it (armctl_hold, the transcription of Saturation.hold,
 * armctl/sim/saturation.py): the checks of the state and the controller's call are ClosedLoop's, in Python.
 *
 *   period(TAU, W, par, opt, S, LIM) -> (Q, V, A, F, STUCK, WF, WE, out, S, TAUA, H, P, TE, WR)
 *
 * TAU, TAUA and the outputs Q … WE are bound to the whole arrays of the run's record (rows of N, or of 1 for the
 * work), larger than the one row they are declared as (CasADi's buffers take any buffer at least that large). The
 * function reads τ_k from row k of TAU (the controller's torques), holds it (finite, clipped at the effort limits
 * LIM where opt[8] says so) into row k of TAUA (the applied torques), reads the state of sample k (row k of Q and V,
 * the work so far from WF[k] and WE[k]) and writes row k of A, F and STUCK (STUCK only where a joint is stuck: the
 * record starts as zeros) and row k + 1 of Q, V, WF and WE. W holds the disturbance's samples of every sub-step, 18
 * each (start, middle, end of sub-step i at W + 18 i; only its start for the last sample).
 *
 * Where opt[9] says so (a plant with contact points and no disturbance), the period also records the contacts at the
 * state it leaves, sample k + 1 (armctl_record_sample: the kernel pk_sample, the generated transcription of
 * Recorder.record_external, armctl/sim/recorder.py): rows of H (the points' forces on the environment, 3 P a row), P
 * (their positions), TE (τ_ext) and WR (the wrench about the tool frame's origin). m < 0 records sample k only
 * (the run's first sample, before any period).
 *
 * opt = [k, h, scheme, m, rows, q̈ by an evaluation at t_k (1) or from the first sub-step (0), max_velocity,
 *        max_position, saturate (1: clip at LIM), record the contacts (1)]; m = 0: the last sample (no step after
 *        it: the hold, the stick solve, its records and q̈ only); m < 0: the contacts of sample k only.
 * out = [status, where it failed (PERIOD_BEGIN, PERIOD_ACCEL, PERIOD_STEP), the state code of the state it left
 *        (armctl_state_check), or TORQUE_NOT_FINITE: τ_k is not finite and nothing else was written].
 * A row outside the record (k < 0, or k + 1 ≥ rows with m > 0, k ≥ rows) writes nothing: status BAD_ROW.
 */
#define BAD_ROW 3
#define PERIOD_BEGIN 0
#define PERIOD_ACCEL 1
#define PERIOD_STEP 2
#define STATE_OK 0
#define STATE_NOT_FINITE 1
#define STATE_VELOCITY 2
#define STATE_POSITION 3
#define TORQUE_NOT_FINITE 4

/* Saturation.hold (armctl/sim/saturation.py), the torque held over a period: nothing (0) where an entry of τ is not
 * finite, else (1) max(min(τ_i, limit_i), −limit_i) where clip, τ itself otherwise. A change to one is a change to the
 * other (tests/sim/test_period.py compares them). */
static int armctl_hold(const double* tau, const double* limit, int clip, double* held) {
  int i;
  for (i = 0; i < N; ++i)
    if (!isfinite(tau[i])) return 0;
  for (i = 0; i < N; ++i) held[i] = clip ? fmax(fmin(tau[i], limit[i]), -limit[i]) : tau[i];
  return 1;
}

/* engine.state_code (armctl/sim/engine.py), the stop rules on the state a period leaves: the same tests in the same
 * order (finite: every entry; a sum could overflow). A change to one is a change to the other
 * (tests/sim/test_period.py compares them). */
static int armctl_state_check(const double* q, const double* v, double max_velocity, double max_position) {
  double vmax = -INFINITY, vmin = INFINITY, qmax = -INFINITY, qmin = INFINITY;
  int i, finite = 1;
  for (i = 0; i < N; ++i) {
    if (!isfinite(q[i]) || !isfinite(v[i])) finite = 0;
    if (v[i] > vmax) vmax = v[i];
    if (v[i] < vmin) vmin = v[i];
    if (q[i] > qmax) qmax = q[i];
    if (q[i] < qmin) qmin = q[i];
  }
  if (!finite) return STATE_NOT_FINITE;
  if (vmax > max_velocity || -vmin > max_velocity) return STATE_VELOCITY;
  if (max_position < INFINITY && (qmax > max_position || -qmin > max_position)) return STATE_POSITION;
  return STATE_OK;
}

/* Recorder.record_external (armctl/sim/recorder.py) for a plant without a disturbance: the contacts at the state
 * (q, v) of sample k into row k of H, P, TE and WR (res[10] … res[13]) by the kernel pk_sample
 * (generated_plant.PlantExpressions.sample). A change to one is a change to the other
 * (tests/sim/test_contact_record.py compares them). */
static void armctl_record_sample(const double* q, const double* v, const double* par, long k, double** res) {
#if ARMCTL_POINTS
  const double* in[3] = {q, v, par};
  double* out[4] = {res[10] + k * 3 * ARMCTL_POINTS, res[11] + k * 3 * ARMCTL_POINTS, res[12] + k * N, res[13] + k * 6};
  CALL(pk_sample, 3, in, 4, out);
#else
  (void)q; (void)v; (void)par; (void)k; (void)res;
#endif
}

CASADI_SYMBOL_EXPORT int period(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem) {
  const double *W = arg[1], *par = arg[2], *opt = arg[3];
  double *Q = res[0], *V = res[1], *A = res[2], *F = res[3], *STUCK = res[4], *WF = res[5], *WE = res[6];
  double *out = res[7];
  double S[NS], q[N], v[N], tau[N], hd[6];
  long k = (long)opt[0], m = (long)opt[3], rows = (long)opt[4], i;
  int scheme = (int)opt[2], st, j;
  double h = opt[1];
  armctl_mode md;
  (void)iw; (void)w; (void)mem;
  out[0] = out[1] = out[2] = 0.0;
  if (k < 0 || k >= rows || (m > 0 && k + 1 >= rows)) {
    out[0] = BAD_ROW;
    return 0;
  }
  if (m < 0) { /* the contacts of sample k only */
    if (opt[9] != 0.0) armctl_record_sample(Q + k * N, V + k * N, par, k, res);
    memmove(res[8], arg[4], sizeof S);
    return 0;
  }
  if (!armctl_hold(arg[0] + k * N, arg[5], opt[8] != 0.0, tau)) {
    out[2] = TORQUE_NOT_FINITE;
    memmove(res[8], arg[4], sizeof S); /* (the state unchanged: they may be one buffer) */
    return 0;
  }
  memcpy(res[9] + k * N, tau, sizeof tau);
  memcpy(S, arg[4], sizeof S);
  memcpy(q, Q + k * N, sizeof q);
  memcpy(v, V + k * N, sizeof v);
  /* Plant.begin at t_k, and what Recorder.record_friction records of it (as the function begin) */
  armctl_mode_read(S, &md);
  armctl_interp(W, 0.0, hd);
  st = armctl_begin(q, v, tau, hd, par, &md, 0, S);
  armctl_mode_write(&md, S);
  if (st != OK) {
    out[0] = st;
    out[1] = PERIOD_BEGIN;
    memcpy(res[8], S, sizeof S);
    return 0;
  }
  armctl_friction_torque(v, &md, par, S);
  for (j = 0; j < N; ++j) F[k * N + j] = S[S_TAUF + j];
  if (md.any) /* (else the row stays as the record starts it: zeros) */
    for (j = 0; j < N; ++j) STUCK[k * N + j] = md.stuck[j];
  if (opt[5] != 0.0 || m == 0) { /* q̈ at t_k by an evaluation (the implicit schemes' and the last sample's) */
    double a[N], f[N], e[N];
    st = md.all ? OK : armctl_rhs(q, v, tau, hd, par, &md, a, f, e);
    if (st != OK) {
      out[0] = st;
      out[1] = PERIOD_ACCEL;
      memcpy(res[8], S, sizeof S);
      return 0;
    }
    if (md.all) memset(a, 0, sizeof a);
    memcpy(A + k * N, a, sizeof a);
  }
  if (m > 0) {
    double q1[N], v1[N], a0[N], wf = WF[k], we = WE[k], dwf, dwe;
    int valid;
    for (i = 0; i < m; ++i) {
      st = armctl_advance(scheme, h, i == 0, &md, q, v, tau, W + 18 * i, par, S, q1, v1, a0, &valid, &dwf, &dwe);
      if (st != OK) {
        out[0] = st;
        out[1] = PERIOD_STEP;
        memcpy(res[8], S, sizeof S);
        return 0;
      }
      if (i == 0 && valid) memcpy(A + k * N, a0, sizeof a0);
      wf += dwf;
      we += dwe;
      memcpy(q, q1, sizeof q);
      memcpy(v, v1, sizeof v);
    }
    memcpy(Q + (k + 1) * N, q, sizeof q);
    memcpy(V + (k + 1) * N, v, sizeof v);
#if ARMCTL_FRICTION || ARMCTL_EXTERNAL
    WF[k + 1] = wf;
    WE[k + 1] = we;
#else
    (void)wf; (void)we;
#endif
    out[2] = armctl_state_check(q, v, opt[6], opt[7]);
    if (opt[9] != 0.0 && out[2] == STATE_OK) armctl_record_sample(q, v, par, k + 1, res);
  }
  S[S_BEGUN] = 0.0;
  memcpy(res[8], S, sizeof S);
  return 0;
}

ARMCTL_SHAPE(period)
