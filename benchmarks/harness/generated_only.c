/* The generated side of the runtime harness alone (no Pinocchio): times the five routines of every linked
   model, and the others of runtime.PAIRS it was generated with, the way pinocchio_bench.cpp does (batches over
   precomputed random states, median of per-batch means) and writes JSON.  Used by tests/test_bench_harness.py, which cannot wait for the C++ build.

     generated_only SECONDS STATES CALLS OUT.json */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench.h"

static unsigned long long rng_state = 88172645463325252ULL;

static double uniform01(void) {
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return ((double)(rng_state >> 11) + 0.5) / 9007199254740992.0;
}

static double normal01(void) {
    return sqrt(-2.0 * log(uniform01())) * cos(6.283185307179586 * uniform01());
}

static int cmp(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *v, int n) {
    qsort(v, (size_t)n, sizeof *v, cmp);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

int main(int argc, char **argv) {
    static const char *const roles[] = {"inertia", "nonlinear_effects", "inverse_dynamics", "forward_dynamics",
                                        "inertia_inverse", "inverse_dynamics_derivatives",
                                        "forward_dynamics_derivatives", "frame_jacobians", "regressor"};
    double seconds;
    int nstates, calls, m, k, b, i, written;
    FILE *out;
    if (argc != 5) {
        fprintf(stderr, "usage: %s SECONDS STATES CALLS OUT.json\n", argv[0]);
        return 2;
    }
    seconds = atof(argv[1]);
    nstates = atoi(argv[2]);
    calls = atoi(argv[3]);
    out = fopen(argv[4], "w");
    if (!out || nstates < 1 || calls < 1) return 2;
    fprintf(out, "{\"states\": %d, \"robots\": [", nstates);
    for (m = 0; bench_models[m]; ++m) {
        const bench_model *bm = bench_models[m];
        const int n = bm->nv;
        const size_t size = (size_t)nstates * (size_t)n, size_q = (size_t)nstates * (size_t)bm->nq;
        /* the largest output: two n*n matrices, the frames' 6 x n blocks, or the regressor */
        size_t out_size = 2 * (size_t)n * (size_t)n;
        double *q = malloc(size_q * sizeof *q), *qd = malloc(size * sizeof *q), *qdd = malloc(size * sizeof *q);
        double *tau = malloc(size * sizeof *q), *buf;
        bench_timer timers[9];
        bench_states s;
        timers[0] = bm->t_inertia;
        timers[1] = bm->t_nonlinear_effects;
        timers[2] = bm->t_inverse_dynamics;
        timers[3] = bm->t_forward_dynamics;
        timers[4] = bm->t_inertia_inverse;
        timers[5] = bm->t_inverse_dynamics_derivatives;
        timers[6] = bm->t_forward_dynamics_derivatives;
        timers[7] = bm->t_frame_jacobians;
        timers[8] = bm->t_regressor;
        if ((size_t)bm->nframes * 6 * (size_t)n > out_size) out_size = (size_t)bm->nframes * 6 * (size_t)n;
        if ((size_t)bm->regressor_cols * (size_t)n > out_size) out_size = (size_t)bm->regressor_cols * (size_t)n;
        buf = malloc(out_size * sizeof *buf);
        for (i = 0; i < (int)size_q; ++i) q[i] = -3.141592653589793 + 6.283185307179586 * uniform01();
        for (i = 0; i < (int)size; ++i) {
            qd[i] = normal01();
            qdd[i] = normal01();
            tau[i] = normal01();
        }
        s.count = nstates;
        s.nq = bm->nq;
        s.nv = n;
        s.q = q;
        s.qd = qd;
        s.qdd = qdd;
        s.tau = tau;
        s.p = bm->p;
        fprintf(out, "%s{\"name\": \"%s\", \"nq\": %d, \"nv\": %d, \"pairs\": [", m ? ", " : "", bm->name,
                bm->nq, n);
        for (k = 0, written = 0; k < 9; ++k) {
            double cpu, t = 0.0;
            int batches, first;
            double *g, *c;
            if (!timers[k]) continue; /* a routine the model was generated without */
            for (first = 0; first < nstates; first += calls) t += timers[k](&s, first, calls, buf, &cpu) * calls;
            batches = (int)ceil(seconds * 1e9 / (t > 1.0 ? t : 1.0) * nstates / calls);
            batches = batches < 51 ? 51 : (batches > 400001 ? 400001 : batches);
            g = malloc((size_t)batches * sizeof *g);
            c = malloc((size_t)batches * sizeof *c);
            for (b = 0; b < batches; ++b)
                g[b] = timers[k](&s, (int)(((long long)b * calls) % nstates), calls, buf, &c[b]);
            fprintf(out, "%s{\"role\": \"%s\", \"batches\": %d, \"generated_ns\": %.3f, \"generated_cpu_ns\": %.3f}",
                    written++ ? ", " : "", roles[k], batches, median(g, batches), median(c, batches));
            free(g);
            free(c);
        }
        fprintf(out, "]}");
        free(q);
        free(qd);
        free(qdd);
        free(tau);
        free(buf);
    }
    fprintf(out, "], \"sink\": %g}\n", (double)bench_sink);
    fclose(out);
    return 0;
}
