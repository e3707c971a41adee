"""Long JAX routines cut into segments (issue 32: XLA's CPU compiler fuses a whole straight line into kernels
that evaluate shared values again at every use): each segment a function called through ``jax.lax.cond`` with
itself in both branches, on a predicate XLA cannot fold.

Shown here: the cutting keeps every statement once, in program order, and every name a segment reads is defined
before it (on a real routine and on random straight lines); with segments forced small on the small models,
every routine still equals the NumPy module to 1e-12 (batched, unbatched, with a status, with the time t), jit,
vmap, jacfwd, jacrev, grad along p and hessian go through them (against central differences), the custom JVP
through a cut derivative routine agrees with plain tracing; the conditionals survive XLA's compiler (else the
kernels would not end at the borders); generation stays deterministic.  The functions of the inputs (sines,
cosines) go first into a calls segment of their own in every routine, and XLA then evaluates each of them once."""
from __future__ import annotations

import re

import numpy as np
import pytest

import aggsym
from aggsym.codegen.generate import generate
from aggsym.codegen.targets import jax as jax_target
from aggsym.codegen.targets import jax_segments
from aggsym.codegen.targets.jax_segments import segmented
from aggsym.codegen.targets.numpy import statement_parts as _parts
from aggsym.contract import select_routines
from conftest import model_path
from helpers import robot_path
from jax_support import (arguments, as_tuple, central_differences, float64, four_bar_dead_centre, jax, jnp, modules,
                         relative, routines)

SIZE = 6  # statements per segment when forced small


def _check_cut(body, tail, cut, size):
    """Every statement once: the unpacked inputs first, then the calls segment (if any: statements that read only
    inputs and each other), then the others in program order; a segment's reads are its parameters or its own
    earlier statements; the parameters are defined before the call; the names the tail reads are defined at the
    end."""
    prelude = [s for s in cut["body"] if "= _cut(_kept, " not in s and not s.startswith("_kept =")]
    assert [s for s in body if s in prelude] == prelude
    segments = cut["segments"]
    hoisted = list(segments[0].lines) if segments and segments[0].name.endswith("__calls") else []
    assert [s for s in body if s in hoisted] == hoisted
    known = {_parts(s)[0] for s in prelude}  # the inputs' entries
    for line in hoisted:
        name, used = _parts(line)
        assert set(used) - {"jnp"} <= known, line
        known.add(name)
    cut_lines = [line for seg in segments for line in seg.lines]
    assert [s for s in body if s not in prelude and s not in hoisted] == cut_lines[len(hoisted):]
    assert sorted(cut_lines + prelude) == sorted(body)
    available = {_parts(s)[0] for s in prelude}
    calls = [s for s in cut["body"] if "= _cut(_kept, " in s]
    assert len(calls) == len(segments)
    for seg, call in zip(segments, calls):
        assert 1 <= len(seg.lines) <= (len(hoisted) if seg.name.endswith("__calls") else size)
        assert set(seg.params) <= available, seg.name
        assert call.endswith(f" = _cut(_kept, {seg.name}, {', '.join(seg.params)})")
        inside = set(seg.params)
        for line in seg.lines:
            name, used = _parts(line)
            assert all(u in inside or u == "jnp" for u in used), line
            inside.add(name)
        assert set(seg.results) <= inside
        available |= set(seg.results)
    assert {n for t in tail for n in re.findall(r"[A-Za-z_]\w*", t)} <= available


def _random_line(rng, n, function="sin"):
    """A random straight line of n statements over inputs q_0..q_3, each reading two earlier names, and the
    outputs' entries: every name nothing reads (as in the pruned programs), and a few more."""
    names = [f"q_{i}" for i in range(4)]
    body = [f"q_{i} = q[..., {i}]" for i in range(4)]
    read = set()
    for k in range(n):
        a, b = rng.choice(len(names), 2)
        body.append(f"x{k} = jnp.{function}({names[a]})*{names[b]} + 0.5")
        read |= {names[a], names[b]}
        names.append(f"x{k}")
    return body, [x for x in names if x not in read] + [f"x{n // 2}", "q_1"]


def test_a_run_nothing_reads_is_dropped():
    body = ["q_0 = q[..., 0]", "x0 = q_0*2.0", "x1 = x0 + 1.0", "x2 = x0*x0", "x3 = x2 + x0"]
    cut = segmented("f", body, ["x3"], size=1, above=0)
    assert [seg.lines for seg in cut["segments"]] == [("x0 = q_0*2.0",), ("x2 = x0*x0",), ("x3 = x2 + x0",)]


def test_a_short_routine_is_kept_whole():
    body, tail = _random_line(np.random.default_rng(0), 30, "sign")  # (sign: cheap, no calls segment)
    assert segmented("f", body, tail) == {"body": body, "segments": []}


def test_a_short_routine_with_many_entries_goes_into_one_segment():
    """More than GATHERED computed entries: every statement but the prelude in one segment, whose results are what
    the outputs read; at GATHERED entries (constant entries not counted), kept whole."""
    body, _ = _random_line(np.random.default_rng(1), 60, "sign")
    names = [_parts(s)[0] for s in body[4:]]
    tail = names[-jax_segments.GATHERED - 1:]
    cut = segmented("f", body, tail)
    assert [seg.name for seg in cut["segments"]] == ["_f__1"]
    assert cut["segments"][0].lines == tuple(body[4:])
    _check_cut(body, tail, cut, len(body))
    kept = tail[1:] + ["0.0"] * 5
    assert segmented("f", body, kept) == {"body": body, "segments": []}


def test_a_short_routine_with_many_entries_equals_the_numpy_module(tmp_path, rng):
    """manipulator6's A(q) (36 entries, one segment after its calls) and forward dynamics (6 entries, whole), under
    jit, against the NumPy module; its outputs assembled by one stack."""
    model = select_routines(aggsym.load(model_path("manipulator6")), ["inertia", "forward_dynamics"])
    npm, jm = modules(model, tmp_path)
    assert hasattr(jm, "_inertia__1") and not hasattr(jm, "_forward_dynamics__1")
    with float64():
        for role in ("inertia", "forward_dynamics"):
            for batch in ((), (5,)):
                args = arguments(npm, role, rng, batch)
                assert relative(jax.jit(getattr(jm, role))(*args), getattr(npm, role)(*args)) < 1e-12, role


def test_the_functions_of_the_inputs_go_first_into_their_segment():
    """cos and sin of the inputs (and of a sum of an input and a constant) go into _f__calls, in every routine;
    a call that depends on more than NEAR statements, or on one that does, stays where it is."""
    body = ["q_0 = q[..., 0]", "q_1 = q[..., 1]", "x0 = q_0*q_1", "x1 = 0.5 + q_1", "x2 = jnp.cos(x1)",
            "x3 = jnp.sin(q_0)", "x4 = x2*x3"]
    body += [f"x{k} = x{k - 1}*x0" for k in range(5, 5 + jax_segments.NEAR + 1)]
    last = 5 + jax_segments.NEAR
    body += [f"x{last + 1} = jnp.sqrt(x{last})", f"x{last + 2} = jnp.sign(q_1)*x4", f"x{last + 3} = x{last + 1} + x0"]
    tail = [f"x{last + 3}", f"x{last + 2}"]
    for above in (None, 0):  # whole, then cut
        cut = segmented("f", body, tail, size=3, above=above)
        calls = cut["segments"][0]
        assert calls.name == "_f__calls"
        assert calls.lines == ("x1 = 0.5 + q_1", "x2 = jnp.cos(x1)", "x3 = jnp.sin(q_0)")
        assert calls.params == ("q_1", "q_0") and calls.results == ("x2", "x3")
        assert cut["body"][:3] == ["q_0 = q[..., 0]", "q_1 = q[..., 1]",
                                   "_kept = jax.lax.optimization_barrier(jnp.asarray(False))  # a predicate XLA "
                                   "cannot fold (see _SEGMENTS)"]
        assert cut["body"][3] == "x2, x3, = _cut(_kept, _f__calls, q_1, q_0)"
        _check_cut(body, tail, cut, 3)
    whole = segmented("f", body, tail)
    assert len(whole["segments"]) == 1 and whole["body"][4:] == [s for s in body[2:] if s not in calls.lines]


@pytest.mark.parametrize("seed", range(5))
def test_cutting_random_lines_keeps_every_statement_and_defines_every_read(seed):
    rng = np.random.default_rng(seed)
    body, tail = _random_line(rng, int(rng.integers(20, 120)))
    size = int(rng.integers(1, 12))
    cut = segmented("f", body, tail, size=size, above=0)
    assert cut["segments"]
    _check_cut(body, tail, cut, size)


def test_cutting_a_real_routine(monkeypatch):
    """planar_3link's forward dynamics derivatives, as the JAX target prints them (short enough to stay whole
    by default, but for the calls segment of its sines and cosines)."""
    model = select_routines(aggsym.load(model_path("planar_3link")), ["forward_dynamics_derivatives"])
    text = generate(model, targets="jax").files["planar_3link_jax.py"]
    assert "def _forward_dynamics_derivatives__calls(" in text and "def _forward_dynamics_derivatives__1(" not in text
    monkeypatch.setattr(jax_target, "segmented", lambda role, body, tail: {"body": body, "segments": []})
    text = generate(model, targets="jax").files["planar_3link_jax.py"]
    lines = text.split("\n")
    start = lines.index(next(x for x in lines if x.startswith("def _forward_dynamics_derivatives(")))
    body = []
    for line in lines[start + 4:]:
        if line.startswith("    return"):
            break
        body.append(line.strip())
    tail = re.findall(r"_o\d+_\d+", "\n".join(lines[start:]).split("    return", 1)[1].split("\n\n")[0])
    cut = segmented("forward_dynamics_derivatives", body, tail, size=SIZE, above=0)
    _check_cut(body, tail, cut, SIZE)


SMALL = {"planar_2link": ["all"], "four_bar": None, "gyroscope_spinning_rotor": None,
         "planar_3link": ["inertia", "inertia_inverse", "forward_dynamics", "forward_dynamics_derivatives"]}


@pytest.fixture(scope="module")
def cut(tmp_path_factory):
    """{name: (NumPy module, JAX module)} with every routine of more than 8 statements cut into segments of 6."""
    out = {}
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(jax_segments, "SEGMENT", SIZE)
        mp.setattr(jax_segments, "SEGMENTED", 8)
        for name, roles in SMALL.items():
            model = aggsym.load(model_path(name))
            if roles:
                model = select_routines(model, roles)
            out[name] = modules(model, tmp_path_factory.mktemp(name))
    return out


@pytest.mark.slow
@pytest.mark.parametrize("name", list(SMALL))
def test_cut_routines_equal_the_numpy_module(cut, name, rng):
    npm, jm = cut[name]
    assert jm._SEGMENTS == SIZE
    cut_roles = {f.rsplit("__", 1)[0][1:] for f in vars(jm) if re.fullmatch(r"_\w+__\d+", f)}
    assert len(cut_roles) >= len(routines(npm)) // 2
    with float64():
        for role in routines(npm):
            for batch, traced in (((), False), ((2, 3), True)):  # eager: the segments called directly
                args = arguments(npm, role, rng, batch)
                try:
                    want = getattr(npm, role)(*args)
                except np.linalg.LinAlgError:
                    continue
                got = (jax.jit(getattr(jm, role)) if traced else getattr(jm, role))(*args)
                assert [np.shape(x) for x in as_tuple(got)] == [np.shape(x) for x in as_tuple(want)], role
                assert relative(got, want) < 1e-12, role


def test_a_cut_routine_with_a_status_gives_nan_where_numpy_raises(cut):
    npm, jm = cut["four_bar"]
    with float64():
        qdd, lam = jax.jit(jm.constrained_forward_dynamics)(*four_bar_dead_centre(npm))
    assert np.isnan(qdd[1]).all() and np.isnan(lam[1]).all() and np.isfinite(qdd[0]).all()


THROUGH = {"planar_2link": ["forward_dynamics", "inverse_dynamics", "regressor"],
           "gyroscope_spinning_rotor": ["forward_dynamics"]}  # (the time t)


@pytest.mark.slow
@pytest.mark.parametrize("name", list(THROUGH))
def test_transforms_go_through_cut_routines(cut, name, rng):
    """jit and vmap equal the NumPy module; jacfwd equals jacrev and central differences along the first input;
    grad along p equals central differences; the hessian of a scalar of the outputs is symmetric."""
    npm, jm = cut[name]
    with float64():
        for role in THROUGH[name]:
            assert hasattr(jm, f"_{role}__2"), role  # cut
            f = getattr(jm, role)
            args = arguments(npm, role, rng)
            assert relative(jax.jit(f)(*args), getattr(npm, role)(*args)) < 1e-12, role
            batch = arguments(npm, role, rng, (3,))
            assert relative(jax.jit(jax.vmap(f))(*batch), getattr(npm, role)(*batch)) < 1e-12, role
            x0 = np.asarray(args[0])
            fwd = as_tuple(jax.jit(jax.jacfwd(f))(*args))
            rev = as_tuple(jax.jit(jax.jacrev(f))(*args))
            flat = central_differences(lambda x: np.concatenate([np.ravel(o) for o in as_tuple(f(x, *args[1:]))]), x0)
            start = 0
            for a, b in zip(fwd, rev):
                size = int(np.prod(a.shape[:-1]))
                assert relative(a, b) < 1e-10, role
                assert relative(a, flat[start:start + size].reshape(a.shape), floor=1.0) < 1e-6, role
                start += size
            p = np.asarray(npm.PARAMETERS, dtype=float)

            def of_p(p, args=args, f=f):
                return sum(jnp.sum(o) for o in as_tuple(f(*args, p)))
            g = jax.jit(jax.grad(of_p))(p)
            assert relative(g, central_differences(lambda x: np.asarray(of_p(x)), p), floor=1.0) < 1e-6, role

            def scalar(x, args=args, f=f):
                return sum(jnp.sum(jnp.sin(o)) for o in as_tuple(f(x, *args[1:])))
            H = np.asarray(jax.jit(jax.hessian(scalar))(x0))
            assert np.isfinite(H).all() and np.allclose(H, H.T, rtol=1e-10, atol=1e-10), role


def test_the_custom_jvp_through_a_cut_derivative_routine(cut, rng):
    """planar_3link: jacfwd and jacrev of forward dynamics apply the cut derivative routine; they equal plain
    tracing of the (cut) straight line and central differences."""
    npm, jm = cut["planar_3link"]
    assert any(f.startswith("_forward_dynamics_derivatives__") for f in vars(jm))
    n = jm.NV
    q, qd, tau = rng.uniform(-1.5, 1.5, n), rng.normal(size=n), rng.normal(size=n)
    p = np.asarray(jm.PARAMETERS)

    def plain(q, qd):
        return jm._forward_dynamics(*(jnp.asarray(a, jnp.float64) for a in (q, qd, tau, p)))[0]
    with float64():
        for k, x in enumerate((q, qd)):
            custom = jax.jit(jax.jacfwd(jm.forward_dynamics, k))(q, qd, tau)
            assert relative(custom, jax.jacrev(jm.forward_dynamics, k)(q, qd, tau)) < 1e-10
            assert relative(custom, jax.jacfwd(plain, k)(q, qd)) < 1e-10
            diff = central_differences(
                lambda y: np.asarray(jm.forward_dynamics(*((y, qd) if k == 0 else (q, y)), tau)), x)
            assert relative(custom, diff, floor=1.0) < 1e-6
        want = npm.forward_dynamics_derivatives(q, qd, tau)
        assert relative(jm.forward_dynamics_derivatives(q, qd, tau), want) < 1e-12


def test_the_conditionals_survive_xla(cut, rng):
    """The compiled program keeps one conditional per segment: were the predicate folded, XLA would inline the
    branches and fuse the whole straight line again."""
    npm, jm = cut["planar_3link"]
    segments = [f for f in vars(jm) if f.startswith("_forward_dynamics_derivatives__")]
    args = arguments(npm, "forward_dynamics_derivatives", rng, (16,))
    with float64():
        text = jax.jit(jm.forward_dynamics_derivatives).lower(*args).compile().as_text()
    assert len(re.findall(r"\bconditional\(", text)) >= len(segments) >= 3


def test_generation_with_segments_is_deterministic(monkeypatch):
    monkeypatch.setattr(jax_segments, "SEGMENT", SIZE)
    monkeypatch.setattr(jax_segments, "SEGMENTED", 8)
    model = aggsym.load(model_path("planar_3link"))
    first = generate(model, targets="jax").files
    assert "_forward_dynamics__2(" in first["planar_3link_jax.py"]
    assert first == generate(model, targets="jax").files


def test_xla_evaluates_each_sine_once(tmp_path, rng):
    """The calls segment's sines and cosines are results of a conditional, so every kernel after it reads them:
    the compiled forward dynamics holds each of them once per branch.  Without the segment XLA copies them into
    the kernels that read them (here 140 for Panda's 12, five times slower)."""
    model = select_routines(aggsym.load(robot_path("panda")), ["forward_dynamics"])
    npm, jm = modules(model, tmp_path)
    text = open(jm.__file__).read()
    written = len(re.findall(r"jnp\.(?:sin|cos)\(", text))
    assert written >= 12
    args = arguments(npm, "forward_dynamics", rng, (64,))
    with float64():
        hlo = jax.jit(jm.forward_dynamics).lower(*args).compile().as_text()
    assert len(re.findall(r"\b(?:sine|cosine)\(", hlo)) <= 2 * written
