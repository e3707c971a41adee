"""aggsym: equations of motion of rigid-body trees by Konoplev's aggregative method.

``aggsym.load(path, **options)`` reads a model and applies the options as ``aggsym generate`` does
(:mod:`aggsym.pipeline`), ``aggsym.equations(model)`` gives its SymPy matrices,
``aggsym.NumericTwin(model)`` evaluates every routine of the contract in floating point, and
``aggsym.generate(model)`` gives the files of the generated code.  Importing the package is light: each of these
is imported on first use, so the mechanics never pull in the code generator (and jinja2).
"""
from .errors import AggsymError, ModelError

__version__ = "0.1.0"
__all__ = ["load", "equations", "Equations", "NumericTwin", "generate", "ModelError", "AggsymError", "__version__"]

_LAZY = {"load": ("aggsym.pipeline", "load"), "equations": ("aggsym.symbolic", "equations"),
         "Equations": ("aggsym.symbolic", "Equations"), "NumericTwin": ("aggsym.twin", "NumericTwin"),
         "generate": ("aggsym.codegen.generate", "generate")}


def __getattr__(name):
    if name in _LAZY:
        import importlib

        module, attr = _LAZY[name]
        value = getattr(importlib.import_module(module), attr)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'aggsym' has no attribute {name!r}")
