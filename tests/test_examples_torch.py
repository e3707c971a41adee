"""examples/torch_module.py runs (small): the Panda's generated forward dynamics inside torch.nn.Modules, a policy
trained through the simulated motion; its cost falls and stays finite."""
from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import torch

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "torch_module.py"


def load_example():
    spec = importlib.util.spec_from_file_location("torch_module_example", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_policy_example_runs_small_and_its_cost_falls(capsys):
    example = load_example()
    assert example.main(["--batch", "4", "--steps", "4", "--iterations", "3"]) == 0
    out = capsys.readouterr().out
    first, last = (float(x) for x in re.search(r"cost (\S+) -> (\S+)", out).groups())
    assert last < first and "panda: 9 coordinates" in out


def test_the_dynamics_module_follows_dtype_and_learns_parameters(tmp_path):
    """ForwardDynamics: p a buffer that .to() converts, or a Parameter that receives a gradient."""
    example = load_example()
    generated = example.generated_module(Path(__file__).resolve().parent.parent / "models" / "double_pendulum.yaml",
                                         tmp_path)
    n = generated.NV
    fixed = example.ForwardDynamics(generated).to(torch.float32)
    q = torch.zeros(2, n, dtype=torch.float32)
    assert fixed.p.dtype == torch.float32 and fixed(q, q, q).dtype == torch.float32
    learned = example.ForwardDynamics(generated, learn_parameters=True).double()
    x = torch.rand(2, n, dtype=torch.float64)
    learned(x, x, x).square().sum().backward()
    assert learned.p.grad is not None and torch.isfinite(learned.p.grad).all() and learned.p.grad.abs().max() > 0
