/* The interface between the generated C of a model with contacts (generated with --constraints and the routines
   constrained_forward_dynamics(_derivatives), impulse_dynamics(_derivatives)) and constrained_derivatives_bench.cpp:
   one record per model, four batch timers each (bench.h's BENCH_TIMER loop).  In these models' bench_states, qd
   is a velocity consistent with the constraints (J qd = 0: the constrained forward dynamics is evaluated there)
   and qdd holds the velocity before an impact (any velocity: the impulse dynamics is evaluated there). */
#ifndef AGGSYM_CONTACT_BENCH_H
#define AGGSYM_CONTACT_BENCH_H

#include "bench.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef int (*bench_fn_cfd_derivatives)(const double *q, const double *qd, const double *tau, const double *p,
                                        double *dqdd_dq, double *dqdd_dqd, double *dqdd_dtau, double *dJtlambda_dq,
                                        double *dJtlambda_dqd, double *dJtlambda_dtau);
typedef int (*bench_fn_impulse)(const double *q, const double *qd_minus, const double *r, const double *p,
                                double *qd_plus, double *impulse, double *Lambda);
typedef int (*bench_fn_impulse_derivatives)(const double *q, const double *qd_minus, const double *r,
                                            const double *p, double *dqd_plus_dq, double *dqd_plus_dqd_minus,
                                            double *dimpulse_dq, double *dimpulse_dqd_minus);

typedef struct {
    const char *name;
    int nq, nv, nc;             /* q's length, qd's, and the constraint rows (lambda's length) */
    int free_flyer;             /* 1: --floating-base quaternion (Pinocchio's JointModelFreeFlyer), 0: fixed base */
    int np;
    const double *p;            /* default parameters or NULL */
    double r;                   /* the restitution coefficient of the timed impacts */
    const char *const *joints;  /* the joint name of each velocity coordinate */
    bench_fn_cfd constrained_forward_dynamics;
    bench_fn_cfd_derivatives constrained_forward_dynamics_derivatives;
    bench_fn_impulse impulse_dynamics;
    bench_fn_impulse_derivatives impulse_dynamics_derivatives;
    /* out: the derivatives' blocks at out + k n*n (six, or four), then the value's outputs after them */
    bench_timer t_cfd_derivatives;       /* constrained_forward_dynamics_derivatives alone */
    bench_timer t_cfd_with_value;        /* constrained_forward_dynamics, then its derivatives */
    bench_timer t_impulse_derivatives;   /* impulse_dynamics_derivatives alone */
    bench_timer t_impulse_with_value;    /* impulse_dynamics, then its derivatives */
} bench_contact_model;

extern const bench_contact_model *const bench_contact_models[]; /* NULL-terminated */

#ifdef __cplusplus
}
#endif

#ifndef __cplusplus
/* The four timers and the record of model NAME (its r a one-entry array NAME_r). */
#define BENCH_CONTACT_MODEL(NAME, NQ, NV, NC, FF, NP, P, R, JOINTS)                                          \
    static const double NAME##_r[1] = {R};                                                                    \
    BENCH_TIMER(NAME##_t_cfd_derivatives,                                                                     \
                NAME##_constrained_forward_dynamics_derivatives(s->q + at_q, s->qd + at, s->tau + at, s->p,   \
                    out, out + n * n, out + 2 * n * n, out + 3 * n * n, out + 4 * n * n, out + 5 * n * n))    \
    BENCH_TIMER(NAME##_t_cfd_with_value,                                                                      \
                (NAME##_constrained_forward_dynamics(s->q + at_q, s->qd + at, s->tau + at, s->p,              \
                                                     out + 6 * n * n, out + 6 * n * n + n),                   \
                 NAME##_constrained_forward_dynamics_derivatives(s->q + at_q, s->qd + at, s->tau + at, s->p,  \
                    out, out + n * n, out + 2 * n * n, out + 3 * n * n, out + 4 * n * n, out + 5 * n * n)))   \
    BENCH_TIMER(NAME##_t_impulse_derivatives,                                                                 \
                NAME##_impulse_dynamics_derivatives(s->q + at_q, s->qdd + at, NAME##_r, s->p, out,            \
                    out + n * n, out + 2 * n * n, out + 3 * n * n))                                           \
    BENCH_TIMER(NAME##_t_impulse_with_value,                                                                  \
                (NAME##_impulse_dynamics(s->q + at_q, s->qdd + at, NAME##_r, s->p, out + 6 * n * n,           \
                                         out + 6 * n * n + n, out + 6 * n * n + 2 * n),                       \
                 NAME##_impulse_dynamics_derivatives(s->q + at_q, s->qdd + at, NAME##_r, s->p, out,           \
                    out + n * n, out + 2 * n * n, out + 3 * n * n)))                                          \
    static const bench_contact_model NAME##_contact_bench = {                                                 \
        #NAME, NQ, NV, NC, FF, NP, P, R, JOINTS, NAME##_constrained_forward_dynamics,                         \
        NAME##_constrained_forward_dynamics_derivatives, NAME##_impulse_dynamics,                             \
        NAME##_impulse_dynamics_derivatives, NAME##_t_cfd_derivatives, NAME##_t_cfd_with_value,               \
        NAME##_t_impulse_derivatives, NAME##_t_impulse_with_value};
#endif

#endif
