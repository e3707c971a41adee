"""The JAX examples of docs/batched.md (issue 32, item 5; on the batch kernels since issue 51), run small:
examples/jax_simulate.py (a batch of arms through jax.lax.scan) matches the NumPy module stepped the same way;
examples/jax_fit_inertia.py (inertial parameters fitted to noisy torques with jax.grad) brings the torque error down
to the noise and predicts fresh torques; examples/jax_humanoid.py (forward dynamics and its Jacobian of a batch)."""
from __future__ import annotations

import sys

import pytest

from conftest import ROOT
import jax_support  # noqa: F401  (skips this module where jax does not import)

sys.path.insert(0, str(ROOT / "examples"))


def test_the_simulation_example_matches_the_numpy_module(tmp_path):
    import jax_simulate

    out = jax_simulate.main(["--batch", "6", "--steps", "40", "--robot", "double_pendulum", "--folder",
                             str(tmp_path), "--check"])
    assert out["q"].shape == (6, 2)
    assert out["difference"] < 1e-9


def test_the_fitting_example_converges_to_the_noise(tmp_path):
    import jax_fit_inertia

    out = jax_fit_inertia.main(["--samples", "150", "--robot", "double_pendulum", "--noise", "0.02", "--folder",
                                str(tmp_path)])
    start, one, two = out["rms"]
    assert start > 1.5 * out["noise"]
    assert one == pytest.approx(two, rel=1e-6)  # a quadratic: Newton's first step is the minimum
    assert 0.8 * out["noise"] < one < 1.1 * out["noise"]  # down to the noise (with 2 x 10 parameters fitted)
    assert out["fresh"] < 0.3 * out["noise"]


def test_the_humanoid_example_runs_on_the_kernels(tmp_path):
    """examples/jax_humanoid.py, small (a double pendulum on a free-flyer, 8 states): on the kernels, the NumPy
    module's values and central differences."""
    import jax_humanoid

    out = jax_humanoid.main(["--batch", "8", "--robot", "double_pendulum", "--folder", str(tmp_path)])
    assert out["difference"] < 1e-12
    assert out["central_differences"] < 1e-6
    assert set(out) >= {"forward_dynamics", "jacfwd", "jacrev"}
