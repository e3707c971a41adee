"""The CasADi section of the benchmark (benchmarks/runtime/casadi_target.py), quickly, on models/arm3.urdf: CasADi's
C of aggsym's forward dynamics, of its Jacobian by CasADi's AD and by the attached derivative routines, and of the
peer's compiles and runs; the Jacobians built for timing are the right ones; the table marks the target met or
missed by the ratios.  No timing is asserted (make bench times)."""
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from benchmarks.runtime import casadi_target  # noqa: E402

URDF = ROOT / "models" / "arm3.urdf"


@pytest.mark.compiler
def test_the_section_measures_arm3(tmp_path):
    out = casadi_target.measure("arm3", URDF, tmp_path / "arm3")
    assert out["nq"] == 3 and set(out["entries"]) == {"aggsym fd", "aggsym jac (CasADi AD)", "aggsym jac (attached)",
                                                        "peer fd", "peer jac (CasADi AD)"}
    for entry in out["entries"].values():
        assert entry["n_instructions"] > 0 and entry["ns"] > 0.0
    table = casadi_target.markdown({"robots": {"arm3": out}, "load_before": 0.0, "load_after": 0.0})
    assert table.count("(<= 0.5)") == 2 and "| arm3 (nq 3) | aggsym fd |" in table


def test_the_timed_jacobians_are_the_dynamics_jacobians(tmp_path):
    """The three Functions the section times for aggsym agree: forward dynamics with the NumPy module's, the two
    Jacobians with each other and with central differences of it."""
    import aggsym
    from helpers import central_differences

    module, _, _ = casadi_target.aggsym_functions(URDF, tmp_path)
    fd = module.functions()["forward_dynamics"]
    ad_fd, ad_jac = casadi_target._with_defaults(module, module.functions(analytic=False)["forward_dynamics"], "a",
                                                 False)
    _, attached = casadi_target._with_defaults(module, fd, "b", True)
    twin = aggsym.NumericTwin(aggsym.load(URDF))
    x = np.random.default_rng(3).uniform(-1, 1, 9)
    got = np.asarray(ad_fd(x[:3], x[3:6], x[6:]).full()).ravel()
    assert np.max(np.abs(got - twin.forward_dynamics(x[:3], x[3:6], x[6:]))) <= 1e-13 * np.max(np.abs(got))
    J1, J2 = (np.asarray(f(x[:3], x[3:6], x[6:]).full()) for f in (ad_jac, attached))
    cd = central_differences(lambda y: np.asarray(ad_fd(y[:3], y[3:6], y[6:]).full()).ravel(), x)
    assert J1.shape == (3, 9) and np.max(np.abs(J1 - J2)) <= 1e-10 * np.max(np.abs(J1))
    assert np.max(np.abs(J1 - cd)) <= 1e-6 * np.max(np.abs(J1))
