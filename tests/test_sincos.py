"""The generated C's aggsym_sincos (templates/c/helpers.c.j2; issue 18, item 4): one branch-free sin-and-cos per
angle, within 2 ulp of libm's sin and cos over [-1e6, 1e6], equal to libm's at the double nearest every k pi/2,
libm's own values outside |x| < 1e6 and for nan and inf, and all of this also when compiled with -ffast-math;
and the same of aggsym_sincos2, two angles at once in the lanes of one vector (each test runs on both).

The function under test is the one in a generated model's C (double_pendulum.c, #included by a small driver so
that its static function is reachable); the reference is libm (Python's math.sin and math.cos call the C
library's sin and cos), and the doubles nearest k pi/2 come from mpmath at 200 bits."""
from __future__ import annotations

import ctypes
import json
import math
import re
import subprocess
import warnings

import mpmath
import numpy as np
import pytest

import aggsym
from aggsym.codegen.compile import compiler
from aggsym.codegen.generate import generate
from conftest import model_path

FLAGS = {"O2": ["-O2"], "O2-fast-math": ["-O2", "-ffast-math"]}
BOUND_ULP = 2
K_MAX = int(1e6 / (math.pi / 2))  # the largest |k| with k pi/2 inside (-1e6, 1e6)

DRIVER = """
#include "double_pendulum.c"
void sincos_many(const double *x, double *s, double *c, long n)
{
    for (long i = 0; i < n; i++)
        aggsym_sincos(x[i], s + i, c + i);
}
void sincos2_many(const double *x, double *s, double *c, long n)
{
    long i = 0;
    for (; i + 1 < n; i += 2)
        aggsym_sincos2(x[i], x[i + 1], s + i, c + i, s + i + 1, c + i + 1);
    if (i < n) {  /* the last of an odd count beside pi/3 */
        double s1, c1;
        aggsym_sincos2(x[i], 1.0471975511965976, s + i, c + i, &s1, &c1);
    }
}
"""


def compiled_driver(folder, flags):
    """The generated double_pendulum.c (which calls both aggsym_sincos and aggsym_sincos2) with DRIVER, compiled
    with the flags and -Werror (warning-free), loaded."""
    gen = generate(aggsym.load(model_path("double_pendulum")), targets="c,numpy,manifest")
    for name, text in gen.files.items():
        (folder / name).write_text(text)
    assert "aggsym_sincos(" in gen.files["double_pendulum.c"] and "aggsym_sincos2(" in gen.files["double_pendulum.c"]
    (folder / "driver.c").write_text(DRIVER)
    lib = folder / "libdriver.so"
    subprocess.run([compiler(), "-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Werror", *flags,
                    "-fPIC", "-shared", "-o", str(lib), str(folder / "driver.c"), "-lm"], check=True, cwd=folder)
    return ctypes.CDLL(str(lib))


def as_function(dll, symbol):
    ptr = ctypes.POINTER(ctypes.c_double)

    def f(x):
        x = np.ascontiguousarray(x, dtype=np.float64)
        s, c = np.empty_like(x), np.empty_like(x)
        getattr(dll, symbol)(x.ctypes.data_as(ptr), s.ctypes.data_as(ptr), c.ctypes.data_as(ptr),
                             ctypes.c_long(x.size))
        return s, c
    return f


@pytest.fixture(scope="module", params=sorted(FLAGS))
def driver(request, tmp_path_factory):
    return compiled_driver(tmp_path_factory.mktemp(request.param), FLAGS[request.param])


@pytest.fixture(scope="module", params=["sincos_many", "sincos2_many"])
def sincos(request, driver):
    """The generated aggsym_sincos (one angle a call) or aggsym_sincos2 (two), as f(x) -> (sin, cos)."""
    return as_function(driver, request.param)


def libm(x):
    return np.array([math.sin(v) for v in x]), np.array([math.cos(v) for v in x])


def ulps(a, b) -> np.ndarray:
    """The distance between doubles in units in the last place (the number of doubles between them)."""
    def ordered(v):
        i = np.asarray(v, dtype=np.float64).view(np.int64)
        return np.where(i < 0, np.int64(-2 ** 63) - i, i)
    return np.abs(ordered(a) - ordered(b))


def nearest_multiples(ks, step) -> np.ndarray:
    """The doubles nearest k step, for step = pi/2 or pi/4 (mpmath at 200 bits, rounded to nearest)."""
    with mpmath.workprec(200):
        unit = mpmath.pi * step
        return np.array([float(mpmath.mpf(int(k)) * unit) for k in ks])


def sample_ks(rng, n):
    return np.unique(np.concatenate([np.arange(-400, 401), rng.integers(-K_MAX, K_MAX + 1, n),
                                     [K_MAX, -K_MAX, K_MAX - 1, -(K_MAX - 1)]]))


def test_ulp_distance_counts_doubles():
    """The ulp measure itself: neighbours are 1 apart, across zero too, and identical values 0."""
    x = np.array([1.0, -1.0, 0.0, 1e-300])
    assert list(ulps(x, np.nextafter(x, np.inf))) == [1, 1, 1, 1]
    assert ulps(np.array([5e-324]), np.array([-5e-324]))[0] == 2 and ulps(x, x).max() == 0


@pytest.mark.compiler
def test_within_2_ulp_of_libm_on_a_million_points(sincos, rng):
    """10^6 uniform in [-1e6, 1e6], 10^5 of small |x| (log-uniform down to 1e-300), and the doubles nearest and
    next to k pi/2 and k pi/4 (where the reduction cancels most and where the quadrants meet)."""
    ks = sample_ks(rng, 30000)
    half, quarter = nearest_multiples(ks, 0.5), nearest_multiples(2 * ks + 1, 0.25)
    neighbours = [np.nextafter(half, np.inf), np.nextafter(half, -np.inf),
                  np.nextafter(np.nextafter(half, np.inf), np.inf), np.nextafter(quarter, np.inf),
                  np.nextafter(quarter, -np.inf)]
    sets = {"uniform": rng.uniform(-1e6, 1e6, 10 ** 6),
            "small": rng.choice([-1.0, 1.0], 10 ** 5) * 10.0 ** rng.uniform(-300, 0.5, 10 ** 5),
            "near k pi/2": np.concatenate([half] + neighbours[:3]),
            "near k pi/4": np.concatenate([quarter] + neighbours[3:])}
    for name, x in sets.items():
        x = x[np.abs(x) < 1e6]
        s, c = sincos(x)
        rs, rc = libm(x)
        worst = max(int(ulps(s, rs).max()), int(ulps(c, rc).max()))
        assert worst <= BOUND_ULP, (name, worst, x[np.argmax(np.maximum(ulps(s, rs), ulps(c, rc)))])


@pytest.mark.compiler
def test_equal_to_libm_at_the_doubles_nearest_k_half_pi(sincos, rng):
    """sin and cos of the double nearest k pi/2 (|k| up to 636619, i.e. |x| < 1e6) equal libm's bit for bit: 0
    and +-1 exactly where libm gives them, and the tiny residual of the other one correctly rounded."""
    ks = sample_ks(rng, 60000)
    x = nearest_multiples(ks, 0.5)
    s, c = sincos(x)
    rs, rc = libm(x)
    bad = np.nonzero((s != rs) | (c != rc))[0]
    assert not bad.size, [(int(ks[i]), x[i], s[i], rs[i], c[i], rc[i]) for i in bad[:5]]
    assert np.all(np.abs(np.where(ks % 2 == 0, c, s)) == 1.0)


@pytest.mark.compiler
@pytest.mark.parametrize("x", [1e6, -1e6, 1e6 + 0.5, 2.5e7, -1e300, 1.7e308, math.inf, -math.inf, math.nan])
def test_outside_the_fast_range_it_is_libm(sincos, x):
    """|x| >= 1e6, inf and nan take libm's sin and cos (nan for inf and nan)."""
    s, c = sincos(np.array([x]))
    rs, rc = math.sin(x) if math.isfinite(x) else math.nan, math.cos(x) if math.isfinite(x) else math.nan
    for got, ref in ((s[0], rs), (c[0], rc)):
        assert (math.isnan(got) and math.isnan(ref)) or got == ref


def test_the_helper_is_static_inline_and_has_no_quadrant_branch():
    """C99 static inline, and the quadrant chosen by masks on k: no switch, no if or ?: between the range check
    and the end of the function (the range check is the only branch, predictable)."""
    c = generate(aggsym.load(model_path("double_pendulum")), targets="c,numpy,manifest").files["double_pendulum.c"]
    body = c[c.index("static inline void aggsym_sincos(double x"):]
    body = body[:body.index("\n}\n")]
    assert body.count("if (") == 1 and "switch" not in body
    fast = body[body.index("return;"):]
    assert "if" not in re.sub(r"#if|#endif", "", fast) and "?" not in fast
    assert "static inline void aggsym_sincos(float x" in generate(
        aggsym.load(model_path("double_pendulum")), targets="c,numpy,manifest", scalar="float").files["double_pendulum.c"]


@pytest.mark.compiler
def test_the_pair_gives_the_single_angle_results_bit_for_bit(tmp_path, rng):
    """Without -ffast-math the two lanes of aggsym_sincos2 do aggsym_sincos's arithmetic: identical doubles, also
    where one of the pair is outside the fast range (both then go through aggsym_sincos)."""
    dll = compiled_driver(tmp_path, ["-O2"])
    x = np.concatenate([rng.uniform(-10, 10, 10 ** 5), rng.uniform(-1e6, 1e6, 10 ** 5), [3e6, 0.5, -0.25, np.inf]])
    one, two = as_function(dll, "sincos_many")(x), as_function(dll, "sincos2_many")(x)
    for a, b in zip(one, two):
        assert np.array_equal(a.view(np.int64), b.view(np.int64))


def test_angles_of_one_routine_are_paired_when_both_are_ready():
    """The emitter joins two sincos calls into one aggsym_sincos2 when the second angle's argument is already
    computable (here the coordinates), and an odd one out stays a single call; the operation count still counts
    one call per angle."""
    gen = generate(aggsym.load(model_path("manipulator6")), targets="c,numpy,manifest")
    c = gen.files["manipulator6.c"]
    body = c[c.index("void manipulator6_inertia("):]
    body = body[:body.index("\n}\n")]
    pairs, singles = body.count("aggsym_sincos2("), body.count("aggsym_sincos(")
    calls = json.loads(gen.files["manipulator6.json"])["ops"]["inertia"]["call"]
    assert pairs >= 1 and 2 * pairs + singles == calls


def test_an_offset_angle_is_emitted_early_to_share_a_call():
    """Panda's internal frames move a joint's zero (q_6 + 3 pi/4): that sum, a named temp, is emitted just before
    the call it joins (not at its own place, after the call), the NumPy module keeps its order, each routine has
    at most one single call, and the operation counts are still those of the text."""
    from helpers import robot_path
    from aggsym.codegen.printing import count_ops

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the finger's <mimic>
        gen = generate(aggsym.load(robot_path("panda")), targets="c,numpy,manifest")
    c = gen.files["panda.c"]
    body = c[c.index("void panda_inverse_dynamics("):]
    body = body[:body.index("\n}\n")]
    lines = body.splitlines()
    early = []
    for k, line in enumerate(lines):
        m = re.search(r"aggsym_sincos2\((\w+), (\w+),", line)
        for t in m.groups() if m else ():
            if t.startswith("x"):
                early.append(t)
                assert lines[k - 2].strip().startswith(f"const double {t} = "), lines[k - 2:k + 1]  # (declaration between)
    assert early
    assert body.count("aggsym_sincos(") <= 1
    for r in gen.routines:
        assert r.ops == count_ops("\n".join(r.bodies["c"].lines)), r.routine.role
    module = gen.files["panda.py"]
    assert all(module.index(f"    {t} = ") > module.index("    q_6 = ") for t in early)
