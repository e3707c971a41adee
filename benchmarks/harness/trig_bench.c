/* trig_bench.c: the time of one sin-and-cos of a double, for benchmarks/runtime/trig.py.
 *
 * Built with -DAGGSYM_SINCOS_FILE=... naming a file that defines the generated code's aggsym_sincos (rendered by
 * benchmarks/runtime/trig.py from templates/c/helpers.c.j2), it times, per call, on the same N arguments (uniform in
 * [-LO, LO], LO the first argument, default pi: joint angles, so that a quadrant branch mispredicts):
 *   libm        sin(x) and cos(x), two calls
 *   sincos      GNU sincos(x, &s, &c) where _GNU_SOURCE provides it (glibc), else not printed
 *   switch      aggsym's helper before: a quadrant switch (branchy), libm under -ffast-math (the baseline)
 *   aggsym      the generated aggsym_sincos
 *   aggsym2     the generated aggsym_sincos2, two consecutive arguments a call (time per angle)
 *   latency     aggsym_sincos when each argument depends on the previous result (x_i + 1e-3 s_{i-1}): the time
 *               from an argument to its sin and cos, what one call of a routine waits for
 * and prints one line per variant: NAME NS_PER_ANGLE (the best of REPEATS passes over the arguments, in CPU
 * time). */
#define _GNU_SOURCE  /* sincos, clock_gettime */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include AGGSYM_SINCOS_FILE

#define N 4096
#define PASSES 200
#define REPEATS 7

static void switch_sincos(double x, double *s, double *c)
{
#ifdef __FAST_MATH__
    *s = sin(x);  /* as before: libm under -ffast-math (the reduction below is not safe from reassociation) */
    *c = cos(x);
#else
    if (!(fabs(x) < 1.0e6)) {
        *s = sin(x);
        *c = cos(x);
        return;
    }
    const double t = x * 0.6366197723675814;
    const long k = (long)(t < 0.0 ? t - 0.5 : t + 0.5);
    const double kd = (double)k;
    const double r = ((x - kd * 1.5707963267341256) - kd * 6.077100506303966e-11) - kd * 2.0222662487959506e-21;
    const double r2 = r * r;
    const double sr = r + r * r2 * (-0.16666666666666666 + r2 * (0.008333333333333333 + r2 * (-0.0001984126984126984
        + r2 * (2.7557319223985893e-06 + r2 * (-2.505210838544172e-08 + r2 * (1.6059043836821613e-10
        + r2 * (-7.647163731819816e-13 + r2 * 2.8114572543455206e-15)))))));
    const double cr = 1.0 + r2 * (-0.5 + r2 * (0.041666666666666664 + r2 * (-0.001388888888888889
        + r2 * (2.48015873015873e-05 + r2 * (-2.755731922398589e-07 + r2 * (2.08767569878681e-09
        + r2 * (-1.1470745597729725e-11 + r2 * (4.779477332387385e-14 + r2 * -1.5619206968586225e-16))))))));
    switch (k & 3) {
    case 0: *s = sr; *c = cr; break;
    case 1: *s = cr; *c = -sr; break;
    case 2: *s = -sr; *c = -cr; break;
    default: *s = -cr; *c = sr; break;
    }
#endif
}

static void libm_sincos(double x, double *s, double *c)
{
    *s = sin(x);
    *c = cos(x);
}

#if defined(__GLIBC__)
static void gnu_sincos(double x, double *s, double *c)
{
    sincos(x, s, c);
}
#endif

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);  /* CPU time: a shared machine's waits left out */
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double xs[N];
static volatile double sink;

/* a pass over the arguments, one call per angle, the call inlined where the compiler chooses (as in generated
 * code): pass_FN(acc) */
#define ONE_ANGLE_PASS(FN)                                                      \
    static double pass_##FN(double acc)                                         \
    {                                                                           \
        for (int i = 0; i < N; i++) {                                           \
            double s, c;                                                        \
            FN(xs[i], &s, &c);                                                  \
            acc += s + c;                                                       \
        }                                                                       \
        return acc;                                                             \
    }

ONE_ANGLE_PASS(libm_sincos)
#if defined(__GLIBC__)
ONE_ANGLE_PASS(gnu_sincos)
#endif
ONE_ANGLE_PASS(switch_sincos)
ONE_ANGLE_PASS(aggsym_sincos)

static double pair_pass(double acc)  /* aggsym_sincos2 on consecutive arguments */
{
    for (int i = 0; i < N; i += 2) {
        double s0, c0, s1, c1;
        aggsym_sincos2(xs[i], xs[i + 1], &s0, &c0, &s1, &c1);
        acc += s0 + c0 + s1 + c1;
    }
    return acc;
}

static double latency_pass(double acc)  /* each argument waits for the last result */
{
    for (int i = 0; i < N; i++) {
        double s, c;
        aggsym_sincos(xs[i] + 1e-3 * acc, &s, &c);
        acc = s;
    }
    return acc;
}

#define TIME_PASS(NAME, PASS)                                                   \
    do {                                                                        \
        double best = 1e300;                                                    \
        for (int rep = 0; rep < REPEATS; rep++) {                               \
            double acc = 0.0;                                                   \
            const double t0 = now();                                            \
            for (int pass = 0; pass < PASSES; pass++)                           \
                acc = PASS(acc);                                                \
            const double t = now() - t0;                                        \
            sink = acc;                                                         \
            if (t < best)                                                       \
                best = t;                                                       \
        }                                                                       \
        printf("%s %.3f\n", NAME, 1e9 * best / ((double)PASSES * N));          \
    } while (0)

int main(int argc, char **argv)
{
    const double lo = argc > 1 ? atof(argv[1]) : 3.141592653589793;
    srand(12345);
    for (int i = 0; i < N; i++)
        xs[i] = lo * (2.0 * ((double)rand() / RAND_MAX) - 1.0);
    TIME_PASS("libm", pass_libm_sincos);
#if defined(__GLIBC__)
    TIME_PASS("sincos", pass_gnu_sincos);
#endif
    TIME_PASS("switch", pass_switch_sincos);
    TIME_PASS("aggsym", pass_aggsym_sincos);
    TIME_PASS("aggsym2", pair_pass);
    TIME_PASS("latency", latency_pass);
    return 0;
}
