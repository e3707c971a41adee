/* The runtime benchmark's interface between the generated C (timed from C, bench_models.c) and the
   Pinocchio side (pinocchio_bench.cpp).  Each timer runs one batch: every precomputed state once, each call's
   output read into an accumulator that ends in a volatile sink, so no call can be optimised away (the
   generated functions live in another translation unit and a shared library anyway). */
#ifndef AGGSYM_BENCH_H
#define AGGSYM_BENCH_H

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    int count;          /* number of states */
    int nq;             /* the length of q */
    int nv;             /* the length of qd, qdd, tau (nq - 1 with a quaternion free-flyer, else nq) */
    const double *q;    /* count x nq, row-major: our coordinates */
    const double *qd;   /* count x nv, as qdd and tau */
    const double *qdd;
    const double *tau;
    const double *p;    /* parameter vector (NULL when the model has none) */
} bench_states;

typedef void (*bench_fn_q)(const double *q, const double *p, double *out);
typedef void (*bench_fn_qv)(const double *q, const double *qd, const double *p, double *out);
typedef void (*bench_fn_qvx)(const double *q, const double *qd, const double *x, const double *p, double *out);
typedef void (*bench_fn_qvx2)(const double *q, const double *qd, const double *x, const double *p, double *out1,
                              double *out2);
/* One batch: `calls` calls on the states first, first+1, ... (cycling through the `count` states); returns the
   batch's mean wall-clock ns per call (CLOCK_MONOTONIC) and stores its mean thread-CPU ns per call
   (CLOCK_THREAD_CPUTIME_ID, which leaves out time the thread was preempted) in *cpu_ns. */
typedef double (*bench_timer)(const bench_states *s, int first, int calls, double *out, double *cpu_ns);

typedef struct {
    const char *name;
    int nq;                     /* the length of q */
    int nv;                     /* the length of qd, qdd, tau */
    int free_flyer;             /* 1: generated with --floating-base quaternion (Pinocchio's JointModelFreeFlyer root);
                                   2: with --floating-base euler (Pinocchio's composite root PX PY PZ RX RY RZ) */
    int np;
    const double *p;            /* default parameters or NULL */
    const char *const *joints;  /* the joint name of each velocity coordinate, in qd order */
    bench_fn_q inertia;         /* A(q), n*n row-major */
    bench_fn_qv nonlinear_effects; /* b + g */
    bench_fn_qvx inverse_dynamics; /* (q, qd, qdd) -> tau */
    bench_fn_qvx forward_dynamics; /* (q, qd, tau) -> qdd */
    bench_fn_q inertia_inverse;  /* A^-1, n*n row-major */
    bench_timer t_inertia;
    bench_timer t_nonlinear_effects;
    bench_timer t_inverse_dynamics;
    bench_timer t_forward_dynamics;
    bench_timer t_inertia_inverse;
    /* The routines beyond the five (NULL when the model was generated without them).  A timer of a routine with two
       n*n outputs writes them to out and out + n*n. */
    int nframes;                /* frames of frame_jacobians (0 without it) */
    const char *const *frames;  /* their names (URDF links), in the routine's order */
    int regressor_cols;         /* columns of the regressor, 10 per moving body (0 without it) */
    bench_fn_qvx2 inverse_dynamics_derivatives; /* (q, qd, qdd) -> dtau_dq, dtau_dqd, n*n each */
    bench_fn_qvx2 forward_dynamics_derivatives; /* (q, qd, tau) -> dqdd_dq, dqdd_dqd, n*n each */
    bench_fn_q frame_jacobians;  /* per frame a 6 x n block (v, w of its origin, world axes), row-major */
    bench_fn_qvx regressor;      /* (q, qd, qdd) -> Y, n x regressor_cols row-major */
    bench_timer t_inverse_dynamics_derivatives;
    bench_timer t_forward_dynamics_derivatives;
    bench_timer t_frame_jacobians;
    bench_timer t_regressor;
} bench_model;

/* A model with constraints (generated with --constraints): its constrained forward dynamics alone. */
typedef int (*bench_fn_cfd)(const double *q, const double *qd, const double *tau, const double *p, double *qdd,
                            double *lambda);
typedef struct {
    const char *name;
    int nq;
    int nc;                     /* constraint rows: the length of lambda */
    int np;
    const double *p;            /* default parameters or NULL */
    const char *const *joints;  /* the joint name of each coordinate, in q order */
    bench_fn_cfd constrained_forward_dynamics; /* (q, qd, tau) -> qdd, lambda; nonzero when singular */
    bench_timer t_constrained_forward_dynamics; /* out: nq + nc doubles (qdd, then lambda) */
} bench_constrained_model;

/* A peer of a generated model: the same five routines by other code, timed beside the generated code and
   Pinocchio on the same states in the same batches (the generated C compiled -O3, the CasADi peer of
   benchmarks/runtime/casadi_peer.py at -O2 and -O3).  Its model has the generated model's name, joints and parameters;
   only the five routines and their timers are set. */
typedef struct {
    const char *label;          /* e.g. "aggsym -O3", "CasADi -O2" */
    const bench_model *model;
} bench_peer;

extern const bench_model *const bench_models[]; /* NULL-terminated, bench_models.c */
extern const bench_peer *const bench_peers[];   /* NULL-terminated, bench_models.c */
extern const bench_constrained_model *const bench_constrained_models[]; /* NULL-terminated, bench_models.c */
extern volatile double bench_sink;
double bench_now_ns(void);      /* CLOCK_MONOTONIC */
double bench_cpu_now_ns(void);  /* CLOCK_THREAD_CPUTIME_ID */

#ifdef __cplusplus
}
#endif

/* Timers with direct calls (C only): BENCH_TIMER(timer name, the call on state i) */
#ifndef __cplusplus
#define BENCH_TIMER(T, CALL)                                                                    \
    static double T(const bench_states *s, int first, int calls, double *out, double *cpu_ns) { \
        double acc = 0.0, t0, t1, c0, c1;                                                       \
        int k, i = first;                                                                       \
        const size_t n = (size_t)s->nv;                                                         \
        c0 = bench_cpu_now_ns();                                                                \
        t0 = bench_now_ns();                                                                    \
        for (k = 0; k < calls; ++k) {                                                           \
            const size_t at = (size_t)i * n, at_q = (size_t)i * (size_t)s->nq;                  \
            CALL;                                                                               \
            acc += out[0];                                                                      \
            if (++i == s->count) i = 0;                                                         \
        }                                                                                       \
        t1 = bench_now_ns();                                                                    \
        c1 = bench_cpu_now_ns();                                                                \
        bench_sink += acc;                                                                      \
        *cpu_ns = (c1 - c0) / calls;                                                            \
        return (t1 - t0) / calls;                                                               \
    }
#define BENCH_TIMER_Q(T, F) BENCH_TIMER(T, F(s->q + at_q, s->p, out))
#define BENCH_TIMER_QV(T, F) BENCH_TIMER(T, F(s->q + at_q, s->qd + at, s->p, out))
#define BENCH_TIMER_QVX(T, F, X) BENCH_TIMER(T, F(s->q + at_q, s->qd + at, s->X + at, s->p, out))
#define BENCH_TIMER_QVX2(T, F, X) BENCH_TIMER(T, F(s->q + at_q, s->qd + at, s->X + at, s->p, out, out + n * n))
/* The five timers every model has (its bench_model record is written by benchmarks/runtime/pinocchio_cpp.py, with the
   other routines it was generated with). */
#define BENCH_MODEL_TIMERS(NAME)                                                                \
    BENCH_TIMER_Q(NAME##_t_inertia, NAME##_inertia)                                             \
    BENCH_TIMER_QV(NAME##_t_nonlinear_effects, NAME##_nonlinear_effects)                        \
    BENCH_TIMER_QVX(NAME##_t_inverse_dynamics, NAME##_inverse_dynamics, qdd)                    \
    BENCH_TIMER_QVX(NAME##_t_forward_dynamics, NAME##_forward_dynamics, tau)                    \
    BENCH_TIMER_Q(NAME##_t_inertia_inverse, NAME##_inertia_inverse)
/* The timers of the routines beyond the five, one macro each. */
#define BENCH_INVERSE_DYNAMICS_DERIVATIVES(NAME)                                                \
    BENCH_TIMER_QVX2(NAME##_t_inverse_dynamics_derivatives, NAME##_inverse_dynamics_derivatives, qdd)
#define BENCH_FORWARD_DYNAMICS_DERIVATIVES(NAME)                                                \
    BENCH_TIMER_QVX2(NAME##_t_forward_dynamics_derivatives, NAME##_forward_dynamics_derivatives, tau)
#define BENCH_FRAME_JACOBIANS(NAME) BENCH_TIMER_Q(NAME##_t_frame_jacobians, NAME##_frame_jacobians)
#define BENCH_REGRESSOR(NAME) BENCH_TIMER_QVX(NAME##_t_regressor, NAME##_regressor, qdd)
/* A constrained model: its timer (qdd into out, lambda after it) and its bench_constrained_model record. */
#define BENCH_CONSTRAINED_MODEL(NAME, NQ, NC, NP, P, JOINTS)                                    \
    BENCH_TIMER(NAME##_t_constrained_forward_dynamics,                                          \
                NAME##_constrained_forward_dynamics(s->q + at_q, s->qd + at, s->tau + at, s->p, \
                                                    out, out + n))                              \
    static const bench_constrained_model NAME##_constrained_bench = {                           \
        #NAME, NQ, NC, NP, P, JOINTS, NAME##_constrained_forward_dynamics,                      \
        NAME##_t_constrained_forward_dynamics};
#endif

#endif
