"""Batches of states (issue 32): the generated JAX, PyTorch and NumPy modules against adam-robotics, jaxsim, MuJoCo
MJX and a loop over Pinocchio, per batch size, in the peers' own venv (``.venv-batch``, from
``benchmarks/batch/requirements.txt``).  ``python -m benchmarks.batch`` runs :mod:`.orchestrator`, which starts one
:mod:`.worker` process per entry, robot and routine; the entries are :mod:`.peers` and :mod:`.engines`; the tables,
plot and targets :mod:`.report`.
"""
