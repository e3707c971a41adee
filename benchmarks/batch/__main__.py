"""``python -m benchmarks.batch``: the batched benchmark (:mod:`benchmarks.batch.orchestrator`)."""
import sys

from .orchestrator import main

sys.exit(main())
