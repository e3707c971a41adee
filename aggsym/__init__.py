"""aggsym: equations of motion of rigid-body trees by Konoplev's aggregative method.

``aggsym.load(path)`` reads a model, ``aggsym.equations(model)`` gives its SymPy matrices, and
``aggsym.NumericTwin(model)`` evaluates every generated routine in floating point.
"""
from .equations import Equations, equations
from .errors import AggsymError, ModelError
from .model import load
from .numeric import NumericTwin

__version__ = "0.1.0"
__all__ = ["load", "equations", "Equations", "NumericTwin", "ModelError", "AggsymError", "__version__"]
