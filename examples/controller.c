/* controller.c: PD control with gravity compensation holds arm3 at a target pose; the plant is the same arm,
   its forward dynamics with the joints' damping, stepped by semi-implicit Euler (SI units: rad, N m, s) */
#include <stdio.h>
#include "arm3.h"

int main(void)
{
    const double target[ARM3_NQ] = {0.5, -0.8, 1.2}, kp = 60.0, kd = 12.0, dt = 1e-3;
    double p[ARM3_NP] = ARM3_P_DEFAULTS;          /* run-time parameters: here the joints' damping */
    double q[ARM3_NQ] = {0}, qd[ARM3_NQ] = {0}, g[ARM3_NQ], f[ARM3_NQ], tau[ARM3_NQ], qdd[ARM3_NQ];
    for (int step = 0; step < 3000; ++step) {     /* 3 s */
        arm3_gravity(q, p, g);                    /* g(q): the torques that hold the arm still */
        for (int i = 0; i < ARM3_NQ; ++i) tau[i] = g[i] + kp * (target[i] - q[i]) - kd * qd[i];
        arm3_joint_friction(qd, p, f);            /* the plant's joint friction: -damping qd (URDF <dynamics>) */
        for (int i = 0; i < ARM3_NQ; ++i) f[i] += tau[i];
        arm3_forward_dynamics(q, qd, f, p, qdd);  /* A(q) qdd + b(q, qd) + g(q) = tau + tau_f */
        for (int i = 0; i < ARM3_NQ; ++i) { qd[i] += dt * qdd[i]; q[i] += dt * qd[i]; }
    }
    for (int i = 0; i < ARM3_NQ; ++i) printf("q[%d] = % .9f  (target % .3f)\n", i, q[i], target[i]);
    return 0;
}
