"""The expression grammar of model files (issue 15, point 1): what it reads, what it refuses, and its bounds.

The reference for the accepted expressions is Python's own arithmetic on floats (math), independent of the parser;
the refusals are the attacks of the issue (code execution, strings, attribute access) and the resource bombs.
"""
import io
import math
import re
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import pytest
import sympy as sp

from aggsym import cli
from aggsym.model.readers import expressions as ex
from aggsym.model.readers.expressions import ExpressionError, check_supported, evaluate, parse_value

A, B = sp.Symbol("a", real=True), sp.Symbol("b", real=True)
SYMBOLS = {"a": A, "b": B}
AT = {A: 0.7, B: -1.3}

# text, the same value computed by Python with a = 0.7, b = -1.3
ACCEPTED = [
    ("1+2*3", 7.0), ("-2^2", -4.0), ("-2**2", -4.0), ("2^3^2", 512.0), ("2^-1", 0.5), ("(1+2)*3", 9.0),
    ("a*b - a/b", 0.7 * -1.3 - 0.7 / -1.3), ("a^2 + b**3", 0.7 ** 2 + (-1.3) ** 3), ("--a", 0.7), ("+a", 0.7),
    ("30 deg", math.pi / 6), ("10 + 20 deg", math.pi / 6), ("sin(30 deg)", 0.5), ("a*deg", 0.7 * math.pi / 180),
    ("(a + b) deg", (0.7 - 1.3) * math.pi / 180), ("pi/2", math.pi / 2), ("1e-3", 1e-3), (".5", 0.5), ("5.", 5.0),
    ("2.5e+2", 250.0), ("sqrt(a)", math.sqrt(0.7)), ("a^0.5", math.sqrt(0.7)), ("a^1.5", 0.7 ** 1.5),
    ("exp(b)", math.exp(-1.3)), ("log(a)", math.log(0.7)), ("abs(b)", 1.3), ("tan(a)", math.tan(0.7)),
    ("asin(a)", math.asin(0.7)), ("acos(a)", math.acos(0.7)), ("atan(b)", math.atan(-1.3)),
    ("atan2(b, a)", math.atan2(-1.3, 0.7)), ("cos(sin(a)) * 2", 2 * math.cos(math.sin(0.7))), ("  a\t+ 1 ", 1.7),
    ("1/3", 1 / 3), ("2^64", 2.0 ** 64), ("1e300 * 1e-300", 1.0),
]


@pytest.mark.parametrize("text,value", ACCEPTED, ids=[t for t, _ in ACCEPTED])
def test_accepted_expressions_have_their_arithmetic_value(text, value):
    expr = parse_value(text, SYMBOLS)
    assert evaluate(expr, AT) == pytest.approx(value, rel=1e-14, abs=1e-15)
    assert check_supported(expr) is None


def test_yaml_numbers_pass_through():
    assert parse_value(3, {}) == 3 and parse_value(-0.25, {}) == sp.Float(-0.25)
    for bad in (True, None, [1], {"a": 1}, float("nan"), float("inf"), 10 ** 40):
        with pytest.raises(ExpressionError):
            parse_value(bad, {})


# text, words of the error message
REFUSED = [
    ("__import__('os').system('true')", ["unexpected character"]),
    ("import os", ["unexpected 'os'"]),
    ("x.__class__", ["unexpected character '.'"]),
    ("sin('x')", ["unexpected character"]),
    ("a[0]", ["unexpected character '['"]),
    ("lambda: 1", ["unexpected character ':'"]),
    ("a; b", ["unexpected character ';'"]),
    ("eval(1)", ["unknown function 'eval'"]),
    ("Symbol(1)", ["unknown function 'Symbol'"]),
    ("sympify(1)", ["unknown function"]),
    ("open(1)", ["unknown function"]),
    ("x", ["undefined parameter 'x'", "parameters"]),
    ("t", ["time t is not allowed"]),
    ("E", ["undefined parameter 'E'"]),
    ("I", ["undefined parameter 'I'"]),
    ("sin", ["sin is a function"]),
    ("sin(1, 2)", ["expected ')'"]),
    ("atan2(1)", ["expected ','"]),
    ("", ["empty expression"]),
    ("   ", ["empty expression"]),
    ("1 +", ["unexpected the end"]),
    ("(1", ["expected ')'"]),
    ("1)", ["unexpected ')'"]),
    ("3!", ["unexpected character '!'"]),
    ("a b", ["unexpected 'b'"]),
    ("2 a", ["unexpected 'a'"]),
    ("1 deg deg", ["unexpected 'deg'"]),
    ("1/0", ["division by zero"]),
    ("pi/(1-1)", ["division by zero"]),
    ("0^-1", ["division by zero"]),
    ("log(0)", ["log(0) is not finite"]),
    ("atan2(0, 0)", ["undefined"]),
    ("sqrt(-1)", ["not a real finite value"]),
    ("log(-1)", ["not a real finite value"]),
    ("1e400", ["not finite"]),
    ("1e300*1e300", ["not finite"]),
    ("1" * 40, ["integer is too large"]),
    ("9^9^9^9", ["exponent", "at most 64"]),
    ("2^65", ["exponent", "at most 64"]),
    ("a^a", ["exponent", "constant"]),
    ("a^pi", ["exponent", "constant"]),
    ("a^(1/3)", ["integer or half-integer"]),
    ("(a^64)^64", ["exponent grows too large"]),
    ("a^64*a^64", ["exponent grows too large"]),
    ("99999999999999999999^64", ["constant grows too large"]),
    ("(" * 101 + "1" + ")" * 101, ["nested too deeply"]),
    ("-" * 101 + "1", ["nested too deeply"]),
    ("sin(" * 101 + "1" + ")" * 101, ["nested too deeply"]),
    ("2^" * 101 + "1", ["nested too deeply"]),
    ("+".join(["sin(a)"] * 1001), ["too many function calls"]),
    ("*".join(["99999999999999"] * 200), ["constant grows too large"]),
    ("+".join(f"1/{k}" for k in range(1, 3000)), ["constant grows too large"]),
    ("1" + "+1" * 60000, ["too long"]),
    ("a\u2212b", ["unexpected character"]),
    ("\u202e1", ["unexpected character"]),
]


@pytest.mark.parametrize("text,words", REFUSED, ids=[re.sub(r"\s", "_", t[:30]) or "empty" for t, _ in REFUSED])
def test_refused_expressions_say_why(text, words):
    with pytest.raises(ExpressionError) as info:
        parse_value(text, SYMBOLS)
    message = str(info.value)
    for w in words:
        assert w in message, message
    assert len(message) < 400, message  # a long input is quoted shortened


def test_a_long_sum_is_read_by_a_loop():
    """Sums and products cost no recursion: 20,000 terms, far beyond Python's recursion limit."""
    expr = parse_value("+".join(["a*b"] * 20000) + "-" + "*".join(["a"] * 60), SYMBOLS)
    assert evaluate(expr, AT) == pytest.approx(20000 * 0.7 * -1.3 - 0.7 ** 60)


def test_time_where_allowed_and_supported_derivatives():
    t = sp.Symbol("t", real=True)
    angle = parse_value("0.5*t^2 + sin(3*t) + atan2(t, 2) + exp(-t)", {"t": t})
    for k in range(3):
        assert check_supported(sp.diff(angle, t, k)) is None
    assert "DiracDelta" in check_supported(sp.diff(parse_value("abs(t)", {"t": t}), t, 2))


def test_evaluate_is_in_doubles_and_refuses_what_has_no_real_value():
    for text, why in [("asin(a + 1)", "no real value"), ("exp(2000*a)", "not finite"), ("1/(a - 0.7)", "zero"),
                      ("sqrt(b)", "no real value"), ("log(b)", "no real value")]:
        with pytest.raises(ValueError, match=why):
            evaluate(parse_value(text, SYMBOLS), AT)
    deep = A
    for _ in range(5000):  # deeper than Python's recursion limit: the walk is iterative
        deep = sp.Mul(sp.Add(deep, B, evaluate=False), sp.Rational(1, 2), evaluate=False)
    assert evaluate(deep, AT) == pytest.approx(-1.3)


def test_identifiers():
    assert ex.check_identifier("link_1") is None
    for bad in ("1a", "_a", "a-b", "sin", "pi", "deg", "t", "world", "class", "lambda", "", None, 3, "a b"):
        assert ex.check_identifier(bad) is not None, bad


def test_no_python_or_sympy_parser_in_the_package():
    """No text of a model reaches eval, exec, sympify or parse_expr: none of them is called anywhere."""
    root = Path(ex.__file__).resolve().parents[1]
    pattern = re.compile(r"\b(eval|exec|sympify|parse_expr|compile|__import__)\s*\(|setrecursionlimit")
    found = [f"{p.relative_to(root)}:{n}: {line.strip()}" for p in sorted(root.rglob("*.py"))
             for n, line in enumerate(p.read_text().splitlines(), 1)
             if pattern.search(line.split("#")[0]) and "re.compile" not in line]
    assert found == []


MODEL = """name: attack
parameters: {m: 1.5}
bodies:
  - name: link
    parent: world
    pair: {rotation: [[z, 0]], functional: {theta6: q1}}
    mass: m
    com: [VALUE, 0, 0]
    inertia: {xx: 0.1, yy: 0.1, zz: 0.1}
"""


@pytest.mark.parametrize("value", [
    "\"__import__('os').system('touch MARKER')\"",
    "\"sin('__import__(\\\\'os\\\\').system(\\\\'touch MARKER\\\\')')\"",
    "\"m.__class__.__mro__\"",
    "\"9^9^9^9\"",
    "\"exp(exp(exp(m*1000)))\"",
], ids=["import", "string-in-sin", "attribute", "power-tower", "overflow"])
def test_an_attack_through_the_command_line_is_an_error_and_runs_nothing(tmp_path, value):
    marker = tmp_path / "pwned"
    path = tmp_path / "attack.yaml"
    path.write_text(MODEL.replace("VALUE", value.replace("MARKER", str(marker))))
    out = tmp_path / "out"
    err = io.StringIO()
    with redirect_stderr(err), redirect_stdout(io.StringIO()):
        code = cli.main(["generate", str(path), "-o", str(out), "-q"])
    assert code == 2, err.getvalue()
    assert f"{path}:8:" in err.getvalue() and "bodies[0].com[0]" in err.getvalue(), err.getvalue()
    assert "Traceback" not in err.getvalue()
    assert not marker.exists() and not out.exists()


def test_the_models_expressions_have_a_budget_in_all(tmp_path):
    long = "+".join(["1"] * 30000)  # 60k characters, each allowed alone
    bodies = "".join(f"""  - name: b{i}
    parent: {'world' if i == 0 else f'b{i - 1}'}
    pair: {{rotation: [[z, 0]], functional: {{theta6: q{i}}}}}
    mass: 1
    com: ['{long}', 0, 0]
    inertia: {{xx: 0.1, yy: 0.1, zz: 0.1}}
""" for i in range(20))
    path = tmp_path / "big.yaml"
    path.write_text("name: big\nbodies:\n" + bodies)
    err = io.StringIO()
    with redirect_stderr(err), redirect_stdout(io.StringIO()):
        code = cli.main(["generate", str(path), "-o", str(tmp_path / "out"), "-q"])
    assert code == 2 and "too long in all" in err.getvalue() and "bodies[16].com[0]" in err.getvalue(), err.getvalue()
    assert len(err.getvalue()) < 500


def test_a_huge_integer_default_is_an_error(tmp_path):
    path = tmp_path / "huge.yaml"
    path.write_text(MODEL.replace("VALUE", "0").replace("{m: 1.5}", "{m: " + "9" * 400 + "}"))
    err = io.StringIO()
    with redirect_stderr(err), redirect_stdout(io.StringIO()):
        code = cli.main(["generate", str(path), "-o", str(tmp_path / "out"), "-q"])
    assert code == 2 and "parameters.m" in err.getvalue() and "larger than any finite double" in err.getvalue(), err.getvalue()
